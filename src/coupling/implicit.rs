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

use crate::continuum::compliance::{Compliance, dense_mul_rows};
use crate::dem::contact::{ContactLaw, SlipNormal};
use crate::geom::Vec2;
use crate::sparse::gauss_solve;

/// One disc–body contact candidate of a step, linearised in the increment
/// `w` of its body point.
#[derive(Debug, Clone, Copy)]
pub struct Linear {
    /// Contact law of the disc–boundary pair (Eqs. 35–38).
    pub law: ContactLaw,
    /// Normal dashpot coefficient `c_n` for this contact's effective mass.
    pub cn: f64,
    /// Shear dashpot coefficient `c_s`.
    pub cs: f64,
    /// Unit normal from the disc towards the body.
    pub n: Vec2,
    /// Overlap for `w = 0`.
    pub delta0: f64,
    /// Relative normal velocity `v·n` of the disc's contact point for `w = 0`.
    pub vn0: f64,
    /// Relative tangential velocity `v·t + ω r` for `w = 0`.
    pub vt0: f64,
    /// Shear force history at the start of the step.
    pub fs_old: f64,
    /// Time step Δt of the body step (increments over it).
    pub dt: f64,
    /// Not a contact but a contact's geometric stiffness `C` (row-major) on
    /// the increment `w` of its functional pair
    /// ([`ChainStiffness`](crate::continuum::ChainStiffness)): `g = −C w`.
    pub spring: Option<[f64; 4]>,
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
    /// New shear history (force along `t = perp(n)`, Eq. 36 capped by Eq. 37).
    pub fs: f64,
    /// Overlap δ at `w`.
    pub overlap: f64,
    /// Elastic normal force `k_n δ`.
    pub fn_elastic: f64,
    /// Total normal force `k_n δ + c_n δ̇` (clamped at 0 with `no_tension`).
    pub fn_total: f64,
    /// Normal force of the Coulomb cap (`max(0, F_n,total)` or `k_n δ`,
    /// [`ContactLaw::slip_normal`]); it also limits the rolling moment.
    pub fn_cap: f64,
    /// Open 0; else stick 1, slide along +t 2, along −t 3, plus 4 when the
    /// no-tension clamp bites and 8 when the total-force cap is clamped at
    /// zero (each a different affine piece).
    pub regime: i8,
}

impl Linear {
    /// The unknown of a geometric stiffness `c` ([`Linear::spring`]).
    pub fn spring(c: [[f64; 2]; 2], dt: f64) -> Linear {
        Linear {
            law: ContactLaw::default(),
            cn: 0.0,
            cs: 0.0,
            n: Vec2::ZERO,
            delta0: 0.0,
            vn0: 0.0,
            vt0: 0.0,
            fs_old: 0.0,
            dt,
            spring: Some([c[0][0], c[0][1], c[1][0], c[1][1]]),
        }
    }

    /// Eqs. (35)–(37) (E6, E12) at the increment `w` of the body point (a
    /// geometric stiffness: `g = −C w`).
    pub fn eval(&self, w: Vec2) -> Eval {
        if let Some(c) = self.spring {
            let jac = [-c[0], -c[1], -c[2], -c[3]];
            return Eval {
                w,
                g: apply2(&jac, w),
                jac,
                fs: 0.0,
                overlap: 0.0,
                fn_elastic: 0.0,
                fn_total: 0.0,
                fn_cap: 0.0,
                regime: 1,
            };
        }
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
                fn_cap: 0.0,
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
        // the cap's normal force and its gradient ∂F_cap/∂w = dcap · n:
        // with the total force (the default, Eq. 37 with Eq. 35) the
        // sliding shear force follows the normal dashpot too, so the slide
        // branch's Jacobian has the term μ (k_n + c_n/Δt) along n
        let (fn_cap, dcap) = match law.slip_normal {
            SlipNormal::Elastic => (fn_el, -law.kn),
            SlipNormal::Total => {
                if fn_tot > 0.0 {
                    (fn_tot, dfn)
                } else {
                    regime += 8;
                    (0.0, 0.0)
                }
            }
        };
        let cap = law.mu * fn_cap + law.cohesion;
        // F_s total and its gradient ∂F_s/∂w = dfs_t · t + dfs_n · n
        let (fs, fs_tot, dfs_t, dfs_n) = if trial.abs() <= cap {
            regime += 1;
            (trial, trial - self.cs * vt, law.ks + self.cs / dt, 0.0)
        } else {
            let s = trial.signum();
            regime += if s > 0.0 { 2 } else { 3 };
            (s * cap, s * cap, 0.0, s * law.mu * dcap)
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
            fn_cap,
            regime,
        }
    }
}

