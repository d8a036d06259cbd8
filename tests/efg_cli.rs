//! The `efgdem` binary on EFG scenarios: the Timoshenko example end to end,
//! and bad input reported with file, line and field, exit code 2.

mod common;

use common::{bin, run, summary, tmpdir};
use std::path::Path;

#[test]
fn timoshenko_example_reports_tip_deflection() {
    let out = tmpdir("cli-tim");
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/timoshenko.toml");
    run(&ex, &out);
    let s = summary(&out);
    let tip = s["tip_uy"].as_f64().unwrap();
    let exact = s["bodies"][0]["timoshenko"]["tip_uy_exact"]
        .as_f64()
        .unwrap();
    assert!((exact + 0.0089).abs() < 1e-6);
    assert!(
        (tip - exact).abs() < 0.005 * exact.abs(),
        "tip {tip} vs {exact}"
    );
    assert!(out.join("history.csv").exists() && out.join("beam.vtu").exists());
    let chk = bin()
        .args(["check", ex.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(chk.status.success());
    let text = String::from_utf8_lossy(&chk.stdout);
    assert!(
        text.contains("297 nodes") && text.contains("594 DOFs") && text.contains("coverage"),
        "{text}"
    );
    std::fs::remove_dir_all(out).unwrap();
}

#[test]
fn dynamic_run_writes_frames_and_series() {
    let root = tmpdir("cli-dyn");
    let f = root.join("vib.toml");
    let out = root.join("out");
    std::fs::write(
        &f,
        r#"
[simulation]
analysis = "dynamic"
dt = 0.01
steps = 20
[[body]]
name = "b"
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
[output]
vtk_every = 5
"#,
    )
    .unwrap();
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
    std::fs::remove_dir_all(out).unwrap();
}

const GOOD: &str = r#"[simulation]
analysis = "static"

[[body]]
name = "b"
rectangle = { origin = [0.0, 0.0], size = [4.0, 1.0] }
nodes = [9, 3]
d_max = 2.0
elastic = { E = 1000.0, nu = 0.3 }

[[body.bc]]
edge = "left"
fixed = true
"#;

/// Run `check` on `GOOD` with `from` replaced by `to`; expect exit 2 and a
/// message with `file:line: field`.
fn bad(tag: &str, from: &str, to: &str, line: usize, field: &str, words: &str) {
    let d = tmpdir(tag);
    let f = d.join("bad.toml");
    assert!(GOOD.contains(from));
    std::fs::write(&f, GOOD.replace(from, to)).unwrap();
    for cmd in ["check", "run"] {
        let mut c = bin();
        c.args([cmd, f.to_str().unwrap()]);
        if cmd == "run" {
            c.arg("-o").arg(d.join("out"));
        }
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{cmd} {tag}: {err}");
        let at = format!("{}:{line}:", f.display());
        assert!(err.contains(&at), "{tag}: expected `{at}` in: {err}");
        assert!(err.contains(field), "{tag}: expected `{field}` in: {err}");
        assert!(err.contains(words), "{tag}: expected `{words}` in: {err}");
    }
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn good_file_checks() {
    let d = tmpdir("cli-good");
    let f = d.join("good.toml");
    std::fs::write(&f, GOOD).unwrap();
    let o = bin().args(["check", f.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn unknown_field_is_reported() {
    bad(
        "unknown",
        "d_max = 2.0",
        "d_max = 2.0\nsmoothing = 1",
        9,
        "",
        "unknown field `smoothing`",
    );
}

#[test]
fn negative_young_modulus_is_reported() {
    bad(
        "negE",
        "E = 1000.0",
        "E = -1000.0",
        9,
        "body[0].elastic.E",
        "> 0",
    );
}

#[test]
fn incompressible_poisson_ratio_is_reported() {
    bad("nu", "nu = 0.3", "nu = 0.5", 9, "body[0].elastic.nu", "0.5");
}

#[test]
fn single_node_grid_is_reported() {
    bad(
        "grid",
        "nodes = [9, 3]",
        "nodes = [1, 1]",
        7,
        "body[0].nodes",
        "at least 2",
    );
}

#[test]
fn too_small_support_is_reported() {
    bad(
        "dmax",
        "d_max = 2.0",
        "d_max = 0.9",
        8,
        "body[0].d_max",
        "d_max",
    );
}
