//! `efgdem reproduce`: the paper's §4 end to end, from built-in scenarios
//! (the same files as `examples/`): Example 1 (disc on a cantilever) with
//! both Newmark variants, friction 0.3 / 0.5 / no sliding and the thin
//! disc; Example 2 (nine discs) against rigid plates and the EFG plate,
//! Tests 1 and 2, and the Young's-modulus sweep. Writes every run's
//! `history.csv` / `summary.json`, the data and PNG plots of Figs. 9, 10,
//! 11, 12, 14, 15 and 17, the values the paper's text gives for them
//! (`paper_values.csv`, drawn in black on the figures), and `report.md`
//! with our numbers beside the paper's and beside theory. The FE–DE
//! cross-check (§4.2.1, Q4 plate on the EFG grid) runs beside the EFG
//! plate in Fig. 14.

use crate::coupling::CouplingError;
use crate::efg::boundary::EfgContinuum;
use crate::geom::Vec2;
use crate::output::csv::{HistoryWriter, read};
use crate::output::plot::{
    Chart, Mark, PAPER_COLOR, Panel, PlotError, REFERENCE_COLOR, Series, line_chart, palette,
};
use crate::run::{RunError, RunOptions};
use crate::scenario::{Probe, Scenario, ScenarioError, parse};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

// The paper's scenarios, built in (also shipped in `examples/`).

/// Example 1 (§4.1): a disc dropped on the free end of an EFG cantilever
/// (`examples/paper_cantilever_disc.toml`).
pub const EXAMPLE1: &str = include_str!("../examples/paper_cantilever_disc.toml");
/// Example 2 (§4.2), Tests 1 and 2: the nine discs with the left plate an
/// EFG strip (`examples/paper_nine_disc_test{1,2}.toml`).
pub const NINE_DISC_EFG: [&str; 2] = [
    include_str!("../examples/paper_nine_disc_test1.toml"),
    include_str!("../examples/paper_nine_disc_test2.toml"),
];
/// Example 2, Tests 1 and 2, FE–DE version (§4.2.1): the left plate a Q4
/// strip on the EFG grid (`examples/fem_nine_disc_test{1,2}.toml`).
pub const NINE_DISC_FEM: [&str; 2] = [
    include_str!("../examples/fem_nine_disc_test1.toml"),
    include_str!("../examples/fem_nine_disc_test2.toml"),
];
/// Cundall & Strack's nine-disc Tests 1 and 2 with four rigid plates
/// (`examples/nine_disc_rigid_test{1,2}.toml`).
pub const NINE_DISC_RIGID: [&str; 2] = [
    include_str!("../examples/nine_disc_rigid_test1.toml"),
    include_str!("../examples/nine_disc_rigid_test2.toml"),
];

/// Young's moduli of the paper's sweep (§4.2.3, Fig. 15).
pub const E_SWEEP: [f64; 4] = [2.1e14, 2.1e13, 2.1e12, 1.0e10];
/// Young's modulus of the plate of Fig. 17.
pub const E_FIG17: f64 = 1.0e12;

/// The values the paper's §4 text gives for the reproduced figures
/// (`assets/paper_values.csv`), one per row with where it comes from.
/// Columns: `figure` (the PNG's stem, e.g. `fig12`, `fig14_test1`),
/// `kind` (`vline`: an instant or cycle, drawn as a vertical line;
/// `point`: an `(x, y)` value, `y` may be `m g`, the disc's weight;
/// `time`: the instant the figure shows; `setting`: a parameter of the
/// figure; `none`: what the paper does not give), `x`, `y`, their units,
/// `tag` (the mark on the figure), `label` (its legend entry), `source`
/// (section and the paper's own line numbers) and `quote` (the sentence). `efgdem reproduce`
/// copies it to `DIR/paper_values.csv`.
pub const PAPER_VALUES: &str = include_str!("../assets/paper_values.csv");

/// One row of [`PAPER_VALUES`].
#[derive(Debug, Clone, PartialEq)]
pub struct PaperValue {
    /// The figure it belongs to (the PNG's file stem without its suffix).
    pub figure: String,
    /// `vline`, `point`, `time`, `setting` or `none` (see [`PAPER_VALUES`]).
    pub kind: String,
    /// x value (time in s, cycle, position in m, modulus in units).
    pub x: Option<f64>,
    /// y value as written (a number, or `m g` for the disc's weight).
    pub y: String,
    /// Unit of `x`.
    pub x_unit: String,
    /// Unit of `y`.
    pub y_unit: String,
    /// The mark written next to it on the figure (`(a)`, `plates stop`, …).
    pub tag: String,
    /// Legend entry (rows with the same label form one legend entry).
    pub label: String,
    /// Section and lines of the paper it is read from.
    pub source: String,
    /// The paper's sentence.
    pub quote: String,
}

/// Split one CSV line (fields in double quotes may hold commas; `""` is a
/// quote).
fn csv_fields(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

/// The rows of [`PAPER_VALUES`].
pub fn paper_values() -> std::result::Result<Vec<PaperValue>, String> {
    let mut lines = PAPER_VALUES.lines().enumerate();
    let header = lines.next().map(|(_, h)| csv_fields(h)).unwrap_or_default();
    if header.len() != 10 {
        return Err(format!(
            "paper_values.csv: header has {} columns, not 10",
            header.len()
        ));
    }
    lines
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            let f = csv_fields(l);
            if f.len() != 10 {
                return Err(format!(
                    "paper_values.csv:{}: {} fields, not 10",
                    i + 1,
                    f.len()
                ));
            }
            let x = match f[2].trim() {
                "" => None,
                s => Some(
                    s.parse::<f64>()
                        .map_err(|e| format!("paper_values.csv:{}: x `{s}`: {e}", i + 1))?,
                ),
            };
            let mut it = f.into_iter();
            let mut next = || it.next().unwrap_or_default();
            let (figure, kind) = (next(), next());
            let _x = next();
            Ok(PaperValue {
                figure,
                kind,
                x,
                y: next(),
                x_unit: next(),
                y_unit: next(),
                tag: next(),
                label: next(),
                source: next(),
                quote: next(),
            })
        })
        .collect()
}