/// Contacts up to which the Newton matrix `I − S J` is formed and factored
/// densely (`8m³/3` flops); beyond, it is solved by GMRES with products `S x`.
const DENSE_MAX: usize = 48;
/// Semi-smooth Newton iterations at most, by default (the regimes settle
/// in 1–5; `[simulation] contact_iterations`).
pub const MAX_NEWTON: usize = 30;
/// Full Newton steps before the steps are damped ([`Solver::line_search`]).
const UNDAMPED: usize = 10;
/// A damped Newton step has converged when the residual is this fraction
/// of the increments and free motions.
const RESIDUAL_TOL: f64 = 1e-10;
/// A solve whose regimes still change at the iteration cap is accepted
/// when its residual is this fraction of the increments and free motions
/// (regimes flickering at a kink of a law whose force is continuous there:
/// the iterate is a solution to this accuracy).
const ACCEPT_TOL: f64 = 1e-6;
/// GMRES: Krylov vectors per restart, restarts, relative tolerance.
const KRYLOV: usize = 40;
const RESTARTS: usize = 25;
const GMRES_RTOL: f64 = 1e-13;

/// When [`Solver::line_search`] counts a contact that crossed zero overlap
/// (the jump of its dashpot force) as settled.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Touch {
    /// With the full Newton step: every other contact then solves the
    /// affine system of its regime exactly.
    FullStep,
    /// With a damped step too (after [`UNDAMPED`] iterations).
    Any,
}

/// Why a contact solve did not converge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Unsolved {
    /// The contacts' regimes (open, stick, slide) still changed at the
    /// last Newton iteration allowed.
    Newton {
        /// Iterations taken (the cap).
        iterations: usize,
    },
    /// A Newton step's linear system kept a residual above the tolerance
    /// after every GMRES restart.
    Gmres {
        /// Relative residual reached.
        residual: f64,
    },
}

impl std::fmt::Display for Unsolved {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Unsolved::Newton { iterations } => write!(
                f,
                "the contacts' regimes still changed after {iterations} Newton iterations (simulation.contact_iterations)"
            ),
            Unsolved::Gmres { residual } => write!(
                f,
                "GMRES left a relative residual of {residual:.2e} (above {GMRES_RTOL:e}) after {RESTARTS} restarts of {KRYLOV}"
            ),
        }
    }
}

/// The contact solve and its scratch (kept between steps).
#[derive(Default)]
pub struct Solver {
    /// Newton iterations allowed (0: [`MAX_NEWTON`]).
    pub max_newton: usize,
    w: Vec<Vec2>,
    s: Vec<f64>,
    mat: Vec<f64>,
    rhs: Vec<f64>,
    r: Vec<Vec2>,
    t: Vec<Vec2>,
    st: Vec<Vec2>,
    d: Vec<Vec2>,
    /// Preconditioner blocks `(I − S_kk J_k)⁻¹`, row-major.
    pre: Vec<[f64; 4]>,
    /// Diagonal blocks `S_kk`.
    diag: Vec<[f64; 4]>,
    basis: Vec<Vec<Vec2>>,
    hess: Vec<f64>,
    res: Vec<Vec2>,
    scratch: Vec<Vec2>,
    /// Products `S x` of the last solve.
    pub products: usize,
    /// The squared residual and squared scale of the last damped step
    /// ([`line_search`](Self::line_search)).
    last: (f64, f64),
    /// Row permutation of the LU factors in `mat` ([`lu_factor`]).
    perm: (Vec<usize>, Vec<usize>),
}

