//! The penalty boundary conditions of an EFG body (Eq. 21, ERRATA E4), kept
//! point by point: at each Gauss point `x_g` of a prescribed edge Γu, the
//! row `φ_J(x_g)`, the weights `W_g = diag(α_x, α_y) w_g t` and the
//! prescribed displacement `ū(x_g, t)`. From these:
//!
//! - the penalty matrix `K^α = Σ_g Φ_gᵀ W_g Φ_g` and load
//!   `F^α(t) = Σ_g Φ_gᵀ W_g ū_g(t)` (E4), so `K̄ = K + K^α`;
//! - the energy of the penalty springs from their gap,
//!   `E^α = ½ Σ_g (u(x_g) − ū_g)ᵀ W_g (u(x_g) − ū_g)` — equal to
//!   `½UᵀK^αU − UᵀF^α + ½Σ_g ūᵀW_gū` but without its cancellation (with
//!   α = 10⁵E the three terms are huge and nearly cancel when the edge has
//!   moved);
//! - the force of a moving edge on the body, `Σ_g s_g w_g,c (ū_c − u_c(x_g))`
//!   (the generalised force conjugate to its drive's position, `s_g` the
//!   drive's scale at the point: 1 for a translation).
//!
//! A moving edge's prescribed values are known at the body's present step
//! ([`When::Now`]) and, once its drive decided the step under way, at the
//! next ([`When::Next`]).

use crate::continuum::Drive;
use crate::geom::Vec2;
use crate::sparse::SymCsc;
use std::ops::Range;

/// One moving component of a prescribed edge (`ux` or `uy` given as a
/// drive, [`crate::continuum::drive`]): `ū_c(x_g, tₙ) = ū_c(x_g, 0) +
/// s_g d(n)` on the edge's points.
#[derive(Debug, Clone)]
pub struct MovingEdge {
    /// The edge's penalty points.
    pub points: Range<usize>,
    /// 0: x, 1: y.
    pub component: usize,
    /// The scale `s_g` per point of `points` (empty: all 1).
    pub scale: Vec<f64>,
    /// The drive: its law and position.
    pub drive: Drive,
}

pub use crate::continuum::drive::When;

impl MovingEdge {
    /// The scale at point `g` (of `points`).
    fn scale_at(&self, g: usize) -> f64 {
        self.scale
            .get(g - self.points.start)
            .copied()
            .unwrap_or(1.0)
    }
    /// The drive's position `d`.
    pub fn position(&self, when: When) -> f64 {
        self.drive.state.position(when)
    }
}

/// The penalty points of a body (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct Penalty {
    /// Row of point g: `(idx[k], phi[k])` for `k ∈ ptr[g]..ptr[g+1]`.
    ptr: Vec<usize>,
    idx: Vec<u32>,
    phi: Vec<f64>,
    /// `[α_x w_g t, α_y w_g t]` (0 for a free component).
    weight: Vec<[f64; 2]>,
    /// `ū(x_g)` at t = 0 (a moving component starts at 0).
    value: Vec<[f64; 2]>,
    /// Moving components.
    pub moving: Vec<MovingEdge>,
}

impl Penalty {
    /// An empty set of penalty points.
    pub fn new() -> Self {
        Penalty {
            ptr: vec![0],
            ..Default::default()
        }
    }

    /// Add a point with its row `(node, φ_J(x_g))` and weights; its
    /// `ū(x_g, 0)` is 0 until [`set_value`](Self::set_value).
    pub fn push(&mut self, row: impl IntoIterator<Item = (u32, f64)>, weight: [f64; 2]) {
        for (j, phi) in row {
            self.idx.push(j);
            self.phi.push(phi);
        }
        self.ptr.push(self.idx.len());
        self.weight.push(weight);
        self.value.push([0.0, 0.0]);
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.weight.len()
    }
    /// No penalty points (no prescribed edge).
    pub fn is_empty(&self) -> bool {
        self.weight.is_empty()
    }

    /// Set the prescribed displacement `ū(x_g)` at t = 0 of point `g`.
    pub fn set_value(&mut self, g: usize, value: [f64; 2]) {
        self.value[g] = value;
    }

