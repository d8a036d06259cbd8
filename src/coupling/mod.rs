//! EFG–DE coupling (§2.4 and §3 of the paper): the time loop.
//!
//! One coupled step (explicit DEM, implicit Newmark, one Δt for both by
//! default — ERRATA E11):
//! 1. DEM contacts: disc–disc and disc–wall forces ([`Granular`] phases),
//!    plus the disc–body forces found at the end of the previous step.
//! 2. Discs advance by the central difference to `t + Δt`.
//! 3. Disc–body contacts on each body's current boundary
//!    ([`interface::detect`]): the body side moves with the material point
//!    `H` (Eq. 41, E7), the contact law is the DEM's (Eqs. 35–37, E6), and
//!    the contact springs enter the body's Newmark step implicitly
//!    ([`implicit`]): the body solves for `U(t + Δt)` with the contact
//!    forces at `t + Δt` as point loads through the same shape functions
//!    (Eq. 46, E7), and the discs get exactly the opposite forces at the
//!    next step.
//!
//! Rolling resistance ([`crate::dem::contact::rolling`], `r̄ = r`, relative
//! rotation `ω_disc`) acts on the disc alone: the body feels no moment,
//! only the contact force on its boundary. It is evaluated after the
//! contact solve, from the contact's normal force at `t + Δt` (it does not
//! change the body's unknowns).
//!
//! Sub-cycled (`substeps` = n > 1 DEM steps per body step of `h = nΔt`,
//! [`Continuum::begin_path`]): at the start of a body step each body
//! predicts its step under the last step's contact loads (one solve, kept
//! pending); over the n DEM steps its contact chain moves on the straight
//! path from its present to its predicted position (the discs meet it like
//! a moving wall, the path's velocity in their dashpots), and the discs'
//! forces go to the ends of the touched segment (the loads work-conjugate
//! to that straight-segment geometry), averaged over the n steps. The
//! average belongs to the middle of the body step: the body takes the end
//! load `1.5 F̄ₖ − 0.5 F̄ₖ₋₁` (Newmark's trapezoidal work `½(Fₖ + Fₖ₊₁)·ΔU`
//! then matches the discs' `F̄ₖ·ΔU` to second differences of `F̄`), whose
//! difference from the held load joins the pending prediction (one more
//! solve). The discs' work differs from the body's by `F̄·A⁻¹Φᵀ(ΔF̄)`, the
//! prediction's error: small when the body is stiff against the contacts
//! over a body step (`k_n c` ≤ 0.05, checked at build). It is a lag all
//! the same (the body's response to a change of the contact forces reaches
//! the discs a body step late), which can drive the contacts' own
//! oscillation when the body step resolves it: each body keeps the energy
//! the scheme created ([`Continuum::path_energy`]) and the driver stops a
//! run that creates too much ([`MAX_CREATED`]). Cost: two body solves per
//! n DEM steps, no contact solve.
//!
//! `coupling = "staggered"` instead applies the contact forces of the
//! body's last state (boundary frozen over the body step) as loads of the
//! next body step. That lag acts as a negative dashpot of about `k_n Δt`
//! on the body; it is stable only with a dissipative Newmark (the paper's
//! γ = 1.5, β = 0.8) or a soft contact.

pub mod candidates;
pub mod energy;
mod growth;
pub mod implicit;
pub mod interface;
pub mod scheme;
pub mod segments;
pub mod state;
pub mod workers;

use crate::continuum::{BoundaryChain, Continuum, SolveError};
use crate::dem::Granular;
use crate::dem::contact::{self, ContactLaw, Side, effective_mass};
use crate::dem::particles::Particles;
use crate::geom::Vec2;
use candidates::Candidates;
use segments::SegmentGrid;
use std::time::Instant;

/// Shear history and last state of one disc–body contact, keyed by
/// `(disc id, body, chain)` so that a disc sliding from one segment to the
/// next keeps its shear force.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyContact {
    /// Disc id (stable; not the DEM slot, which changes when the DEM
    /// reorders its discs).
    pub disc: u32,
    /// Index of the body in [`CoupledModel::bodies`].
    pub body: u16,
    /// Index of the chain in the body's
    /// [`contact_boundary`](Continuum::contact_boundary).
    pub chain: u16,
    /// Shear force history along `t = perp(n_disc→body)`.
    pub fs: f64,
    /// Rolling-spring history: the rolling resistance moment on the disc
    /// ([`contact::rolling`], relative rotation `ω_disc`; 0 without
    /// rolling friction).
    pub mr: f64,
    /// Rolling moment on the disc (spring + dashpot). The body feels no
    /// moment: the rolling resistance acts on the disc only, and the body
    /// takes the contact force on its boundary alone.
    pub moment: f64,
    /// Overlap at the last evaluation.
    pub overlap: f64,
    /// Elastic normal force `k_n δ` (Eq. 35, E6).
    pub fn_elastic: f64,
    /// Total normal force `k_n δ + β k_n δ̇` (with dashpot, E6).
    pub fn_total: f64,
    /// Force on the disc.
    pub force: Vec2,
    /// Contact point on the body boundary (current configuration).
    pub point: Vec2,
    /// Unit normal from the disc towards the body (the disc's torque arm is
    /// `r n`, E12).
    pub normal: Vec2,
    /// Material (reference) coordinates of the contact point `X_H`.
    pub material: Vec2,
    /// Feature touched (Fig. 5).
    pub feature: interface::Feature,
}

impl BodyContact {
    fn key(&self) -> (u32, u16, u16) {
        (self.disc, self.body, self.chain)
    }
}

/// A granular assembly coupled with continuum bodies.
pub struct CoupledModel {
    /// The discs, walls and their contacts (DEM).
    pub granular: Granular,
    /// The continuum bodies (EFG or FE), in scenario order.
    pub bodies: Vec<Box<dyn Continuum>>,
    /// Contact law of body `b` against disc material `a`: `body_laws[b * n_mat + a]`.
    pub body_laws: Vec<ContactLaw>,
    /// DEM steps per body step (1 = same Δt for both; more: the sub-cycled
    /// scheme, or the staggered one if `staggered`).
    pub substeps: usize,
    /// Body takes the previous state's contact forces with its boundary
    /// frozen (no implicit contact springs, no predicted path).
    pub staggered: bool,
    /// Live disc–body contacts, sorted by key.
    pub contacts: Vec<BodyContact>,
    /// Per body, per chain: its segments binned for detection.
    grids: Vec<Vec<SegmentGrid>>,
    /// Per body, per chain: the discs that may touch it.
    near: Vec<Vec<Candidates>>,
    /// The largest disc radius and the DEM rebuild count it was found at
    /// (discs are only added with a rebuild).
    r_max: Option<(usize, f64)>,
    scratch: Vec<BodyContact>,
    loads: Vec<Load>,
    sub: usize,
    /// Disc–body forces of the present state are known (implicit scheme).
    primed: bool,
    work: Work,
    /// Newton iterations of the last implicit contact solve (diagnostics).
    pub newton_iterations: usize,
    /// The geometric stiffness of segment contacts implicit in the step
    /// ([`interface::Touch::geometric_stiffness`]); default true.
    pub geometric_stiffness: bool,
    /// Products `S x` of all implicit contact solves so far (diagnostics).
    pub compliance_products: usize,
    /// Wall time spent so far in each part of the step.
    pub timing: StepTiming,
    /// The compliant sub-cycled scheme ([`CoupledModel::set_compliant`]).
    pub compliant: bool,
    /// Compliant scheme, per body: how far its boundary's response to the
    /// contacts may go before its segments are binned again.
    allow: Vec<f64>,
    /// Per body, the sub-cycling energy guard's record (saved with the
    /// state).
    pub over: Vec<GuardRecord>,
    /// The scheme and substeps, and why ([`scheme::apply`]).
    pub choice: Option<scheme::Choice>,
    /// The body step (in DEM steps) the bodies are factored for.
    pub factored: usize,
    /// An automatically chosen sub-cycled scheme given up for the exact
    /// step ([`CoupledModel::fall_back`]; saved with the state).
    pub fallback: Option<Fallback>,
    /// Warnings for the user since they were last taken
    /// ([`crate::model::Model::take_notices`]).
    pub notices: Vec<String>,
    /// The largest disc radius of the whole assembly when `granular` holds
    /// only the discs near the bodies (a decomposed run, [`DiscStep`]):
    /// the segment grids are then binned as the whole's are.
    pub radius_bound: Option<f64>,
    /// Exact step taken with [`step_deferring`](CoupledModel::step_deferring):
    /// per body, the contact forces whose response
    /// ([`Continuum::finish_step`]) is still to be added — the bodies are at
    /// the previous step until [`settle`](CoupledModel::settle) or the next
    /// step adds it.
    pending: Vec<(usize, Vec<Vec2>)>,
    /// The present step may leave its bodies' ends pending.
    defer: bool,
    /// Compliant scheme, [`step_deferring`](CoupledModel::step_deferring):
    /// the discs have taken the present step but its contact solve is
    /// still to come; the next step solves it beside its disc sweep
    /// ([`CoupledModel::settle`] before reading the contacts or bodies).
    tail_pending: bool,
    /// The discs near the bodies, copied for that solve (kept for its
    /// buffers).
    view: Option<Granular>,
}