impl Solver {
    /// Solve `u = u_free + S g(u − u_base)` for the contact forces `g` on
    /// the body (semi-smooth Newton over the piecewise-affine contact laws;
    /// exact once the regimes settle), starting from the body's free
    /// increment `u_free − u_base` (the regimes there are usually those of
    /// the solution: one Newton step). Writes the evaluations at the
    /// solution; returns the number of Newton iterations.
    ///
    /// Up to `DENSE_MAX` (48) contacts the Newton matrix `I − S J` is formed
    /// and factored; above, each Newton step is solved by GMRES on products
    /// `S x` (right block-Jacobi preconditioner `(I − S_kk J_k)⁻¹`), to a
    /// relative residual of 1e-13. The contact springs are usually much
    /// softer than the body, so `I − S J` is close to the identity and a few
    /// products suffice.
    pub fn solve(
        &mut self,
        contacts: &[Linear],
        base: &[Vec2],
        free: &[Vec2],
        s: &mut Compliance,
        out: &mut Vec<Eval>,
    ) -> Result<usize, Unsolved> {
        let m = contacts.len();
        self.products = 0;
        self.last = (f64::INFINITY, 0.0);
        self.w.clear();
        self.w.extend(free.iter().zip(base).map(|(f, b)| *f - *b));
        out.clear();
        out.extend(contacts.iter().zip(&self.w).map(|(c, w)| c.eval(*w)));
        if m <= DENSE_MAX {
            s.dense(&mut self.s);
            self.dense_newton(contacts, base, free, out)
        } else {
            self.krylov_newton(contacts, base, free, s, out)
        }
    }

    /// [`solve`](Self::solve) for a dense `S` (2m × 2m, row-major) of any
    /// size, each Newton step solved directly over the closed contacts only
    /// (an open contact takes no force: its unknown follows the others'),
    /// `(2c)³` for `c` closed contacts. The compliant sub-cycled scheme's
    /// solve, whose compliance is that of a whole body step.
    pub fn solve_dense(
        &mut self,
        contacts: &[Linear],
        base: &[Vec2],
        free: &[Vec2],
        s: &[f64],
        out: &mut Vec<Eval>,
    ) -> Result<usize, Unsolved> {
        let m = contacts.len();
        let m2 = 2 * m;
        self.products = 0;
        self.last = (f64::INFINITY, 0.0);
        out.clear();
        out.extend(contacts.iter().map(|c| c.eval(Vec2::ZERO)));
        self.w.clear();
        self.w.resize(m, Vec2::ZERO);
        for v in [&mut self.r, &mut self.t, &mut self.st] {
            v.clear();
            v.resize(m, Vec2::ZERO);
        }
        let mut closed: Vec<usize> = Vec::new();
        // the closed contacts and their Jacobians of the factored matrix
        let mut factored: (Vec<usize>, Vec<[f64; 4]>) = (vec![usize::MAX], Vec::new());
        for iter in 1..=self.newton_cap() {
            // −R = −(w + base − free − S g); after the first iteration `st`
            // holds S g of the present iterate (the line search's last
            // residual)
            if iter == 1 {
                for (t, e) in self.t.iter_mut().zip(out.iter()) {
                    *t = e.g;
                }
                Compliance::Dense(s).mul(&self.t, &mut self.st);
                self.products += 1;
            }
            for k in 0..m {
                self.r[k] = -(self.w[k] + base[k] - free[k] - self.st[k]);
            }
            // (I − S_CC J_C) d_C = −R_C over the closed contacts; the
            // matrix depends on those contacts' Jacobians only (S is fixed
            // for the solve), so while they stay the same its LU factors
            // are used again: the same arithmetic, one factorisation less
            closed.clear();
            closed.extend((0..m).filter(|&k| out[k].regime != 0));
            let c2 = 2 * closed.len();
            let same = closed == factored.0
                && closed
                    .iter()
                    .zip(&factored.1)
                    .all(|(&k, j)| out[k].jac == *j);
            self.rhs.clear();
            for &k in &closed {
                self.rhs.extend([self.r[k].x, self.r[k].y]);
            }
            if !same {
                self.mat.clear();
                self.mat.resize(c2 * c2, 0.0);
                for (i, &k) in closed.iter().enumerate() {
                    // column-major: entry (row 2i + a, column q) at q c2 + 2i + a
                    for a in 0..2 {
                        let row = &s[(2 * k + a) * m2..(2 * k + a + 1) * m2];
                        let ri = 2 * i + a;
                        for (j, &l) in closed.iter().enumerate() {
                            let (x, y) = (row[2 * l], row[2 * l + 1]);
                            let jac = &out[l].jac;
                            self.mat[2 * j * c2 + ri] = -(x * jac[0] + y * jac[2]);
                            self.mat[(2 * j + 1) * c2 + ri] = -(x * jac[1] + y * jac[3]);
                        }
                        self.mat[ri * c2 + ri] += 1.0;
                    }
                }
                lu_factor(&mut self.mat, c2, &mut self.perm);
                factored.0.clone_from(&closed);
                factored.1.clear();
                factored.1.extend(closed.iter().map(|&k| out[k].jac));
            }
            lu_apply(&self.mat, &mut self.rhs, c2, &self.perm);
            // d_O = −R_O + S_OC J_C d_C: J d on the closed ones, S of it
            self.t.iter_mut().for_each(|t| *t = Vec2::ZERO);
            for (i, &k) in closed.iter().enumerate() {
                let d = Vec2::new(self.rhs[2 * i], self.rhs[2 * i + 1]);
                self.t[k] = apply2(&out[k].jac, d);
            }
            let open = (0..m).filter(|&k| out[k].regime == 0);
            dense_mul_rows(s, &self.t, open, &mut self.st);
            self.products += 1;
            let mut d: Vec<Vec2> = (0..m)
                .map(|k| match out[k].regime {
                    0 => self.r[k] + self.st[k],
                    _ => Vec2::ZERO,
                })
                .collect();
            for (i, &k) in closed.iter().enumerate() {
                d[k] = Vec2::new(self.rhs[2 * i], self.rhs[2 * i + 1]);
            }
            // the compliance of a whole body step makes the contacts
            // strongly coupled: damped steps from the first
            let touch = if iter > UNDAMPED {
                Touch::Any
            } else {
                Touch::FullStep
            };
            // the residual at the present iterate is −R's (its squares)
            let phi = self.r[..m].iter().map(|r| r.dot(*r)).sum::<f64>();
            if self.line_search(
                contacts,
                base,
                free,
                &mut Compliance::Dense(s),
                out,
                &d,
                (touch, Some(phi)),
            ) {
                return Ok(iter);
            }
        }
        self.unsettled()
    }

