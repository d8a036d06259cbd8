//! What the coupling needs from a continuum body: its current contact
//! boundary, the velocity of a boundary material point, point loads, and one
//! time step. Two implementations: the EFG body and (for comparison) the
//! bilinear FE body, so the coupling never knows which one it talks to.

use crate::geom::Vec2;
use crate::newmark::{Newmark, State, StepStiffness};
use crate::scenario::body::Edge;

/// A polyline on the body's contact boundary, oriented with the body on its
/// left (counter-clockwise around the body), so the outward normal of a
/// segment `a → b` is `(b − a)` rotated by −90°.
#[derive(Debug, Clone, Default)]
pub struct BoundaryChain {
    /// Material (reference) coordinates of the chain's points.
    pub reference: Vec<Vec2>,
    /// Current (true, displaced) positions of the same points (ERRATA E7:
    /// interpolated displacements, not raw EFG nodal parameters).
    pub current: Vec<Vec2>,
}

impl BoundaryChain {
    /// A chain at rest: current = reference.
    pub fn new(reference: Vec<Vec2>) -> Self {
        BoundaryChain {
            current: reference.clone(),
            reference,
        }
    }

    /// Number of segments.
    pub fn segments(&self) -> usize {
        self.reference.len().saturating_sub(1)
    }

    /// Material point at parameter `s ∈ [0, 1]` of segment `seg`.
    pub fn material_point(&self, seg: usize, s: f64) -> Vec2 {
        let a = self.reference[seg];
        a + (self.reference[seg + 1] - a) * s
    }
}

/// Edges in counter-clockwise order around a rectangle (body on the left).
const CCW: [Edge; 4] = [Edge::Bottom, Edge::Right, Edge::Top, Edge::Left];

/// Reference points along `edge` of the rectangle `origin`, `size` with a
/// `grid = [nx, ny]` of nodes, counter-clockwise, `refine` points per node
/// spacing (both ends included).
fn edge_points(origin: Vec2, size: Vec2, grid: [usize; 2], edge: Edge, refine: usize) -> Vec<Vec2> {
    let (o, s) = (origin, size);
    let (a, e, n) = match edge {
        Edge::Bottom => (o, Vec2::new(o.x + s.x, o.y), grid[0]),
        Edge::Right => (Vec2::new(o.x + s.x, o.y), o + s, grid[1]),
        Edge::Top => (o + s, Vec2::new(o.x, o.y + s.y), grid[0]),
        Edge::Left => (Vec2::new(o.x, o.y + s.y), o, grid[1]),
    };
    let m = (n - 1) * refine;
    (0..=m)
        .map(|k| a + (e - a) * (k as f64 / m as f64))
        .collect()
}

/// Chains of reference points along the listed `edges` of a rectangular
/// body (`origin`, `size`, node `grid`), `refine` points per node spacing:
/// consecutive listed edges (in CCW order) are joined around their common
/// corner; all four edges make one closed loop. Shared by the EFG and FE
/// bodies (for FE the node spacing is the element edge).
pub fn contact_chains(
    origin: Vec2,
    size: Vec2,
    grid: [usize; 2],
    edges: &[Edge],
    refine: usize,
) -> Vec<Vec<Vec2>> {
    let listed = |e: Edge| edges.contains(&e);
    let k0 = match (0..4).find(|&k| listed(CCW[k]) && !listed(CCW[(k + 3) % 4])) {
        Some(k) => k,
        None if edges.is_empty() => return Vec::new(),
        None => 0, // all four: a closed loop starting at the bottom edge
    };
    let mut chains: Vec<Vec<Vec2>> = Vec::new();
    let mut open = false;
    for k in k0..k0 + 4 {
        let e = CCW[k % 4];
        if !listed(e) {
            open = false;
            continue;
        }
        let pts = edge_points(origin, size, grid, e, refine);
        match chains.last_mut() {
            Some(c) if open => c.extend_from_slice(&pts[1..]),
            _ => chains.push(pts),
        }
        open = true;
    }
    chains
}

/// An interpolation row `[(node, φ_J(x))]`: the body's shape functions at a
/// material point, the same for displacement, velocity and point loads (E7).
pub type Row = Vec<(u32, f64)>;

/// `Σ_J φ_J a_J` of a nodal vector `a` (interleaved x, y) over a row.
pub fn interpolate(row: &[(u32, f64)], a: &[f64]) -> Vec2 {
    let mut s = Vec2::ZERO;
    for &(j, phi) in row {
        s.x += phi * a[2 * j as usize];
        s.y += phi * a[2 * j as usize + 1];
    }
    s
}

