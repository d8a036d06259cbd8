//! The Brazilian test of `examples/bonded_brazilian.toml` against
//! references that do not come from the Brazilian test itself: the same
//! bonded packing pulled apart between grips (direct tension) and crushed
//! between platens (uniaxial compression).
//!
//! - **σ_t against direct tension.** Elasticity gives the tensile stress
//!   at the centre of a disc loaded along a diameter as exactly
//!   `2F/(πDt)` (Timoshenko & Goodier, the Hertz solution), so a material
//!   that fails in tension at its centre gives σ_t equal to its direct
//!   tension strength. Departures come from the compressive stress
//!   `−6F/(πDt)` across the diameter at the centre, the crushing under
//!   the platens and the discreteness of a specimen 25 grains across;
//!   for bonded-particle models the ratio stays of order one (Potyondy &
//!   Cundall 2004 report Brazilian strengths of their PFC2D granite
//!   material of the same order as its tension strength). Asserted:
//!   `0.5 < σ_t / σ_DT < 2` — a factor two either way, which a wrong
//!   formula (a missing 2 or π) would break.
//! - **Crack pattern.** The splitting crack runs along the loaded
//!   diameter: at least 60 % of the broken bonds lie within 0.2 D of it
//!   and at least 80 % broke in tension.
//! - **UCS/σ_t.** Bonded discs are known to give a low ratio of the
//!   uniaxial compressive to the tensile strength (a few, where rock has
//!   10–20: Potyondy & Cundall 2004, Cho, Martin & Sego 2007, whose
//!   clumped particles were made to raise it). Asserted: `2 < UCS/σ_t < 8`
//!   (the square box's UCS).
//!
//! Measured (σ_t, direct tension, UCS of the square box, breaks near the
//! diameter / in tension): the fast test's 40 mm disc (cut from a 42 mm box of
//! 460 discs, the example's grains and bonds) 3.57, 3.97,
//! 15.4 MPa, 90/90/90 breaks; the example itself (50 mm, 499 discs,
//! behind `--ignored`) 3.05, 3.70, 18.4 MPa, 75/75/74. The example's
//! slender UCS specimen (`examples/bonded_ucs.toml`, 2:1) gives
//! 8.6 MPa: UCS/σ_t from 2.8 to 6 with the specimen's shape.

use efgdem::dem::Granular;
use efgdem::dem::particles::{FIX_ROT, FIX_X, FIX_Y};
use efgdem::geom::Vec2;
use efgdem::model::System;
#[allow(dead_code)]
mod common;

use common::{column, csv};
use efgdem::run::RunOptions;
use efgdem::scenario::{self, Scenario};
use std::path::{Path, PathBuf};

fn example() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/bonded_brazilian.toml"),
    )
    .unwrap()
}

/// Replace `from` by `to` once, asserting it was there.
fn swap(src: &str, from: &str, to: &str) -> String {
    assert!(src.contains(from), "`{from}` not in the scenario");
    src.replacen(from, to, 1)
}

/// The example at a smaller size: a 40 mm disc (20 grains across) from a
/// 42 mm box with as many discs per area (705 · (42/52)² = 460). A 30 mm
/// disc (15 grains) is too small to be a specimen: it gave σ_t = 5.6 MPa
/// against 2.4 MPa in direct tension.
fn small() -> String {
    let mut s = example();
    for (a, b) in [
        ("[0.052, 0.052]], radius", "[0.042, 0.042]], radius"),
        ("count = 705", "count = 460"),
        (
            "keep = { centre = [0.026, 0.026], radius = 0.025 }",
            "keep = { centre = [0.021, 0.021], radius = 0.02 }",
        ),
        ("to = [0.052, 0.001]", "to = [0.042, 0.001]"),
        (
            "from = [0.0, 0.051]\nto = [0.052, 0.051]",
            "from = [0.0, 0.041]\nto = [0.042, 0.041]",
        ),
    ] {
        s = swap(&s, a, b);
    }
    s
}

/// The square box the packing was grown in: `[x0, y0, x1, y1]`.
fn grown_box(sc: &Scenario) -> [f64; 4] {
    let g = sc.granular.as_ref().unwrap();
    let scenario::granular::DiscsSpec::Table(t) = &g.discs else {
        panic!("a generated packing")
    };
    let [a, b] = t.region.unwrap();
    [a[0], a[1], b[0], b[1]]
}

