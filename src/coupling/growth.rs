//! Crack growth in a coupled run: after a body step a body whose cracks
//! grew has new contact chains (the faces run to the new tips), so the
//! disc–body detection is set up again for it and the disc–body forces of
//! the present state are evaluated again on the new boundary at once.
//!
//! **The energy.** The new pieces open against the disc contacts, the
//! discs held in place (no time passes): the body relaxes with the
//! contacts' normal springs in its matrix
//! ([`HeldContact`], [`EfgBody::grow_under`](crate::efg::EfgBody::grow_under)).
//! The energy the growth took is the drop of the body's stored energy less
//! its loads' work plus the drop of the energy of the contacts' normal
//! springs, these measured on the contacts evaluated again: the body books
//! its linearised part, and the rest (the springs' exact energy against
//! their linearisation, and the points that moved on the new boundary) is
//! booked here, so in a frictionless run the energy account closes across
//! a growth to round-off. The contacts evaluated again start without shear
//! or rolling history (evaluated at rest relative to the body); what those
//! springs held counts as dissipated, not as fracture.

use super::{CoupledModel, CouplingError};
use crate::continuum::HeldContact;

impl CoupledModel {
    /// Grow the bodies' cracks where due ([`Continuum::grow`](crate::continuum::Continuum::grow)),
    /// after an exact body step; a body that grew has its segment grid and
    /// candidate discs made again, and the forces of the present state are
    /// evaluated again on its new boundary (module doc).
    pub(super) fn grow_bodies(&mut self) -> Result<(), CouplingError> {
        let mut grown = Vec::new();
        for b in 0..self.bodies.len() {
            if !self.bodies[b].growth_due() {
                continue;
            }
            let held = self.held_contacts(b);
            let before = self.energy_less_work(b);
            if self.bodies[b].grow(&held)? {
                if let Some(g) = self.grids.get_mut(b) {
                    g.clear();
                }
                if let Some(n) = self.near.get_mut(b) {
                    n.clear();
                }
                grown.push((b, before));
            }
        }
        if grown.is_empty() {
            return Ok(());
        }
        self.implicit_contacts(false)?;
        self.primed = true;
        for (b, before) in grown {
            let taken = before - self.energy_less_work(b);
            self.bodies[b].book_fracture(taken);
        }
        Ok(())
    }

    /// The disc contacts on body `b` as springs holding it while it grows:
    /// their present forces, and the normal stiffness of the closed ones.
    fn held_contacts(&self, b: usize) -> Vec<HeldContact> {
        let nm = self.granular.materials.len();
        let p = &self.granular.particles;
        self.contacts
            .iter()
            .filter(|q| q.body as usize == b)
            .map(|q| {
                let slot = self.granular.slot(q.disc as usize);
                let law = &self.body_laws[b * nm + p.material[slot] as usize];
                HeldContact {
                    point: q.material,
                    force: -q.force,
                    normal: q.normal,
                    kn: if q.overlap > 0.0 { law.kn } else { 0.0 },
                }
            })
            .collect()
    }

    /// Body `b`'s stored energy (kinetic, strain, penalty) and that of the
    /// normal springs of its disc contacts, `½ k_n δ²`, less the work of its
    /// own loads and the energy its growth took so far. (The contacts'
    /// shear and rolling springs do not hold the body as it grows; the
    /// contacts evaluated again start them afresh, and what they held
    /// counts as dissipated.)
    fn energy_less_work(&self, b: usize) -> f64 {
        let e = self.bodies[b].energies();
        let normal: f64 = self
            .contacts
            .iter()
            .filter(|q| q.body as usize == b && q.overlap > 0.0)
            .map(|q| 0.5 * q.fn_elastic * q.overlap)
            .sum();
        e.kinetic + e.strain + e.penalty + normal - e.work + e.fracture
    }
}
