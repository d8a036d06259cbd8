//! The exact field of an infinite plate with a traction-free circular hole
//! of radius `a` (centre at the origin) under uniaxial tension `σ` along x
//! at infinity (Kirsch 1898; in Cartesian components as in Belytschko, Lu &
//! Gu 1994, Eq. 56, and Szabó & Babuška 1991 for the displacement).

use crate::geom::Vec2;

/// Kirsch's solution for remote tension `s` along x and hole radius `a`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kirsch {
    /// Remote tension σ.
    pub s: f64,
    /// Hole radius.
    pub a: f64,
}

impl Kirsch {
    /// The field for tension `s` and radius `a`.
    pub fn new(s: f64, a: f64) -> Self {
        Kirsch { s, a }
    }

    /// `[σ_xx, σ_yy, σ_xy]` at `p` (outside the hole):
    /// `σ_xx = σ[1 − a²/r² (3/2 cos2θ + cos4θ) + 3a⁴/(2r⁴) cos4θ]`,
    /// `σ_yy = σ[−a²/r² (1/2 cos2θ − cos4θ) − 3a⁴/(2r⁴) cos4θ]`,
    /// `σ_xy = σ[−a²/r² (1/2 sin2θ + sin4θ) + 3a⁴/(2r⁴) sin4θ]`.
    pub fn stress(&self, p: Vec2) -> [f64; 3] {
        let r2 = p.norm2();
        let t = p.y.atan2(p.x);
        let (c2, c4, s2, s4) = (
            (2.0 * t).cos(),
            (4.0 * t).cos(),
            (2.0 * t).sin(),
            (4.0 * t).sin(),
        );
        let q = self.a * self.a / r2;
        let q2 = q * q;
        [
            self.s * (1.0 - q * (1.5 * c2 + c4) + 1.5 * q2 * c4),
            self.s * (-q * (0.5 * c2 - c4) - 1.5 * q2 * c4),
            self.s * (-q * (0.5 * s2 + s4) + 1.5 * q2 * s4),
        ]
    }

    /// `[u_x, u_y]` at `p` for shear modulus `mu` and Kolosov constant
    /// `kappa` (`3 − 4ν` plane strain, `(3 − ν)/(1 + ν)` plane stress), with
    /// `u_x = 0` on x = 0 and `u_y = 0` on y = 0:
    /// `u_x = σa/(8μ)[r/a (κ+1) cosθ + 2a/r ((1+κ) cosθ + cos3θ) − 2a³/r³ cos3θ]`,
    /// `u_y = σa/(8μ)[r/a (κ−3) sinθ + 2a/r ((1−κ) sinθ + sin3θ) − 2a³/r³ sin3θ]`.
    pub fn displacement(&self, p: Vec2, mu: f64, kappa: f64) -> [f64; 2] {
        let r = p.norm();
        let t = p.y.atan2(p.x);
        let a = self.a;
        let f = self.s * a / (8.0 * mu);
        let (c1, c3, s1, s3) = (t.cos(), (3.0 * t).cos(), t.sin(), (3.0 * t).sin());
        let (ra, ar) = (r / a, a / r);
        [
            f * (ra * (kappa + 1.0) * c1 + 2.0 * ar * ((1.0 + kappa) * c1 + c3)
                - 2.0 * ar.powi(3) * c3),
            f * (ra * (kappa - 3.0) * s1 + 2.0 * ar * ((1.0 - kappa) * s1 + s3)
                - 2.0 * ar.powi(3) * s3),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentration_three_at_the_top_and_free_hole() {
        let k = Kirsch::new(2.0, 1.5);
        let top = k.stress(Vec2::new(0.0, 1.5));
        assert!((top[0] - 6.0).abs() < 1e-12);
        // traction-free hole: σ·n = 0 with n = −p/|p| (into the hole)
        for i in 0..12 {
            let t = i as f64 * 0.5;
            let p = Vec2::new(1.5 * t.cos(), 1.5 * t.sin());
            let s = k.stress(p);
            let n = p * (1.0 / 1.5);
            assert!((s[0] * n.x + s[2] * n.y).abs() < 1e-12);
            assert!((s[2] * n.x + s[1] * n.y).abs() < 1e-12);
        }
        // far field: uniaxial σ
        let far = k.stress(Vec2::new(1e4, 3e4));
        assert!((far[0] - 2.0).abs() < 1e-6 && far[1].abs() < 1e-6);
        // displacement consistent with the stress: ε_xx = ∂u_x/∂x
        let (e, nu) = (100.0, 0.3);
        let mu = e / (2.0 * (1.0 + nu));
        let kappa = (3.0 - nu) / (1.0 + nu);
        let p = Vec2::new(2.0, 1.3);
        let h = 1e-6;
        let du = |d: Vec2| k.displacement(p + d, mu, kappa);
        let exx = (du(Vec2::new(h, 0.0))[0] - du(Vec2::new(-h, 0.0))[0]) / (2.0 * h);
        let s = k.stress(p);
        assert!((exx - (s[0] - nu * s[1]) / e).abs() < 1e-7, "{exx}");
    }
}
