//! The tutorial's numbers cannot go stale: each step of `docs/tutorial.md`
//! is run as the page says, and every number the page quotes from a run is
//! compared with the run's own `history.csv` / `summary.json` to the digits
//! shown. The shipped `docs/tutorial/bed.csv` must be exactly the bed that
//! step 1 writes.
//!
//! When a change of the code moves a result, this test names the number
//! and the page to update.

mod common;

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A run's `history.csv`: column name → values.
struct History {
    names: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl History {
    fn read(out: &Path) -> History {
        let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
        let mut lines = text.lines();
        let names = lines.next().unwrap().split(',').map(String::from).collect();
        let rows = lines
            .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
            .collect();
        History { names, rows }
    }

    fn col(&self, name: &str) -> Vec<f64> {
        let k = self
            .names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("history.csv has no column `{name}`: {:?}", self.names));
        self.rows.iter().map(|r| r[k]).collect()
    }

    fn last(&self, name: &str) -> f64 {
        *self.col(name).last().unwrap()
    }

    /// Mean of `name` over the rows with `from ≤ t < to`.
    fn mean(&self, name: &str, from: f64, to: f64) -> f64 {
        let t = self.col("t");
        let v: Vec<f64> = self
            .col(name)
            .into_iter()
            .zip(&t)
            .filter(|(_, t)| (from..to).contains(*t))
            .map(|(v, _)| v)
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    }

    /// (largest value, its time) of `name`.
    fn max(&self, name: &str) -> (f64, f64) {
        self.max_of(name, 1.0)
    }

    /// (smallest value, its time) of `name`.
    fn min(&self, name: &str) -> (f64, f64) {
        let (v, t) = self.max_of(name, -1.0);
        (-v, t)
    }

    /// (largest `sign · value`, its time) of `name`.
    fn max_of(&self, name: &str, sign: f64) -> (f64, f64) {
        let t = self.col("t");
        self.col(name)
            .into_iter()
            .map(|v| sign * v)
            .zip(t)
            .fold((f64::MIN, 0.0), |a, b| if b.0 > a.0 { b } else { a })
    }
}

/// A number as the page writes it: `−600.6`, `13 644`, `4.4·10⁻⁷`.
/// Returns the value and half a unit of its last digit.
fn parse_shown(shown: &str) -> (f64, f64) {
    let s: String = shown
        .replace('−', "-")
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    let (mantissa, exp) = match s.split_once("·10") {
        Some((m, e)) => {
            let e: String = e
                .chars()
                .map(|c| match c {
                    '⁻' => '-',
                    '⁰' => '0',
                    '¹' => '1',
                    '²' => '2',
                    '³' => '3',
                    '⁴' => '4',
                    '⁵' => '5',
                    '⁶' => '6',
                    '⁷' => '7',
                    '⁸' => '8',
                    '⁹' => '9',
                    c => c,
                })
                .collect();
            (m.to_string(), e.parse::<i32>().unwrap())
        }
        None => (s.clone(), 0),
    };
    let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len() as i32);
    let scale = 10f64.powi(exp);
    let value = mantissa.parse::<f64>().unwrap() * scale;
    (value, 0.5 * 10f64.powi(-decimals) * scale)
}

/// Checks one quoted number: the page contains `context`, `context`
/// contains `shown`, and `actual` rounds to `shown` at its last digit.
struct Page {
    name: &'static str,
    text: String,
    failures: Vec<String>,
}

impl Page {
    fn read(name: &'static str) -> Page {
        let text = std::fs::read_to_string(root().join(name)).unwrap();
        // join the lines, so that a context may wrap across them
        let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
        Page {
            name,
            text,
            failures: Vec::new(),
        }
    }

    fn quote(&mut self, context: &str, shown: &str, actual: f64) {
        assert!(
            context.contains(shown),
            "{context:?} does not contain {shown:?}"
        );
        if !self.text.contains(context) {
            self.failures.push(format!(
                "{}: the text {context:?} is not on the page",
                self.name
            ));
            return;
        }
        let (value, half_digit) = parse_shown(shown);
        if (actual - value).abs() > half_digit * (1.0 + 1e-9) {
            self.failures.push(format!(
                "{}: {context:?} quotes {shown}, the run gives {actual}",
                self.name
            ));
        }
    }

    fn finish(self) {
        assert!(self.failures.is_empty(), "{}", self.failures.join("\n"));
    }
}

fn tutorial_file(name: &str) -> PathBuf {
    root().join("docs/tutorial").join(name)
}

