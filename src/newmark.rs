//! Newmark time integration (Table 1, Eqs. 49/52/55, ERRATA E8–E9) over a
//! body's `(M, C, K̄)`, with the effective matrix factored once.
//!
//! With `α₁ = 1/(βΔt²)`, `α₂ = 1/(βΔt)`, `α₃ = 1/(2β) − 1`,
//! `α₄ = γ/(βΔt)`, `α₅ = γ/β − 1`, `α₆ = Δt(γ/(2β) − 1)`, each step solves
//! (ERRATA E8)
//! `(α₁M + α₄C + K̄) U₊ = F₊ + M(α₁U + α₂U̇ + α₃Ü) + C(α₄U + α₅U̇ + α₆Ü)`,
//! then `Ü₊ = α₁(U₊ − U) − α₂U̇ − α₃Ü` and `U̇₊ = U̇ + Δt((1 − γ)Ü + γÜ₊)`.
//! The paper's β₁ = 1.5, β₂ = 1.6 are γ = 1.5, β = 0.8 (E9, strongly
//! dissipative); γ = 1/2, β = 1/4 (average acceleration) conserves energy.
//!
//! Reused by every continuum body (EFG, FE): it only needs three symmetric
//! matrices on one sparsity pattern.

use crate::geom::Vec2;
use crate::sparse::{Cholesky, SparseError, SymCsc};

/// Newmark parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewmarkParams {
    pub dt: f64,
    pub gamma: f64,
    pub beta: f64,
}

impl NewmarkParams {
    /// `[α₁, …, α₆]` of Table 1 (ERRATA E9).
    pub fn alphas(&self) -> [f64; 6] {
        let (dt, g, b) = (self.dt, self.gamma, self.beta);
        [
            1.0 / (b * dt * dt),
            1.0 / (b * dt),
            1.0 / (2.0 * b) - 1.0,
            g / (b * dt),
            g / b - 1.0,
            dt * (g / (2.0 * b) - 1.0),
        ]
    }
}

/// Displacement, velocity and acceleration (nodal parameters).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct State {
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
}

impl State {
    pub fn zeros(n: usize) -> Self {
        State {
            u: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
        }
    }
}

/// An extra stiffness of one step on a few functionals of the increment
/// (for example the geometric stiffness of contacts, treated implicitly):
/// energy `½ Σ_kl c_kl ψ_k ψ_l` with `ψ_k = v_k · (U₊ − U)`, i.e. the
/// step's matrix becomes `A + V C Vᵀ` and its right-hand side gains
/// `V C Vᵀ U`.
#[derive(Debug, Clone, Copy)]
pub struct StepStiffness<'a> {
    /// The functionals `v_k`, sparse: `(DOF, coefficient)`.
    pub v: &'a [Vec<(usize, f64)>],
    /// `C`, q × q row-major, symmetric.
    pub c: &'a [f64],
    /// `U` at the start of the step.
    pub u: &'a [f64],
}

/// A Newmark integrator with its factored effective matrix.
#[derive(Debug)]
pub struct Newmark {
    pub params: NewmarkParams,
    alpha: [f64; 6],
    pub mass: SymCsc,
    pub damping: Option<SymCsc>,
    pub stiffness: SymCsc,
    factor: Cholesky,
    rhs: Vec<f64>,
    tmp: Vec<f64>,
    /// `A⁻¹Φᵀ` of the points of the last [`point_compliance`](Self::point_compliance),
    /// column `2k + a` for point k, component a.
    cols: Vec<f64>,
    /// `A⁻¹V` of the last [`StepStiffness`] (scratch of `stiffen`).
    stiff_y: Vec<f64>,
    /// DOFs whose value the body imposes after every solve (FE elimination,
    /// see [`set_imposed`](Self::set_imposed)); empty: none.
    imposed: Vec<bool>,
}