/// How the coupling steps the discs. [`Whole`]: the assembly held in
/// [`CoupledModel::granular`]. A run divided over ranks (`crate::decomp`)
/// steps its rank's part instead and keeps in `granular` a copy, the same
/// on every rank, of the discs near the bodies at the present state.
pub trait DiscStep: Send {
    /// The neighbour list ready for the next step
    /// ([`Granular::prepare_contacts`]).
    fn prepare(&mut self, g: &mut Granular);
    /// One fused DEM step ([`Granular::step`]) with the disc–body forces
    /// `contacts` acting on their discs (by id).
    fn step(&mut self, g: &mut Granular, contacts: &[BodyContact]);
}

/// The discs in [`CoupledModel::granular`] are the whole assembly.
pub struct Whole;

impl DiscStep for Whole {
    fn prepare(&mut self, g: &mut Granular) {
        g.prepare_contacts();
    }
    fn step(&mut self, g: &mut Granular, contacts: &[BodyContact]) {
        set_contacts_on_discs(g, contacts);
        g.step();
    }
}

/// The disc–body forces `contacts` as external forces of the next (fused)
/// step of `g`, on those of their discs that `g` holds.
pub fn set_contacts_on_discs(g: &mut Granular, contacts: &[BodyContact]) {
    let p = &g.particles;
    let ext: Vec<_> = contacts
        .iter()
        .filter_map(|q| {
            let slot = *p.slot.get(q.disc as usize)? as usize;
            // the torque arm r n; the rolling moment acts on the disc only
            (slot < p.len()).then(|| {
                (
                    slot,
                    q.force,
                    p.pos[slot] + q.normal * p.radius[slot],
                    q.moment,
                )
            })
        })
        .collect();
    g.set_external_with_moments(ext);
}

/// An automatically chosen sub-cycled scheme that created energy
/// ([`MAX_CREATED`]), replaced from a body step's end on by the same
/// scheme with at most half its substeps, or by the exact step
/// ([`fallback_substeps`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Fallback {
    /// The scheme given up (`"predicted"` or `"compliant"`).
    pub from: String,
    /// Its DEM steps per body step.
    pub substeps: usize,
    /// The DEM steps per body step taken on (1: the exact step).
    pub to: usize,
    /// The DEM step from which they are taken.
    pub step: usize,
    /// The time then.
    pub time: f64,
    /// The body whose scheme created the energy.
    pub body: String,
    /// The energy it had created, and the work it had exchanged with the
    /// discs.
    pub created: f64,
    /// See `created`.
    pub exchanged: f64,
}

impl CoupledModel {
    /// Newton iterations a contact solve may take before the run stops
    /// ([`CouplingError::NotConverged`]; default
    /// [`implicit::MAX_NEWTON`]).
    pub fn set_contact_iterations(&mut self, n: usize) {
        self.work.solver.max_newton = n;
    }
}

/// Where the time of the coupled steps goes (seconds, accumulated).
#[derive(Debug, Clone, Copy, Default)]
pub struct StepTiming {
    /// DEM contacts and integration.
    pub dem: f64,
    /// Disc–body detection, contact law, transfer.
    pub transfer: f64,
    /// The implicit contact solve (Newton over the contacts, given `S`).
    pub contact_solve: f64,
    /// Body Newmark solves (free step, compliance, update).
    pub body: f64,
}

/// Scratch of the implicit contact step.
#[derive(Default)]
struct Work {
    lin: Vec<implicit::Linear>,
    points: Vec<(usize, Vec2)>,
    base: Vec<Vec2>,
    free: Vec<Vec2>,
    solver: implicit::Solver,
    /// Geometric stiffness of the candidates
    /// ([`interface::Touch::geometric_stiffness`]).
    stiffness: Vec<crate::continuum::ChainStiffness>,
    evals: Vec<implicit::Eval>,
    forces: Vec<Vec2>,
    /// Per candidate: (disc slot, body, chain, contact point, feature).
    meta: Vec<(usize, usize, usize, Vec2, interface::Feature)>,
    /// Compliant scheme, per candidate: (chain, segment, parameter), and
    /// the compliance among them.
    pts: Vec<(usize, usize, f64)>,
    dense: Vec<f64>,
}

/// A disc–body force waiting to be applied.
#[derive(Debug, Clone, Copy)]
struct Load {
    slot: usize,
    body: usize,
    chain: usize,
    /// Material point of the body where the reaction acts.
    material: Vec2,
    /// Segment and parameter of that point (the sub-cycled scheme's
    /// boundary path).
    seg: usize,
    s: f64,
    /// Contact point on the disc (for its moment).
    arm: Vec2,
    /// Force on the disc.
    f: Vec2,
    /// Rolling moment on the disc (not on the body).
    moment: f64,
}

/// Why a coupled step failed.
#[derive(Debug, thiserror::Error)]
pub enum CouplingError {
    /// A body's Newmark step failed.
    #[error(transparent)]
    Solve(#[from] crate::continuum::SolveError),
    /// The DEM step failed.
    #[error(transparent)]
    Dem(#[from] crate::dem::DemError),
    /// A disc's state became non-finite.
    #[error(
        "the discs became unstable at step {step} (non-finite state); reduce dt (DEM critical step {dt_crit:e})"
    )]
    Unstable {
        /// DEM steps done when it was detected (with sub-cycling, n per
        /// body step).
        step: usize,
        /// The critical time step of the contacts in use
        /// ([`Granular::critical_step`]).
        dt_crit: f64,
    },
    /// A body's sub-cycled scheme created energy ([`MAX_CREATED`]).
    #[error(
        "body `{body}`: the sub-cycled scheme ({scheme}) created {created:.3e} J by step {step} (t = {time:.6} s), {pct:.2} % of the {exchanged:.3e} J the body exchanged with the discs, above {limit} % for {GUARD_STEPS} body steps in a row: the body is too soft against the contacts for this scheme and step; {remedy}",
        pct = 100.0 * created / exchanged,
        limit = 100.0 * MAX_CREATED
    )]
    Subcycling {
        /// Name of the body.
        body: String,
        /// `"predicted"` or `"compliant"`.
        scheme: &'static str,
        /// DEM steps taken.
        step: usize,
        /// Time of the discs when it was found.
        time: f64,
        /// Energy the scheme created on this body so far.
        created: f64,
        /// Work the body exchanged with the discs so far.
        exchanged: f64,
        /// What to do about it.
        remedy: &'static str,
    },
    /// A contact solve did not converge.
    #[error(
        "body `{body}`: the contact solve did not converge at step {step} (t = {time:.6} s): {why}; the run stops rather than go on with forces that are not a solution"
    )]
    NotConverged {
        /// Name of the body.
        body: String,
        /// DEM steps taken (the step being solved is the next).
        step: usize,
        /// Time of the discs.
        time: f64,
        /// What failed.
        why: implicit::Unsolved,
    },
}

