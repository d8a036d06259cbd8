//! The biaxial test (issue 13 §5): a packing grown in a box of four walls,
//! consolidated isotropically by servo walls, then compressed by its top
//! and bottom walls at a constant strain rate (wall `phases`) while the
//! side walls hold σ₃. Fast version (500 discs, 5 % of axial strain): the
//! side walls hold σ₃ within 1 % (means over 200 steps; single steps but
//! during a few rearrangements); the Love–Weber stress of the whole
//! sample (§4) equals the walls' stresses within 2 % (means over 1000
//! steps; the discs' inertia is left in single states); `efgdem run` writes the same `history.csv`
//! on 1 and 2 threads, and `efgdem::biaxial` reads it. The full example
//! (`examples/biaxial.toml`, ~2 min) is behind `--ignored`.

use efgdem::biaxial::{self, History, Options, Setup};
use efgdem::dem::Granular;
use efgdem::dem::measure::{self, Region};
use efgdem::geom::Vec2;
use efgdem::model::Model;
use efgdem::run::RunOptions;
use efgdem::scenario::{self, Scenario};
use std::path::{Path, PathBuf};

#[allow(dead_code)]
mod common;

const SIGMA3: f64 = 1.0e5;
/// Steps of the consolidation; the shearing follows.
const CONSOLIDATION: usize = 12_000;

/// 500 discs (r = 0.5–1 mm) grown in a 24 × 48 mm box (frictionless
/// growth), consolidated to σ₃ = 100 kPa by four proportional servo
/// walls, then compressed at ε̇ = 2 /s (I = 4.9e-4) while the side walls
/// hold σ₃ with integral action; μ = 0.5, μ_r = 0.1, ζ = 0.2 — the
/// example's material at a tenth of its size and four times its rate.
fn small(steps: usize) -> String {
    small_seeded(steps, 3)
}

/// [`small`] with the packing grown from `seed`.
fn small_seeded(steps: usize, seed: u64) -> String {
    // proportional servos for the consolidation, integral action for the
    // side walls while the sample is sheared
    let servo = format!("servo = {{ stress = {SIGMA3:e}, max_velocity = 0.1, relaxation = 1.0 }}");
    let servo_pi = format!(
        "servo = {{ stress = {SIGMA3:e}, max_velocity = 0.1, relaxation = 1.0, integral = 0.1 }}"
    );
    let wall = |name: &str, from: [f64; 2], to: [f64; 2], motion: &str| {
        format!(
            "[[wall]]\nname = \"{name}\"\nfrom = {from:?}\nto = {to:?}\nmaterial = \"smooth\"\n{motion}\n\n"
        )
    };
    let axial =
        format!("phases = [{{ until_step = {CONSOLIDATION}, {servo} }}, {{ strain_rate = 2.0 }}]");
    let lateral =
        format!("phases = [{{ until_step = {CONSOLIDATION}, {servo} }}, {{ {servo_pi} }}]");
    let probe = |name: &str, wall: &str, q: &str| {
        format!("[[probe]]\nname = \"{name}\"\nwall = \"{wall}\"\nquantity = \"{q}\"\n\n")
    };
    format!(
        r#"[simulation]
dt = 1.4e-6
steps = {steps}

[output]
every = 200

[[material]]
name = "grain"
density = 2650.0
kn = 1.0e8
ks = 5.0e7
friction = 0.5
rolling_friction = 0.1

[[material]]
name = "smooth"
kn = 1.0e8

[granular]
material = "grain"
discs = {{ generate = "random", method = "grow", box = [[0.0, 0.0], [0.024, 0.048]], radius = [0.0005, 0.001], count = 500, seed = {seed}, settle_steps = 10000, settle_material = "smooth" }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}

{}{}{}{}{}{}{}{}{}{}{}{}[[measure]]
name = "all"
rectangle = [[-0.01, -0.01], [0.034, 0.058]]
quantities = ["sxx_cpos", "syy_cpos", "porosity"]
"#,
        wall("bottom", [0.0, 0.0], [0.024, 0.0], &axial),
        wall("top", [0.0, 0.048], [0.024, 0.048], &axial),
        wall("left", [0.0, 0.0], [0.0, 0.048], &lateral),
        wall("right", [0.024, 0.0], [0.024, 0.048], &lateral),
        probe("sb", "bottom", "wall_stress"),
        probe("st", "top", "wall_stress"),
        probe("sl", "left", "wall_stress"),
        probe("sr", "right", "wall_stress"),
        probe("yb", "bottom", "wall_y"),
        probe("yt", "top", "wall_y"),
        probe("xl", "left", "wall_x"),
        probe("xr", "right", "wall_x"),
    )
}

