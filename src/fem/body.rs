//! [`FemBody`]: a bilinear finite-element continuum on the same rectangular
//! node grid as an [`EfgBody`](crate::efg::EfgBody): the elements are the
//! `(nx − 1) × (ny − 1)` grid cells, so the mesh coincides with the EFG
//! background grid (§4.2.1 of the paper). Same material, loads, Newmark
//! integrator and factor-once Cholesky as the EFG body.
//!
//! # Boundary conditions: exact elimination on the nodes
//! FE shape functions have the Kronecker-delta property, so a prescribed
//! displacement `ū_c(t)` is imposed on the nodal DOF itself (no penalty).
//! Every constrained DOF `c` keeps its place in the DOF numbering (so states
//! are laid out as in the EFG body), but in the operators used for solving
//! rows and columns `c` of K and M are replaced by the identity and those
//! of C by zero: the effective matrix `α₁M + α₄C + K` is block diagonal
//! (free block, identity), SPD, factored once. Each solve then
//! - moves the prescribed DOFs' known terms to the right-hand side of the
//!   free rows with the unmodified matrices: `F_f −= K_fc u_c + C_fc u̇_c +
//!   M_fc ü_c`, where for a Newmark step `(u̇_c, ü_c)` at `t + Δt` are the
//!   Newmark rates of `u_c: ū_c(t) → ū_c(t + Δt)`
//!   ([`Newmark::rates`]);
//! - sets `U_c = ū_c(t + Δt)` in the solution, exactly.
//!
//! The free DOFs are then exactly those of the unreduced Newmark system in
//! which the constrained DOFs are driven through `ū_c(tₙ)` (a Lagrange
//! multiplier solve gives the same numbers); prescribed velocities and
//! accelerations are Newmark's, so a sudden start excites the γ = ½
//! trapezoidal oscillation of `u̇_c` (2v, 0, 2v, … for a ramp from rest)
//! that a dissipative γ > ½ damps. Constant values (`fixed`, numbers,
//! linear fields, Timoshenko) have `u̇_c = ü_c = 0`; moving edges
//! (`{ velocity, until_step }`) follow `ū_c(tₙ) = v·min(n, N)·Δt`.
//! Loads on constrained DOFs go to the support; the support reaction
//! `R_c = (M Ü + C U̇ + K U)_c − F_c` of moving DOFs does work
//! `Σ ½(R_c,n + R_c,n+1) Δū_c`, kept for the energy account
//! ([`FemBody::work`]). Kinetic and strain energy use the unmodified M, K.
//!
//! A node in two bcs (a corner) takes, per component, the value of the
//! last one listed.

use super::FemError;
use super::q4;
use crate::continuum::conditions::{
    constrained, edge_ends, prescribed, timoshenko_of, traction_at,
};
use crate::continuum::drive::When;
use crate::continuum::material::energy_error_of;
use crate::continuum::newmark::{Newmark, NewmarkParams, State};
use crate::continuum::quadrature::{self, QuadPoint};
use crate::continuum::timoshenko::Timoshenko;
use crate::continuum::{BodyParams, Drive, Edge, MassKind, Measure, TimedLoad};
use crate::continuum::{BodyState, Material, Sample, StateError};
use crate::geom::Vec2;
use crate::sparse::{Cholesky, Pattern, SymCsc};
use std::sync::Arc;
use std::time::Instant;

/// Sizes and timings of a build, for `check` and summaries.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct FemInfo {
    /// Number of nodes.
    pub nodes: usize,
    /// Number of DOFs, 2 per node.
    pub dofs: usize,
    /// Number of Q4 elements, `(nx − 1)(ny − 1)`.
    pub elements: usize,
    /// DOFs with a prescribed value (eliminated).
    pub constrained_dofs: usize,
    /// `"consistent"` or `"lumped"`.
    pub mass: &'static str,
    /// Stored entries of the lower triangle of K.
    pub nnz: usize,
    /// Wall time of the build (s).
    pub assembly_seconds: f64,
}

/// Where a point lies in the mesh: its element's four nodes
/// (counter-clockwise, see [`q4::CORNERS`]), their coordinates and the
/// parent coordinates `(ξ, η)` of the point.
#[derive(Debug, Clone, Copy)]
pub struct Located {
    /// The element's node numbers, counter-clockwise from the lower left.
    pub nodes: [usize; 4],
    /// Their reference coordinates.
    pub xy: [[f64; 2]; 4],
    /// Parent coordinate ξ ∈ [−1, 1] (along x).
    pub xi: f64,
    /// Parent coordinate η ∈ [−1, 1] (along y).
    pub eta: f64,
}

impl Located {
    /// Shape functions `N_a` at the point.
    pub fn shape(&self) -> [f64; 4] {
        q4::shape(self.xi, self.eta).0
    }
}