/// The Newton iterations of a contact solve, or the error naming the body
/// and the step.
fn unsolved(
    r: Result<usize, implicit::Unsolved>,
    body: &str,
    g: &Granular,
) -> Result<usize, CouplingError> {
    r.map_err(|why| CouplingError::NotConverged {
        body: body.to_string(),
        step: g.step,
        time: g.time,
        why,
    })
}

impl CoupledModel {
    /// Couple `granular` with `bodies`; `body_material[b]` is the contact
    /// material index of body `b` (`None`: the disc's own material, as for walls).
    pub fn new(
        granular: Granular,
        bodies: Vec<Box<dyn Continuum>>,
        body_material: &[Option<u16>],
        substeps: usize,
    ) -> Self {
        let nm = granular.materials.len();
        let body_laws = (0..bodies.len())
            .flat_map(|b| {
                (0..nm).map(move |a| {
                    body_material
                        .get(b)
                        .copied()
                        .flatten()
                        .map_or(a, usize::from)
                })
            })
            .map(|m| granular.materials[m])
            .collect();
        CoupledModel {
            granular,
            bodies,
            body_laws,
            substeps: substeps.max(1),
            staggered: false,
            contacts: Vec::new(),
            grids: Vec::new(),
            near: Vec::new(),
            r_max: None,
            scratch: Vec::new(),
            loads: Vec::new(),
            sub: 0,
            primed: false,
            work: Work::default(),
            newton_iterations: 0,
            compliance_products: 0,
            geometric_stiffness: true,
            timing: StepTiming::default(),
            compliant: false,
            allow: Vec::new(),
            over: Vec::new(),
            choice: None,
            factored: substeps.max(1),
            fallback: None,
            notices: Vec::new(),
            radius_bound: None,
            pending: Vec::new(),
            defer: false,
            tail_pending: false,
            view: None,
        }
    }

    /// Use the compliant sub-cycled scheme: over a body step of `substeps`
    /// DEM steps each body's contact boundary is its predicted path plus
    /// its response, through the body step's compliance, to the change of
    /// the contact forces; the contacts are solved implicitly against that
    /// response in every DEM step ([`CoupledModel::step`]).
    pub fn set_compliant(&mut self) -> Result<(), CouplingError> {
        for b in &mut self.bodies {
            b.set_compliant()?;
        }
        self.compliant = true;
        Ok(())
    }

    /// One DEM step, and a body step every `substeps` of them. The work
    /// outside the DEM's parallel sweep runs with the other workers kept
    /// awake ([`workers::awake`]).
    pub fn step(&mut self) -> Result<(), CouplingError> {
        self.step_with(&mut Whole)
    }

    /// [`step`](Self::step), except that an exact step may leave the end of
    /// its body step — the response to the contact forces, one solve per
    /// body, and the commit — pending, and a compliant step within a body
    /// step its contact solve: the next step does it beside the discs'
    /// step, on another thread (the same arithmetic, so the same results).
    /// Until then the bodies (and the contacts) hold the previous step's
    /// state; call [`settle`](Self::settle) before reading them.
    pub fn step_deferring(&mut self) -> Result<(), CouplingError> {
        self.defer = true;
        let r = self.step_with(&mut Whole);
        self.defer = false;
        r
    }

    /// Whether every body holds the present step ([`step_deferring`](Self::step_deferring)).
    pub fn is_settled(&self) -> bool {
        self.pending.is_empty() && !self.tail_pending
    }

    /// End what [`step_deferring`](Self::step_deferring) left pending.
    pub fn settle(&mut self) -> Result<(), CouplingError> {
        self.settle_bodies()?;
        self.settle_tail()
    }