fn out_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("efgdem-brazilian-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn run(sc: &Scenario, dir: &Path) {
    let opts = RunOptions {
        quiet: true,
        ..RunOptions::new(dir)
    };
    efgdem::run::run(sc, &opts).unwrap();
}

struct Brazilian {
    /// Splitting tensile strength 2F/(πDt).
    sigma_t: f64,
    /// Broken bonds, and of them: within 0.2 D of the loaded diameter, in
    /// tension.
    breaks: usize,
    near: usize,
    tension: usize,
}

/// Run the Brazilian scenario `src`: its strength and crack pattern.
fn brazilian(src: &str, tag: &str) -> Brazilian {
    let sc = scenario::parse(src, "bonded_brazilian.toml").unwrap();
    let keep = sc.granular.as_ref().unwrap().keep.unwrap();
    let d = 2.0 * keep.radius;
    let dir = out_dir(tag);
    run(&sc, &dir);
    let history = csv(&dir.join("history.csv"));
    let force = column(&history, "force");
    let peak = force.iter().fold(0.0f64, |m, f| m.max(f.abs()));
    let last = force.last().unwrap().abs();
    // the specimen split: the platens carry little after the peak
    assert!(last < 0.3 * peak, "{last} after a peak of {peak}");
    let breaks = csv(&dir.join("bond_breaks.csv"));
    let x = column(&breaks, "x");
    let near = x
        .iter()
        .filter(|&&x| (x - keep.centre[0]).abs() < 0.2 * d)
        .count();
    let k = breaks.0.iter().position(|h| h == "mode").unwrap();
    let tension = breaks.1.iter().filter(|r| r[k] == "tension").count();
    let t = sc.granular.as_ref().unwrap().thickness;
    std::fs::remove_dir_all(dir).unwrap();
    Brazilian {
        sigma_t: 2.0 * peak / (std::f64::consts::PI * d * t),
        breaks: x.len(),
        near,
        tension,
    }
}

/// The whole grown box (no `keep`) between frictionless platens at the
/// Brazilian test's strain rate: the peak of the top platen's force over
/// the specimen's width (unconfined compressive strength).
fn ucs(src: &str) -> f64 {
    let sc = scenario::parse(src, "bonded_brazilian.toml").unwrap();
    let [x0, y0, x1, y1] = grown_box(&sc);
    let w = x1 - x0;
    let mut s = src
        .lines()
        .filter(|l| !l.starts_with("keep ="))
        .collect::<Vec<_>>()
        .join("\n");
    let platen = |y: f64| {
        format!(
            "from = [{:?}, {y:?}]\nto = [{:?}, {y:?}]",
            x0 - 0.5 * w,
            x1 + 0.5 * w
        )
    };
    let (bottom, top) = (
        format!(
            "from = [{x0:?}, {:?}]\nto = [{x1:?}, {:?}]",
            y0 + 0.001,
            y0 + 0.001
        ),
        format!(
            "from = [{x0:?}, {:?}]\nto = [{x1:?}, {:?}]",
            y1 - 0.001,
            y1 - 0.001
        ),
    );
    s = swap(&s, &bottom, &platen(y0));
    s = swap(&s, &top, &platen(y1));
    let sc = scenario::parse(&s, "ucs.toml").unwrap();
    let dir = out_dir("ucs");
    run(&sc, &dir);
    let force = column(&csv(&dir.join("history.csv")), "force");
    std::fs::remove_dir_all(dir).unwrap();
    let t = sc.granular.as_ref().unwrap().thickness;
    force.iter().fold(0.0f64, |m, f| m.max(f.abs())) / (w * t)
}

