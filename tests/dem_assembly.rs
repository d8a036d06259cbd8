//! Many-disc properties: energy conservation (issue 3, validation item 4)
//! and results independent of the thread count.

use efgdem::Vec2;
use efgdem::dem::contact::ContactLaw;
use efgdem::dem::packing::{Lattice, lattice_packing};
use efgdem::dem::particles::Particles;
use efgdem::dem::walls::{Wall, WallMotion};
use efgdem::dem::{BodyDamping, Granular};

#[allow(dead_code)]
mod common;

/// `n` polydisperse discs (r ∈ [0.8, 1.2], ρ = 1) loosely packed in a
/// closed square box, with random velocities of magnitude ~`v`.
fn gas(n: usize, side: f64, v: f64, law: ContactLaw, seed: u64) -> Granular {
    let rows = lattice_packing(
        Lattice::Hex,
        Vec2::new(0.0, 0.0),
        Vec2::new(side, side),
        (0.8, 1.2),
        Some(n),
        0.1,
        1.0,
        seed,
    )
    .expect("fits");
    let mut p = Particles::default();
    let mut rng = oorandom::Rand64::new(seed as u128 + 99);
    for r in &rows {
        p.push(r.pos, r.r, 1.0, 1.0, 0);
        let k = p.len() - 1;
        p.vel[k] = Vec2::new(rng.rand_float() - 0.5, rng.rand_float() - 0.5) * (2.0 * v);
        p.omega[k] = (rng.rand_float() - 0.5) * v;
    }
    let c = [
        Vec2::new(0.0, 0.0),
        Vec2::new(side, 0.0),
        Vec2::new(side, side),
        Vec2::new(0.0, side),
    ];
    let walls = (0..4)
        .map(|k| Wall::new(&format!("w{k}"), c[k], c[(k + 1) % 4], WallMotion::Fixed))
        .collect();
    Granular::new(p, vec![law], walls, 1.0)
}

/// Total energy at integer steps: potential from x_n, kinetic from the
/// average of the half-step velocities around n.
fn energy_drift(n: usize, steps: usize, dt_frac: f64) -> f64 {
    let law = ContactLaw {
        kn: 1.0e4,
        ks: 1.0e4,
        mu: 0.0,
        ..Default::default()
    };
    let mut g = gas(n, 1.6 * (n as f64).sqrt() * 2.0, 1.0, law, 5);
    g.dt = dt_frac * g.critical_dt();
    let mut e0 = None;
    let mut e_last = 0.0;
    let mut worst = 0.0f64;
    for _ in 0..steps {
        g.prepare_contacts();
        let pot = g.energies_with(&g.particles.vel.clone(), &g.particles.omega.clone());
        let v_before = g.particles.vel.clone();
        let w_before = g.particles.omega.clone();
        g.compute_contact_forces();
        g.integrate();
        let p = &g.particles;
        let mut kin = 0.0;
        for k in 0..p.len() {
            let v = (v_before[k] + p.vel[k]) * 0.5;
            let w = 0.5 * (w_before[k] + p.omega[k]);
            kin += 0.5 * p.mass[k] * v.norm2() + 0.5 * p.inertia[k] * w * w;
        }
        let e = kin + pot.spring;
        let e0 = *e0.get_or_insert(e);
        worst = worst.max((e - e0).abs() / e0);
        e_last = e;
    }
    let (dd, dw) = g.touching();
    let e0 = e0.unwrap();
    println!(
        "{n} discs, {steps} steps at {dt_frac} × critical: drift {:.2e} (worst {worst:.2e}); {dd}+{dw} contacts at the end, {} rebuilds",
        (e_last - e0).abs() / e0,
        g.grid.rebuilds
    );
    (e_last - e0).abs() / e0
}

#[test]
fn energy_is_conserved_without_damping_and_friction() {
    let drift = energy_drift(1000, 10_000, 0.1);
    assert!(drift < 1e-3, "drift {drift}");
}