/// Steps of the fast test: consolidation, then 18 000 steps of shearing
/// (ε₁ = 1 − e^{−2 × 0.0252} = 4.9 %).
const STEPS: usize = CONSOLIDATION + 18_000;

fn build(src: &str) -> Model {
    scenario::parse(src, "biaxial.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

fn wall<'a>(g: &'a Granular, name: &str) -> &'a efgdem::dem::walls::Wall {
    g.walls.iter().find(|w| w.name == name).unwrap()
}

/// `[σ_xx, σ_yy]` of the whole sample (Love–Weber over the walls' box)
/// and `[σ_lateral, σ_axial]` of the walls.
fn stresses(g: &Granular) -> ([f64; 2], [f64; 2]) {
    let (x0, x1) = (wall(g, "left").a.x, wall(g, "right").a.x);
    let (y0, y1) = (wall(g, "bottom").a.y, wall(g, "top").a.y);
    let region = Region::Rectangle {
        lo: Vec2::new(x0, y0),
        hi: Vec2::new(x1, y1),
    };
    let s = measure::contacts(g, &region, []).stress;
    let t = g.thickness;
    let mean = |a: &str, b: &str| 0.5 * (wall(g, a).normal_stress(t) + wall(g, b).normal_stress(t));
    ([s[0], s[1]], [mean("left", "right"), mean("bottom", "top")])
}

#[test]
fn side_walls_hold_sigma3_and_the_sample_measures_the_wall_stresses() {
    let mut m = build(&small(STEPS));
    let h0 = {
        let g = m.granular().unwrap();
        wall(g, "top").a.y - wall(g, "bottom").a.y
    };
    // the consolidation: every wall at σ₃, the sample at rest
    while m.step < CONSOLIDATION {
        m.step().unwrap();
    }
    let g = m.granular().unwrap();
    let (lw, walls) = stresses(g);
    let (hc, wc) = (
        wall(g, "top").a.y - wall(g, "bottom").a.y,
        wall(g, "right").a.x - wall(g, "left").a.x,
    );
    eprintln!(
        "consolidated: box {wc:.5} × {hc:.5} (grown in 0.024 × 0.048), walls σ = {walls:?}, Love–Weber {lw:?}"
    );
    for w in &g.walls {
        let e = (w.normal_stress(g.thickness) - SIGMA3) / SIGMA3;
        assert!(e.abs() < 1e-3, "{}: {e}", w.name);
    }
    for k in 0..2 {
        assert!(
            ((lw[k] - walls[k]) / walls[k]).abs() < 5e-3,
            "{lw:?} {walls:?}"
        );
    }
    assert!(hc < h0, "the consolidation compressed the sample");
    // the shearing
    let (mut worst3, mut sum3, mut n3) = (0.0f64, 0.0, 0);
    let (mut at3, mut over1) = (0usize, 0usize);
    // means over blocks of 200 steps (~2 transit times of a sound wave
    // across the sample: a rigid wall's force is a sum of contacts and
    // jumps when a force chain at it buckles; a servo follows within
    // tens of steps)
    let (mut block, mut worst_block) = ([0.0f64; 2], 0.0f64);
    let (mut lw_sum, mut wall_sum) = ([0.0; 2], [0.0; 2]);
    let (mut worst_row, mut worst_window) = (0.0f64, 0.0f64);
    let mut q_max = 0.0f64;
    while m.step < STEPS {
        m.step().unwrap();
        let g = m.granular().unwrap();
        for (k, side) in ["left", "right"].into_iter().enumerate() {
            let e = (wall(g, side).normal_stress(g.thickness) - SIGMA3) / SIGMA3;
            block[k] += e / 200.0;
            if m.step.is_multiple_of(200) {
                worst_block = worst_block.max(block[k].abs());
                block[k] = 0.0;
            }
            if e.abs() > worst3 {
                at3 = m.step;
            }
            worst3 = worst3.max(e.abs());
            over1 += (e.abs() > 0.01) as usize;
            sum3 += e;
            n3 += 1;
        }
        if m.step.is_multiple_of(50) {
            let (lw, walls) = stresses(g);
            q_max = q_max.max(walls[1] - walls[0]);
            for k in 0..2 {
                worst_row = worst_row.max(((lw[k] - walls[k]) / walls[k]).abs());
                lw_sum[k] += lw[k];
                wall_sum[k] += walls[k];
            }
            // windows of 1000 steps (0.2 % of axial strain)
            if m.step.is_multiple_of(1000) {
                for k in 0..2 {
                    let e = (lw_sum[k] - wall_sum[k]) / wall_sum[k];
                    worst_window = worst_window.max(e.abs());
                }
                (lw_sum, wall_sum) = ([0.0; 2], [0.0; 2]);
            }
        }
    }
    let g = m.granular().unwrap();
    let h = wall(g, "top").a.y - wall(g, "bottom").a.y;
    eprintln!(
        "side walls' σ: 200-step means within {:.3} % of σ₃; single steps: worst at step {at3}, {over1} of {n3} wall-steps above 1 %",
        100.0 * worst_block
    );
    eprintln!(
        "sheared to ε₁ = {:.3} %, q up to {q_max:.4e}: side walls' σ within {:.3} % of σ₃ at every step (mean {:+.4} %); whole-sample Love–Weber vs walls: {:.3} % (1000-step means), {:.3} % (single states)",
        100.0 * (hc - h) / hc,
        100.0 * worst3,
        100.0 * sum3 / n3 as f64,
        100.0 * worst_window,
        100.0 * worst_row
    );
    assert!(
        q_max > 0.5 * SIGMA3,
        "the sample carried a deviatoric stress"
    );
    assert!(worst_block < 0.01, "σ₃ held within 1 %: {worst_block}");
    // single steps: within 1 % but during rearrangements (< 1 % of them)
    assert!(over1 * 100 < n3 && worst3 < 0.05, "{over1} {worst3}");
    assert!(
        worst_window < 0.02,
        "Love–Weber = walls within 2 %: {worst_window}"
    );
}

