//! Impossible start states are refused by `efgdem check` (and `run`) with
//! `file:line: field: message` and exit code 2 (issue 12).

#[allow(dead_code)]
mod common;

const BASE: &str = r#"[simulation]
dt = 1.0e-5
steps = 10
gravity = [0.0, -9.81]

[[material]]
name = "m"
density = 1000.0
kn = 1.0e6
ks = 1.0e6

[granular]
material = "m"
DISCS
"#;

/// Run `efgdem check` on `text`; (exit code, stderr).
fn check(name: &str, text: &str) -> (i32, String) {
    let f = common::tmpdir(&format!("start-{name}")).join(format!("{name}.toml"));
    std::fs::write(&f, text).unwrap();
    let out = common::bin().arg("check").arg(&f).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn with_discs(discs: &str) -> String {
    BASE.replace("DISCS", discs)
}

#[test]
fn discs_at_the_same_centre_or_overlapping_are_refused() {
    let (code, err) = check(
        "same_centre",
        &with_discs("discs = [[0.0, 0.0, 0.05], [0.5, 0.5, 0.05], [0.0, 0.0, 0.05]]"),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("same_centre.toml:14: granular.discs:"),
        "{err}"
    );
    assert!(err.contains("discs 1 and 3 (overlap 1.000e-1)"), "{err}");
    // 1 % of a radius overlap: refused; 0.05 % of a radius: accepted
    let (code, err) = check(
        "overlap",
        &with_discs("discs = [[0.0, 0.0, 0.05], [0.0995, 0.0, 0.05]]"),
    );
    assert_eq!(code, 2, "{err}");
    let (code, err) = check(
        "touching",
        &with_discs("discs = [[0.0, 0.0, 0.05], [0.099975, 0.0, 0.05]]"),
    );
    assert_eq!(code, 0, "{err}");
    // a pre-stressed packing, said so
    let (code, err) = check(
        "allowed",
        &with_discs("discs = [[0.0, 0.0, 0.05], [0.0995, 0.0, 0.05]]\nallow_overlap = true"),
    );
    assert_eq!(code, 0, "{err}");
}

#[test]
fn a_disc_inside_a_body_or_across_a_wall_is_refused() {
    let body = r#"
[[body]]
name = "block"
rectangle = { origin = [0.0, 0.0], size = [1.0, 0.2] }
nodes = [11, 3]
elastic = { E = 1.0e8, nu = 0.3, density = 2000.0 }
[[body.bc]]
edge = "bottom"
fixed = true
"#;
    let (code, err) = check(
        "inside",
        &(with_discs("discs = [[0.5, 0.1, 0.05], [0.5, 0.3, 0.05]]") + body),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("inside.toml:17: body[0]: 1 disc(s) overlap body `block`"),
        "{err}"
    );
    assert!(err.contains("disc 1 (overlap 1.500e-1)"), "{err}");
    let wall = "\n[[wall]]\nname = \"floor\"\nfrom = [-1.0, 0.0]\nto = [1.0, 0.0]\n";
    let (code, err) = check(
        "across",
        &(with_discs("discs = [[0.0, 0.02, 0.05], [0.5, 0.06, 0.05]]") + wall),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("across.toml:17: wall[0]: 1 disc(s) cross wall `floor`"),
        "{err}"
    );
}

#[test]
fn missing_duration_duplicate_probes_and_unstable_dt_are_refused() {
    let one = "discs = [[0.0, 0.0, 0.05]]";
    let (code, err) = check("no_steps", &with_discs(one).replace("steps = 10\n", ""));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("no_steps.toml:1: simulation: give `steps` or `end_time`"),
        "{err}"
    );
    let probes = "\n[[probe]]\nname = \"ke\"\nquantity = \"kinetic\"\n[[probe]]\nname = \"ke\"\nquantity = \"total_energy\"\n";
    let (code, err) = check("dup", &(with_discs(one) + probes));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("dup.toml:20: probe[1].name: probe `ke` is defined twice"),
        "{err}"
    );
    // a disc on a wall: 2√(m/k) = 2√(7.85/1e6) ≈ 5.6e-3, the limit of its
    // normal mode at the first collision: dt = 1e-2 is above it
    let (code, err) = check(
        "big_dt",
        &with_discs(one).replace("dt = 1.0e-5", "dt = 1.0e-2"),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("big_dt.toml:2: simulation.dt: dt = 1e-2 is above 5.6"),
        "{err}"
    );
}

