//! Stress and fabric measurement (issue 13 §4, `dem::measure`): the
//! Love–Weber stress, coordination number, fabric and porosity of three
//! hand-made discs (exact numbers); a confined packing at rest measures the
//! walls' stresses; a packing settled under gravity measures the weight of
//! the discs above; `[[measure]]` gives history columns in `efgdem run`.

#[allow(dead_code)]
mod common;

use efgdem::dem::Granular;
use efgdem::dem::contact::ContactLaw;
use efgdem::dem::measure::{self, Quantity, Region};
use efgdem::dem::particles::Particles;
use efgdem::dem::walls::{Wall, WallMotion};
use efgdem::geom::Vec2;
use efgdem::model::Model;
use efgdem::scenario;
use std::f64::consts::PI;

/// A at (0, 0), B at (1.8, 0), C at (0, 1.9), radius 1, k_n = 100, A on a
/// floor at y = −0.9; thickness 2. Overlaps: AB 0.2, AC 0.1, A–floor 0.1;
/// the AB contact carries a shear force 3 (force on A: (−20, 3)).
fn three_discs() -> Granular {
    let mut p = Particles::default();
    for x in [[0.0, 0.0], [1.8, 0.0], [0.0, 1.9]] {
        p.push(Vec2::from(x), 1.0, 1.0, 2.0, 0);
    }
    let law = ContactLaw {
        kn: 100.0,
        ks: 50.0,
        mu: 0.5,
        ..Default::default()
    };
    // short: B, at 1.58 from its end, does not touch it
    let floor = Wall::new(
        "floor",
        Vec2::new(-2.0, -0.9),
        Vec2::new(0.5, -0.9),
        WallMotion::Fixed,
    );
    let mut g = Granular::new(p, vec![law], vec![floor], 1e-3);
    g.thickness = 2.0;
    g.prepare_contacts();
    let (a, b) = (g.slot(0) as u32, g.slot(1) as u32);
    let k = g.contacts.find(a, b).expect("AB listed");
    // along t = perp(n), n from the pair's first disc to its second: the
    // same value gives the force (−20, 3) on A in either order
    g.contacts.shear[k] = 3.0;
    g
}

#[test]
fn love_weber_of_three_discs_by_hand() {
    let g = three_discs();
    // every disc inside: Σ f⊗l = [xx −36, xy 0, yx 5.4, yy −28] (A: AB
    // (−20, 3)⊗(0.9, 0), AC (0, −10)⊗(0, 0.95), floor (0, 10)⊗(0, −0.9);
    // B: (20, −3)⊗(−0.9, 0); C: (0, 10)⊗(0, −0.95)); A t = 25 × 2
    let all = Region::Rectangle {
        lo: Vec2::new(-2.0, -2.0),
        hi: Vec2::new(3.0, 3.0),
    };
    let m = measure::contacts(&g, &all, []);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-14 * b.abs().max(1.0);
    assert!(close(m.stress[0], 36.0 / 50.0), "{:?}", m.stress);
    assert!(close(m.stress[1], 28.0 / 50.0), "{:?}", m.stress);
    assert!(close(m.stress[2], -2.7 / 50.0), "{:?}", m.stress);
    assert_eq!((m.discs, m.contacts), (3, 5));
    assert!(close(m.coordination, 5.0 / 3.0));
    assert!(close(m.fabric[0], 0.4) && close(m.fabric[1], 0.6) && m.fabric[2] == 0.0);
    assert!(close(measure::porosity(&g, &all), 1.0 - 3.0 * PI / 25.0));
    // a circle of radius 1.5 about A holds A alone: its three contacts
    let around_a = Region::Circle {
        centre: Vec2::ZERO,
        radius: 1.5,
    };
    let m = measure::contacts(&g, &around_a, []);
    let at = 2.25 * PI * 2.0;
    assert!(close(m.stress[0], 18.0 / at), "{:?}", m.stress);
    assert!(close(m.stress[1], 18.5 / at), "{:?}", m.stress);
    assert!(close(m.stress[2], -1.35 / at), "{:?}", m.stress);
    assert_eq!((m.discs, m.contacts), (1, 3));
    assert!(close(m.coordination, 3.0));
    assert!(close(m.fabric[0], 1.0 / 3.0) && close(m.fabric[1], 2.0 / 3.0));
    // porosity: A whole, B and C cut by the circle (against a fine grid)
    let n = 3000;
    let mut solid = 0usize;
    for i in 0..n {
        for j in 0..n {
            let q = Vec2::new(
                -1.5 + 3.0 * (i as f64 + 0.5) / n as f64,
                -1.5 + 3.0 * (j as f64 + 0.5) / n as f64,
            );
            if q.norm2() < 2.25 {
                solid += [[0.0, 0.0], [1.8, 0.0], [0.0, 1.9]]
                    .iter()
                    .filter(|c| (q - Vec2::from(**c)).norm2() < 1.0)
                    .count();
            }
        }
    }
    let grid = 1.0 - solid as f64 * (3.0 / n as f64).powi(2) / (2.25 * PI);
    let por = measure::porosity(&g, &around_a);
    assert!((por - grid).abs() < 1e-4, "{por} vs grid {grid}");
    // a rectangle holding B alone: its one contact, the force (20, −3) at
    // the branch (−0.9, 0)
    let b_only = Region::Rectangle {
        lo: Vec2::new(1.0, -1.0),
        hi: Vec2::new(3.0, 1.0),
    };
    let m = measure::contacts(&g, &b_only, []);
    assert!(close(m.stress[0], 18.0 / 8.0) && m.stress[1] == 0.0);
    assert!(close(m.stress[2], -2.7 / 2.0 / 8.0));
    // an empty region
    let empty = Region::Circle {
        centre: Vec2::new(10.0, 10.0),
        radius: 1.0,
    };
    let m = measure::contacts(&g, &empty, []);
    assert_eq!(
        (m.stress, m.coordination, m.fabric),
        ([0.0; 3], 0.0, [0.0; 3])
    );
    assert_eq!(measure::porosity(&g, &empty), 1.0);
}

