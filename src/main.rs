//! `efgdem`: the command-line interface.

use anyhow::Context;
use clap::{Parser, Subcommand};
use efgdem::run::RunError;
use efgdem::scenario::{self, ScenarioError};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize};

/// Element-free Galerkin continua coupled with discrete elements (Wang et al. 2020).
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Run a scenario file and write summary.json, history.csv and ParaView frames.
    ///
    /// Ctrl-C (SIGINT) or SIGTERM stops the run after the current step with
    /// complete outputs, OUT/checkpoint.bin and "status": "interrupted" in
    /// summary.json (exit code 130 or 143); `--restart OUT/checkpoint.bin`
    /// continues it. A second Ctrl-C aborts at once. Exit codes: 0 done, 1
    /// other failure, 2 bad input, 3 the run became unstable.
    Run {
        /// The scenario (TOML), see docs/scenario.md.
        file: PathBuf,
        /// Output directory (created if missing; default `out`, or the
        /// checkpoint's directory with --restart).
        #[arg(short, long)]
        out: Option<PathBuf>,
        /// Worker threads (0 = all cores; results do not depend on it).
        #[arg(long)]
        threads: Option<usize>,
        /// Write OUT/checkpoint.bin every N steps (atomically; one is also
        /// written when the run is stopped by Ctrl-C or SIGTERM).
        #[arg(long, value_name = "N", default_value_t = 0)]
        checkpoint_every: usize,
        /// Continue a stopped run from its checkpoint: same scenario, same
        /// output directory; the outputs are continued as if the run had
        /// never stopped (bitwise, on any number of threads).
        #[arg(long, value_name = "CHECKPOINT")]
        restart: Option<PathBuf>,
        /// No progress display.
        #[arg(short, long)]
        quiet: bool,
        /// Run into a non-empty output directory, removing the files of a
        /// previous run there first (history.csv, summary.json, *.pvd,
        /// *.vtu, frames/, …; other files are kept).
        #[arg(long)]
        overwrite: bool,
    },
    /// Reproduce the paper's §4 (both examples, all variants) from built-in
    /// scenarios: run data, PNG plots of Figs. 9–17 and report.md.
    Reproduce {
        /// Output directory (created if missing).
        #[arg(short, long, default_value = "reproduce")]
        out: PathBuf,
        /// Worker threads (0 = all cores; results do not depend on it).
        #[arg(long, default_value_t = 0)]
        threads: usize,
        /// No per-run progress lines.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Find by bisection the largest stable Δt of a coupled scenario, up to
    /// the DEM critical step (same physical time; "stable" = finite and the
    /// stored energy never above 10× the work put in).
    StudyDt {
        /// The coupled scenario (TOML).
        file: PathBuf,
        /// Relative tolerance of the bisection.
        #[arg(long, default_value_t = 0.02)]
        tol: f64,
    },
    /// Look at a run's results in ParaView: writes OUT/view.py (discs as
    /// true-size circles coloured by speed, bodies deformed and coloured by
    /// von Mises stress, force chains, walls, the time) and opens it in
    /// ParaView, or renders an image with --screenshot (on a virtual
    /// display, Xvfb, when there is none). The options are the script's
    /// defaults; `pvbatch OUT/view.py --screenshot FILE.png [options]`
    /// takes them too.
    View {
        /// The output directory of `efgdem run`.
        out: PathBuf,
        /// Only write OUT/view.py; do not start ParaView.
        #[arg(long)]
        no_open: bool,
        /// Render the view to this PNG file with ParaView's `pvbatch`
        /// instead of opening the GUI.
        #[arg(long, value_name = "FILE")]
        screenshot: Option<PathBuf>,
        /// The frame shown, by its time (default: the last).
        #[arg(long, value_name = "T")]
        time: Option<f64>,
        /// Image size in pixels (--screenshot; default 1600 900).
        #[arg(long, num_args = 2, value_names = ["W", "H"])]
        size: Option<Vec<u32>>,
        /// Colour the discs by their speed or by their displacement since
        /// t = 0.
        #[arg(long, value_parser = ["velocity", "displacement"], default_value = "velocity")]
        discs: String,
        /// Colour ranges over all frames (they stay put when you step
        /// through time) or each frame's own.
        #[arg(long, value_parser = ["series", "frame"], default_value = "series")]
        range: String,
        /// The discs' colour range ends at this percentile of their values
        /// (faster discs saturate: one fast disc does not turn the others
        /// blue); 100: the largest value.
        #[arg(long, value_name = "P", default_value_t = 99.0)]
        percentile: f64,
        /// Show only this rectangle (zoom into a part of a large bed).
        #[arg(long, num_args = 4, value_names = ["X0", "Y0", "X1", "Y1"], allow_negative_numbers = true)]
        region: Option<Vec<f64>>,
        /// Body grid lines: auto (only where a cell is at least 6 pixels
        /// wide), on or off.
        #[arg(long, value_parser = ["auto", "on", "off"], default_value = "auto")]
        edges: String,
        /// Draw the bodies' displacements this many times larger (small
        /// static deflections); 1 is true scale.
        #[arg(long, value_name = "F", default_value_t = 1.0)]
        warp: f64,
    },
    /// Validate a scenario without running it; print sizes and time-step diagnostics.
    Check {
        /// The scenario (TOML).
        file: PathBuf,
    },
}

