//! Linear elastic fracture mechanics at a crack tip, independent of the
//! discretisation: Williams' near-tip fields, the interaction (domain)
//! integral for the mixed-mode stress intensity factors `K_I`, `K_II`,
//! and the maximum hoop-stress criterion for the direction of growth.
//!
//! **Interaction integral** (Yau, Wang & Corten 1980; domain form of
//! Moran & Shih 1987, as in Moës, Dolbow & Belytschko 1999). In the tip's
//! frame (x₁ along the direction of advance, x₂ to its left), with the
//! actual fields (σ, u) and an auxiliary field (σᵃ, uᵃ) of Williams for
//! `K_I = 1` or `K_II = 1`,
//!
//! `I = ∫_A [σ_ij uᵃ_i,1 + σᵃ_ij u_i,1 − σ_ik εᵃ_ik δ_1j] q,j dA`,
//!
//! over a ring `A` around the tip where the weight `q` falls from 1 (inner
//! radius) to 0 (outer radius), and `I = 2 (K_I Kᵃ_I + K_II Kᵃ_II)/E′`
//! with `E′ = E` (plane stress) or `E/(1 − ν²)` (plane strain). Traction-
//! free, straight faces within the ring and no body force there make it
//! independent of the ring (its domain independence is a check of the
//! discrete field). Faces that touch carry tractions `t`; then
//! `I −= ∫_faces t_i uᵃ_i,1 q ds` (the divergence theorem over the ring
//! leaves that line integral on the faces; the auxiliary faces are free),
//! summed over the face points' forces.

use crate::geom::Vec2;
use std::f64::consts::PI;

/// Shear modulus μ and Kolosov's constant κ (`3 − 4ν` plane strain,
/// `(3 − ν)/(1 + ν)` plane stress).
pub fn mu_kappa(e: f64, nu: f64, plane_strain: bool) -> (f64, f64) {
    let mu = e / (2.0 * (1.0 + nu));
    let kappa = if plane_strain {
        3.0 - 4.0 * nu
    } else {
        (3.0 - nu) / (1.0 + nu)
    };
    (mu, kappa)
}

/// `E′`: `E` in plane stress, `E/(1 − ν²)` in plane strain.
pub fn e_prime(e: f64, nu: f64, plane_strain: bool) -> f64 {
    if plane_strain { e / (1.0 - nu * nu) } else { e }
}

/// Energy release rate `G = (K_I² + K_II²)/E′` (Irwin).
pub fn energy_release_rate(k: [f64; 2], e_prime: f64) -> f64 {
    (k[0] * k[0] + k[1] * k[1]) / e_prime
}

/// Williams' near-tip field for `K_I = 1` (`mode = 0`) or `K_II = 1`
/// (`mode = 1`) at polar coordinates `(r, θ)` of the tip's frame (θ = ±π
/// on the faces): `([σ₁₁, σ₂₂, σ₁₂], ∂u_i/∂x_j)` in that frame, with
/// `u = √(r/2π)/(2μ) g(θ)`:
/// mode I `g = (cos(θ/2)(κ − 1 + 2 sin²(θ/2)), sin(θ/2)(κ + 1 − 2 cos²(θ/2)))`,
/// mode II `g = (sin(θ/2)(κ + 1 + 2 cos²(θ/2)), −cos(θ/2)(κ − 1 − 2 sin²(θ/2)))`
/// (Anderson, *Fracture Mechanics*, Tables 2.1–2.2).
pub fn williams(mode: usize, r: f64, theta: f64, mu: f64, kappa: f64) -> ([f64; 3], [[f64; 2]; 2]) {
    let (s, c) = (0.5 * theta).sin_cos();
    let (s3, c3) = (1.5 * theta).sin_cos();
    let f = 1.0 / (2.0 * PI * r).sqrt();
    let stress = if mode == 0 {
        [
            f * c * (1.0 - s * s3),
            f * c * (1.0 + s * s3),
            f * s * c * c3,
        ]
    } else {
        [
            -f * s * (2.0 + c * c3),
            f * s * c * c3,
            f * c * (1.0 - s * s3),
        ]
    };
    let (g, dg) = williams_g(mode, theta, kappa);
    let a = (r / (2.0 * PI)).sqrt() / (2.0 * mu);
    let (st, ct) = theta.sin_cos();
    let mut grad = [[0.0; 2]; 2];
    for i in 0..2 {
        let du_dr = a * g[i] / (2.0 * r);
        let du_dt = a * dg[i];
        grad[i][0] = ct * du_dr - st / r * du_dt;
        grad[i][1] = st * du_dr + ct / r * du_dt;
    }
    (stress, grad)
}