    fn dense_newton(
        &mut self,
        contacts: &[Linear],
        base: &[Vec2],
        free: &[Vec2],
        out: &mut [Eval],
    ) -> Result<usize, Unsolved> {
        let m2 = 2 * contacts.len();
        let cap = self.newton_cap();
        self.mat.resize(m2 * m2, 0.0);
        self.rhs.resize(m2, 0.0);
        for iter in 1..=cap {
            let (s, w) = (&self.s, &self.w);
            let (mat, rhs) = (&mut self.mat, &mut self.rhs);
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
            gauss_solve(mat, rhs, m2);
            let rhs = &self.rhs;
            let d = |k: usize| Vec2::new(rhs[2 * k], rhs[2 * k + 1]);
            let settled = if iter <= UNDAMPED {
                settle(&mut self.w, contacts, out, d)
            } else {
                let d: Vec<Vec2> = (0..m2 / 2).map(d).collect();
                let dense = std::mem::take(&mut self.s);
                let settled = self.line_search(
                    contacts,
                    base,
                    free,
                    &mut Compliance::Dense(&dense),
                    out,
                    &d,
                    (Touch::Any, None),
                );
                self.s = dense;
                settled
            };
            if settled {
                return Ok(iter);
            }
        }
        self.unsettled()
    }

    fn krylov_newton(
        &mut self,
        contacts: &[Linear],
        base: &[Vec2],
        free: &[Vec2],
        s: &mut Compliance,
        out: &mut [Eval],
    ) -> Result<usize, Unsolved> {
        let m = contacts.len();
        s.diagonal(&mut self.diag);
        for v in [&mut self.r, &mut self.t, &mut self.st, &mut self.d] {
            v.clear();
            v.resize(m, Vec2::ZERO);
        }
        for iter in 1..=self.newton_cap() {
            // R = w + base − free − S g; the Newton step solves (I − S J) d = −R
            for (t, e) in self.t.iter_mut().zip(out.iter()) {
                *t = e.g;
            }
            s.mul(&self.t, &mut self.st);
            self.products += 1;
            for k in 0..m {
                self.r[k] = -(self.w[k] + base[k] - free[k] - self.st[k]);
            }
            self.pre.clear();
            self.pre.extend(out.iter().zip(&self.diag).map(|(e, sk)| {
                let a = mul2(sk, &e.jac);
                inv2(&[1.0 - a[0], -a[1], -a[2], 1.0 - a[3]])
            }));
            if let Some(residual) = self.gmres(s, out) {
                return Err(Unsolved::Gmres { residual });
            }
            let d = std::mem::take(&mut self.d);
            let settled = if iter <= UNDAMPED {
                settle(&mut self.w, contacts, out, |k| d[k])
            } else {
                self.line_search(contacts, base, free, s, out, &d, (Touch::Any, None))
            };
            self.d = d;
            if settled {
                return Ok(iter);
            }
        }
        self.unsettled()
    }