/// Print a line on standard output. A closed pipe (`efgdem check … | head
/// -2`) ends the program quietly (exit 0); another failure (`> /dev/full`)
/// is reported once, exit 1 (an i/o failure).
fn say(args: std::fmt::Arguments) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let written = out
        .write_fmt(args)
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush());
    if let Err(e) = written {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        let _ = writeln!(std::io::stderr(), "error: writing to standard output: {e}");
        std::process::exit(1);
    }
}

/// `println!` through [`say`].
macro_rules! say {
    ($($t:tt)*) => {
        say(format_args!($($t)*))
    };
}

fn main() -> ExitCode {
    efgdem::run::memory::keep_large_allocations_mapped();
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // under mpirun every rank fails alike: rank 0 says why
            let rank = ["OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"]
                .iter()
                .find_map(|v| std::env::var(v).ok()?.parse::<usize>().ok());
            if rank.is_some_and(|r| r > 0) {
                let run = e.chain().find_map(|c| c.downcast_ref::<RunError>());
                let scenario = e.downcast_ref::<ScenarioError>().is_some();
                return ExitCode::from(if scenario {
                    2
                } else {
                    run.map_or(1, RunError::exit_code)
                });
            }
            if let Some(se) = e.downcast_ref::<ScenarioError>() {
                eprintln!("error: {se}");
                return ExitCode::from(2);
            }
            let run = e.chain().find_map(|c| c.downcast_ref::<RunError>());
            // 2 bad input, 1 i/o, 3 numerical, 128 + signal a stop
            // (RunError::exit_code); anything else 1
            match run {
                Some(RunError::Scenario(se)) => {
                    eprintln!("error: {se}");
                    ExitCode::from(2)
                }
                // rank 0 of the run said why
                Some(RunError::OnRank0 { code }) => ExitCode::from(*code),
                _ => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(run.map_or(1, RunError::exit_code))
                }
            }
        }
    }
}

/// The ranks of this process's MPI job (`mpirun -np N`): one rank when not
/// started by mpirun (the build with MPI then never initialises it: it is
/// the one-process program, as a build without it). A build without the `mpi` feature started as one of
/// several ranks refuses to run (each copy would run the whole scenario).
fn ranks() -> anyhow::Result<Arc<dyn efgdem::decomp::Comm>> {
    #[cfg(feature = "mpi")]
    {
        // not started by a launcher: the one-process program, without MPI
        if launched_ranks().is_none() {
            return Ok(Arc::new(efgdem::decomp::Solo));
        }
        match efgdem::decomp::mpi::Mpi::init() {
            Some(m) => Ok(Arc::new(m)),
            None => anyhow::bail!("MPI cannot be initialised with serialised thread support"),
        }
    }
    #[cfg(not(feature = "mpi"))]
    {
        if let Some(n) = launched_ranks().filter(|&n| n > 1) {
            return Err(RunError::Ranks(format!(
                "started as one of {n} MPI ranks, but this efgdem was built without MPI: build it with `cargo build --release --features mpi` (needs a system MPI, e.g. the libopenmpi-dev, openmpi-bin and libclang-dev packages)"
            ))
            .into());
        }
        Ok(Arc::new(efgdem::decomp::Solo))
    }
}