/// A stiffness on the motion of a few points of a contact chain during one
/// implicit step: energy `½ Σ_kl c[k][l] ψ_k ψ_l`, where
/// `ψ_k = Σ_(i, a) a · ΔP_i` over the pairs `(i, a)` of `psi[k]` and `ΔP_i`
/// is the increment of chain point `i` over the step. This is how a
/// contact's geometric stiffness (its normal turning with the boundary,
/// [`crate::coupling::interface::Touch::geometric_stiffness`]) joins the
/// body's Newmark step implicitly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainStiffness {
    /// Index of the chain in [`Continuum::contact_boundary`].
    pub chain: usize,
    /// The two functionals: `(chain point, coefficient)` pairs.
    pub psi: [[(usize, Vec2); 2]; 2],
    /// Their symmetric 2 × 2 matrix.
    pub c: [[f64; 2]; 2],
}

/// Energies of a body (for the coupled energy account).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyEnergies {
    /// `½ U̇ᵀ M U̇`.
    pub kinetic: f64,
    /// `½ Uᵀ K̄ U` (elastic plus penalty springs, moving springs measured
    /// from their current position).
    pub strain: f64,
    /// Work done on the body since t = 0 by its own loads (permanent loads,
    /// moving edges) — not by the contacts.
    pub work: f64,
}

/// Why a body could not advance.
#[derive(Debug, thiserror::Error)]
#[error("body `{body}`: {message}")]
pub struct SolveError {
    pub body: String,
    pub message: String,
}

/// What the coupling needs from a continuum body (EFG or FE).
pub trait Continuum: Send {
    /// Name (for messages and outputs).
    fn name(&self) -> &str;
    /// The contact boundary: polylines through boundary points at their true
    /// current positions (ERRATA E7), refreshed by [`advance`](Self::advance).
    fn contact_boundary(&self) -> &[BoundaryChain];
    /// Velocity of the boundary material point `x` (reference coordinates)
    /// of chain `chain`: `Σ_J φ_J(x) U̇_J` (Eq. 41 per ERRATA E7).
    fn boundary_velocity(&self, chain: usize, x: Vec2) -> Vec2;
    /// Accumulate a point load `f` at material point `x` of chain `chain`
    /// for the next step: `F += Φᵀ(x) f` (Eqs. 43–46), with the same shape
    /// functions as [`boundary_velocity`](Self::boundary_velocity).
    fn add_point_load(&mut self, chain: usize, x: Vec2, f: Vec2);
    /// Displacement `Σ_J φ_J(x) u_J` of the boundary material point `x`.
    fn boundary_displacement(&self, chain: usize, x: Vec2) -> Vec2;
    /// First half of an implicit step (contact springs treated implicitly):
    /// solve the step under the accumulated loads, and report, for the
    /// material points `points[k] = (chain, x)`, the free displacement
    /// `free[k]` at `t + Δt` and the compliance `S` (2m × 2m, row-major,
    /// index `2k + a`): point forces `f` change the displacements at
    /// `t + Δt` by `S f`.
    fn begin_step(
        &mut self,
        points: &[(usize, Vec2)],
        free: &mut Vec<Vec2>,
        compliance: &mut Vec<f64>,
    ) -> Result<(), SolveError>;
    /// [`begin_step`](Self::begin_step) with the step's matrix stiffened by
    /// `stiffness` (implicit geometric stiffness of the contacts). Default:
    /// a body that cannot take it ignores it.
    fn begin_step_stiffened(
        &mut self,
        points: &[(usize, Vec2)],
        stiffness: &[ChainStiffness],
        free: &mut Vec<Vec2>,
        compliance: &mut Vec<f64>,
    ) -> Result<(), SolveError> {
        let _ = stiffness;
        self.begin_step(points, free, compliance)
    }
    /// Second half: add the point forces `forces[k]` at the points of
    /// [`begin_step`](Self::begin_step), accept the step, clear the loads
    /// and refresh the contact boundary.
    fn finish_step(&mut self, forces: &[Vec2]) -> Result<(), SolveError>;
    /// Advance one time step with the accumulated loads, clear them, and
    /// refresh the contact boundary.
    fn advance(&mut self) -> Result<(), SolveError> {
        self.begin_step(&[], &mut Vec::new(), &mut Vec::new())?;
        self.finish_step(&[])
    }
    /// Kinetic and strain energy of the present state.
    fn energies(&self) -> BodyEnergies;
    /// The concrete body (for outputs that need more than the trait).
    fn as_any(&self) -> &dyn std::any::Any;
}