impl Newmark {
    /// Build `α₁M + α₄C + K̄` and factor it (sparse Cholesky, AMD), once.
    pub fn new(
        mass: SymCsc,
        damping: Option<SymCsc>,
        stiffness: SymCsc,
        params: NewmarkParams,
    ) -> Result<Self, SparseError> {
        let alpha = params.alphas();
        let mut eff = stiffness.combine(1.0, &mass, alpha[0])?;
        if let Some(c) = &damping {
            eff = eff.combine(1.0, c, alpha[3])?;
        }
        let factor = Cholesky::factor(&eff)?;
        drop(eff);
        let n = stiffness.n();
        Ok(Newmark {
            params,
            alpha,
            mass,
            damping,
            stiffness,
            factor,
            rhs: vec![0.0; n],
            tmp: vec![0.0; n],
            cols: Vec::new(),
            stiff_y: Vec::new(),
            imposed: Vec::new(),
        })
    }

    /// Mark DOFs whose value the body imposes after every solve (prescribed
    /// displacements eliminated from a block-diagonal effective matrix):
    /// point forces there are support reactions, so the compliance columns
    /// of [`point_compliance`](Self::point_compliance) put no load on them
    /// and respond with exactly zero there.
    pub fn set_imposed(&mut self, imposed: Vec<bool>) {
        self.imposed = imposed;
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.stiffness.n()
    }

    /// Stored entries of the Cholesky factor.
    pub fn factor_nnz(&self) -> usize {
        self.factor.nnz_l()
    }

    /// The acceleration that satisfies the equation of motion at the current
    /// state: `M Ü = F − C U̇ − K̄ U` (factors M once; call at t = 0).
    pub fn initial_acceleration(&self, state: &mut State, f: &[f64]) -> Result<(), SparseError> {
        consistent_acceleration(&self.mass, self.damping.as_ref(), &self.stiffness, state, f)
    }

    /// One step `t → t + Δt` under the external force `f` at `t + Δt`
    /// (Eq. 49 per E8, one solve with the cached factor, no allocation).
    pub fn advance(&mut self, state: &mut State, f: &[f64]) {
        self.predict(state, f);
        self.commit(state);
    }

    /// First half of a step: solve Eq. (49) for `U₊` under `f` and keep it
    /// as the step's solution ([`solution_mut`](Self::solution_mut)), which
    /// the caller may correct (for loads that depend on `U₊`, e.g. implicit
    /// contact springs) before [`commit`](Self::commit).
    pub fn predict(&mut self, state: &State, f: &[f64]) {
        let [a1, a2, a3, a4, a5, a6] = self.alpha;
        let n = self.n();
        debug_assert!(f.len() == n && state.u.len() == n);
        self.rhs.copy_from_slice(f);
        for i in 0..n {
            self.tmp[i] = a1 * state.u[i] + a2 * state.v[i] + a3 * state.a[i];
        }
        self.mass.mul_add(&self.tmp, &mut self.rhs);
        if let Some(c) = &self.damping {
            for i in 0..n {
                self.tmp[i] = a4 * state.u[i] + a5 * state.v[i] + a6 * state.a[i];
            }
            c.mul_add(&self.tmp, &mut self.rhs);
        }
        self.factor.solve_in_place(&mut self.rhs);
    }

    /// The step's solution `U₊` after [`predict`](Self::predict).
    pub fn solution_mut(&mut self) -> &mut [f64] {
        &mut self.rhs
    }