/// A bilinear (Q4) finite-element body.
#[derive(Debug)]
pub struct FemBody {
    /// Name (for messages and outputs).
    pub name: String,
    /// Node grid `[nx, ny]`; node `(i, j)` is `j·nx + i` at `(xs[i], ys[j])`.
    pub grid: [usize; 2],
    /// x of the node columns, ascending (reference configuration).
    pub xs: Vec<f64>,
    /// y of the node rows, ascending (reference configuration).
    pub ys: Vec<f64>,
    /// Lower-left corner of the rectangle.
    pub origin: Vec2,
    /// Width and height of the rectangle.
    pub size: Vec2,
    /// Elastic constants, density, thickness, damping and `D`.
    pub material: Material,
    /// Consistent or lumped mass.
    pub mass_kind: MassKind,
    /// Unmodified stiffness K (strain energy, prescribed-DOF couplings).
    pub k_full: SymCsc,
    /// K with the constrained rows/columns replaced by the identity.
    pub k: SymCsc,
    /// Unmodified `G = ∫ Nᵀ N t dA` (consistent or lumped): `M = ρ G`,
    /// `C = c G`.
    pub gram_full: SymCsc,
    /// G with the constrained rows/columns replaced by the identity
    /// (zeroed for C).
    pub gram: SymCsc,
    /// Per DOF: is it prescribed (eliminated)?
    pub constrained: Vec<bool>,
    /// The prescribed DOFs (module docs).
    constraints: Vec<Constraint>,
    /// Permanent loads (tractions, body force), prescribed DOFs not lifted.
    pub f_permanent: Vec<f64>,
    /// Loads applied for the initial static state only.
    pub f_released: Vec<f64>,
    /// Point loads accumulated for the next step, cleared by `advance`.
    pub f_point: Vec<f64>,
    /// Loads that change in time (tractions and point loads with a
    /// `table`): `F(t) = f_permanent + Σ_k s_k(t) F_k`.
    pub timed: Vec<TimedLoad>,
    /// Work of the timed loads since t = 0 (trapezoidal in time).
    pub load_work: f64,
    /// Total force of the discs on the body at the present state (set by
    /// the coupling before each step, for servo drives).
    pub contact_force: Vec2,
    /// The drives (prescribed components that change in time) with their
    /// component (0: x, 1: y), one per bc component.
    pub drives: Vec<(usize, Drive)>,
    /// Right-hand side scratch of a step.
    rhs: Vec<f64>,
    /// Work of the supports of moving edges since t = 0.
    motion_work: f64,
    /// Nodal displacements (Kronecker delta: these are the true values).
    pub state: State,
    /// Time reached, `step · Δt`.
    pub time: f64,
    /// Steps done.
    pub step: usize,
    /// Δt (0 until the dynamic start), γ, β.
    pub params: NewmarkParams,
    newmark: Option<Newmark>,
    /// The Timoshenko field if a bc uses it (for error norms and summaries).
    pub timoshenko: Option<Timoshenko>,
    /// Sizes and timings of the build.
    pub info: FemInfo,
}

/// A prescribed DOF: its value, its motion, and its couplings in the
/// unmodified K and G.
#[derive(Debug, Clone)]
struct Constraint {
    dof: usize,
    /// `ū_c` at t = 0.
    value: f64,
    /// A moving edge: its drive and the scale `s` of this DOF,
    /// `ū_c(tₙ) = value + s d(n)`.
    drive: Option<(usize, f64)>,
    /// `(j, K_cj, G_cj)` for every DOF `j` coupled with this one (itself
    /// included).
    row: Vec<(usize, f64, f64)>,
    /// Support reaction at the last step (moving DOFs).
    reaction: f64,
}

impl Constraint {
    /// The prescribed value now or at the next step.
    fn at(&self, drives: &[(usize, Drive)], when: When) -> f64 {
        self.value
            + self
                .drive
                .map_or(0.0, |(k, s)| s * drives[k].1.state.position(when))
    }
}

/// `U_c = ū_c` (now or next) in `u`, exactly.
fn impose(constraints: &[Constraint], drives: &[(usize, Drive)], u: &mut [f64], when: When) {
    for c in constraints {
        u[c.dof] = c.at(drives, when);
    }
}

/// Nodes of the grid element in column `i`, row `j`, counter-clockwise from
/// its lower-left corner (the Q4 node order).
fn element_nodes(nx: usize, i: usize, j: usize) -> [usize; 4] {
    [
        j * nx + i,
        j * nx + i + 1,
        (j + 1) * nx + i + 1,
        (j + 1) * nx + i,
    ]
}

/// Nodes sharing an element with `node` (itself included), ascending.
fn neighbours(nx: usize, ny: usize, node: usize) -> impl Iterator<Item = usize> {
    let (i, j) = (node % nx, node / nx);
    (j.saturating_sub(1)..=(j + 1).min(ny - 1))
        .flat_map(move |jj| (i.saturating_sub(1)..=(i + 1).min(nx - 1)).map(move |ii| jj * nx + ii))
}