    /// A damped Newton step: `w += t d` with `t` halved from 1 until the
    /// residual `|w + base − free − S g|` drops (Armijo), at least 1/64;
    /// true when the full step was taken and no contact changed regime
    /// (then `w` solves the system exactly), or the residual is at
    /// round-off. The semi-smooth Newton steps of the piecewise-affine
    /// contact laws can swap regimes back and forth without end; halving
    /// them settles the cycle.
    ///
    /// A contact that opened or closed within its own step's reach of zero
    /// overlap (`|δ| ≤ t |d·n|`) counts as settled — with the full step
    /// only, or also with a damped one ([`Touch`]): with a normal dashpot
    /// the force jumps at `δ = 0` (from 0 to `c_n δ̇`), and a contact just
    /// touching has no exact solution on either side of the jump — the
    /// step ends with it on the side the last iterate found.
    /// `phi`: the squared residual at the present iterate, if known.
    #[allow(clippy::too_many_arguments)]
    fn line_search(
        &mut self,
        contacts: &[Linear],
        base: &[Vec2],
        free: &[Vec2],
        s: &mut Compliance,
        out: &mut [Eval],
        d: &[Vec2],
        (touch, phi): (Touch, Option<f64>),
    ) -> bool {
        let m = contacts.len();
        for v in [&mut self.t, &mut self.st, &mut self.scratch] {
            v.resize(m, Vec2::ZERO);
        }
        let mut residual = |w: &[Vec2], e: &[Eval], t: &mut [Vec2], st: &mut [Vec2]| {
            for (t, e) in t.iter_mut().zip(e) {
                *t = e.g;
            }
            s.mul(t, st);
            (0..m)
                .map(|k| {
                    let r = w[k] + base[k] - free[k] - st[k];
                    r.dot(r)
                })
                .sum::<f64>()
        };
        let phi = phi.unwrap_or_else(|| {
            self.products += 1;
            residual(&self.w, out, &mut self.t, &mut self.st)
        });
        let mut step = 1.0;
        loop {
            for ((x, &w), &dk) in self.scratch[..m].iter_mut().zip(&self.w).zip(d) {
                *x = w + dk * step;
            }
            let trial: Vec<Eval> = (contacts.iter().zip(&self.scratch))
                .map(|(c, w)| c.eval(*w))
                .collect();
            let now = residual(&self.scratch, &trial, &mut self.t, &mut self.st);
            self.products += 1;
            if now <= (1.0 - 1e-4 * step) * phi || step < 1.0 / 64.0 {
                let mut flips = false;
                let same = (trial.iter().zip(out.iter()).zip(contacts.iter().zip(d))).all(
                    |((a, b), (c, d))| {
                        let flip = (a.regime == 0) != (b.regime == 0)
                            && a.overlap.abs() <= step * d.dot(c.n).abs();
                        flips |= flip;
                        a.regime == b.regime || flip
                    },
                );
                self.w.copy_from_slice(&self.scratch);
                out.copy_from_slice(&trial);
                // a solution on a regime's boundary (a contact just
                // closing, a shear force just at its cap) is reached by
                // the residual, not by a regime that stays put
                let scale: f64 = (0..m)
                    .map(|k| (free[k] - base[k]).dot(free[k] - base[k]) + self.w[k].dot(self.w[k]))
                    .sum();
                self.last = (now, scale);
                return ((step == 1.0 || (flips && touch == Touch::Any)) && same)
                    || now <= RESIDUAL_TOL * RESIDUAL_TOL * scale;
            }
            step *= 0.5;
        }
    }

