//! Helpers shared by the CLI tests: the binary, a fresh output directory,
//! a run that must succeed, and its `summary.json`.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The `efgdem` binary built for the tests.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_efgdem"))
}

/// An empty directory `efgdem-{tag}-{pid}` in the system's temp dir.
pub fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("efgdem-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `efgdem run FILE -q -o OUT EXTRA…`, whatever its outcome.
pub fn run_with(file: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    bin()
        .args([
            "run",
            file.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
        .args(extra)
        .output()
        .unwrap()
}

/// `efgdem run FILE -q -o OUT`, which must succeed (stderr shown if not).
pub fn run(file: &Path, out: &Path) {
    let o = run_with(file, out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The `summary.json` a run wrote to `out`.
pub fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// A CSV file as `(header, rows)` of strings, `#` lines skipped.
#[allow(dead_code)]
pub type Csv = (Vec<String>, Vec<Vec<String>>);

/// Read a CSV file ([`Csv`]).
#[allow(dead_code)]
pub fn csv(path: &Path) -> Csv {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (head, rows)
}

/// The column `name` of a [`Csv`] as numbers.
#[allow(dead_code)]
pub fn column(csv: &Csv, name: &str) -> Vec<f64> {
    let k = csv.0.iter().position(|h| h == name).unwrap();
    csv.1.iter().map(|r| r[k].parse().unwrap()).collect()
}

/// `examples/hex_footing.toml` with friction (0.3) and rolling resistance
/// (0.05) in the bed, a 3 GPa footing, `steps` steps instead of its end
/// time, and `extra` appended to `[simulation]` (e.g. the coupled scheme,
/// or an `[output]` table).
#[allow(dead_code)]
pub fn hex_footing(steps: usize, extra: &str) -> String {
    let src = include_str!("../../examples/hex_footing.toml")
        .replace("end_time = 0.05\n", &format!("steps = {steps}\n"))
        .replace(
            "gravity = [0.0, -9.81]\n",
            &format!("gravity = [0.0, -9.81]\n{extra}\n"),
        )
        .replace(
            "friction = 0.0\n",
            "friction = 0.3\nrolling_friction = 0.05\n",
        )
        .replace("E = 2.0e9", "E = 3.0e9");
    assert!(src.contains("rolling_friction") && src.contains("E = 3.0e9"));
    src
}