/// Lower-triangle pattern of the Q4 mesh: DOF `2I + a` couples with the
/// DOFs of every node sharing an element with node `I`.
fn grid_pattern(nx: usize, ny: usize) -> Pattern {
    let n = nx * ny;
    let ndof = 2 * n;
    let mut col_ptr = Vec::with_capacity(ndof + 1);
    let mut row_idx = Vec::with_capacity(ndof * 10);
    col_ptr.push(0);
    let mut nb = Vec::with_capacity(9);
    for node in 0..n {
        nb.clear();
        nb.extend(neighbours(nx, ny, node).filter(|&m| m >= node));
        for a in 0..2 {
            for &m in &nb {
                for b in 0..2 {
                    if m > node || b >= a {
                        row_idx.push(2 * m + b);
                    }
                }
            }
            col_ptr.push(row_idx.len());
        }
    }
    Pattern {
        n: ndof,
        col_ptr,
        row_idx,
    }
}

/// Position of entry `(r, c)` (`r ≥ c`) in the values of `p`.
fn slot(p: &Pattern, r: usize, c: usize) -> usize {
    let s = p.col_ptr[c];
    let rows = &p.row_idx[s..p.col_ptr[c + 1]];
    s + rows
        .binary_search(&r)
        .expect("entry in the Q4 mesh pattern")
}

fn add(m: &mut SymCsc, r: usize, c: usize, v: f64) {
    let (r, c) = if r >= c { (r, c) } else { (c, r) };
    let k = slot(&m.pattern, r, c);
    m.values[k] += v;
}

