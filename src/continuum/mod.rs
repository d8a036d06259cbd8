//! What the coupling needs from a continuum body: its current contact
//! boundary, the velocity of a boundary material point, point loads, and one
//! time step. Two implementations: the EFG body and (for comparison) the
//! bilinear FE body, so the coupling never knows which one it talks to.

pub mod body_params;
pub mod cantilever;
pub mod chain_compliance;
pub mod compliance;
pub mod conditions;
pub mod crack_tip;
pub mod drive;
pub mod griffith;
pub mod kirsch;
pub mod material;
pub mod newmark;
pub mod quadrature;
pub mod state;
pub mod table;
pub mod timoshenko;

pub use body_params::{
    BodyParams, CrackShape, Elastic, Fracture, MassKind, Plane, PolygonShape, Rectangle, Refine,
};
pub use conditions::{
    Edge, EdgeCondition, EdgeName, GriffithSpec, KirschSpec, LinearField, MotionField, PointLoad,
    Prescribed, TimoshenkoSpec, WilliamsSpec,
};
pub use drive::{Drive, DriveLaw, DrivePhase, DriveState, Measure, ServoSpec, Target};
pub use material::{Material, Sample};
pub use state::{BodyState, BoundaryState, CrackState, StateError};
pub use table::{Table, TimedLoad};

use crate::continuum::chain_compliance::ChainCompliance;
use crate::continuum::compliance::{BoundaryGreen, Compliance, PointRows};
use crate::continuum::newmark::{Newmark, State, pair_values};
use crate::geom::Vec2;
use rayon::prelude::*;

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

    /// The chain is a closed loop: its last point is its first (a body
    /// whose whole boundary is in contact).
    pub fn is_closed(&self) -> bool {
        let r = &self.reference;
        r.len() > 3 && r.first() == r.last()
    }

    /// Material point at parameter `s ∈ [0, 1]` of segment `seg`.
    pub fn material_point(&self, seg: usize, s: f64) -> Vec2 {
        let a = self.reference[seg];
        a + (self.reference[seg + 1] - a) * s
    }
}

/// Edges in counter-clockwise order around a rectangle (body on the left).
const CCW: [Edge; 4] = Edge::ALL;

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
/// body's Newmark step implicitly: the pair `(ψ_0, ψ_1)` is one more
/// unknown of the contact solve, with the linear law `g = −C ψ`.
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
    /// Elastic strain energy `½ Uᵀ K U` (without penalty springs).
    pub strain: f64,
    /// Energy of the penalty springs of prescribed edges (EFG, ERRATA E4),
    /// from their gap to the prescribed displacement (moving edges at their
    /// present position): `½ Σ_g (u(x_g) − ū_g)ᵀ W_g (u(x_g) − ū_g)`.
    /// Zero for FE bodies (prescribed DOFs eliminated exactly).
    pub penalty: f64,
    /// Work done on the body since t = 0 by its own loads (permanent loads,
    /// moving edges) — not by the contacts.
    pub work: f64,
    /// Energy the growth of its cracks took out of the body and its
    /// contacts since t = 0 (EFG: [`fracture_energy`](crate::efg::EfgBody::fracture_energy)).
    pub fracture: f64,
}

/// A disc–body contact holding a body while its cracks grow
/// ([`Continuum::grow`]): the disc is held in place, and the contact is a
/// normal spring `k_n` between it and the body's material point `point`
/// (the linearisation of the contact law about the present state, the
/// normal fixed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldContact {
    /// Material (reference) point of the body.
    pub point: Vec2,
    /// Force on the body at the present state.
    pub force: Vec2,
    /// Unit normal from the disc towards the body: the force grows by
    /// `k_n` per unit the body's point moves against it.
    pub normal: Vec2,
    /// Normal stiffness `k_n` (0: the force is held fixed).
    pub kn: f64,
}

/// Why a body could not advance.
#[derive(Debug, thiserror::Error)]
#[error("body `{body}`: {message}")]
pub struct SolveError {
    /// Name of the body.
    pub body: String,
    /// What went wrong (e.g. the factorisation failed).
    pub message: String,
}

