//! The coupled example `examples/cemented_footing.toml`: an EFG footing
//! pushed into a cemented (bonded) layer over uncemented sand, then held.
//! Independent checks:
//!
//! - **Equilibrium at rest.** The floor is frictionless and the side
//!   walls are vertical and frictionless, so at rest the floor carries
//!   the discs' weight (`Σ ρπr²t g`, from the bed's radii) plus the
//!   footing's load, measured on the other side of the bed as the discs'
//!   force on the body. Asserted within 1 % (mean of the last 2 500
//!   steps; measured under 0.01 %).
//! - **The cement spreads the load.** The same bed and push without the
//!   bonds: the footing meets far less resistance. Asserted: the cemented
//!   bed's reaction at the same settlement (0.37 mm) is more than 10 × the
//!   uncemented one (measured: 6.0 kN/m against 9.5 N/m).
//! - **Cracks under the edges.** The layer bends and cracks where the
//!   footing's edges cut it: at least 60 % of the broken bonds lie within
//!   B/4 of an edge (the two bands, a quarter of the layer's width, would
//!   hold 25 % of uniformly spread breaks; measured 24 of 27), and at
//!   least 80 % broke in tension (measured all).

#[allow(dead_code)]
mod common;

use common::{Csv, column, csv};
use efgdem::run::RunOptions;
use efgdem::scenario;
use std::path::{Path, PathBuf};

fn example() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/cemented_footing.toml"),
    )
    .unwrap()
}

fn out_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("efgdem-footing-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Run `src` (written as `dir/footing.toml`, the bed cached in `dir`).
fn run(src: &str, dir: &Path) {
    let file = dir.join("footing.toml");
    std::fs::write(&file, src).unwrap();
    let sc = scenario::load(&file).unwrap();
    let opts = RunOptions {
        quiet: true,
        ..RunOptions::new(dir.join("out"))
    };
    efgdem::run::run(&sc, &opts).unwrap();
}

#[test]
fn a_cemented_layer_carries_the_footing_and_cracks_under_its_edges() {
    let dir = out_dir("cemented");
    let cached = example().replace(
        "settle_material = \"smooth\" }",
        "settle_material = \"smooth\", cache = \"bed.csv\" }",
    );
    assert!(cached.contains("cache = \"bed.csv\""));
    run(&cached, &dir);
    let h = csv(&dir.join("out/history.csv"));
    let (step, reaction, floor) = (
        column(&h, "step"),
        column(&h, "reaction"),
        column(&h, "floor"),
    );
    // the discs' weight from the grown bed (x, y, r rows)
    let bed = std::fs::read_to_string(dir.join("bed.csv")).unwrap();
    let weight: f64 = bed
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('x'))
        .map(|l| {
            let r: f64 = l.split(',').nth(2).unwrap().parse().unwrap();
            2650.0 * std::f64::consts::PI * r * r * 9.81
        })
        .sum();
    let last = |v: &[f64]| {
        let tail: Vec<f64> = v
            .iter()
            .zip(&step)
            .filter(|&(_, &s)| s > 57_500.0)
            .map(|(x, _)| *x)
            .collect();
        tail.iter().sum::<f64>() / tail.len() as f64
    };
    let (load, carried) = (last(&reaction), -last(&floor));
    let error = (carried - weight - load) / load;
    eprintln!(
        "weight {weight:.2} N/m, footing {load:.1} N/m, floor {carried:.1} N/m: error {:.2} %",
        100.0 * error
    );
    assert!(error.abs() < 0.01, "{error}");

    let b = csv(&dir.join("out/bond_breaks.csv"));
    let x = column(&b, "x");
    let (left, right) = (0.03, 0.05);
    let near = x
        .iter()
        .filter(|&&x| (x - left).abs() < 0.005 || (x - right).abs() < 0.005)
        .count();
    let k = b.0.iter().position(|h| h == "mode").unwrap();
    let tension = b.1.iter().filter(|r| r[k] == "tension").count();
    eprintln!(
        "{} breaks, {near} within B/4 of an edge, {tension} in tension",
        x.len()
    );
    assert!(x.len() >= 20);
    assert!(near as f64 >= 0.6 * x.len() as f64);
    assert!(tension as f64 >= 0.8 * x.len() as f64);

    // the same bed and push without bonds, to step 30 000 (0.63 mm)
    let bonds = cached.find("[bonds]").unwrap();
    let end = bonds + cached[bonds..].find("\n\n").unwrap();
    let loose = format!("{}{}", &cached[..bonds], &cached[end + 2..])
        .replace("steps = 60000", "steps = 30000");
    assert!(!loose.contains("[bonds]") && loose.contains("steps = 30000"));
    let dir2 = out_dir("loose");
    std::fs::copy(dir.join("bed.csv"), dir2.join("bed.csv")).unwrap();
    run(&loose, &dir2);
    let h2 = csv(&dir2.join("out/history.csv"));
    // the reaction when the footing's drive first reaches a settlement (the
    // runs' time steps differ: the bonds shorten the critical step)
    let at = |h: &Csv, settlement: f64| {
        let s = column(h, "settlement");
        let i = s.iter().position(|&s| s <= settlement).unwrap();
        (column(h, "reaction")[i], s[i])
    };
    let i = step.iter().position(|&s| s >= 30_000.0).unwrap();
    let (cemented, s1) = at(&h, column(&h, "settlement")[i]);
    let (uncemented, s2) = at(&h2, s1);
    eprintln!(
        "at settlement {:.3} mm: reaction {cemented:.1} N/m cemented, {uncemented:.1} N/m without bonds (at {:.3} mm)",
        -1e3 * s1,
        -1e3 * s2
    );
    assert!((s1 - s2).abs() < 0.01e-3, "{s1} {s2}");
    assert!(cemented > 10.0 * uncemented, "{cemented} {uncemented}");
    for d in [dir, dir2] {
        std::fs::remove_dir_all(d).unwrap();
    }
}
