//! The coupling plumbing against the DEM's own rigid wall: a disc thrown
//! with spin onto a body that cannot move must follow exactly the path it
//! follows onto a rigid wall at the same place (same contact law, same
//! arms), and the body must receive the opposite of the force on the disc.

use efgdem::Vec2;
use efgdem::continuum::compliance::Compliance;
use efgdem::continuum::{
    BodyEnergies, BodyState, BoundaryChain, ChainStiffness, Continuum, SolveError, StateError,
};
use efgdem::coupling::CoupledModel;
use efgdem::dem::Granular;
use efgdem::dem::contact::ContactLaw;
use efgdem::dem::particles::Particles;
use efgdem::dem::walls::{Wall, WallMotion};
use std::sync::{Arc, Mutex};

/// A body that never moves; records the loads it receives.
struct Fixed {
    chains: Vec<BoundaryChain>,
    received: Arc<Mutex<Vec<Vec2>>>,
    pending: Vec2,
    zero: Vec<f64>,
}

impl Continuum for Fixed {
    fn name(&self) -> &str {
        "fixed"
    }
    fn contact_boundary(&self) -> &[BoundaryChain] {
        &self.chains
    }
    fn boundary_velocity(&self, _: usize, _: Vec2) -> Vec2 {
        Vec2::ZERO
    }
    fn boundary_displacement(&self, _: usize, _: Vec2) -> Vec2 {
        Vec2::ZERO
    }
    fn add_point_load(&mut self, _: usize, _: Vec2, f: Vec2) {
        self.pending += f;
    }
    /// Rigid: no displacement, zero compliance.
    fn begin_step(
        &mut self,
        points: &[(usize, Vec2)],
        stiffness: &[ChainStiffness],
        base: &mut Vec<Vec2>,
        free: &mut Vec<Vec2>,
    ) -> Result<(), SolveError> {
        let m = points.len() + stiffness.len();
        base.clear();
        base.resize(m, Vec2::ZERO);
        free.clear();
        free.resize(m, Vec2::ZERO);
        self.zero.clear();
        self.zero.resize(4 * m * m, 0.0);
        Ok(())
    }
    fn compliance(&mut self) -> Compliance<'_> {
        Compliance::Dense(&self.zero)
    }
    fn finish_step(&mut self, forces: &[Vec2]) -> Result<(), SolveError> {
        let total = forces.iter().fold(self.pending, |a, &f| a + f);
        self.received.lock().unwrap().push(total);
        self.pending = Vec2::ZERO;
        Ok(())
    }
    fn energies(&self) -> BodyEnergies {
        BodyEnergies::default()
    }
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    /// Rigid: nothing but the pending load changes (none between steps).
    fn save_state(&self) -> BodyState {
        BodyState {
            name: "fixed".into(),
            ..Default::default()
        }
    }
    fn restore_state(&mut self, _: &BodyState) -> Result<(), StateError> {
        Ok(())
    }
}

fn law() -> ContactLaw {
    ContactLaw {
        kn: 1e6,
        ks: 5e5,
        mu: 0.4,
        zeta_n: 0.2,
        ..Default::default()
    }
}

fn disc(dt: f64, law: ContactLaw) -> Granular {
    let mut p = Particles::default();
    p.push(Vec2::new(0.3, 0.12), 0.1, 1000.0, 1.0, 0);
    p.vel[0] = Vec2::new(0.8, -1.5);
    p.omega[0] = 20.0;
    let mut g = Granular::new(p, vec![law], Vec::new(), dt);
    g.gravity = Vec2::new(0.0, -9.81);
    g
}

#[test]
fn disc_on_a_fixed_body_matches_disc_on_a_rigid_wall() {
    compare(law(), false);
    compare(law(), true);
}

/// The same with rolling resistance (spring, limit and dashpot): the
/// disc–body rolling moment is the disc–wall one (`r̄ = r`, relative
/// rotation `ω_disc`), on the implicit and on the staggered path.
#[test]
fn rolling_resistance_on_a_fixed_body_matches_a_rigid_wall() {
    let l = ContactLaw {
        mu_roll: 0.3,
        roll_damping: 0.3,
        ..law()
    };
    let w_roll = compare(l, false);
    assert!((compare(l, true) - w_roll).abs() < 1e-10 * w_roll.abs());
    // and the rolling resistance did act on the spin
    let w_free = compare(law(), false);
    println!("final spin: {w_roll} with rolling resistance, {w_free} without");
    assert!((w_roll - w_free).abs() > 1e-3 * w_free.abs());
}

/// Runs the disc onto the wall and onto the fixed body side by side;
/// returns the final spin.
fn compare(law: ContactLaw, staggered: bool) -> f64 {
    let dt = 1e-5;
    let steps = 6000;
    // DEM reference: a wall along y = 0, body side below.
    let mut wall_run = disc(dt, law);
    wall_run.walls.push(Wall::new(
        "floor",
        Vec2::new(2.0, 0.0),
        Vec2::new(-1.0, 0.0),
        WallMotion::Fixed,
    ));
    wall_run.update_laws();
    // Coupled: the same line as the top edge of a body (body on the left
    // when going from x = 2 to x = −1), 30 segments.
    let received = Arc::new(Mutex::new(Vec::new()));
    let chain = BoundaryChain::new(
        (0..=30)
            .map(|k| Vec2::new(2.0 - 0.1 * k as f64, 0.0))
            .collect(),
    );
    let body = Fixed {
        chains: vec![chain],
        received: received.clone(),
        pending: Vec2::ZERO,
        zero: Vec::new(),
    };
    let mut coupled = CoupledModel::new(disc(dt, law), vec![Box::new(body)], &[None], 1);
    coupled.staggered = staggered;
    let mut max_dev: f64 = 0.0;
    let mut touched = 0;
    for _ in 0..steps {
        wall_run.step();
        coupled.step().unwrap();
        let (a, b) = (&wall_run.particles, &coupled.granular.particles);
        max_dev = max_dev
            .max((a.pos[0] - b.pos[0]).norm())
            .max((a.omega[0] - b.omega[0]).abs() * 0.1);
        if !coupled.contacts.is_empty() {
            touched += 1;
        }
        if !coupled.contacts.is_empty() && !staggered {
            // action = −reaction, this step
            let f_disc = coupled.contacts[0].force;
            let f_body = *received.lock().unwrap().last().unwrap();
            assert!((f_disc + f_body).norm() <= 1e-12 * f_disc.norm());
        }
    }
    assert!(
        touched > 100,
        "the disc must hit the body ({touched} steps in contact)"
    );
    assert!(
        max_dev < 1e-12,
        "coupled path deviates from the wall path by {max_dev:e}"
    );
    // it bounced: moving up at the end
    assert!(coupled.granular.particles.vel[0].y > 0.0);
    coupled.granular.particles.omega[0]
}
