//! The evolving state of a [`CoupledModel`], for checkpoint/restart: the
//! discs' ([`GranularState`]), each body's through
//! [`Continuum::save_state`](crate::continuum::Continuum::save_state), the
//! disc–body contacts with their histories and last forces (the implicit
//! scheme applies them to the discs at the next step), and the scheme's
//! counters. Not saved: the segment grids and the contact solve's work
//! arrays (rebuilt or rewritten at every step), and the timing.

use super::{BodyContact, CoupledModel};
use crate::continuum::{BodyState, StateError};
use crate::dem::state::GranularState;

/// Everything that changes while a [`CoupledModel`] steps.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CoupledState {
    /// The discs, walls and their contacts.
    pub granular: GranularState,
    /// Each body's state, in scenario order.
    pub bodies: Vec<BodyState>,
    /// The live disc–body contacts, sorted by `(disc, body, chain)`.
    pub contacts: Vec<BodyContact>,
    /// DEM steps done in the present body step (sub-cycling).
    pub sub: usize,
    /// The disc–body forces of the present state are known (implicit
    /// scheme; false only before the first step).
    pub primed: bool,
    /// Newton iterations of the last contact solve (diagnostics).
    pub newton_iterations: usize,
    /// Products `S x` of all contact solves so far (diagnostics).
    pub compliance_products: usize,
    /// Per body, the sub-cycling energy guard's record.
    pub over: Vec<super::GuardRecord>,
    /// The automatically chosen sub-cycled scheme given up for the exact
    /// step, if it was ([`CoupledModel::fall_back`]).
    pub fallback: Option<super::Fallback>,
}

impl CoupledModel {
    /// Everything that changes while the model steps ([`CoupledState`]).
    /// Call between steps.
    pub fn save_state(&self) -> CoupledState {
        CoupledState {
            granular: self.granular.save_state(),
            bodies: self.bodies.iter().map(|b| b.save_state()).collect(),
            contacts: self.contacts.clone(),
            sub: self.sub,
            primed: self.primed,
            newton_iterations: self.newton_iterations,
            compliance_products: self.compliance_products,
            over: self.over.clone(),
            fallback: self.fallback.clone(),
        }
    }

    /// Restore a [`save_state`](Self::save_state) onto a model built from
    /// the same scenario. A state of another model (disc, wall or body
    /// counts, body names or DOFs, contacts out of range) is refused; when
    /// a body refuses its state, the discs and the bodies before it are
    /// already restored (see [`crate::model::Model::restore_state`], which
    /// puts the model back as it was).
    pub fn restore_state(&mut self, s: &CoupledState) -> Result<(), StateError> {
        let nb = self.bodies.len();
        if s.bodies.len() != nb {
            return Err(StateError::new(format!(
                "the saved state has {} bodies, the model {nb}",
                s.bodies.len()
            )));
        }
        // the run had fallen back to fewer substeps (or the exact step): so
        // does this model, unless it has gone further
        let to = |f: &Option<super::Fallback>| f.as_ref().map_or(usize::MAX, |f| f.to);
        match (&s.fallback, to(&s.fallback).cmp(&to(&self.fallback))) {
            (Some(f), std::cmp::Ordering::Less) => self
                .fall_back(f.clone())
                .map_err(|e| StateError::new(e.to_string()))?,
            (_, std::cmp::Ordering::Greater) => {
                return Err(StateError::new(
                    "the saved state is of a sub-cycled scheme this model has given up for shorter body steps; restore it into a model built anew",
                ));
            }
            _ => {}
        }
        if s.sub >= self.substeps {
            return Err(StateError::new(format!(
                "the saved state is at DEM step {} of a body step of {}",
                s.sub, self.substeps
            )));
        }
        let n = s.granular.id.len();
        let fits = |q: &BodyContact| {
            (q.disc as usize) < n
                && (q.body as usize) < nb
                && (q.chain as usize) < self.bodies[q.body as usize].contact_boundary().len()
        };
        if !s.contacts.iter().all(fits) || !s.contacts.windows(2).all(|w| w[0].key() < w[1].key()) {
            return Err(StateError::new(
                "the saved disc–body contacts are not sorted or name a missing disc, body or chain",
            ));
        }
        self.granular.restore_state(&s.granular)?;
        for (b, bs) in self.bodies.iter_mut().zip(&s.bodies) {
            b.restore_state(bs)?;
        }
        self.contacts.clone_from(&s.contacts);
        self.sub = s.sub;
        self.primed = s.primed;
        self.newton_iterations = s.newton_iterations;
        self.compliance_products = s.compliance_products;
        self.over.clone_from(&s.over);
        Ok(())
    }
}
