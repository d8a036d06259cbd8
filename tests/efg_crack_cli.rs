//! Cracks from the scenario file: `examples/cracked_plate.toml` end to end
//! (growth, probes, frames, summary), and bad cracks reported with file,
//! line and field, exit code 2.

mod common;

use common::{bin, run, summary, tmpdir};
use std::path::Path;

/// Brown & Srawley's polynomial for the single-edge-cracked strip in
/// tension (Tada, Paris & Irwin, *The Stress Analysis of Cracks
/// Handbook*, 3rd ed., §2.10).
fn brown_srawley(alpha: f64) -> f64 {
    1.12 - 0.231 * alpha + 10.55 * alpha.powi(2) - 21.72 * alpha.powi(3) + 30.39 * alpha.powi(4)
}

/// The example's crack grows four increments of 5 × 0.0025 straight
/// ahead (mode I: `K_II` a ten-thousandth of `K_I`, the tip within 0.5 %
/// of the increment of the crack's line), `K_I` of the grown crack is of
/// the handbook's order for a strip (clamped at one end, so not within
/// its 0.5 %), and the frames hold the body and the two crack faces.
#[test]
fn cracked_plate_example_grows_its_crack() {
    let out = tmpdir("cli-crack");
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/cracked_plate.toml");
    run(&ex, &out);
    let s = summary(&out);
    let c = &s["bodies"][0]["cracks"][0];
    assert_eq!(c["increments"][1].as_u64(), Some(4));
    let a = s["a"].as_f64().unwrap();
    assert!((a - (0.03 + 4.0 * 0.0125)).abs() < 1e-9, "{a}");
    let tip = &c["tips"][0];
    let [x, y] = [0, 1].map(|i| tip["at"][i].as_f64().unwrap());
    assert!(
        (x - 0.08).abs() < 1e-5 && (y - 0.1).abs() < 0.005 * 0.0125 * 4.0,
        "{x} {y}"
    );
    let (k1, k2) = (s["K_I"].as_f64().unwrap(), s["K_II"].as_f64().unwrap());
    assert!(k2.abs() < 1e-3 * k1, "{k1} {k2}");
    let handbook = 3.0e6 * (std::f64::consts::PI * a).sqrt() * brown_srawley(a / 0.1);
    println!("K_I {k1:.4e}, handbook (free strip) {handbook:.4e}");
    assert!(k1 > 0.5 * handbook && k1 < 1.5 * handbook);
    let g = s["G_released"].as_f64().unwrap();
    assert!(g > 0.0 && g == s["bodies"][0]["fracture_energy"].as_f64().unwrap());
    let faces = std::fs::read(out.join("plate_cracks.vtp")).unwrap();
    let faces = String::from_utf8_lossy(&faces);
    assert!(faces.contains("NumberOfLines=\"2\"") && faces.contains("Name=\"displacement\""));
    assert!(out.join("plate.vtu").exists());
    std::fs::remove_dir_all(out).unwrap();
}

const GOOD: &str = r#"[simulation]
analysis = "static"

[[body]]
name = "b"
rectangle = { origin = [0.0, 0.0], size = [4.0, 2.0] }
nodes = [9, 5]
elastic = { E = 1000.0, nu = 0.3 }

[[body.crack]]
points = [[0.0, 1.0], [1.0, 1.0]]
spacing = 0.125

[body.fracture]
toughness = 1.0

[[body.bc]]
edge = "bottom"
fixed = true

[[probe]]
name = "K"
quantity = "k1"
"#;

/// Run `check` and `run` on `GOOD` with `from` replaced by `to`; expect
/// exit 2 and `file:line:`, `field` and `words` in the message.
fn bad(tag: &str, from: &str, to: &str, line: usize, field: &str, words: &str) {
    let d = tmpdir(tag);
    let f = d.join("bad.toml");
    assert!(GOOD.contains(from), "{from}");
    std::fs::write(&f, GOOD.replace(from, to)).unwrap();
    for cmd in ["check", "run"] {
        let mut c = bin();
        c.args([cmd, f.to_str().unwrap()]);
        if cmd == "run" {
            c.arg("-q").arg("-o").arg(d.join("out"));
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
fn good_cracked_file_checks() {
    let d = tmpdir("cli-crack-good");
    let f = d.join("good.toml");
    std::fs::write(&f, GOOD).unwrap();
    let o = bin().args(["check", f.to_str().unwrap()]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn bad_cracks_are_located() {
    let pts = "points = [[0.0, 1.0], [1.0, 1.0]]";
    bad(
        "crack-out",
        pts,
        "points = [[1.0, 1.0], [5.0, 1.0]]",
        11,
        "body[0].crack[0].points",
        "outside the body",
    );
    bad(
        "crack-cut",
        pts,
        "points = [[0.0, 1.0], [4.0, 1.0]]",
        11,
        "body[0].crack[0].points",
        "cut the body in two",
    );
    bad(
        "crack-one",
        pts,
        "points = [[1.0, 1.0]]",
        11,
        "body[0].crack[0].points",
        "at least 2",
    );
    bad(
        "crack-tiny",
        pts,
        "points = [[0.0, 1.0], [1.0e-300, 1.0]]",
        11,
        "body[0].crack[0].points",
        "coincide",
    );
    bad(
        "crack-spacing",
        "spacing = 0.125",
        "spacing = 0.9",
        12,
        "body[0].crack[0].spacing",
        "below the body's node spacing 0.5",
    );
    bad(
        "crack-toughness",
        "toughness = 1.0",
        "toughness = -1.0",
        15,
        "body[0].fracture.toughness",
        "> 0",
    );
    bad(
        "crack-fem",
        "nodes = [9, 5]",
        "nodes = [9, 5]\nmethod = \"fem-q4\"",
        11,
        "body[0].crack",
        "EFG",
    );
    bad(
        "crack-probe",
        "quantity = \"k1\"",
        "quantity = \"k1\"\ncrack = 2",
        24,
        "probe[0].crack",
        "has 1 crack",
    );
    bad(
        "crack-mouth",
        "quantity = \"k1\"",
        "quantity = \"k1\"\ntip = 1",
        24,
        "probe[0].tip",
        "mouth",
    );
}