/// The number of ranks an MPI launcher (mpirun, mpiexec, srun) started
/// this process as one of, from the variables it sets (OpenMPI, MPICH and
/// Hydra, PMIx); `None` when no launcher started it.
fn launched_ranks() -> Option<usize> {
    let size = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.parse::<usize>().ok());
    // PMIx launchers (srun --mpi=pmix) may set the rank only
    size.or_else(|| std::env::var_os("PMIX_RANK").map(|_| 1))
}

/// A flag that SIGINT and SIGTERM set to their number, so that a run can
/// stop after its current step; a second signal exits at once.
fn stop_on_signals() -> anyhow::Result<Arc<AtomicUsize>> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let stop = Arc::new(AtomicUsize::new(0));
    let again = Arc::new(AtomicBool::new(false));
    for sig in [SIGINT, SIGTERM] {
        // registered first, so it sees the flag as the previous signal left it
        signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&again))?;
        signal_hook::flag::register(sig, Arc::clone(&again))?;
        signal_hook::flag::register_usize(sig, Arc::clone(&stop), sig as usize)?;
    }
    Ok(stop)
}

/// A run stopped by a signal or by an instability wrote its summary: its
/// results up to there, on stdout as for a completed run.
fn stopped_recap(e: &RunError, out: &std::path::Path) {
    if !matches!(e, RunError::Interrupted { .. } | RunError::Model(_)) {
        return;
    }
    let Ok(text) = std::fs::read_to_string(out.join("summary.json")) else {
        return;
    };
    let Ok(summary) = serde_json::from_str::<serde_json::Value>(&text) else {
        return;
    };
    if matches!(summary["status"].as_str(), Some("interrupted" | "unstable")) {
        say!("{}", efgdem::run::recap::recap(&summary, out).trim_end());
    }
}

