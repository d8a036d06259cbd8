//! The evolving state of a continuum body, for checkpoint/restart: what
//! changes while a body steps (Newmark `U`, `U̇`, `Ü`, clock, pending point
//! loads, work counters, and which DOFs its boundary Green matrix holds),
//! but not what its build computes again deterministically from the same
//! parameters (matrices, factorisations, shape functions).
//!
//! A state is restored onto a body freshly built from the same parameters
//! ([`Continuum::restore_state`](super::Continuum::restore_state)); the
//! body then steps bitwise as the body the state was saved from.

use super::newmark::State;

/// Why a saved state does not fit the model or body it is restored onto.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct StateError(pub String);

impl StateError {
    /// An error with the message `m`.
    pub fn new(m: impl Into<String>) -> Self {
        StateError(m.into())
    }
}

/// What changes while a continuum body (EFG or FE) steps.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyState {
    /// The body's name (checked on restore).
    pub name: String,
    /// `U`, `U̇`, `Ü` (nodal parameters).
    pub state: State,
    /// Steps done.
    pub step: usize,
    /// Time reached.
    pub time: f64,
    /// Point loads accumulated for the next step (non-zero between steps
    /// only with sub-cycling, where the discs' forces of several DEM steps
    /// are summed before a body step).
    pub f_point: Vec<f64>,
    /// Work done by the moving edges since t = 0 (energy account).
    pub motion_work: f64,
    /// The running state of each drive (prescribed components that change
    /// in time: position, velocity, servo integral, measured force), in
    /// the body's drive order.
    pub drives: Vec<DriveState>,
    /// Work done since t = 0 by the loads that change in time (tractions
    /// and point loads with a `table`), trapezoidal in time.
    pub load_work: f64,
    /// FE: the support reaction of each prescribed DOF at the last step
    /// (the trapezoidal work of moving edges uses it); empty for EFG.
    pub reactions: Vec<f64>,
    /// The contact boundary's compliance state, for a body the coupling
    /// drives ([`WithBoundary`](super::WithBoundary)); `None` for a body
    /// of a continuum-only model.
    pub boundary: Option<BoundaryState>,
    /// The cracks of an EFG body as they have grown and the friction of
    /// their faces (`None`: a body without cracks): a restart rebuilds
    /// the body with them.
    pub cracks: Option<CrackState>,
}

/// The grown cracks of a body (checkpointed).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CrackState {
    /// Each crack's polyline now.
    pub cracks: Vec<crate::geom::crack::Crack>,
    /// Growth increments so far per crack `[first end, last end]`.
    pub increments: Vec<[usize; 2]>,
    /// Energy released by growth so far.
    pub fracture_energy: f64,
    /// The shear force of each pair of crack faces in contact (its
    /// friction's history; 0 for an open pair).
    pub face_shear: Vec<f64>,
}

/// The running state of a drive (checkpointed).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DriveState {
    /// Position `d(n)` at the body's present step.
    pub d: f64,
    /// Position `d(n+1)` decided for the step under way (equal to `d`
    /// between steps until [`Drive::decide`](super::Drive::decide)).
    pub d_next: f64,
    /// Velocity of the last decided step, `(d(n+1) − d(n))/Δt`.
    pub velocity: f64,
    /// Integral velocity of a servo with integral action.
    pub integral: f64,
    /// The force measured when the last step was decided (the servo's
    /// measure, or the edge's reaction for a drive without servo).
    pub measured: f64,
}

impl DriveState {
    /// The position now or at the next step.
    pub fn position(&self, when: super::drive::When) -> f64 {
        match when {
            super::drive::When::Now => self.d,
            super::drive::When::Next => self.d_next,
        }
    }
}

/// The compliance state of a body's contact boundary.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoundaryState {
    /// The body fell back to (or was set to) two solves per contact
    /// ([`ComplianceMode::Direct`](super::ComplianceMode::Direct)).
    pub direct: bool,
    /// The boundary Green matrix's DOFs as it was extended, batch by batch
    /// ([`BoundaryGreen::batches`](super::compliance::BoundaryGreen::batches));
    /// `None` when it was not built yet. Replayed on restore: its order
    /// decides the order of the sums of the contact solve.
    pub green: Option<Vec<Vec<u32>>>,
    /// The sub-cycled scheme's boundary path and loads
    /// ([`Path`](super::Path)).
    pub path: super::Path,
}

impl BodyState {
    /// Check that this state fits a body named `name` with `dofs` unknowns
    /// and `reactions` prescribed DOFs with reactions.
    pub fn check(&self, name: &str, dofs: usize, reactions: usize) -> Result<(), StateError> {
        self.check_drives(name, None)?;
        if self.name != name {
            return Err(StateError::new(format!(
                "the saved body `{}` is restored onto body `{name}`",
                self.name
            )));
        }
        let s = &self.state;
        for (what, len) in [
            ("U", s.u.len()),
            ("U̇", s.v.len()),
            ("Ü", s.a.len()),
            ("point loads", self.f_point.len()),
        ] {
            if len != dofs {
                return Err(StateError::new(format!(
                    "body `{name}`: the saved {what} has {len} DOFs, the body {dofs}"
                )));
            }
        }
        if self.reactions.len() != reactions {
            return Err(StateError::new(format!(
                "body `{name}`: {} saved support reactions, the body has {reactions} prescribed DOFs",
                self.reactions.len()
            )));
        }
        Ok(())
    }

    /// Check that this state has `drives` drives (when given).
    pub fn check_drives(&self, name: &str, drives: Option<usize>) -> Result<(), StateError> {
        match drives {
            Some(n) if n != self.drives.len() => Err(StateError::new(format!(
                "body `{name}`: {} saved drives, the body has {n}",
                self.drives.len()
            ))),
            _ => Ok(()),
        }
    }
}
