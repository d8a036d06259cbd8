//! The FE body as seen by the coupling: [`FemContinuum`], the body with
//! contact chains along its contact edges (element edges refined
//! `contact_refine` times) at their displaced positions. The element's
//! bilinear shape functions `N_a(x_H)` give the contact-point displacement
//! and velocity and distribute the reaction (Eq. 46), so the pair is
//! work-consistent, as for EFG (E7). Point forces put no load on prescribed
//! DOFs: that share goes to the support
//! ([`Newmark::set_imposed`]).

use super::FemError;
use super::body::FemBody;
use crate::continuum::newmark::{Newmark, State};
use crate::continuum::{
    BodyEnergies, BodyState, ContactBody, Row, StateError, WithBoundary, add_dof_load,
};
use crate::geom::Vec2;

/// A [`FemBody`] with its contact boundary: what the coupling drives.
pub type FemContinuum = WithBoundary<FemBody>;

impl ContactBody for FemBody {
    type Error = FemError;
    fn name(&self) -> &str {
        &self.name
    }
    fn grid(&self) -> (Vec2, Vec2, [usize; 2]) {
        (self.origin, self.size, self.grid)
    }
    /// The shape functions `N_a(x)` of the element containing `x`.
    fn row(&self, x: Vec2) -> Result<Row, FemError> {
        FemBody::row(self, x)
    }
    fn start_dynamic(&mut self, dt: f64) -> Result<(), FemError> {
        FemBody::start_dynamic(self, dt)
    }
    fn retime(&mut self, dt: f64, scale: (usize, usize)) -> Result<(), FemError> {
        FemBody::retime(self, dt, scale)
    }
    fn state(&self) -> &State {
        &self.state
    }
    fn add_point_load_row(&mut self, row: &[(u32, f64)], f: Vec2) {
        FemBody::add_point_load_row(self, row, f);
    }
    fn add_dof_loads(&mut self, row: &[(usize, f64)], g: f64) {
        add_dof_load(&mut self.f_point, row, g);
    }
    fn set_contact_force(&mut self, f: Vec2) {
        self.contact_force = f;
    }
    fn predict(&mut self) -> Result<&mut Newmark, FemError> {
        FemBody::predict(self)
    }
    fn newmark_mut(&mut self) -> Option<&mut Newmark> {
        FemBody::newmark_mut(self)
    }
    fn commit(&mut self) -> Result<(), FemError> {
        FemBody::commit(self)
    }
    fn save_state(&self) -> BodyState {
        FemBody::save_state(self)
    }
    fn restore_state(&mut self, s: &BodyState) -> Result<(), StateError> {
        FemBody::restore_state(self, s)
    }
    fn energies(&self) -> BodyEnergies {
        BodyEnergies {
            kinetic: self.kinetic_energy(),
            strain: self.strain_energy(),
            penalty: 0.0,
            work: self.work(),
            fracture: 0.0,
        }
    }
}