/// A settling, frictional, damped assembly with walls, run for a while
/// (several rebuilds and renumberings) in a 1-thread and a 2-thread pool:
/// every array must be bitwise identical.
#[test]
fn one_and_two_threads_give_bitwise_identical_results() {
    let law = ContactLaw {
        kn: 1.0e5,
        ks: 1.0e5,
        mu: 0.5,
        zeta_n: 0.2,
        ..Default::default()
    };
    let run = |threads: usize| {
        common::on_threads(threads, || {
            let mut g = gas(6000, 200.0, 3.0, law, 11);
            g.gravity = Vec2::new(0.0, -9.81);
            g.damping = BodyDamping::Local { alpha: 0.1 };
            g.dt = 0.1 * g.critical_dt();
            g.set_skin(0.6);
            for _ in 0..400 {
                g.step();
            }
            g
        })
    };
    let (a, b) = (run(1), run(2));
    assert!(
        a.grid.rebuilds > 2,
        "exercise rebuilds: {}",
        a.grid.rebuilds
    );
    assert!(a.contacts.len() > 4096, "exercise several chunks");
    let bits = |v: &[Vec2]| {
        v.iter()
            .flat_map(|p| [p.x.to_bits(), p.y.to_bits()])
            .collect::<Vec<_>>()
    };
    let bits1 = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let (pa, pb) = (&a.particles, &b.particles);
    assert_eq!(pa.id, pb.id);
    assert_eq!(bits(&pa.pos), bits(&pb.pos));
    assert_eq!(bits(&pa.vel), bits(&pb.vel));
    assert_eq!(bits(&pa.force), bits(&pb.force));
    assert_eq!(bits1(&pa.omega), bits1(&pb.omega));
    assert_eq!(bits1(&pa.theta), bits1(&pb.theta));
    assert_eq!(bits1(&pa.torque), bits1(&pb.torque));
    assert_eq!(
        (&a.contacts.first, &a.contacts.j),
        (&b.contacts.first, &b.contacts.j)
    );
    assert_eq!(bits1(&a.contacts.shear), bits1(&b.contacts.shear));
    assert_eq!(a.contacts.walls, b.contacts.walls);
    for (wa, wb) in a.walls.iter().zip(&b.walls) {
        assert_eq!(wa.force.x.to_bits(), wb.force.x.to_bits());
        assert_eq!(wa.force.y.to_bits(), wb.force.y.to_bits());
    }
    println!(
        "{} discs, {} pairs, {} rebuilds: 1 and 2 threads identical",
        pa.len(),
        a.contacts.len(),
        a.grid.rebuilds
    );
}

/// Shear histories survive a rebuild and a renumbering of the discs.
#[test]
fn shear_history_survives_renumbering() {
    let law = ContactLaw {
        kn: 1.0e5,
        ks: 1.0e5,
        mu: 0.5,
        zeta_n: 0.2,
        ..Default::default()
    };
    let mut g = gas(500, 60.0, 0.0, law, 3);
    g.gravity = Vec2::new(0.0, -9.81);
    g.dt = 0.1 * g.critical_dt();
    for _ in 0..3000 {
        g.step();
    }
    let key = |g: &Granular| {
        let mut v: Vec<(u32, u32, u64)> = g
            .contacts
            .pairs()
            .zip(&g.contacts.shear)
            .filter(|(_, fs)| **fs != 0.0)
            .map(|((i, j), fs)| {
                let (a, b) = (g.particles.id[i], g.particles.id[j]);
                (a.min(b), a.max(b), fs.to_bits())
            })
            .collect();
        v.sort();
        v
    };
    let before = key(&g);
    assert!(!before.is_empty());
    g.grid.rebuilds = 0; // next rebuild renumbers
    g.grid.stale = true;
    g.prepare_contacts();
    assert_eq!(before, key(&g));
}

/// 800 frictional discs with a normal dashpot settling under gravity in a box.
fn settling_gas(seed: u64) -> Granular {
    let law = ContactLaw {
        kn: 1.0e5,
        ks: 1.0e5,
        mu: 0.5,
        zeta_n: 0.2,
        ..Default::default()
    };
    let mut g = gas(800, 80.0, 2.0, law, seed);
    g.gravity = Vec2::new(0.0, -9.81);
    g.dt = 0.1 * g.critical_dt();
    g
}

/// `step()` (one fused sweep) equals the three public phases.
#[test]
fn fused_step_equals_public_phases() {
    let mut a = settling_gas(8);
    let mut b = a.clone();
    for _ in 0..500 {
        a.step();
        b.prepare_contacts();
        b.compute_contact_forces();
        b.integrate();
    }
    let bits = |g: &Granular| {
        let p = &g.particles;
        p.pos
            .iter()
            .chain(&p.vel)
            .chain(&p.force)
            .flat_map(|v| [v.x.to_bits(), v.y.to_bits()])
            .chain(p.omega.iter().chain(&p.torque).map(|x| x.to_bits()))
            .chain(
                g.walls
                    .iter()
                    .flat_map(|w| [w.force.x.to_bits(), w.force.y.to_bits()]),
            )
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
    assert!(a.touching().1 > 0, "exercise wall contacts");
}

/// Discs held out of the sweep and advanced after it with their external
/// forces (`hold` / `release_held`, as the coupling does while it solves
/// the disc–body contacts beside the sweep) take bitwise the fused step
/// with those forces, on 1 and 2 threads, with `store_forces` off too.
#[test]
fn held_discs_take_the_fused_step_bitwise() {
    for threads in [1, 2] {
        common::on_threads(threads, || {
            let mut a = settling_gas(10);
            let mut b = a.clone();
            (a.store_forces, b.store_forces) = (false, false);
            let held: Vec<u32> = (0..800).step_by(7).collect();
            for step in 0..400 {
                // a force and moment on every third held disc, two on some
                let ext = |g: &Granular| {
                    let mut e = Vec::new();
                    for (k, &s) in held.iter().enumerate().filter(|(k, _)| k % 3 == 0) {
                        let s = s as usize;
                        let f = Vec2::new((k as f64).sin(), -1.0) * (50.0 + step as f64);
                        e.push((s, f, g.particles.pos[s] + Vec2::new(0.5, 0.0), 0.1));
                        if k % 2 == 0 {
                            e.push((s, -f * 0.5, g.particles.pos[s], 0.0));
                        }
                    }
                    e
                };
                a.prepare_contacts();
                a.set_external_with_moments(ext(&a));
                a.step();
                b.prepare_contacts();
                b.hold(&held);
                let bad = b.advance_discs();
                b.set_external_with_moments(ext(&b));
                let bad = b.release_held(&held) | bad;
                b.wall_totals();
                b.finish_step(!bad);
            }
            let bits = |g: &Granular| {
                let p = &g.particles;
                (p.pos.iter().chain(&p.vel))
                    .flat_map(|v| [v.x.to_bits(), v.y.to_bits()])
                    .chain(p.omega.iter().chain(&p.theta).map(|x| x.to_bits()))
                    .chain(p.fixity.iter().map(|&f| f as u64))
                    .chain([g.max_disp.to_bits()])
                    .chain(
                        g.walls
                            .iter()
                            .flat_map(|w| [w.force.x.to_bits(), w.force.y.to_bits()]),
                    )
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&a), bits(&b), "{threads} threads");
            assert_eq!(a.step_check(a.check_radii), b.step_check(b.check_radii));
            assert!(a.particles.vel.iter().any(|v| v.y < -1.0), "the forces act");
        });
    }
}

