//! Disc–body contact springs treated implicitly in the body's Newmark step.
//!
//! Why: if the body received at `t + Δt` the contact force computed from
//! its state at `t` (a plain staggered scheme), the lag would act on the
//! body as a negative dashpot of about `k_n Δt`, and with energy-conserving
//! Newmark (γ = 1/2, β = 1/4) a stiff contact gains energy without bound.
//!
//! How, per coupled step (disc positions already at `t + Δt`):
//! * each contact is linearised in the unknown displacement increment `w`
//!   of its body point `H` over the step: overlap `δ = δ̂ − n·w`, relative
//!   velocity `(v_disc − w/Δt)` (the disc's `v_{n+½}` is its increment over
//!   the same step), shear `F_s = F_s,old − k_s v_t Δt`, Coulomb cap — the
//!   DEM law of [`crate::dem::contact::evaluate`], piecewise affine in `w`;
//! * the body reports its free displacement `u_free` at the points and its
//!   compliance `S = Φ A⁻¹ Φᵀ` (Eq. 49 with point loads, Eq. 46 / E7), so
//!   `u = u_free + S g(u)` with `g` the contact forces on the body;
//! * that small piecewise-affine system is solved by semi-smooth Newton
//!   (exact once the contact regimes — open, stick, slide — settle);
//! * the body takes the forces, the discs get their opposite at the next
//!   step: both sides see the same force at the same time level.

use crate::dem::contact::ContactLaw;
use crate::geom::Vec2;

/// One disc–body contact candidate of a step, linearised in the increment
/// `w` of its body point.
#[derive(Debug, Clone, Copy)]
pub struct Linear {
    pub law: ContactLaw,
    /// Dashpot coefficients.
    pub cn: f64,
    pub cs: f64,
    /// Unit normal from the disc towards the body.
    pub n: Vec2,
    /// Overlap for `w = 0`.
    pub delta0: f64,
    /// Disc contact-point velocity components: `v·n` and `v·t + ω r`.
    pub vn0: f64,
    pub vt0: f64,
    /// Shear force history at the start of the step.
    pub fs_old: f64,
    pub dt: f64,
}

/// The contact law at one increment `w`: force on the body, its Jacobian
/// `∂g/∂w`, and what the contact stores.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Eval {
    /// The increment `w` of the body point it was evaluated at.
    pub w: Vec2,
    /// Force on the body (the disc gets `−g`).
    pub g: Vec2,
    /// `∂g/∂w`, row-major.
    pub jac: [f64; 4],
    /// New shear history, overlap, elastic and total normal force.
    pub fs: f64,
    pub overlap: f64,
    pub fn_elastic: f64,
    pub fn_total: f64,
    /// Open 0, stick 1, slide ±2, +4 when the no-tension clamp bites.
    pub regime: i8,
}

impl Linear {
    /// Eqs. (35)–(37) (E6, E12) at the increment `w` of the body point.
    pub fn eval(&self, w: Vec2) -> Eval {
        let (n, law, dt) = (self.n, &self.law, self.dt);
        let t = n.perp();
        let delta = self.delta0 - n.dot(w);
        if delta <= 0.0 {
            return Eval {
                w,
                g: Vec2::ZERO,
                jac: [0.0; 4],
                fs: 0.0,
                overlap: delta,
                fn_elastic: 0.0,
                fn_total: 0.0,
                regime: 0,
            };
        }
        let vn = self.vn0 - n.dot(w) / dt;
        let vt = self.vt0 - t.dot(w) / dt;
        let fn_el = law.kn * delta;
        let mut fn_tot = fn_el + self.cn * vn;
        // ∂F_n/∂w = dfn · n
        let mut dfn = -(law.kn + self.cn / dt);
        let mut regime = 0;
        if law.no_tension && fn_tot < 0.0 {
            fn_tot = 0.0;
            dfn = 0.0;
            regime = 4;
        }
        let trial = self.fs_old - law.ks * vt * dt;
        let cap = law.mu * fn_el + law.cohesion;
        // F_s total and its gradient ∂F_s/∂w = dfs_t · t + dfs_n · n
        let (fs, fs_tot, dfs_t, dfs_n) = if trial.abs() <= cap {
            regime += 1;
            (trial, trial - self.cs * vt, law.ks + self.cs / dt, 0.0)
        } else {
            let s = trial.signum();
            regime += 2 * s as i8;
            (s * cap, s * cap, 0.0, -s * law.mu * law.kn)
        };
        // g = F_n n − F_s t
        let g = n * fn_tot - t * fs_tot;
        let dfs = t * dfs_t + n * dfs_n;
        let dn = n * dfn;
        let jac = [
            n.x * dn.x - t.x * dfs.x,
            n.x * dn.y - t.x * dfs.y,
            n.y * dn.x - t.y * dfs.x,
            n.y * dn.y - t.y * dfs.y,
        ];
        Eval {
            w,
            g,
            jac,
            fs,
            overlap: delta,
            fn_elastic: fn_el,
            fn_total: fn_tot,
            regime,
        }
    }
}