/// A body's collective response to a layer of contacts along its whole
/// contact boundary ([`Continuum::collective_gain`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Collective {
    /// The layer's gain: the largest eigenvalue of `K^½ S K^½`.
    pub gain: f64,
    /// Angular frequency of the body's response to the layer's push
    /// (Rayleigh's quotient, rad/s; 0 if unknown).
    pub omega: f64,
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
    /// solve the step under the accumulated loads, and report the values at
    /// `t` (`base`) and the free values at `t + Δt` (`free`) of the step's
    /// unknowns: first the displacements of the material points
    /// `points[k] = (chain, x)`, then the functional pairs of the
    /// `stiffness` terms (their increments are measured from `base`);
    /// [`compliance`](Self::compliance) then gives `S`: generalised forces
    /// `f` on the unknowns change their values at `t + Δt` by `S f`.
    fn begin_step(
        &mut self,
        points: &[(usize, Vec2)],
        stiffness: &[ChainStiffness],
        base: &mut Vec<Vec2>,
        free: &mut Vec<Vec2>,
    ) -> Result<(), SolveError>;
    /// Solve the next step under the present loads ahead of
    /// [`begin_step`](Self::begin_step), which then takes this prediction
    /// instead of solving again (the same numbers): the exact step
    /// predicts while the discs take their step on another thread. The
    /// loads must not change in between.
    fn predict_step(&mut self) -> Result<(), SolveError> {
        Ok(())
    }
    /// The compliance `S = Φ A⁻¹ Φᵀ` of the unknowns of
    /// [`begin_step`](Self::begin_step).
    fn compliance(&mut self) -> Compliance<'_>;
    /// Second half: add the generalised forces `forces[k]` on the unknowns
    /// of [`begin_step`](Self::begin_step), accept the step, clear the
    /// loads and refresh the contact boundary.
    fn finish_step(&mut self, forces: &[Vec2]) -> Result<(), SolveError>;
    /// Advance one time step with the accumulated loads, clear them, and
    /// refresh the contact boundary.
    fn advance(&mut self) -> Result<(), SolveError> {
        self.begin_step(&[], &[], &mut Vec::new(), &mut Vec::new())?;
        self.finish_step(&[])
    }
    /// Sub-cycled scheme, at the start of a body step of length `h`:
    /// predict the step under the last body step's contact loads (held)
    /// and let the contact boundary move on the straight path from its
    /// present position to the predicted one ([`set_path`](Self::set_path)).
    /// The prediction stays pending until [`end_path`](Self::end_path).
    fn begin_path(&mut self, _h: f64) -> Result<(), SolveError> {
        Ok(())
    }
    /// Sub-cycled scheme: the energy the scheme created since t = 0 (what
    /// the body received from its end loads, `Σ ½(Fₖ + Fₖ₊₁)·ΔU` at the
    /// chain points, less what the discs did on the boundary: `Σ F̄ₖ·ΔŶ` on
    /// the predicted path, or per DEM step the mean of its two loads on the
    /// chain points' displacement in the compliant scheme), and the work
    /// the discs exchanged with the body (the sum of the magnitudes of
    /// their work, chain point by chain point). With γ = ½ (any β) the
    /// body's load work in Newmark's energy balance is exactly
    /// `½(Fₖ + Fₖ₊₁)·ΔU` (the balance of `½U̇ᵀMU̇ + ½UᵀKU + (β − ¼)Δt²½ÜᵀMÜ`),
    /// so what is created is energy the coupled system gained; with γ > ½
    /// the balance has a numerical dissipation term besides, and the same
    /// difference measures the interface's mismatch alone (the discs' work
    /// against the trapezoidal work of the loads the body took).
    fn path_energy(&self) -> (f64, f64) {
        (0.0, 0.0)
    }
    /// Sub-cycled scheme: how far any chain point moves on the present
    /// path (0 when none is under way).
    fn path_extent(&self) -> f64 {
        0.0
    }
    /// Compliant scheme: how far any chain point is from its path (its
    /// response to the contacts within the present body step).
    fn path_correction(&self) -> f64 {
        0.0
    }
    /// Sub-cycled scheme: put the contact boundary at the fraction `s ∈
    /// [0, 1)` of the present body step's path.
    fn set_path(&mut self, _s: f64) {}
    /// Sub-cycled scheme: the velocity of the boundary point at parameter
    /// `s` of segment `seg` of chain `chain` on the path.
    fn path_velocity(&self, chain: usize, seg: usize, s: f64) -> Vec2 {
        let x = self.contact_boundary()[chain].material_point(seg, s);
        self.boundary_velocity(chain, x)
    }
    /// Sub-cycled scheme: a force `f` on the boundary point at parameter
    /// `s` of segment `seg`, for the end of the present body step.
    fn add_path_load(&mut self, chain: usize, seg: usize, s: f64, f: Vec2) {
        let x = self.contact_boundary()[chain].material_point(seg, s);
        self.add_point_load(chain, x, f);
    }
    /// Sub-cycled scheme: take the body step with the loads of
    /// [`add_path_load`](Self::add_path_load), which are then held for the
    /// next path.
    fn end_path(&mut self) -> Result<(), SolveError> {
        self.advance()
    }
    /// Compliant sub-cycled scheme (switched on once, at the build): over
    /// a body step the boundary is the predicted path plus its response,
    /// through the body step's compliance, to the present contact loads
    /// less the held ones ([`compliant_system`](Self::compliant_system),
    /// [`compliant_loads`](Self::compliant_loads)); the step ends with the
    /// last DEM step's loads. A body that cannot do it says so.
    fn set_compliant(&mut self) -> Result<(), SolveError> {
        Err(SolveError {
            body: self.name().to_string(),
            message: "this body cannot take the compliant sub-cycled scheme".to_string(),
        })
    }
    /// After a body step: grow its cracks if due, and rebuild the contact
    /// chains along the longer faces. Whether it grew (a body without
    /// crack growth never does). `held`: the disc contacts of the present
    /// state, which hold the body while its new crack pieces open.
    fn grow(&mut self, held: &[HeldContact]) -> Result<bool, SolveError> {
        let _ = held;
        Ok(false)
    }
    /// Whether [`grow`](Self::grow) would look at the tips now (a body
    /// without crack growth: never).
    fn growth_due(&self) -> bool {
        false
    }
    /// Whether the body's cracks can grow at all ([`grow`](Self::grow)).
    fn grows(&self) -> bool {
        false
    }
    /// Add `e` to the energy its crack growth took
    /// ([`BodyEnergies::fracture`]); a body without cracks ignores it.
    fn book_fracture(&mut self, e: f64) {
        let _ = e;
    }
    /// Compliant scheme, at the fraction `s` of the body step: for the
    /// contact points `pts[k] = (chain, segment, σ)` (parameter σ on the
    /// segment), their positions with the held loads only (`free`) and the
    /// compliance among them (`out`, 2m × 2m row-major): the boundary at
    /// the points is `free + S g` under forces `g` on them.
    fn compliant_system(
        &mut self,
        _s: f64,
        _pts: &[(usize, usize, f64)],
        _free: &mut Vec<Vec2>,
        _out: &mut Vec<f64>,
    ) -> Result<(), SolveError> {
        self.set_compliant()
    }
    /// Compliant scheme: the forces `g[k]` on the contact points `pts[k]`
    /// are the body's present loads (shared by the ends of the segment);
    /// the boundary at the fraction `s` follows them. `ds` is the DEM
    /// step's fraction of the body step (for the discs' work).
    fn compliant_loads(
        &mut self,
        _s: f64,
        _ds: f64,
        _pts: &[(usize, usize, f64)],
        _g: &[Vec2],
    ) -> Result<(), SolveError> {
        self.set_compliant()
    }
    /// Take body steps of `h` (before the first step): the Newmark matrix
    /// factored again for it. A body that cannot says so.
    fn set_step(&mut self, _h: f64) -> Result<(), SolveError> {
        self.set_compliant()
    }
    /// Go on, from the present state, with steps of `dt`, `scale.0` of
    /// them per `scale.1` present steps (the Newmark matrix factored again,
    /// the state and the time kept, the step count scaled; no sub-cycled
    /// scheme after it until it is set again): a sub-cycled body falling
    /// back to shorter body steps. A body that cannot says so.
    fn retime(&mut self, _dt: f64, _scale: (usize, usize)) -> Result<(), SolveError> {
        self.set_compliant()
    }
    /// The gain with which the contacts, acting together, feed back on
    /// themselves within one body step: the largest eigenvalue of
    /// `K^½ S K^½`, `S` the body step's compliance among all the chain
    /// points and `K` a contact layer along the whole contact boundary,
    /// one contact of stiffness `k_n` normal and `k_s` tangential per
    /// `spacing` of boundary (the densest row of the smallest discs: each
    /// chain point carries the contacts of its share of the boundary). A
    /// single contact's gain `k_n φᵀA⁻¹φ` is at most this. 0 if unknown.
    /// With it, the angular frequency of the body's response to that
    /// collective push, `ω² = uᵀK̄u / uᵀMu` (Rayleigh's quotient of the
    /// displacement `u = A⁻¹ φ K^½ x`): for a body step long against the
    /// body's own period `u` is the static response and `ω` the frequency
    /// of the mode the contacts drive together; shorter, `u` holds more
    /// inertia and `ω` comes out higher. 0 if unknown.
    fn collective_gain(
        &mut self,
        _kn: f64,
        _ks: f64,
        _spacing: f64,
    ) -> Result<Collective, SolveError> {
        Ok(Collective::default())
    }
    /// Stored entries of the factor of the body step's Newmark matrix (the
    /// cost of a body solve; 0 if not dynamic).
    fn factor_nnz(&mut self) -> usize {
        0
    }
    /// Kinetic and strain energy of the present state.
    fn energies(&self) -> BodyEnergies;
    /// The total force of the discs on the body at the present state, set
    /// by the coupling before each step (servo drives measure it).
    fn set_contact_force(&mut self, _f: Vec2) {}
    /// DOFs and bytes of the boundary Green matrix, once built
    /// ([`crate::continuum::compliance`]); `(0, 0)` if none.
    fn green_size(&self) -> (usize, usize) {
        (0, 0)
    }
    /// The concrete body (for outputs that need more than the trait).
    fn as_any(&self) -> &dyn std::any::Any;
    /// Everything that changes while the body steps (checkpoint/restart,
    /// [`state`]); call between steps.
    fn save_state(&self) -> BodyState;
    /// Restore a state saved by [`save_state`](Self::save_state) from a
    /// body built from the same parameters; the body then steps bitwise as
    /// the one it was saved from. A state of another body (name, DOFs) is
    /// refused.
    fn restore_state(&mut self, s: &BodyState) -> Result<(), StateError>;
}

