//! The `efgdem` binary on FE (`method = "fem-q4"`) scenarios: static
//! Timoshenko example, a dynamic run with frames, EFG-only options
//! rejected with file, line and field, and the nine-disc test with an FE
//! plate (coupled run).

mod common;

use common::{bin, run, summary, tmpdir};
use std::path::Path;

#[test]
fn fem_timoshenko_example_writes_tip_uy() {
    let out = tmpdir("femcli-tim");
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/timoshenko_fem.toml");
    run(&ex, &out);
    let s = summary(&out);
    let tip = s["tip_uy"].as_f64().unwrap();
    let b = &s["bodies"][0];
    assert_eq!(b["method"], "fem-q4");
    let exact = b["timoshenko"]["tip_uy_exact"].as_f64().unwrap();
    assert!((tip - exact).abs() < 0.01 * exact.abs(), "{tip} vs {exact}");
    assert!(out.join("history.csv").exists() && out.join("beam.vtu").exists());
    let chk = bin()
        .args(["check", ex.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(chk.status.success());
    let text = String::from_utf8_lossy(&chk.stdout);
    assert!(
        text.contains("1105 nodes") && text.contains("1024 elements"),
        "{text}"
    );
    std::fs::remove_dir_all(out).unwrap();
}

const DYN: &str = r#"
[simulation]
analysis = "dynamic"
dt = 0.01
steps = 20
[[body]]
name = "b"
method = "fem-q4"
mass = "lumped"
rectangle = { origin = [0.0, 0.0], size = [4.0, 1.0] }
nodes = [9, 3]
elastic = { E = 1000.0, nu = 0.3, density = 1.0 }
initial = { static_under = ["push"] }
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
name = "push"
edge = "right"
traction = [0.0, -1.0]
[[probe]]
name = "tip"
point = [4.0, 0.5]
quantity = "uy"
[[probe]]
name = "energy"
quantity = "total_energy"
[output]
vtk_every = 5
"#;

#[test]
fn fem_dynamic_run_writes_frames_and_history() {
    let root = tmpdir("femcli-dyn");
    let f = root.join("vib.toml");
    let out = root.join("out");
    std::fs::write(&f, DYN).unwrap();
    run(&f, &out);
    let pvd = std::fs::read_to_string(out.join("b.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 5);
    let frame = std::fs::read(out.join("frames/b_0000020.vtu")).unwrap();
    let frame = String::from_utf8_lossy(&frame);
    assert!(frame.contains("compressor=\"vtkZLibDataCompressor\""));
    for a in ["displacement", "velocity", "stress", "strain", "von_mises"] {
        assert!(frame.contains(&format!("Name=\"{a}\"")), "{a}");
    }
    let hist = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert_eq!(hist.lines().count(), 22);
    // average acceleration conserves the energy of the released vibration
    let e = &summary(&out)["probes"]["energy"];
    let (lo, hi) = (e["min"].as_f64().unwrap(), e["max"].as_f64().unwrap());
    assert!(hi > 0.0 && (hi - lo) < 1e-9 * hi, "{lo} {hi}");
    std::fs::remove_dir_all(out).unwrap();
}

/// EFG-only options on a `fem-q4` body: exit 2, `file:line:` and the field.
#[test]
fn efg_options_on_a_fem_body_are_reported() {
    for (tag, from, to, field) in [
        (
            "dmax",
            "nodes = [9, 3]",
            "nodes = [9, 3]\nd_max = 3.0",
            "body[0].d_max",
        ),
        (
            "gauss",
            "nodes = [9, 3]",
            "nodes = [9, 3]\ngauss = 6",
            "body[0].gauss",
        ),
        (
            "cells",
            "nodes = [9, 3]",
            "nodes = [9, 3]\ncells = [4, 2]",
            "body[0].cells",
        ),
        (
            "pen",
            "nodes = [9, 3]",
            "nodes = [9, 3]\npenalty = 1e9",
            "body[0].penalty",
        ),
        (
            "lumped",
            "method = \"fem-q4\"",
            "method = \"efg\"",
            "body[0].mass",
        ),
    ] {
        let d = tmpdir(tag);
        let f = d.join("bad.toml");
        let src = DYN.replace(from, to);
        std::fs::write(&f, &src).unwrap();
        let o = bin().args(["check", f.to_str().unwrap()]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{tag}: {err}");
        let key = field.rsplit('.').next().unwrap();
        let line = src
            .lines()
            .position(|l| l.starts_with(&format!("{key} =")))
            .unwrap()
            + 1;
        let at = format!("{}:{line}:", f.display());
        assert!(
            err.contains(&at) && err.contains(field),
            "{tag}: expected `{at}` `{field}` in: {err}"
        );
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// The nine-disc test with the left plate as an FE strip: history with the
/// contact probe, plate probes and the energy columns, ParaView frames of
/// the plate, and the plate's edges where the moving rigid plates put them.
#[test]
fn fem_nine_disc_example_runs_coupled() {
    let out = tmpdir("femcli-nine");
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/fem_nine_disc_test1.toml");
    run(&ex, &out);
    let hist = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let head: Vec<&str> = hist.lines().next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let last: Vec<f64> = hist
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(hist.lines().count(), 152);
    assert!(last[col("force_C")] > 4e7, "{}", last[col("force_C")]);
    assert!(last[col("E_kin_body")].is_finite() && last[col("W_ext")] > 0.0);
    // the plate's top edge moved 0.12 × 40 × Δt and stopped there
    let ux = last[col("plate_top_ux")];
    assert!((ux - 0.12 * 40.0 * 0.01525).abs() < 1e-12, "{ux}");
    assert!(out.join("plate.pvd").exists() && out.join("frames/plate_0000150.vtu").exists());
    assert_eq!(summary(&out)["kind"], "coupled");
    std::fs::remove_dir_all(out).unwrap();
}