    /// `x ← (α₁M + α₄C + K̄)⁻¹ x`: the response of `U₊` to an extra load.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        self.factor.solve_in_place(x);
    }

    /// After [`predict`](Self::predict): the response of the step to point
    /// forces at `m` points with shape rows `rows[k] = [(node, φ)]`
    /// (`u_k = Σ φ U_{2·node+a}`; no load on [imposed](Self::set_imposed) DOFs). Writes the free displacements `u_k` of the
    /// predicted `U₊` and the compliance `S = Φ A⁻¹ Φᵀ` (2m × 2m, row-major,
    /// index `2k + a`), and keeps `A⁻¹Φᵀ` for
    /// [`apply_point_forces`](Self::apply_point_forces). Cost: 2m solves.
    pub fn point_compliance(
        &mut self,
        rows: &[Vec<(u32, f64)>],
        free: &mut Vec<Vec2>,
        s: &mut Vec<f64>,
    ) {
        self.point_compliance_stiffened(rows, None, free, s);
    }

    /// [`point_compliance`](Self::point_compliance) of the step whose matrix
    /// is stiffened by `extra` (if given): `A + V C Vᵀ` replaces `A` in `U₊`,
    /// in `S` and in the kept columns. Cost: 2m + q solves.
    pub fn point_compliance_stiffened(
        &mut self,
        rows: &[Vec<(u32, f64)>],
        extra: Option<StepStiffness<'_>>,
        free: &mut Vec<Vec2>,
        s: &mut Vec<f64>,
    ) {
        let n = self.n();
        let m2 = 2 * rows.len();
        let dot = |x: &[f64], row: &[(u32, f64)], a: usize| -> f64 {
            row.iter().map(|&(j, p)| p * x[2 * j as usize + a]).sum()
        };
        let mut cols = std::mem::take(&mut self.cols);
        cols.clear();
        cols.resize(m2 * n, 0.0);
        for (c, col) in cols.chunks_exact_mut(n).enumerate() {
            for &(j, p) in &rows[c / 2] {
                self.add_load(col, 2 * j as usize + c % 2, p);
            }
            self.factor.solve_in_place(col);
        }
        if let Some(k) = extra {
            self.stiffen(&k, &mut cols);
        }
        free.clear();
        free.extend(
            rows.iter()
                .map(|r| Vec2::new(dot(&self.rhs, r, 0), dot(&self.rhs, r, 1))),
        );
        s.clear();
        s.resize(m2 * m2, 0.0);
        for (c, col) in cols.chunks_exact(n).enumerate() {
            for (r, row) in rows.iter().enumerate() {
                s[(2 * r) * m2 + c] = dot(col, row, 0);
                s[(2 * r + 1) * m2 + c] = dot(col, row, 1);
            }
        }
        self.cols = cols;
    }

    /// `x[dof] += p` unless the DOF is [imposed](Self::set_imposed) (a load
    /// there is a support reaction).
    fn add_load(&self, x: &mut [f64], dof: usize, p: f64) {
        if !self.imposed.get(dof).copied().unwrap_or(false) {
            x[dof] += p;
        }
    }

    /// Replace the step's matrix `A` by `A + V C Vᵀ` (the stiffness `k`) in
    /// the predicted `U₊` (right-hand side plus `V C Vᵀ U`, so the extra
    /// forces act on the increment `U₊ − U`) and in the columns `A⁻¹Φᵀ`,
    /// by the Woodbury identity:
    /// `(A + V C Vᵀ)⁻¹ = A⁻¹ − Y (I + C G)⁻¹ C Yᵀ`, `Y = A⁻¹V`, `G = VᵀY`,
    /// so `x ← x − Y (I + C G)⁻¹ C Vᵀ x` for `x = U₊ − U` and for each column.
    /// Cost: q solves and dense q × q work.
    fn stiffen(&mut self, k: &StepStiffness<'_>, cols: &mut [f64]) {
        let (n, q) = (self.n(), k.v.len());
        if q == 0 {
            return;
        }
        let mut y = std::mem::take(&mut self.stiff_y);
        y.clear();
        y.resize(q * n, 0.0);
        for (col, v) in y.chunks_exact_mut(n).zip(k.v) {
            for &(dof, a) in v {
                self.add_load(col, dof, a);
            }
            self.factor.solve_in_place(col);
        }
        let apply =
            |v: &[(usize, f64)], x: &[f64]| -> f64 { v.iter().map(|&(i, a)| a * x[i]).sum() };
        // B = I + C G, then M = B⁻¹ C
        let mut g = vec![0.0; q * q];
        for (l, yl) in y.chunks_exact(n).enumerate() {
            for (kk, v) in k.v.iter().enumerate() {
                g[kk * q + l] = apply(v, yl);
            }
        }
        let mut b = vec![0.0; q * q];
        for i in 0..q {
            for j in 0..q {
                b[i * q + j] = (0..q).map(|l| k.c[i * q + l] * g[l * q + j]).sum::<f64>()
                    + if i == j { 1.0 } else { 0.0 };
            }
        }
        let mut m = k.c.to_vec();
        dense_solve(&mut b, &mut m, q, q);
        // x ← x − Y M Vᵀ x
        let correct = |x: &mut [f64], x0: Option<&[f64]>| {
            let r: Vec<f64> =
                k.v.iter()
                    .map(|v| apply(v, x) - x0.map_or(0.0, |u| apply(v, u)))
                    .collect();
            for (l, yl) in y.chunks_exact(n).enumerate() {
                let z: f64 = (0..q).map(|j| m[l * q + j] * r[j]).sum();
                if z != 0.0 {
                    for (xi, yi) in x.iter_mut().zip(yl) {
                        *xi -= z * yi;
                    }
                }
            }
        };
        correct(&mut self.rhs, Some(k.u));
        for col in cols.chunks_exact_mut(n) {
            correct(col, None);
        }
        self.stiff_y = y;
    }

    /// `U₊ += A⁻¹Φᵀ f`: the forces `f[k]` at the points of the last
    /// [`point_compliance`](Self::point_compliance) added to the solution.
    pub fn apply_point_forces(&mut self, f: &[Vec2]) {
        let n = self.n();
        for (c, col) in self.cols.chunks_exact(n).enumerate().take(2 * f.len()) {
            let fc = if c % 2 == 0 { f[c / 2].x } else { f[c / 2].y };
            if fc != 0.0 {
                for (u, p) in self.rhs.iter_mut().zip(col) {
                    *u += fc * p;
                }
            }
        }
    }

    /// Second half of a step: accept the solution as `U₊` and update `Ü`,
    /// `U̇` (Table 1).
    pub fn commit(&mut self, state: &mut State) {
        for i in 0..self.n() {
            let u1 = self.rhs[i];
            (state.v[i], state.a[i]) = self.rates(state.u[i], state.v[i], state.a[i], u1);
            state.u[i] = u1;
        }
    }

    /// Velocity and acceleration at `t + Δt` of a DOF going from
    /// `(u, u̇, ü)` at `t` to `u₁` (Table 1): `Ü₊ = α₁(U₊ − U) − α₂U̇ − α₃Ü`,
    /// `U̇₊ = U̇ + Δt((1 − γ)Ü + γÜ₊)`.
    pub fn rates(&self, u: f64, v: f64, a: f64, u1: f64) -> (f64, f64) {
        let [a1, a2, a3, ..] = self.alpha;
        let (dt, g) = (self.params.dt, self.params.gamma);
        let acc = a1 * (u1 - u) - a2 * v - a3 * a;
        (v + dt * ((1.0 - g) * a + g * acc), acc)
    }

    /// Kinetic energy `½ U̇ᵀ M U̇`.
    pub fn kinetic_energy(&self, state: &State) -> f64 {
        0.5 * self.mass.quad_form(&state.v)
    }

    /// Strain (plus penalty) energy `½ Uᵀ K̄ U`.
    pub fn strain_energy(&self, state: &State) -> f64 {
        0.5 * self.stiffness.quad_form(&state.u)
    }
}

