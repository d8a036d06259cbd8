//! Clumps of discs against independent references: mass, centre and
//! moment of inertia of the union against a fine-grid integration; a clump
//! on an incline slides and tips at the analytic angles; an undamped,
//! frictionless clump collision conserves energy and momenta; 1 vs 2
//! threads and a restart give bitwise the same run.

use efgdem::Vec2;
use efgdem::dem::clumps::{Fit, replace_with_template, union_shape};
use efgdem::dem::contact::ContactLaw;
use efgdem::dem::packing::DiscRow;
use efgdem::dem::particles::Particles;
use efgdem::dem::walls::{Wall, WallMotion};
use efgdem::dem::{BodyDamping, Granular};

#[allow(dead_code)]
mod common;

const RHO: f64 = 1000.0;

/// `[A, ∫x dA, ∫y dA, ∫x² dA, ∫y² dA]` of the union of discs by columns:
/// the midpoint rule over `n` columns in x, each column's cut through the
/// union (merged intervals of the discs' chords) integrated exactly in y.
fn grid_moments(discs: &[(Vec2, f64)], n: usize) -> [f64; 5] {
    let x0 = discs
        .iter()
        .map(|&(c, r)| c.x - r)
        .fold(f64::INFINITY, f64::min);
    let x1 = discs
        .iter()
        .map(|&(c, r)| c.x + r)
        .fold(f64::NEG_INFINITY, f64::max);
    let h = (x1 - x0) / n as f64;
    let mut m = [0.0; 5];
    let mut cut = Vec::new();
    for k in 0..n {
        let x = x0 + (k as f64 + 0.5) * h;
        cut.clear();
        for &(c, r) in discs {
            let d = r * r - (x - c.x) * (x - c.x);
            if d > 0.0 {
                cut.push((c.y - d.sqrt(), c.y + d.sqrt()));
            }
        }
        cut.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (mut l, mut y1, mut y2) = (0.0, 0.0, 0.0);
        let mut i = 0;
        while i < cut.len() {
            let (a, mut b) = cut[i];
            while i + 1 < cut.len() && cut[i + 1].0 <= b {
                i += 1;
                b = b.max(cut[i].1);
            }
            l += b - a;
            y1 += (b * b - a * a) / 2.0;
            y2 += (b.powi(3) - a.powi(3)) / 3.0;
            i += 1;
        }
        m[0] += l * h;
        m[1] += x * l * h;
        m[2] += y1 * h;
        m[3] += x * x * l * h;
        m[4] += y2 * h;
    }
    m
}

/// Validation item 5 (shape): the exact union (arcs of the boundary,
/// Green's theorem) against the grid integration of the same union, to
/// 1e-4 of the area, of the size (centroid) and of the polar moment —
/// for two, three and four discs, unequal, one covered by the others, one
/// inside another; the sum over the discs would be off by the overlaps
/// (tens of per cent here).
#[test]
fn union_mass_centre_and_inertia_match_a_grid_integration() {
    let v = Vec2::new;
    let cases: Vec<Vec<(Vec2, f64)>> = vec![
        vec![(v(0.0, 0.0), 1.0), (v(1.3, 0.4), 0.7)],
        vec![(v(0.0, 0.0), 1.0), (v(1.2, 0.0), 1.0), (v(0.6, 0.9), 0.8)],
        // the middle disc's rim is covered by its two neighbours
        vec![(v(-0.8, 0.0), 1.0), (v(0.0, 0.1), 0.45), (v(0.8, 0.0), 1.0)],
        vec![
            (v(10.0, -5.0), 2.0),
            (v(12.5, -4.0), 1.5),
            (v(10.5, -4.5), 0.5), // inside the first
            (v(11.0, -2.5), 1.2),
        ],
    ];
    for discs in &cases {
        let s = union_shape(discs);
        let [a, mx, my, ixx, iyy] = grid_moments(discs, 400_000);
        let c = Vec2::new(mx / a, my / a);
        let polar = ixx + iyy - a * c.norm2();
        let sum: f64 = discs
            .iter()
            .map(|&(_, r)| std::f64::consts::PI * r * r)
            .sum();
        let (ea, ec, ei) = (
            (s.area - a).abs() / a,
            (s.centroid - c).norm() / a.sqrt(),
            (s.polar - polar).abs() / polar,
        );
        println!(
            "{} discs: area {:.10} (sum of discs {sum:.4}), errors area {ea:.1e} centre {ec:.1e} inertia {ei:.1e}",
            discs.len(),
            s.area
        );
        assert!(ea < 1e-4 && ec < 1e-4 && ei < 1e-4);
        assert!((sum - s.area) / s.area > 0.05, "the overlaps matter here");
    }
}