/// Williams' angular displacement function `g(θ)` and `dg/dθ` (see
/// [`williams`]).
fn williams_g(mode: usize, theta: f64, kappa: f64) -> ([f64; 2], [f64; 2]) {
    let (s, c) = (0.5 * theta).sin_cos();
    if mode == 0 {
        (
            [
                c * (kappa - 1.0 + 2.0 * s * s),
                s * (kappa + 1.0 - 2.0 * c * c),
            ],
            [
                -0.5 * s * (kappa - 1.0 + 2.0 * s * s) + 2.0 * s * c * c,
                0.5 * c * (kappa + 1.0 - 2.0 * c * c) + 2.0 * s * s * c,
            ],
        )
    } else {
        (
            [
                s * (kappa + 1.0 + 2.0 * c * c),
                -c * (kappa - 1.0 - 2.0 * s * s),
            ],
            [
                0.5 * c * (kappa + 1.0 + 2.0 * c * c) - 2.0 * s * s * c,
                0.5 * s * (kappa - 1.0 - 2.0 * s * s) + 2.0 * s * c * c,
            ],
        )
    }
}

/// The displacement of the two-term near-tip field of a straight crack
/// along the negative x axis with its tip at the origin:
/// `u = K_I √(r/2π)/(2μ) g_I(θ) + K_II √(r/2π)/(2μ) g_II(θ)` ([`williams`])
/// plus the uniform stress `σ_xx = T` along the crack (the T-stress),
/// `u_x = T (κ + 1) x/(8μ)`, `u_y = T (κ − 3) y/(8μ)`. On the faces
/// (`θ = ±π`) the sign of `p.y` picks the face (`y = 0` behind the tip:
/// the upper face).
pub fn k_t_displacement(k: [f64; 2], t: f64, p: Vec2, mu: f64, kappa: f64) -> [f64; 2] {
    let (r, theta) = (p.norm(), p.y.atan2(p.x));
    let a = (r / (2.0 * PI)).sqrt() / (2.0 * mu);
    let (g1, _) = williams_g(0, theta, kappa);
    let (g2, _) = williams_g(1, theta, kappa);
    let tt = t / (8.0 * mu);
    [
        a * (k[0] * g1[0] + k[1] * g2[0]) + tt * (kappa + 1.0) * p.x,
        a * (k[0] * g1[1] + k[1] * g2[1]) + tt * (kappa - 3.0) * p.y,
    ]
}

/// The actual field at a point for the interaction integral: stress
/// `[σ_xx, σ_yy, σ_xy]` and displacement gradient `∂u_i/∂x_j` (global
/// axes).
pub type TipSample = ([f64; 3], [[f64; 2]; 2]);

/// The ring of the interaction integral: `q = 1` for `r ≤ inner`, falling
/// smoothly (`1 − 3s² + 2s³`, `s = (r − inner)/(outer − inner)`) to 0 at
/// `outer`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ring {
    /// Radius where `q` starts to fall.
    pub inner: f64,
    /// Radius where `q` reaches 0.
    pub outer: f64,
}

