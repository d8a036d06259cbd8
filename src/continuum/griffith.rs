//! The exact field of a straight crack of length `2a` centred at the origin,
//! inclined at `β` to the x axis, in an infinite plate under remote
//! uniaxial tension `σ` along y (Griffith's crack; Westergaard's stress
//! functions, in the form of Anderson, *Fracture Mechanics*, App. 2, and
//! Tada, Paris & Irwin, *The Stress Analysis of Cracks Handbook*, §5).
//!
//! In the crack's frame (x′ along the crack) the remote stress is
//! `σ′_yy = σ cos²β`, `σ′_xx = σ sin²β`, `σ′_xy = σ sinβ cosβ`; the field
//! is the sum of Westergaard's mode I solution for the biaxial remote
//! stress `σ′_yy` (`Z = σ′_yy z/√(z² − a²)`), a uniform `σ′_xx − σ′_yy`
//! along x′, and Westergaard's mode II solution (`Z = σ′_xy z/√(z² − a²)`).
//! The stress intensity factors at both tips are
//! `K_I = σ√(πa) cos²β`, `K_II = σ√(πa) sinβ cosβ`.

pub use super::crack_tip::mu_kappa;
use crate::geom::Vec2;
use num_complex::Complex64 as C;

/// Griffith's inclined crack in an infinite plate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Griffith {
    /// Remote tension σ along y.
    pub s: f64,
    /// Half-length `a` of the crack.
    pub a: f64,
    /// Angle β of the crack to the x axis (radians).
    pub beta: f64,
    /// Shear modulus μ.
    pub mu: f64,
    /// Kolosov's constant κ (`3 − 4ν` plane strain, `(3 − ν)/(1 + ν)`
    /// plane stress).
    pub kappa: f64,
}

impl Griffith {
    /// `K_I = σ√(πa) cos²β` and `K_II = σ√(πa) sinβ cosβ`.
    pub fn k(&self) -> [f64; 2] {
        let k0 = self.s * (std::f64::consts::PI * self.a).sqrt();
        let (sb, cb) = self.beta.sin_cos();
        [k0 * cb * cb, k0 * sb * cb]
    }

    /// The remote stress in the crack's frame `[σ′_xx, σ′_yy, σ′_xy]`.
    fn remote(&self) -> [f64; 3] {
        let (sb, cb) = self.beta.sin_cos();
        [self.s * sb * sb, self.s * cb * cb, self.s * sb * cb]
    }

    /// `p` in the crack's frame as `z = x′ + i y′`.
    fn local(&self, p: Vec2) -> C {
        let (sb, cb) = self.beta.sin_cos();
        C::new(cb * p.x + sb * p.y, -sb * p.x + cb * p.y)
    }

    /// `√(z² − a²)` with its cut on the crack, `≈ z` far away.
    fn root(&self, z: C) -> C {
        (z - self.a).sqrt() * (z + self.a).sqrt()
    }

    /// `[σ_xx, σ_yy, σ_xy]` at `p` (off the crack).
    pub fn stress(&self, p: Vec2) -> [f64; 3] {
        let [sxx, syy, sxy] = self.remote();
        let z = self.local(p);
        let y = z.im;
        let r = self.root(z);
        let w = z / r; // Z / σ₀
        let dw = -self.a * self.a / (r * r * r); // Z′ / σ₀
        let (zi, dzi) = (w * syy, dw * syy);
        let (zii, dzii) = (w * sxy, dw * sxy);
        let l = [
            zi.re - y * dzi.im + (sxx - syy) + 2.0 * zii.im + y * dzii.re,
            zi.re + y * dzi.im - y * dzii.re,
            -y * dzi.re + zii.re - y * dzii.im,
        ];
        rotate_stress(l, self.beta)
    }