/// Discs of density [`RHO`] and thickness 1, clumps of the given member
/// groups, one material, walls.
fn assembly(
    discs: &[(Vec2, f64)],
    groups: &[Vec<usize>],
    law: ContactLaw,
    walls: Vec<Wall>,
    dt: f64,
) -> Granular {
    let mut p = Particles::default();
    for &(c, r) in discs {
        p.push(c, r, RHO, 1.0, 0);
    }
    let mut g = Granular::new(p, vec![law], walls, dt);
    for m in groups {
        g.add_clump(m).unwrap();
    }
    g
}

/// A clump of `discs` resting on a long horizontal wall at y = 0, under
/// gravity tilted by `beta` (an incline of that angle, downhill along +x),
/// stepped for `time`; returns the clump's displacement along x and its
/// rotation over the second half of the time (after the landing, whose
/// load ramp lets the contacts slip a little), and its velocity at the
/// half and at the end.
fn on_incline(discs: &[(Vec2, f64)], mu: f64, beta: f64, time: f64) -> (f64, f64, Vec2, Vec2) {
    let law = ContactLaw {
        kn: 1e8,
        ks: 1e8,
        mu,
        zeta_n: 0.5,
        ..Default::default()
    };
    let wall = Wall::new(
        "slope",
        Vec2::new(-200.0, 0.0),
        Vec2::new(200.0, 0.0),
        WallMotion::Fixed,
    );
    let all: Vec<usize> = (0..discs.len()).collect();
    let mut g = assembly(discs, &[all], law, vec![wall], 2e-4);
    g.gravity = Vec2::new(beta.sin(), -beta.cos()) * 9.81;
    let n = (time / g.dt).round() as usize;
    let mut half = (Vec2::ZERO, 0.0, Vec2::ZERO);
    for k in 0..n {
        g.step();
        if k + 1 == n / 2 {
            let c = &g.clumps;
            half = (c.pos[0], c.theta[0], c.vel[0]);
        }
    }
    let c = &g.clumps;
    (c.pos[0].x - half.0.x, c.theta[0] - half.1, half.2, c.vel[0])
}

/// Validation item 5 (incline, sliding): a flat two-disc clump (tipping
/// angle 38.7°) with μ = 0.3 stays put 1.5° below `atan μ` = 16.7° (it
/// moves by the elastic shear only) and slides 1.5° above it with the
/// analytic acceleration `g (sin β − μ cos β)` to 1 % (an error in the
/// friction or the summed contact force would be tens of per cent).
#[test]
fn a_clump_on_an_incline_slides_at_the_friction_angle() {
    let discs = [(Vec2::new(-0.8, 1.0), 1.0), (Vec2::new(0.8, 1.0), 1.0)];
    let mu: f64 = 0.3;
    let limit = mu.atan();
    let margin = 1.5f64.to_radians();
    let (dx, th, _, _) = on_incline(&discs, mu, limit - margin, 1.0);
    println!("below: dx {dx:e}, rotation {th:e}");
    assert!(dx.abs() < 1e-4 && th.abs() < 1e-4);
    let beta = limit + margin;
    let (dx, th, v1, v2) = on_incline(&discs, mu, beta, 1.0);
    let a = (v2.x - v1.x) / 0.5;
    let exact = 9.81 * (beta.sin() - mu * beta.cos());
    println!("above: dx {dx:e}, rotation {th:e}, acceleration {a} (analytic {exact})");
    assert!((a - exact).abs() < 1e-6 * exact, "{a} vs {exact}");
    assert!(th.abs() < 1e-3, "slides without tipping");
}