    /// The end of a solve whose regimes still changed at the iteration
    /// cap: accepted when the last damped step's residual is within
    /// [`ACCEPT_TOL`] of the motions, else [`Unsolved::Newton`].
    fn unsettled(&self) -> Result<usize, Unsolved> {
        let cap = self.newton_cap();
        let (residual, scale) = self.last;
        if residual <= ACCEPT_TOL * ACCEPT_TOL * scale {
            Ok(cap)
        } else {
            Err(Unsolved::Newton { iterations: cap })
        }
    }

    /// `y ← (I − S J) P x` (P the preconditioner), using `t`, `st`.
    fn apply(&mut self, s: &mut Compliance, out: &[Eval], x: &[Vec2], y: &mut [Vec2]) {
        for k in 0..x.len() {
            let px = apply2(&self.pre[k], x[k]);
            y[k] = px;
            self.t[k] = apply2(&out[k].jac, px);
        }
        s.mul(&self.t, &mut self.st);
        self.products += 1;
        for (yk, sk) in y.iter_mut().zip(&self.st) {
            *yk -= *sk;
        }
    }

    /// Restarted GMRES with right preconditioning for `(I − S J) d = r`
    /// (modified Gram–Schmidt, Givens rotations); the solution in `d`.
    /// Returns the relative residual if it is still above the tolerance
    /// after the last restart.
    fn gmres(&mut self, s: &mut Compliance, out: &[Eval]) -> Option<f64> {
        let m = self.r.len();
        let dot = |a: &[Vec2], b: &[Vec2]| a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum::<f64>();
        self.d.iter_mut().for_each(|v| *v = Vec2::ZERO);
        let b_norm = dot(&self.r, &self.r).sqrt();
        if b_norm == 0.0 {
            return None;
        }
        let tol = GMRES_RTOL * b_norm;
        let mut basis = std::mem::take(&mut self.basis);
        basis.resize_with(KRYLOV + 1, Vec::new);
        for v in &mut basis {
            v.resize(m, Vec2::ZERO);
        }
        let mut res = std::mem::take(&mut self.res); // residual of the current d
        res.clear();
        res.extend_from_slice(&self.r);
        let mut hess = std::mem::take(&mut self.hess);
        hess.resize((KRYLOV + 1) * KRYLOV, 0.0);
        let h = |i: usize, j: usize| i * KRYLOV + j;
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.resize(m, Vec2::ZERO);
        for _ in 0..RESTARTS {
            let beta = dot(&res, &res).sqrt();
            if beta <= tol {
                break;
            }
            for (v, r) in basis[0].iter_mut().zip(&res) {
                *v = *r * (1.0 / beta);
            }
            let mut g = [0.0; KRYLOV + 1];
            g[0] = beta;
            let mut rot = [(1.0, 0.0); KRYLOV];
            let mut k = 0;
            while k < KRYLOV {
                let (head, tail) = basis.split_at_mut(k + 1);
                self.apply(s, out, &head[k], &mut tail[0]);
                let wv = &mut tail[0];
                for (i, vi) in head.iter().enumerate() {
                    let hij = dot(wv, vi);
                    hess[h(i, k)] = hij;
                    for (a, b) in wv.iter_mut().zip(vi) {
                        *a -= *b * hij;
                    }
                }
                let hn = dot(wv, wv).sqrt();
                hess[h(k + 1, k)] = hn;
                if hn > 0.0 {
                    for a in wv.iter_mut() {
                        *a = *a * (1.0 / hn);
                    }
                }
                for (i, &(c, sn)) in rot.iter().enumerate().take(k) {
                    let (a, b) = (hess[h(i, k)], hess[h(i + 1, k)]);
                    hess[h(i, k)] = c * a + sn * b;
                    hess[h(i + 1, k)] = -sn * a + c * b;
                }
                let (a, b) = (hess[h(k, k)], hess[h(k + 1, k)]);
                let r = a.hypot(b);
                let (c, sn) = if r > 0.0 { (a / r, b / r) } else { (1.0, 0.0) };
                rot[k] = (c, sn);
                hess[h(k, k)] = r;
                hess[h(k + 1, k)] = 0.0;
                g[k + 1] = -sn * g[k];
                g[k] *= c;
                k += 1;
                if g[k].abs() <= tol || hn == 0.0 {
                    break;
                }
            }
            // y = H⁻¹ g (upper triangular), d += P Σ y_i v_i
            let mut y = [0.0; KRYLOV];
            for i in (0..k).rev() {
                let mut v = g[i];
                for j in i + 1..k {
                    v -= hess[h(i, j)] * y[j];
                }
                y[i] = if hess[h(i, i)] != 0.0 {
                    v / hess[h(i, i)]
                } else {
                    0.0
                };
            }
            for (q, sc) in scratch.iter_mut().enumerate() {
                let mut z = Vec2::ZERO;
                for (i, yi) in y.iter().enumerate().take(k) {
                    z += basis[i][q] * *yi;
                }
                *sc = apply2(&self.pre[q], z);
            }
            for (dk, z) in self.d.iter_mut().zip(&scratch) {
                *dk += *z;
            }
            // true residual r − (I − S J) d for the next restart
            for (t, (dk, e)) in self.t.iter_mut().zip(self.d.iter().zip(out)) {
                *t = apply2(&e.jac, *dk);
            }
            s.mul(&self.t, &mut self.st);
            self.products += 1;
            for (q, rq) in res.iter_mut().enumerate() {
                *rq = self.r[q] - (self.d[q] - self.st[q]);
            }
        }
        let left = dot(&res, &res).sqrt();
        self.res = res;
        self.scratch = scratch;
        self.basis = basis;
        self.hess = hess;
        // NaN is not converged either
        (left.is_nan() || left > tol).then_some(left / b_norm)
    }

