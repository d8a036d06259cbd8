//! `summary.json` reports the measured peak memory of a run
//! (`peak_memory_bytes`, `peak_bytes_per_disc`): on a 200 000-disc run
//! with neighbour rebuilds (and a renumbering) it is within 10 % of the
//! peak resident set the operating system reports for the process.
//!
//! One test in this file: the OS figure is the largest of this test
//! process's waited-for children (`getrusage(RUSAGE_CHILDREN)`), so no
//! other child may run beside it.

#![cfg(target_os = "linux")]

use std::process::Command;

const SCENARIO: &str = r#"
[simulation]
dt = 4.0e-4
steps = 300
gravity = [0.0, -981.0]    # a fast fall: a neighbour rebuild every few dozen steps

[[material]]
name = "grain"
density = 1.0
kn = 1.0e6
ks = 1.0e6
friction = 0.5

[granular]
material = "grain"
discs = { generate = "random", box = [[0.0, 0.0], [6680.0, 200.0]], radius = [0.8, 1.2], count = 200000, seed = 1 }
damping = { kind = "critical-ratio", zeta = 0.2 }

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [6680.0, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 200.0]

[[wall]]
name = "right"
from = [6680.0, 0.0]
to = [6680.0, 200.0]

[output]
every = 100
vtk_every = 0
"#;

/// Largest resident set of the children waited for so far, in bytes.
fn children_peak() -> u64 {
    // SAFETY: getrusage writes the struct it is given and nothing else.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    assert_eq!(
        unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut ru) },
        0
    );
    ru.ru_maxrss as u64 * 1024 // kilobytes on Linux
}

#[test]
fn summary_peak_memory_is_the_os_peak() {
    let dir = std::env::temp_dir().join(format!("efgdem-memory-peak-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scenario = dir.join("fall_200k.toml");
    std::fs::write(&scenario, SCENARIO).unwrap();
    let out = dir.join("out");
    let status = Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .args(["run", "--quiet"])
        .arg(&scenario)
        .arg("-o")
        .arg(&out)
        .status()
        .expect("efgdem runs");
    assert!(status.success(), "{status}");
    let os_peak = children_peak() as f64;
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    let reported = s["peak_memory_bytes"].as_f64().expect("peak_memory_bytes");
    let per_disc = s["peak_bytes_per_disc"]
        .as_f64()
        .expect("peak_bytes_per_disc");
    let rebuilds = s["neighbour_rebuilds"].as_u64().unwrap();
    println!(
        "summary: {reported:.0} bytes ({per_disc:.0} per disc), OS: {os_peak:.0} bytes; {rebuilds} rebuilds; estimate {:.0} B/disc",
        s["bytes_per_disc"].as_f64().unwrap()
    );
    assert!(
        rebuilds >= 9,
        "a run with rebuilds and a renumbering: {rebuilds}"
    );
    assert!(
        (reported - os_peak).abs() <= 0.1 * os_peak,
        "summary {reported} vs OS {os_peak}"
    );
    assert_eq!(per_disc, reported / 200_000.0);
    std::fs::remove_dir_all(&dir).ok();
}