fn weight_of_bed() -> f64 {
    let bed = std::fs::read_to_string(tutorial_file("bed.csv")).unwrap();
    bed.lines()
        .skip(1)
        .map(|l| {
            let r: f64 = l.split(',').nth(2).unwrap().parse().unwrap();
            2650.0 * std::f64::consts::PI * r * r * 9.81
        })
        .sum()
}

/// Highest top `y + r` of the bed's discs whose centre is within
/// `[x0 − r, x1 + r]`.
fn bed_top(x0: f64, x1: f64) -> f64 {
    let bed = std::fs::read_to_string(tutorial_file("bed.csv")).unwrap();
    bed.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (v[0], v[1], v[2])
        })
        .filter(|&(x, _, r)| x > x0 - r && x < x1 + r)
        .map(|(_, y, r)| y + r)
        .fold(f64::MIN, f64::max)
}

#[test]
fn tutorial_step_1_settling_box() {
    let out = common::tmpdir("tutorial-01");
    common::run(&tutorial_file("01_settling_box.toml"), &out);
    // the shipped bed is this run's bed
    let made = std::fs::read(out.join("discs_final.csv")).unwrap();
    let shipped = std::fs::read(tutorial_file("bed.csv")).unwrap();
    assert!(
        made == shipped,
        "docs/tutorial/bed.csv is not the bed step 1 writes: copy {} over it \
         (and update docs/tutorial.md's numbers)",
        out.join("discs_final.csv").display()
    );

    let h = History::read(&out);
    let s = common::summary(&out);
    let mut page = Page::read("docs/tutorial.md");
    page.quote("`dt = 1.01e-4` s", "1.01e-4", s["dt"].as_f64().unwrap());
    page.quote("9897 steps", "9897", s["steps"].as_f64().unwrap());
    page.quote("last step (9897)", "9897", h.last("step"));
    let (ke_peak, t_ke) = h.max("kinetic");
    page.quote("peaks at 8.7 J", "8.7", ke_peak);
    page.quote("land at t ≈ 0.08 s", "0.08", t_ke);
    let (floor_peak, t_floor) = h.min("floor_fy");
    page.quote("peaks at −1293 N", "−1293", floor_peak);
    page.quote("−1293 N at t ≈ 0.08 s", "0.08", t_floor);
    let t = h.col("t");
    let quiet = h
        .col("kinetic")
        .iter()
        .zip(&t)
        .find(|&(k, &tt)| tt > t_ke && *k < 1e-3 * ke_peak)
        .map(|(_, &tt)| tt)
        .unwrap();
    page.quote("of its peak by t = 0.27 s", "0.27", quiet);
    page.quote("levels off at 528", "528", h.last("contacts"));
    page.quote("carries −605.8 N", "−605.8", h.last("floor_fy"));
    page.quote("discs weigh 612.9 N", "612.9", weight_of_bed());
    let walls_fy: f64 = s["wall_forces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["force"][1].as_f64().unwrap())
        .sum();
    page.quote("add up to −612.7 N", "−612.7", walls_fy);
    let c = &s["contacts"];
    page.quote("492 disc–disc", "492", c["disc_disc"].as_f64().unwrap());
    page.quote("36 disc–wall", "36", c["disc_wall"].as_f64().unwrap());
    page.quote("reaches y = 0.107 m", "0.107", bed_top(f64::MIN, f64::MAX));
    page.quote("the surface is at 0.103 m", "0.103", bed_top(0.1, 0.2));
    page.finish();
}

#[test]
fn tutorial_step_2_block_on_bed() {
    let file = tutorial_file("02_block_on_bed.toml");
    let check = common::bin().arg("check").arg(&file).output().unwrap();
    assert!(check.status.success());
    let check = String::from_utf8_lossy(&check.stdout).into_owned();
    let out = common::tmpdir("tutorial-02");
    common::run(&file, &out);
    let h = History::read(&out);
    let s = common::summary(&out);
    let mut page = Page::read("docs/tutorial.md");
    for quoted in ["4949 steps", "55 nodes, 110 DOFs", "with 112 segments"] {
        assert!(
            check.contains(quoted),
            "`check` no longer says {quoted:?}:\n{check}"
        );
    }
    page.quote("reports 4949 steps", "4949", s["steps"].as_f64().unwrap());
    let gap = 0.106 - bed_top(0.1, 0.2);
    page.quote("2.83 mm above the highest grain", "2.83", gap * 1e3);
    page.quote("free fall of 2.83 mm", "2.83", gap * 1e3);
    page.quote(
        "takes √(2 · 0.00283/9.81) = 0.0240 s",
        "0.0240",
        (2.0 * gap / 9.81).sqrt(),
    );
    let first = s["first_contact_time"].as_f64().unwrap();
    page.quote("`first_contact_time` 0.0240 s", "0.0240", first);
    let peak = s["peak_contact_force"].as_f64().unwrap();
    page.quote("`peak_contact_force` 300 N", "300", peak);
    page.quote(
        "300 N at t = 0.029 s",
        "0.029",
        s["peak_contact_time"].as_f64().unwrap(),
    );
    let weight = 0.1 * 0.04 * 2000.0 * 9.81;
    page.quote("2000 × 9.81 = 78.48 N", "78.48", weight);
    page.quote("3.8 × the weight", "3.8", peak / weight);
    page.quote("averages 78.4 N", "78.4", h.mean("bed_force", 0.4, 1.0));
    page.quote("ends at −4.10 mm", "−4.10", h.last("block_uy") * 1e3);
    page.quote(
        "1.3 mm of bed compaction",
        "1.3",
        -h.last("block_uy") * 1e3 - gap * 1e3,
    );
    page.quote("ends at 522", "522", h.last("contacts"));
    let tilt = h.last("left_uy") - h.last("right_uy");
    page.quote("ends 1.2 mm lower", "1.2", tilt * 1e3);
    page.quote("a turn of 0.012 rad", "0.012", tilt / 0.1);
    page.quote("`W_ext` is 0.362 J", "0.362", h.last("W_ext"));
    page.quote("`E_diss` = 0.253 J", "0.253", h.last("E_diss"));
    page.quote("`E_contact` = 0.109 J", "0.109", h.last("E_contact"));
    // the first row after step 0
    page.quote("`E_diss` starts at −0.061 J", "−0.061", h.col("E_diss")[1]);
    page.finish();
}

#[test]
fn tutorial_step_3_footing() {
    let out = common::tmpdir("tutorial-03");
    common::run(&tutorial_file("03_footing.toml"), &out);
    let h = History::read(&out);
    let s = common::summary(&out);
    let mut page = Page::read("docs/tutorial.md");
    page.quote(
        "10 000 steps in about",
        "10 000",
        s["steps"].as_f64().unwrap(),
    );
    page.quote("−20.0 mm from", "−20.0", h.last("settlement") * 1e3);
    page.quote(
        "at t = 0.0569 s",
        "0.0569",
        s["first_contact_time"].as_f64().unwrap(),
    );
    page.quote("averages 216 N", "216", h.mean("reaction", 0.0, 0.15));
    page.quote("266 N between", "266", h.mean("reaction", 0.15, 0.25));
    page.quote("605 N over 0.1–0.4 s", "605", h.mean("reaction", 0.1, 0.4));
    page.quote(
        "peaks at 1342 N",
        "1342",
        s["peak_contact_force"].as_f64().unwrap(),
    );
    page.quote(
        "1342 N at t = 0.328 s",
        "0.328",
        s["peak_contact_time"].as_f64().unwrap(),
    );
    page.quote("reaction ends at 176 N", "176", h.last("reaction"));
    page.quote("`W_ext` = 9.03 J", "9.03", h.last("W_ext"));
    page.quote("`E_diss` = 8.84 J", "8.84", h.last("E_diss"));
    page.quote("`E_contact` = 0.19 J", "0.19", h.last("E_contact"));
    page.finish();
}

#[test]
fn tutorial_plate_with_a_hole_check() {
    let file = root().join("examples/culvert.toml");
    let check = common::bin().arg("check").arg(&file).output().unwrap();
    assert!(check.status.success());
    let check = String::from_utf8_lossy(&check.stdout).into_owned();
    let page = Page::read("docs/tutorial/plate-with-hole.md");
    for quoted in [
        "1200 discs",
        "377 nodes, 754 DOFs, 1 contact chain(s) with 320 segments",
        "7949 steps",
        "compliant with 14 DEM step(s) per body step",
    ] {
        assert!(
            check.contains(quoted),
            "`check` no longer says {quoted:?}:\n{check}"
        );
        assert!(
            page.text.contains(quoted),
            "{} does not quote {quoted:?}",
            page.name
        );
    }
}

#[test]
fn shown_numbers_parse() {
    let (v, h) = parse_shown("−600.6");
    assert!((v + 600.6).abs() < 1e-12 && (h - 0.05).abs() < 1e-15);
    assert_eq!(parse_shown("13 644"), (13644.0, 0.5));
    let (v, h) = parse_shown("4.4·10⁻⁷");
    assert!((v - 4.4e-7).abs() < 1e-20 && (h - 0.5e-8).abs() < 1e-20);
}