    /// End the exact steps' pending body steps.
    fn settle_bodies(&mut self) -> Result<(), CouplingError> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let t = Instant::now();
        let r = finish_pending(&mut self.bodies, &mut self.pending);
        self.timing.body += t.elapsed().as_secs_f64();
        Ok(r?)
    }

    /// Solve the compliant step's pending contacts.
    fn settle_tail(&mut self) -> Result<(), CouplingError> {
        if !std::mem::take(&mut self.tail_pending) {
            return Ok(());
        }
        workers::awake(|| self.compliant_tail())
    }

    /// [`step`](Self::step) with the discs stepped by `discs`. The
    /// predicted and staggered schemes step the discs in phases and need
    /// [`Whole`].
    pub fn step_with(&mut self, discs: &mut dyn DiscStep) -> Result<(), CouplingError> {
        // only the exact step ends a body step left pending itself, and
        // only the compliant one its contact solve
        if self.compliant || self.staggered || self.substeps > 1 {
            self.settle_bodies()?;
        }
        if !self.compliant {
            self.settle_tail()?;
        }
        if self.compliant {
            return self.step_compliant(discs);
        }
        if self.substeps == 1 && !self.staggered {
            return self.step_exact(discs);
        }
        let path = self.path_scheme();
        workers::awake(|| self.begin_substep(path))?;
        let t0 = Instant::now();
        self.granular.compute_contact_forces();
        let t1 = Instant::now();
        workers::awake(|| self.body_contact_forces(path));
        let t2 = Instant::now();
        self.granular.integrate();
        let t3 = Instant::now();
        self.timing.dem += (t1 - t0).as_secs_f64() + (t3 - t2).as_secs_f64();
        self.timing.transfer += (t2 - t1).as_secs_f64();
        let r = workers::awake(|| self.end_substep(path));
        self.timing.body += t3.elapsed().as_secs_f64();
        r
    }

    /// The exact step: the disc–body forces of the present state go into
    /// the DEM's fused step as external forces — while the discs take it,
    /// the bodies solve their step under their present loads on another
    /// thread ([`Continuum::predict_step`]) — then the contacts and the
    /// bodies are solved implicitly over the step. In the timing split the
    /// prediction counts as `body` and `dem` is the rest of that time
    /// (with several threads the two overlap).
    fn step_exact(&mut self, discs: &mut dyn DiscStep) -> Result<(), CouplingError> {
        workers::awake(|| {
            let t = Instant::now();
            // the DEM's neighbour list (part of its step)
            discs.prepare(&mut self.granular);
            let t0 = Instant::now();
            self.timing.dem += (t0 - t).as_secs_f64();
            if !self.primed {
                self.settle()?;
                self.implicit_contacts(false)?;
                self.primed = true;
            }
            // what a servo drive measures (the present contacts)
            self.set_contact_forces();
            self.timing.transfer += t0.elapsed().as_secs_f64();
            Ok::<_, CouplingError>(())
        })?;
        let t1 = Instant::now();
        let (granular, bodies) = (&mut self.granular, &mut self.bodies);
        let (contacts, pending) = (&self.contacts, &mut self.pending);
        let ((), predicted) = rayon::join(
            || discs.step(granular, contacts),
            || {
                let t = Instant::now();
                let r = finish_pending(bodies, pending)
                    .and_then(|()| bodies.iter_mut().try_for_each(|b| b.predict_step()));
                (r, t.elapsed().as_secs_f64())
            },
        );
        let (predicted, tp) = predicted;
        self.timing.body += tp;
        self.timing.dem += (t1.elapsed().as_secs_f64() - tp).max(0.0);
        predicted?;
        workers::awake(|| {
            let t2 = Instant::now();
            self.check_finite()?;
            let r = self.implicit_contacts(true);
            self.timing.transfer += t2.elapsed().as_secs_f64();
            r.and_then(|()| self.grow_bodies())
        })
    }

    /// Before a DEM step of the predicted or staggered scheme: the DEM's
    /// neighbour list, and the bodies' paths (predicted at the start of a
    /// body step).
    fn begin_substep(&mut self, path: bool) -> Result<(), CouplingError> {
        let t = Instant::now();
        self.granular.prepare_contacts();
        let tb = Instant::now();
        self.timing.dem += (tb - t).as_secs_f64();
        if path {
            if self.sub == 0 {
                let h = self.granular.dt * self.substeps as f64;
                for b in &mut self.bodies {
                    b.begin_path(h)?;
                }
            }
            let s = self.sub as f64 / self.substeps as f64;
            for b in &mut self.bodies {
                b.set_path(s);
            }
        }
        self.timing.body += tb.elapsed().as_secs_f64();
        Ok(())
    }

    /// After a DEM step of the predicted or staggered scheme: the body
    /// step once every `substeps` DEM steps.
    fn end_substep(&mut self, path: bool) -> Result<(), CouplingError> {
        self.check_finite()?;
        self.sub += 1;
        if self.sub == self.substeps {
            self.sub = 0;
            self.set_contact_forces();
            for b in &mut self.bodies {
                if path {
                    b.end_path()?;
                } else {
                    b.advance()?;
                }
            }
            if path {
                self.guard()?;
            }
        }
        Ok(())
    }

    /// [`energy_guard`](Self::energy_guard); an automatically chosen
    /// scheme that it catches falls back to the exact step instead
    /// ([`fall_back`](Self::fall_back)).
    fn guard(&mut self) -> Result<(), CouplingError> {
        match self.energy_guard() {
            Err(CouplingError::Subcycling {
                body,
                scheme,
                step,
                time,
                created,
                exchanged,
                ..
            }) if self.choice.as_ref().is_some_and(|c| c.automatic) => {
                let f = Fallback {
                    from: scheme.into(),
                    substeps: self.substeps,
                    to: fallback_substeps(self.substeps, step),
                    step,
                    time,
                    body,
                    created,
                    exchanged,
                };
                let then = match f.to {
                    1 => "the exact step is taken".to_string(),
                    n => format!("the {} scheme goes on with {n} substeps", f.from),
                };
                self.notices.push(format!(
                    "body `{}`: the automatically chosen {} scheme ({} substeps) created {:.3e} J, {:.2} % of the {:.3e} J the body exchanged with the discs, above {} % for {GUARD_STEPS} body steps in a row: {then} from step {} (t = {:.6} s) on",
                    f.body,
                    f.from,
                    f.substeps,
                    f.created,
                    100.0 * f.created / f.exchanged.max(f64::MIN_POSITIVE),
                    f.exchanged,
                    100.0 * MAX_CREATED,
                    f.step,
                    f.time
                ));
                self.fall_back(f)
            }
            r => r,
        }
    }

    /// Take `f.to` DEM steps per body step from now on (at the end of a
    /// body step; 1: the exact step): every body factored for its new step
    /// with its state kept ([`Continuum::retime`]), the disc–body forces
    /// of the present state evaluated again before the next step; the
    /// scheme stays the one given up unless `f.to` is 1. `f` says why
    /// (kept in [`CoupledModel::fallback`] and the saved state).
    pub fn fall_back(&mut self, f: Fallback) -> Result<(), CouplingError> {
        let to = f.to.clamp(1, self.substeps);
        let h = self.granular.dt * to as f64;
        for b in &mut self.bodies {
            b.retime(h, (self.substeps, to))?;
        }
        (self.substeps, self.factored, self.sub) = (to, to, 0);
        self.primed = false;
        self.over.clear();
        if to == 1 {
            (self.compliant, self.staggered) = (false, false);
        } else if self.compliant {
            self.set_compliant()?;
        }
        let scheme = self.scheme();
        if let Some(c) = &mut self.choice {
            (c.scheme, c.substeps) = (scheme, to);
            c.fallback = Some(f.clone());
        }
        self.fallback = Some(f);
        Ok(())
    }

    /// The sub-cycled schemes' guard, at the end of every body step: a
    /// body whose scheme has created more than [`MAX_CREATED`] of the work
    /// it exchanged with the discs (and of the energy it holds) for
    /// [`GUARD_STEPS`] body steps in a row, and more than that fraction of
    /// the work exchanged over those steps, stops the run.
    fn energy_guard(&mut self) -> Result<(), CouplingError> {
        self.over.resize(self.bodies.len(), GuardRecord::default());
        let mut interface = vec![0.0; self.bodies.len()];
        for q in &self.contacts {
            interface[q.body as usize] += self.contact_energy(q);
        }
        for ((body, g), interface) in self.bodies.iter().zip(&mut self.over).zip(interface) {
            let (created, exchanged) = body.path_energy();
            // against what the body and its contacts hold too: a stiff
            // body barely moving exchanges almost no work, and a fraction
            // of nothing is noise (its energies, two products with the
            // body's matrices, only when the work alone would not do)
            if created > MAX_CREATED * exchanged.max(g.held) {
                let e = body.energies();
                g.held = g.held.max(e.kinetic + e.strain + interface);
            }
            if created > MAX_CREATED * exchanged.max(g.held) {
                if g.over == 0 {
                    (g.created, g.exchanged) = (created, exchanged);
                }
                g.over += 1;
            } else {
                g.over = 0;
            }
            // over the row, the scheme went on creating: a bump of the
            // first contacts stays put, an unstable scheme's creation grows
            let (row_created, row_exchanged) = (created - g.created, exchanged - g.exchanged);
            if g.over >= GUARD_STEPS && row_created > MAX_CREATED * row_exchanged.max(0.0) {
                let (scheme, remedy) = if self.compliant {
                    ("compliant", "use fewer `substeps`, or 1 (the exact step)")
                } else {
                    (
                        "predicted",
                        "use `coupling = \"compliant\"`, fewer `substeps`, or 1 (the exact step)",
                    )
                };
                return Err(CouplingError::Subcycling {
                    body: body.name().to_string(),
                    scheme,
                    step: self.granular.step,
                    time: self.granular.time,
                    created,
                    exchanged,
                    remedy,
                });
            }
        }
        Ok(())
    }

    /// One DEM step of the compliant sub-cycled scheme. At the start of a
    /// body step (`h = nΔt`) each body predicts its step under the held
    /// loads (the last body step's end loads; on another thread while the
    /// discs take their step, except in the very first); the discs take one DEM
    /// step with the disc–body forces of the present state, the boundary
    /// goes to its path at the new fraction `s` of the body step, and the
    /// contacts are solved implicitly ([`implicit`], as in the exact
    /// step) with the boundary `Y(s) + S (L − L_held)`, `S` the
    /// compliance of the body step among the chain points
    /// ([`Continuum::compliant_system`]): the discs never act on a body
    /// that does not give way. Each body step ends with the last DEM
    /// step's loads, at which the body then is exactly where the discs
    /// last saw it (`Y(1) + S (L − L_held)`). Cost: two body solves per
    /// body step (or one, [`Continuum::end_path`] summing kept columns)
    /// and a contact solve over the chain points' compliance per DEM step;
    /// with n = 1 it is the exact step with the contact forces shared by
    /// the segment ends.
    fn step_compliant(&mut self, discs: &mut dyn DiscStep) -> Result<(), CouplingError> {
        if std::mem::take(&mut self.tail_pending) {
            // (`defer` is set by `step_deferring` alone, with `Whole`)
            if self.defer {
                return self.step_compliant_beside();
            }
            workers::awake(|| self.compliant_tail())?;
        }
        // a body step's prediction does not depend on the discs' step:
        // once primed, the two run side by side (as in the exact step)
        let side_by_side = self.sub == 0 && self.primed;
        let h = self.granular.dt * self.substeps as f64;
        workers::awake(|| {
            let t = Instant::now();
            discs.prepare(&mut self.granular);
            let t0 = Instant::now();
            self.timing.dem += (t0 - t).as_secs_f64();
            if self.sub == 0 && !side_by_side {
                for b in &mut self.bodies {
                    b.begin_path(h)?;
                }
            }
            let t1 = Instant::now();
            self.timing.body += (t1 - t0).as_secs_f64();
            if !self.primed {
                self.compliant_contacts(false)?;
                self.primed = true;
            }
            self.timing.transfer += t1.elapsed().as_secs_f64();
            Ok::<_, CouplingError>(())
        })?;
        let t2 = Instant::now();
        let (granular, bodies) = (&mut self.granular, &mut self.bodies);
        let contacts = &self.contacts;
        let ((), (begun, tb)) = rayon::join(
            || discs.step(granular, contacts),
            || {
                let t = Instant::now();
                let r = (bodies.iter_mut())
                    .filter(|_| side_by_side)
                    .try_for_each(|b| b.begin_path(h));
                (r, t.elapsed().as_secs_f64())
            },
        );
        self.timing.body += tb;
        self.timing.dem += (t2.elapsed().as_secs_f64() - tb).max(0.0);
        begun?;
        self.end_compliant_step()
    }

    /// The rest of a compliant DEM step once the discs have taken it: its
    /// contact solve ([`compliant_tail`](Self::compliant_tail)) now, or —
    /// deferring, within a body step — beside the next step's sweep.
    fn end_compliant_step(&mut self) -> Result<(), CouplingError> {
        let beside = self.defer
            && self.sub + 1 < self.substeps
            && self.granular.clumps.is_empty()
            && rayon::current_num_threads() > 1
            && !self.bodies.iter().any(|b| b.grows());
        if beside {
            self.tail_pending = true;
            return Ok(());
        }
        workers::awake(|| self.compliant_tail())
    }

    /// The compliant scheme after the discs' DEM step: the boundary to the
    /// new fraction of the body step and the contacts solved there; at the
    /// end of a body step, the body step's end and the energy guard.
    fn compliant_tail(&mut self) -> Result<(), CouplingError> {
        let t = Instant::now();
        self.begin_tail()?;
        self.compliant_solve(true)?;
        self.timing.transfer += t.elapsed().as_secs_f64();
        if self.sub == self.substeps {
            let tb = Instant::now();
            self.sub = 0;
            self.set_contact_forces();
            for b in &mut self.bodies {
                b.end_path()?;
            }
            self.timing.body += tb.elapsed().as_secs_f64();
            self.guard()?;
        }
        Ok(())
    }

    /// [`compliant_tail`](Self::compliant_tail) up to the contact solve:
    /// the discs near the bodies checked, the boundary to the new fraction,
    /// the candidates (a pass over all discs now and then).
    fn begin_tail(&mut self) -> Result<(), CouplingError> {
        self.check_finite()?;
        self.sub += 1;
        let s = self.sub as f64 / self.substeps as f64;
        for b in &mut self.bodies {
            b.set_path(s);
        }
        self.compliant_grids();
        Ok(())
    }

    /// A compliant step after one that left its contact solve pending
    /// (within a body step): that solve runs on a copy of the discs near
    /// the bodies beside this step's disc sweep, which holds those discs
    /// ([`Granular::hold`]) and advances them once the solve's forces are
    /// known — the same arithmetic in the same order, so bitwise the steps
    /// taken in turn. Its own contact solve is left pending again, or
    /// done, as [`end_compliant_step`](Self::end_compliant_step) decides.
    fn step_compliant_beside(&mut self) -> Result<(), CouplingError> {
        let t = Instant::now();
        workers::awake(|| self.begin_tail())?;
        let (mut whole, near) = self.enter_view();
        let ids: Vec<u32> = near
            .iter()
            .map(|&s| whole.particles.id[s as usize])
            .collect();
        whole.prepare_contacts();
        let mut held: Vec<u32> = ids.iter().map(|&i| whole.slot(i as usize) as u32).collect();
        held.sort_unstable();
        whole.hold(&held);
        let t0 = Instant::now();
        self.timing.transfer += (t0 - t).as_secs_f64();
        let (bad, (solved, ts)) = rayon::join(
            || whole.advance_discs(),
            || {
                let t = Instant::now();
                let r = self.compliant_solve(true);
                (r, t.elapsed().as_secs_f64())
            },
        );
        self.timing.transfer += ts;
        self.timing.dem += (t0.elapsed().as_secs_f64() - ts).max(0.0);
        self.leave_view(whole, &near);
        // the held discs advance with the forces (those of the last
        // state if the solve failed: the run stops with its error)
        let t1 = Instant::now();
        set_contacts_on_discs(&mut self.granular, &self.contacts);
        let bad = self.granular.release_held(&held) | bad;
        self.granular.wall_totals();
        self.granular.finish_step(!bad);
        self.timing.dem += t1.elapsed().as_secs_f64();
        solved?;
        self.end_compliant_step()
    }

    /// Make `granular` a copy of the candidates' discs, in slot order (the
    /// candidate lists renumbered into it), for a contact solve beside the
    /// sweep; returns the whole assembly and the candidates' slots in it.
    fn enter_view(&mut self) -> (Granular, Vec<u32>) {
        let mut near: Vec<u32> = (self.near.iter().flatten())
            .flat_map(|c| c.slots.iter().copied())
            .collect();
        near.sort_unstable();
        near.dedup();
        let g = &self.granular;
        let mut view = (self.view.take()).unwrap_or_else(|| g.with_discs(Default::default()));
        g.particles.select_into(&near, &mut view.particles);
        (view.dt, view.step, view.time) = (g.dt, g.step, g.time);
        let in_view = |s: &mut u32| *s = near.binary_search(s).map_or(u32::MAX, |k| k as u32);
        (self.near.iter_mut().flatten()).for_each(|c| c.slots.iter_mut().for_each(in_view));
        (std::mem::replace(&mut self.granular, view), near)
    }

    /// Undo [`enter_view`](Self::enter_view).
    fn leave_view(&mut self, whole: Granular, near: &[u32]) {
        self.view = Some(std::mem::replace(&mut self.granular, whole));
        (self.near.iter_mut().flatten())
            .for_each(|c| c.slots.iter_mut().for_each(|s| *s = near[*s as usize]));
    }

    /// The compliant scheme's contacts at the present fraction of the body
    /// step (discs at the end of their DEM step): the candidates within a
    /// margin, linearised in the increment of their contact points
    /// relative to the boundary's path, solved with the bodies'
    /// compliance; the forces become the bodies' present loads. With
    /// `advance` false (before the first step) the forces of the present
    /// state, with the discs at rest relative to the body and no history.
    fn compliant_contacts(&mut self, advance: bool) -> Result<(), CouplingError> {
        self.compliant_grids();
        self.compliant_solve(advance)
    }

    /// The compliant scheme's grids and candidates: binned once per body
    /// step, again if a boundary's response to the contacts outgrew the
    /// allowance it was binned with.
    fn compliant_grids(&mut self) {
        let regrid = self.sub <= 1
            || (self.bodies.iter())
                .zip(&self.allow)
                .any(|(b, a)| b.path_correction() > *a);
        self.rebuild_grids(CANDIDATE_MARGIN, regrid);
    }

    /// [`compliant_contacts`](Self::compliant_contacts) on the candidates
    /// found ([`compliant_grids`](Self::compliant_grids)); reads the discs
    /// of `granular` through the candidate lists only.
    fn compliant_solve(&mut self, advance: bool) -> Result<(), CouplingError> {
        let dt = self.granular.dt;
        let nm = self.granular.materials.len();
        let s = self.sub as f64 / self.substeps as f64;
        let ds = 1.0 / self.substeps as f64;
        let mut next = std::mem::take(&mut self.scratch);
        next.clear();
        let w = &mut self.work;
        let p = &self.granular.particles;
        let mut solve_time = 0.0;
        for (b, body) in self.bodies.iter_mut().enumerate() {
            w.lin.clear();
            w.base.clear();
            w.meta.clear();
            w.pts.clear();
            for (c, chain) in body.contact_boundary().iter().enumerate() {
                if chain.segments() == 0 {
                    continue;
                }
                for (d, t) in touching(
                    chain,
                    &self.grids[b][c],
                    &self.near[b][c],
                    p,
                    CANDIDATE_MARGIN,
                ) {
                    let along = advance.then(|| body.path_velocity(c, t.seg, t.s));
                    let laws = (&self.body_laws[..], nm);
                    w.lin.push(linearised(
                        p,
                        &self.contacts,
                        laws,
                        (b, c),
                        d,
                        &t,
                        along,
                        dt,
                    ));
                    w.base.push(t.point);
                    w.pts.push((c, t.seg, t.s));
                    w.meta.push((d, b, c, t.point, t.feature));
                    w.points.push((c, t.material));
                }
            }
            if advance {
                let ts = Instant::now();
                body.compliant_system(s, &w.pts, &mut w.free, &mut w.dense)?;
                let solved =
                    (w.solver).solve_dense(&w.lin, &w.base, &w.free, &w.dense, &mut w.evals);
                self.newton_iterations = unsolved(solved, body.name(), &self.granular)?;
                self.compliance_products += w.solver.products;
                solve_time += ts.elapsed().as_secs_f64();
            } else {
                w.evals.clear();
                w.evals.extend(w.lin.iter().map(|l| l.eval(Vec2::ZERO)));
            }
            w.forces.clear();
            w.forces.extend(w.evals.iter().map(|e| e.g));
            if advance {
                body.compliant_loads(s, ds, &w.pts, &w.forces)?;
            }
            let laws = (&self.body_laws[..], nm);
            closed_contacts(w, laws, &self.contacts, p, advance, dt, &mut next);
            w.points.clear();
        }
        next.sort_by_key(|q| q.key());
        self.scratch = std::mem::replace(&mut self.contacts, next);
        self.timing.contact_solve += solve_time;
        self.timing.transfer -= solve_time;
        Ok(())
    }

    /// The sub-cycled scheme's energy over all bodies since t = 0: what it
    /// created (the bodies received from their end loads more than the
    /// discs did on the predicted paths) and the work exchanged through
    /// the paths ([`Continuum::path_energy`]).
    pub fn subcycling_energy(&self) -> (f64, f64) {
        self.bodies.iter().fold((0.0, 0.0), |(c, w), b| {
            let (c1, w1) = b.path_energy();
            (c + c1, w + w1)
        })
    }

    /// The scheme the model steps with.
    pub fn scheme(&self) -> scheme::Scheme {
        use scheme::Scheme;
        if self.staggered {
            Scheme::Staggered
        } else if self.compliant {
            Scheme::Compliant
        } else if self.substeps > 1 {
            Scheme::Predicted
        } else {
            Scheme::Exact
        }
    }

    /// Whether the last step ended a body step (the bodies' states change
    /// only then; the exact step: every step).
    pub fn at_body_step(&self) -> bool {
        self.sub == 0
    }

    /// The sub-cycled scheme: more than one DEM step per body step, the
    /// boundary on its predicted path (not the staggered transfer).
    pub fn path_scheme(&self) -> bool {
        self.substeps > 1 && !self.staggered
    }

    /// Tell each body the total force of the discs on it at the present
    /// state (`Σ −f` over its contacts, in contact order: the same sum on
    /// any number of threads), for servo drives that measure it.
    fn set_contact_forces(&mut self) {
        for (b, body) in self.bodies.iter_mut().enumerate() {
            let f = self
                .contacts
                .iter()
                .filter(|c| c.body as usize == b)
                .fold(Vec2::ZERO, |s, c| s - c.force);
            body.set_contact_force(f);
        }
    }

    /// The discs that may touch a body ([`Candidates`]) have a finite
    /// state: a non-finite one must not reach a body's step. The others
    /// are the DEM's (`Model::step` checks every disc after each step; a
    /// pass over the whole bed here cost as much as the transfer itself on
    /// large beds).
    fn check_finite(&self) -> Result<(), CouplingError> {
        let p = &self.granular.particles;
        let finite = |d: usize| {
            let (x, v) = (p.pos[d], p.vel[d]);
            (x.x + x.y + v.x + v.y + p.omega[d]).is_finite()
        };
        let near = self.near.iter().flatten().flat_map(|c| &c.slots);
        if near.copied().all(|d| finite(d as usize)) {
            Ok(())
        } else {
            Err(CouplingError::Unstable {
                step: self.granular.step,
                dt_crit: self.granular.critical_step(&self.body_laws).dt,
            })
        }
    }

    /// The implicit scheme's body step ([`implicit`]): contacts of the discs
    /// (already at `t + Δt`) with the bodies' boundaries at `t`, linearised
    /// in the motion of the body points, solved together with each body's
    /// Newmark step; the forces at `t + Δt` are kept for the discs' next
    /// step. With `advance = false` (before the first step) the forces of
    /// the present state are evaluated with the discs at rest relative to
    /// the body and no history, and the bodies do not move.
    fn implicit_contacts(&mut self, advance: bool) -> Result<(), CouplingError> {
        let dt = self.granular.dt;
        let nm = self.granular.materials.len();
        let mut next = std::mem::take(&mut self.scratch);
        next.clear();
        self.rebuild_grids(CANDIDATE_MARGIN, true);
        let w = &mut self.work;
        let p = &self.granular.particles;
        let mut body_time = 0.0;
        let mut solve_time = 0.0;
        for (b, body) in self.bodies.iter_mut().enumerate() {
            w.lin.clear();
            w.points.clear();
            w.base.clear();
            w.meta.clear();
            w.stiffness.clear();
            for (c, chain) in body.contact_boundary().iter().enumerate() {
                if chain.segments() == 0 {
                    continue;
                }
                // candidates within a margin: contacts that close during
                // the step are part of the implicit solve
                for (d, t) in touching(
                    chain,
                    &self.grids[b][c],
                    &self.near[b][c],
                    p,
                    CANDIDATE_MARGIN,
                ) {
                    // the body's own motion over the step is among the unknowns
                    let along = advance.then_some(Vec2::ZERO);
                    let laws = (&self.body_laws[..], nm);
                    let lin = linearised(p, &self.contacts, laws, (b, c), d, &t, along, dt);
                    let law = lin.law;
                    w.lin.push(lin);
                    w.points.push((c, t.material));
                    w.meta.push((d, b, c, t.point, t.feature));
                    // the turn of the normal with the boundary, implicit too
                    if self.geometric_stiffness {
                        let fn0 = law.kn * (t.overlap - CANDIDATE_MARGIN * p.radius[d]);
                        w.stiffness
                            .extend(t.geometric_stiffness(chain, c, p.pos[d], fn0));
                    }
                }
            }
            if advance {
                w.lin.extend(
                    w.stiffness
                        .iter()
                        .map(|k| implicit::Linear::spring(k.c, dt)),
                );
                let tb = Instant::now();
                body.begin_step(&w.points, &w.stiffness, &mut w.base, &mut w.free)?;
                let tc = Instant::now();
                body_time += (tc - tb).as_secs_f64();
                let mut s = body.compliance();
                let solved = w
                    .solver
                    .solve(&w.lin, &w.base, &w.free, &mut s, &mut w.evals);
                self.newton_iterations = unsolved(solved, body.name(), &self.granular)?;
                self.compliance_products += w.solver.products;
                solve_time += tc.elapsed().as_secs_f64();
            } else {
                w.evals.clear();
                w.evals.extend(w.lin.iter().map(|l| l.eval(Vec2::ZERO)));
            }
            w.forces.clear();
            w.forces.extend(w.evals.iter().map(|e| e.g));
            if advance && self.defer && !body.grows() {
                self.pending.push((b, w.forces.clone()));
            } else if advance {
                let tb = Instant::now();
                body.finish_step(&w.forces)?;
                body_time += tb.elapsed().as_secs_f64();
            }
            // the contacts (the geometric stiffness unknowns follow them)
            let laws = (&self.body_laws[..], nm);
            closed_contacts(w, laws, &self.contacts, p, advance, dt, &mut next);
        }
        next.sort_by_key(|q| q.key());
        self.scratch = std::mem::replace(&mut self.contacts, next);
        // counted in `body`, not in `transfer` (the caller times the whole call)
        self.timing.body += body_time;
        self.timing.contact_solve += solve_time;
        self.timing.transfer -= body_time + solve_time;
        Ok(())
    }

    /// Detect disc–body contacts, evaluate them with the DEM contact law,
    /// apply the force to the disc and the reaction to the body.
    fn body_contact_forces(&mut self, path: bool) {
        let dt = self.granular.dt;
        let nm = self.granular.materials.len();
        let share = 1.0 / self.substeps as f64;
        let mut next = std::mem::take(&mut self.scratch);
        next.clear();
        self.loads.clear();
        // on a path the grids of its first DEM step serve the whole body
        // step (binned with the path's extent)
        self.rebuild_grids(0.0, !path || self.sub == 0);
        let p = &self.granular.particles;
        for (b, body) in self.bodies.iter().enumerate() {
            for (c, chain) in body.contact_boundary().iter().enumerate() {
                if chain.segments() == 0 {
                    continue;
                }
                for (d, t) in touching(chain, &self.grids[b][c], &self.near[b][c], p, 0.0) {
                    let (x, r) = (p.pos[d], p.radius[d]);
                    let key = (p.id[d], b as u16, c as u16);
                    let (mut fs, mut mr) = history(&self.contacts, key);
                    let v_h = if path {
                        body.path_velocity(c, t.seg, t.s)
                    } else {
                        body.boundary_velocity(c, t.material)
                    };
                    let law = &self.body_laws[b * nm + p.material[d] as usize];
                    let n = -t.normal; // from the disc towards the body
                    let m_eff = effective_mass(p.inv_mass[d], 0.0);
                    let i = Side {
                        pos: x,
                        vel: p.vel[d],
                        omega: p.omega[d],
                        radius: r,
                    };
                    // the body side is a point, like a DEM wall (arm 0)
                    let j = Side {
                        pos: t.point,
                        vel: v_h,
                        omega: 0.0,
                        radius: 0.0,
                    };
                    let dashpots = law.dashpots(m_eff);
                    let (cf, fn_cap) =
                        contact::evaluate_capped(law, n, t.overlap, &i, &j, dashpots, &mut fs, dt);
                    // rolling resistance on the disc only (the body feels
                    // no moment)
                    let moment = if law.rolling() {
                        body_rolling(law, p, d, fn_cap, &mut mr, dt)
                    } else {
                        mr = 0.0;
                        0.0
                    };
                    let vn = (i.vel - v_h).dot(n);
                    let (fe, ft) = contact::normal_force(law, t.overlap, vn, m_eff);
                    next.push(BodyContact {
                        disc: key.0,
                        body: key.1,
                        chain: key.2,
                        fs,
                        mr,
                        moment,
                        overlap: t.overlap,
                        fn_elastic: fe,
                        fn_total: ft,
                        force: cf.f,
                        point: t.point,
                        normal: n,
                        material: t.material,
                        feature: t.feature,
                    });
                    self.loads.push(Load {
                        slot: d,
                        body: b,
                        chain: c,
                        material: t.material,
                        seg: t.seg,
                        s: t.s,
                        // torque arm r n, the DEM's convention (E12)
                        arm: x + n * r,
                        f: cf.f,
                        moment,
                    });
                }
            }
        }
        for l in &self.loads {
            self.granular.add_external_force(l.slot, l.f, l.arm);
            if l.moment != 0.0 {
                self.granular.add_external_moment(l.slot, l.moment);
            }
            let body = &mut self.bodies[l.body];
            if path {
                body.add_path_load(l.chain, l.seg, l.s, -l.f * share);
            } else {
                body.add_point_load(l.chain, l.material, -l.f * share);
            }
        }
        next.sort_by_key(|q| q.key());
        self.scratch = std::mem::replace(&mut self.contacts, next);
    }

    /// Bin every chain's current segments; a segment within twice the
    /// largest (margin-grown) radius of a centre is in that centre's cell,
    /// so the grid gives the closest feature [`interface::detect`] gives.
    /// Bin each chain's segments ([`SegmentGrid`]) and keep its candidate
    /// discs ([`Candidates`]) for a detection with the contact `margin`.
    ///
    /// With `regrid` false the grids are kept (the sub-cycled scheme bins
    /// a chain once per body step, its reach and box grown by how far the
    /// chain moves on its path, so the grid holds every segment within
    /// reach of a disc at any point of the path); with `regrid` true too
    /// while the chain has moved less than the grid's skin ([`GRID_SKIN`],
    /// [`SegmentGrid::bin`]). The candidates are updated all the same.
    fn rebuild_grids(&mut self, margin: f64, mut regrid: bool) {
        let g = &self.granular;
        let r_max = match self.r_max {
            Some((n, r)) if n == g.grid.rebuilds => r,
            _ => {
                let r = self
                    .radius_bound
                    .unwrap_or_else(|| g.particles.max_radius());
                // a larger disc needs a longer reach
                regrid |= self.r_max.is_none_or(|(_, r0)| r > r0);
                self.r_max = Some((g.grid.rebuilds, r));
                r
            }
        };
        let reach = 2.0 * r_max * (1.0 + margin);
        // the candidates' growth: the DEM's skin, at least a tenth of the
        // largest radius (refreshes every few DEM rebuilds at most)
        let s = g.grid.skin.max(0.1 * r_max);
        self.grids.resize_with(self.bodies.len(), Vec::new);
        self.near.resize_with(self.bodies.len(), Vec::new);
        self.allow.resize(self.bodies.len(), 0.0);
        let bodies = self.bodies.iter().zip(&mut self.allow);
        for (((body, allowance), grids), near) in bodies.zip(&mut self.grids).zip(&mut self.near) {
            let chains = body.contact_boundary();
            grids.resize_with(chains.len(), SegmentGrid::default);
            near.resize_with(chains.len(), Candidates::default);
            for ((chain, sg), cand) in chains.iter().zip(grids.iter_mut()).zip(near.iter_mut()) {
                if regrid || sg.is_empty() {
                    // the compliant scheme's boundary also moves with its
                    // response to the contacts: rebinned when it outgrows
                    // the allowance
                    let allow = if self.compliant {
                        (0.5 * r_max).max(2.0 * body.path_correction())
                    } else {
                        0.0
                    };
                    *allowance = allow;
                    let extent = body.path_extent() + allow;
                    sg.bin(chain, reach + extent, extent, GRID_SKIN * r_max);
                }
                cand.update(
                    &g.particles,
                    sg.chain_lo,
                    sg.chain_hi,
                    1.0 + margin,
                    g.grid.rebuilds,
                    g.max_disp,
                    s,
                );
            }
        }
    }

    /// Contact spring energy of the disc–body contacts, `½k_nδ² + F_s²/(2k_s)`.
    pub fn body_contact_energy(&self) -> f64 {
        self.contacts.iter().map(|q| self.contact_energy(q)).sum()
    }

    /// Spring energy of one disc–body contact ([`body_contact_energy`](Self::body_contact_energy)).
    fn contact_energy(&self, q: &BodyContact) -> f64 {
        let nm = self.granular.materials.len();
        let slot = self.granular.slot(q.disc as usize);
        let law =
            &self.body_laws[q.body as usize * nm + self.granular.particles.material[slot] as usize];
        let mut e = 0.5 * law.kn * q.overlap * q.overlap;
        if law.ks > 0.0 {
            e += 0.5 * q.fs * q.fs / law.ks;
        }
        if q.mr != 0.0 {
            let r = self.granular.particles.radius[slot];
            e += contact::rolling_energy(law, r, q.mr);
        }
        e
    }
}

