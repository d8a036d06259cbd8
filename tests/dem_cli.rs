//! The command line on granular scenarios: bad input is reported with
//! file, line and field and exit code 2; `check` prints the critical step.

use std::process::Command;

fn efgdem(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs")
}

fn scratch(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("efgdem-demcli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const GOOD: &str = r#"[simulation]
dt = 1e-4
steps = 10
gravity = [0.0, -9.81]

[[material]]
name = "m"
density = 1000.0
kn = 1e6
ks = 1e6
friction = 0.5

[granular]
material = "m"
discs = [[0.0, 1.0, 1.0], [2.5, 1.0, 1.0]]
damping = { kind = "critical-ratio", zeta = 0.2 }

[[wall]]
name = "floor"
from = [-5.0, 0.0]
to = [5.0, 0.0]

[[probe]]
name = "fy"
wall = "floor"
quantity = "wall_fy"
"#;

#[test]
fn bad_damping_value_reports_file_line_field() {
    let text = GOOD.replace("zeta = 0.2", "zeta = 1.5");
    let f = scratch("bad_zeta.toml", &text);
    let out = efgdem(&["check", f.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("bad_zeta.toml:16:"), "{err}");
    assert!(err.contains("granular.damping.zeta"), "{err}");
}

#[test]
fn unknown_field_and_unknown_damping_kind_exit_2() {
    for (name, text) in [
        (
            "unknown.toml",
            GOOD.replace("until_step", "x")
                .replace("to = [5.0, 0.0]", "to = [5.0, 0.0]\nspeed = 1.0"),
        ),
        ("kind.toml", GOOD.replace("critical-ratio", "viscous")),
        (
            "probe.toml",
            GOOD.replace("wall = \"floor\"", "wall = \"roof\""),
        ),
        (
            "wall.toml",
            GOOD.replace("to = [5.0, 0.0]", "to = [-5.0, 0.0]"),
        ),
    ] {
        let f = scratch(name, &text);
        let out = efgdem(&["run", f.to_str().unwrap(), "-o", "/tmp/never"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(&format!("{name}:")), "{name}: {err}");
        println!("{err}");
    }
}

#[test]
fn bad_csv_disc_file_is_an_error_not_a_panic() {
    let csv = scratch("discs_bad.csv", "x,y,r\n0,0,1\n1,oops,1\n");
    let text = GOOD.replace(
        "discs = [[0.0, 1.0, 1.0], [2.5, 1.0, 1.0]]",
        &format!(
            "discs = {{ csv = \"{}\" }}",
            csv.file_name().unwrap().to_str().unwrap()
        ),
    );
    let f = scratch("csv.toml", &text);
    let out = efgdem(&["check", f.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("line 3"), "{err}");
}

#[test]
fn check_prints_the_critical_step_and_run_writes_outputs() {
    let f = scratch("good.toml", GOOD);
    let out = efgdem(&["check", f.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("critical"), "{text}");
    let dir = f.parent().unwrap().join("out_good");
    let out = efgdem(&[
        "run",
        f.to_str().unwrap(),
        "-o",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (h, rows) = efgdem::output::csv::read(&dir.join("history.csv")).unwrap();
    assert_eq!(h, ["step", "t", "fy"]);
    assert_eq!(rows.len(), 11, "step 0 and 10 steps");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["discs"], 2);
    // a too-large dt is a warning, not a failure
    let f = scratch("big_dt.toml", &GOOD.replace("dt = 1e-4", "dt = 5e-2"));
    let out = efgdem(&["check", f.to_str().unwrap()]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("warning"));
}

/// The issue-13 material fields: bad values are reported at their line.
#[test]
fn bad_slip_normal_and_rolling_fields_report_file_line_field() {
    for (name, extra, line, field) in [
        (
            "slip.toml",
            "slip_normal = \"dashpot\"",
            12,
            "material[0].slip_normal",
        ),
        (
            "mur.toml",
            "rolling_friction = -0.1",
            12,
            "material[0].rolling_friction",
        ),
        (
            "kr.toml",
            "rolling_stiffness = 0.0",
            12,
            "material[0].rolling_stiffness",
        ),
        (
            "eta.toml",
            "rolling_damping = 1.5",
            12,
            "material[0].rolling_damping",
        ),
    ] {
        let text = GOOD.replace("friction = 0.5\n", &format!("friction = 0.5\n{extra}\n"));
        let f = scratch(name, &text);
        let out = efgdem(&["check", f.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        println!("{err}");
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("{name}:{line}:")), "{err}");
        assert!(err.contains(field), "{err}");
    }
    // good values pass
    let text = GOOD.replace(
        "friction = 0.5\n",
        "friction = 0.5\nslip_normal = \"elastic\"\nrolling_friction = 0.1\nrolling_stiffness = 0.5\nrolling_damping = 0.3\n",
    );
    let f = scratch("rolling_ok.toml", &text);
    let out = efgdem(&["check", f.to_str().unwrap()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
