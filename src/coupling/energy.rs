//! The energy account of a coupled run: what is stored (kinetic, strain,
//! penalty and contact springs), the external work since t = 0, and their
//! difference, the energy dissipated (friction, dashpots, numerics).

use super::CoupledModel;
use crate::dem::Granular;
use crate::geom::Vec2;

/// Energy account of the coupled system (all in the scenario's units).
#[derive(Debug, Clone, Copy, Default)]
pub struct EnergyAccount {
    /// Kinetic energy of the discs, translational `½mv²` plus rotational
    /// `½Iω²`.
    pub kin_dem: f64,
    /// Kinetic energy of the bodies, `Σ ½U̇ᵀMU̇`.
    pub kin_body: f64,
    /// Elastic strain energy of the bodies, `Σ ½UᵀKU`.
    pub strain: f64,
    /// Energy of the bodies' penalty springs (EFG prescribed edges), from
    /// their gap to the prescribed displacement.
    pub penalty: f64,
    /// Energy in the contact springs — disc–disc and disc–wall (DEM) and
    /// disc–body — and in the intact parallel bonds (the energy of broken
    /// bonds counts as dissipated).
    pub contact: f64,
    /// Work of gravity on the discs, of the bodies' permanent loads and
    /// moving edges, and of the walls since t = 0.
    pub w_ext: f64,
    /// Energy the growth of the bodies' cracks took (the
    /// drop of the stored energy less the work of the loads as the new
    /// crack pieces open, [`EfgBody::grow_under`](crate::efg::EfgBody::grow_under)).
    pub fracture: f64,
    /// `W_ext − (stored − stored at t = 0) − fracture`: friction, dashpots
    /// and numerical dissipation.
    pub diss: f64,
}

impl EnergyAccount {
    /// Energy stored: kinetic (discs, bodies), strain, penalty and contact
    /// springs.
    pub fn stored(&self) -> f64 {
        self.kin_dem + self.kin_body + self.strain + self.penalty + self.contact
    }
}

/// Tracks the external work between steps. It belongs to the driver, not
/// to the model: a restart restores it with the model's state (it is
/// serde-serialisable; [`WorkMeter::new`] on a restored model would start
/// the account afresh there).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WorkMeter {
    /// Initial disc positions by disc id (the DEM renumbers its slots).
    x0: Vec<Vec2>,
    wall_work: f64,
    /// Energy stored at t = 0 (initial velocities, overlaps, deformation)
    /// minus the work the permanent loads count at t = 0.
    stored0: f64,
}

impl WorkMeter {
    /// Start the account at the present state of `m` (t = 0): its
    /// dissipated energy is zero there.
    pub fn new(m: &CoupledModel) -> Self {
        let p = &m.granular.particles;
        let mut x0 = vec![Vec2::ZERO; p.len()];
        for k in 0..p.len() {
            x0[p.id[k] as usize] = p.pos[k];
        }
        let mut w = WorkMeter {
            x0,
            wall_work: 0.0,
            stored0: 0.0,
        };
        // stored minus external work (and fracture energy) at t = 0, so
        // that E_diss(0) = 0
        w.stored0 = -w.account(m).diss;
        w
    }
    /// After a step: work the walls did on the discs during it.
    pub fn after_step(&mut self, g: &Granular) {
        for w in &g.walls {
            self.wall_work -= w.force.dot(w.vel) * g.dt;
        }
    }
    /// The energy account of the present state of `m`.
    pub fn account(&self, m: &CoupledModel) -> EnergyAccount {
        let g = &m.granular;
        let p = &g.particles;
        let e = g.energies();
        let mut w_grav = 0.0;
        for k in 0..p.len() {
            w_grav += p.mass[k] * g.gravity.dot(p.pos[k] - self.x0[p.id[k] as usize]);
        }
        let (mut kin_body, mut strain, mut penalty, mut w_body) = (0.0, 0.0, 0.0, 0.0);
        let mut fracture = 0.0;
        for b in &m.bodies {
            let en = b.energies();
            kin_body += en.kinetic;
            strain += en.strain;
            penalty += en.penalty;
            w_body += en.work;
            fracture += en.fracture;
        }
        let contact = e.spring + e.bond + m.body_contact_energy();
        let w_ext = w_grav + w_body + self.wall_work;
        let kin_dem = e.kinetic + e.rotational;
        let mut e = EnergyAccount {
            kin_dem,
            kin_body,
            strain,
            penalty,
            contact,
            w_ext,
            fracture,
            diss: 0.0,
        };
        e.diss = w_ext - (e.stored() - self.stored0) - fracture;
        e
    }
}
