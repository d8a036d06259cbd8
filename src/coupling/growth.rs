//! Crack growth in a coupled run: after a body step a body whose cracks
//! grew has new contact chains (the faces run to the new tips), so the
//! disc–body detection is set up again for it and the disc–body forces of
//! the present state are evaluated again on the new boundary before the
//! next step.

use super::{CoupledModel, CouplingError};
use crate::geom::Vec2;

impl CoupledModel {
    /// Grow the bodies' cracks where due ([`Continuum::grow`](crate::continuum::Continuum::grow)),
    /// after an exact body step; a body that grew has its segment grid and
    /// candidate discs made again, and the forces of the present state are
    /// evaluated again at the next step (the contacts keep their shear
    /// histories, keyed by disc and chain).
    pub(super) fn grow_bodies(&mut self) -> Result<(), CouplingError> {
        for b in 0..self.bodies.len() {
            // the contact forces on the body hold it while its cracks open
            let loads: Vec<(Vec2, Vec2)> = self
                .contacts
                .iter()
                .filter(|q| q.body as usize == b)
                .map(|q| (q.material, -q.force))
                .collect();
            if self.bodies[b].grow(&loads)? {
                if let Some(g) = self.grids.get_mut(b) {
                    g.clear();
                }
                if let Some(n) = self.near.get_mut(b) {
                    n.clear();
                }
                self.primed = false;
            }
        }
        Ok(())
    }
}