/// A body on a rectangular node grid that the coupling can drive through
/// [`WithBoundary`]: EFG ([`EfgBody`](crate::efg::EfgBody)) or FE
/// ([`FemBody`](crate::fem::FemBody)). Its rows `φ_J(x)` interpolate
/// displacement and velocity and distribute point loads (E7).
pub trait ContactBody: Send + 'static {
    type Error: std::fmt::Display;
    fn name(&self) -> &str;
    /// Origin and size of the rectangle, node grid `[nx, ny]`.
    fn grid(&self) -> (Vec2, Vec2, [usize; 2]);
    /// The row `[(node, φ_J(x))]` at the material point `x`.
    fn row(&self, x: Vec2) -> Result<Row, Self::Error>;
    /// Nodal displacement, velocity, acceleration.
    fn state(&self) -> &State;
    /// `F += Φᵀ f` for the next step.
    fn add_point_load_row(&mut self, row: &[(u32, f64)], f: Vec2);
    /// Solve the step under the accumulated loads; the integrator holds the
    /// solution until [`commit`](Self::commit).
    fn predict(&mut self) -> Result<&mut Newmark, Self::Error>;
    /// The integrator between `predict` and `commit`.
    fn newmark_mut(&mut self) -> Option<&mut Newmark>;
    /// Accept the step, clear the point loads.
    fn commit(&mut self) -> Result<(), Self::Error>;
    fn energies(&self) -> BodyEnergies;
}

/// `F += Φᵀ f`: the point load `f` on the nodal force vector through a row.
pub fn add_row_load(force: &mut [f64], row: &[(u32, f64)], f: Vec2) {
    for &(j, phi) in row {
        force[2 * j as usize] += phi * f.x;
        force[2 * j as usize + 1] += phi * f.y;
    }
}

/// A body with its contact boundary: chains along its contact edges through
/// points whose rows are computed once, at their true displaced positions
/// (E7). The [`Continuum`] the coupling drives, for EFG and FE alike.
pub struct WithBoundary<B> {
    pub body: B,
    chains: Vec<BoundaryChain>,
    /// Per chain, per point: its row.
    rows: Vec<Vec<Row>>,
    /// Rows of the points of the current implicit step.
    point_rows: Vec<Row>,
    /// Scratch of [`Continuum::begin_step_stiffened`]: functionals on DOFs,
    /// their q × q matrix, `U` at the start of the step.
    stiff_v: Vec<Vec<(usize, f64)>>,
    stiff_c: Vec<f64>,
    stiff_u: Vec<f64>,
}

impl<B: ContactBody> WithBoundary<B> {
    /// Wrap `body` with contact chains along `edges` ([`contact_chains`]),
    /// `refine` points per node spacing (for FE: per element edge).
    pub fn new(body: B, edges: &[Edge], refine: usize) -> Result<Self, B::Error> {
        let (origin, size, grid) = body.grid();
        let mut chains = Vec::new();
        let mut rows = Vec::new();
        for pts in contact_chains(origin, size, grid, edges, refine.max(1)) {
            rows.push(pts.iter().map(|&x| body.row(x)).collect::<Result<_, _>>()?);
            chains.push(BoundaryChain::new(pts));
        }
        let mut c = WithBoundary {
            body,
            chains,
            rows,
            point_rows: Vec::new(),
            stiff_v: Vec::new(),
            stiff_c: Vec::new(),
            stiff_u: Vec::new(),
        };
        c.refresh();
        Ok(c)
    }

    /// Current chain positions `X + Σ φ_J(X) u_J` (true displacement, E7).
    pub fn refresh(&mut self) {
        let u = &self.body.state().u;
        for (chain, rows) in self.chains.iter_mut().zip(&self.rows) {
            for ((cur, x), row) in chain.current.iter_mut().zip(&chain.reference).zip(rows) {
                *cur = *x + interpolate(row, u);
            }
        }
    }

    /// The row at a boundary material point (empty if the body cannot give
    /// one, which a point of a chain segment never is).
    fn row(&self, x: Vec2) -> Row {
        self.body.row(x).unwrap_or_default()
    }

    fn solve_error(&self, e: B::Error) -> SolveError {
        SolveError {
            body: self.body.name().to_string(),
            message: e.to_string(),
        }
    }
}