/// The phases are safe to call in any state: forces before any rebuild,
/// and after discs were added.
#[test]
fn phases_rebuild_when_the_list_does_not_match_the_discs() {
    let law = ContactLaw {
        kn: 1.0e5,
        ks: 1.0e5,
        mu: 0.5,
        ..Default::default()
    };
    let mut p = Particles::default();
    p.push(Vec2::new(0.0, 0.0), 1.0, 1.0, 1.0, 0);
    p.push(Vec2::new(1.9, 0.0), 1.0, 1.0, 1.0, 0);
    let mut g = Granular::new(p, vec![law], vec![], 1e-3);
    g.compute_contact_forces(); // no prepare_contacts() before
    assert!(g.particles.force[0].x < 0.0);
    g.integrate();
    g.particles.push(Vec2::new(0.0, 1.9), 1.0, 1.0, 1.0, 0);
    g.step();
    assert!(g.particles.force[2].y > 0.0);
}

/// Skipping the force store (`store_forces = false`, as `efgdem run` does
/// between frames) changes nothing but the force arrays.
#[test]
fn skipping_the_force_store_leaves_the_motion_bitwise_unchanged() {
    let mut a = settling_gas(9);
    let mut b = a.clone();
    b.store_forces = false;
    for _ in 0..300 {
        a.step();
        b.step();
    }
    let bits = |v: &[Vec2]| {
        v.iter()
            .flat_map(|p| [p.x.to_bits(), p.y.to_bits()])
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a.particles.pos), bits(&b.particles.pos));
    assert_eq!(bits(&a.particles.vel), bits(&b.particles.vel));
    assert!(b.particles.force.iter().all(|f| *f == Vec2::ZERO));
    assert!(a.particles.force.iter().any(|f| *f != Vec2::ZERO));
    b.store_forces = true;
    a.step();
    b.step();
    assert_eq!(bits(&a.particles.force), bits(&b.particles.force));
}

/// The disc check done inside `Granular::step` (what `Model::step`'s
/// stability check relies on) agrees with a pass over the discs: clean on
/// a settling gas, flagged once one disc moves more than a radius per step
/// or turns non-finite, and unknown for another bound.
#[test]
fn the_step_checks_every_disc() {
    let law = ContactLaw {
        kn: 1.0e5,
        ks: 1.0e5,
        mu: 0.5,
        zeta_n: 0.2,
        ..Default::default()
    };
    let mut g = gas(2000, 120.0, 1.0, law, 5);
    g.dt = 0.1 * g.critical_dt();
    let limit = g.check_radii;
    for _ in 0..50 {
        g.step();
        assert_eq!(g.step_check(limit), Some(true));
    }
    // the bound itself: a different one is not what the step checked
    assert_eq!(g.step_check(2.0 * limit), None);
    let s = g.slot(1234);
    let r = g.particles.radius[s];
    // just below one radius per step: clean; just above: flagged
    for (speed, clean) in [(0.99, true), (1.01, false)] {
        g.particles.vel[s] = Vec2::new(speed * r / g.dt, 0.0);
        g.particles.force[s] = Vec2::ZERO;
        g.gravity = Vec2::ZERO;
        let mut h = g.clone();
        h.step();
        let v = h.particles.vel[s];
        let moved = v.norm() * h.dt / r;
        assert_eq!(h.step_check(limit), Some(moved <= 1.0), "{moved}");
        assert_eq!(moved <= 1.0, clean, "{moved}");
    }
    g.particles.omega[s] = f64::NAN;
    g.step();
    assert_eq!(g.step_check(limit), Some(false));
    assert!(g.check_finite().is_err());
}