/// The inputs a body's time stepping needs: a positive finite step and a
/// positive density (body `name`). The message says which is wrong.
pub fn check_dynamic(dt: f64, density: f64, name: &str) -> Result<(), String> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(format!("time step must be > 0 (got {dt})"));
    }
    if density <= 0.0 {
        return Err(format!("body `{name}`: dynamics needs a density > 0"));
    }
    Ok(())
}

/// `Ü` from `M Ü = F − C U̇ − K̄ U` (a temporary Cholesky factor of M; zero
/// without factoring when the right-hand side vanishes). Call it before
/// [`Newmark::new`] to keep the two factors from coexisting in memory.
pub fn consistent_acceleration(
    mass: &SymCsc,
    damping: Option<&SymCsc>,
    stiffness: &SymCsc,
    state: &mut State,
    f: &[f64],
) -> Result<(), SparseError> {
    let mut r = f.to_vec();
    let mut ku = vec![0.0; r.len()];
    stiffness.mul_add(&state.u, &mut ku);
    if let Some(c) = damping {
        c.mul_add(&state.v, &mut ku);
    }
    for (ri, k) in r.iter_mut().zip(&ku) {
        *ri -= k;
    }
    if r.iter().all(|&x| x == 0.0) {
        state.a = r;
        return Ok(());
    }
    let mut mf = Cholesky::factor(mass)?;
    mf.solve_in_place(&mut r);
    state.a = r;
    Ok(())
}