impl<B: ContactBody> Continuum for WithBoundary<B> {
    fn name(&self) -> &str {
        self.body.name()
    }
    fn contact_boundary(&self) -> &[BoundaryChain] {
        &self.chains
    }
    /// Eq. (41) per ERRATA E7: `v_H = Σ_J φ_J(x_H) u̇_J`.
    fn boundary_velocity(&self, _chain: usize, x: Vec2) -> Vec2 {
        interpolate(&self.row(x), &self.body.state().v)
    }
    fn boundary_displacement(&self, _chain: usize, x: Vec2) -> Vec2 {
        interpolate(&self.row(x), &self.body.state().u)
    }
    /// Eq. (46) per ERRATA E7: `F += Φᵀ(x_H) f`.
    fn add_point_load(&mut self, _chain: usize, x: Vec2, f: Vec2) {
        let row = self.row(x);
        self.body.add_point_load_row(&row, f);
    }
    /// Eqs. (46) and (49): the points' rows `φ_J(x_H)` (E7) give both the
    /// free displacements and the compliance `Φ A⁻¹ Φᵀ`.
    fn begin_step(
        &mut self,
        points: &[(usize, Vec2)],
        free: &mut Vec<Vec2>,
        compliance: &mut Vec<f64>,
    ) -> Result<(), SolveError> {
        self.begin_step_stiffened(points, &[], free, compliance)
    }
    /// The chain points' rows turn each `ψ_k` into a functional on the
    /// nodal parameters, `Σ_(i, a) Σ_J φ_J(X_i) a · ΔU_J`.
    fn begin_step_stiffened(
        &mut self,
        points: &[(usize, Vec2)],
        stiffness: &[ChainStiffness],
        free: &mut Vec<Vec2>,
        compliance: &mut Vec<f64>,
    ) -> Result<(), SolveError> {
        let mut rows = std::mem::take(&mut self.point_rows);
        rows.clear();
        rows.extend(points.iter().map(|&(_, x)| self.row(x)));
        let q = 2 * stiffness.len();
        self.stiff_v.resize_with(q, Vec::new);
        self.stiff_c.clear();
        self.stiff_c.resize(q * q, 0.0);
        for (b, k) in stiffness.iter().enumerate() {
            for (a, psi) in k.psi.iter().enumerate() {
                let v = &mut self.stiff_v[2 * b + a];
                v.clear();
                for &(i, c) in psi {
                    for &(j, phi) in &self.rows[k.chain][i] {
                        v.push((2 * j as usize, phi * c.x));
                        v.push((2 * j as usize + 1, phi * c.y));
                    }
                }
                for (e, &c) in k.c[a].iter().enumerate() {
                    self.stiff_c[(2 * b + a) * q + 2 * b + e] = c;
                }
            }
        }
        self.stiff_u.clear();
        if q > 0 {
            self.stiff_u.extend_from_slice(&self.body.state().u);
        }
        let extra = (q > 0).then_some(StepStiffness {
            v: &self.stiff_v[..q],
            c: &self.stiff_c,
            u: &self.stiff_u,
        });
        let res = self
            .body
            .predict()
            .map(|nm| nm.point_compliance_stiffened(&rows, extra, free, compliance));
        self.point_rows = rows;
        res.map_err(|e| self.solve_error(e))
    }
    /// The forces join the solution through `A⁻¹Φᵀ`, and are booked as the
    /// step's point loads (an FE body's support reactions exclude them).
    fn finish_step(&mut self, forces: &[Vec2]) -> Result<(), SolveError> {
        if let Some(nm) = self.body.newmark_mut() {
            nm.apply_point_forces(forces);
        }
        for (row, f) in self.point_rows.iter().zip(forces) {
            self.body.add_point_load_row(row, *f);
        }
        self.body.commit().map_err(|e| self.solve_error(e))?;
        self.refresh();
        Ok(())
    }
    fn energies(&self) -> BodyEnergies {
        self.body.energies()
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacent_edges_join_around_the_corner_counter_clockwise() {
        let (o, s, g) = (Vec2::ZERO, Vec2::new(2.0, 1.0), [5, 3]);
        let ch = contact_chains(o, s, g, &[Edge::Top, Edge::Right], 1);
        assert_eq!(ch.len(), 1);
        // right edge bottom→top (3 points), then top right→left (5, corner shared)
        assert_eq!(ch[0].len(), 3 + 5 - 1);
        assert_eq!(ch[0][0], Vec2::new(2.0, 0.0));
        assert_eq!(ch[0][2], Vec2::new(2.0, 1.0));
        assert_eq!(ch[0][ch[0].len() - 1], Vec2::new(0.0, 1.0));
        // opposite edges stay separate; wrap-around left+bottom joins
        assert_eq!(
            contact_chains(o, s, g, &[Edge::Top, Edge::Bottom], 1).len(),
            2
        );
        let lb = contact_chains(o, s, g, &[Edge::Left, Edge::Bottom], 2);
        assert_eq!(lb.len(), 1);
        assert_eq!(lb[0][0], Vec2::new(0.0, 1.0));
        assert_eq!(lb[0].len(), 5 + 9 - 1);
        let all = contact_chains(
            o,
            s,
            g,
            &[Edge::Left, Edge::Bottom, Edge::Right, Edge::Top],
            1,
        );
        assert_eq!(all.len(), 1);
        assert_eq!(all[0].first(), all[0].last());
    }
}