/// Solve `u = u_free + S g(u − u_base)` for the contact forces `g` on the
/// body (semi-smooth Newton over the piecewise-affine contact laws).
/// `s` is the 2m × 2m compliance, row-major. Returns the evaluations at the
/// solution and the number of Newton iterations.
pub fn solve(
    contacts: &[Linear],
    base: &[Vec2],
    free: &[Vec2],
    s: &[f64],
    out: &mut Vec<Eval>,
) -> usize {
    let m = contacts.len();
    let m2 = 2 * m;
    let mut w = vec![Vec2::ZERO; m];
    let mut mat = vec![0.0; m2 * m2];
    let mut rhs = vec![0.0; m2];
    out.clear();
    out.extend(contacts.iter().map(|c| c.eval(Vec2::ZERO)));
    const MAX_ITER: usize = 30;
    for iter in 1..=MAX_ITER {
        // residual R = w + base − free − S g, Newton matrix I − S J
        for i in 0..m2 {
            let mut sg = 0.0;
            for (k, e) in out.iter().enumerate() {
                sg += s[i * m2 + 2 * k] * e.g.x + s[i * m2 + 2 * k + 1] * e.g.y;
            }
            let (wi, bi, fi) = if i % 2 == 0 {
                (w[i / 2].x, base[i / 2].x, free[i / 2].x)
            } else {
                (w[i / 2].y, base[i / 2].y, free[i / 2].y)
            };
            rhs[i] = -(wi + bi - fi - sg);
            for (k, e) in out.iter().enumerate() {
                let (a, b) = (s[i * m2 + 2 * k], s[i * m2 + 2 * k + 1]);
                mat[i * m2 + 2 * k] = -(a * e.jac[0] + b * e.jac[2]);
                mat[i * m2 + 2 * k + 1] = -(a * e.jac[1] + b * e.jac[3]);
            }
            mat[i * m2 + i] += 1.0;
        }
        gauss_solve(&mut mat, &mut rhs, m2);
        let mut settled = true;
        for (k, c) in contacts.iter().enumerate() {
            w[k] += Vec2::new(rhs[2 * k], rhs[2 * k + 1]);
            let e = c.eval(w[k]);
            settled &= e.regime == out[k].regime;
            out[k] = e;
        }
        if settled {
            return iter;
        }
    }
    MAX_ITER
}

