//! Settle a bed, then place a body in it, in one scenario
//! (docs/howto/settle-then-place.md): `check` and `run` refuse a body in
//! the region a `deposit` or `grow` will fill before any preparation step,
//! at the body's line, with a hint that works; `overlapping_discs =
//! "remove"` places the body after the preparation and removes the discs
//! it overlaps — as many as an independent count of the settled bed finds;
//! the preparation is kept in its `cache` and reused bit for bit, refused
//! when it does not match; a preparation shows its steps and an ETA, and
//! Ctrl-C stops it at once.
#![cfg(unix)]

#[allow(dead_code)]
mod common;
use common::{bin, run_with, summary, tmpdir};
use efgdem::scenario;
use std::time::{Duration, Instant};

/// 600 discs deposited in a 0.2 m box (surface near y = 0.13; at least
/// y = 0.11 at the densest packing), a footing FOOTING.
const BED: &str = r#"
[simulation]
dt = 1.0e-5
steps = 2000
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 5.0e7
ks = 2.5e7
friction = 0.5

[granular]
material = "sand"
discs = { generate = "random", method = "deposit", box = [[0.0, 0.0], [0.2, 0.3]], radius = [0.0025, 0.004], count = 600, seed = SEED, settle_steps = STEPS CACHE}
damping = { kind = "critical-ratio", zeta = 0.2 }

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.2, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 0.3]

[[wall]]
name = "right"
from = [0.2, 0.0]
to = [0.2, 0.3]

[[body]]
name = "footing"
rectangle = RECT
nodes = [11, 5]
elastic = { E = 30.0e9, nu = 0.2, density = 2400.0, plane = "strain" }
self_weight = false
REMOVE

[[body.bc]]
edge = "top"
fixed = true

[[probe]]
name = "reaction"
body = "footing"
quantity = "contact_fy"
"#;

/// The scenario with `rect` for the footing, `remove` or not, a cache file.
fn bed(rect: &str, remove: bool, cache: Option<&str>, seed: u32, steps: usize) -> String {
    BED.replace("RECT", rect)
        .replace(
            "REMOVE",
            if remove {
                "overlapping_discs = \"remove\""
            } else {
                ""
            },
        )
        .replace(
            "CACHE",
            &cache.map_or(String::new(), |c| format!(", cache = \"{c}\" ")),
        )
        .replace("SEED", &seed.to_string())
        .replace("STEPS", &steps.to_string())
}

/// Deep in the future bed.
const INSIDE: &str = "{ origin = [0.05, 0.02], size = [0.1, 0.05] }";
/// Its base 2 cm under the surface.
const EMBEDDED: &str = "[[0.05, 0.11], [0.15, 0.16]]";