/// Validation item 5 (incline, tipping): a three-disc clump standing on
/// two feet at x = ±0.6 with μ = 1 (sliding at 45°) tips when the
/// downhill gravity's moment about the lower foot exceeds the normal
/// one's, `tan β = 0.6 / y_c` with the union's centroid height `y_c`:
/// 1.5° below it the clump stays (moves and turns by less than 1e-5 in
/// the second second), 1.5° above it it turns over by more than 0.3 rad
/// in that second.
#[test]
fn a_clump_on_an_incline_tips_at_the_analytic_angle() {
    let discs = [
        (Vec2::new(-0.6, 1.0), 1.0),
        (Vec2::new(0.6, 1.0), 1.0),
        (Vec2::new(0.0, 2.6), 1.0),
    ];
    let yc = union_shape(&discs).centroid.y;
    let tip = (0.6 / yc).atan();
    println!(
        "centroid height {yc}, tipping angle {:.3}°",
        tip.to_degrees()
    );
    let margin = 1.5f64.to_radians();
    let (dx, th, _, _) = on_incline(&discs, 1.0, tip - margin, 2.0);
    println!("below: dx {dx:e}, rotation {th:e}");
    assert!(dx.abs() < 1e-5 && th.abs() < 1e-5);
    let (dx, th, _, _) = on_incline(&discs, 1.0, tip + margin, 2.0);
    println!("above: dx {dx:e}, rotation {th:e}");
    // downhill along +x: it turns clockwise
    assert!(th < -0.3);
}

/// Validation item 5 (energy): two clumps (three discs and two discs)
/// collide off-centre, undamped and frictionless, in zero gravity: after
/// the contact has opened, kinetic + rotational energy equals its value
/// before to 1e-4 (the central difference's energy error over the
/// contact; measured 9e-7), linear momentum to 1e-12 and angular momentum about
/// the origin to 1e-9 (a wrong inertia or lever arm breaks the
/// angular-momentum balance at once).
#[test]
fn an_undamped_clump_collision_conserves_energy_and_momenta() {
    let v = Vec2::new;
    let discs = [
        (v(0.0, 0.0), 1.0),
        (v(1.2, 0.0), 1.0),
        (v(0.6, 0.9), 0.8),
        (v(5.0, 1.5), 0.9),
        (v(6.2, 2.1), 0.7),
    ];
    let law = ContactLaw {
        kn: 1e7,
        ks: 0.0,
        mu: 0.0,
        ..Default::default()
    };
    let mut g = assembly(&discs, &[vec![0, 1, 2], vec![3, 4]], law, Vec::new(), 5e-5);
    g.damping = BodyDamping::None;
    let c = &mut g.clumps;
    c.vel[0] = v(2.0, 0.0);
    c.omega[0] = 0.5;
    c.vel[1] = v(-1.0, -0.2);
    let momenta = |g: &Granular| {
        let c = &g.clumps;
        let (mut p, mut l) = (Vec2::ZERO, 0.0);
        for k in 0..c.len() {
            p += c.vel[k] * c.mass[k];
            l += c.pos[k].cross(c.vel[k] * c.mass[k]) + c.inertia[k] * c.omega[k];
        }
        (p, l)
    };
    let e0 = g.energies();
    let (p0, l0) = momenta(&g);
    let mut touched = 0;
    for _ in 0..40_000 {
        g.step();
        touched += (g.touching().0 > 0) as usize;
    }
    assert!(touched > 100 && g.touching().0 == 0, "one collision, over");
    let e1 = g.energies();
    let (p1, l1) = momenta(&g);
    let (k0, k1) = (e0.kinetic + e0.rotational, e1.kinetic + e1.rotational);
    println!(
        "energy {k0} -> {k1} (rel {:.1e}; rotational {} -> {}), momentum {p0:?} -> {p1:?}, angular {l0} -> {l1}",
        (k1 - k0) / k0,
        e0.rotational,
        e1.rotational
    );
    assert!(
        (e1.rotational - e0.rotational).abs() > 0.01 * k0,
        "the collision spins the clumps"
    );
    assert!((k1 - k0).abs() < 1e-4 * k0);
    assert!((p1 - p0).norm() < 1e-12 * p0.norm());
    assert!((l1 - l0).abs() < 1e-9 * l0.abs());
}

