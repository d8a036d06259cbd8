//! Helpers shared by the tests: the binary, a fresh output directory, a
//! run that must succeed and its `summary.json`, scenarios used by
//! several tests, and a closure run on a pool of n threads.

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

/// The sand of the ranks tests: radii 2–3 mm, friction 0.5, rolling
/// resistance 0.1, normal dashpots at ζ = 0.2.
const SAND: &str = r#"
[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5
rolling_friction = 0.1
"#;

/// A box `w` wide for discs of [`SAND`]: a floor from `x = −0.01` to
/// `w + 0.01` (`floor` appended to its table, e.g. a motion) and two side
/// walls up to `h` (`sides` appended to theirs).
fn sand_box(w: f64, h: f64, floor: &str, sides: &str) -> String {
    format!(
        r#"
[[wall]]
name = "floor"
from = [-0.01, 0.0]
to = [{r}, 0.0]
{floor}
[[wall]]
name = "left"
from = [0.0, -0.02]
to = [0.0, {h}]
{sides}
[[wall]]
name = "right"
from = [{w}, -0.02]
to = [{w}, {h}]
{sides}"#,
        r = w + 0.01
    )
}

/// `n` loose discs of [`SAND`] falling for `steps` steps into a box
/// `w` × `h` (they are generated in it, at most four a cm²) under a servo
/// lid at `h` (2 kPa).
#[allow(dead_code)]
pub fn settling(n: usize, steps: usize, w: f64, h: f64) -> String {
    format!(
        r#"
[simulation]
steps = {steps}
gravity = [0.0, -9.81]
{SAND}
[granular]
material = "sand"
discs = {{ generate = "random", box = [[0.0, 0.0], [{w}, {h}]], count = {n}, radius = [0.002, 0.003], seed = 5 }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}
{walls}
[[wall]]
name = "lid"
from = [-0.01, {h}]
to = [{r}, {h}]
servo = {{ stress = 2.0e3, max_velocity = 0.5 }}
"#,
        walls = sand_box(w, h + 0.1, "", ""),
        r = w + 0.01
    )
}

/// A column of 1000 discs of [`SAND`] grown dense in a box 50 mm wide and
/// 0.5 m tall between frictionless walls (no arching holds it up), on a
/// floor shaken vertically for `steps` steps: its velocity a triangle
/// wave of ±1 m/s and period 0.04 s (a 10 mm stroke, peak acceleration
/// 100 m/s², about 10 g). The column leaps and lands every period, and
/// the discs near a horizontal cut cross it back and forth with their
/// contacts. A history row every 500 steps (kinetic energy, the floor's
/// force, two discs' heights), a frame every 4000.
#[allow(dead_code)]
pub fn shaken_column(steps: usize) -> String {
    let (period, v) = (0.04, 1.0);
    let mut hist = vec!["[0.0, 0.0, 0.0]".to_string()];
    for k in 0..100 {
        let t = period / 4.0 + period / 2.0 * k as f64;
        let vy = if k % 2 == 0 { v } else { -v };
        hist.push(format!("[{t:.3}, 0.0, {vy:.1}]"));
    }
    format!(
        r#"
[simulation]
steps = {steps}
gravity = [0.0, -9.81]
{SAND}
[[material]]
name = "smooth"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.0

[granular]
material = "sand"
discs = {{ generate = "random", method = "grow", box = [[0.0, 0.0], [0.05, 0.5]], count = 1000, radius = [0.002, 0.003], seed = 4, settle_steps = 3000 }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}
{walls}
[output]
every = 500
vtk_every = 4000

[[probe]]
name = "kinetic"
quantity = "kinetic"

[[probe]]
name = "floor_fy"
quantity = "wall_fy"
wall = "floor"

[[probe]]
name = "y500"
disc = 500
quantity = "y"

[[probe]]
name = "y900"
disc = 900
quantity = "y"
"#,
        walls = sand_box(
            0.05,
            0.8,
            &format!("history = [{}]", hist.join(", ")),
            "material = \"smooth\""
        )
    )
}

/// A column of 1000 discs of [`SAND`] grown dense 0.1 m wide and 0.25 m
/// tall against the left wall of a box 0.6 m wide, released under
/// gravity for `steps` steps: it collapses and spreads to the right, so
/// regions cut for the column lose their balance as it runs out. A
/// history row every 500 steps (the kinetic energy, the contacts).
#[allow(dead_code)]
pub fn collapsing_column(steps: usize) -> String {
    format!(
        r#"
[simulation]
steps = {steps}
gravity = [0.0, -9.81]
{SAND}
[granular]
material = "sand"
discs = {{ generate = "random", method = "grow", box = [[0.0, 0.0], [0.1, 0.25]], count = 1000, radius = [0.002, 0.003], seed = 6, settle_steps = 3000 }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}
{walls}
[output]
every = 500
vtk_every = 0

[[probe]]
name = "kinetic"
quantity = "kinetic"

[[probe]]
name = "contacts"
quantity = "contacts"
"#,
        walls = sand_box(0.6, 0.4, "", "")
    )
}

/// `f` run on a pool of `threads` worker threads (results of the library
/// must not depend on how many).
#[allow(dead_code)]
pub fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
        .install(f)
}
