//! Closed-form elasticity solutions used for boundary conditions and
//! validation.

use crate::geom::Vec2;

/// Timoshenko & Goodier's cantilever: length L, depth D, clamped at `x₀`
/// (x measured from it), end shear P at `x₀ + L`, y from the centre line
/// `y_c`. Plane stress with (E, ν); for plane strain pass
/// `E/(1 − ν²)` and `ν/(1 − ν)` (see [`Timoshenko::new`]).
#[derive(Debug, Clone, Copy)]
pub struct Timoshenko {
    /// End shear `P` (force per unit thickness; positive along +y, so the
    /// tip deflects upward).
    pub p: f64,
    /// Length L.
    pub l: f64,
    /// Depth D (`I = D³/12` per unit thickness).
    pub d: f64,
    /// Young's modulus (plane-stress equivalent if built for plane strain).
    pub e: f64,
    /// Poisson's ratio (plane-stress equivalent if built for plane strain).
    pub nu: f64,
    /// x of the clamped end.
    pub x0: f64,
    /// y of the centre line.
    pub yc: f64,
}

impl Timoshenko {
    #[allow(clippy::too_many_arguments)]
    /// `plane_strain` converts (E, ν) to the plane-stress equivalents.
    pub fn new(
        p: f64,
        l: f64,
        d: f64,
        e: f64,
        nu: f64,
        plane_strain: bool,
        x0: f64,
        yc: f64,
    ) -> Self {
        let (e, nu) = if plane_strain {
            (e / (1.0 - nu * nu), nu / (1.0 - nu))
        } else {
            (e, nu)
        };
        Timoshenko {
            p,
            l,
            d,
            e,
            nu,
            x0,
            yc,
        }
    }

    fn inertia(&self) -> f64 {
        self.d.powi(3) / 12.0
    }

    /// Exact displacement `(u_x, u_y)` at `q`.
    pub fn displacement(&self, q: Vec2) -> [f64; 2] {
        let (x, y) = (q.x - self.x0, q.y - self.yc);
        let (p, l, d, nu) = (self.p, self.l, self.d, self.nu);
        let c = p / (6.0 * self.e * self.inertia());
        [
            -c * y * ((6.0 * l - 3.0 * x) * x + (2.0 + nu) * (y * y - d * d / 4.0)),
            c * (3.0 * nu * y * y * (l - x)
                + (4.0 + 5.0 * nu) * d * d * x / 4.0
                + (3.0 * l - x) * x * x),
        ]
    }

    /// Exact stress `(σ_xx, σ_yy, σ_xy)` at `q`.
    pub fn stress(&self, q: Vec2) -> [f64; 3] {
        let (x, y) = (q.x - self.x0, q.y - self.yc);
        let i = self.inertia();
        [
            -self.p * (self.l - x) * y / i,
            0.0,
            self.p / (2.0 * i) * (self.d * self.d / 4.0 - y * y),
        ]
    }

    /// Exact vertical displacement at the tip centre `(x₀ + L, y_c)`.
    pub fn tip_deflection(&self) -> f64 {
        self.displacement(Vec2::new(self.x0 + self.l, self.yc))[1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn liu_gu_tip_deflection() {
        let t = Timoshenko::new(-1000.0, 48.0, 12.0, 3e7, 0.3, false, 0.0, 0.0);
        let tip = t.tip_deflection();
        assert!((tip + 0.0089).abs() < 1e-5, "{tip}");
        // strains from finite differences match the stress (plane stress)
        let q = Vec2::new(20.0, 3.0);
        let h = 1e-4;
        let du = |dx: f64, dy: f64| t.displacement(Vec2::new(q.x + dx, q.y + dy));
        let exx = (du(h, 0.0)[0] - du(-h, 0.0)[0]) / (2.0 * h);
        let gxy = (du(0.0, h)[0] - du(0.0, -h)[0] + du(h, 0.0)[1] - du(-h, 0.0)[1]) / (2.0 * h);
        let s = t.stress(q);
        assert!((s[0] - 3e7 * exx).abs() < 1e-6 * s[0].abs());
        assert!((s[2] - 3e7 / 2.6 * gxy).abs() < 1e-6 * s[2].abs());
    }
}
