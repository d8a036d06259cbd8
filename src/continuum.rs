//! What the coupling needs from a continuum body: its current contact
//! boundary, the velocity of a boundary material point, point loads, and one
//! time step. Two implementations: the EFG body and (for comparison) the
//! bilinear FE body, so the coupling never knows which one it talks to.

use crate::geom::Vec2;

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