    /// The row `φ_J(x_g)` of point `g`.
    pub fn row(&self, g: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let r = self.ptr[g]..self.ptr[g + 1];
        self.idx[r.clone()]
            .iter()
            .copied()
            .zip(self.phi[r].iter().copied())
    }

    /// `W_g` of point `g`.
    pub fn weight(&self, g: usize) -> [f64; 2] {
        self.weight[g]
    }

    /// `ū(x_g)` now or at the next step.
    pub fn prescribed(&self, g: usize, when: When) -> [f64; 2] {
        let mut v = self.value[g];
        for e in self.moving.iter().filter(|e| e.points.contains(&g)) {
            v[e.component] += e.scale_at(g) * e.position(when);
        }
        v
    }

    /// Place every drive whose law is a function of time at `step`
    /// ([`Drive::set_step`]).
    pub fn set_step(&mut self, step: usize, dt: f64) {
        for e in &mut self.moving {
            e.drive.set_step(step, dt);
        }
    }

    /// `u(x_g) = Σ_J φ_J(x_g) u_J` of the nodal vector `u`.
    fn displacement(&self, g: usize, u: &[f64]) -> Vec2 {
        let r = self.ptr[g]..self.ptr[g + 1];
        let mut s = Vec2::ZERO;
        for (&j, &phi) in self.idx[r.clone()].iter().zip(&self.phi[r]) {
            s.x += phi * u[2 * j as usize];
            s.y += phi * u[2 * j as usize + 1];
        }
        s
    }

    /// `K̄ = K + K^α`, `K^α = Σ_g Φ_gᵀ W_g Φ_g` (E4), on `k`'s pattern
    /// (which must hold every node pair sharing a penalty point — the
    /// assembler's does). Added in point order after the domain terms, as
    /// a single assembly pass over all points would.
    pub fn stiffen(&self, k: &SymCsc) -> SymCsc {
        let mut kbar = k.clone();
        let p = &*kbar.pattern;
        let pos = |r: usize, c: usize| {
            let s = p.col_ptr[c];
            p.row_idx[s..p.col_ptr[c + 1]]
                .binary_search(&r)
                .map(|k| s + k)
                .expect("the pattern covers the node pairs of every penalty point")
        };
        // added in place, in the order of the points (the list of additions
        // it replaces cost 6 kB per point at its peak: 64 MB for a fixed
        // outline of 10 000 vertices)
        let values = &mut kbar.values;
        for g in 0..self.len() {
            let [wx, wy] = self.weight[g];
            let (s, e) = (self.ptr[g], self.ptr[g + 1]);
            for a in s..e {
                let i = self.idx[a] as usize;
                let (fx, fy) = (wx * self.phi[a], wy * self.phi[a]);
                for b in s..e {
                    let j = self.idx[b] as usize;
                    if j < i {
                        continue;
                    }
                    values[pos(2 * j, 2 * i)] += self.phi[b] * fx;
                    values[pos(2 * j + 1, 2 * i + 1)] += self.phi[b] * fy;
                }
            }
        }
        kbar
    }

    /// `f += F^α(t) = Σ_g Φ_gᵀ W_g ū_g(t)` now or at the next step (E4).
    pub fn add_load(&self, f: &mut [f64], when: When) {
        for g in 0..self.len() {
            let [wx, wy] = self.weight[g];
            let ub = self.prescribed(g, when);
            let (fx, fy) = (wx * ub[0], wy * ub[1]);
            if fx == 0.0 && fy == 0.0 {
                continue;
            }
            for (j, phi) in self.row(g) {
                f[2 * j as usize] += phi * fx;
                f[2 * j as usize + 1] += phi * fy;
            }
        }
    }

    /// `f += F^α(t) − K^α U = Σ_g Φ_gᵀ W_g (ū_g − u(x_g))`: the force of the
    /// penalty springs on the nodes, from their gap (no `K^α U` formed).
    pub fn add_spring_force(&self, u: &[f64], when: When, f: &mut [f64]) {
        for g in 0..self.len() {
            let [wx, wy] = self.weight[g];
            let ub = self.prescribed(g, when);
            let d = Vec2::new(ub[0], ub[1]) - self.displacement(g, u);
            let (fx, fy) = (wx * d.x, wy * d.y);
            for (j, phi) in self.row(g) {
                f[2 * j as usize] += phi * fx;
                f[2 * j as usize + 1] += phi * fy;
            }
        }
    }