/// The substeps an automatically chosen sub-cycled scheme with `n`
/// substeps falls back to when its guard stops it at DEM step `step`:
/// the most that are at most half of `n` and divide `step` (so that the
/// bodies' step count stays whole); 1, the exact step, at the end.
pub fn fallback_substeps(n: usize, step: usize) -> usize {
    (1..=n / 2)
        .rev()
        .find(|d| step.is_multiple_of(*d))
        .unwrap_or(1)
}

/// End the pending body steps ([`CoupledModel::step_deferring`]), in body
/// order.
fn finish_pending(
    bodies: &mut [Box<dyn Continuum>],
    pending: &mut Vec<(usize, Vec<Vec2>)>,
) -> Result<(), SolveError> {
    for (b, forces) in pending.drain(..) {
        bodies[b].finish_step(&forces)?;
    }
    Ok(())
}

/// A sub-cycled body stops the run ([`CouplingError::Subcycling`]) once
/// the energy its scheme created exceeds this fraction of the work it
/// exchanged with the discs and of the largest energy it and its contacts
/// have held (kinetic, strain, the disc–body contact springs) at the end
/// of [`GUARD_STEPS`] body steps in a row, and created more than this
/// fraction of the work exchanged over those steps too (checked at every
/// body step, [`CoupledModel::step`]). A contact's
/// first body step of the predicted scheme is off by a quarter of its own
/// work (the end load's extrapolation starts from zero): a bump that stays
/// put while the later work dwarfs it, hence the row of body steps and the
/// creation over the row rather than one step's total.
pub const MAX_CREATED: f64 = 0.02;