/// A body on a rectangular node grid that the coupling can drive through
/// [`WithBoundary`]: EFG ([`EfgBody`](crate::efg::EfgBody)) or FE
/// ([`FemBody`](crate::fem::FemBody)). Its rows `φ_J(x)` interpolate
/// displacement and velocity and distribute point loads (E7).
pub trait ContactBody: Send + Sync + 'static {
    /// The body's own error (building a row, solving a step).
    type Error: std::fmt::Display;
    /// Name (for messages and outputs).
    fn name(&self) -> &str;
    /// Origin and size of the rectangle, node grid `[nx, ny]`.
    fn grid(&self) -> (Vec2, Vec2, [usize; 2]);
    /// Reference points of the contact chains along `edges`, `refine`
    /// points per node spacing ([`contact_chains`] on the rectangle); a
    /// polygon body gives one closed chain per loop instead.
    fn chains(&self, edges: &[Edge], refine: usize) -> Vec<Vec<Vec2>> {
        let (origin, size, grid) = self.grid();
        contact_chains(origin, size, grid, edges, refine)
    }
    /// [`chains`](Self::chains), or for a polygon body those along its
    /// edges named `names` (all loops if `None`); unknown names are an
    /// error.
    fn named_chains(
        &self,
        _names: Option<&[EdgeName]>,
        edges: &[Edge],
        refine: usize,
    ) -> Result<Vec<Vec<Vec2>>, Self::Error> {
        Ok(self.chains(edges, refine))
    }
    /// The row `[(node, φ_J(x))]` at the material point `x`.
    fn row(&self, x: Vec2) -> Result<Row, Self::Error>;
    /// Start (or, before the first step, start again) the time stepping
    /// with the step `dt`: the Newmark matrix factored for it.
    fn start_dynamic(&mut self, dt: f64) -> Result<(), Self::Error>;
    /// Go on with steps of `dt`, `scale.0` of them per `scale.1` present
    /// steps: the Newmark matrix factored for it, the state kept
    /// ([`Continuum::retime`], [`rescaled_step`]).
    fn retime(&mut self, dt: f64, scale: (usize, usize)) -> Result<(), Self::Error>;
    /// Nodal displacement, velocity, acceleration.
    fn state(&self) -> &State;
    /// `F += Φᵀ f` for the next step.
    fn add_point_load_row(&mut self, row: &[(u32, f64)], f: Vec2);
    /// Solve the step under the accumulated loads; the integrator holds the
    /// solution until [`commit`](Self::commit).
    fn predict(&mut self) -> Result<&mut Newmark, Self::Error>;
    /// The integrator between `predict` and `commit`.
    fn newmark_mut(&mut self) -> Option<&mut Newmark>;
    /// After [`predict`](Self::predict): `U₊ += A⁻¹ Φᵀ f` for the
    /// generalised forces `f[k]` on the functional pairs `rows[2k]`,
    /// `rows[2k + 1]` ([`Newmark::point_compliance`]), one solve (a body may
    /// fold pending corrections of its own into the same solve).
    fn add_point_forces(
        &mut self,
        rows: &[Vec<(usize, f64)>],
        f: &[Vec2],
    ) -> Result<(), Self::Error> {
        if let Some(nm) = self.newmark_mut() {
            nm.add_point_forces(rows, f, &[]);
        }
        Ok(())
    }
    /// Whether the step's solution waits for a solve of the body's own
    /// that [`add_point_forces`](Self::add_point_forces) folds in (an EFG
    /// body's refinement on moving edges): then the contact forces'
    /// response is solved for, not summed from kept columns.
    fn solve_pending(&self) -> bool {
        false
    }
    /// `F[i] += c · g` over `row = [(DOF, c)]` for the next step (a
    /// generalised force booked as a load).
    fn add_dof_loads(&mut self, row: &[(usize, f64)], g: f64);
    /// The total force of the discs on the body at the present state, set
    /// before each step (what a servo drive with `measure = "contacts"`
    /// measures); bodies without such a drive ignore it.
    fn set_contact_force(&mut self, _f: Vec2) {}
    /// Accept the step, clear the point loads.
    fn commit(&mut self) -> Result<(), Self::Error>;
    /// Grow the body's cracks if due (after a committed step); whether it
    /// grew. Its contact chains ([`chains`](Self::chains)) then change.
    /// `held` as in [`Continuum::grow`].
    fn grow(&mut self, held: &[HeldContact]) -> Result<bool, Self::Error> {
        let _ = held;
        Ok(false)
    }
    /// As [`Continuum::growth_due`].
    fn growth_due(&self) -> bool {
        false
    }
    /// As [`Continuum::grows`].
    fn grows(&self) -> bool {
        false
    }
    /// As [`Continuum::book_fracture`].
    fn book_fracture(&mut self, e: f64) {
        let _ = e;
    }
    /// Kinetic, strain and penalty energy and load work of the present
    /// state.
    fn energies(&self) -> BodyEnergies;
    /// The body's evolving state ([`state`]), without the boundary's.
    fn save_state(&self) -> BodyState;
    /// Restore a state of [`save_state`](Self::save_state) (sizes checked).
    fn restore_state(&mut self, s: &BodyState) -> Result<(), StateError>;
}

/// `F += Φᵀ f` for the loads on a body's chain points (`loads` in chain
/// order, point by point; zeros skipped), through the points' `rows`.
fn add_chain_loads<'a, B: ContactBody>(
    body: &mut B,
    rows: &[Vec<Row>],
    loads: impl IntoIterator<Item = &'a Vec2>,
) {
    for (row, f) in rows.iter().flatten().zip(loads) {
        if *f != Vec2::ZERO {
            body.add_point_load_row(row, *f);
        }
    }
}

/// The nonzero entries of a per-chain, per-point field, chain points
/// numbered chain after chain.
fn nonzero(v: &[Vec<Vec2>]) -> impl Iterator<Item = (usize, Vec2)> + '_ {
    v.iter()
        .flatten()
        .copied()
        .enumerate()
        .filter(|(_, f)| *f != Vec2::ZERO)
}

/// Position of point `i` of chain `c` at the fraction `s` of the path.
fn path_at(p: &Path, c: usize, i: usize, s: f64) -> Vec2 {
    let a = p.start[c][i];
    a + (p.end[c][i] - a) * s
}

/// `F += Φᵀ f`: the point load `f` on the nodal force vector through a row.
pub fn add_row_load(force: &mut [f64], row: &[(u32, f64)], f: Vec2) {
    for &(j, phi) in row {
        force[2 * j as usize] += phi * f.x;
        force[2 * j as usize + 1] += phi * f.y;
    }
}

/// `F[i] += c g` over a functional `row = [(i, c)]`: a generalised force
/// `g` on it booked as a load.
pub fn add_dof_load(force: &mut [f64], row: &[(usize, f64)], g: f64) {
    for &(i, c) in row {
        force[i] += c * g;
    }
}

/// How a body computes the compliance of the implicit contact step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ComplianceMode {
    /// Through the boundary Green matrix `G = (A⁻¹)_BB`, built once
    /// ([`crate::continuum::compliance`]): no solve per contact.
    #[default]
    Boundary,
    /// `A⁻¹Φᵀ` by 2 solves per contact and step (the reference).
    Direct,
}

/// Largest boundary Green matrix a body keeps (bytes); a body whose
/// boundary DOFs need more uses [`ComplianceMode::Direct`].
pub const MAX_GREEN_BYTES: usize = 2 << 30;

