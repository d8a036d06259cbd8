//! Post-processing of the biaxial test `examples/biaxial.toml`, and a sweep over the rolling friction μ_r
//! (manual: docs/tutorial/biaxial.md). Time: seconds for one run's
//! post-processing; `--run 0,0.1,0.3` runs the example three times (about
//! 4 minutes on 2 cores: slow).
//!
//! One run, already made with `efgdem run examples/biaxial.toml -o out/biaxial`:
//!
//!     cargo run --release --example biaxial_post -- examples/biaxial.toml out/biaxial
//!
//! writes into `out/biaxial`: `biaxial.csv` (ε₁, ε₃, ε_v, σ₁, σ₃, q, p,
//! sin φ and the whole sample's Love–Weber stress per row of the
//! shearing), `q.png`, `volumetric.png` and `biaxial.json` (peak and
//! critical-state friction angles, dilatancy angles, inertial number, the
//! checks), and prints them.
//!
//! The sweep runs the scenario once per μ_r (the rolling friction of the
//! discs' material; the packing is the same: its growth uses another
//! material), each into `DIR/mu_r_<μ_r>`, then post-processes each and
//! writes `DIR/table.md` and the plots of all runs together:
//!
//!     cargo run --release --example biaxial_post -- --run 0,0.1,0.3 -o out/biaxial_sweep [--scenario examples/biaxial.toml] [--threads N]
//!
//! Everything is computed by `efgdem::biaxial` (module docs there: the
//! conventions and how φ_peak, φ_cs and ψ are estimated).