/// A contact with a body reaches the measure as an outer contact.
#[test]
fn outer_contacts_count_like_wall_contacts() {
    let g = three_discs();
    let all = Region::Rectangle {
        lo: Vec2::new(-2.0, -2.0),
        hi: Vec2::new(3.0, 3.0),
    };
    let base = measure::contacts(&g, &all, []);
    // C pressed from above by a body: force (1, −4) at (0, 2.85)
    let o = measure::OuterContact {
        slot: g.slot(2),
        point: Vec2::new(0.0, 2.85),
        normal: Vec2::new(0.0, 1.0),
        force: Vec2::new(1.0, -4.0),
    };
    let m = measure::contacts(&g, &all, [o]);
    assert_eq!(m.contacts, 6);
    // Σ f⊗l gains xx 0, xy 1 × 0.95, yx 0, yy −4 × 0.95
    assert!((m.stress[1] - (base.stress[1] + 3.8 / 50.0)).abs() < 1e-15);
    assert!((m.stress[2] - (base.stress[2] - 0.95 / 2.0 / 50.0)).abs() < 1e-15);
    assert_eq!(m.stress[0], base.stress[0]);
}

fn build(src: &str) -> Model {
    scenario::parse(src, "t.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

const MATERIALS: &str = r#"
[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[[material]]
name = "smooth"
kn = 1.0e6
"#;

/// A confined packing at rest: ~1000 discs in a box closed by four
/// frictionless servo walls at σ_x = 4e4, σ_y = 6e4 (no gravity). The box
/// measures the walls' stresses (exactly, at equilibrium); regions inside
/// it measure them up to the packing's heterogeneity.
#[test]
fn confined_packing_measures_the_wall_stresses() {
    let (sx, sy) = (4.0e4, 6.0e4);
    let wall = |name: &str, from: [f64; 2], to: [f64; 2], s: f64| {
        format!(
            "[[wall]]\nname = \"{name}\"\nfrom = {from:?}\nto = {to:?}\nmaterial = \"smooth\"\nservo = {{ stress = {s}, max_velocity = 0.2 }}\n"
        )
    };
    let src = format!(
        r#"
[simulation]
end_time = 0.5
{MATERIALS}
[granular]
material = "sand"
discs = {{ generate = "random", box = [[0.0, 0.0], [0.2, 0.2]], radius = [0.002, 0.003], seed = 11 }}
damping = {{ kind = "critical-ratio", zeta = 0.3 }}
{}{}{}{}
[[measure]]
name = "core"
rectangle = [[0.03, 0.03], [0.1, 0.1]]

[[measure]]
name = "disc"
centre = [0.07, 0.07]
radius = 0.035
"#,
        wall("floor", [0.0, 0.0], [0.2, 0.0], sy),
        wall("left", [0.0, 0.0], [0.0, 0.2], sx),
        wall("right", [0.2, 0.0], [0.2, 0.2], sx),
        wall("top", [0.0, 0.2], [0.2, 0.2], sy),
    );
    let sc = scenario::parse(&src, "t.toml").unwrap();
    let mut m = sc.build().unwrap();
    while m.step < m.steps {
        m.step().unwrap();
    }
    let g = m.granular().unwrap();
    let e = g.energies();
    let w = |n: &str| g.walls.iter().find(|w| w.name == n).unwrap();
    let (x0, x1, y0, y1) = (w("left").a.x, w("right").a.x, w("floor").a.y, w("top").a.y);
    let wx = (w("left").normal_stress(1.0) + w("right").normal_stress(1.0)) / 2.0;
    let wy = (w("floor").normal_stress(1.0) + w("top").normal_stress(1.0)) / 2.0;
    eprintln!(
        "{} discs, box [{x0:.4}, {x1:.4}] × [{y0:.4}, {y1:.4}], kinetic {:.2e} J; walls σ_x = {wx:.6e}, σ_y = {wy:.6e}",
        g.particles.len(),
        e.kinetic + e.rotational
    );
    assert!(((wx - sx) / sx).abs() < 0.01 && ((wy - sy) / sy).abs() < 0.01);
    let whole = Region::Rectangle {
        lo: Vec2::new(x0, y0),
        hi: Vec2::new(x1, y1),
    };
    // the inner regions: centred in the present box, 60 % of its size
    let (cx, cy, lx, ly) = (0.5 * (x0 + x1), 0.5 * (y0 + y1), x1 - x0, y1 - y0);
    let inner = Region::Rectangle {
        lo: Vec2::new(cx - 0.3 * lx, cy - 0.3 * ly),
        hi: Vec2::new(cx + 0.3 * lx, cy + 0.3 * ly),
    };
    let circle = Region::Circle {
        centre: Vec2::new(cx, cy),
        radius: 0.3 * lx.min(ly),
    };
    let show = |what: &str, r: &Region| {
        let c = measure::contacts(g, r, []);
        let (ex, ey) = ((c.stress[0] - wx) / wx, (c.stress[1] - wy) / wy);
        eprintln!(
            "{what}: σ_xx = {:.6e} ({ex:+.2e}), σ_yy = {:.6e} ({ey:+.2e}), σ_xy = {:.2e}; {} discs, Z = {:.3}, F = [{:.3}, {:.3}, {:.3}], porosity {:.4}",
            c.stress[0],
            c.stress[1],
            c.stress[2],
            c.discs,
            c.coordination,
            c.fabric[0],
            c.fabric[1],
            c.fabric[2],
            measure::porosity(g, r)
        );
        assert!((c.fabric[0] + c.fabric[1] - 1.0).abs() < 1e-12);
        (c, ex, ey)
    };
    // the whole box: at equilibrium exactly the walls' stresses
    let (c, ex, ey) = show("whole box", &whole);
    assert!(ex.abs() < 0.002 && ey.abs() < 0.002, "{ex} {ey}");
    assert_eq!(c.discs, g.particles.len());
    // ten full-height strips and ten full-width bands partition the discs
    // (half-open rectangles): their area-weighted stresses add up to the
    // box's. A strip's σ_xx and a band's σ_yy are the walls' on average
    // (the force across a cut); the other components vary from strip to
    // strip with the force chains
    let mut sum = [[0.0; 3]; 2];
    let mut spread = [(f64::INFINITY, f64::NEG_INFINITY); 2];
    for k in 0..10 {
        let f = |a: f64, b: f64, k: usize| a + (b - a) * k as f64 / 10.0;
        let strip = Region::Rectangle {
            lo: Vec2::new(f(x0, x1, k), y0),
            hi: Vec2::new(f(x0, x1, k + 1), y1),
        };
        let band = Region::Rectangle {
            lo: Vec2::new(x0, f(y0, y1, k)),
            hi: Vec2::new(x1, f(y0, y1, k + 1)),
        };
        for (i, (r, own, w)) in [(strip, 0, wx), (band, 1, wy)].into_iter().enumerate() {
            let c = measure::contacts(g, &r, []);
            for (s, v) in sum[i].iter_mut().zip(c.stress) {
                *s += 0.1 * v;
            }
            let e = c.stress[own] / w - 1.0;
            spread[i] = (spread[i].0.min(e), spread[i].1.max(e));
        }
    }
    for s in sum {
        for (a, b) in s.iter().zip(c.stress) {
            assert!(
                (a - b).abs() < 1e-12 * b.abs().max(1.0),
                "{s:?} vs {:?}",
                c.stress
            );
        }
    }
    eprintln!(
        "10 strips: σ_xx from {:+.3} to {:+.3} of the walls'; 10 bands: σ_yy from {:+.3} to {:+.3}",
        spread[0].0, spread[0].1, spread[1].0, spread[1].1
    );
    // regions inside the box: the packing's own heterogeneity (printed)
    show("inner 60 % rectangle", &inner);
    show("inner circle", &circle);
    // the [[measure]] columns are the same numbers
    let probes = sc.probes(&m).unwrap();
    let names: Vec<&str> = probes.iter().map(|p| p.0.as_str()).collect();
    assert_eq!(
        names,
        [
            "core_sxx_cpos",
            "core_syy_cpos",
            "core_sxy_cpos",
            "core_porosity",
            "core_coordination",
            "core_fxx",
            "core_fyy",
            "core_fxy",
            "disc_sxx_cpos",
            "disc_syy_cpos",
            "disc_sxy_cpos",
            "disc_porosity",
            "disc_coordination",
            "disc_fxx",
            "disc_fyy",
            "disc_fxy"
        ]
    );
    let core = Region::Rectangle {
        lo: Vec2::new(0.03, 0.03),
        hi: Vec2::new(0.1, 0.1),
    };
    let c = measure::contacts(g, &core, []);
    for (k, q) in Quantity::ALL.into_iter().enumerate() {
        let want = if q == Quantity::Porosity {
            measure::porosity(g, &core)
        } else {
            c.get(q)
        };
        assert_eq!(m.probe(&probes[k].1).to_bits(), want.to_bits(), "{q:?}");
    }
    // time for one row of a measure (all eight columns, on a state not
    // measured before: fresh probes) against one step
    let reps = 200;
    let (mut t_row, mut t_one, mut t_step) = (0.0, 0.0, 0.0);
    let mut s = 0.0;
    for _ in 0..reps {
        let t0 = std::time::Instant::now();
        m.step().unwrap();
        t_step += t0.elapsed().as_secs_f64();
        let fresh = sc.probes(&m).unwrap();
        let t0 = std::time::Instant::now();
        for (_, p) in &fresh[..8] {
            s += m.probe(p);
        }
        t_row += t0.elapsed().as_secs_f64();
        let fresh = sc.probes(&m).unwrap();
        let t0 = std::time::Instant::now();
        s += m.probe(&fresh[0].1);
        t_one += t0.elapsed().as_secs_f64();
    }
    let n = g_len(&m);
    let k = 1e6 / reps as f64;
    eprintln!(
        "cost ({n} discs, {} threads): one step {:.1} µs; a measure's 8 columns {:.1} µs (ratio {:.2}), one stress column {:.1} µs [{s:.1}]",
        rayon::current_num_threads(),
        t_step * k,
        t_row * k,
        t_row / t_step,
        t_one * k
    );
}

fn g_len(m: &Model) -> usize {
    m.granular().unwrap().particles.len()
}

/// Discs settled under gravity between frictionless side walls: the
/// vertical stress in a horizontal band is the weight of the discs above
/// per unit width (averaged over the band's height, as the measure is).
#[test]
fn settled_packing_measures_the_weight_above() {
    let (width, g_acc) = (0.2, 9.81);
    let src = format!(
        r#"
[simulation]
end_time = 1.2
gravity = [0.0, -{g_acc}]
{MATERIALS}
[granular]
material = "sand"
discs = {{ generate = "random", box = [[0.0, 0.0], [{width}, 0.3]], radius = [0.002, 0.004], seed = 4 }}
damping = {{ kind = "local", alpha = 0.5 }}

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [{width}, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 0.4]
material = "smooth"

[[wall]]
name = "right"
from = [{width}, 0.0]
to = [{width}, 0.4]
material = "smooth"
"#
    );
    let mut m = build(&src);
    while m.step < m.steps {
        m.step().unwrap();
    }
    let g = m.granular().unwrap();
    let p = &g.particles;
    let e = g.energies();
    let top = (0..p.len())
        .map(|k| p.pos[k].y + p.radius[k])
        .fold(0.0, f64::max);
    let floor = -g.walls[0].force.y;
    let weight: f64 = p.mass.iter().sum::<f64>() * g_acc;
    eprintln!(
        "{} discs settled to height {top:.4}; kinetic {:.2e} J; floor carries {:.6} of the weight",
        p.len(),
        e.kinetic + e.rotational,
        floor / weight
    );
    assert!((floor / weight - 1.0).abs() < 0.01);
    let h = 0.06;
    for depth in [0.05, 0.08, 0.11] {
        let (ya, yb) = (top - depth - 0.5 * h, top - depth + 0.5 * h);
        let band = Region::Rectangle {
            lo: Vec2::new(0.0, ya),
            hi: Vec2::new(width, yb),
        };
        let c = measure::contacts(g, &band, []);
        // (1/h) ∫ W(z) dz over the band, W(z) the weight above z
        let avg: f64 = (0..p.len())
            .map(|k| p.mass[k] * g_acc * ((p.pos[k].y - ya) / h).clamp(0.0, 1.0))
            .sum::<f64>()
            / (width * g.thickness);
        let mid: f64 = (0..p.len())
            .filter(|&k| p.pos[k].y > top - depth)
            .map(|k| p.mass[k] * g_acc)
            .sum::<f64>()
            / (width * g.thickness);
        let err = (c.stress[1] - avg) / avg;
        eprintln!(
            "band at depth {depth} (h = {h}, {} discs): σ_yy = {:.6e}, weight above {avg:.6e} (error {err:+.2e}); at mid-depth {mid:.6e} ({:+.2e}); σ_xx = {:.4e} (K = {:.3})",
            c.discs,
            c.stress[1],
            (c.stress[1] - mid) / mid,
            c.stress[0],
            c.stress[0] / c.stress[1]
        );
        assert!(err.abs() < 0.02, "{err}");
        assert!(((c.stress[1] - mid) / mid).abs() < 0.02);
    }
}

/// `efgdem run` writes the `[[measure]]` columns after the probes.
#[test]
fn measure_columns_in_history_csv() {
    let dir = common::tmpdir("measure_cli");
    let file = dir.join("m.toml");
    std::fs::write(
        &file,
        format!(
            r#"
[simulation]
steps = 20
gravity = [0.0, -9.81]
{MATERIALS}
[granular]
material = "sand"
discs = [[0.1, 0.1, 0.05], [0.2, 0.1, 0.05]]

[[wall]]
name = "floor"
from = [0.0, 0.05]
to = [1.0, 0.05]

[[probe]]
name = "n"
quantity = "contacts"

[[probe]]
name = "floor_s"
wall = "floor"
quantity = "wall_stress"

[[measure]]
name = "bed"
centre = [0.15, 0.1]
radius = 0.2
quantities = ["syy_cpos", "porosity", "coordination"]
"#
        ),
    )
    .unwrap();
    let out = dir.join("out");
    common::run(&file, &out);
    assert_eq!(common::summary(&out)["status"], "completed");
    let csv = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "step,t,n,floor_s,bed_syy_cpos,bed_porosity,bed_coordination"
    );
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    // two discs on the floor: porosity 1 − 2πr²/(π 0.2²), one contact each
    assert!((last[5] - (1.0 - 2.0 * 0.05f64.powi(2) / 0.04)).abs() < 1e-12);
    assert_eq!(last[6], 1.0);
    assert!(last[4] > 0.0 && last[3] > 0.0);
}