/// Run `f` on a pool of `n` worker threads (0 = one per core). The whole
/// command runs *inside* the pool, so that the time loop's parallel phases
/// start on a worker instead of injecting a job from outside at every step
/// (in a bare harness that cost 35 % on 10 000 dense discs; in `efgdem run`
/// the difference was within the machine's noise).
fn in_pool<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> anyhow::Result<T> {
    let (n, note) = efgdem::run::worker_threads(n);
    if let Some(note) = note {
        eprintln!("warning: {note}");
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .context("setting up the thread pool")?;
    Ok(pool.install(f))
}

fn dispatch(cli: Cli) -> anyhow::Result<()> {
    match cli.cmd {
        Cmd::Run {
            file,
            out,
            threads,
            quiet,
            overwrite,
            checkpoint_every,
            restart,
        } => {
            // before anything else: a build without MPI under mpirun stops here
            let comm = ranks()?;
            let sc = scenario::load(&file)?;
            let out = out.unwrap_or_else(|| match &restart {
                Some(ck) => ck.parent().map_or_else(PathBuf::new, PathBuf::from),
                None => PathBuf::from("out"),
            });
            let opts = efgdem::run::RunOptions {
                quiet,
                overwrite,
                stop: Some(stop_on_signals()?),
                checkpoint_every,
                restart,
                ..efgdem::run::RunOptions::new(&out)
            };
            let root = comm.rank() == 0;
            let t0 = std::time::Instant::now();
            let result = in_pool(threads.unwrap_or(sc.simulation.threads), || {
                efgdem::run::run_on(&sc, &opts, comm)
            })?;
            if let Err(e) = &result
                && root
            {
                stopped_recap(e, &out);
            }
            let summary = result.with_context(|| format!("running {}", file.display()))?;
            if root {
                eprintln!("done in {:.3} s", t0.elapsed().as_secs_f64());
                say!("{}", efgdem::run::recap::recap(&summary, &out).trim_end());
            }
        }
        Cmd::Reproduce {
            out,
            threads,
            quiet,
        } => {
            let t0 = std::time::Instant::now();
            let report = in_pool(threads, || efgdem::reproduce::reproduce(&out, quiet))??;
            eprintln!("done in {:.2} s", t0.elapsed().as_secs_f64());
            say!(
                "report: {}
figures: {}/fig*.png (their data: fig*.csv); runs: {}/runs/",
                report.display(),
                out.display(),
                out.display()
            );
        }
        Cmd::StudyDt { file, tol } => {
            let sc = scenario::load(&file)?;
            if scenario::kind(&sc) != scenario::Kind::Coupled {
                anyhow::bail!(
                    "{}: study-dt needs a coupled scenario ([[body]] and [granular])",
                    file.display()
                );
            }
            if !(tol > 0.0 && tol < 1.0) {
                anyhow::bail!("--tol must be in (0, 1), got {tol}");
            }
            say!("{:>12}  {:>8}  {:>8}  reason", "dt", "bounded", "seconds");
            let r = in_pool(0, || {
                efgdem::study::study_dt(&sc, tol, |t| {
                    say!(
                        "{:>12.5e}  {:>8}  {:>8.2}  {}",
                        t.dt,
                        t.bounded,
                        t.seconds,
                        t.reason
                    )
                })
            })??;
            say!(
                "largest dt studied (2√(m_min/k_max), or the limit of a first collision): {:.5e}",
                r.dt_critical
            );
            match r.dt_max {
                Some(dt) => say!(
                    "largest bounded dt: {dt:.5e} ({:.3} × the largest studied)",
                    dt / r.dt_critical
                ),
                None => say!("no bounded dt found down to 1e-4 × the scenario's dt"),
            }
        }
        Cmd::View {
            out,
            no_open,
            screenshot,
            time,
            size,
            discs,
            range,
            percentile,
            region,
            edges,
            warp,
        } => {
            let options = efgdem::output::view::ViewOptions {
                time,
                size: size.map(|s| [s[0], s[1]]),
                discs,
                range,
                percentile,
                region: region.map(|r| [r[0], r[1], r[2], r[3]]),
                edges,
                warp,
            };
            view(&out, no_open, screenshot.as_deref(), &options)?
        }
        Cmd::Check { file } => {
            let sc = scenario::load(&file)?;
            let report = efgdem::run::check(&sc)?;
            say!("{}: ok\n{report}", file.display());
        }
    }
    Ok(())
}

/// `efgdem view OUT`: write OUT/view.py, then open it in ParaView or
/// render it. Without a display the GUI is not started (it would abort):
/// the message says how to render an image instead.
fn view(
    out: &std::path::Path,
    no_open: bool,
    screenshot: Option<&std::path::Path>,
    options: &efgdem::output::view::ViewOptions,
) -> anyhow::Result<()> {
    use efgdem::output::view;
    if !(options.percentile > 0.0 && options.percentile <= 100.0) {
        anyhow::bail!(
            "--percentile must be in (0, 100], got {}",
            options.percentile
        );
    }
    if !(options.warp.is_finite() && options.warp > 0.0) {
        anyhow::bail!("--warp must be a number > 0, got {}", options.warp);
    }
    if let Some(r) = options.region
        && !(r[2] > r[0] && r[3] > r[1])
    {
        anyhow::bail!("--region X0 Y0 X1 Y1 needs X1 > X0 and Y1 > Y0, got {r:?}");
    }
    let found = view::has_frames(out).with_context(|| format!("reading {}", out.display()))?;
    if !found {
        anyhow::bail!(
            "{}: no ParaView files (*.pvd, *.vtu); run with `[output] vtk_every = N` first",
            out.display()
        );
    }
    let script = view::write_script(out, options)
        .with_context(|| format!("writing into {}", out.display()))?;
    say!("wrote {}", script.display());
    if let Some(png) = screenshot {
        let colours =
            view::render(&script, png).with_context(|| format!("rendering {}", png.display()))?;
        say!("wrote {}", png.display());
        for c in colours {
            say!("{c}");
        }
        return Ok(());
    }
    let how = format!(
        "render an image with `efgdem view {} --screenshot view.png` (a virtual display is started when there is none), or open the script in ParaView: `paraview --script={}`",
        out.display(),
        script.display()
    );
    if no_open {
        eprintln!("{how}");
        return Ok(());
    }
    if !view::has_display() {
        anyhow::bail!(
            "no display to open ParaView on (DISPLAY and WAYLAND_DISPLAY are not set): {how}"
        );
    }
    let Some(pv) = view::on_path("paraview") else {
        anyhow::bail!(
            "ParaView (`paraview`) is not on PATH (Debian: apt-get install paraview): {how}"
        );
    };
    let status = std::process::Command::new(&pv)
        .arg(format!("--script={}", script.display()))
        .status()
        .with_context(|| format!("starting {}", pv.display()))?;
    if !status.success() {
        anyhow::bail!("{} exited with {status}; {how}", pv.display());
    }
    Ok(())
}