/// Body steps in a row above [`MAX_CREATED`] that stop a run.
pub const GUARD_STEPS: u32 = 100;

/// A body's record in the sub-cycling energy guard
/// ([`CoupledModel::step`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GuardRecord {
    /// Body steps in a row above [`MAX_CREATED`].
    pub over: u32,
    /// Energy created when the row began.
    pub created: f64,
    /// Work exchanged when the row began.
    pub exchanged: f64,
    /// The largest energy the body and its contacts have held (kinetic,
    /// strain, the disc–body contact springs), sampled at the body steps
    /// whose creation exceeded [`MAX_CREATED`] of the work exchanged.
    pub held: f64,
}

/// The closed contacts of a solve (`w.evals` over the candidates of
/// `w.meta`; the geometric stiffness unknowns after them are skipped) as
/// [`BodyContact`]s into `next`, with the rolling resistance on the disc
/// (the body feels no moment), limited by the contact's normal force at
/// t + Δt, from the history in `old`. `laws`: the disc–body laws and the
/// number of disc materials ([`CoupledModel::body_laws`]).
fn closed_contacts(
    w: &Work,
    (laws, nm): (&[ContactLaw], usize),
    old: &[BodyContact],
    p: &Particles,
    advance: bool,
    dt: f64,
    next: &mut Vec<BodyContact>,
) {
    for (k, e) in w.evals.iter().enumerate().take(w.meta.len()) {
        if e.regime == 0 {
            continue;
        }
        let (d, b, c, point, feature) = w.meta[k];
        let key = (p.id[d], b as u16, c as u16);
        let law = &laws[b * nm + p.material[d] as usize];
        let (mut mr, mut moment) = (0.0, 0.0);
        if advance && law.rolling() {
            mr = history(old, key).1;
            moment = body_rolling(law, p, d, e.fn_cap, &mut mr, dt);
        }
        next.push(BodyContact {
            disc: key.0,
            body: key.1,
            chain: key.2,
            fs: e.fs,
            mr,
            moment,
            overlap: e.overlap,
            fn_elastic: e.fn_elastic,
            fn_total: e.fn_total,
            force: -e.g,
            point: point + e.w,
            normal: w.lin[k].n,
            material: w.points[k].1,
            feature,
        });
    }
}