/// The whole grown box pulled apart: left free for 5 000 steps, then the
/// discs within 2.5 mm of its top and bottom are grips (no rotation; the bottom fixed, the top moved up
/// at the strain rate 0.5 /s of the box's height). The peak of the force
/// the top grip needs over the box's width (direct tension strength).
fn direct_tension(src: &str) -> f64 {
    let s: String = src
        .split("[[wall]]")
        .next()
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("keep ="))
        .collect::<Vec<_>>()
        .join("\n");
    let sc = scenario::parse(&s, "tension.toml").unwrap();
    let [x0, y0, x1, y1] = grown_box(&sc);
    let mut model = sc.build().unwrap();
    let System::Granular(g) = &mut model.system else {
        panic!("a granular model")
    };
    let g: &mut Granular = g;
    // first free, as the other specimens are between their platens: the
    // contact forces locked in by the growth relax against the bonds
    for _ in 0..5000 {
        g.step();
    }
    let v = 0.5 * (y1 - y0);
    let mut top = vec![];
    for s in 0..g.particles.len() {
        let y = g.particles.pos[s].y;
        let grip = y < y0 + 0.0025 || y > y1 - 0.0025;
        if grip {
            g.particles.fixity[s] = FIX_X | FIX_Y | FIX_ROT;
            g.particles.vel[s] = Vec2::ZERO;
            g.particles.omega[s] = 0.0;
        }
        if y > y1 - 0.0025 {
            g.particles.vel[s] = Vec2::new(0.0, v);
            top.push(g.particles.id[s] as usize);
        }
    }
    let mut peak = 0.0f64;
    for _ in 0..100_000 {
        g.step();
        // the bonds and contacts pull the top grip down
        // (slots are renumbered as the discs move: find them by id)
        let f: f64 = -top
            .iter()
            .map(|&id| g.particles.force[g.slot(id)].y)
            .sum::<f64>();
        peak = peak.max(f);
        if f < 0.2 * peak && peak > 0.0 {
            break;
        }
    }
    peak / ((x1 - x0) * g.thickness)
}

fn check(b: &Brazilian, sigma_dt: f64, ucs: f64) {
    let (ratio, ucs_ratio) = (b.sigma_t / sigma_dt, ucs / b.sigma_t);
    eprintln!(
        "σ_t = {:.3} MPa, direct tension {:.3} MPa (ratio {ratio:.2}), UCS {:.3} MPa (UCS/σ_t {ucs_ratio:.2}); {} breaks, {} within 0.2 D, {} in tension",
        b.sigma_t / 1e6,
        sigma_dt / 1e6,
        ucs / 1e6,
        b.breaks,
        b.near,
        b.tension
    );
    assert!(ratio > 0.5 && ratio < 2.0, "σ_t / σ_DT = {ratio}");
    assert!(
        ucs_ratio > 2.0 && ucs_ratio < 8.0,
        "UCS / σ_t = {ucs_ratio}"
    );
    assert!(b.breaks >= 20, "{} breaks", b.breaks);
    assert!(
        b.near as f64 >= 0.6 * b.breaks as f64,
        "{} of {}",
        b.near,
        b.breaks
    );
    assert!(
        b.tension as f64 >= 0.8 * b.breaks as f64,
        "{} of {}",
        b.tension,
        b.breaks
    );
}

#[test]
fn a_bonded_disc_splits_along_its_loaded_diameter_at_its_tensile_strength() {
    let src = small();
    let b = brazilian(&src, "small");
    check(&b, direct_tension(&src), ucs(&src));
}

/// The example itself, `examples/bonded_brazilian.toml` (499 discs), with
/// the same references on its 52 mm box.
#[test]
#[ignore]
fn full_brazilian_example() {
    let src = example();
    let b = brazilian(&src, "full");
    check(&b, direct_tension(&src), ucs(&src));
}

/// Bad `keep` input: `file:line: field: message`, exit code 2.
#[test]
fn bad_keep_reports_file_line_field_and_exits_2() {
    let dir = out_dir("bad");
    std::fs::create_dir_all(&dir).unwrap();
    for (name, keep, says) in [
        (
            "radius.toml",
            "keep = { centre = [0.026, 0.026], radius = -0.025 }",
            "granular.keep.radius",
        ),
        (
            "outside.toml",
            "keep = { centre = [1.0, 1.0], radius = 0.025 }",
            "granular.keep: none of the 705 discs lies inside the circle",
        ),
        (
            "key.toml",
            "keep = { centre = [0.026, 0.026], r = 0.025 }",
            "unknown field `r`",
        ),
    ] {
        let file = dir.join(name);
        let src = swap(
            &example(),
            "keep = { centre = [0.026, 0.026], radius = 0.025 }",
            keep,
        );
        std::fs::write(&file, src).unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
            .args(["check", file.to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(&format!("{name}:")) && err.contains(says),
            "{name}: {err}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}
