//! Parallel bonds from a scenario file, through the command line: a small
//! uniaxial compression of a bonded hexagonal block. The bonds made are
//! the lattice's touching pairs (counted by hand), and the breakage data
//! agree with each other: `history.csv` counts, `bond_breaks.csv` rows,
//! the released energy, the crack frames and `summary.json`. Bad `[bonds]`
//! input is reported with file, line and field, exit code 2.

use std::path::PathBuf;

#[allow(dead_code)]
mod common;

fn efgdem(args: &[&str]) -> std::process::Output {
    common::bin().args(args).output().expect("runs")
}

fn scratch(name: &str) -> PathBuf {
    common::tmpdir(&format!("bonds-{name}"))
}

/// The bonded block of `tests/common/bonded_block.toml`, with outputs.
fn ucs() -> String {
    include_str!("common/bonded_block.toml").to_string()
        + "\n[output]\nevery = 100\nvtk_every = 2500\n"
}

fn csv(path: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let head = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (head, rows)
}

#[test]
fn a_bonded_block_breaks_and_every_output_tells_the_same_story() {
    let dir = scratch("ucs");
    let file = dir.join("ucs.toml");
    std::fs::write(&file, ucs()).unwrap();
    let out_dir = dir.join("out");
    let out = efgdem(&[
        "run",
        file.to_str().unwrap(),
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // touching pairs of the lattice: 11 rows of 10 and 11 of 9 discs give
    // 11·9 + 11·8 = 187 horizontal pairs, and each of the 21 gaps between
    // rows 2·9 = 18 diagonal ones
    let made = 187 + 21 * 18;
    let (head, rows) = csv(&out_dir.join("history.csv"));
    let col = |name: &str| head.iter().position(|h| h == name).unwrap();
    let num = |r: &Vec<String>, name: &str| r[col(name)].parse::<f64>().unwrap();
    let mut broken_before = 0.0;
    for r in &rows {
        let broken = num(r, "bonds_broken_tension") + num(r, "bonds_broken_shear");
        assert_eq!(num(r, "bonds") + broken, made as f64, "step {}", r[0]);
        assert!(broken >= broken_before);
        broken_before = broken;
    }
    let last = rows.last().unwrap();
    let (tension, shear) = (
        num(last, "bonds_broken_tension") as usize,
        num(last, "bonds_broken_shear") as usize,
    );
    assert!(tension > 50 && shear > 5, "{tension} {shear}");
    let (bhead, breaks) = csv(&out_dir.join("bond_breaks.csv"));
    assert_eq!(
        bhead.join(","),
        "step,t,x,y,nx,ny,radius,disc_a,disc_b,mode,energy"
    );
    assert_eq!(breaks.len(), tension + shear);
    let mode = |m: &str| breaks.iter().filter(|b| b[9] == m).count();
    assert_eq!((mode("tension"), mode("shear")), (tension, shear));
    let released: f64 = breaks.iter().map(|b| b[10].parse::<f64>().unwrap()).sum();
    let e = num(last, "E_bond_released");
    assert!((released - e).abs() <= 1e-12 * e, "{released} {e}");
    // each break is counted from the history row of its step on
    for b in &breaks {
        let step: usize = b[0].parse().unwrap();
        let (a, c): (usize, usize) = (b[7].parse().unwrap(), b[8].parse().unwrap());
        assert!((1..=5000).contains(&step) && a < c && c <= 209);
        let radius: f64 = b[6].parse().unwrap();
        assert_eq!(radius, 0.0025);
    }
    // the last crack frame holds every crack
    let frame = std::fs::read(out_dir.join("frames/cracks_0005000.vtp")).unwrap();
    let frame = String::from_utf8_lossy(&frame);
    assert!(
        frame.contains(&format!("NumberOfLines=\"{}\"", tension + shear)),
        "the last crack frame"
    );
    assert!(out_dir.join("cracks.pvd").exists());
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["bonds"]["made"].as_u64(), Some(made as u64));
    assert_eq!(s["bonds"]["broken_tension"].as_u64(), Some(tension as u64));
    println!("{made} bonds, {tension} broken in tension, {shear} in shear, {e:.4e} J released");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_bonds_input_reports_file_line_field_and_exits_2() {
    let dir = scratch("bad");
    for (name, from, to, field) in [
        ("kn.toml", "kn = 2.0e11", "kn = -2.0e11", "bonds.kn"),
        ("noshear.toml", "shear = 1.0e7\n", "", "bonds"),
        (
            "both.toml",
            "shear = 1.0e7",
            "shear = 1.0e7\ncohesion = 1.0e6",
            "bonds",
        ),
        (
            "phi.toml",
            "shear = 1.0e7",
            "shear = 1.0e7\nfriction_angle = 30",
            "bonds.friction_angle",
        ),
        (
            "scatter.toml",
            "scatter = 0.2",
            "scatter = 0.5",
            "bonds.scatter",
        ),
        (
            "mat.toml",
            "scatter = 0.2",
            "scatter = 0.2\nmaterials = [\"granite\"]",
            "bonds.materials",
        ),
        (
            "unknown.toml",
            "scatter = 0.2",
            "scatter = 0.2\nstrength = 1",
            "strength",
        ),
    ] {
        let f = dir.join(name);
        std::fs::write(&f, ucs().replace(from, to)).unwrap();
        let out = efgdem(&["check", f.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(&format!("{name}:")) && err.contains(field),
            "{name}: {err}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}