/// The skin of the segment grids, in largest disc radii: a chain is binned
/// again once its points have moved this far since it was binned.
const GRID_SKIN: f64 = 0.1;

/// Discs within `(1 + CANDIDATE_MARGIN) r` of a boundary enter the implicit
/// contact solve (as open contacts unless the step closes them).
const CANDIDATE_MARGIN: f64 = 0.1;

/// Discs touching `chain` with their radius enlarged by `margin × r`
/// (bounding-box pruned, then the segments near the disc from `grid`):
/// slot and contact (its overlap includes the margin).
fn touching<'a>(
    chain: &'a BoundaryChain,
    grid: &'a SegmentGrid,
    near: &'a Candidates,
    p: &'a Particles,
    margin: f64,
) -> impl Iterator<Item = (usize, interface::Touch)> + 'a {
    let (lo, hi) = (grid.chain_lo, grid.chain_hi);
    near.slots.iter().filter_map(move |&d| {
        let d = d as usize;
        let (x, rm) = (p.pos[d], p.radius[d] * (1.0 + margin));
        if x.x + rm < lo.x || x.x - rm > hi.x || x.y + rm < lo.y || x.y - rm > hi.y {
            return None;
        }
        interface::detect_near(chain, x, rm, grid.near(x).iter().map(|&i| i as usize))
            .map(|t| (d, t))
    })
}