/// Solve `a x = b` in place (`b ← x`), Gaussian elimination with partial
/// pivoting; `a` is n × n row-major and is destroyed.
fn gauss_solve(a: &mut [f64], b: &mut [f64], n: usize) {
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap_or(col);
        if a[piv * n + col] == 0.0 {
            continue;
        }
        if piv != col {
            for k in 0..n {
                a.swap(piv * n + k, col * n + k);
            }
            b.swap(piv, col);
        }
        let d = a[col * n + col];
        for i in col + 1..n {
            let f = a[i * n + col] / d;
            if f != 0.0 {
                for k in col..n {
                    a[i * n + k] -= f * a[col * n + k];
                }
                b[i] -= f * b[col];
            }
        }
    }
    for col in (0..n).rev() {
        let mut x = b[col];
        for k in col + 1..n {
            x -= a[col * n + k] * b[k];
        }
        let d = a[col * n + col];
        b[col] = if d != 0.0 { x / d } else { 0.0 };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::contact::{Side, evaluate};

    fn law() -> ContactLaw {
        ContactLaw {
            kn: 1e6,
            ks: 5e5,
            mu: 0.4,
            beta_n: 0.01,
            ..Default::default()
        }
    }

    /// The linearised law is the DEM law with the body point moving by `w`.
    #[test]
    fn matches_the_dem_contact_law_in_every_regime() {
        let dt = 1e-3;
        let n = Vec2::new(0.6, -0.8);
        for (fs_old, vt0, w) in [
            (0.0, 0.1, Vec2::new(1e-5, 2e-5)),   // stick
            (150.0, 3.0, Vec2::new(-1e-5, 0.0)), // slide +
            (-50.0, -4.0, Vec2::new(0.0, 3e-5)), // slide −
            (0.0, 0.0, Vec2::new(-8e-4, 1e-3)),  // open
        ] {
            let l = law();
            let (cn, cs) = (l.beta_n * l.kn, 0.0);
            let c = Linear {
                law: l,
                cn,
                cs,
                n,
                delta0: 5e-4,
                vn0: 0.2,
                vt0,
                fs_old,
                dt,
            };
            let e = c.eval(w);
            // the same contact through dem::contact::evaluate: disc i at
            // rest frame, body point j moving with w/dt
            let t = n.perp();
            let vi = n * c.vn0 + t * c.vt0;
            let i = Side {
                pos: Vec2::ZERO,
                vel: vi,
                omega: 0.0,
                radius: 0.0,
            };
            let j = Side {
                pos: n,
                vel: w * (1.0 / dt),
                omega: 0.0,
                radius: 0.0,
            };
            let delta = c.delta0 - n.dot(w);
            let mut fs = fs_old;
            if delta > 0.0 {
                let f = evaluate(&l, n, delta, &i, &j, (cn, cs), &mut fs, dt);
                assert!((e.g + f.f).norm() < 1e-9 * f.f.norm(), "{e:?} {f:?}");
                assert!((e.fs - fs).abs() < 1e-9 * fs.abs().max(1.0));
            } else {
                assert_eq!(e.g, Vec2::ZERO);
            }
            // Jacobian against central differences (affine within a regime)
            let h = 1e-9;
            for (a, dw) in [Vec2::new(h, 0.0), Vec2::new(0.0, h)]
                .into_iter()
                .enumerate()
            {
                let d = (c.eval(w + dw).g - c.eval(w - dw).g) * (0.5 / h);
                let scale = l.kn + cn / dt;
                assert!(
                    (d.x - e.jac[a]).abs() < 1e-6 * scale,
                    "{a} {d:?} {:?}",
                    e.jac
                );
                assert!((d.y - e.jac[2 + a]).abs() < 1e-6 * scale);
            }
        }
    }

    /// A body point on a spring of compliance s: the Newton solution makes
    /// `u = u_free + s g(u)` hold exactly, and finds the stick/slide regime.
    #[test]
    fn newton_solves_the_piecewise_affine_system() {
        let dt = 1e-3;
        let l = ContactLaw {
            beta_n: 0.0,
            ..law()
        };
        let n = Vec2::new(0.0, -1.0);
        let c = Linear {
            law: l,
            cn: 0.0,
            cs: 0.0,
            n,
            delta0: 1e-3,
            vn0: 0.0,
            vt0: 2.0,
            fs_old: 0.0,
            dt,
        };
        let s = [2e-6, 0.5e-6, 0.5e-6, 1e-6];
        let base = [Vec2::new(0.01, 0.02)];
        let free = [Vec2::new(0.0101, 0.0199)];
        let mut out = Vec::new();
        let it = solve(&[c], &base, &free, &s, &mut out);
        assert!(it < 10);
        let g = out[0].g;
        let u = base[0]
            + (free[0] - base[0])
            + Vec2::new(s[0] * g.x + s[1] * g.y, s[2] * g.x + s[3] * g.y);
        let w = u - base[0];
        assert_eq!(c.eval(w).regime, out[0].regime);
        assert!((c.eval(w).g - g).norm() < 1e-9 * g.norm());
        // sliding (v_t Δt k_s = 1000 > μ F_n): the shear sits on the cap
        assert_eq!(out[0].regime.abs(), 2);
        assert!((out[0].fs.abs() - l.mu * out[0].fn_elastic).abs() < 1e-9 * out[0].fn_elastic);
    }

    #[test]
    fn gauss_with_pivoting() {
        let mut a = vec![0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0];
        let x = [1.0, -2.0, 0.5];
        let mut b: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|k| a[i * 3 + k] * x[k]).sum())
            .collect();
        gauss_solve(&mut a, &mut b, 3);
        for k in 0..3 {
            assert!((b[k] - x[k]).abs() < 1e-14);
        }
    }
}