/// A 12 × 10 box of discs replaced by three-disc clumps (random
/// rotations), dropped under gravity with local damping and a small skin
/// (several rebuilds and renumberings), stepped `steps` times from `from`
/// (or from the start).
fn pile(steps: usize, from: Option<&efgdem::dem::state::GranularState>) -> Granular {
    pile_of(12, 10, steps, from)
}

/// [`pile`] of `nx × ny` discs.
fn pile_of(
    nx: usize,
    ny: usize,
    steps: usize,
    from: Option<&efgdem::dem::state::GranularState>,
) -> Granular {
    let rows: Vec<DiscRow> = (0..nx * ny)
        .map(|k| DiscRow {
            pos: Vec2::new(1.0 + 2.05 * (k % nx) as f64, 1.0 + 2.05 * (k / nx) as f64),
            r: 1.0,
            material: None,
        })
        .collect();
    let template = [
        (Vec2::new(0.0, 0.0), 1.0),
        (Vec2::new(1.0, 0.0), 0.8),
        (Vec2::new(0.4, 0.8), 0.6),
    ];
    let (rows, groups) = replace_with_template(&rows, &template, Fit::Inside, |k| k % 5 != 0, 3);
    let discs: Vec<(Vec2, f64)> = rows.iter().map(|r| (r.pos, r.r)).collect();
    let w = |a: (f64, f64), b: (f64, f64)| {
        Wall::new(
            "w",
            Vec2::new(a.0, a.1),
            Vec2::new(b.0, b.1),
            WallMotion::Fixed,
        )
    };
    let (x, y) = (2.05 * nx as f64, 3.0 * ny as f64);
    let walls = vec![
        w((0.0, 0.0), (x, 0.0)),
        w((0.0, 0.0), (0.0, y)),
        w((x, y), (x, 0.0)),
    ];
    let law = ContactLaw {
        kn: 1e7,
        ks: 5e6,
        mu: 0.5,
        zeta_n: 0.2,
        ..Default::default()
    };
    let mut g = assembly(&discs, &groups, law, walls, 2e-4);
    g.gravity = Vec2::new(0.0, -9.81);
    g.damping = BodyDamping::Local { alpha: 0.1 };
    g.set_skin(0.02);
    if let Some(s) = from {
        g.restore_state(s).unwrap();
    }
    for _ in 0..steps {
        g.step();
    }
    g
}

/// The state of the discs and clumps of `g`, as bits (and the disc ids
/// in slot order).
fn bits(g: &Granular) -> Vec<u64> {
    let p = &g.particles;
    let c = &g.clumps;
    let mut v: Vec<u64> = p
        .pos
        .iter()
        .chain(&p.vel)
        .chain(&c.pos)
        .chain(&c.vel)
        .flat_map(|x| [x.x.to_bits(), x.y.to_bits()])
        .collect();
    v.extend(
        p.omega
            .iter()
            .chain(&c.omega)
            .chain(&c.theta)
            .map(|w| w.to_bits()),
    );
    v.extend(p.id.iter().map(|&i| i as u64));
    v
}