    /// `[u_x, u_y]` at `p` (on a face: the face of the sign of `y′`):
    /// Westergaard's displacement, zero at the crack's centre.
    pub fn displacement(&self, p: Vec2) -> [f64; 2] {
        let [sxx, syy, sxy] = self.remote();
        let (mu, k) = (self.mu, self.kappa);
        let z = self.local(p);
        let (x, y) = (z.re, z.im);
        let r = self.root(z);
        let (w, wh) = (z / r, r); // Z/σ₀ and Ẑ/σ₀
        let s1 = sxx - syy;
        let ux = ((k - 1.0) / 2.0 * syy * wh.re - y * syy * w.im)
            + ((k + 1.0) / 2.0 * sxy * wh.im + y * sxy * w.re)
            + (k + 1.0) / 4.0 * s1 * x;
        let uy = ((k + 1.0) / 2.0 * syy * wh.im - y * syy * w.re)
            + (-(k - 1.0) / 2.0 * sxy * wh.re - y * sxy * w.im)
            + (k - 3.0) / 4.0 * s1 * y;
        let (sb, cb) = self.beta.sin_cos();
        let (ux, uy) = (ux / (2.0 * mu), uy / (2.0 * mu));
        [cb * ux - sb * uy, sb * ux + cb * uy]
    }
}

/// `[σ_xx, σ_yy, σ_xy]` of a stress given in a frame turned by `beta`.
pub fn rotate_stress(l: [f64; 3], beta: f64) -> [f64; 3] {
    let (s, c) = beta.sin_cos();
    let [a, b, t] = l;
    [
        c * c * a + s * s * b - 2.0 * s * c * t,
        s * s * a + c * c * b + 2.0 * s * c * t,
        s * c * (a - b) + (c * c - s * s) * t,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::continuum::material::elasticity;

    fn field(beta: f64, strain: bool) -> (Griffith, [f64; 4]) {
        let (e, nu) = (200.0, 0.3);
        let (mu, kappa) = mu_kappa(e, nu, strain);
        (
            Griffith {
                s: 2.0,
                a: 1.0,
                beta,
                mu,
                kappa,
            },
            elasticity(e, nu, strain),
        )
    }

    #[test]
    fn displacement_stress_and_faces_agree() {
        for strain in [false, true] {
            for beta in [0.0, 0.5, 1.1] {
                let (g, d) = field(beta, strain);
                for p in [[0.3, 0.7], [-1.5, 0.2], [2.0, -1.7], [0.1, -0.05]] {
                    let p = Vec2::from(p);
                    let h = 1e-6;
                    let du = |dx: Vec2| {
                        let (a, b) = (g.displacement(p + dx), g.displacement(p - dx));
                        [(a[0] - b[0]) / (2.0 * h), (a[1] - b[1]) / (2.0 * h)]
                    };
                    let (gx, gy) = (du(Vec2::new(h, 0.0)), du(Vec2::new(0.0, h)));
                    let e = [gx[0], gy[1], gy[0] + gx[1]];
                    let s = [
                        d[0] * e[0] + d[1] * e[1],
                        d[1] * e[0] + d[2] * e[1],
                        d[3] * e[2],
                    ];
                    let ex = g.stress(p);
                    for k in 0..3 {
                        assert!(
                            (s[k] - ex[k]).abs() < 1e-6,
                            "{strain} {beta} {p:?}: {s:?} vs {ex:?}"
                        );
                    }
                }
                // far away: the remote tension; faces traction-free
                let far = g.stress(Vec2::new(3e3, 2e3));
                assert!(
                    (far[0]).abs() < 1e-5 && (far[1] - 2.0).abs() < 1e-5 && far[2].abs() < 1e-5
                );
                let (sb, cb) = beta.sin_cos();
                for t in [-0.9, 0.0, 0.6] {
                    for side in [1e-9, -1e-9] {
                        let p = Vec2::new(cb * t - sb * side, sb * t + cb * side);
                        let l = rotate_stress(g.stress(p), -beta);
                        assert!(l[1].abs() < 1e-6 && l[2].abs() < 1e-6, "{l:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn near_tip_stress_gives_k() {
        let (g, _) = field(0.6, false);
        let [k1, k2] = g.k();
        let r = 1e-8;
        let (sb, cb) = 0.6f64.sin_cos();
        let p = Vec2::new(cb * (1.0 + r), sb * (1.0 + r));
        let l = rotate_stress(g.stress(p), -0.6);
        let f = (2.0 * std::f64::consts::PI * r).sqrt();
        assert!((l[1] * f - k1).abs() < 1e-3 * k1, "{} vs {k1}", l[1] * f);
        assert!((l[2] * f - k2).abs() < 1e-3 * k2, "{} vs {k2}", l[2] * f);
    }
}
