//! `efgdem check` is cheap and bounded (issue 12): no time stepping (a
//! deposit or growth is announced, not run), a memory estimate in the
//! report, and a run that would not fit in the machine's memory refused
//! by `check` and `run` alike with `file:line: field: message`, exit 2.

#[allow(dead_code)]
mod common;

use std::time::Instant;

const DEPOSIT: &str = r#"[simulation]
dt = 1.0e-5
end_time = 0.1
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 5.0e7
ks = 2.5e7
friction = 0.5

[granular]
material = "sand"
discs = { generate = "random", method = "METHOD", box = [[0.0, 0.0], [BOX]], radius = [0.0025, 0.004], COUNT seed = 7, settle_steps = STEPS }
damping = { kind = "critical-ratio", zeta = 0.2 }

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.8, 0.0]
"#;

fn scenario(method: &str, bx: &str, count: &str, steps: &str) -> String {
    DEPOSIT
        .replace("METHOD", method)
        .replace("BOX", bx)
        .replace("COUNT", count)
        .replace("STEPS", steps)
}

/// `efgdem ARGS…` on `text` written to a fresh file; (exit code, stdout,
/// stderr).
fn efgdem(name: &str, text: &str, args: &[&str]) -> (i32, String, String) {
    let dir = common::tmpdir(&format!("check-{name}"));
    let f = dir.join(format!("{name}.toml"));
    std::fs::write(&f, text).unwrap();
    let mut cmd = common::bin();
    cmd.arg(args[0]).arg(&f).args(&args[1..]).current_dir(&dir);
    let o = cmd.output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn check_runs_no_deposit_or_growth_and_says_what_run_will_do() {
    // 5 000 discs and 10¹² settling steps: `check` used to run them all
    for (method, what) in [("deposit", "gravity deposit"), ("grow", "radius growth")] {
        let text = scenario(method, "0.8, 0.9", "count = 5000,", "1000000000000");
        let t0 = Instant::now();
        let (code, out, err) = efgdem(method, &text, &["check"]);
        let secs = t0.elapsed().as_secs_f64();
        assert_eq!(code, 0, "{err}");
        assert!(secs < 5.0, "{method}: check took {secs} s");
        assert!(out.contains("granular: 5000 discs"), "{out}");
        assert!(
            out.contains(&format!(
                "preparation: a {what} of 1000000000000 DEM steps will be run at the start of `run`"
            )),
            "{out}"
        );
        // the estimate, and human text rather than Rust debug output
        assert!(out.contains("memory: about "), "{out}");
        assert!(out.contains("5000 discs × ~400 B"), "{out}");
        assert!(
            out.contains("damping: critical-ratio: normal dashpot at ζ = 0.2 of critical"),
            "{out}"
        );
        assert!(
            !out.contains("Some(") && !out.contains("CriticalRatio {"),
            "{out}"
        );
    }
}

#[test]
fn a_disc_count_beyond_the_machines_memory_is_refused_by_check_and_run() {
    if efgdem::scenario::build::machine_memory().is_none() {
        return; // no /proc/meminfo: the memory check is skipped
    }
    // 10¹¹ discs given as `count`: refused at the `count` field
    let text = scenario("deposit", "8000.0, 9000.0", "count = 100000000000,", "100");
    for cmd in ["check", "run"] {
        let t0 = Instant::now();
        let args: &[&str] = if cmd == "run" {
            &["run", "-q"]
        } else {
            &["check"]
        };
        let (code, _, err) = efgdem("huge_count", &text, args);
        assert_eq!(code, 2, "{cmd}: {err}");
        assert!(t0.elapsed().as_secs_f64() < 5.0, "{cmd}");
        assert!(
            err.contains(
                "huge_count.toml:15: granular.discs.count: the run would need about 36.4 TiB"
            ),
            "{cmd}: {err}"
        );
        assert!(err.contains("100000000000 discs"), "{err}");
        assert!(err.contains("MemTotal"), "{err}");
    }
    // no `count`: as many as the (huge) box holds, refused at `discs`
    let text = scenario("loose", "8000.0, 9000.0", "", "100");
    let (code, _, err) = efgdem("huge_box", &text, &["check"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("huge_box.toml:15: granular.discs: the run would need"),
        "{err}"
    );
}

#[test]
fn a_body_beyond_the_machines_memory_is_refused_at_its_nodes() {
    if efgdem::scenario::build::machine_memory().is_none() {
        return;
    }
    // 7 000 × 7 000 EFG nodes with 2 × 2 Gauss points pass the limits of
    // the validation (5·10⁷ nodes, 2·10⁸ Gauss points) but not the memory: hundreds of GiB of operators and shape functions
    let text = r#"[simulation]
analysis = "static"

[[body]]
name = "slab"
rectangle = { origin = [0.0, 0.0], size = [1.0, 1.0] }
nodes = [7000, 7000]
gauss = 2
elastic = { E = 1.0e8, nu = 0.3 }
[[body.bc]]
edge = "left"
fixed = true
"#;
    let t0 = Instant::now();
    let (code, _, err) = efgdem("huge_body", text, &["check"]);
    assert_eq!(code, 2, "{err}");
    assert!(t0.elapsed().as_secs_f64() < 5.0);
    assert!(
        err.contains("huge_body.toml:7: body[0].nodes: the run would need about "),
        "{err}"
    );
    assert!(err.contains("body `slab`"), "{err}");
}

#[test]
fn the_estimate_follows_the_scenario() {
    use efgdem::scenario::build::{DISC_BYTES, memory_estimate};
    let sc = efgdem::scenario::parse(
        &scenario("deposit", "0.8, 0.9", "count = 300,", "10"),
        "x.toml",
    )
    .unwrap();
    let e = memory_estimate(&sc);
    assert_eq!(e.discs, 300.0);
    assert_eq!(e.disc_bytes, 300.0 * DISC_BYTES);
    assert!(e.bodies.is_empty());
    // as many as fit: the lattice count, without generating
    let sc = efgdem::scenario::parse(&scenario("loose", "0.8, 0.9", "", "10"), "x.toml").unwrap();
    let n = sc
        .build_unprepared()
        .unwrap()
        .granular()
        .unwrap()
        .particles
        .len();
    assert_eq!(memory_estimate(&sc).discs, n as f64);
}