impl Ring {
    /// `q` at `r`.
    pub fn q(&self, r: f64) -> f64 {
        if r <= self.inner {
            return 1.0;
        }
        if r >= self.outer {
            return 0.0;
        }
        let s = (r - self.inner) / (self.outer - self.inner);
        1.0 - 3.0 * s * s + 2.0 * s * s * s
    }
    /// `dq/dr` at `r` (0 outside the ring).
    pub fn dq_dr(&self, r: f64) -> f64 {
        if r <= self.inner || r >= self.outer {
            return 0.0;
        }
        let w = self.outer - self.inner;
        let s = (r - self.inner) / w;
        6.0 * s * (s - 1.0) / w
    }
}

/// `[K_I, K_II]` at the tip `tip` advancing along the unit vector `dir`,
/// from the interaction integral over `points` (`(x, weight)`; those
/// outside the ring are skipped) with the actual field `sample(x)`, in a
/// material of `E`, ν (plane strain or stress), less the work of the
/// face forces `faces` (`(x, f)`: a force `f` per thickness on the body
/// at the face point `x`, on its side of the crack) on the auxiliary
/// field.
#[allow(clippy::too_many_arguments)]
pub fn interaction_integral(
    tip: Vec2,
    dir: Vec2,
    ring: Ring,
    points: &[(Vec2, f64)],
    mut sample: impl FnMut(Vec2) -> Option<TipSample>,
    faces: &[(Vec2, Vec2)],
    (e, nu, plane_strain): (f64, f64, bool),
) -> [f64; 2] {
    let (mu, kappa) = mu_kappa(e, nu, plane_strain);
    let ep = e_prime(e, nu, plane_strain);
    let (e1, e2) = (dir, dir.perp());
    let mut i = [0.0; 2];
    for &(x, w) in points {
        let d = x - tip;
        let (x1, x2) = (d.dot(e1), d.dot(e2));
        let r = d.norm();
        let dq = ring.dq_dr(r);
        if dq == 0.0 {
            continue;
        }
        let Some((s, g)) = sample(x) else { continue };
        let q = [dq * x1 / r, dq * x2 / r];
        // the actual field in the tip's frame: σ' = R σ Rᵀ, ∇u' = R ∇u Rᵀ
        let rm = [[e1.x, e1.y], [e2.x, e2.y]];
        let sg = [[s[0], s[2]], [s[2], s[1]]];
        let rot = |m: [[f64; 2]; 2]| {
            let mut o = [[0.0; 2]; 2];
            for a in 0..2 {
                for b in 0..2 {
                    for k in 0..2 {
                        for l in 0..2 {
                            o[a][b] += rm[a][k] * m[k][l] * rm[b][l];
                        }
                    }
                }
            }
            o
        };
        let (sl, gl) = (rot(sg), rot(g));
        let theta = x2.atan2(x1);
        for (mode, im) in i.iter_mut().enumerate() {
            let (sa, ga) = williams(mode, r, theta, mu, kappa);
            let sa = [[sa[0], sa[2]], [sa[2], sa[1]]];
            let ea = [
                [ga[0][0], 0.5 * (ga[0][1] + ga[1][0])],
                [0.5 * (ga[0][1] + ga[1][0]), ga[1][1]],
            ];
            let mut wint = 0.0;
            for a in 0..2 {
                for b in 0..2 {
                    wint += sl[a][b] * ea[a][b];
                }
            }
            let mut sum = -wint * q[0];
            for j in 0..2 {
                for k in 0..2 {
                    sum += (sl[k][j] * ga[k][0] + sa[k][j] * gl[k][0]) * q[j];
                }
            }
            *im += w * sum;
        }
    }
    for &(x, f) in faces {
        let d = x - tip;
        let r = d.norm();
        let q = ring.q(r);
        if q == 0.0 {
            continue;
        }
        let (x1, x2) = (d.dot(e1), d.dot(e2));
        let fl = [f.dot(e1), f.dot(e2)];
        for (mode, im) in i.iter_mut().enumerate() {
            let (_, ga) = williams(mode, r, x2.atan2(x1), mu, kappa);
            *im -= q * (fl[0] * ga[0][0] + fl[1] * ga[1][0]);
        }
    }
    [0.5 * ep * i[0], 0.5 * ep * i[1]]
}