/// Without integral action (`integral = 0`, the plain PFC servo) the side
/// walls lag behind the dilating sample: their stress stays above σ₃ by
/// `v/G` while they move out.
#[test]
fn integral_action_removes_the_servo_lag() {
    let mean_error = |src: &str| {
        let mut m = build(src);
        let (mut sum, mut n) = (0.0, 0);
        while m.step < STEPS {
            m.step().unwrap();
            // from 0.7 % of axial strain on (the sides move out steadily)
            if m.step > CONSOLIDATION + 2500 {
                let g = m.granular().unwrap();
                for side in ["left", "right"] {
                    sum += (wall(g, side).normal_stress(g.thickness) - SIGMA3) / SIGMA3;
                    n += 1;
                }
            }
        }
        sum / n as f64
    };
    let pi = mean_error(&small(STEPS));
    let p = mean_error(&small(STEPS).replace(", integral = 0.1", ""));
    eprintln!(
        "mean error of the side walls' stress while shearing: {:+.4} % with integral action, {:+.4} % without",
        100.0 * pi,
        100.0 * p
    );
    // measured +0.0010 % with integral action, +7.49 % without (quoted
    // in docs/scenario.md, "Integral action")
    assert!(pi.abs() < 1e-4, "{pi}");
    assert!(p > 5.0 * pi.abs() && p > 0.05, "{p}");
}