/// A step with clumps (the contact sweep advancing the free discs, then
/// the clumps' passes) gives bitwise the discs, clumps and largest
/// displacement of the phased step: contacts, every disc advanced, the
/// clumps summed and advanced and their members placed.
#[test]
fn a_clumped_step_is_the_phased_step() {
    let mut a = pile(300, None);
    step_fused_and_phased(&mut a, 700);
}

/// Step `a` `steps` times and a copy of it as many times in phases
/// (contacts, walls, every disc advanced, the clumps' passes), asserting
/// the same largest displacement at every step and the same list rebuilds
/// (more than one), discs, clumps and step count at the end.
fn step_fused_and_phased(a: &mut Granular, steps: usize) {
    let mut b = a.clone();
    for _ in 0..steps {
        a.step();
        b.prepare_contacts();
        b.compute_contact_forces();
        b.wall_totals();
        b.integrate();
        assert_eq!(a.max_disp.to_bits(), b.max_disp.to_bits());
    }
    assert!(a.grid.rebuilds > 1 && a.grid.rebuilds == b.grid.rebuilds);
    assert_eq!(bits(a), bits(&b));
    assert_eq!(a.step, b.step);
}

/// The same with several blocks of the contact sweep (the clumps whose
/// members lie in one block stepped after it, the others after the
/// sweep), on 1 and 2 threads.
#[test]
fn a_clumped_step_over_blocks_is_the_phased_step_on_any_threads() {
    let run = |threads: usize| {
        common::on_threads(threads, || {
            let mut a = pile_of(40, 30, 0, None);
            step_fused_and_phased(&mut a, 300);
            assert!(a.particles.len() > 4 * a.contacts.block);
            bits(&a)
        })
    };
    assert_eq!(run(1), run(2));
}

/// Validation item 6 (clumps): 1 and 2 threads, and a run restarted from
/// a saved state, give bitwise the same discs and clumps.
#[test]
fn clumps_are_bitwise_independent_of_threads_and_restart() {
    let on = |threads: usize, f: &(dyn Fn() -> Granular + Sync)| common::on_threads(threads, f);
    let a = on(1, &|| pile(3000, None));
    let b = on(2, &|| pile(3000, None));
    let saved = on(2, &|| pile(1000, None)).save_state();
    let c = on(2, &|| pile(2000, Some(&saved)));
    println!(
        "{} clumps, {} discs, {} rebuilds, lowest clump at y = {}",
        a.clumps.len(),
        a.particles.len(),
        a.grid.rebuilds,
        a.clumps
            .pos
            .iter()
            .map(|x| x.y)
            .fold(f64::INFINITY, f64::min)
    );
    assert!(a.clumps.len() == 96 && a.grid.rebuilds > 3);
    for other in [&b, &c] {
        assert_eq!(bits(&a), bits(other));
        assert_eq!(a.step, other.step);
    }
}

/// A measurement region holding a clump counts the clump's area once: the
/// porosity is `1 − A_union / A_region` (to round-off), not the sum of
/// its discs' areas.
#[test]
fn porosity_counts_a_clump_once() {
    use efgdem::dem::measure::{Region, porosity};
    let discs = [(Vec2::new(0.0, 0.0), 1.0), (Vec2::new(1.2, 0.3), 0.8)];
    let g = assembly(
        &discs,
        &[vec![0, 1]],
        ContactLaw::default(),
        Vec::new(),
        1e-3,
    );
    let region = Region::Rectangle {
        lo: Vec2::new(-2.0, -2.0),
        hi: Vec2::new(3.0, 2.0),
    };
    let exact = 1.0 - union_shape(&discs).area / 20.0;
    let phi = porosity(&g, &region);
    println!("porosity {phi} (union {exact})");
    assert!((phi - exact).abs() < 1e-12);
}