    /// The Newton iterations allowed.
    fn newton_cap(&self) -> usize {
        if self.max_newton == 0 {
            MAX_NEWTON
        } else {
            self.max_newton
        }
    }
}
/// `w += d`, re-evaluate; true when no contact changed regime.
fn settle(
    w: &mut [Vec2],
    contacts: &[Linear],
    out: &mut [Eval],
    d: impl Fn(usize) -> Vec2,
) -> bool {
    let mut settled = true;
    for (k, c) in contacts.iter().enumerate() {
        w[k] += d(k);
        let e = c.eval(w[k]);
        settled &= e.regime == out[k].regime;
        out[k] = e;
    }
    settled
}

/// `a b` of 2 × 2 row-major matrices.
fn mul2(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] + a[1] * b[2],
        a[0] * b[1] + a[1] * b[3],
        a[2] * b[0] + a[3] * b[2],
        a[2] * b[1] + a[3] * b[3],
    ]
}

/// Inverse of a 2 × 2 row-major matrix (identity if singular).
fn inv2(a: &[f64; 4]) -> [f64; 4] {
    let det = a[0] * a[3] - a[1] * a[2];
    if det == 0.0 || !det.is_finite() {
        return [1.0, 0.0, 0.0, 1.0];
    }
    [a[3] / det, -a[1] / det, -a[2] / det, a[0] / det]
}

/// `a x` for a 2 × 2 row-major matrix.
#[inline]
fn apply2(a: &[f64; 4], x: Vec2) -> Vec2 {
    Vec2::new(a[0] * x.x + a[1] * x.y, a[2] * x.x + a[3] * x.y)
}

/// The scratch of faer's dense LU with partial pivoting and of its solve
/// with one right-hand side, for `n × n`.
fn lu_scratch(n: usize) -> faer::dyn_stack::MemBuffer {
    use faer::linalg::lu::partial_pivoting::{factor, solve};
    let par = faer::Par::Seq;
    let req = factor::lu_in_place_scratch::<usize, f64>(n, n, par, Default::default())
        .or(solve::solve_in_place_scratch::<usize, f64>(n, 1, par));
    faer::dyn_stack::MemBuffer::new(req)
}

/// `a` (n × n, column-major) overwritten by its LU factors with partial
/// pivoting, the row permutation in `perm`.
fn lu_factor(a: &mut [f64], n: usize, perm: &mut (Vec<usize>, Vec<usize>)) {
    use faer::dyn_stack::MemStack;
    use faer::linalg::lu::partial_pivoting::factor;
    if n == 0 {
        return;
    }
    perm.0.resize(n, 0);
    perm.1.resize(n, 0);
    let mut mem = lu_scratch(n);
    let m = faer::MatMut::from_column_major_slice_mut(a, n, n);
    factor::lu_in_place(
        m,
        &mut perm.0,
        &mut perm.1,
        faer::Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    );
}