/// The maximum hoop-stress criterion (Erdogan & Sih 1963): the angle θ_c
/// (radians, from the direction of advance, positive to the left) at
/// which `σ_θθ` of the near-tip field is largest,
/// `θ_c = 2 arctan[(K_I − √(K_I² + 8K_II²)) / (4K_II)]` (0 for
/// `K_II = 0`), and the equivalent `K_eq = cos(θ_c/2)[K_I cos²(θ_c/2) −
/// (3/2) K_II sin θ_c]`, which growth compares with `K_Ic`.
pub fn max_hoop_stress(k: [f64; 2]) -> (f64, f64) {
    let [k1, k2] = k;
    let theta = if k2 == 0.0 {
        0.0
    } else {
        2.0 * ((k1 - (k1 * k1 + 8.0 * k2 * k2).sqrt()) / (4.0 * k2)).atan()
    };
    let c = (0.5 * theta).cos();
    (theta, c * (k1 * c * c - 1.5 * k2 * theta.sin()))
}

/// The path `y = λ(x)` of a crack that starts straight along the x axis
/// (tip at the origin) under `K_I`, a small `K_II` and the T-stress `T`,
/// growing with `k_II = 0` at its tip (local symmetry), to first order in
/// `K_II/K_I` (Cotterell & Rice 1980, "Slightly curved or kinked cracks",
/// Int. J. Fract. 16:155–169): their first-order
/// `k_II(x) = K_II + ½ K_I λ′(x) − T √(2/π) ∫₀ˣ λ′(ξ)/√(x − ξ) dξ`
/// set to zero and solved by Laplace transform gives
/// `λ′(x) = −(2K_II/K_I) e^{c²x} erfc(−c√x)` with `c = 2√2 T/K_I`, and
///
/// `λ(x) = −(2K_II/(K_I c²)) [e^{c²x} erfc(−c√x) − 1 − 2c √(x/π)]`:
///
/// the kink `−2K_II/K_I` of the maximum hoop stress at the start; a
/// negative T turns the path back parallel to the crack, a positive T
/// away from it (`λ = −2K_II x/K_I` for `T = 0`).
pub fn cotterell_rice_path(k: [f64; 2], t: f64, x: f64) -> f64 {
    let [k1, k2] = k;
    let c = 2.0 * std::f64::consts::SQRT_2 * t / k1;
    let z = c * x.sqrt();
    if z.abs() < 1e-4 {
        // e^{z²} erfc(−z) = 1 + 2z/√π + z² + 4z³/(3√π) + …
        return -2.0 * k2 / k1 * x * (1.0 + 4.0 * z / (3.0 * PI.sqrt()));
    }
    let e = (z * z).exp() * libm::erfc(-z);
    -2.0 * k2 / (k1 * c * c) * (e - 1.0 - 2.0 * z / PI.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::continuum::griffith::Griffith;
    use crate::continuum::material::elasticity;

    #[test]
    fn williams_strain_is_the_compliance_of_its_stress() {
        for strain in [false, true] {
            let (e, nu) = (3.0, 0.25);
            let (mu, kappa) = mu_kappa(e, nu, strain);
            let d = elasticity(e, nu, strain);
            for mode in 0..2 {
                for &(r, t) in &[(0.3, 0.4), (1.2, -2.5), (0.01, 3.0), (2.0, -0.1)] {
                    let (s, g) = williams(mode, r, t, mu, kappa);
                    let eps = [g[0][0], g[1][1], g[0][1] + g[1][0]];
                    let sd = [
                        d[0] * eps[0] + d[1] * eps[1],
                        d[1] * eps[0] + d[2] * eps[1],
                        d[3] * eps[2],
                    ];
                    for k in 0..3 {
                        assert!(
                            (sd[k] - s[k]).abs() < 1e-10 * s[k].abs().max(1.0 / r.sqrt()),
                            "{mode} {r} {t}: {sd:?} vs {s:?}"
                        );
                    }
                }
                // faces traction-free
                for t in [PI, -PI] {
                    let (s, _) = williams(mode, 0.5, t, mu, kappa);
                    assert!(s[1].abs() < 1e-12 && s[2].abs() < 1e-12, "{s:?}");
                }
            }
        }
    }

    /// The interaction integral of Griffith's exact field, on a polar grid
    /// around a tip, gives the exact `K_I`, `K_II` for any ring.
    #[test]
    fn interaction_integral_of_the_exact_field_is_exact() {
        let (e, nu) = (100.0, 0.3);
        for strain in [false, true] {
            let (mu, kappa) = mu_kappa(e, nu, strain);
            let dm = elasticity(e, nu, strain);
            for beta in [0.0f64, 0.5, 1.0] {
                let g = Griffith {
                    s: 1.5,
                    a: 1.0,
                    beta,
                    mu,
                    kappa,
                };
                let (sb, cb) = beta.sin_cos();
                let tip = Vec2::new(cb, sb);
                let dir = Vec2::new(cb, sb);
                let h = 1e-6;
                let sample = |x: Vec2| -> Option<TipSample> {
                    let du = |dx: Vec2| {
                        let (a, b) = (g.displacement(x + dx), g.displacement(x - dx));
                        [(a[0] - b[0]) / (2.0 * h), (a[1] - b[1]) / (2.0 * h)]
                    };
                    let (gx, gy) = (du(Vec2::new(h, 0.0)), du(Vec2::new(0.0, h)));
                    let _ = dm;
                    Some((g.stress(x), [[gx[0], gy[0]], [gx[1], gy[1]]]))
                };
                let exact = g.k();
                for ring in [
                    Ring {
                        inner: 0.1,
                        outer: 0.3,
                    },
                    Ring {
                        inner: 0.2,
                        outer: 0.6,
                    },
                ] {
                    let (gr, gw) = crate::continuum::quadrature::gauss_legendre(16);
                    let (gt, gwt) = crate::continuum::quadrature::gauss_legendre(64);
                    let mut pts = Vec::new();
                    for (a, wa) in gr.iter().zip(&gw) {
                        let r = ring.inner + (ring.outer - ring.inner) * 0.5 * (a + 1.0);
                        for (b, wb) in gt.iter().zip(&gwt) {
                            let t = PI * b;
                            let p = tip
                                + Vec2::new(
                                    cb * t.cos() - sb * t.sin(),
                                    sb * t.cos() + cb * t.sin(),
                                ) * r;
                            pts.push((p, wa * wb * 0.5 * (ring.outer - ring.inner) * PI * r));
                        }
                    }
                    let k =
                        interaction_integral(tip, dir, ring, &pts, sample, &[], (e, nu, strain));
                    let scale = exact[0].abs().max(exact[1].abs());
                    assert!(
                        (k[0] - exact[0]).abs() < 1e-4 * scale
                            && (k[1] - exact[1]).abs() < 1e-4 * scale,
                        "{strain} β {beta}: {k:?} vs {exact:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn hoop_stress_direction() {
        assert_eq!(max_hoop_stress([1.0, 0.0]), (0.0, 1.0));
        // pure mode II: θ_c = −2 arctan(1/√2) ≈ −70.53°
        let (t, k) = max_hoop_stress([0.0, 1.0]);
        assert!(
            (t.to_degrees() + 70.528779).abs() < 1e-5,
            "{}",
            t.to_degrees()
        );
        assert!((k - 2.0 / 3f64.sqrt()).abs() < 1e-9, "{k}");
        // σ_θθ is stationary there: ∂σ_θθ/∂θ = 0 ⇔ K_I sinθ + K_II (3cosθ − 1) = 0
        for kk in [[1.0, 0.5], [0.3, -1.0], [2.0, 0.1]] {
            let (t, _) = max_hoop_stress(kk);
            assert!((kk[0] * t.sin() + kk[1] * (3.0 * t.cos() - 1.0)).abs() < 1e-12);
        }
    }
}