/// The contact of the disc in `slot` with chain `bc = (body, chain)` at
/// `t`, linearised for the implicit contact solve ([`implicit::Linear`]):
/// the candidate's gap less the margin, its shear history, and its
/// velocity relative to the boundary moving at `along` (`None` before the
/// first step: the discs at rest relative to the body and no history).
#[allow(clippy::too_many_arguments)]
fn linearised(
    p: &Particles,
    contacts: &[BodyContact],
    (laws, nm): (&[ContactLaw], usize),
    (b, c): (usize, usize),
    d: usize,
    t: &interface::Touch,
    along: Option<Vec2>,
    dt: f64,
) -> implicit::Linear {
    let r = p.radius[d];
    let law = laws[b * nm + p.material[d] as usize];
    let (cn, cs) = law.dashpots(effective_mass(p.inv_mass[d], 0.0));
    let n = -t.normal; // from the disc towards the body
    let (vn0, vt0, fs_old) = match along {
        Some(vb) => {
            let v = p.vel[d] - vb;
            let (fs, _) = history(contacts, (p.id[d], b as u16, c as u16));
            (v.dot(n), v.dot(n.perp()) + p.omega[d] * r, fs)
        }
        None => (0.0, 0.0, 0.0),
    };
    implicit::Linear {
        law,
        cn,
        cs,
        n,
        delta0: t.overlap - CANDIDATE_MARGIN * r,
        vn0,
        vt0,
        fs_old,
        dt,
        spring: None,
    }
}

/// Shear force and rolling-spring histories of the contact `key`, 0 for
/// a new contact.
fn history(contacts: &[BodyContact], key: (u32, u16, u16)) -> (f64, f64) {
    contacts
        .binary_search_by(|q| q.key().cmp(&key))
        .map_or((0.0, 0.0), |i| (contacts[i].fs, contacts[i].mr))
}

/// Rolling resistance of a disc–body contact ([`contact::rolling`] with
/// `r̄ = r`, relative rotation `ω_disc`: the body's own local rotation is
/// not counted, as a wall's): the moment on the disc in `slot`, with the
/// history `mr` updated. The body feels no moment — the rolling
/// resistance is a couple on the disc alone, and the body takes only the
/// contact force on its boundary — so this moment does work on the disc
/// only (dissipated at the limit, stored in the rolling spring below it).
fn body_rolling(
    law: &ContactLaw,
    p: &Particles,
    slot: usize,
    fn_cap: f64,
    mr: &mut f64,
    dt: f64,
) -> f64 {
    let r = p.radius[slot];
    let c_r = if law.roll_damping != 0.0 {
        let a = contact::contact_inertia(p.inv_mass[slot], p.inv_inertia[slot], r);
        contact::rolling_dashpot(law, law.roll_kr(r), a, (0.0, 1.0))
    } else {
        0.0
    };
    contact::rolling(law, r, fn_cap, p.omega[slot], c_r, mr, dt)
}

#[cfg(test)]
mod tests {
    use super::fallback_substeps;

    /// At most half, dividing the steps taken, 1 (the exact step) at the end.
    #[test]
    fn a_fallback_takes_at_most_half_the_substeps_that_divide_the_steps() {
        for (n, step, to) in [
            (10, 1000, 5),
            (5, 500, 2),
            (6, 606, 3),
            (6, 6 * 101 * 7, 3),
            (5, 505, 1),
            (4, 400, 2),
            (2, 200, 1),
            (3, 300, 1),
        ] {
            assert_eq!(
                fallback_substeps(n, step),
                to,
                "{n} substeps at step {step}"
            );
        }
    }
}