use efgdem::biaxial::{self, History, Options, Point, Setup, Summary};
use efgdem::run::{RunOptions, run};
use efgdem::scenario::{self, Scenario};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() {
    if let Err(e) = main_() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn main_() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    if let Some(list) = value("--run") {
        let file = PathBuf::from(value("--scenario").unwrap_or("examples/biaxial.toml".into()));
        let out = PathBuf::from(value("-o").unwrap_or("out/biaxial_sweep".into()));
        let threads = value("--threads")
            .map(|t| t.parse::<usize>().map_err(|e| format!("--threads: {e}")))
            .transpose()?;
        let mus = list
            .split(',')
            .map(|m| {
                m.trim()
                    .parse::<f64>()
                    .map_err(|e| format!("--run {m}: {e}"))
            })
            .collect::<Result<Vec<f64>, String>>()?;
        return sweep(&file, &out, &mus, threads);
    }
    let [file, dirs @ ..] = args.as_slice() else {
        return Err("usage: biaxial_post SCENARIO OUT_DIR [OUT_DIR …] | --run 0,0.1,0.3 [-o DIR] [--scenario FILE] [--threads N]".into());
    };
    if dirs.is_empty() {
        return Err("give the output directory of the run".into());
    }
    let sc = scenario::load(Path::new(file)).map_err(|e| e.to_string())?;
    let mut runs = vec![];
    for d in dirs {
        let dir = Path::new(d);
        let (p, s) = post(&sc, dir, None)?;
        print_summary(&d.to_string(), &sc, &s);
        print_mean_stress_angles(&p);
        runs.push((d.clone(), p));
    }
    if runs.len() > 1 {
        let dir = Path::new(&dirs[0]);
        biaxial::plot(dir, &runs).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Post-process the run of `sc` in `dir`: CSV, PNG and JSON there.
fn post(sc: &Scenario, dir: &Path, seconds: Option<f64>) -> Result<(Vec<Point>, Summary), String> {
    let setup = Setup::from_scenario(sc)?;
    let h = History::read(&dir.join("history.csv"))?;
    let p = biaxial::curve(&setup, &h)?;
    let s = biaxial::summarize(&setup, &p, &Options::default());
    biaxial::write_csv(&dir.join("biaxial.csv"), &p).map_err(|e| e.to_string())?;
    biaxial::plot(dir, &[(dir.display().to_string(), p.clone())]).map_err(|e| e.to_string())?;
    let json = serde_json::json!({
        "summary": s,
        "inertial_number": setup.inertial_number(),
        "strain_rate": setup.strain_rate,
        "sigma3": setup.sigma3,
        "shear_from_step": setup.shear_from,
        "run_seconds": seconds,
    });
    efgdem::output::write_json(&dir.join("biaxial.json"), &json).map_err(|e| e.to_string())?;
    Ok((p, s))
}

fn print_summary(label: &str, sc: &Scenario, s: &Summary) {
    let setup = Setup::from_scenario(sc).ok();
    println!("{label}:");
    println!(
        "  φ_peak = {:.2}° at ε₁ = {:.2} %; φ_cs = {:.2}° (± {:.2}°, ε₁ = {:.1}–{:.1} %, dε_v/dε₁ there {:+.3})",
        s.phi_peak,
        100.0 * s.eps1_peak,
        s.phi_cs,
        s.phi_cs_spread,
        100.0 * s.cs_from,
        100.0 * s.cs_to,
        s.dilatancy_rate_cs
    );
    println!(
        "  ψ_max = {:.2}° at ε₁ = {:.2} %, ψ at the peak {:.2}°; ε_v: largest contraction {:.3} %, end {:.3} %",
        s.psi_max,
        100.0 * s.eps1_psi_max,
        s.psi_peak,
        100.0 * s.epsv_max,
        100.0 * s.epsv_end
    );
    println!(
        "  σ₃ of the side walls: within {:.3} % ({:.2} % of the rows within 1 %, mean {:+.4} %); whole-sample Love–Weber stress vs walls: {}",
        100.0 * s.sigma3_error,
        100.0 * s.sigma3_within_1pc,
        100.0 * s.sigma3_bias,
        match (s.love_weber_error, s.love_weber_error_rows) {
            (Some(e), Some(r)) => format!(
                "within {:.2} % (moving averages over 1 % of ε₁; single rows {:.2} %; {} of {} rows inside the measure)",
                100.0 * e,
                100.0 * r,
                s.love_weber_rows,
                s.rows
            ),
            _ => "(no whole-sample measure)".to_string(),
        }
    );
    if let Some(i) = setup.and_then(|s| s.inertial_number()) {
        println!("  inertial number I = ε̇ d̄ √(ρ/σ₃) = {i:.2e}");
    }
}

/// The friction angles from the *mean* stresses of a window,
/// `sin φ = (⟨σ₁⟩ − ⟨σ₃⟩)/(⟨σ₁⟩ + ⟨σ₃⟩)`, instead of the mean of the
/// rows' `sin φ` (`biaxial::summarize`). The two agree when the rows are
/// smooth (the dense test at 100 kPa); when the wall stress of single rows
/// jumps by ±100 % (stiff grains at a low σ₃: `biaxial_backfill.toml`)
/// the mean of `sin φ`, a concave function of σ₁, lies below the angle of
/// the mean stresses, which is the one the Love–Weber check supports.
fn print_mean_stress_angles(p: &[Point]) {
    let o = Options::default();
    let sin = |rows: &[Point]| {
        let n = rows.len().max(1) as f64;
        let s1 = rows.iter().map(|x| x.sigma1).sum::<f64>() / n;
        let s3 = rows.iter().map(|x| x.sigma3).sum::<f64>() / n;
        (s1 - s3) / (s1 + s3)
    };
    let deg = |s: f64| s.asin().to_degrees();
    let (mut best, mut at) = (f64::NEG_INFINITY, 0.0);
    for (i, x) in p.iter().enumerate() {
        let s = sin(&p[biaxial::window(p, i, o.smooth)]);
        if s > best {
            (best, at) = (s, x.eps1);
        }
    }
    let end = p.last().map_or(0.0, |x| x.eps1);
    let cs = &p[p.partition_point(|x| x.eps1 < o.cs_from * end)..];
    println!(
        "  from the mean stresses (windows of {:.0} % of ε₁): φ_peak = {:.2}° at ε₁ = {:.2} %; φ_cs = {:.2}° (ε₁ ≥ {:.1} %)",
        100.0 * o.smooth,
        deg(best),
        100.0 * at,
        deg(sin(cs)),
        100.0 * o.cs_from * end
    );
}

/// One run per μ_r, then the table and the plots of all.
fn sweep(file: &Path, out: &Path, mus: &[f64], threads: Option<usize>) -> Result<(), String> {
    let base = scenario::load(file).map_err(|e| e.to_string())?;
    let grain = base
        .granular
        .as_ref()
        .map(|g| g.material.clone())
        .ok_or("the scenario has no [granular]")?;
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    let mut rows = vec![];
    let mut runs = vec![];
    for &mu in mus {
        let mut sc = base.clone();
        for m in sc.material.iter_mut().filter(|m| m.name == grain) {
            m.rolling_friction = mu;
        }
        if let Some(t) = threads {
            sc.simulation.threads = t;
        }
        let dir = out.join(format!("mu_r_{mu}"));
        eprintln!("μ_r = {mu}: running into {}", dir.display());
        let opts = RunOptions {
            overwrite: true,
            ..RunOptions::new(&dir)
        };
        let t0 = Instant::now();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(sc.simulation.threads)
            .build()
            .map_err(|e| e.to_string())?;
        pool.install(|| run(&sc, &opts))
            .map_err(|e| e.to_string())?;
        let seconds = t0.elapsed().as_secs_f64();
        let (p, s) = post(&sc, &dir, Some(seconds))?;
        print_summary(&format!("μ_r = {mu} ({seconds:.0} s)"), &sc, &s);
        rows.push((mu, s, seconds));
        runs.push((format!("μ_r = {mu}"), p));
    }
    biaxial::plot(out, &runs).map_err(|e| e.to_string())?;
    let setup = Setup::from_scenario(&base)?;
    let mut md = String::from(
        "| μ_r | φ_peak | ε₁ at peak | φ_cs (ε₁ ≥ ⅔ ε₁,end) | dε_v/dε₁ there | ψ_max | ψ at peak | ε_v end | σ₃ error: max; rows within 1 % | Love–Weber vs walls: averaged; rows | run time |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (mu, s, secs) in &rows {
        md += &format!(
            "| {mu} | {:.1}° | {:.1} % | {:.1}° ± {:.1}° | {:+.3} | {:.1}° | {:.1}° | {:+.2} % | {:.2} %; {:.2} % | {} | {:.0} s |\n",
            s.phi_peak,
            100.0 * s.eps1_peak,
            s.phi_cs,
            s.phi_cs_spread,
            s.dilatancy_rate_cs,
            s.psi_max,
            s.psi_peak,
            100.0 * s.epsv_end,
            100.0 * s.sigma3_error,
            100.0 * s.sigma3_within_1pc,
            match (s.love_weber_error, s.love_weber_error_rows) {
                (Some(e), Some(r)) => format!("{:.2} %; {:.2} %", 100.0 * e, 100.0 * r),
                _ => "—".into(),
            },
            secs
        );
    }
    if let Some(i) = setup.inertial_number() {
        md += &format!(
            "\nInertial number I = ε̇ d̄ √(ρ/σ₃) = {i:.2e} (ε̇ = {} /s, σ₃ = {} Pa).\n",
            setup.strain_rate, setup.sigma3
        );
    }
    std::fs::write(out.join("table.md"), &md).map_err(|e| e.to_string())?;
    println!("\n{md}");
    Ok(())
}