/// A body with its contact boundary: chains along its contact edges through
/// points whose rows are computed once, at their true displaced positions
/// (E7). The [`Continuum`] the coupling drives, for EFG and FE alike.
pub struct WithBoundary<B> {
    /// The wrapped EFG or FE body.
    pub body: B,
    chains: Vec<BoundaryChain>,
    /// Per chain, per point: its row.
    rows: Vec<Vec<Row>>,
    /// Rows of the points of the current implicit step.
    point_rows: Vec<Row>,
    /// The step is predicted ([`Continuum::predict_step`]).
    predicted: bool,
    /// The step's functionals: per point its `x` and `y` rows, then per
    /// stiffness term its two functionals (`[(DOF, coefficient)]`).
    functionals: Vec<Vec<(usize, f64)>>,
    /// How the compliance `S` of the implicit step is computed.
    pub mode: ComplianceMode,
    /// `G`, built at the first implicit step with contacts.
    green: Option<BoundaryGreen>,
    /// The rows of the step's points on `G`.
    mapped: PointRows,
    /// `S` of the step ([`ComplianceMode::Direct`]).
    dense: Vec<f64>,
    /// Sub-cycled scheme ([`Path`]).
    path: Path,
    /// The body's state before the pending prediction of a path (what a
    /// save in the middle of a path holds: a restore predicts again).
    pre: Option<BodyState>,
    /// The contact force last set ([`Continuum::set_contact_force`]).
    contact_force: Vec2,
    /// Per chain point, its `x` and `y` functionals (the path's loads).
    point_fs: Vec<Vec<(usize, f64)>>,
    /// Per chain, the number of its first point in the chain points
    /// numbered chain after chain.
    offsets: Vec<usize>,
    /// Compliant scheme: the columns of the body step's compliance among
    /// the chain points computed so far.
    chain_s: ChainCompliance,
    /// Compliant scheme, per chain point: the response to the held loads,
    /// once a contact point's segment needs it in the body step (`None`
    /// until then: most chain points are never near a contact).
    held_resp: Vec<Option<Vec2>>,
    /// Compliant scheme: the held loads `(chain point, load)` of the body
    /// step.
    held_loads: Vec<(usize, Vec2)>,
    /// The edge names, edges and points per spacing the chains were made
    /// of ([`named`](Self::named)); `None` for chains given as points.
    source: Option<ChainSource>,
}

/// How a body's contact chains were made ([`WithBoundary::named`]).
#[derive(Debug, Clone)]
struct ChainSource {
    names: Option<Vec<EdgeName>>,
    edges: Vec<Edge>,
    refine: usize,
}

impl ChainSource {
    fn points<B: ContactBody>(&self, body: &B) -> Result<Vec<Vec<Vec2>>, B::Error> {
        body.named_chains(self.names.as_deref(), &self.edges, self.refine)
    }
}

/// The sub-cycled scheme's boundary path over one body step: the chain
/// points move on straight lines from their positions at the start of the
/// step to those of the step predicted under the last step's contact
/// loads; the discs' forces go to the chain points (the shares of a
/// segment's ends, the loads work-conjugate to that straight-segment
/// geometry) and are averaged over the DEM steps.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Path {
    /// Per chain, per point: position at the start of the body step.
    pub start: Vec<Vec<Vec2>>,
    /// Per chain, per point: predicted position at its end (empty: no
    /// path under way).
    pub end: Vec<Vec<Vec2>>,
    /// Length of the body step.
    pub h: f64,
    /// Per chain, per point: loads of the last body step (held for the
    /// prediction of the next).
    pub held: Vec<Vec<Vec2>>,
    /// Per chain, per point: loads of the present body step so far.
    pub acc: Vec<Vec<Vec2>>,
    /// The discs' total force on the body when the path was predicted
    /// (what a servo drive measured then; a restore predicts again).
    pub measured: Vec2,
    /// Per chain, per point: the end load of the last body step.
    pub last_end: Vec<Vec<Vec2>>,
    /// Energy the scheme created so far ([`Continuum::path_energy`]).
    pub created: f64,
    /// Work exchanged with the discs through the path so far.
    pub exchanged: f64,
    /// The compliant sub-cycled scheme ([`Continuum::set_compliant`]): the
    /// boundary responds to the loads within the body step, and `acc`
    /// holds the last DEM step's loads, not their sum.
    pub compliant: bool,
    /// Compliant scheme: the discs' work on the boundary in the present
    /// body step so far (per DEM step, its mean load times the chain
    /// points' displacement).
    pub done: f64,
    /// Compliant scheme: the sum of the magnitudes of that work, chain
    /// point by chain point and DEM step by DEM step.
    pub swept: f64,
    /// Compliant scheme, per chain, per point: the boundary's response to
    /// the present loads less the held ones, as last updated (the points
    /// near the contacts every DEM step, all of them zero at the start of
    /// a body step).
    pub corr: Vec<Vec<Vec2>>,
}

impl<B: ContactBody> WithBoundary<B> {
    /// Wrap `body` with contact chains along `edges` ([`contact_chains`]),
    /// `refine` points per node spacing (for FE: per element edge).
    pub fn new(body: B, edges: &[Edge], refine: usize) -> Result<Self, B::Error> {
        Self::named(body, None, edges, refine)
    }

    /// Wrap `body` with the chains of [`ContactBody::named_chains`]; they
    /// are made again the same way when the body's cracks grow.
    pub fn named(
        body: B,
        names: Option<&[EdgeName]>,
        edges: &[Edge],
        refine: usize,
    ) -> Result<Self, B::Error> {
        let source = ChainSource {
            names: names.map(<[EdgeName]>::to_vec),
            edges: edges.to_vec(),
            refine: refine.max(1),
        };
        let chains = source.points(&body)?;
        let mut c = Self::with_chains(body, chains)?;
        c.source = Some(source);
        Ok(c)
    }

    /// Wrap `body` with the given contact chains (reference points, body
    /// on the left), e.g. a polygon body's named edges.
    pub fn with_chains(body: B, points: Vec<Vec<Vec2>>) -> Result<Self, B::Error> {
        let mut c = WithBoundary {
            body,
            chains: Vec::new(),
            rows: Vec::new(),
            point_rows: Vec::new(),
            predicted: false,
            functionals: Vec::new(),
            mode: ComplianceMode::default(),
            green: None,
            mapped: PointRows::default(),
            dense: Vec::new(),
            path: Path::default(),
            pre: None,
            contact_force: Vec2::ZERO,
            point_fs: Vec::new(),
            offsets: Vec::new(),
            chain_s: ChainCompliance::default(),
            held_resp: Vec::new(),
            held_loads: Vec::new(),
            source: None,
        };
        c.set_chains(points)?;
        Ok(c)
    }

    /// Make the contact chains of `points` (reference points, body on the
    /// left): their rows, and the boundary's compliance and path at zero.
    fn set_chains(&mut self, points: Vec<Vec<Vec2>>) -> Result<(), B::Error> {
        let c = self;
        c.rows = points
            .iter()
            .map(|pts| pts.iter().map(|&x| c.body.row(x)).collect())
            .collect::<Result<_, _>>()?;
        c.chains = points.into_iter().map(BoundaryChain::new).collect();
        c.green = None;
        c.mapped = PointRows::default();
        c.dense.clear();
        c.offsets.clear();
        c.pre = None;
        let mut total = 0;
        for ch in &c.chains {
            c.offsets.push(total);
            total += ch.reference.len();
        }
        c.chain_s = ChainCompliance::new(total);
        c.held_resp = vec![None; total];
        let zeros: Vec<Vec<Vec2>> = c
            .chains
            .iter()
            .map(|ch| vec![Vec2::ZERO; ch.reference.len()])
            .collect();
        c.path.held.clone_from(&zeros);
        c.path.last_end.clone_from(&zeros);
        c.path.corr.clone_from(&zeros);
        c.path.acc = zeros;
        c.refresh();
        Ok(())
    }