/// `b ← A⁻¹ b` from the factors of [`lu_factor`].
fn lu_apply(lu: &[f64], b: &mut [f64], n: usize, perm: &(Vec<usize>, Vec<usize>)) {
    use faer::dyn_stack::MemStack;
    use faer::linalg::lu::partial_pivoting::solve;
    if n == 0 {
        return;
    }
    let mut mem = lu_scratch(n);
    let m = faer::MatRef::from_column_major_slice(lu, n, n);
    let p = faer::perm::PermRef::new_checked(&perm.0, &perm.1, n);
    let rhs = faer::MatMut::from_column_major_slice_mut(b, n, 1);
    solve::solve_in_place(m, m, p, rhs, faer::Par::Seq, MemStack::new(&mut mem));
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

    /// The linearised law is the DEM law with the body point moving by `w`,
    /// with either normal force in the Coulomb cap (the total one gives
    /// the slide branch a Jacobian term μ (k_n + c_n/Δt) along n).
    #[test]
    fn matches_the_dem_contact_law_in_every_regime() {
        let dt = 1e-3;
        let n = Vec2::new(0.6, -0.8);
        for (slip, (fs_old, vt0, vn0, w, regime)) in [SlipNormal::Total, SlipNormal::Elastic]
            .into_iter()
            .flat_map(|s| {
                let el = s == SlipNormal::Elastic;
                [
                    (0.0, 0.1, 0.2, Vec2::new(1e-5, 2e-5), 1),   // stick
                    (150.0, 3.0, 0.2, Vec2::new(-1e-5, 0.0), 3), // slide, F_s < 0
                    (-50.0, -4.0, 0.2, Vec2::new(0.0, 3e-5), 2), // slide, F_s > 0
                    (0.0, 0.0, 0.2, Vec2::new(8e-4, -1e-3), 0),  // open
                    // separating fast: the dashpot pulls (F_n,total < 0),
                    // the total-force cap is 0, the elastic one k_n δ μ
                    (100.0, 3.0, -0.2, Vec2::ZERO, 3),
                    (100.0, 0.01, -0.2, Vec2::ZERO, if el { 1 } else { 2 }),
                ]
                .map(|c| (s, c))
            })
        {
            let l = ContactLaw {
                slip_normal: slip,
                ..law()
            };
            let (cn, cs) = (l.beta_n * l.kn, 0.0);
            let c = Linear {
                law: l,
                cn,
                cs,
                n,
                delta0: 5e-4,
                vn0,
                vt0,
                fs_old,
                dt,
                spring: None,
            };
            let e = c.eval(w);
            // the cap's clamp at zero is its own piece (flag 8)
            let clamped = slip == SlipNormal::Total && e.fn_total <= 0.0 && regime != 0;
            assert_eq!(e.regime, regime + if clamped { 8 } else { 0 }, "{e:?}");
            if regime >= 2 {
                assert_eq!(e.fs.abs(), l.mu * e.fn_cap);
                let want = match slip {
                    SlipNormal::Total => e.fn_total.max(0.0),
                    SlipNormal::Elastic => e.fn_elastic,
                };
                assert_eq!(e.fn_cap, want);
            }
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
            spring: None,
        };
        let s = [2e-6, 0.5e-6, 0.5e-6, 1e-6];
        let base = [Vec2::new(0.01, 0.02)];
        let free = [Vec2::new(0.0101, 0.0199)];
        let mut out = Vec::new();
        let it = Solver::default()
            .solve(&[c], &base, &free, &mut Compliance::Dense(&s), &mut out)
            .unwrap();
        assert!(it < 10);
        let g = out[0].g;
        let u = base[0]
            + (free[0] - base[0])
            + Vec2::new(s[0] * g.x + s[1] * g.y, s[2] * g.x + s[3] * g.y);
        let w = u - base[0];
        assert_eq!(c.eval(w).regime, out[0].regime);
        assert!((c.eval(w).g - g).norm() < 1e-9 * g.norm());
        // sliding (v_t Δt k_s = 1000 > μ F_n): the shear sits on the cap
        assert_eq!(out[0].regime, 3);
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