fn out_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("efgdem-biaxial-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// `efgdem::run::run` of `sc` on `threads` threads into `dir`.
fn drive(sc: &Scenario, threads: usize, dir: &Path) {
    let opts = RunOptions {
        quiet: true,
        ..RunOptions::new(dir)
    };
    common::on_threads(threads, || efgdem::run::run(sc, &opts)).unwrap();
}

#[test]
fn history_is_the_same_on_one_and_two_threads_and_post_processes() {
    let sc = scenario::parse(&small(STEPS), "biaxial.toml").unwrap();
    let (d1, d2) = (out_dir("1"), out_dir("2"));
    drive(&sc, 1, &d1);
    drive(&sc, 2, &d2);
    let (h1, h2) = (
        std::fs::read(d1.join("history.csv")).unwrap(),
        std::fs::read(d2.join("history.csv")).unwrap(),
    );
    assert!(h1 == h2, "history.csv differs between 1 and 2 threads");
    assert!(
        std::fs::read(d1.join("discs_final.csv")).unwrap()
            == std::fs::read(d2.join("discs_final.csv")).unwrap()
    );
    // the post-processing finds the test and reads the history
    let setup = Setup::from_scenario(&sc).unwrap();
    assert_eq!(setup.shear_from, CONSOLIDATION);
    assert_eq!((setup.strain_rate, setup.sigma3), (2.0, SIGMA3));
    assert_eq!(setup.axial_stress, ["sb".to_string(), "st".to_string()]);
    assert_eq!(setup.lateral_position, ["xl".to_string(), "xr".to_string()]);
    let (name, rect) = setup
        .whole
        .clone()
        .expect("the `all` measure holds the sample");
    assert_eq!(
        (name.as_str(), rect),
        ("all", [[-0.01, -0.01], [0.034, 0.058]])
    );
    let i = setup.inertial_number().unwrap();
    assert!((i - 2.0 * 1.5e-3 * (2650.0f64 / SIGMA3).sqrt()).abs() < 1e-15);
    let h = History::read(&d1.join("history.csv")).unwrap();
    let p = biaxial::curve(&setup, &h).unwrap();
    assert_eq!(p.len(), (STEPS - CONSOLIDATION) / 200 + 1);
    assert_eq!((p[0].eps1, p[0].epsv), (0.0, 0.0));
    let end = p.last().unwrap();
    assert!(
        (end.log1 - 2.0 * 18_000.0 * 1.4e-6).abs() < 1e-3,
        "{}",
        end.log1
    );
    let s = biaxial::summarize(&setup, &p, &Options::default());
    eprintln!("{s:#?}");
    // σ₃ is held as in the full example below: the rows are single states
    // (every 200 steps), 98 % of the lateral walls' stresses within 1 % of
    // σ₃ and no bias (the servo's control), single rows within 3 % (a
    // rearrangement of the packing unloads a wall for a moment, before the
    // servo catches up: measured 0.88 % and 1.21 % on two realizations
    // that differ only in the order of the force sums, 99.5–100 % of the
    // rows within 1 %). A servo aiming at another stress (a factor of two)
    // has a bias of tens of per cent; one of the wrong sign runs away.
    assert!(s.sigma3_error < 0.03, "{s:?}");
    assert!(s.sigma3_within_1pc > 0.98, "{s:?}");
    assert!(s.sigma3_bias.abs() < 1e-3, "{s:?}");
    assert!(s.love_weber_error.unwrap() < 0.02, "{s:?}");
    assert_eq!(s.love_weber_rows, p.len());
    assert!(s.phi_peak > 15.0 && s.phi_peak < 40.0, "{s:?}");
    for d in [d1, d2] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// The full example, `examples/biaxial.toml` (5 000 discs, 272 000 steps,
/// 75 s on 2 cores): σ₃ within 1 % (99 % of the rows; the rest within
/// 3 %, at rearrangements), the whole sample's Love–Weber
/// stress = the walls' within 2 %, a peak above the critical state; and
/// the same history on 1 thread (145 s for both here).
#[test]
#[ignore]
fn full_biaxial_example() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/biaxial.toml");
    let sc = scenario::load(&file).unwrap();
    let (d2, d1) = (out_dir("full2"), out_dir("full1"));
    drive(&sc, 2, &d2);
    let setup = Setup::from_scenario(&sc).unwrap();
    let h = History::read(&d2.join("history.csv")).unwrap();
    let p = biaxial::curve(&setup, &h).unwrap();
    let s = biaxial::summarize(&setup, &p, &Options::default());
    eprintln!("{s:#?}\nI = {:.3e}", setup.inertial_number().unwrap());
    // rows are single states: within 1 % but at a few rearrangements
    assert!(s.sigma3_within_1pc > 0.99 && s.sigma3_error < 0.03, "{s:?}");
    assert!(s.sigma3_bias.abs() < 1e-3, "{s:?}");
    assert!(s.love_weber_error.unwrap() < 0.02, "{s:?}");
    assert!(s.phi_peak > s.phi_cs && s.psi_max > 0.0, "{s:?}");
    assert!(setup.inertial_number().unwrap() < 1e-3);
    drive(&sc, 1, &d1);
    assert!(
        std::fs::read(d1.join("history.csv")).unwrap()
            == std::fs::read(d2.join("history.csv")).unwrap(),
        "history.csv differs between 1 and 2 threads"
    );
    for d in [d1, d2] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// Grain shape (fast version of `examples/biaxial_clumps.toml`): the
/// sample of [`small`] with μ_r = 0, sheared to 9.6 % axial strain, once
/// as round discs and once with each disc replaced by a rigid clump of two
/// discs (radius 0.8 r, 0.4 r apart: elongation 1.25, inside the disc's
/// circle); and, third, as round discs with rolling resistance μ_r = 0.1
/// ([`small`]'s own material); each on three packings (seeds 3, 4, 5).
/// A 500-grain sample's friction angles move with round-off (a change of
/// the clumps' sine and cosine by an ulp in a few angles moved seed 3's
/// critical-state angle of the clumps from 21.8° to 19.5°-20.6°), so the
/// gaps are asserted on the means over the seeds: grain shape raises the
/// friction angle at the critical state (the mean over the last third of
/// the shear) by more than 2°, and the peak is higher too; rolling
/// resistance raises it by more than 3°; in each packing, the clumps' and
/// rolling resistance's critical-state angles are above the round discs'.
/// Measured (means): φ_cs 21.0° (clumps), 21.9° (rolling), 16.1°
/// (round); φ_peak 22.7° (clumps), 18.8° (round); with the clumps' sine
/// and cosine changed by an ulp in a few angles, 21.4° and 23.5° for the
/// clumps (seed 5's φ_cs moved from 19.3° to 22.5°). Clumps and rolling resistance
/// swap places between seeds, so their order is not asserted. The
/// clumps' whole-sample Love–Weber stress (branch vectors from the
/// clumps' centres) equals the walls' within 2 %, as for discs.
#[test]
fn clumps_give_a_higher_peak_friction_angle_than_round_discs() {
    let samples = SEEDS.map(|seed| {
        let [round, clumps, rolling] = small_three(seed);
        let parse = |src: &str| scenario::parse(src, "biaxial.toml").unwrap();
        [
            (format!("round {seed}"), parse(&round)),
            (format!("clumps {seed}"), parse(&clumps)),
            (format!("rolling {seed}"), parse(&rolling)),
        ]
    });
    shape_against_rolling(&samples);
}

/// The packings' seeds of the fast comparison of grain shape.
const SEEDS: [u64; 3] = [3, 4, 5];

/// The sources of the fast comparison of grain shape, packing grown from
/// `seed`: round discs, clumps of two discs, round discs with rolling
/// resistance.
fn small_three(seed: u64) -> [String; 3] {
    const SHEAR: usize = 36_000;
    let rolling = small_seeded(CONSOLIDATION + SHEAR, seed);
    let round = rolling.replace("rolling_friction = 0.1", "rolling_friction = 0.0");
    assert!(round.contains("rolling_friction = 0.0"));
    // the clumps turn under forces at their rims: a shorter step
    // (0.79 × the critical step of `efgdem check`), the same strain rate
    let scale = 1.4;
    let cons = (CONSOLIDATION as f64 * scale) as usize;
    let clumps = round
        .replace("dt = 1.4e-6", "dt = 1.0e-6")
        .replace(
            &format!("steps = {}", CONSOLIDATION + SHEAR),
            &format!("steps = {}", cons + (SHEAR as f64 * scale) as usize),
        )
        .replace(
            &format!("until_step = {CONSOLIDATION}"),
            &format!("until_step = {cons}"),
        )
        .replacen(
            "[[wall]]",
            "[clumps]\ntemplate = [[-0.2, 0.0, 0.8], [0.2, 0.0, 0.8]]\n\n[[wall]]",
            1,
        );
    assert!(clumps.contains(&format!("until_step = {cons}")) && clumps.contains("[clumps]"));
    [round, clumps, rolling]
}

/// Run the biaxial tests of each sample's round discs, clumps and round
/// discs with rolling resistance (in that order) and assert the gaps of
/// their friction angles, means over the samples: the clumps' peak above
/// the round discs', their critical-state angle by more than 2°, rolling
/// resistance's by more than 3°; in each sample the clumps' and rolling
/// resistance's critical-state angles above the round discs'; and each
/// whole-sample Love–Weber stress equal to the walls' within 2 %.
fn shape_against_rolling(samples: &[[(String, Scenario); 3]]) {
    let mut phi = vec![];
    for runs in samples {
        let mut three = vec![];
        for (tag, sc) in runs {
            let dir = out_dir(&tag.replace(' ', "-"));
            drive(sc, 2, &dir);
            let setup = Setup::from_scenario(sc).unwrap();
            let h = History::read(&dir.join("history.csv")).unwrap();
            let p = biaxial::curve(&setup, &h).unwrap();
            let s = biaxial::summarize(&setup, &p, &Options::default());
            eprintln!(
                "{tag}: φ_peak {:.2}° at ε₁ = {:.2} %, φ_cs {:.2}° ± {:.2}°, Love–Weber error {:?}",
                s.phi_peak,
                100.0 * s.eps1_peak,
                s.phi_cs,
                s.phi_cs_spread,
                s.love_weber_error
            );
            assert!(s.love_weber_error.unwrap() < 0.02, "{tag}: {s:?}");
            three.push((s.phi_peak, s.phi_cs));
            std::fs::remove_dir_all(dir).unwrap();
        }
        let ((_, cs_round), (_, cs_clumps), (_, cs_rolling)) = (three[0], three[1], three[2]);
        assert!(cs_clumps > cs_round && cs_rolling > cs_round, "{three:?}");
        phi.push(three);
    }
    let mean = |k: usize, peak: bool| {
        let a = |t: &Vec<(f64, f64)>| if peak { t[k].0 } else { t[k].1 };
        phi.iter().map(a).sum::<f64>() / phi.len() as f64
    };
    let (peak_round, peak_clumps) = (mean(0, true), mean(1, true));
    let (cs_round, cs_clumps, cs_rolling) = (mean(0, false), mean(1, false), mean(2, false));
    eprintln!(
        "means: φ_peak {peak_round:.2}° (round), {peak_clumps:.2}° (clumps); \
         φ_cs {cs_round:.2}°, {cs_clumps:.2}°, {cs_rolling:.2}° (rolling)"
    );
    assert!(peak_clumps > peak_round, "{phi:?}");
    assert!(cs_clumps > cs_round + 2.0, "{phi:?}");
    assert!(cs_rolling > cs_round + 3.0, "{phi:?}");
}

/// The full-size comparison of grain shape and rolling resistance
/// (5 000 grains, 15 % axial strain): `examples/biaxial_clumps.toml`
/// against `examples/biaxial.toml` with μ_r = 0 and 0.1 (the packing of
/// both is grown frictionless, so the three share it before the clumps
/// replace the discs). Measured: φ_peak / φ_cs 21.8° / 20.9° ± 0.5°
/// (clumps), 18.1° / 16.9° ± 0.5° (round), 23.9° / 21.2° ± 0.7° (round,
/// μ_r = 0.1). Asserted as in the fast test: the clumps' critical-state
/// angle above the round discs' by more than 2° and their peak higher,
/// rolling resistance's critical-state angle above by more than 3°.
/// 20–40 minutes on 2 cores (38 min measured on a shared, loaded machine).
#[test]
#[ignore]
fn full_clumps_against_round_discs_with_and_without_rolling_resistance() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let clumps = scenario::load(&root.join("examples/biaxial_clumps.toml")).unwrap();
    let rolling = scenario::load(&root.join("examples/biaxial.toml")).unwrap();
    let mut round = rolling.clone();
    for m in round.material.iter_mut().filter(|m| m.name == "grain") {
        m.rolling_friction = 0.0;
    }
    shape_against_rolling(&[[
        ("round".into(), round),
        ("clumps".into(), clumps),
        ("rolling".into(), rolling),
    ]]);
}