    /// The chains made again from the body (after its cracks grew); `false`
    /// for chains given as points, or when they are the same.
    fn remake_chains(&mut self) -> Result<bool, B::Error> {
        let Some(source) = &self.source else {
            return Ok(false);
        };
        let points = source.points(&self.body)?;
        let same = points.len() == self.chains.len()
            && points
                .iter()
                .zip(&self.chains)
                .all(|(p, c)| *p == c.reference);
        if !same {
            self.set_chains(points)?;
        }
        Ok(!same)
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

    /// The body step with the loads changed by `delta` at the chain
    /// points (point forces and chain loads), committed; the boundary and
    /// its prediction refreshed.
    fn take_step(&mut self, delta: &[Vec2]) -> Result<(), SolveError> {
        if !self.add_kept_response(delta) {
            self.body
                .add_point_forces(&self.point_fs, delta)
                .map_err(|e| self.solve_error(e))?;
        }
        add_chain_loads(&mut self.body, &self.rows, delta);
        self.body.commit().map_err(|e| self.solve_error(e))?;
        self.refresh();
        self.pre = None;
        Ok(())
    }

    /// The response to the loads `delta` on the chain points added to the
    /// pending solution from the kept columns `A⁻¹ φ_b`
    /// ([`ChainCompliance::add_response`]) instead of a solve, when the
    /// body has no solve of its own pending, every loaded point's column is
    /// kept, and their sum costs less than the solve (`2k` columns of `n`
    /// entries against the factor's entries); whether it was.
    fn add_kept_response(&mut self, delta: &[Vec2]) -> bool {
        if self.body.solve_pending() {
            return false;
        }
        let Some(nm) = self.body.newmark_mut() else {
            return false;
        };
        let loads: Vec<(usize, Vec2)> = (delta.iter().copied().enumerate())
            .filter(|(_, f)| *f != Vec2::ZERO)
            .collect();
        loads.len() * nm.n() <= nm.factor_nnz()
            && self.chain_s.add_response(&loads, nm.solution_mut())
    }

    /// The body's step under its present loads (pending in the integrator).
    fn solve_free_step(&mut self) -> Result<(), SolveError> {
        let r = self.body.predict().map(|_| ());
        r.map_err(|e| self.solve_error(e))
    }

    fn solve_error(&self, e: impl std::fmt::Display) -> SolveError {
        SolveError {
            body: self.body.name().to_string(),
            message: e.to_string(),
        }
    }

    /// The nodes any contact point of the chains can load: those of the
    /// rows at the chain points and at three points inside every segment
    /// (a support that reaches a segment reaches one of them; a node missed
    /// here is added when a contact first needs it).
    fn boundary_nodes(&self) -> Vec<u32> {
        let mut nodes: Vec<u32> = self.rows.iter().flatten().flatten().map(|e| e.0).collect();
        for chain in &self.chains {
            for s in 0..chain.segments() {
                for t in [0.25, 0.5, 0.75] {
                    nodes.extend(self.row(chain.material_point(s, t)).iter().map(|e| e.0));
                }
            }
        }
        nodes.sort_unstable();
        nodes.dedup();
        nodes
    }

    /// Predict the body step under the held path loads (the solution stays
    /// pending in the integrator) and set the path's end positions.
    fn predict_path(&mut self) -> Result<(), SolveError> {
        add_chain_loads(&mut self.body, &self.rows, self.path.held.iter().flatten());
        let (chains, rows, path) = (&self.chains, &self.rows, &mut self.path);
        path.end.resize_with(chains.len(), Vec::new);
        let predicted = self.body.predict().map(|nm| {
            let u = nm.solution();
            for ((end, chain), rows) in path.end.iter_mut().zip(chains).zip(rows) {
                end.clear();
                end.extend(
                    chain
                        .reference
                        .iter()
                        .zip(rows)
                        .map(|(x, row)| *x + interpolate(row, u)),
                );
            }
        });
        predicted.map_err(|e| self.solve_error(e))
    }

    /// Compliant scheme: the compliance columns of the chain points `pts`
    /// (numbered chain after chain) that are not known yet.
    fn ensure_columns(&mut self, pts: &[usize]) -> Result<(), SolveError> {
        if pts.iter().all(|&b| self.chain_s.has(b)) {
            return Ok(());
        }
        let body = self.body.name().to_string();
        let rows: Vec<&Row> = self.rows.iter().flatten().collect();
        let Some(nm) = self.body.newmark_mut() else {
            return Err(SolveError {
                body,
                message: "the compliant sub-cycled scheme needs a dynamic body".to_string(),
            });
        };
        self.chain_s
            .ensure(pts, &rows, nm.imposed(), nm.factor())
            .map_err(|e| SolveError {
                body,
                message: e.to_string(),
            })
    }

    /// Compliant scheme: the held loads of the body step, their columns
    /// known; their response at a chain point is formed when a contact
    /// first needs it ([`compliant_system`](Continuum::compliant_system)).
    fn held_response(&mut self) -> Result<(), SolveError> {
        self.held_loads = nonzero(&self.path.held).collect();
        let pts: Vec<usize> = self.held_loads.iter().map(|h| h.0).collect();
        self.ensure_columns(&pts)?;
        self.held_resp.iter_mut().for_each(|r| *r = None);
        Ok(())
    }

    /// Chain and point of the chain point numbered `a`.
    fn locate(&self, a: usize) -> (usize, usize) {
        let c = self.offsets.partition_point(|&o| o <= a) - 1;
        (c, a - self.offsets[c])
    }

    /// The chain points' `x` and `y` functionals, built at their first use.
    fn ensure_point_fs(&mut self) {
        if self.point_fs.is_empty() {
            self.point_fs = self
                .rows
                .iter()
                .flatten()
                .flat_map(|row| {
                    (0..2).map(move |a| {
                        row.iter()
                            .map(|&(j, phi)| (2 * j as usize + a, phi))
                            .collect()
                    })
                })
                .collect();
        }
    }

    /// Compliant scheme, end of a body step: the body takes the last DEM
    /// step's loads (their difference from the held ones joins the pending
    /// prediction, one solve), which are held for the next step; the
    /// energy account compares the body's trapezoidal load work with the
    /// discs' work on the boundary.
    fn end_compliant(&mut self) -> Result<(), SolveError> {
        self.ensure_point_fs();
        let p = &self.path;
        let delta: Vec<Vec2> = p
            .acc
            .iter()
            .flatten()
            .zip(p.held.iter().flatten())
            .map(|(f, h)| *f - *h)
            .collect();
        self.take_step(&delta)?;
        let p = &mut self.path;
        let current = self.chains.iter().flat_map(|c| &c.current);
        let received: f64 = p
            .acc
            .iter()
            .flatten()
            .zip(p.last_end.iter().flatten())
            .zip(p.start.iter().flatten().zip(current))
            .map(|((f1, f0), (y0, y1))| (*f0 + *f1).dot(*y1 - *y0) * 0.5)
            .sum();
        p.created += received - p.done;
        p.exchanged += p.swept;
        (p.done, p.swept) = (0.0, 0.0);
        p.last_end.clone_from(&p.acc);
        p.held.clone_from(&p.acc);
        p.corr.iter_mut().flatten().for_each(|c| *c = Vec2::ZERO);
        p.end.clear();
        Ok(())
    }

    /// Build `G` (first call) and extend it to the nodes of the step's rows
    /// if a contact reaches one it does not hold yet.
    fn ensure_green(&mut self) -> Result<(), SolveError> {
        let seed = if self.green.is_none() {
            let nodes = self.boundary_nodes();
            let nb = 2 * nodes.len();
            if nb * nb * 8 > MAX_GREEN_BYTES {
                self.mode = ComplianceMode::Direct;
                return Ok(());
            }
            Some(nodes)
        } else {
            None
        };
        let covered = |g: &BoundaryGreen, rows: &[Vec<(usize, f64)>]| {
            rows.iter()
                .all(|r| g.covers(r.iter().map(|e| (e.0 / 2) as u32)))
        };
        let name = self.body.name().to_string();
        let err = |e: crate::sparse::SparseError| SolveError {
            body: name.clone(),
            message: e.to_string(),
        };
        let Some(nm) = self.body.newmark_mut() else {
            return Ok(());
        };
        let green = self
            .green
            .get_or_insert_with(|| BoundaryGreen::new(nm.n(), nm.imposed().to_vec()));
        if let Some(nodes) = seed {
            green.extend(nodes, nm.factor()).map_err(err)?;
        }
        if !covered(green, &self.functionals) {
            let extra: Vec<u32> = self
                .functionals
                .iter()
                .flatten()
                .map(|e| (e.0 / 2) as u32)
                .collect();
            green.extend(extra, nm.factor()).map_err(err)?;
        }
        Ok(())
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
    /// free displacements and the compliance `Φ A⁻¹ Φᵀ`; a stiffness term's
    /// functionals go through the rows of its chain points.
    fn begin_step(
        &mut self,
        points: &[(usize, Vec2)],
        stiffness: &[ChainStiffness],
        base: &mut Vec<Vec2>,
        free: &mut Vec<Vec2>,
    ) -> Result<(), SolveError> {
        let mut rows = std::mem::take(&mut self.point_rows);
        // one shape-function evaluation per contact, in parallel (each row
        // on its own: the same for any number of threads)
        points
            .par_iter()
            .with_min_len(64)
            .map(|&(_, x)| self.row(x))
            .collect_into_vec(&mut rows);
        self.point_rows = rows;
        let mut fs = std::mem::take(&mut self.functionals);
        fs.resize_with(2 * (points.len() + stiffness.len()), Vec::new);
        for (k, row) in self.point_rows.iter().enumerate() {
            for a in 0..2 {
                let f = &mut fs[2 * k + a];
                f.clear();
                f.extend(row.iter().map(|&(j, phi)| (2 * j as usize + a, phi)));
            }
        }
        let off = 2 * points.len();
        for (b, k) in stiffness.iter().enumerate() {
            for (a, psi) in k.psi.iter().enumerate() {
                let f = &mut fs[off + 2 * b + a];
                f.clear();
                for &(i, c) in psi {
                    for &(j, phi) in &self.rows[k.chain][i] {
                        f.push((2 * j as usize, phi * c.x));
                        f.push((2 * j as usize + 1, phi * c.y));
                    }
                }
            }
        }
        self.functionals = fs;
        pair_values(&self.functionals, &self.body.state().u, base);
        if !points.is_empty() && self.mode == ComplianceMode::Boundary {
            self.ensure_green()?;
        }
        let direct = self.mode == ComplianceMode::Direct;
        if !std::mem::take(&mut self.predicted) {
            self.solve_free_step()?;
        }
        let (fs, dense) = (&self.functionals, &mut self.dense);
        if let Some(nm) = self.body.newmark_mut() {
            if direct {
                nm.point_compliance(fs, free, dense);
            } else {
                pair_values(fs, nm.solution(), free);
            }
        }
        if let (false, Some(g)) = (direct, &self.green) {
            self.mapped.set(&self.functionals, g);
        }
        Ok(())
    }
    fn predict_step(&mut self) -> Result<(), SolveError> {
        self.solve_free_step()?;
        self.predicted = true;
        Ok(())
    }
    fn compliance(&mut self) -> Compliance<'_> {
        match (&self.green, self.mode) {
            (Some(g), ComplianceMode::Boundary) => Compliance::Boundary(g, &mut self.mapped),
            _ => Compliance::Dense(&self.dense),
        }
    }
    /// The forces join the solution through `A⁻¹Φᵀ`, and are booked as the
    /// step's loads (an FE body's support reactions exclude them).
    fn finish_step(&mut self, forces: &[Vec2]) -> Result<(), SolveError> {
        if self.mode == ComplianceMode::Direct {
            if let Some(nm) = self.body.newmark_mut() {
                nm.apply_point_forces(forces);
            }
        } else if !forces.is_empty() {
            let fs = std::mem::take(&mut self.functionals);
            let r = self.body.add_point_forces(&fs, forces);
            self.functionals = fs;
            r.map_err(|e| self.solve_error(e))?;
        }
        let m = self.point_rows.len();
        for (row, f) in self.point_rows.iter().zip(forces) {
            self.body.add_point_load_row(row, *f);
        }
        for (pair, f) in self.functionals.chunks_exact(2).zip(forces).skip(m) {
            self.body.add_dof_loads(&pair[0], f.x);
            self.body.add_dof_loads(&pair[1], f.y);
        }
        self.body.commit().map_err(|e| self.solve_error(e))?;
        self.refresh();
        Ok(())
    }
    /// One solve under the held loads, kept pending: the step's end adds
    /// the rest of the loads to it ([`end_path`](Continuum::end_path)).
    fn begin_path(&mut self, h: f64) -> Result<(), SolveError> {
        self.pre = Some(self.body.save_state());
        self.path.measured = self.contact_force;
        self.predict_path()?;
        let starts = self.chains.iter().map(|c| &c.current);
        self.path.start.resize_with(self.chains.len(), Vec::new);
        for (start, current) in self.path.start.iter_mut().zip(starts) {
            start.clone_from(current);
        }
        self.path.h = h;
        if self.path.compliant {
            self.held_response()?;
            self.path
                .corr
                .iter_mut()
                .flatten()
                .for_each(|c| *c = Vec2::ZERO);
        }
        Ok(())
    }
    fn grow(&mut self, held: &[HeldContact]) -> Result<bool, SolveError> {
        if !self.body.grow(held).map_err(|e| self.solve_error(e))? {
            return Ok(false);
        }
        self.remake_chains().map_err(|e| self.solve_error(e))?;
        Ok(true)
    }
    fn growth_due(&self) -> bool {
        self.body.growth_due()
    }
    fn grows(&self) -> bool {
        self.body.grows()
    }
    fn book_fracture(&mut self, e: f64) {
        self.body.book_fracture(e);
    }
    fn set_step(&mut self, h: f64) -> Result<(), SolveError> {
        self.body
            .start_dynamic(h)
            .map_err(|e| self.solve_error(e))?;
        self.green = None;
        self.chain_s = ChainCompliance::new(self.held_resp.len());
        Ok(())
    }
    fn retime(&mut self, dt: f64, scale: (usize, usize)) -> Result<(), SolveError> {
        self.body
            .retime(dt, scale)
            .map_err(|e| self.solve_error(e))?;
        self.green = None;
        self.chain_s = ChainCompliance::new(self.held_resp.len());
        self.path.compliant = false;
        Ok(())
    }
    /// Power iteration on `K^½ S K^½` (one solve per product), from a
    /// uniform push along the normals, to 1e-3 or 60 products.
    fn collective_gain(
        &mut self,
        kn: f64,
        ks: f64,
        spacing: f64,
    ) -> Result<Collective, SolveError> {
        // per chain point: K^½ (2 × 2, symmetric) from its normal and share
        let mut half: Vec<[f64; 4]> = Vec::new();
        for ch in &self.chains {
            let p = &ch.reference;
            for i in 0..p.len() {
                let seg = |a: usize| p[a + 1] - p[a];
                let (prev, next) = (
                    (i > 0).then(|| seg(i - 1)),
                    (i + 1 < p.len()).then(|| seg(i)),
                );
                let len = 0.5 * (prev.map_or(0.0, |d| d.norm()) + next.map_or(0.0, |d| d.norm()));
                let tan = prev.unwrap_or(Vec2::ZERO) + next.unwrap_or(Vec2::ZERO);
                let t = if tan.norm() > 0.0 {
                    tan * (1.0 / tan.norm())
                } else {
                    Vec2::new(1.0, 0.0)
                };
                let n = Vec2::new(t.y, -t.x);
                let w = (len / spacing).sqrt();
                let (a, b) = (w * kn.sqrt(), w * ks.sqrt());
                half.push([
                    a * n.x * n.x + b * t.x * t.x,
                    a * n.x * n.y + b * t.x * t.y,
                    a * n.x * n.y + b * t.x * t.y,
                    a * n.y * n.y + b * t.y * t.y,
                ]);
            }
        }
        let rows: Vec<&Row> = self.rows.iter().flatten().collect();
        let name = self.body.name().to_string();
        let Some(nm) = self.body.newmark_mut() else {
            return Ok(Collective::default());
        };
        let apply =
            |k: &[f64; 4], v: Vec2| Vec2::new(k[0] * v.x + k[1] * v.y, k[2] * v.x + k[3] * v.y);
        let mut x: Vec<Vec2> = half.iter().map(|k| apply(k, Vec2::new(0.3, 1.0))).collect();
        let mut load = vec![0.0; nm.n()];
        let mut lambda = 0.0;
        for _ in 0..60 {
            let norm = x.iter().map(|v| v.dot(*v)).sum::<f64>().sqrt();
            if !(norm > 0.0 && norm.is_finite()) {
                return Ok(Collective::default());
            }
            load.iter_mut().for_each(|l| *l = 0.0);
            for ((row, k), v) in rows.iter().zip(&half).zip(&x) {
                add_row_load(&mut load, row, apply(k, *v * (1.0 / norm)));
            }
            for (l, &imposed) in load.iter_mut().zip(nm.imposed()) {
                if imposed {
                    *l = 0.0;
                }
            }
            nm.solve_in_place(&mut load);
            let y: Vec<Vec2> = rows
                .iter()
                .zip(&half)
                .map(|(row, k)| apply(k, interpolate(row, &load)))
                .collect();
            let next = y.iter().zip(&x).map(|(a, b)| a.dot(*b)).sum::<f64>() / norm;
            x = y;
            let done = (next - lambda).abs() <= 1e-3 * next.abs();
            lambda = next;
            if done {
                break;
            }
        }
        if !lambda.is_finite() {
            return Err(SolveError {
                body: name,
                message: "the collective contact gain is not finite".to_string(),
            });
        }
        // `load` holds the last response u = A⁻¹ φ K^½ x
        let (stiff, mass) = (nm.stiffness.quad_form(&load), nm.mass.quad_form(&load));
        let omega = if mass > 0.0 && stiff > 0.0 {
            (stiff / mass).sqrt()
        } else {
            0.0
        };
        Ok(Collective {
            gain: lambda,
            omega,
        })
    }
    fn path_extent(&self) -> f64 {
        let p = &self.path;
        let pairs = p.start.iter().flatten().zip(p.end.iter().flatten());
        pairs.fold(0.0, |m, (a, b)| m.max((*b - *a).norm()))
    }
    fn path_energy(&self) -> (f64, f64) {
        (self.path.created, self.path.exchanged)
    }
    fn set_path(&mut self, s: f64) {
        let p = &self.path;
        for ((chain, a), b) in self.chains.iter_mut().zip(&p.start).zip(&p.end) {
            for ((cur, a), b) in chain.current.iter_mut().zip(a).zip(b) {
                *cur = *a + (*b - *a) * s;
            }
        }
        if p.compliant {
            for (chain, corr) in self.chains.iter_mut().zip(&p.corr) {
                for (cur, c) in chain.current.iter_mut().zip(corr) {
                    *cur += *c;
                }
            }
        }
    }
    fn set_compliant(&mut self) -> Result<(), SolveError> {
        self.path.compliant = true;
        Ok(())
    }
    fn path_correction(&self) -> f64 {
        let c = self.path.corr.iter().flatten();
        c.fold(0.0, |m, c| m.max(c.norm()))
    }
    fn factor_nnz(&mut self) -> usize {
        self.body.newmark_mut().map_or(0, |nm| nm.factor_nnz())
    }
    /// The free positions and the compliance `S_kl = Σ w_ka w_lb S_ab`
    /// over the segment ends `a`, `b` of the points and their weights
    /// `1 − σ`, `σ`.
    fn compliant_system(
        &mut self,
        s: f64,
        pts: &[(usize, usize, f64)],
        free: &mut Vec<Vec2>,
        out: &mut Vec<f64>,
    ) -> Result<(), SolveError> {
        let w: Vec<[(usize, f64); 2]> = pts
            .iter()
            .map(|&(c, seg, t)| {
                let a = self.offsets[c] + seg;
                [(a, 1.0 - t), (a + 1, t)]
            })
            .collect();
        let ends: Vec<usize> = w.iter().flatten().map(|e| e.0).collect();
        self.ensure_columns(&ends)?;
        for &a in &ends {
            if self.held_resp[a].is_none() {
                self.held_resp[a] = Some(self.chain_s.response_at(a, &self.held_loads));
            }
        }
        let (p, held) = (&self.path, &self.held_resp);
        free.clear();
        free.extend(pts.iter().zip(&w).map(|(&(c, seg, _), wk)| {
            let at = |i: usize, (a, x): (usize, f64)| {
                (path_at(p, c, i, s) - held[a].unwrap_or(Vec2::ZERO)) * x
            };
            at(seg, wk[0]) + at(seg + 1, wk[1])
        }));
        let m2 = 2 * pts.len();
        out.clear();
        out.resize(m2 * m2, 0.0);
        // by columns (l), each down its chain points' column (k ≥ l)
        for (l, wl) in w.iter().enumerate() {
            for (k, wk) in w.iter().enumerate().skip(l) {
                let mut blk = [0.0; 4];
                for &(b, y) in wl {
                    for &(a, x) in wk {
                        let sab = self.chain_s.block(a, b);
                        for (q, v) in blk.iter_mut().zip(sab) {
                            *q += x * y * v;
                        }
                    }
                }
                // S_lk = S_klᵀ (A is symmetric)
                for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                    out[(2 * k + i) * m2 + 2 * l + j] = blk[2 * i + j];
                    out[(2 * l + j) * m2 + 2 * k + i] = blk[2 * i + j];
                }
            }
        }
        Ok(())
    }
    /// The new loads replace the last DEM step's; the response to them
    /// (less the held ones) is updated at the points loaded now or then,
    /// which move to the path plus it, and the discs' work over the DEM
    /// step is booked (the mean of the two loads on each point's
    /// displacement).
    fn compliant_loads(
        &mut self,
        s: f64,
        ds: f64,
        pts: &[(usize, usize, f64)],
        g: &[Vec2],
    ) -> Result<(), SolveError> {
        let o = &self.offsets;
        let old: Vec<(usize, Vec2)> = nonzero(&self.path.acc).collect();
        let acc = &mut self.path.acc;
        acc.iter_mut().flatten().for_each(|f| *f = Vec2::ZERO);
        for (&(c, seg, t), f) in pts.iter().zip(g) {
            acc[c][seg] += *f * (1.0 - t);
            acc[c][seg + 1] += *f * t;
        }
        let mut win: Vec<usize> = old
            .iter()
            .map(|x| x.0)
            .chain(
                pts.iter()
                    .flat_map(|&(c, seg, _)| [o[c] + seg, o[c] + seg + 1]),
            )
            .collect();
        win.sort_unstable();
        win.dedup();
        let p = &self.path;
        let diff: Vec<(usize, Vec2)> = p
            .acc
            .iter()
            .flatten()
            .zip(p.held.iter().flatten())
            .enumerate()
            .filter(|(_, (f, h))| f != h)
            .map(|(b, (f, h))| (b, *f - *h))
            .collect();
        let need: Vec<usize> = diff.iter().map(|d| d.0).collect();
        self.ensure_columns(&need)?;
        // the response at the window, column by column
        let mut resp = vec![Vec2::ZERO; win.len()];
        for &(b, d) in &diff {
            for (r, &a) in resp.iter_mut().zip(&win) {
                let k = self.chain_s.block(a, b);
                r.x += k[0] * d.x + k[1] * d.y;
                r.y += k[2] * d.x + k[3] * d.y;
            }
        }
        let (mut done, mut swept) = (0.0, 0.0);
        for (a, r) in win.into_iter().zip(resp) {
            let (c, i) = self.locate(a);
            let p = &mut self.path;
            let f0 = old
                .binary_search_by_key(&a, |x| x.0)
                .map_or(Vec2::ZERO, |k| old[k].1);
            let dy = (p.end[c][i] - p.start[c][i]) * ds + r - p.corr[c][i];
            let work = (f0 + p.acc[c][i]).dot(dy) * 0.5;
            done += work;
            swept += work.abs();
            p.corr[c][i] = r;
            self.chains[c].current[i] = path_at(p, c, i, s) + r;
        }
        self.path.done += done;
        self.path.swept += swept;
        Ok(())
    }
    /// Constant along the path: the chain points' displacement over the
    /// step divided by `h`, interpolated along the segment.
    fn path_velocity(&self, chain: usize, seg: usize, s: f64) -> Vec2 {
        let p = &self.path;
        let (a, b) = (&p.start[chain], &p.end[chain]);
        let v = |i: usize| (b[i] - a[i]) * (1.0 / p.h);
        v(seg) * (1.0 - s) + v(seg + 1) * s
    }
    fn add_path_load(&mut self, chain: usize, seg: usize, s: f64, f: Vec2) {
        let acc = &mut self.path.acc[chain];
        acc[seg] += f * (1.0 - s);
        acc[seg + 1] += f * s;
    }
    /// The end load less the held one joins the pending prediction through
    /// `A⁻¹` (with a moving edge's refinement residual: one solve).
    fn end_path(&mut self) -> Result<(), SolveError> {
        if self.path.compliant {
            return self.end_compliant();
        }
        self.ensure_point_fs();
        // the average over the step belongs to its middle: the load at its
        // end is extrapolated from it and the last step's average, except
        // where a point starts or stops being loaded (a contact's first
        // body step would be off by a quarter of its work, its last would
        // pull)
        let p = &self.path;
        let held = || p.held.iter().flatten();
        let ends: Vec<Vec2> = p
            .acc
            .iter()
            .flatten()
            .zip(held())
            .map(|(f, f0)| {
                if *f0 == Vec2::ZERO || *f == Vec2::ZERO {
                    *f
                } else {
                    *f * 1.5 - *f0 * 0.5
                }
            })
            .collect();
        let delta: Vec<Vec2> = ends.iter().zip(held()).map(|(f, f0)| *f - *f0).collect();
        // the step's loads: the held ones went in before the prediction
        self.take_step(&delta)?;
        // the energy account of the step: what the body received against
        // what the discs did on the path
        let p = &mut self.path;
        let (mut received, mut done, mut exchanged) = (0.0, 0.0, 0.0);
        for (((((f1, f0), avg), y0), yp), y1) in ends
            .into_iter()
            .zip(p.last_end.iter_mut().flatten())
            .zip(p.acc.iter().flatten())
            .zip(p.start.iter().flatten())
            .zip(p.end.iter().flatten())
            .zip(self.chains.iter().flat_map(|c| &c.current))
        {
            received += (*f0 + f1).dot(*y1 - *y0) * 0.5;
            let w = avg.dot(*yp - *y0);
            done += w;
            exchanged += w.abs();
            *f0 = f1;
        }
        p.created += received - done;
        p.exchanged += exchanged;
        std::mem::swap(&mut p.held, &mut p.acc);
        p.acc.iter_mut().flatten().for_each(|f| *f = Vec2::ZERO);
        p.end.clear();
        Ok(())
    }
    fn energies(&self) -> BodyEnergies {
        self.body.energies()
    }
    fn set_contact_force(&mut self, f: Vec2) {
        self.contact_force = f;
        self.body.set_contact_force(f);
    }
    fn green_size(&self) -> (usize, usize) {
        self.green.as_ref().map_or((0, 0), |g| (g.len(), g.bytes()))
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    /// The body's state, the compliance mode and the Green matrix's DOFs
    /// batch by batch (not its entries: [`restore_state`](Self::restore_state)
    /// computes them again by the same solves, in the same order).
    fn save_state(&self) -> BodyState {
        let mut s = self.pre.clone().unwrap_or_else(|| self.body.save_state());
        s.boundary = Some(BoundaryState {
            direct: self.mode == ComplianceMode::Direct,
            green: self.green.as_ref().map(BoundaryGreen::batches),
            path: self.path.clone(),
        });
        s
    }
    fn restore_state(&mut self, s: &BodyState) -> Result<(), StateError> {
        self.predicted = false;
        let name = self.body.name().to_string();
        let Some(b) = &s.boundary else {
            return Err(StateError::new(format!(
                "body `{name}`: the saved state has no contact boundary (a continuum-only model's)"
            )));
        };
        self.body.restore_state(s)?;
        // a state saved after a growth: the chains along the longer cracks
        self.remake_chains()
            .map_err(|e| StateError::new(e.to_string()))?;
        let shape = |v: &[Vec<Vec2>]| {
            v.len() == self.chains.len()
                && v.iter()
                    .zip(&self.chains)
                    .all(|(p, c)| p.len() == c.reference.len())
        };
        let p = &b.path;
        if !shape(&p.held)
            || !shape(&p.acc)
            || !shape(&p.last_end)
            || !shape(&p.corr)
            || p.compliant != self.path.compliant
            || !(p.end.is_empty() || shape(&p.end) && shape(&p.start))
        {
            return Err(StateError::new(format!(
                "body `{name}`: the saved boundary path does not fit its contact chains"
            )));
        }
        self.refresh();
        self.path.clone_from(p);
        self.pre = None;
        if !p.end.is_empty() {
            // the pending prediction, made again from the same state
            let mut pre = s.clone();
            pre.boundary = None;
            self.pre = Some(pre);
            self.body.set_contact_force(p.measured);
            self.predict_path()
                .map_err(|e| StateError::new(e.to_string()))?;
            if p.compliant {
                self.held_response()
                    .map_err(|e| StateError::new(e.to_string()))?;
            }
        }
        self.mode = if b.direct {
            ComplianceMode::Direct
        } else {
            ComplianceMode::Boundary
        };
        self.green = None;
        if let Some(batches) = &b.green {
            let Some(nm) = self.body.newmark_mut() else {
                return Err(StateError::new(format!(
                    "body `{name}`: a saved boundary Green matrix, but the body is not dynamic"
                )));
            };
            let mut g = BoundaryGreen::new(nm.n(), nm.imposed().to_vec());
            for batch in batches {
                g.extend_dofs(batch, nm.factor())
                    .map_err(|e| StateError::new(format!("body `{name}`: {e}")))?;
            }
            self.green = Some(g);
        }
        Ok(())
    }
}

/// A body's step count after [`Continuum::retime`] to `scale.0` steps per
/// `scale.1` present ones (the time `step · dt` kept), or `None` when the
/// present time is not a whole number of the new steps.
pub fn rescaled_step(step: usize, scale: (usize, usize)) -> Option<usize> {
    let n = step.checked_mul(scale.0)?;
    (scale.1 > 0 && n.is_multiple_of(scale.1)).then(|| n / scale.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_retimed_body_keeps_its_time_in_whole_steps() {
        assert_eq!(rescaled_step(100, (5, 1)), Some(500));
        assert_eq!(rescaled_step(100, (5, 2)), Some(250));
        assert_eq!(rescaled_step(101, (5, 2)), None);
        assert_eq!(rescaled_step(0, (5, 3)), Some(0));
    }

    /// All four edges make one closed chain (its ends one corner,
    /// [`BoundaryChain::is_closed`]); fewer make open ones.
    #[test]
    fn all_four_edges_make_a_closed_chain() {
        let (o, s, g) = (Vec2::new(0.15, 0.0798), Vec2::new(0.2, 0.04), [41, 9]);
        for refine in [1, 2, 3] {
            let ch = contact_chains(o, s, g, &Edge::ALL, refine);
            assert_eq!(ch.len(), 1);
            assert!(
                BoundaryChain::new(ch[0].clone()).is_closed(),
                "refine {refine}"
            );
            let open = contact_chains(o, s, g, &[Edge::Bottom, Edge::Right, Edge::Top], refine);
            assert!(!BoundaryChain::new(open[0].clone()).is_closed());
        }
    }

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
