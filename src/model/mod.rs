//! The model a scenario describes, ready to step: continuum bodies, a
//! granular assembly, or both coupled. This is the library's state API:
//! [`Model::step`], [`Model::run_until`], and read-only views of discs,
//! walls, bodies and contacts. Build one with
//! [`Scenario::build`](crate::scenario::Scenario::build) (from a file, a
//! string, or a scenario assembled in code).

pub mod body;
pub mod contacts;
pub mod probe;
pub mod stability;
pub mod state;
pub mod traction;

use crate::coupling::{CoupledModel, CouplingError};
use crate::dem::{DemError, Granular};
use crate::efg::boundary::EfgContinuum;
use crate::fem::FemContinuum;
use body::{Body, BodyRef};
pub use contacts::{ContactKind, ContactView};
pub use probe::Probe;
pub use stability::Instability;
pub use state::{ModelState, STATE_FORMAT_VERSION, SystemState};
use std::ops::ControlFlow;

/// Why a step failed.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A body's solve or step failed.
    #[error(transparent)]
    Body(#[from] body::BodyError),
    /// The DEM failed (non-finite discs).
    #[error(transparent)]
    Dem(#[from] DemError),
    /// A coupled step failed.
    #[error(transparent)]
    Coupling(#[from] CouplingError),
    /// The state stopped being physical (exit code 3 of `efgdem run`).
    #[error("{0}")]
    Unstable(Box<Instability>),
    /// A saved state does not fit the model ([`Model::restore_state`]).
    #[error("cannot restore the state: {0}")]
    State(#[from] crate::continuum::StateError),
    /// A static model has no time steps (call [`Model::solve_static`]).
    #[error("a static analysis has no time steps; call solve_static()")]
    Static,
    /// A call that does not fit the model: a static solve of a model with
    /// discs, a non-finite end time.
    #[error("{0}")]
    Usage(String),
}

impl ModelError {
    /// A numerical failure of the run (exit code 3 of `efgdem run`): the
    /// state stopped being physical, a sub-cycled body created energy, a
    /// contact solve did not converge.
    pub fn is_numerical(&self) -> bool {
        use crate::coupling::CouplingError as C;
        matches!(
            self,
            ModelError::Unstable(_)
                | ModelError::Coupling(
                    C::Unstable { .. } | C::Subcycling { .. } | C::NotConverged { .. }
                )
        )
    }
}

/// What is simulated.
pub enum System {
    /// Continuum bodies only; `dynamic` false: a static analysis.
    Continuum {
        /// The bodies, in scenario order.
        bodies: Vec<Body>,
        /// Time-stepped (Newmark) rather than one static solve.
        dynamic: bool,
    },
    /// Discs and walls.
    Granular(Box<Granular>),
    /// Bodies and discs, coupled through disc–boundary contacts.
    Coupled(Box<CoupledModel>),
}

/// A model ready to run.
pub struct Model {
    /// The bodies and/or discs being simulated.
    pub system: System,
    /// Time step: the DEM step in granular and coupled runs, the bodies'
    /// step in continuum runs (0 for a static analysis).
    pub dt: f64,
    /// Steps the scenario asks for (`steps`, or `end_time / dt`).
    pub steps: usize,
    /// Steps taken so far.
    pub step: usize,
}

impl Model {
    /// Advance one time step, then check that the state is still physical
    /// ([`stability::check`]: finite, no disc moving more than its radius
    /// per step); an instability is [`ModelError::Unstable`] with a
    /// diagnosis and a suggested time step.
    pub fn step(&mut self) -> Result<(), ModelError> {
        let r = self.step_deferring();
        r.and(self.settle())
    }

    /// [`step`](Self::step) for a driver that reads no body before the
    /// next step (e.g. between two outputs): an exact coupled step may leave
    /// the end of its body step (one solve per body and the commit) to the
    /// next step, which does it beside the discs' step on another thread
    /// ([`CoupledModel::step_deferring`]) — the same arithmetic, so the same
    /// results. The bodies hold the previous step's state until then or
    /// until [`settle`](Self::settle); the stability check of the bodies
    /// waits for it too.
    pub fn step_deferring(&mut self) -> Result<(), ModelError> {
        let r = match &mut self.system {
            System::Continuum { dynamic: false, .. } => return Err(ModelError::Static),
            System::Continuum { bodies, .. } => bodies
                .iter_mut()
                .try_for_each(|b| b.advance())
                .map_err(ModelError::from),
            System::Granular(g) => {
                g.step();
                Ok(())
            }
            System::Coupled(m) => m.step_deferring().map_err(ModelError::from),
        };
        self.step += 1;
        // the inner checks only see non-finite discs: diagnose here
        stability::check(self).map_err(|e| ModelError::Unstable(Box::new(e)))?;
        r
    }

    /// End the body steps [`step_deferring`](Self::step_deferring) left
    /// pending, and check the bodies' state; nothing to do otherwise.
    pub fn settle(&mut self) -> Result<(), ModelError> {
        let System::Coupled(m) = &mut self.system else {
            return Ok(());
        };
        if m.is_settled() {
            return Ok(());
        }
        m.settle()?;
        stability::check(self).map_err(|e| ModelError::Unstable(Box::new(e)))
    }

    /// Warnings since the last call: e.g. an automatically chosen
    /// sub-cycled scheme given up for fewer substeps or the exact step
    /// ([`crate::coupling::CoupledModel::fall_back`]).
    pub fn take_notices(&mut self) -> Vec<String> {
        match &mut self.system {
            System::Coupled(m) => std::mem::take(&mut m.notices),
            _ => Vec::new(),
        }
    }

    /// Step until the time reaches `t_end` (within half a step), calling
    /// `after` after every step; `after` may stop the run early by
    /// returning [`ControlFlow::Break`]. Returns the number of steps taken.
    pub fn run_until(
        &mut self,
        t_end: f64,
        mut after: impl FnMut(&Model) -> ControlFlow<()>,
    ) -> Result<usize, ModelError> {
        if !t_end.is_finite() {
            return Err(ModelError::Usage(format!(
                "run until t = {t_end}: the end time must be a finite number"
            )));
        }
        let mut n = 0;
        while self.time() + 0.5 * self.dt < t_end {
            self.step()?;
            n += 1;
            if after(self).is_break() {
                break;
            }
        }
        Ok(n)
    }

    /// Solve the static problem of every body (continuum static analysis).
    /// A model with discs has none ([`ModelError::Usage`]).
    pub fn solve_static(&mut self) -> Result<(), ModelError> {
        let System::Continuum { bodies, .. } = &mut self.system else {
            return Err(ModelError::Usage(
                "a model with discs has no static solve (only continuum bodies have one); advance it with step() or run()".into(),
            ));
        };
        for b in bodies {
            b.solve_static()?;
        }
        Ok(())
    }

    /// The granular assembly, taken out of a granular model.
    pub fn into_granular(self) -> Option<Granular> {
        match self.system {
            System::Granular(g) => Some(*g),
            _ => None,
        }
    }

    /// The coupled model, taken out of a coupled model.
    pub fn into_coupled(self) -> Option<CoupledModel> {
        match self.system {
            System::Coupled(m) => Some(*m),
            _ => None,
        }
    }

    /// Present time.
    pub fn time(&self) -> f64 {
        match &self.system {
            System::Continuum { bodies, .. } => bodies.first().map_or(0.0, |b| b.time()),
            System::Granular(g) => g.time,
            System::Coupled(m) => m.granular.time,
        }
    }

    /// The granular assembly (discs, walls, disc–disc and disc–wall
    /// contacts), if there is one. Discs are stored in *slots* renumbered
    /// in space-filling order; `particles.id[slot]` is the scenario id and
    /// [`Granular::slot`] finds the slot of an id.
    pub fn granular(&self) -> Option<&Granular> {
        match &self.system {
            System::Continuum { .. } => None,
            System::Granular(g) => Some(g),
            System::Coupled(m) => Some(&m.granular),
        }
    }

    /// The coupled model (disc–body contacts, timing), if coupled.
    pub fn coupled(&self) -> Option<&CoupledModel> {
        match &self.system {
            System::Coupled(m) => Some(m),
            _ => None,
        }
    }

    /// The coupled model, to change before the first step (e.g. its
    /// scheme, [`crate::coupling::scheme::apply`]).
    pub fn coupled_mut(&mut self) -> Option<&mut CoupledModel> {
        match &mut self.system {
            System::Coupled(m) => Some(m),
            _ => None,
        }
    }

    /// Number of continuum bodies.
    pub fn n_bodies(&self) -> usize {
        match &self.system {
            System::Continuum { bodies, .. } => bodies.len(),
            System::Granular(_) => 0,
            System::Coupled(m) => m.bodies.len(),
        }
    }

    /// Body `i` (scenario order): sample its true fields, nodes, state.
    pub fn body(&self, i: usize) -> BodyRef<'_> {
        match &self.system {
            System::Continuum { bodies, .. } => bodies[i].view(),
            System::Granular(_) => panic!("a granular model has no bodies"),
            System::Coupled(m) => coupled_body(m, i),
        }
    }

    /// Every contact of the present state (disc–disc, disc–wall, disc–body)
    /// with its forces.
    pub fn contacts(&self) -> Vec<ContactView> {
        contacts::all(self.granular(), self.coupled())
    }

    /// The value of a bound probe now.
    pub fn probe(&self, p: &Probe) -> f64 {
        probe::value(p, self.granular(), self.coupled(), |i| self.body(i))
    }
}

/// The body behind `m.bodies[i]` (EFG or FE, as the scenario builds them).
pub fn coupled_body(m: &CoupledModel, i: usize) -> BodyRef<'_> {
    let c = m.bodies[i].as_any();
    if let Some(c) = c.downcast_ref::<EfgContinuum>() {
        BodyRef::Efg(&c.body)
    } else if let Some(c) = c.downcast_ref::<FemContinuum>() {
        BodyRef::Fem(&c.body)
    } else {
        unreachable!("coupled bodies are EFG or FE bodies")
    }
}