/// Solve `a x = b` for `nrhs` right-hand sides in place (`b ← x`, `b` is
/// n × nrhs row-major): Gaussian elimination with partial pivoting, `a`
/// (n × n row-major) is destroyed. A zero pivot leaves that unknown 0.
fn dense_solve(a: &mut [f64], b: &mut [f64], n: usize, nrhs: usize) {
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
            for k in 0..nrhs {
                b.swap(piv * nrhs + k, col * nrhs + k);
            }
        }
        for i in col + 1..n {
            let f = a[i * n + col] / a[col * n + col];
            if f != 0.0 {
                for k in col..n {
                    a[i * n + k] -= f * a[col * n + k];
                }
                for k in 0..nrhs {
                    b[i * nrhs + k] -= f * b[col * nrhs + k];
                }
            }
        }
    }
    for col in (0..n).rev() {
        let d = a[col * n + col];
        for k in 0..nrhs {
            let mut x = b[col * nrhs + k];
            for j in col + 1..n {
                x -= a[col * n + j] * b[j * nrhs + k];
            }
            b[col * nrhs + k] = if d != 0.0 { x / d } else { 0.0 };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::Pattern;
    use std::sync::Arc;

    fn diag(v: f64) -> SymCsc {
        SymCsc {
            pattern: Arc::new(Pattern {
                n: 1,
                col_ptr: vec![0, 1],
                row_idx: vec![0],
            }),
            values: vec![v],
        }
    }

    /// A full symmetric n × n matrix as a [`SymCsc`].
    fn dense(n: usize, f: impl Fn(usize, usize) -> f64) -> SymCsc {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut values = Vec::new();
        for j in 0..n {
            for i in j..n {
                row_idx.push(i);
                values.push(f(i, j));
            }
            col_ptr.push(row_idx.len());
        }
        SymCsc {
            pattern: Arc::new(Pattern {
                n,
                col_ptr,
                row_idx,
            }),
            values,
        }
    }

    /// The step stiffened by `V C Vᵀ` (Woodbury) is the step of the body
    /// whose stiffness has `V C Vᵀ` added and whose load has `V C Vᵀ U`
    /// added: free displacements, compliance and the committed state, with
    /// an indefinite `C` like a contact's geometric stiffness.
    #[test]
    fn stiffened_step_is_the_step_with_the_stiffness_added() {
        let n = 6;
        let p = NewmarkParams {
            dt: 0.1,
            gamma: 0.5,
            beta: 0.25,
        };
        let mass = dense(n, |i, j| if i == j { 2.0 } else { 0.1 });
        let stiff = dense(n, |i, j| match i - j {
            0 => 30.0,
            1 => -10.0,
            _ => 0.0,
        });
        let v = vec![
            vec![(0, 1.0), (3, -0.5), (4, 0.25)],
            vec![(1, 0.4), (2, 0.8)],
        ];
        let c = [40.0, -7.0, -7.0, 0.0];
        let vcv = |i: usize, j: usize| -> f64 {
            let at =
                |k: usize, d: usize| v[k].iter().filter(|e| e.0 == d).map(|e| e.1).sum::<f64>();
            (0..2)
                .flat_map(|k| (0..2).map(move |l| (k, l)))
                .map(|(k, l)| c[2 * k + l] * at(k, i) * at(l, j))
                .sum()
        };
        let state = State {
            u: (0..n).map(|i| 0.01 * i as f64 - 0.02).collect(),
            v: (0..n).map(|i| 0.3 - 0.1 * i as f64).collect(),
            a: (0..n).map(|i| (i as f64).sin()).collect(),
        };
        let f: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
        let mut f2 = f.clone();
        for (i, fi) in f2.iter_mut().enumerate() {
            *fi += (0..n).map(|j| vcv(i, j) * state.u[j]).sum::<f64>();
        }
        let rows = vec![vec![(0, 0.3), (1, 0.7)], vec![(1, 0.5), (2, 0.5)]];
        let forces = [Vec2::new(1.0, -2.0), Vec2::new(0.5, 0.25)];
        let mut a = Newmark::new(mass.clone(), None, stiff.clone(), p).unwrap();
        let mut b =
            Newmark::new(mass, None, dense(n, |i, j| stiff.get(i, j) + vcv(i, j)), p).unwrap();
        let (mut sa, mut sb) = (state.clone(), state.clone());
        let (mut free_a, mut s_a, mut free_b, mut s_b) = (vec![], vec![], vec![], vec![]);
        a.predict(&sa, &f);
        let extra = StepStiffness {
            v: &v,
            c: &c,
            u: &state.u,
        };
        a.point_compliance_stiffened(&rows, Some(extra), &mut free_a, &mut s_a);
        b.predict(&sb, &f2);
        b.point_compliance(&rows, &mut free_b, &mut s_b);
        for (x, y) in free_a.iter().zip(&free_b) {
            assert!((*x - *y).norm() < 1e-13, "{x:?} {y:?}");
        }
        for (x, y) in s_a.iter().zip(&s_b) {
            assert!((x - y).abs() < 1e-13, "{x} {y}");
        }
        a.apply_point_forces(&forces);
        b.apply_point_forces(&forces);
        a.commit(&mut sa);
        b.commit(&mut sb);
        for (x, y) in [(&sa.u, &sb.u), (&sa.v, &sb.v), (&sa.a, &sb.a)] {
            for (p, q) in x.iter().zip(y) {
                assert!((p - q).abs() < 1e-10 * q.abs().max(1.0), "{p} {q}");
            }
        }
    }

    /// Single oscillator ω = 1: average acceleration keeps the energy and has
    /// the textbook period elongation.
    #[test]
    fn oscillator_average_acceleration() {
        let dt = 0.05;
        let p = NewmarkParams {
            dt,
            gamma: 0.5,
            beta: 0.25,
        };
        let mut nm = Newmark::new(diag(1.0), None, diag(1.0), p).unwrap();
        let mut s = State {
            u: vec![1.0],
            v: vec![0.0],
            a: vec![0.0],
        };
        nm.initial_acceleration(&mut s, &[0.0]).unwrap();
        assert!((s.a[0] + 1.0).abs() < 1e-14);
        let e0 = nm.kinetic_energy(&s) + nm.strain_energy(&s);
        let mut crossings = vec![];
        let mut prev = s.u[0];
        for k in 1..=2000 {
            nm.advance(&mut s, &[0.0]);
            let e = nm.kinetic_energy(&s) + nm.strain_energy(&s);
            assert!((e - e0).abs() < 1e-12);
            if prev < 0.0 && s.u[0] >= 0.0 {
                crossings.push(k as f64 * dt - dt * s.u[0] / (s.u[0] - prev));
            }
            prev = s.u[0];
        }
        let t = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        // trapezoidal rule: ω̄Δt = 2 atan(ωΔt/2)
        let exact = 2.0 * std::f64::consts::PI * dt / (2.0 * (dt / 2.0f64).atan());
        assert!((t - exact).abs() < 1e-4 * exact, "{t} vs {exact}");
    }
}
