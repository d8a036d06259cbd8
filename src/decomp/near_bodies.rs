//! Coupled (continuum + discs) models on ranks: the bodies replicated on
//! every rank, the discs near them copied to every rank each step.
//!
//! Each rank holds the whole [`CoupledModel`] except its discs: every
//! body, the disc–body contacts and their histories, and in
//! [`CoupledModel::granular`] a *view* — the discs whose centres lie within
//! a pad of a body's contact chains, in key order (the whole's slot order),
//! with their present state. The view is built the same on every rank (the
//! owners' records merged in key order), so every rank detects the same
//! contacts in the same order, solves the same implicit contact problem
//! and steps bitwise the same bodies; no force is sent back. The discs
//! themselves step in the rank's part ([`Decomposed`]), with the
//! disc–body forces acting on those the rank holds.
//!
//! Why replicated bodies rather than bodies owned by one rank: the exact
//! and the compliant schemes solve the contacts and the bodies together
//! once per DEM step, and that solve needs the discs near the bodies at the
//! end of the step. Owning the bodies on one rank would take the same
//! gather plus a scatter of the forces back to the owners, and leave the
//! other ranks idle during the body solve. Replicating costs one
//! all-gather per step of the discs near the bodies (a few hundred to a few
//! thousand records of about 120 bytes) and the body solve on every rank,
//! which is a serial cost on one rank as well.
//!
//! The pad covers where a disc can touch a chain until the next view: the
//! contact margin on the largest radius, the skin, and the chain's motion
//! on its sub-cycled path ([`Continuum::path_extent`],
//! [`Continuum::path_correction`]).

use super::comm::{Pack, Unpack};
use super::{Decomposed, Src, pack_disc, regather, unpack_disc};
use crate::continuum::Continuum;
use crate::coupling::{BodyContact, CoupledModel, DiscStep, set_contacts_on_discs};
use crate::dem::Granular;
use crate::dem::broadphase::centre_bounds;
use crate::dem::particles::GHOST;
use crate::geom::Vec2;

/// The discs of a coupled model stepped on ranks ([module docs](self)).
pub struct NearBodies {
    /// This rank's part of the assembly.
    pub d: Decomposed,
    /// Boxes around the contact chains, grown by their pad.
    zone: Vec<(Vec2, Vec2)>,
    /// A condition to be or-ed over the ranks at the next step (e.g. a
    /// stop request).
    pub flag: bool,
    /// The last step's outcome: every disc passed the step check, and the
    /// flag of any rank ([`Decomposed::step`]).
    pub outcome: (bool, bool),
}

impl NearBodies {
    /// Divide the discs of `m` (the whole model, the same on every rank)
    /// over the ranks of `d`, and make `m.granular` the view of the discs
    /// near its bodies (collective). Returns the whole assembly.
    pub fn new(d: Decomposed, m: &mut CoupledModel) -> (NearBodies, Granular) {
        let mut nb = NearBodies {
            d,
            zone: Vec::new(),
            flag: false,
            outcome: (true, false),
        };
        nb.d.sum_every_wall();
        m.radius_bound = Some(nb.d.max_radius());
        let view = nb.d.part.with_discs(Default::default());
        let whole = std::mem::replace(&mut m.granular, view);
        nb.set_zone(&m.bodies);
        nb.view(&mut m.granular);
        (nb, whole)
    }

    /// The boxes of the bodies' contact chains at the present state, grown
    /// by their pad: call before each step.
    pub fn set_zone(&mut self, bodies: &[Box<dyn Continuum>]) {
        let g = &self.d.part;
        let base = 2.0 * self.d.max_radius() + 2.0 * g.grid.skin;
        self.zone.clear();
        for b in bodies {
            let pad = base + 2.0 * (b.path_extent() + b.path_correction());
            for c in b
                .contact_boundary()
                .iter()
                .filter(|c| !c.current.is_empty())
            {
                let (lo, hi) = centre_bounds(&c.current);
                let e = Vec2::new(pad, pad);
                self.zone.push((lo - e, hi + e));
            }
        }
    }

    fn in_zone(&self, q: Vec2, r: f64) -> bool {
        self.zone.iter().any(|(lo, hi)| {
            q.x + r >= lo.x && q.x - r <= hi.x && q.y + r >= lo.y && q.y - r <= hi.y
        })
    }

    /// Make `g` the view of the discs near the bodies at the present state
    /// (collective): every rank's owned discs in the zone, in key order.
    pub fn view(&mut self, g: &mut Granular) {
        let part = &self.d.part;
        let p = &part.particles;
        let keys = self.d.keys();
        let mut mine = Pack::default();
        let mut own = Vec::new();
        for (s, &key) in keys.iter().enumerate() {
            if p.fixity[s] & GHOST == 0 && self.in_zone(p.pos[s], p.radius[s]) {
                pack_disc(&mut mine, p, s, key, true);
                own.push((key, Src::Old(s as u32)));
            }
        }
        let all = self.d.comm().all_gather(&mine.0);
        let me = self.d.comm().rank();
        let mut records = Vec::new();
        for (r, b) in all.iter().enumerate() {
            if r == me {
                continue;
            }
            let mut u = Unpack(b);
            while !u.is_empty() {
                let rec = unpack_disc(&mut u);
                own.push((rec.key, Src::Got(records.len() as u32)));
                records.push(rec);
            }
        }
        own.sort_unstable_by_key(|e| e.0);
        let sources: Vec<Src> = own.iter().map(|e| e.1).collect();
        let mut np = crate::dem::particles::Particles::default();
        regather(&mut np, Some(p), &sources, &records, self.d.total());
        np.fixity.iter_mut().for_each(|f| *f &= !GHOST);
        g.particles = np;
        // the slots changed: the coupling's candidate lists are refreshed
        g.grid.rebuilds += 1;
        (g.step, g.time, g.max_disp) = (part.step, part.time, part.max_disp);
        g.walls.clone_from(&part.walls);
    }
}

impl DiscStep for NearBodies {
    fn prepare(&mut self, g: &mut Granular) {
        let before = self.d.part.grid.rebuilds;
        self.d.begin_step();
        if self.d.part.grid.rebuilds != before {
            // the keys may have been renewed: the view in the new order
            self.view(g);
        }
    }

    fn step(&mut self, g: &mut Granular, contacts: &[BodyContact]) {
        set_contacts_on_discs(&mut self.d.part, contacts);
        self.outcome = self.d.advance(self.flag);
        self.view(g);
    }
}