impl FemBody {
    /// Build the body: node grid, element matrices (2 × 2 Gauss), global K
    /// and Gram matrix on one pattern, loads, and the exact elimination of
    /// the prescribed DOFs (module docs).
    pub fn new(spec: &BodyParams, gravity: [f64; 2]) -> Result<FemBody, FemError> {
        let [nx, ny] = spec.nodes;
        if nx < 2 || ny < 2 {
            return Err(FemError::Invalid(format!(
                "body `{}`: the node grid needs at least 2 × 2 nodes",
                spec.name
            )));
        }
        let t0 = Instant::now();
        let origin = Vec2::from(spec.rectangle.origin);
        let size = Vec2::from(spec.rectangle.size);
        let xs: Vec<f64> = (0..nx)
            .map(|i| origin.x + size.x * i as f64 / (nx - 1) as f64)
            .collect();
        let ys: Vec<f64> = (0..ny)
            .map(|j| origin.y + size.y * j as f64 / (ny - 1) as f64)
            .collect();
        let material = Material::of_params(spec);
        let t = material.thickness;
        let [d11, d12, d22, d33] = material.d;
        let d = [[d11, d12, 0.0], [d12, d22, 0.0], [0.0, 0.0, d33]];
        let n = nx * ny;
        let ndof = 2 * n;
        let pattern = Arc::new(grid_pattern(nx, ny));
        let mut k = SymCsc::zeros(pattern.clone());
        let mut gram = SymCsc::zeros(pattern);
        let mut phi_integral = vec![0.0; n];
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let nodes = element_nodes(nx, i, j);
                let xy = [
                    [xs[i], ys[j]],
                    [xs[i + 1], ys[j]],
                    [xs[i + 1], ys[j + 1]],
                    [xs[i], ys[j + 1]],
                ];
                let ke = q4::stiffness(&xy, &d, t);
                let me = q4::consistent_mass(&xy, 1.0, t);
                for a in 0..4 {
                    phi_integral[nodes[a]] += me[a].iter().sum::<f64>();
                    for b in 0..4 {
                        for r in 0..2 {
                            for c in 0..2 {
                                let (gr, gc) = (2 * nodes[a] + r, 2 * nodes[b] + c);
                                if gr >= gc {
                                    add(&mut k, gr, gc, ke[2 * a + r][2 * b + c]);
                                }
                            }
                        }
                        if spec.mass == MassKind::Consistent && nodes[a] >= nodes[b] {
                            for r in 0..2 {
                                add(&mut gram, 2 * nodes[a] + r, 2 * nodes[b] + r, me[a][b]);
                            }
                        }
                    }
                }
            }
        }
        if spec.mass == MassKind::Lumped {
            for (i, m) in phi_integral.iter().enumerate() {
                add(&mut gram, 2 * i, 2 * i, *m);
                add(&mut gram, 2 * i + 1, 2 * i + 1, *m);
            }
        }
        let timoshenko = timoshenko_of(spec);
        // prescribed DOFs: the nodes on the edge take ū at their position
        // per DOF: its value at t = 0 and its drive (index, scale)
        type Fixed = (f64, Option<(usize, f64)>);
        let mut fixed: Vec<Option<Fixed>> = vec![None; ndof];
        let mut drives: Vec<(usize, Drive)> = Vec::new();
        let edge_nodes = |e: Edge| -> Vec<usize> {
            match e {
                Edge::Left => (0..ny).map(|j| j * nx).collect(),
                Edge::Right => (0..ny).map(|j| j * nx + nx - 1).collect(),
                Edge::Bottom => (0..nx).collect(),
                Edge::Top => (0..nx).map(|i| (ny - 1) * nx + i).collect(),
            }
        };
        for bc in spec.bc.iter().filter(|b| !b.is_load()) {
            let (cx, cy) = constrained(bc);
            // one drive per moving component of the bc
            let mut ids = [None, None];
            for (a, pr) in [(0, &bc.ux), (1, &bc.uy)] {
                if let Some(law) = pr.as_ref().and_then(|p| p.drive_law()) {
                    ids[a] = Some(drives.len());
                    drives.push((a, Drive::new(law)));
                }
            }
            for node in edge_nodes(bc.side().map_err(FemError::Invalid)?) {
                let x = Vec2::new(xs[node % nx], ys[node / nx]);
                let ub = prescribed(bc, x, timoshenko.as_ref(), &spec.elastic);
                for (a, on, pr) in [(0, cx, &bc.ux), (1, cy, &bc.uy)] {
                    if on {
                        let drive = ids[a].map(|k| {
                            let s = pr.as_ref().map_or(1.0, |p| p.drive_scale(x.x, x.y));
                            (k, s)
                        });
                        fixed[2 * node + a] = Some((ub[a], drive));
                    }
                }
            }
        }
        let constraints: Vec<Constraint> = fixed
            .iter()
            .enumerate()
            .filter_map(|(dof, f)| {
                let (value, drive) = (*f)?;
                let row = neighbours(nx, ny, dof / 2)
                    .flat_map(|m| [2 * m, 2 * m + 1])
                    .map(|j| (j, k.get(dof, j), gram.get(dof, j)))
                    .collect();
                Some(Constraint {
                    dof,
                    value,
                    drive,
                    row,
                    reaction: 0.0,
                })
            })
            .collect();
        let constrained: Vec<bool> = fixed.iter().map(Option::is_some).collect();
        let (k_full, gram_full) = (k.clone(), gram.clone());
        // the constrained rows/columns of K and G become the identity
        let p = k.pattern.clone();
        for c in 0..ndof {
            for s in p.col_ptr[c]..p.col_ptr[c + 1] {
                let r = p.row_idx[s];
                if constrained[r] || constrained[c] {
                    let diag = if r == c { 1.0 } else { 0.0 };
                    k.values[s] = diag;
                    gram.values[s] = diag;
                }
            }
        }
        let mut f_permanent = vec![0.0; ndof];
        let mut f_released = vec![0.0; ndof];
        let mut body = FemBody {
            name: spec.name.clone(),
            grid: spec.nodes,
            xs,
            ys,
            origin,
            size,
            material,
            mass_kind: spec.mass,
            k_full,
            k,
            gram_full,
            gram,
            constrained,
            constraints,
            f_permanent: vec![],
            f_released: vec![],
            f_point: vec![0.0; ndof],
            timed: Vec::new(),
            load_work: 0.0,
            contact_force: Vec2::ZERO,
            drives,
            rhs: vec![0.0; ndof],
            motion_work: 0.0,
            state: State::zeros(ndof),
            time: 0.0,
            step: 0,
            params: NewmarkParams {
                dt: 0.0,
                gamma: spec.newmark[0],
                beta: spec.newmark[1],
            },
            newmark: None,
            timoshenko,
            info: FemInfo::default(),
        };
        // tractions (Eq. 27, boundary term), 3 Gauss points per element edge
        // (exact for the parabolic shear times the linear edge functions)
        let segs = |e: Edge| match e {
            Edge::Left | Edge::Right => ny - 1,
            Edge::Top | Edge::Bottom => nx - 1,
        };
        let mut scratch = Vec::new();
        for bc in spec.bc.iter().filter(|b| b.is_load()) {
            let target = if bc.table.is_some() {
                scratch.clear();
                scratch.resize(ndof, 0.0);
                &mut scratch
            } else if bc.name.as_deref().is_some_and(|n| spec.is_released(n)) {
                &mut f_released
            } else {
                &mut f_permanent
            };
            let side = bc.side().map_err(FemError::Invalid)?;
            let (a, b) = edge_ends(origin, size, side);
            for QuadPoint { x, w } in quadrature::edge_points(a, b, segs(side), 3) {
                let tr = traction_at(bc, a, b, x);
                let loc = body.locate(x)?;
                for (&node, phi) in loc.nodes.iter().zip(loc.shape()) {
                    target[2 * node] += w * t * phi * tr[0];
                    target[2 * node + 1] += w * t * phi * tr[1];
                }
            }
            if let Some(tb) = &bc.table {
                body.timed.push(TimedLoad::from_dense(tb.clone(), &scratch));
            }
        }
        // point loads at material points, F += Nᵀ(p) f (Eq. 46)
        for pl in &spec.loads {
            let loc = body.locate(Vec2::from(pl.point))?;
            let target = if pl.table.is_some() {
                scratch.clear();
                scratch.resize(ndof, 0.0);
                &mut scratch
            } else {
                &mut f_permanent
            };
            for (&node, phi) in loc.nodes.iter().zip(loc.shape()) {
                target[2 * node] += phi * pl.force[0];
                target[2 * node + 1] += phi * pl.force[1];
            }
            if let Some(tb) = &pl.table {
                body.timed.push(TimedLoad::from_dense(tb.clone(), &scratch));
            }
        }
        // body force ρ g (Eq. 27, domain term)
        if spec.self_weight && gravity != [0.0, 0.0] && material.density > 0.0 {
            let target = if spec.is_released("gravity") {
                &mut f_released
            } else {
                &mut f_permanent
            };
            for (i, s) in phi_integral.iter().enumerate() {
                target[2 * i] += material.density * gravity[0] * s;
                target[2 * i + 1] += material.density * gravity[1] * s;
            }
        }
        impose(
            &body.constraints,
            &body.drives,
            &mut body.state.u,
            When::Now,
        );
        body.info = FemInfo {
            nodes: n,
            dofs: ndof,
            elements: (nx - 1) * (ny - 1),
            constrained_dofs: body.constraints.len(),
            mass: match spec.mass {
                MassKind::Consistent => "consistent",
                MassKind::Lumped => "lumped",
            },
            nnz: body.k.pattern.nnz(),
            assembly_seconds: t0.elapsed().as_secs_f64(),
        };
        body.f_permanent = f_permanent;
        body.f_released = f_released;
        Ok(body)
    }

    /// Number of nodes, `nx · ny`.
    pub fn n_nodes(&self) -> usize {
        self.grid[0] * self.grid[1]
    }
    /// Number of DOFs, `2 · n_nodes` (interleaved x, y).
    pub fn n_dofs(&self) -> usize {
        2 * self.n_nodes()
    }
    /// Reference position of node `i`.
    pub fn node(&self, i: usize) -> Vec2 {
        Vec2::new(self.xs[i % self.grid[0]], self.ys[i / self.grid[0]])
    }

    /// The element containing `p` (on a shared edge or node: the one with
    /// the lower index; the shape functions agree there) and `(ξ, η)`.
    pub fn locate(&self, p: Vec2) -> Result<Located, FemError> {
        let [nx, ny] = self.grid;
        let tol = 1e-9 * (self.size.x + self.size.y);
        let inside = p.x >= self.origin.x - tol
            && p.x <= self.origin.x + self.size.x + tol
            && p.y >= self.origin.y - tol
            && p.y <= self.origin.y + self.size.y + tol;
        if !inside || !p.x.is_finite() || !p.y.is_finite() {
            return Err(FemError::Outside {
                body: self.name.clone(),
                point: [p.x, p.y],
            });
        }
        let cell = |v: f64, o: f64, l: f64, n: usize| -> usize {
            let s = ((v - o) / l * (n - 1) as f64).floor();
            (s.max(0.0) as usize).min(n - 2)
        };
        let i = cell(p.x, self.origin.x, self.size.x, nx);
        let j = cell(p.y, self.origin.y, self.size.y, ny);
        let nodes = element_nodes(nx, i, j);
        let xy = nodes.map(|k| self.node(k).to_array());
        let (xi, eta) = q4::parent_of_rect(&xy, p.to_array());
        Ok(Located {
            nodes,
            xy,
            xi: xi.clamp(-1.0, 1.0),
            eta: eta.clamp(-1.0, 1.0),
        })
    }

    /// Static solve `K U = F` with the permanent and released loads plus the
    /// accumulated point loads; the state becomes (U, 0, 0), `U_c = ū_c`.
    pub fn solve_static(&mut self) -> Result<(), FemError> {
        let mut f: Vec<f64> = (0..self.n_dofs())
            .map(|i| self.f_permanent[i] + self.f_released[i] + self.f_point[i])
            .collect();
        for l in &self.timed {
            l.add_to(&mut f, self.time);
        }
        let drives = &self.drives;
        self.lift(&mut f, |c| [c.at(drives, When::Now), 0.0, 0.0]);
        let mut ch = Cholesky::factor(&self.k)?;
        ch.solve_in_place(&mut f);
        impose(&self.constraints, &self.drives, &mut f, When::Now);
        self.state.u = f;
        self.state.v.iter_mut().for_each(|x| *x = 0.0);
        self.state.a.iter_mut().for_each(|x| *x = 0.0);
        Ok(())
    }

    /// Move the prescribed DOFs' known terms to the right-hand side of the
    /// free rows: `f_j −= K_jc u_c + c G_jc u̇_c + ρ G_jc ü_c` (unmodified
    /// matrices) with `kin(c) = [u_c, u̇_c, ü_c]`.
    fn lift(&self, f: &mut [f64], kin: impl Fn(&Constraint) -> [f64; 3]) {
        let (rho, damp) = (self.material.density, self.material.damping);
        for c in &self.constraints {
            let [u, v, a] = kin(c);
            if u == 0.0 && v == 0.0 && a == 0.0 {
                continue;
            }
            for &(j, k, g) in &c.row {
                if !self.constrained[j] {
                    f[j] -= k * u + g * (damp * v + rho * a);
                }
            }
        }
    }

    /// Support reaction `(M Ü + C U̇ + K U)_c − applied_c` at a prescribed DOF.
    fn reaction(&self, c: &Constraint, applied: f64) -> f64 {
        let (rho, damp, s) = (self.material.density, self.material.damping, &self.state);
        c.row
            .iter()
            .map(|&(j, k, g)| k * s.u[j] + g * (damp * s.v[j] + rho * s.a[j]))
            .sum::<f64>()
            - applied
    }

    /// The mass matrix `ρ G` (constrained part: identity).
    fn mass_matrix(&self) -> SymCsc {
        let mut m = self.gram.scaled(self.material.density);
        self.set_constrained_diagonal(&mut m, 1.0);
        m
    }

    fn set_constrained_diagonal(&self, m: &mut SymCsc, v: f64) {
        let p = m.pattern.clone();
        for c in &self.constraints {
            m.values[p.col_ptr[c.dof]] = v;
        }
    }

    /// Prepare time stepping with step `dt` and the body's γ, β: factor
    /// `α₁M + α₄C + K` once and compute the initial acceleration under the
    /// permanent loads (released loads off; prescribed DOFs: `ü_c = 0`).
    pub fn start_dynamic(&mut self, dt: f64) -> Result<(), FemError> {
        crate::continuum::newmark::check_dynamic(dt, self.material.density, &self.name)
            .map_err(FemError::Invalid)?;
        self.params.dt = dt;
        let (m, c) = self.mass_damping();
        let mut f: Vec<f64> = (0..self.n_dofs())
            .map(|i| self.f_permanent[i] + self.f_point[i])
            .collect();
        for l in &self.timed {
            l.add_to(&mut f, self.step as f64 * dt);
        }
        let s = &self.state;
        self.lift(&mut f, |c| [s.u[c.dof], s.v[c.dof], 0.0]);
        for c in &self.constraints {
            f[c.dof] = s.u[c.dof]; // the identity row gives ü_c = 0
        }
        crate::continuum::newmark::consistent_acceleration(
            &m,
            c.as_ref(),
            &self.k,
            &mut self.state,
            &f,
            None,
        )?;
        for i in 0..self.constraints.len() {
            let c = &self.constraints[i];
            self.state.a[c.dof] = 0.0;
            let mut applied = self.f_permanent[c.dof] + self.f_point[c.dof];
            for l in &self.timed {
                applied += l.table.value(self.step as f64 * dt)
                    * l.dofs
                        .iter()
                        .filter(|e| e.0 == c.dof)
                        .map(|e| e.1)
                        .sum::<f64>();
            }
            let r = self.reaction(c, applied);
            self.constraints[i].reaction = r;
        }
        self.integrator(m, c)
    }

    /// Go on from the present state with steps of `dt`, `scale.0` of them
    /// per `scale.1` present steps: `α₁M + α₄C + K` factored for `dt`, the state (its
    /// acceleration the last step's) and the time kept, the step count
    /// scaled so that the time is still `step · dt`.
    pub fn retime(&mut self, dt: f64, scale: (usize, usize)) -> Result<(), FemError> {
        crate::continuum::newmark::check_dynamic(dt, self.material.density, &self.name)
            .map_err(FemError::Invalid)?;
        self.newmark.as_ref().ok_or(FemError::NotStarted)?;
        self.params.dt = dt;
        self.step = crate::continuum::rescaled_step(self.step, scale).ok_or_else(|| {
            FemError::Invalid(format!(
                "body `{}`: step {} is not a whole number of steps of {dt:e} s",
                self.name, self.step
            ))
        })?;
        let (m, c) = self.mass_damping();
        self.integrator(m, c)
    }

    /// The mass matrix and the damping matrix (if any), prescribed DOFs
    /// undamped.
    fn mass_damping(&self) -> (SymCsc, Option<SymCsc>) {
        let m = self.mass_matrix();
        let c = (self.material.damping > 0.0).then(|| {
            let mut c = self.gram.scaled(self.material.damping);
            self.set_constrained_diagonal(&mut c, 0.0);
            c
        });
        (m, c)
    }

    /// The Newmark integrator of `m`, `c` and the stiffness, prescribed
    /// DOFs imposed.
    fn integrator(&mut self, m: SymCsc, c: Option<SymCsc>) -> Result<(), FemError> {
        let mut nm = Newmark::new(m, c, self.k.clone(), self.params)?;
        nm.set_imposed(self.constrained.clone());
        self.newmark = Some(nm);
        Ok(())
    }

    /// The integrator, once [`FemBody::start_dynamic`] was called.
    pub fn newmark(&self) -> Option<&Newmark> {
        self.newmark.as_ref()
    }

    /// Mutable access to the integrator (between `predict` and `commit`).
    pub fn newmark_mut(&mut self) -> Option<&mut Newmark> {
        self.newmark.as_mut()
    }

    /// One Newmark step with the permanent loads plus the point loads
    /// accumulated since the last step (then cleared).
    pub fn advance(&mut self) -> Result<(), FemError> {
        self.predict()?;
        self.commit()
    }

    /// First half of [`advance`](Self::advance): solve the step under the
    /// permanent loads and the accumulated point loads, with the prescribed
    /// DOFs at `ū_c(t + Δt)` (their terms lifted to the free rows, module
    /// docs); the integrator holds the solution until
    /// [`commit`](Self::commit) (the coupling adds implicit contact forces
    /// in between, which put no load on prescribed DOFs).
    pub fn predict(&mut self) -> Result<&mut Newmark, FemError> {
        let nm = self.newmark.as_ref().ok_or(FemError::NotStarted)?;
        let (step, dt) = (self.step, self.params.dt);
        for (p, f) in self.f_point.iter_mut().zip(&self.f_permanent) {
            *p += f;
        }
        for l in &self.timed {
            l.add_to(&mut self.f_point, (step + 1) as f64 * dt);
        }
        // the drives decide their positions at t + Δt from the state at t:
        // a servo on the edge measures the support reactions
        // `Σ_c s_c R_c` of its DOFs (the force of the support on the body)
        for k in 0..self.drives.len() {
            let (comp, d) = &self.drives[k];
            let measured = match d.measure() {
                Some(Measure::Contacts) => self.contact_force.to_array()[*comp],
                _ => self
                    .constraints
                    .iter()
                    .filter_map(|c| c.drive.filter(|e| e.0 == k).map(|e| e.1 * c.reaction))
                    .sum(),
            };
            self.drives[k].1.decide(step, dt, measured);
        }
        let mut rhs = std::mem::take(&mut self.rhs);
        rhs.copy_from_slice(&self.f_point);
        let s = &self.state;
        let drives = &self.drives;
        self.lift(&mut rhs, |c| {
            let (i, u1) = (c.dof, c.at(drives, When::Next));
            let (v1, a1) = nm.rates(s.u[i], s.v[i], s.a[i], u1);
            [u1, v1, a1]
        });
        let nm = self.newmark.as_mut().ok_or(FemError::NotStarted)?;
        nm.predict(&self.state, &rhs);
        self.rhs = rhs;
        impose(
            &self.constraints,
            &self.drives,
            nm.solution_mut(),
            When::Next,
        );
        Ok(nm)
    }

    /// Second half of [`advance`](Self::advance): accept the solution
    /// (prescribed DOFs reset to `ū_c(t + Δt)` exactly), book the work of
    /// the supports of moving edges, clear the point loads, advance the
    /// clock.
    pub fn commit(&mut self) -> Result<(), FemError> {
        let (step, dt) = (self.step, self.params.dt);
        let (t0, t1) = (step as f64 * dt, (step + 1) as f64 * dt);
        let nm = self.newmark.as_mut().ok_or(FemError::NotStarted)?;
        impose(
            &self.constraints,
            &self.drives,
            nm.solution_mut(),
            When::Next,
        );
        let loads0 = TimedLoad::half_sum(&self.timed, &self.state.u, t0, t1);
        nm.commit(&mut self.state);
        if !self.timed.is_empty() {
            self.load_work += TimedLoad::half_sum(&self.timed, &self.state.u, t0, t1) - loads0;
        }
        for i in 0..self.constraints.len() {
            let c = &self.constraints[i];
            if c.drive.is_none() {
                continue;
            }
            let r = self.reaction(c, self.f_point[c.dof]);
            let du = c.at(&self.drives, When::Next) - c.at(&self.drives, When::Now);
            self.motion_work += 0.5 * (c.reaction + r) * du;
            self.constraints[i].reaction = r;
        }
        for (_, d) in &mut self.drives {
            d.advance();
        }
        self.f_point.iter_mut().for_each(|x| *x = 0.0);
        self.step += 1;
        self.time = self.step as f64 * self.params.dt;
        Ok(())
    }

    /// What changes while the body steps ([`BodyState`]): `U`, `U̇`, `Ü`,
    /// clock, pending point loads, the work of the moving supports and
    /// their last reactions. Call between steps.
    pub fn save_state(&self) -> BodyState {
        BodyState {
            name: self.name.clone(),
            state: self.state.clone(),
            step: self.step,
            time: self.time,
            f_point: self.f_point.clone(),
            motion_work: self.motion_work,
            drives: self.drives.iter().map(|(_, d)| d.state).collect(),
            load_work: self.load_work,
            reactions: self.constraints.iter().map(|c| c.reaction).collect(),
            boundary: None,
            cracks: None,
        }
    }

    /// Restore a [`save_state`](Self::save_state) of a body built from the
    /// same parameters (name, DOFs and prescribed DOFs checked).
    pub fn restore_state(&mut self, s: &BodyState) -> Result<(), StateError> {
        s.check(&self.name, self.n_dofs(), self.constraints.len())?;
        s.check_drives(&self.name, Some(self.drives.len()))?;
        self.state.clone_from(&s.state);
        for ((_, d), st) in self.drives.iter_mut().zip(&s.drives) {
            d.state = *st;
        }
        self.load_work = s.load_work;
        self.step = s.step;
        self.time = s.time;
        self.f_point.clone_from(&s.f_point);
        self.motion_work = s.motion_work;
        for (c, &r) in self.constraints.iter_mut().zip(&s.reactions) {
            c.reaction = r;
        }
        Ok(())
    }

    /// The shape row `[(node, N_a(p))]` of the element containing `p`.
    pub fn row(&self, p: Vec2) -> Result<Vec<(u32, f64)>, FemError> {
        let loc = self.locate(p)?;
        Ok(loc
            .nodes
            .iter()
            .map(|&i| i as u32)
            .zip(loc.shape())
            .collect())
    }

    /// Add the point load `f` at `p` to the next step's force:
    /// `F += Nᵀ(p) f` with the element's shape functions (Eq. 46).
    pub fn add_point_load(&mut self, p: Vec2, f: Vec2) -> Result<(), FemError> {
        let row = self.row(p)?;
        self.add_point_load_row(&row, f);
        Ok(())
    }

    /// [`FemBody::add_point_load`] with a precomputed row.
    pub fn add_point_load_row(&mut self, row: &[(u32, f64)], f: Vec2) {
        crate::continuum::add_row_load(&mut self.f_point, row, f);
    }

    /// Fields at a located point: `u = Σ N_a u_a`, `v = Σ N_a u̇_a`,
    /// engineering strain `B u` (ERRATA E5), stress `D ε`.
    pub fn sample_located(&self, loc: &Located) -> Sample {
        let (u, v) = (&self.state.u, &self.state.v);
        let n = loc.shape();
        let (g, _) = q4::gradients(&loc.xy, loc.xi, loc.eta);
        let mut s = Sample::default();
        let mut e = [0.0; 3];
        for a in 0..4 {
            let i = loc.nodes[a];
            let (ux, uy) = (u[2 * i], u[2 * i + 1]);
            s.u.x += n[a] * ux;
            s.u.y += n[a] * uy;
            s.v.x += n[a] * v[2 * i];
            s.v.y += n[a] * v[2 * i + 1];
            e[0] += g[a][0] * ux;
            e[1] += g[a][1] * uy;
            e[2] += g[a][1] * ux + g[a][0] * uy;
        }
        s.strain = e;
        s.stress = self.material.stress(e);
        s
    }

    /// Displacement, velocity, strain and stress at `p`.
    pub fn sample(&self, p: Vec2) -> Result<Sample, FemError> {
        Ok(self.sample_located(&self.locate(p)?))
    }

    /// Kinetic energy `½ U̇ᵀ M U̇` with the unmodified M.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.material.density * self.gram_full.quad_form(&self.state.v)
    }
    /// Work done on the body since t = 0 by its permanent loads (`F·U`,
    /// constant loads from U = 0) and by the supports of moving edges
    /// (trapezoidal rule, exact for γ = ½, β = ¼).
    pub fn work(&self) -> f64 {
        let w: f64 = self
            .f_permanent
            .iter()
            .zip(&self.state.u)
            .map(|(f, u)| f * u)
            .sum();
        w + self.motion_work + self.load_work
    }
    /// Strain energy `½ Uᵀ K U` with the unmodified K.
    pub fn strain_energy(&self) -> f64 {
        0.5 * self.k_full.quad_form(&self.state.u)
    }

    /// Relative energy-norm error against an exact stress field (see
    /// [`EfgBody::energy_error`](crate::efg::EfgBody::energy_error)).
    pub fn energy_error(
        &self,
        exact_stress: impl Fn(Vec2) -> [f64; 3],
        cells: [usize; 2],
        gauss: usize,
    ) -> Result<f64, FemError> {
        energy_error_of(
            &self.material,
            self.origin,
            self.size,
            cells,
            gauss,
            |p| self.sample(p),
            exact_stress,
        )
    }

    /// Nodal displacement, velocity, and stress averaged over the elements
    /// around each node (for output frames).
    pub fn nodal_fields(&self) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let [nx, ny] = self.grid;
        let n = self.n_nodes();
        let mut s = vec![0.0; 3 * n];
        let mut count = vec![0.0; n];
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let nodes = element_nodes(nx, i, j);
                let xy = nodes.map(|k| self.node(k).to_array());
                for (a, c) in q4::CORNERS.iter().enumerate() {
                    let loc = Located {
                        nodes,
                        xy,
                        xi: c[0],
                        eta: c[1],
                    };
                    let smp = self.sample_located(&loc);
                    for q in 0..3 {
                        s[3 * nodes[a] + q] += smp.stress[q];
                    }
                    count[nodes[a]] += 1.0;
                }
            }
        }
        for (i, c) in count.iter().enumerate() {
            for q in 0..3 {
                s[3 * i + q] /= c;
            }
        }
        (self.state.u.clone(), self.state.v.clone(), s)
    }
}