#[test]
fn a_probe_naming_a_missing_disc_is_found_by_check() {
    let probe = "\n[[probe]]\nname = \"x9\"\ndisc = 9\nquantity = \"x\"\n";
    let (code, err) = check(
        "missing_disc",
        &(with_discs(
            "discs = { generate = \"square\", box = [[0.0, 0.0], [0.4, 0.2]], radius = 0.05 }",
        ) + probe),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(
            "missing_disc.toml:18: probe[0].disc: disc 9 does not exist (the assembly has 8 discs"
        ),
        "{err}"
    );
}

/// A body's name becomes file names: one that collides with the disc
/// series or is not a file name is refused at its line.
#[test]
fn body_names_that_are_not_file_names_or_collide_with_series_are_refused() {
    let body = |name: &str| {
        format!(
            "[simulation]\nanalysis = \"static\"\n[[body]]\nname = \"{name}\"\nrectangle = {{ origin = [0.0, 0.0], size = [2.0, 1.0] }}\nnodes = [5, 3]\nelastic = {{ E = 1e6, nu = 0.3 }}\n[[body.bc]]\nedge = \"left\"\nfixed = true\n"
        )
    };
    for (name, why) in [
        ("walls", "series"),
        ("discs", "series"),
        ("a/b", "file name"),
        ("", "file name"),
    ] {
        let (code, err) = check("bodyname", &body(name));
        assert_eq!(code, 2, "{name}: {err}");
        assert!(
            err.contains(":4: body[0].name:") && err.contains(why),
            "{name}: {err}"
        );
    }
    assert_eq!(check("bodyname", &body("beam_1.a")).0, 0);
}

#[test]
fn a_settled_packing_must_not_overlap_a_body() {
    // the preparation (growth) never sees the bodies: a body placed across
    // the packing's box would start with discs inside it
    let discs = r#"discs = { generate = "random", method = "grow", box = [[0.0, 0.0], [1.0, 0.5]], radius = 0.04, count = 60, seed = 1, settle_steps = 200 }"#;
    let body = r#"
[[body]]
name = "footing"
rectangle = { origin = [0.3, 0.3], size = [0.4, 0.3] }
nodes = [5, 4]
elastic = { E = 1.0e8, nu = 0.3, density = 2000.0 }
[[body.bc]]
edge = "top"
fixed = true
"#;
    // a growth fills its whole box: `check` and `run` refuse the body
    // before any step of the preparation
    let (code, err) = check("settled_check", &(with_discs(discs) + body));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("settled_check.toml:18: body[0].rectangle: body `footing` lies where discs will be: the radius growth"),
        "{err}"
    );
    let dir = common::tmpdir("start-settled-run");
    let f = dir.join("settled.toml");
    std::fs::write(&f, with_discs(discs) + body).unwrap();
    let out = common::bin()
        .arg("run")
        .arg(&f)
        .arg("-q")
        .arg("-o")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("settled.toml:18: body[0].rectangle: body `footing` lies where discs will be"),
        "{err}"
    );
    // above the box it is accepted
    let ok = with_discs(discs) + &body.replace("[0.3, 0.3]", "[0.3, 0.55]");
    std::fs::write(&f, ok).unwrap();
    let out = common::bin()
        .args(["run", "-q", "--overwrite", "-o"])
        .arg(dir.join("out"))
        .arg(&f)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