    /// Energy of the penalty springs from their gap,
    /// `½ Σ_g (u(x_g) − ū_g)ᵀ W_g (u(x_g) − ū_g)` (module docs).
    pub fn energy(&self, u: &[f64], when: When) -> f64 {
        (0..self.len())
            .map(|g| {
                let [wx, wy] = self.weight[g];
                let ub = self.prescribed(g, when);
                let d = self.displacement(g, u) - Vec2::new(ub[0], ub[1]);
                0.5 * (wx * d.x * d.x + wy * d.y * d.y)
            })
            .sum()
    }

    /// Force of moving edge `e` on the body along its component (the
    /// generalised force conjugate to its drive's position),
    /// `Σ_g s_g w_g,c (ū_c(x_g) − u_c(x_g))`, with the prescribed values
    /// `when`.
    pub fn edge_force(&self, e: &MovingEdge, u: &[f64], when: When) -> f64 {
        let c = e.component;
        e.points
            .clone()
            .map(|g| {
                let u_g = self.displacement(g, u);
                let u_c = if c == 0 { u_g.x } else { u_g.y };
                e.scale_at(g) * self.weight[g][c] * (self.prescribed(g, when)[c] - u_c)
            })
            .sum()
    }

    /// Half the trapezoidal work of the moving edges over the step under
    /// way (drives decided), with their forces in the state `u` and the
    /// prescribed values `when`: `Σ_e ½ (d_e(n+1) − d_e(n)) F_e(u, when)`.
    /// Called with the states before (`Now`) and after (`Next`) the step,
    /// the sum is the work of the moving edges on the body; with the gap
    /// energy it is exact for γ = ½, β = ¼ whatever the positions `d_e(n)`
    /// (the stored energy `½U̇ᵀMU̇ + ½UᵀKU + E^α` changes by it plus the
    /// work of the other loads).
    pub fn half_step_work(&self, u: &[f64], when: When) -> f64 {
        self.moving
            .iter()
            .map(|e| {
                let dd = e.drive.state.d_next - e.drive.state.d;
                if dd == 0.0 {
                    return 0.0;
                }
                0.5 * dd * self.edge_force(e, u, when)
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::When;
    use crate::continuum::{
        BodyParams, Edge, EdgeCondition, Elastic, LinearField, MotionField, Prescribed, Rectangle,
    };
    use crate::efg::EfgBody;

    /// A 2 × 1 block, 6 × 4 nodes, with a small penalty α = 2E (so that
    /// `½UᵀK^αU − UᵀF^α + ½ΣūᵀWū` is well conditioned): the bottom edge
    /// moves in y, the left edge has a linear ux.
    fn block() -> EfgBody {
        let mut p = BodyParams::new(
            "b",
            Rectangle {
                origin: [0.0, 0.0],
                size: [2.0, 1.0],
            },
            [6, 4],
            Elastic::new(1000.0, 0.3).density(1.0).thickness(0.5),
        );
        p.penalty = Some(2000.0);
        let motion = MotionField {
            velocity: -0.3,
            until_step: Some(5),
        };
        p.bc.push(EdgeCondition {
            uy: Some(Prescribed::Motion(motion)),
            ..EdgeCondition::on(Edge::Bottom)
        });
        let linear = LinearField {
            linear: [0.01, 0.0, 0.02],
        };
        p.bc.push(EdgeCondition {
            ux: Some(Prescribed::Linear(linear)),
            ..EdgeCondition::on(Edge::Left)
        });
        let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
        b.params.dt = 0.01;
        // a smooth, non-trivial field of nodal parameters
        for i in 0..b.n_nodes() {
            let x = b.node(i);
            b.state.u[2 * i] = 0.01 + 0.003 * x.x * x.y - 0.002 * x.y;
            b.state.u[2 * i + 1] = -0.02 + 0.004 * x.x - 0.001 * x.y * x.y;
        }
        b
    }

    #[test]
    fn gap_energy_equals_the_quadratic_form_when_well_conditioned() {
        let mut b = block();
        let kbar = b.ops.kbar();
        let dt = b.params.dt;
        for step in [0, 3, 5, 9] {
            b.ops.penalty.set_step(step, dt);
            let (pen, u) = (&b.ops.penalty, &b.state.u);
            // ½UᵀK^αU − UᵀF^α(t) + ½ Σ_g ū_gᵀ W_g ū_g
            let mut f = vec![0.0; u.len()];
            pen.add_load(&mut f, When::Now);
            let c: f64 = (0..pen.len())
                .map(|g| {
                    let (w, ub) = (pen.weight(g), pen.prescribed(g, When::Now));
                    0.5 * (w[0] * ub[0] * ub[0] + w[1] * ub[1] * ub[1])
                })
                .sum();
            let quad = 0.5 * (kbar.quad_form(u) - b.ops.k.quad_form(u))
                - f.iter().zip(u).map(|(a, b)| a * b).sum::<f64>()
                + c;
            let gap = pen.energy(u, When::Now);
            assert!(gap > 1e-4, "the springs are stretched: {gap}");
            assert!((gap - quad).abs() < 1e-10 * gap, "{step}: {gap} vs {quad}");
            // the spring force is the gradient: F^α − K^α U
            let mut fs = vec![0.0; u.len()];
            pen.add_spring_force(u, When::Now, &mut fs);
            let mut ku = vec![0.0; u.len()];
            kbar.mul_add(u, &mut ku);
            b.ops
                .k
                .mul_add(&u.iter().map(|x| -x).collect::<Vec<_>>(), &mut ku);
            for i in 0..u.len() {
                assert!((fs[i] - (f[i] - ku[i])).abs() < 1e-10 * f64::max(1.0, f[i].abs()));
            }
        }
    }

    #[test]
    fn moving_edge_force_matches_the_old_unit_load_formula() {
        let mut b = block();
        let dt = b.params.dt;
        let (pen, u) = (&b.ops.penalty, &b.state.u);
        let e = &pen.moving[0];
        assert_eq!(e.component, 1);
        // F^α₁ = ∫ Φᵀ α e_y dΓ over the edge and ∫ α dΓ
        let mut unit = vec![0.0; u.len()];
        for g in e.points.clone() {
            for (j, phi) in pen.row(g) {
                unit[2 * j as usize + 1] += pen.weight(g)[1] * phi;
            }
        }
        let stiffness: f64 = e.points.clone().map(|g| pen.weight(g)[1]).sum();
        // ∫ α dΓ = α t L
        assert!((stiffness - 2000.0 * 0.5 * 2.0).abs() < 1e-9);
        let unit_u = unit.iter().zip(u).map(|(a, b)| a * b).sum::<f64>();
        for step in [0, 2, 7] {
            b.ops.penalty.set_step(step, dt);
            let e = &b.ops.penalty.moving[0];
            let d = e.drive.law.position(step, dt).unwrap();
            let old = d * stiffness - unit_u;
            let new = b.ops.penalty.edge_force(e, &b.state.u, When::Now);
            assert!((new - old).abs() < 1e-12 * stiffness, "{new} vs {old}");
        }
        b.ops.penalty.set_step(3, dt);
        let (pen, u) = (&b.ops.penalty, &b.state.u);
        let e = &pen.moving[0];
        // a rigid translation c of the body against an edge at d: the
        // springs hold ½ (c − d)² α t L, and push with (d − c) α t L
        let mut t = vec![0.0; u.len()];
        t.iter_mut().skip(1).step_by(2).for_each(|x| *x = 0.05);
        let d = e.drive.law.position(3, dt).unwrap();
        let left: f64 = (0..pen.len())
            .filter(|g| !e.points.contains(g))
            .map(|g| {
                let ub = pen.prescribed(g, When::Now);
                0.5 * pen.weight(g)[0] * ub[0] * ub[0]
            })
            .sum();
        let want = 0.5 * (0.05 - d) * (0.05 - d) * stiffness + left;
        assert!((pen.energy(&t, When::Now) - want).abs() < 1e-9 * want);
        let f = pen.edge_force(e, &t, When::Now);
        assert!((f - (d - 0.05) * stiffness).abs() < 1e-9 * stiffness);
    }
}
