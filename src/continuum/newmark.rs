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
use crate::sparse::{Cholesky, SparseError, SymCsc, SymRows};

/// Newmark parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewmarkParams {
    /// Time step Δt.
    pub dt: f64,
    /// γ (the paper's β₁, ERRATA E9).
    pub gamma: f64,
    /// β (the paper's β₂/2, ERRATA E9).
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
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct State {
    /// `U`: nodal parameters `u_I` (Eq. 12), interleaved `[u_x, u_y]` per
    /// node; for EFG not the displacement at the node (no Kronecker delta).
    pub u: Vec<f64>,
    /// `U̇`, same layout.
    pub v: Vec<f64>,
    /// `Ü`, same layout.
    pub a: Vec<f64>,
}

impl State {
    /// A body at rest: `n` unknowns (2 per node), all zero.
    pub fn zeros(n: usize) -> Self {
        State {
            u: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
        }
    }
}

/// A Newmark integrator with its factored effective matrix.
#[derive(Debug)]
pub struct Newmark {
    /// Δt, γ, β.
    pub params: NewmarkParams,
    alpha: [f64; 6],
    /// Mass matrix `M` (Eq. 23).
    pub mass: SymCsc,
    /// Damping matrix `C` (Eq. 24); `None` if `c = 0`.
    pub damping: Option<SymCsc>,
    /// Stiffness `K̄ = K + K^α` (Eq. 60, penalty per ERRATA E4; an FE body:
    /// `K` with the prescribed DOFs decoupled, no penalty).
    pub stiffness: SymCsc,
    factor: Cholesky,
    /// `M` and `C` by rows, for the products of [`predict`](Self::predict).
    mass_rows: SymRows,
    damping_rows: Option<SymRows>,
    rhs: Vec<f64>,
    tmp: Vec<f64>,
    /// `A⁻¹Φᵀ` of the points of the last [`point_compliance`](Self::point_compliance),
    /// column `2k + a` for point k, component a.
    cols: Vec<f64>,
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
            mass_rows: SymRows::new(&mass),
            damping_rows: damping.as_ref().map(SymRows::new),
            params,
            alpha,
            mass,
            damping,
            stiffness,
            factor,
            rhs: vec![0.0; n],
            tmp: vec![0.0; n],
            cols: Vec::new(),
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
        consistent_acceleration(
            &self.mass,
            self.damping.as_ref(),
            &self.stiffness,
            state,
            f,
            Some(&self.factor),
        )
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
        self.mass_rows.mul_add(&self.tmp, &mut self.rhs);
        if let Some(c) = &self.damping_rows {
            for i in 0..n {
                self.tmp[i] = a4 * state.u[i] + a5 * state.v[i] + a6 * state.a[i];
            }
            c.mul_add(&self.tmp, &mut self.rhs);
        }
        self.factor.solve_in_place(&mut self.rhs);
    }

    /// The step's solution `U₊` after [`predict`](Self::predict).
    pub fn solution(&self) -> &[f64] {
        &self.rhs
    }

    /// The step's solution `U₊` after [`predict`](Self::predict), to correct.
    pub fn solution_mut(&mut self) -> &mut [f64] {
        &mut self.rhs
    }

    /// `x ← (α₁M + α₄C + K̄)⁻¹ x`: the response of `U₊` to an extra load.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        self.factor.solve_in_place(x);
    }

    /// After [`predict`](Self::predict): the response of the step to
    /// generalised forces on `2m` linear functionals of the nodal values,
    /// `rows[c] = [(DOF, coefficient)]`, taken in pairs as `m` points (a
    /// point's `x` and `y` rows are `[(2J, φ_J)]`, `[(2J + 1, φ_J)]`; no load
    /// on [imposed](Self::set_imposed) DOFs). Writes the free values of the
    /// predicted `U₊` and the compliance `S = Φ A⁻¹ Φᵀ` (2m × 2m,
    /// row-major), and keeps `A⁻¹Φᵀ` for
    /// [`apply_point_forces`](Self::apply_point_forces). Cost: 2m solves.
    pub fn point_compliance(
        &mut self,
        rows: &[Vec<(usize, f64)>],
        free: &mut Vec<Vec2>,
        s: &mut Vec<f64>,
    ) {
        let n = self.n();
        let m2 = rows.len();
        let mut cols = std::mem::take(&mut self.cols);
        cols.clear();
        cols.resize(m2 * n, 0.0);
        for (col, row) in cols.chunks_exact_mut(n).zip(rows) {
            for &(i, c) in row {
                if !self.imposed.get(i).copied().unwrap_or(false) {
                    col[i] += c;
                }
            }
            self.factor.solve_in_place(col);
        }
        pair_values(rows, &self.rhs, free);
        s.clear();
        s.resize(m2 * m2, 0.0);
        for (c, col) in cols.chunks_exact(n).enumerate() {
            for (r, row) in rows.iter().enumerate() {
                s[r * m2 + c] = functional(row, col);
            }
        }
        self.cols = cols;
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

    /// The factor of `α₁M + α₄C + K̄` (for
    /// [`BoundaryGreen`](crate::continuum::compliance::BoundaryGreen)).
    pub fn factor(&self) -> &Cholesky {
        &self.factor
    }

    /// DOFs whose value the body imposes (empty: none).
    pub fn imposed(&self) -> &[bool] {
        &self.imposed
    }

    /// After [`predict`](Self::predict): `U₊ += A⁻¹ (Φᵀ f + extra)`, the
    /// generalised forces `f[k]` on the functional pairs `rows[2k]`,
    /// `rows[2k + 1]` (as in [`point_compliance`](Self::point_compliance);
    /// none on imposed DOFs) and a load `extra` (empty: none), one solve.
    pub fn add_point_forces(&mut self, rows: &[Vec<(usize, f64)>], f: &[Vec2], extra: &[f64]) {
        self.tmp.iter_mut().for_each(|x| *x = 0.0);
        let mut any = !extra.is_empty();
        for (t, e) in self.tmp.iter_mut().zip(extra) {
            *t = *e;
        }
        for (pair, fk) in rows.chunks_exact(2).zip(f) {
            for (row, fa) in pair.iter().zip([fk.x, fk.y]) {
                for &(i, c) in row {
                    if fa != 0.0 && !self.imposed.get(i).copied().unwrap_or(false) {
                        self.tmp[i] += c * fa;
                        any = true;
                    }
                }
            }
        }
        if any {
            self.factor.solve_in_place(&mut self.tmp);
            for (u, d) in self.rhs.iter_mut().zip(&self.tmp) {
                *u += d;
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

/// `Σ c x[i]` of a linear functional `row = [(i, c)]` of the nodal values.
pub fn functional(row: &[(usize, f64)], x: &[f64]) -> f64 {
    row.iter().map(|&(i, c)| c * x[i]).sum()
}

/// The values on `x` of functionals taken in pairs (`rows[2k]`,
/// `rows[2k + 1]` → `out[k]`), as the contact unknowns use them.
pub fn pair_values(rows: &[Vec<(usize, f64)>], x: &[f64], out: &mut Vec<Vec2>) {
    out.clear();
    out.extend(
        rows.chunks_exact(2)
            .map(|r| Vec2::new(functional(&r[0], x), functional(&r[1], x))),
    );
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
/// [`Newmark::new`] to keep the two factors from coexisting in memory;
/// `like`: a factor on `mass`'s pattern whose analysis to reuse (see
/// [`Cholesky::factor_like`]).
pub fn consistent_acceleration(
    mass: &SymCsc,
    damping: Option<&SymCsc>,
    stiffness: &SymCsc,
    state: &mut State,
    f: &[f64],
    like: Option<&Cholesky>,
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
    let mut mf = match like {
        Some(c) => c.factor_like(mass)?,
        None => Cholesky::factor(mass)?,
    };
    mf.solve_in_place(&mut r);
    state.a = r;
    Ok(())
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