#[test]
fn a_body_in_the_future_bed_is_refused_before_any_step() {
    let root = tmpdir("stp-check");
    let file = root.join("bed.toml");
    std::fs::write(&file, bed(INSIDE, false, None, 3, 30000)).unwrap();
    let line = BED
        .lines()
        .position(|l| l.starts_with("rectangle"))
        .unwrap()
        + 1;
    for cmd in ["check", "run"] {
        let t0 = Instant::now();
        let out = root.join("out");
        let o = bin()
            .args([cmd, file.to_str().unwrap()])
            .args(match cmd {
                "run" => vec!["-q", "-o", out.to_str().unwrap()],
                _ => vec![],
            })
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {err}");
        assert!(
            err.contains(&format!(
                "bed.toml:{line}: body[0].rectangle: body `footing` lies where discs will be"
            )),
            "{cmd}: {err}"
        );
        assert!(err.contains("overlapping_discs = \"remove\""), "{err}");
        // no preparation was run: a 30 000-step deposit takes seconds
        assert!(
            t0.elapsed() < Duration::from_secs(2),
            "{cmd}: {:?}",
            t0.elapsed()
        );
        assert!(!root.join("out/history.csv").exists());
    }
    // the hint works: with it, check passes and says what will happen
    std::fs::write(&file, bed(INSIDE, true, None, 3, 30000)).unwrap();
    let o = bin()
        .args(["check", file.to_str().unwrap()])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("body `footing`: placed after a gravity deposit; the discs it then overlaps will be removed"),
        "{out}"
    );
    // above the certain layer but in the settled bed: `run` finds it once
    // the bed has settled, with the same hint
    let out = root.join("settled");
    std::fs::write(
        &file,
        bed("[[0.05, 0.115], [0.15, 0.165]]", false, None, 3, 30000),
    )
    .unwrap();
    let o = bin()
        .args(["check", file.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run_with(&file, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("overlap body `footing` at the start"), "{err}");
    assert!(
        err.contains("set `overlapping_discs = \"remove\"` on the body"),
        "{err}"
    );
    assert!(!err.contains("allow_overlap"), "{err}");
    // above the bed's surface: no complaint without the option either
    std::fs::write(
        &file,
        bed("[[0.05, 0.2], [0.15, 0.25]]", false, None, 3, 30000),
    )
    .unwrap();
    let o = bin()
        .args(["check", file.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(root).unwrap();
}

/// The discs of the settled bed (the scenario without the footing, built
/// through the Rust API) that a rectangle overlaps by more than 10⁻³ of
/// their radius, counted here from the geometry.
fn independent_count(text: &str, lo: [f64; 2], hi: [f64; 2]) -> (usize, usize) {
    // the footing and its probe are the scenario's last sections
    let granular = &text[..text.find("[[body]]").unwrap()];
    let sc = scenario::parse(granular, "bed-only.toml").unwrap();
    let model = sc.build().unwrap();
    let p = &model.granular().unwrap().particles;
    let hits = (0..p.len())
        .filter(|&k| {
            let (x, r) = (p.pos[k], p.radius[k]);
            let cx = x.x.clamp(lo[0], hi[0]);
            let cy = x.y.clamp(lo[1], hi[1]);
            let inside = cx == x.x && cy == x.y;
            inside || ((x.x - cx).powi(2) + (x.y - cy).powi(2)).sqrt() < r * (1.0 - 1e-3)
        })
        .count();
    (hits, p.len())
}

#[test]
fn a_body_placed_after_the_preparation_removes_the_discs_it_overlaps() {
    let root = tmpdir("stp-run");
    // 0.1 s: the grains beside and under the footing fall into the room
    // of the discs it removed (up to a diameter, 8 mm: 40 ms of free
    // fall) before they load it; in 20 ms they may not have (a bed that
    // differs in the last bits did not)
    let text = bed(EMBEDDED, true, Some("bed.csv"), 3, 30000).replacen(
        "\nsteps = 2000\n",
        "\nsteps = 10000\n",
        1,
    );
    assert!(text.contains("\nsteps = 10000\n"));
    let file = root.join("bed.toml");
    std::fs::write(&file, &text).unwrap();
    let no_cache = bed(EMBEDDED, true, None, 3, 30000);
    let (expected, n) = independent_count(&no_cache, [0.05, 0.11], [0.15, 0.16]);
    assert!(expected > 10, "{expected} discs under the footing");
    let out = root.join("first");
    let o = run_with(&file, &out, &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["removed_discs"]["footing"], expected);
    assert_eq!(s["discs"], n - expected);
    assert_eq!(
        s["preparation"]["cache_written"],
        root.join("bed.csv").to_str().unwrap()
    );
    assert!(
        stdout.contains(&format!(
            "removed {expected} disc(s) overlapping body `footing`"
        )),
        "{stdout}"
    );
    // the grains settle onto the footing's sides and base
    assert!(s["probes"]["reaction"]["max"].as_f64().unwrap() > 0.0);
    // the cache: read back, the same run bit for bit
    let again = root.join("again");
    let o = bin()
        .args(["run", file.to_str().unwrap(), "-o", again.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("600 discs read from"), "{err}");
    assert!(
        std::fs::read(out.join("history.csv")).unwrap()
            == std::fs::read(again.join("history.csv")).unwrap()
    );
    // `check` uses it: the start state is the run's
    let o = bin()
        .args(["check", file.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("read from its cache (600 discs"),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!(
            "body `footing`: {expected} disc(s) overlapping it will be removed"
        )),
        "{stdout}"
    );
    // another packing is refused, saying what differs
    std::fs::write(&file, bed(EMBEDDED, true, Some("bed.csv"), 4, 30000)).unwrap();
    let o = run_with(&file, &root.join("other"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("granular.discs.cache"), "{err}");
    assert!(err.contains("seed 3 in the file, 4 now"), "{err}");
    // and so is an edited one
    std::fs::write(&file, &text).unwrap();
    let cache = root.join("bed.csv");
    let edited =
        std::fs::read_to_string(&cache)
            .unwrap()
            .replacen(",1\n", ",1\n0.1,0.29,0.003,2\n", 1);
    std::fs::write(&cache, edited).unwrap();
    let o = run_with(&file, &root.join("edited"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("changed since it was written") || err.contains("row numbers"),
        "{err}"
    );
    std::fs::remove_dir_all(root).unwrap();
}

#[test]
fn ctrl_c_stops_a_preparation_within_a_second() {
    let root = tmpdir("stp-stop");
    let file = root.join("bed.toml");
    // far too long to finish: 10⁸ steps
    std::fs::write(&file, bed(EMBEDDED, true, Some("bed.csv"), 3, 100_000_000)).unwrap();
    let out = root.join("out");
    let child = bin()
        .args(["run", file.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .env("EFGDEM_PROGRESS_EVERY", "0.3")
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let t0 = Instant::now();
    let k = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(k.success());
    let o = child.wait_with_output().unwrap();
    let waited = t0.elapsed();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(waited < Duration::from_secs(1), "{waited:?}");
    assert!(
        err.contains("during the preparation of the packing"),
        "{err}"
    );
    // its progress (not a terminal: plain lines): the steps, a rate, an ETA
    assert!(
        err.contains("a gravity deposit: 100000000 steps …"),
        "{err}"
    );
    let line = err
        .lines()
        .find(|l| l.starts_with("a gravity deposit: step "))
        .unwrap_or_else(|| panic!("no progress line: {err}"));
    assert!(
        line.contains("/100000000 (") && line.contains(" steps/s, eta "),
        "{line}"
    );
    assert!(!line.contains("eta —"), "{line}");
    let s = summary(&out);
    assert_eq!(s["status"], "interrupted");
    assert_eq!(s["during"], "preparation");
    let done = s["preparation"]["steps_done"].as_u64().unwrap();
    assert!(done > 0 && done < 100_000_000, "{done}");
    // nothing half-made is left: no history, no cache
    assert!(!out.join("history.csv").exists());
    assert!(!root.join("bed.csv").exists());
    std::fs::remove_dir_all(root).unwrap();
}

/// The numbers `examples/settle_then_place.toml`,
/// docs/howto/settle-then-place.md and docs/reference/cli.md quote: the
/// bed's surface (y = 0.292 in the middle of the box), 68 discs removed
/// for the footing, the summary `run` prints. About a
/// minute: `cargo test --release --test settle_then_place -- --ignored`.
#[test]
#[ignore]
fn the_example_removes_the_discs_its_page_says() {
    let root = tmpdir("stp-example");
    let example = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/settle_then_place.toml"
    );
    let file = root.join("settle_then_place.toml");
    std::fs::copy(example, &file).unwrap();
    // the directory docs/reference/cli.md shows
    let out = root.join("out/settle_then_place");
    let o = bin()
        .current_dir(&root)
        .args([
            "run",
            "settle_then_place.toml",
            "-q",
            "-o",
            "out/settle_then_place",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary(&out)["removed_discs"]["footing"], 68);
    // what run printed is what the command line's page shows
    let shown = doc_block("reference/cli.md", "When it ends, stdout has");
    assert_eq!(String::from_utf8_lossy(&o.stdout), shown);
    let bed = std::fs::read_to_string(root.join("settle_then_place.bed.csv")).unwrap();
    let rows = efgdem::scenario::generate::discs_from_csv(&bed).unwrap();
    let top = rows
        .iter()
        .filter(|d| d.pos.x > 0.2 && d.pos.x < 0.4)
        .map(|d| d.pos.y + d.r)
        .fold(0.0, f64::max);
    assert!((top - 0.292).abs() < 0.0005, "surface at {top}");
    std::fs::remove_dir_all(root).unwrap();
}

/// The fenced `text` block that follows `after` in a page of docs/.
fn doc_block(page: &str, after: &str) -> String {
    let path = format!("{}/docs/{page}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let rest = &text[text
        .find(after)
        .unwrap_or_else(|| panic!("{after} in {page}"))..];
    let start = rest.find("```text\n").unwrap() + "```text\n".len();
    rest[start..start + rest[start..].find("```").unwrap()].to_string()
}

/// The message docs/howto/settle-then-place.md shows for
/// `examples/footing.toml` with its footing lowered into the future bed.
#[test]
fn the_refusal_the_page_shows_is_what_check_says() {
    let root = tmpdir("stp-doc");
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/footing.toml");
    let text = std::fs::read_to_string(example).unwrap();
    let lowered = text
        .replace("origin = [0.65, 0.54]", "origin = [0.65, 0.40]")
        .replace("point = [0.8, 0.64]", "point = [0.8, 0.50]");
    assert_ne!(text, lowered);
    let file = root.join("footing.toml");
    std::fs::write(&file, lowered).unwrap();
    let o = bin()
        .args(["check", file.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let shown = doc_block("howto/settle-then-place.md", "its footing lowered to");
    let said: String = err
        .lines()
        .filter(|l| l.starts_with("error:"))
        .map(|l| l.replace(&format!("{}", file.display()), "footing.toml") + "\n")
        .collect();
    assert_eq!(said, shown);
    std::fs::remove_dir_all(root).unwrap();
}

/// A polygon body (a culvert with a circular opening) in a growth's box
/// is refused at its `outline`; partly in the box too; above it, not.
#[test]
fn a_polygon_body_in_a_growth_is_refused_at_its_outline() {
    let root = tmpdir("stp-polygon");
    let scenario = |y0: f64| {
        let y1 = y0 + 0.1;
        format!(
            r#"
[simulation]
dt = 1.0e-5
steps = 10
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 5.0e7

[granular]
material = "sand"
discs = {{ generate = "random", method = "grow", box = [[0.0, 0.0], [0.3, 0.2]], radius = [0.003, 0.004], count = 300 }}

[[body]]
name = "culvert"
outline = [[0.1, {y0}], [0.2, {y0}], [0.2, {y1}], [0.1, {y1}]]
holes = [{{ centre = [0.15, {yc}], radius = 0.03 }}]
spacing = 0.01
elastic = {{ E = 30.0e9, nu = 0.2, density = 2400.0 }}

[[body.bc]]
edge = "outline"
fixed = true
"#,
            yc = y0 + 0.05
        )
    };
    let file = root.join("culvert.toml");
    for (y0, refused) in [(0.05, true), (0.15, true), (0.25, false)] {
        let text = scenario(y0);
        let line = text.lines().position(|l| l.starts_with("outline")).unwrap() + 1;
        std::fs::write(&file, text).unwrap();
        let o = bin()
            .args(["check", file.to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        match refused {
            true => {
                assert_eq!(o.status.code(), Some(2), "{y0}: {err}");
                assert!(
                    err.contains(&format!("culvert.toml:{line}: body[0].outline: body `culvert` lies where discs will be: the radius growth")),
                    "{y0}: {err}"
                );
            }
            false => assert!(o.status.success(), "{y0}: {err}"),
        }
    }
    std::fs::remove_dir_all(root).unwrap();
}

/// A cache that cannot be written loses the cache, not the preparation:
/// the run goes on with the prepared bed and says so.
#[test]
fn a_cache_that_cannot_be_written_does_not_stop_the_run() {
    let root = tmpdir("stp-cache-io");
    // a file where the cache's directory would be
    std::fs::write(root.join("blocker"), "not a directory").unwrap();
    let file = root.join("bed.toml");
    std::fs::write(&file, bed(EMBEDDED, true, Some("blocker/bed.csv"), 3, 2000)).unwrap();
    let out = root.join("out");
    let o = run_with(&file, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: the prepared packing could not be saved in its cache"),
        "{err}"
    );
    let s = summary(&out);
    assert!(s["preparation"]["cache_written"].is_null());
    let why = s["preparation"]["cache_error"].as_str().unwrap();
    assert!(why.contains("blocker/bed.csv"), "{why}");
    assert_eq!(s["status"], "completed");
    std::fs::remove_dir_all(root).unwrap();
}