/// Why `reproduce` failed.
#[derive(Debug, thiserror::Error)]
pub enum ReproduceError {
    /// A built-in scenario did not parse or build.
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// One of the runs failed.
    #[error("run `{name}`: {source}")]
    Run {
        /// The run's name (its output directory).
        name: String,
        /// Why it failed.
        source: RunError,
    },
    /// A coupled step outside `run` failed.
    #[error(transparent)]
    Coupling(#[from] CouplingError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// An EFG body failed (static solve or sampling).
    #[error(transparent)]
    Efg(#[from] crate::efg::EfgError),
    /// Writing or reading an output file failed.
    #[error("i/o: {0}")]
    Io(#[from] std::io::Error),
    /// A result is missing or not what the report expects.
    #[error("{0}")]
    Data(String),
}

type Result<T> = std::result::Result<T, ReproduceError>;

/// The coupled model of a built-in coupled scenario.
fn coupled(sc: &Scenario) -> Result<crate::coupling::CoupledModel> {
    match sc.build()?.system {
        crate::model::System::Coupled(m) => Ok(*m),
        _ => Err(ReproduceError::Data(
            "a built-in scenario is not coupled".into(),
        )),
    }
}

/// A history file as columns.
struct History {
    cols: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl History {
    fn load(dir: &Path) -> Result<Self> {
        let (cols, rows) = read(&dir.join("history.csv"))?;
        Ok(History { cols, rows })
    }
    fn col(&self, name: &str) -> Result<Vec<f64>> {
        let i = self
            .cols
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| ReproduceError::Data(format!("history has no column `{name}`")))?;
        Ok(self.rows.iter().map(|r| r[i]).collect())
    }
    fn xy(&self, x: &str, y: &str, scale: f64) -> Result<Vec<(f64, f64)>> {
        Ok(self
            .col(x)?
            .into_iter()
            .zip(self.col(y)?)
            .map(|(a, b)| (a, b * scale))
            .collect())
    }
    /// The row of step `step`.
    fn at_step(&self, step: usize) -> Result<&[f64]> {
        let i = self.cols.iter().position(|c| c == "step").unwrap_or(0);
        self.rows
            .iter()
            .find(|r| r[i] == step as f64)
            .map(Vec::as_slice)
            .ok_or_else(|| ReproduceError::Data(format!("history has no row for step {step}")))
    }
}

/// `(x, a − b)·scale` of two curves on the same x values (the runs behind
/// them record the same steps).
fn difference(a: &[(f64, f64)], b: &[(f64, f64)], scale: f64) -> Result<Vec<(f64, f64)>> {
    if a.len() != b.len() || a.iter().zip(b).any(|(p, q)| p.0 != q.0) {
        return Err(ReproduceError::Data(
            "deviation of two curves recorded at different x".into(),
        ));
    }
    Ok(a.iter()
        .zip(b)
        .map(|(p, q)| (p.0, (p.1 - q.1) * scale))
        .collect())
}

/// One finished run.
struct Done {
    dir: PathBuf,
    summary: Value,
    history: History,
}

/// One figure written, for the report's list.
struct Figure {
    key: String,
    file: String,
    data: String,
    runs: Vec<String>,
}

/// Runs and collects the results under one output directory.
struct Job {
    out: PathBuf,
    quiet: bool,
    /// The runs' start-up warnings, each with the number of runs that gave
    /// it (printed once each at the end).
    warnings: std::collections::BTreeMap<String, usize>,
    report: String,
    paper: Vec<PaperValue>,
    figures: Vec<Figure>,
}

impl Job {
    fn run(&mut self, name: &str, sc: &Scenario) -> Result<Done> {
        let dir = self.out.join("runs").join(name);
        let t0 = Instant::now();
        // the report's own run directories: replaced on every reproduction
        let opts = RunOptions {
            quiet: true,
            overwrite: true,
            warn: false,
            ..RunOptions::new(&dir)
        };
        let summary = crate::run::run(sc, &opts).map_err(|source| ReproduceError::Run {
            name: name.to_string(),
            source,
        })?;
        if !self.quiet {
            eprintln!("  {name:<28} {:>7.3} s", t0.elapsed().as_secs_f64());
        }
        for w in summary["warnings"].as_array().into_iter().flatten() {
            let w = w.as_str().unwrap_or_default().to_string();
            *self.warnings.entry(w).or_default() += 1;
        }
        let history = History::load(&dir)?;
        Ok(Done {
            dir,
            summary,
            history,
        })
    }

    /// The paper's values for `figure` as series (vertical lines and
    /// points; `mg` stands for `m g`).
    fn paper_series(&self, figure: &str, mg: Option<f64>) -> Result<Vec<Series>> {
        let mut out: Vec<Series> = Vec::new();
        for v in self.paper.iter().filter(|v| v.figure == figure) {
            let Some(x) = v.x else { continue };
            let (mark, y) = match v.kind.as_str() {
                "vline" => (Mark::VLines, f64::NAN),
                "point" => {
                    let y = match v.y.trim() {
                        "m g" => mg.ok_or_else(|| {
                            ReproduceError::Data(format!(
                                "{figure}: paper value `m g` without a disc"
                            ))
                        })?,
                        s => s.parse().map_err(|e| {
                            ReproduceError::Data(format!("{figure}: paper value y `{s}`: {e}"))
                        })?,
                    };
                    (Mark::Diamonds, y)
                }
                _ => continue,
            };
            match out
                .iter_mut()
                .find(|s| s.label == v.label && s.mark == mark)
            {
                Some(s) => {
                    s.points.push((x, y));
                    s.tags.push(v.tag.clone());
                }
                None => out.push(
                    Series::new(v.label.clone(), vec![(x, y)], mark)
                        .with_color(PAPER_COLOR)
                        .with_tags([v.tag.clone()]),
                ),
            }
        }
        Ok(out)
    }

    /// Notes for `figure` from the paper's rows of `kinds` (`time`,
    /// `setting`: what it shows; `none`: what the paper does not give).
    fn paper_notes(&self, figure: &str, kinds: &[&str]) -> Vec<String> {
        self.paper
            .iter()
            .filter(|v| v.figure == figure && kinds.contains(&v.kind.as_str()))
            .map(|v| {
                let mut s = v.label.clone();
                if let Some(c) = s.get(..1) {
                    s.replace_range(..1, &c.to_uppercase());
                }
                s + "."
            })
            .collect()
    }

    /// Check that `sc` is set up as the paper's rows of `key` say (plate
    /// speed, the cycle the plates stop, cycles, Δt; Example 2).
    fn check_setup(&self, key: &str, sc: &Scenario) -> Result<()> {
        let bad = |what: &str, paper: f64, ours: f64| {
            ReproduceError::Data(format!(
                "{key}: the built-in scenario's {what} is {ours}, the paper's {paper} (paper_values.csv)"
            ))
        };
        for v in self.paper.iter().filter(|v| v.figure == key) {
            let Some(x) = v.x else { continue };
            let ours = match (v.kind.as_str(), v.tag.as_str()) {
                ("setting", "speed") => sc
                    .wall
                    .iter()
                    .filter_map(|w| w.velocity)
                    .map(|u| u[0].hypot(u[1]))
                    .fold(0.0, f64::max),
                ("vline", "plates stop") => sc
                    .wall
                    .iter()
                    .filter_map(|w| w.until_step)
                    .max()
                    .unwrap_or(0) as f64,
                ("setting", "cycles") => sc.simulation.steps.unwrap_or(0) as f64,
                ("setting", "dt") => sc.simulation.dt.unwrap_or(0.0),
                _ => continue,
            };
            if (ours - x).abs() > 1e-12 * x.abs() {
                return Err(bad(&v.label, x, ours));
            }
        }
        Ok(())
    }

    /// Draw `chart` to `file` (`key` its rows in [`PAPER_VALUES`], `data`
    /// its CSV, if any, and `runs` the run directories behind it, which
    /// must exist), recorded for the report. Two-panel charts are taller.
    fn plot(
        &mut self,
        key: &str,
        file: &str,
        data: &str,
        runs: &[&str],
        mut chart: Chart,
    ) -> Result<()> {
        for r in runs {
            if !self.out.join("runs").join(r).join("history.csv").is_file() {
                return Err(ReproduceError::Data(format!(
                    "{file}: its run `runs/{r}` was not saved"
                )));
            }
        }
        let stem = key;
        let drawn = self
            .paper
            .iter()
            .any(|v| v.figure == stem && matches!(v.kind.as_str(), "vline" | "point"));
        if drawn {
            chart
                .notes
                .push("Black: values in the paper's text (paper_values.csv).".into());
        }
        chart.notes.extend(self.paper_notes(stem, &["none"]));
        let height = if chart.lower.is_some() { 820 } else { 620 };
        line_chart(&self.out.join(file), &chart, 1200, height)?;
        self.figures.push(Figure {
            key: key.into(),
            file: file.into(),
            data: data.into(),
            runs: runs.iter().map(|r| r.to_string()).collect(),
        });
        Ok(())
    }
}

/// Run everything into `out`; returns the path of `report.md`.
pub fn reproduce(out: &Path, quiet: bool) -> Result<PathBuf> {
    std::fs::create_dir_all(out.join("runs"))?;
    let t0 = Instant::now();
    let mut job = Job {
        out: out.to_path_buf(),
        quiet,
        warnings: Default::default(),
        report: String::new(),
        paper: paper_values().map_err(ReproduceError::Data)?,
        figures: Vec::new(),
    };
    std::fs::write(out.join("paper_values.csv"), PAPER_VALUES)?;
    let _ = writeln!(
        job.report,
        "# efgdem reproduce — Wang et al. (2020), §4\n\nGenerated by `efgdem reproduce` (efgdem {}). \
         Every run's `history.csv` and `summary.json` are under `runs/`; the figure data are the `fig*.csv` files \
         next to the PNGs. \"Ours\" on a figure is one of our runs, named by its parameters; \"paper\" is a value \
         the paper's text gives, drawn in black, each listed with its section and line in `paper_values.csv`. \
         The paper's figures themselves are not available to us: no value is read off them.\n",
        env!("CARGO_PKG_VERSION")
    );
    if !quiet {
        eprintln!("Example 1 — disc on a cantilever (§4.1)");
    }
    example1(&mut job)?;
    if !quiet {
        eprintln!("Example 2 — nine discs against a deformable plate (§4.2)");
    }
    example2(&mut job)?;
    figures_section(&mut job);
    for (w, n) in &job.warnings {
        eprintln!("warning ({n} of the runs): {w}");
    }
    let _ = writeln!(
        job.report,
        "\nTotal wall time of `efgdem reproduce`: {:.2} s.",
        t0.elapsed().as_secs_f64()
    );
    let path = out.join("report.md");
    std::fs::write(&path, &job.report)?;
    Ok(path)
}

/// The report's list of figures: data, runs, and the paper's values each
/// shows or does not have.
fn figures_section(job: &mut Job) {
    let _ = writeln!(
        job.report,
        "\n## Figures, their runs and the paper's values\n\n\
         | figure | data | runs (under `runs/`) | paper values drawn (black) | the paper's set-up it follows | what the paper does not give |\n|---|---|---|---|---|---|"
    );
    job.figures.sort_by(|a, b| a.key.cmp(&b.key));
    for f in &job.figures {
        let rows = |kinds: &[&str]| -> Vec<&PaperValue> {
            job.paper
                .iter()
                .filter(|v| v.figure == f.key && kinds.contains(&v.kind.as_str()))
                .collect()
        };
        let cite = |v: &PaperValue| {
            let what = match (v.kind.as_str(), v.x_unit.as_str()) {
                ("point", _) => {
                    format!("{} = {} at {}", v.y_unit_name(), v.y, at_x(v.x, &v.x_unit))
                }
                ("vline", _) => at_x(v.x, &v.x_unit),
                _ => v.label.trim_start_matches("paper: ").to_string(),
            };
            let tag = match v.kind.as_str() {
                "vline" | "point" if !v.tag.is_empty() => format!(" {}", v.tag),
                _ => String::new(),
            };
            format!("{what}{tag} ({})", v.source)
        };
        let list = |vs: Vec<&PaperValue>, f: &dyn Fn(&PaperValue) -> String| {
            if vs.is_empty() {
                "—".to_string()
            } else {
                vs.into_iter().map(f).collect::<Vec<_>>().join("; ")
            }
        };
        let _ = writeln!(
            job.report,
            "| `{}` | {} | {} | {} | {} | {} |",
            f.file,
            if f.data.is_empty() {
                "its runs' `history.csv`".into()
            } else {
                format!("`{}`", f.data)
            },
            f.runs
                .iter()
                .map(|r| format!("`{r}`"))
                .collect::<Vec<_>>()
                .join(", "),
            list(rows(&["vline", "point"]), &cite),
            list(rows(&["time", "setting"]), &cite),
            list(rows(&["none"]), &|v| v.label.clone()),
        );
    }
}

/// `t = 0.1431 s`, `cycle 40`, `0.3 m`.
fn at_x(x: Option<f64>, unit: &str) -> String {
    match unit {
        "s" => format!("t = {} s", short(x)),
        "cycle" => format!("cycle {}", short(x)),
        u => format!("{} {u}", short(x)),
    }
}

impl PaperValue {
    /// The quantity a `point` row gives (for the report).
    fn y_unit_name(&self) -> &str {
        match self.y_unit.as_str() {
            "N" => "F",
            _ => "y",
        }
    }
}

fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("—".into(), |x| format!("{x:.digits$}"))
}

/// A value as the paper writes it (shortest form: 0.1431, 40, 2.1e14).
fn short(v: Option<f64>) -> String {
    v.map_or("—".into(), |x| {
        if x != 0.0 && !(1e-3..1e6).contains(&x.abs()) {
            format!("{x:e}")
        } else {
            format!("{x}")
        }
    })
}

fn num(s: &Value, key: &str) -> Option<f64> {
    s.get(key).and_then(Value::as_f64)
}

/// First time the series reaches `level` (linear interpolation).
fn first_crossing(t: &[f64], y: &[f64], level: f64) -> Option<f64> {
    (1..t.len()).find_map(|k| {
        (y[k - 1] < level && y[k] >= level)
            .then(|| t[k - 1] + (t[k] - t[k - 1]) * (level - y[k - 1]) / (y[k] - y[k - 1]))
    })
}

/// Largest value of `y` and its `t` (the first if repeated).
fn peak(t: &[f64], y: &[f64]) -> (f64, f64) {
    t.iter()
        .zip(y)
        .fold((f64::NEG_INFINITY, 0.0), |(best, at), (&t, &v)| {
            if v > best { (v, t) } else { (best, at) }
        })
}

/// Largest |y| of a curve.
fn max_abs(pts: &[(f64, f64)]) -> f64 {
    pts.iter().fold(0.0, |a, p| a.max(p.1.abs()))
}

/// Example 1's Newmark labels.
const NM_PAPER: &str = "Newmark γ = 1.5, β = 0.8";
const NM_AVG: &str = "Newmark γ = ½, β = ¼";

fn example1(job: &mut Job) -> Result<()> {
    let base = parse(EXAMPLE1, "examples/paper_cantilever_disc.toml (built in)")?;
    type Edit = fn(&mut Scenario);
    // name, what it is (for the report and the legends)
    let variants: [(&str, &str, Edit); 5] = [
        (
            "ex1_newmark_1.5_0.8",
            "Newmark γ = 1.5, β = 0.8 (the paper's), μ = 0.5",
            |_| {},
        ),
        (
            "ex1_newmark_0.5_0.25",
            "Newmark γ = ½, β = ¼ (average acceleration), μ = 0.5",
            |s| {
                s.body[0].newmark.gamma = 0.5;
                s.body[0].newmark.beta = 0.25;
            },
        ),
        ("ex1_friction_0.3", "γ = 1.5, β = 0.8, μ = 0.3", |s| {
            s.material[0].friction = 0.3
        }),
        (
            "ex1_no_slide",
            "γ = 1.5, β = 0.8, no sliding (μ = 10⁶)",
            |s| s.material[0].friction = 1e6,
        ),
        (
            "ex1_thin_disc",
            "γ = 1.5, β = 0.8, μ = 0.5, disc 0.025 m thick",
            |s| {
                if let Some(g) = s.granular.as_mut() {
                    g.thickness = 0.025
                }
            },
        ),
    ];
    let mut runs = Vec::new();
    for (name, label, edit) in variants {
        let mut sc = base.clone();
        edit(&mut sc);
        // every step: the figures show what the report quotes (peaks
        // between recorded steps would be lost)
        sc.output.every = 1;
        let mass = coupled(&sc)?.granular.particles.mass[0];
        let done = job.run(name, &sc)?;
        runs.push((name, label, sc, mass, done));
    }
    // table
    let r = &mut job.report;
    let _ = writeln!(
        r,
        "## Example 1 — disc on a cantilever (§4.1)\n\n\
         Beam 1 × 0.2 m (t = 0.025 m, E = 2.1e8 Pa, ν = 0.3, ρ = 2000 kg/m³, 20 × 4 nodes), disc r = 0.05 m \
         (ρ = 1000 kg/m³, unit thickness: m = 7.854 kg), k_n = k_s = 1e6 N/m, undamped, Δt = 1e-4 s. \
         Every run records its history at every step; the peak force and the crossings below are read \
         from `history.csv`, the data of Figs. 9 and 12 (the peak is also checked against `summary.json`).\n\n\
         The paper's fall-off (0.1431 s) has three readings, all reported: **(a)** §4.1.2, the centre's \
         projection on the boundary leaves the top edge — the contact point reaches the beam's corner \
         (`fall_off_time` in `summary.json`); **(b)** the centre's x passes the corner's current x \
         (vertical projection); **(c)** §4.1.4, the contact force drops below m g after its peak \
         (`force_below_weight_time`).\n\n\
         | run (ours) | F = m g at (s) | peak force (N) | peak at (s) | fall-off (a) (s) | (b) (s) | (c) (s) | µs / step |\n\
         |---|---|---|---|---|---|---|---|\n\
         | paper (§4.1.2, §4.1.4 text) | 0.05 | — | 0.1 | 0.1431 | 0.1431 | 0.143 | — |"
    );
    for (name, label, sc, mass, d) in &runs {
        let t = d.history.col("t")?;
        let f = d.history.col("contact_fn")?;
        let mg = mass * 9.81;
        // (b): disc centre x − corner x, from the probes
        let x0 = match sc.granular.as_ref().map(|g| &g.discs) {
            Some(crate::scenario::granular::DiscsSpec::Inline(v)) if !v.is_empty() => v[0][0],
            _ => 1.0,
        };
        let gap: Vec<f64> = d
            .history
            .col("disc_ux")?
            .iter()
            .zip(d.history.col("tip_ux")?)
            .map(|(du, tu)| x0 + du - (1.0 + tu))
            .collect();
        let s = &d.summary;
        let (fmax, tmax) = peak(&t, &f);
        // the history has every step: its peak is the summary's
        if let Some(sp) = num(s, "peak_contact_force")
            && (sp - fmax).abs() > 1e-9 * sp.abs()
        {
            return Err(ReproduceError::Data(format!(
                "{name}: peak force {fmax} in history.csv, {sp} in summary.json"
            )));
        }
        let us = num(&s["timing"], "seconds_per_step").map(|x| x * 1e6);
        let _ = writeln!(
            r,
            "| `{name}`: {label} | {} | {fmax:.2} | {tmax:.4} | {} | {} | {} | {} |",
            fmt_opt(first_crossing(&t, &f, mg), 4),
            fmt_opt(num(s, "fall_off_time"), 4),
            fmt_opt(first_crossing(&t, &gap, 0.0), 4),
            fmt_opt(num(s, "force_below_weight_time"), 4),
            fmt_opt(us, 1),
        );
    }
    // energy check of the two Newmark variants
    let _ = writeln!(
        r,
        "\nEnergy account (J): largest |E_diss| over the run against the largest external work \
         (gravity on the disc). γ = 1/2, β = 1/4 conserves energy; the paper's γ = 1.5, β = 0.8 \
         dissipates.\n\n| run | max W_ext | max abs(E_diss) | ratio | E_diss at the end |\n|---|---|---|---|---|"
    );
    for (name, _, _, _, d) in &runs[..2] {
        let w = d
            .history
            .col("W_ext")?
            .iter()
            .fold(0.0f64, |a, x| a.max(x.abs()));
        let diss = d.history.col("E_diss")?;
        let dmax = diss.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let _ = writeln!(
            r,
            "| `{name}` | {w:.4e} | {dmax:.4e} | {:.2e} | {:.4e} |",
            dmax / w,
            diss.last().copied().unwrap_or(0.0)
        );
    }
    let names: Vec<&str> = runs.iter().map(|r| r.0).collect();
    fig09(
        job,
        &runs[0].4,
        &runs[1].4,
        runs[0].2.material[0].kn,
        &names[..2],
    )?;
    // Fig. 12: contact force of the four full-disc runs, deviations from
    // the paper's Newmark parameters below
    let mg = runs[0].3 * 9.81;
    let reference = runs[0].4.history.xy("t", "contact_fn", 1.0)?;
    let t_end = reference.last().map_or(0.2, |p| p.0);
    let mut series = Vec::new();
    let mut lower = Vec::new();
    for (i, (_, label, _, _, d)) in runs[..4].iter().enumerate() {
        let f = d.history.xy("t", "contact_fn", 1.0)?;
        if i > 0 {
            let dev = difference(&f, &reference, 1.0)?;
            let what = label
                .trim_start_matches("Newmark ")
                .replace(" (average acceleration)", "")
                .replace("γ = 1.5, β = 0.8, ", "")
                .replace(", μ = 0.5", "");
            let big = max_abs(&dev);
            let size = if big < 5e-3 {
                format!("largest {big:.1e} N: the same curve")
            } else {
                format!("largest {big:.2} N")
            };
            lower.push(
                Series::new(format!("ΔF, {what} ({size})"), dev, Mark::Line).with_color(palette(i)),
            );
        }
        series.push(Series::new(format!("ours, {label}"), f, Mark::Line).with_color(palette(i)));
    }
    let (fmax, tmax) = peak(
        &reference.iter().map(|p| p.0).collect::<Vec<_>>(),
        &reference.iter().map(|p| p.1).collect::<Vec<_>>(),
    );
    series.push(
        Series::new(
            format!("ours, γ = 1.5, β = 0.8, μ = 0.5: peak {fmax:.2} N at {tmax:.4} s"),
            vec![(tmax, fmax)],
            Mark::Points,
        )
        .with_color(palette(0)),
    );
    series.push(
        Series::new(
            format!("m g = {mg:.2} N (our disc, {:.3} kg)", runs[0].3),
            vec![(0.0, mg), (t_end, mg)],
            Mark::Dashed,
        )
        .with_color(REFERENCE_COLOR),
    );
    series.extend(job.paper_series("fig12", Some(mg))?);
    job.plot(
        "fig12",
        "fig12_contact_force.png",
        "",
        &names[..4],
        Chart {
            title: "Fig. 12 — disc–beam contact force".into(),
            x_label: "t (s)".into(),
            y_label: "normal contact force (N)".into(),
            series,
            lower: Some(Panel {
                y_label: "ΔF (N)".into(),
                series: lower,
                y_range: None,
            }),
            notes: vec![
                "Lower panel: ΔF = each run minus ours with the paper's Newmark γ = 1.5, β = 0.8 and μ = 0.5 (the curves above differ by a few N and hide each other).".into(),
            ],
            ..Default::default()
        },
    )?;
    let thin = &runs[4];
    let mg_thin = thin.3 * 9.81;
    let f_thin = thin.4.history.xy("t", "contact_fn", 1.0)?;
    let (pk, tpk) = peak(
        &f_thin.iter().map(|p| p.0).collect::<Vec<_>>(),
        &f_thin.iter().map(|p| p.1).collect::<Vec<_>>(),
    );
    job.plot(
        "fig12_thin_disc",
        "fig12_thin_disc.png",
        "",
        &names[4..5],
        Chart {
            title: "Not in the paper — contact force with the disc as thick as the beam (0.025 m)"
                .into(),
            x_label: "t (s)".into(),
            y_label: "normal contact force (N)".into(),
            series: vec![
                Series::new(format!("ours, {}", thin.1), f_thin, Mark::Line),
                Series::new(
                    format!("ours: peak {pk:.2} N at {tpk:.4} s"),
                    vec![(tpk, pk)],
                    Mark::Points,
                )
                .with_color(palette(0)),
                Series::new(
                    format!("m g = {mg_thin:.3} N (disc {:.4} kg)", thin.3),
                    vec![(0.0, mg_thin), (t_end, mg_thin)],
                    Mark::Dashed,
                )
                .with_color(REFERENCE_COLOR),
            ],
            notes: vec!["History recorded at every step (the peak is the report's).".into()],
            ..Default::default()
        },
    )?;
    figs_10_11(job, &runs[0].2, runs[0].3, &runs[0].4, names[0])?;
    let _ = writeln!(
        job.report,
        "\nPlots: `fig09_displacements.png`, `fig10_axial_stress.png`, `fig11_deflection.png`, \
         `fig12_contact_force.png`, `fig12_thin_disc.png`. Runs: {}.",
        runs.iter()
            .map(|r| format!(
                "`{}`",
                r.4.dir.strip_prefix(&job.out).unwrap_or(&r.4.dir).display()
            ))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// Fig. 9: vertical displacement of the beam end and of the disc centre
/// for both Newmark variants; below, disc centre minus beam end (the
/// paper's fall-off criterion, §4.1.2) and the two beam ends' difference;
/// `kn` is the contact stiffness (for the overlap the note quotes).
fn fig09(job: &mut Job, paper: &Done, avg: &Done, kn: f64, names: &[&str]) -> Result<()> {
    let mm = |d: &Done, c: &str| d.history.xy("t", c, 1e3);
    let um = |d: &Done| -> Result<Vec<(f64, f64)>> {
        difference(
            &d.history.xy("t", "disc_uy", 1.0)?,
            &d.history.xy("t", "tip_uy", 1.0)?,
            1e6,
        )
    };
    let (gap_p, gap_a) = (um(paper)?, um(avg)?);
    let tips = difference(
        &avg.history.xy("t", "tip_uy", 1.0)?,
        &paper.history.xy("t", "tip_uy", 1.0)?,
        1e6,
    )?;
    let mut series = vec![
        Series::new(
            format!("ours, {NM_PAPER}: beam end"),
            mm(paper, "tip_uy")?,
            Mark::Line,
        )
        .with_color(palette(0)),
        Series::new(
            format!("ours, {NM_PAPER}: disc centre"),
            mm(paper, "disc_uy")?,
            Mark::Dashed,
        )
        .with_color(palette(1)),
        Series::new(
            format!("ours, {NM_AVG}: beam end"),
            mm(avg, "tip_uy")?,
            Mark::Line,
        )
        .with_color(palette(2)),
        Series::new(
            format!("ours, {NM_AVG}: disc centre"),
            mm(avg, "disc_uy")?,
            Mark::Dashed,
        )
        .with_color(palette(3)),
    ];
    series.extend(job.paper_series("fig09", None)?);
    let f = paper.history.col("contact_fn")?;
    let notes = vec![
        format!(
            "The four curves above differ by at most {:.0} µm (< 1 % of the deflection): the lower panel shows the differences.",
            max_abs(&gap_p).max(max_abs(&gap_a)).max(max_abs(&tips))
        ),
        format!(
            "Ours: the disc stays on the beam to t = {:.2} s (contact force {:.1} N at the end); disc centre − beam end includes the contact overlap F/k_n (≤ {:.0} µm). Fall-off readings: report.md.",
            paper.history.col("t")?.last().copied().unwrap_or(0.0),
            f.last().copied().unwrap_or(0.0),
            f.iter().fold(0.0f64, |a, &b| a.max(b)) / kn * 1e6,
        ),
    ];
    job.plot(
        "fig09",
        "fig09_displacements.png",
        "",
        names,
        Chart {
            title: "Fig. 9 — vertical displacement of the beam end and the disc centre".into(),
            x_label: "t (s)".into(),
            y_label: "u_y (mm)".into(),
            series,
            lower: Some(Panel {
                y_label: "difference (µm)".into(),
                series: vec![
                    Series::new(
                        format!("disc centre − beam end, {NM_PAPER}"),
                        gap_p,
                        Mark::Line,
                    )
                    .with_color(palette(1)),
                    Series::new(
                        format!("disc centre − beam end, {NM_AVG}"),
                        gap_a,
                        Mark::Line,
                    )
                    .with_color(palette(3)),
                    Series::new(
                        "beam end: (γ = ½, β = ¼) − (γ = 1.5, β = 0.8)".to_string(),
                        tips,
                        Mark::Dashed,
                    )
                    .with_color(palette(2)),
                ],
                y_range: None,
            }),
            notes,
            ..Default::default()
        },
    )
}

/// Figs. 10 and 11: axial stress across two sections and the deflection
/// profile at t = T/4 (the contact force first equals m g: the disc's
/// acceleration is zero, §4.1.3–4.1.4), against Eqs. (64)–(65) with P the
/// instantaneous contact force (ERRATA E13: I = t H³/12). The state is the
/// run `name`'s (`done`) at that step, re-stepped in memory to sample the
/// fields; its contact force is checked against the run's `history.csv`.
fn figs_10_11(job: &mut Job, sc: &Scenario, mass: f64, done: &Done, name: &str) -> Result<()> {
    let mg = mass * 9.81;
    let steps_col = done.history.col("step")?;
    let f_col = done.history.col("contact_fn")?;
    let k = steps_col
        .iter()
        .zip(&f_col)
        .find(|(_, f)| **f >= mg)
        .map(|(s, _)| *s as usize)
        .ok_or_else(|| ReproduceError::Data("contact force never reached m g".into()))?;
    let mut m = coupled(sc)?;
    for _ in 0..k {
        m.step()?;
    }
    let p: f64 = m.contacts.iter().map(|c| c.fn_elastic).sum();
    let i_fn = done
        .history
        .cols
        .iter()
        .position(|c| c == "contact_fn")
        .unwrap_or(0);
    let p_hist = done.history.at_step(k)?[i_fn];
    if (p - p_hist).abs() > 1e-9 * p_hist.abs() {
        return Err(ReproduceError::Data(format!(
            "Figs. 10–11: the re-stepped state has F = {p} N at step {k}, runs/{name}/history.csv {p_hist} N"
        )));
    }
    let t = m.granular.time;
    let beam = &m.bodies[0]
        .as_any()
        .downcast_ref::<EfgContinuum>()
        .ok_or_else(|| ReproduceError::Data("Example 1 body is not EFG".into()))?
        .body;
    let spec = &sc.body[0];
    let (l, h, th, e) = (
        spec.rectangle.size[0],
        spec.rectangle.size[1],
        spec.elastic.thickness,
        spec.elastic.e,
    );
    let y0 = spec.rectangle.origin[1] + 0.5 * h;
    let inertia = th * h * h * h / 12.0;
    // the load acts per unit thickness in the 2D model: σ from P/t
    let sigma_exact = |x: f64, y: f64| p * (l - x) * (y - y0) / inertia;
    let w_exact = |x: f64| p * x * x * (3.0 * l - x) / (6.0 * e * inertia);
    // the sections the paper names (§4.1.3)
    let sections: Vec<(f64, String)> = job
        .paper
        .iter()
        .filter(|v| v.figure == "fig10" && v.kind == "setting")
        .filter_map(|v| v.x.map(|x| (x, v.tag.clone())))
        .collect();
    if sections.len() != 2 {
        return Err(ReproduceError::Data(
            "paper_values.csv: Fig. 10 needs two sections".into(),
        ));
    }
    let (xa, xb) = (sections[0].0, sections[1].0);
    let mut csv = HistoryWriter::create(
        &job.out.join("fig10_axial_stress.csv"),
        &[
            "y",
            &format!("sigma11_x{xa}"),
            &format!("eq64_x{xa}"),
            &format!("sigma11_x{xb}"),
            &format!("eq64_x{xb}"),
        ],
    )?;
    let mut s = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
    let mut worst10: f64 = 0.0;
    let peak_sigma = sigma_exact(xa, y0 + 0.5 * h).abs();
    for k in 0..=20 {
        let y = y0 - 0.5 * h + h * k as f64 / 20.0;
        let mut row = vec![y - y0];
        for (i, &(x, _)) in sections.iter().enumerate() {
            let sig = beam.sample(Vec2::new(x, y))?.stress[0];
            let ex = sigma_exact(x, y);
            worst10 = worst10.max((sig - ex).abs() / peak_sigma);
            s[2 * i].push(((y - y0) * 1e3, sig / 1e3));
            s[2 * i + 1].push(((y - y0) * 1e3, ex / 1e3));
            row.extend([sig, ex]);
        }
        csv.row(&row)?;
    }
    csv.flush()?;
    let [s_a, e_a, s_b, e_b] = s;
    let mut notes = vec![format!(
        "Ours: the run's state at step {k}, the first with F ≥ m g (disc acceleration ≈ 0)."
    )];
    notes.extend(job.paper_notes("fig10", &["time", "setting"]));
    let sec = |i: usize| format!("section {}, x = {} m", sections[i].1, sections[i].0);
    job.plot(
        "fig10",
        "fig10_axial_stress.png",
        "fig10_axial_stress.csv",
        &[name],
        Chart {
            title: format!("Fig. 10 — σ₁₁ across the beam at t = {t:.4} s (P = {p:.2} N)"),
            x_label: "y (mm from the beam's axis)".into(),
            y_label: "σ₁₁ (kPa)".into(),
            series: vec![
                Series::new(format!("ours, {NM_PAPER}, {}", sec(0)), s_a, Mark::Points)
                    .with_color(palette(0)),
                Series::new(
                    format!("Eq. (64), P = {p:.2} N, {}", sec(0)),
                    e_a,
                    Mark::Dashed,
                )
                .with_color(palette(0)),
                Series::new(format!("ours, {NM_PAPER}, {}", sec(1)), s_b, Mark::Points)
                    .with_color(palette(1)),
                Series::new(
                    format!("Eq. (64), P = {p:.2} N, {}", sec(1)),
                    e_b,
                    Mark::Dashed,
                )
                .with_color(palette(1)),
            ],
            notes: notes.clone(),
            ..Default::default()
        },
    )?;
    let mut csv =
        HistoryWriter::create(&job.out.join("fig11_deflection.csv"), &["x", "w", "eq65"])?;
    let (mut sim, mut ex) = (Vec::new(), Vec::new());
    let tip = w_exact(l);
    let mut worst11: f64 = 0.0;
    for k in 0..=20 {
        let x = l * k as f64 / 20.0;
        let w = -beam.sample(Vec2::new(x, y0))?.u.y;
        let we = w_exact(x);
        worst11 = worst11.max((w - we).abs() / tip);
        sim.push((x, w * 1e3));
        ex.push((x, we * 1e3));
        csv.row(&[x, w, we])?;
    }
    csv.flush()?;
    let mut notes11 = vec![notes[0].clone()];
    notes11.extend(job.paper_notes("fig11", &["time", "setting"]));
    job.plot(
        "fig11",
        "fig11_deflection.png",
        "fig11_deflection.csv",
        &[name],
        Chart {
            title: format!(
                "Fig. 11 — deflection of the beam's axis at t = {t:.4} s (P = {p:.2} N)"
            ),
            x_label: "x (m)".into(),
            y_label: "w (mm, downward)".into(),
            series: vec![
                Series::new(format!("ours, {NM_PAPER}"), sim, Mark::Points),
                Series::new(format!("Eq. (65), P = {p:.2} N"), ex, Mark::Dashed),
            ],
            notes: notes11,
            ..Default::default()
        },
    )?;
    let _ = writeln!(
        job.report,
        "\n### Figs. 10–11 at t = T/4\n\nT/4 is taken where the contact force first equals m g \
         (zero disc acceleration, §4.1.3–4.1.4): step {k} of `runs/{name}`, the first with F ≥ m g \
         in its `history.csv`, t = {t:.4} s (the crossing interpolates to {} s; paper: 0.05 s), \
         P = {p:.2} N. Against Euler–Bernoulli with that P at the beam end (Eqs. 64–65, E13): \
         σ₁₁ at x = {xa} and {xb} m within {:.1} % of the peak Eq.-(64) stress at x = {xa} m; \
         deflection within {:.1} % of the Eq.-(65) tip value. The beam is vibrating (the \
         comparison is with a static formula, as in the paper), so these are not \
         discretisation errors. The paper gives no stress or deflection values to compare with.",
        fmt_opt(first_crossing(&done.history.col("t")?, &f_col, mg), 4),
        100.0 * worst10,
        100.0 * worst11
    );
    Ok(())
}

fn example2(job: &mut Job) -> Result<()> {
    let _ = writeln!(
        job.report,
        "\n## Example 2 — nine discs against a deformable plate (§4.2)\n\n\
         Cundall & Strack's nine-disc test (k_n = k_s = 1.35e9, μ = 0.5, normal dashpot β = 0.1, Coulomb cap on the \
         total normal force k_n δ + c_n δ̇ as Eqs. 35 and 37 (`slip_normal = \"total\"`; PFC's `\"elastic\"` caps with k_n δ), \
         Δt = 0.01525, 150 cycles), left plate an EFG strip 50 × 300 (3 × 11 nodes, ν = 0.3, ρ = 2000, undamped) whose top and \
         bottom edges follow the rigid left plate. Force at contact C (discs 4–5), elastic part k_n δ, in the paper's \
         \"standard units\" (no physical unit). The deviations are from our rigid-plate (DEM) run at the same cycle, \
         as in the lower panels of Figs. 14 and 15.\n"
    );
    let mut table = String::from(
        "| test | plate (ours) | F_C at cycle 40 | F_C at cycle 150 | max abs(F_C − F_rigid) after cycle 20 | relative | wall time (s) |\n|---|---|---|---|---|---|---|\n",
    );
    let scale = 1e-7; // force axis: ×10⁷ units
    let dscale = 1e-5; // deviation axis: ×10⁵ units
    for t in 0..2 {
        let tn = t + 1;
        let rigid_sc = parse(
            NINE_DISC_RIGID[t],
            &format!("examples/nine_disc_rigid_test{tn}.toml (built in)"),
        )?;
        let rigid_name = format!("nine_disc_rigid_test{tn}");
        let rigid = job.run(&rigid_name, &rigid_sc)?;
        let rc = rigid.history.col("force_C")?;
        let rcycle = rigid.history.col("step")?;
        let at = |cyc: &[f64], f: &[f64], c: f64| cyc.iter().position(|&x| x == c).map(|i| f[i]);
        let _ = writeln!(
            table,
            "| {tn} | rigid (DEM) | {} | {} | — | — | {} |",
            fmt_opt(at(&rcycle, &rc, 40.0), 0),
            fmt_opt(at(&rcycle, &rc, 150.0), 0),
            fmt_opt(num(&rigid.summary["timing"], "loop_seconds"), 3),
        );
        let efg_sc = parse(
            NINE_DISC_EFG[t],
            &format!("examples/paper_nine_disc_test{tn}.toml (built in)"),
        )?;
        // one table row per plate run: force at cycles 40 and 150, largest
        // deviation from the rigid run after cycle 20, wall time
        let mut row = |label: &str, d: &Done| -> Result<()> {
            let f = d.history.col("force_C")?;
            let c = d.history.col("step")?;
            let (abs, rel) = c
                .iter()
                .zip(&f)
                .filter(|(c, _)| **c > 20.0)
                .filter_map(|(&cy, &fv)| {
                    at(&rcycle, &rc, cy).map(|fr| ((fv - fr).abs(), (fv - fr).abs() / fr))
                })
                .fold((0.0, 0.0), |(a, r), (x, y)| {
                    (f64::max(a, x), f64::max(r, y))
                });
            let secs = num(&d.summary["timing"], "loop_seconds")
                .zip(num(&d.summary["timing"], "build_seconds"))
                .map(|(a, b)| a + b);
            let _ = writeln!(
                table,
                "| {tn} | {label} | {} | {} | {abs:.3e} | {:.3} % | {} |",
                fmt_opt(at(&c, &f, 40.0), 0),
                fmt_opt(at(&c, &f, 150.0), 0),
                100.0 * rel,
                fmt_opt(secs, 3),
            );
            Ok(())
        };
        let mut sweep = Vec::new();
        for &e in &E_SWEEP {
            let mut sc = efg_sc.clone();
            sc.body[0].elastic.e = e;
            let name = format!("nine_disc_efg_test{tn}_E{e:.1e}");
            let d = job.run(&name, &sc)?;
            row(&format!("EFG, E = {e:.1e}"), &d)?;
            sweep.push((e, name, d));
        }
        // the FE–DE cross-check of §4.2.1: Q4 plate on the same grid
        let fem_sc = parse(
            NINE_DISC_FEM[t],
            &format!("examples/fem_nine_disc_test{tn}.toml (built in)"),
        )?;
        for key in [format!("fig14_test{tn}"), format!("fig15_test{tn}")] {
            for sc in [&rigid_sc, &efg_sc, &fem_sc] {
                job.check_setup(&key, sc)?;
            }
        }
        let fem_name = format!("nine_disc_fem_test{tn}");
        let fem = job.run(&fem_name, &fem_sc)?;
        row("FE (Q4), E = 2.1e14", &fem)?;
        let rigid_f = rigid.history.xy("step", "force_C", 1.0)?;
        let dev = |d: &Done| difference(&d.history.xy("step", "force_C", 1.0)?, &rigid_f, dscale);
        let force_label = "normal force at C (×10⁷ units)";
        let dev_label = "F − F_rigid (×10⁵ units)";
        let cycle_label = "cycle (time step, Δt = 0.01525 units)";
        let rigid_series = |color| {
            Ok::<_, ReproduceError>(
                Series::new(
                    "ours, DEM, rigid plates",
                    rigid.history.xy("step", "force_C", scale)?,
                    Mark::Dashed,
                )
                .with_color(color),
            )
        };
        // Fig. 14: EFG (E = 2.1e14) and FE against rigid plates
        let fig = format!("fig14_test{tn}");
        let efg_dev = dev(&sweep[0].2)?;
        let fem_dev = dev(&fem)?;
        let mut series = vec![
            Series::new(
                "ours, EFG–DE plate, E = 2.1e14 units",
                sweep[0].2.history.xy("step", "force_C", scale)?,
                Mark::Line,
            )
            .with_color(palette(0)),
            Series::new(
                "ours, FE–DE plate (Q4), E = 2.1e14 units",
                fem.history.xy("step", "force_C", scale)?,
                Mark::Line,
            )
            .with_color(palette(1)),
            rigid_series(palette(2))?,
        ];
        series.extend(job.paper_series(&fig, None)?);
        job.plot(
            &fig,
            &format!("{fig}.png"),
            &format!("fig14_15_test{tn}.csv"),
            &[&sweep[0].1, &fem_name, &rigid_name],
            Chart {
                title: format!("Fig. 14 — normal force at contact C, Test {tn}"),
                x_label: cycle_label.into(),
                y_label: force_label.into(),
                series,
                lower: Some(Panel {
                    y_label: dev_label.into(),
                    series: vec![
                        Series::new("EFG–DE − rigid", efg_dev.clone(), Mark::Line)
                            .with_color(palette(0)),
                        Series::new("FE–DE − rigid", fem_dev.clone(), Mark::Line)
                            .with_color(palette(1)),
                    ],
                    y_range: None,
                }),
                notes: std::iter::once(format!(
                    "Lower panel: difference from our rigid-plate DEM run; the curves above differ by at most {:.2} % after cycle 20 and hide each other.",
                    100.0 * [&efg_dev, &fem_dev]
                        .iter()
                        .flat_map(|d| d.iter().zip(&rigid_f))
                        .filter(|(p, _)| p.0 > 20.0)
                        .map(|(p, r)| (p.1 / dscale).abs() / r.1)
                        .fold(0.0, f64::max)
                ))
                .chain(job.paper_notes(&fig, &["setting"]))
                .collect(),
                ..Default::default()
            },
        )?;
        // Fig. 15: the modulus sweep, rigid plates as reference
        let fig = format!("fig15_test{tn}");
        let mut series: Vec<Series> = sweep
            .iter()
            .enumerate()
            .map(|(i, (e, _, d))| {
                Ok(Series::new(
                    format!("ours, EFG–DE plate, E = {e:.1e} units"),
                    d.history.xy("step", "force_C", scale)?,
                    Mark::Line,
                )
                .with_color(palette(i)))
            })
            .collect::<Result<_>>()?;
        series.push(rigid_series(REFERENCE_COLOR)?);
        series.extend(job.paper_series(&fig, None)?);
        let mut lower = Vec::new();
        let mut off_scale = Vec::new();
        for (i, (e, _, d)) in sweep.iter().enumerate() {
            let dv = dev(d)?;
            // the soft plates' deviation is two orders larger: it would
            // flatten the others; it is plain in the upper panel
            if *e < 1e12 {
                off_scale.push(format!(
                    "E = {e:.1e} is left out of the lower panel: its largest |F − F_rigid| is {:.2e} units, plain above.",
                    max_abs(&dv) / dscale
                ));
                continue;
            }
            lower.push(
                Series::new(format!("E = {e:.1e} − rigid"), dv, Mark::Line).with_color(palette(i)),
            );
        }
        let mut notes = vec![
            "Lower panel: difference from our rigid-plate DEM run (dashed grey above).".to_string(),
        ];
        notes.extend(off_scale);
        notes.extend(job.paper_notes(&fig, &["setting"]));
        let mut runs: Vec<&str> = sweep.iter().map(|s| s.1.as_str()).collect();
        runs.push(&rigid_name);
        job.plot(
            &fig,
            &format!("{fig}.png"),
            &format!("fig14_15_test{tn}.csv"),
            &runs,
            Chart {
                title: format!(
                    "Fig. 15 — normal force at contact C against the plate's E, Test {tn}"
                ),
                x_label: cycle_label.into(),
                y_label: force_label.into(),
                series,
                lower: Some(Panel {
                    y_label: dev_label.into(),
                    series: lower,
                    y_range: None,
                }),
                notes,
                ..Default::default()
            },
        )?;
        // the data of Figs. 14–15 side by side
        let mut cols = vec!["cycle".to_string(), "rigid".to_string()];
        cols.extend(E_SWEEP.iter().map(|e| format!("efg_E{e:.1e}")));
        cols.push("fem_E2.1e14".to_string());
        let colrefs: Vec<&str> = cols.iter().map(String::as_str).collect();
        let mut csv =
            HistoryWriter::create(&job.out.join(format!("fig14_15_test{tn}.csv")), &colrefs)?;
        let fs: Vec<(Vec<f64>, Vec<f64>)> = sweep
            .iter()
            .map(|(_, _, d)| d)
            .chain(std::iter::once(&fem))
            .map(|d| Ok((d.history.col("step")?, d.history.col("force_C")?)))
            .collect::<Result<_>>()?;
        for (i, &cy) in rcycle.iter().enumerate() {
            let mut row = vec![cy, rc[i]];
            row.extend(fs.iter().map(|(c, f)| at(c, f, cy).unwrap_or(f64::NAN)));
            csv.row(&row)?;
        }
        csv.flush()?;
    }
    job.report.push_str(&table);
    fig17(job)?;
    Ok(())
}

/// Fig. 17: horizontal displacement of the plate's contact-edge nodes at
/// cycle 40 of Test 1 for E = 10¹²: a saved run whose probes record every
/// node's displacement at every cycle; the figure is its row of cycle 40.
fn fig17(job: &mut Job) -> Result<()> {
    let mut sc = parse(
        NINE_DISC_EFG[0],
        "examples/paper_nine_disc_test1.toml (built in)",
    )?;
    sc.body[0].elastic.e = E_FIG17;
    let cycle = job
        .paper
        .iter()
        .find(|v| v.figure == "fig17" && v.kind == "setting" && v.x_unit == "cycle")
        .and_then(|v| v.x)
        .ok_or_else(|| ReproduceError::Data("paper_values.csv: Fig. 17 has no cycle".into()))?
        as usize;
    // the plate's contact-edge nodes, as probes
    let (x_edge, ys, dt) = {
        let m = coupled(&sc)?;
        let plate = &m.bodies[0]
            .as_any()
            .downcast_ref::<EfgContinuum>()
            .ok_or_else(|| ReproduceError::Data("Example 2 body is not EFG".into()))?
            .body;
        (
            plate.origin.x + plate.size.x,
            plate.ys.clone(),
            m.granular.dt,
        )
    };
    let body = sc.body[0].name.clone();
    let probe_name = |j: usize| format!("edge_ux_{j:02}");
    for (j, &y) in ys.iter().enumerate() {
        sc.probe.push(Probe {
            name: probe_name(j),
            quantity: "ux".into(),
            point: Some([x_edge, y]),
            body: Some(body.clone()),
            contact: None,
            disc: None,
            wall: None,
            crack: None,
            tip: None,
        });
    }
    let name = format!("nine_disc_efg_test1_E{E_FIG17:.1e}");
    let done = job.run(&name, &sc)?;
    let row = done.history.at_step(cycle)?;
    let plate_disp = 0.12 * cycle as f64 * dt;
    let mut csv = HistoryWriter::create(
        &job.out.join("fig17_plate_displacement.csv"),
        &["y", "ux", "ux_edges"],
    )?;
    let mut pts = Vec::new();
    for (j, &y) in ys.iter().enumerate() {
        let i = done
            .history
            .cols
            .iter()
            .position(|c| *c == probe_name(j))
            .ok_or_else(|| ReproduceError::Data(format!("{name}: no probe {}", probe_name(j))))?;
        csv.row(&[y, row[i], plate_disp])?;
        pts.push((y, row[i]));
    }
    csv.flush()?;
    let (lo, hi) = (pts[0].1, pts[pts.len() / 2].1);
    let (umin, umax) = pts
        .iter()
        .map(|p| p.1)
        .chain([plate_disp])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let pad = 0.08 * (umax - umin);
    let yr = (umin - pad, umax + pad);
    let band = 100.0 * (yr.1 - yr.0) / yr.1;
    let mut notes = vec![
        format!(
            "y axis zoomed: {:.5} to {:.5} units, a band of {band:.1} % of the displacement; it does not start at 0.",
            yr.0, yr.1
        ),
        format!("Ours: row of cycle {cycle} of runs/{name}/history.csv (one probe per node)."),
    ];
    notes.extend(job.paper_notes("fig17", &["setting"]));
    job.plot(
        "fig17",
        "fig17_plate_displacement.png",
        "fig17_plate_displacement.csv",
        &[&name],
        Chart {
            title: format!(
                "Fig. 17 — plate's contact-edge nodes at cycle {cycle} (Test 1, E = {E_FIG17:.1e} units), y axis zoomed"
            ),
            x_label: "y of the node (units)".into(),
            y_label: format!("u_x (units; axis zoomed to a {band:.1} % band)"),
            series: vec![
                Series::new(
                    format!("ours, EFG–DE plate, E = {E_FIG17:.1e} units"),
                    pts.clone(),
                    Mark::Points,
                ),
                Series::new(
                    format!("prescribed at the top/bottom edges: 0.12 × {cycle} Δt = {plate_disp:.4} units"),
                    vec![(pts[0].0, plate_disp), (pts[pts.len() - 1].0, plate_disp)],
                    Mark::Dashed,
                )
                .with_color(REFERENCE_COLOR),
            ],
            y_range: Some(yr),
            notes,
            ..Default::default()
        },
    )?;
    let _ = writeln!(
        job.report,
        "\n### Fig. 17\n\nTest 1, E = 1e12, cycle {cycle} (run `runs/{name}`, one probe per contact-edge node, \
         figure from its `history.csv` row of cycle {cycle}): the contact-edge nodes move u_x = {lo:.4} at the \
         top/bottom edges (prescribed {plate_disp:.4}) and {hi:.4} at mid-height: the discs' reaction \
         bends the plate away from them, so the central nodes lag the ends by {:.1e}. The paper \
         (§4.2.3) describes the central nodes as displacing more than the ends, and gives no values; \
         with the top and bottom edges driven and the discs pushing back on the middle, a lagging \
         centre is what statics gives (data: `fig17_plate_displacement.csv`). The figure's y axis is \
         zoomed to {:.5}–{:.5} units ({band:.1} %).",
        lo - hi,
        yr.0,
        yr.1
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_fields_keep_quoted_commas_and_quotes() {
        assert_eq!(
            csv_fields(r#"a,"b, c","say ""x""",,"#),
            ["a", "b, c", r#"say "x""#, "", ""]
        );
    }

    #[test]
    fn paper_values_parse_with_a_source_each() {
        let v = paper_values().unwrap();
        assert!(v.len() > 20);
        for r in &v {
            assert!(
                ["vline", "point", "time", "setting", "none"].contains(&r.kind.as_str()),
                "{r:?}"
            );
            assert_eq!(r.kind != "none", r.x.is_some(), "{r:?}");
            assert!(!r.label.is_empty(), "{r:?}");
        }
    }

    #[test]
    fn a_scenario_unlike_the_papers_set_up_is_refused() {
        let job = Job {
            out: std::env::temp_dir(),
            quiet: true,
            warnings: Default::default(),
            report: String::new(),
            paper: paper_values().unwrap(),
            figures: Vec::new(),
        };
        let mut sc = parse(NINE_DISC_RIGID[0], "test1").unwrap();
        job.check_setup("fig14_test1", &sc).unwrap();
        // Test 2's set-up is not Test 1's
        assert!(job.check_setup("fig14_test2", &sc).is_err());
        sc.simulation.dt = Some(0.02);
        assert!(job.check_setup("fig14_test1", &sc).is_err());
    }
}
