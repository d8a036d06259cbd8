//! Drivers: run a scenario end to end (what `efgdem run` and `check` do),
//! writing `history.csv`, `summary.json` and ParaView frames.

pub mod checkpoint;
mod continuum;
mod coupled;
mod granular;
pub mod memory;
pub mod progress;
mod ranks;
pub mod recap;
mod session;

use crate::decomp::{Comm, Solo};
use crate::model::{Model, ModelError, System};
use crate::scenario::prepare::{Bed, PrepareError, prepare};
use crate::scenario::{Scenario, ScenarioError, build};
use checkpoint::Checkpoint;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Options of `efgdem run` that are not part of the scenario.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output directory (created if missing).
    pub out_dir: PathBuf,
    /// No progress display.
    pub quiet: bool,
    /// Accept a non-empty output directory, removing the files a run
    /// writes (`history.csv`, `summary.json`, `*.pvd`, `*.vtu`,
    /// `frames/`, …) first; other files are kept.
    pub overwrite: bool,
    /// Stop request: when it holds a non-zero signal number (set by a
    /// SIGINT/SIGTERM handler), the run finishes its step, completes its
    /// outputs and ends with [`RunError::Interrupted`].
    pub stop: Option<Arc<AtomicUsize>>,
    /// Write `checkpoint.bin` every this many steps (0: only when stopped
    /// by a signal).
    pub checkpoint_every: usize,
    /// Continue the run saved in this checkpoint (written by a run of the
    /// same scenario into `out_dir`), appending to its outputs.
    pub restart: Option<PathBuf>,
    /// Print the run's start-up warnings (the time step against the
    /// critical step, the coupled scheme's choice) to standard error; they
    /// are in `summary.json` (`warnings`) either way.
    pub warn: bool,
}

impl RunOptions {
    /// Write into `out_dir` (which must be empty or missing), with progress,
    /// no stop request.
    pub fn new(out_dir: impl AsRef<Path>) -> Self {
        RunOptions {
            out_dir: out_dir.as_ref().to_path_buf(),
            quiet: false,
            overwrite: false,
            stop: None,
            checkpoint_every: 0,
            restart: None,
            warn: true,
        }
    }
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is invalid or cannot be built (exit code 2).
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// Writing an output file failed (exit code 1); the message names the
    /// file.
    #[error("{0}")]
    Io(std::io::Error),
    /// The output directory cannot be created or read (exit code 1).
    #[error("output directory {}: {error}", path.display())]
    OutDir {
        /// The directory.
        path: PathBuf,
        /// What failed (in the message, once).
        error: std::io::Error,
    },
    /// Another run holds the output directory (exit code 2).
    #[error(
        "output directory {} is in use by another efgdem run{}; wait for it to end or choose another (-o)",
        path.display(),
        holder.map_or_else(String::new, |p| format!(" (process {p})"))
    )]
    Busy {
        /// The directory.
        path: PathBuf,
        /// The process id the holder wrote in the lock file.
        holder: Option<u32>,
    },
    /// The output directory holds files and `overwrite` was not given
    /// (exit code 2).
    #[error(
        "output directory {} is not empty; choose another (-o) or pass --overwrite to replace the run's files in it",
        .0.display()
    )]
    NotEmpty(PathBuf),
    /// A step or solve of the model failed (an instability: exit code 3).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A stop was requested; the outputs are complete up to `step` and
    /// `summary.json` says `"status": "interrupted"` (exit code 128 +
    /// signal).
    #[error(
        "interrupted by signal {signal} after step {step}; outputs are complete up to it; continue with --restart {}",
        checkpoint.display()
    )]
    Interrupted {
        /// The signal number (2 SIGINT, 15 SIGTERM).
        signal: usize,
        /// Steps taken.
        step: usize,
        /// The checkpoint written at the stop.
        checkpoint: PathBuf,
    },
    /// A stop was requested during the preparation of the packing: nothing
    /// is there to continue (`summary.json` says `"status":
    /// "interrupted"`, `"during": "preparation"`; exit code 128 + signal).
    #[error(
        "interrupted by signal {signal} during the preparation of the packing, after {step} of {steps} steps; nothing to continue from: run it again (with `cache` in the packing's table a finished preparation is kept)"
    )]
    InterruptedPreparing {
        /// The signal number (2 SIGINT, 15 SIGTERM).
        signal: usize,
        /// Preparation steps taken.
        step: usize,
        /// Steps of the whole preparation.
        steps: usize,
    },
    /// The scenario cannot run on several ranks (exit code 2).
    #[error("{0}")]
    Ranks(String),
    /// On a rank other than 0 of a run on several ranks: rank 0 failed
    /// (and said why) with this exit code.
    #[error("rank 0 failed (exit code {code})")]
    OnRank0 {
        /// Rank 0's exit code.
        code: u8,
    },
    /// A checkpoint cannot be used to restart this scenario (exit code 2).
    #[error("cannot restart from {}: {message}", path.display())]
    Restart {
        /// The checkpoint file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

impl From<std::io::Error> for RunError {
    fn from(e: std::io::Error) -> Self {
        RunError::Io(e)
    }
}

impl RunError {
    /// The exit code of `efgdem run` for this error: 2 bad input or a
    /// refused restart (the scenario, a checkpoint, a busy or non-empty
    /// output directory, a state that does not fit), 1 an i/o failure, 3 a
    /// numerical failure (an instability, a solve), 128 + signal a stop.
    pub fn exit_code(&self) -> u8 {
        match self {
            RunError::Scenario(_)
            | RunError::NotEmpty(_)
            | RunError::Busy { .. }
            | RunError::Restart { .. }
            | RunError::Ranks(_)
            | RunError::Model(ModelError::State(_) | ModelError::Static | ModelError::Usage(_)) => {
                2
            }
            RunError::Io(_) | RunError::OutDir { .. } => 1,
            RunError::Model(_) => 3,
            RunError::Interrupted { signal, .. }
            | RunError::InterruptedPreparing { signal, .. } => 128 + (*signal as u8 & 0x7f),
            RunError::OnRank0 { code } => *code,
        }
    }
}

impl From<crate::model::body::BodyError> for RunError {
    fn from(e: crate::model::body::BodyError) -> Self {
        RunError::Model(e.into())
    }
}

impl From<crate::dem::DemError> for RunError {
    fn from(e: crate::dem::DemError) -> Self {
        RunError::Model(e.into())
    }
}

impl From<crate::coupling::CouplingError> for RunError {
    fn from(e: crate::coupling::CouplingError) -> Self {
        RunError::Model(e.into())
    }
}

/// The number of worker threads to start for `requested` (0: one per
/// core): never more than the machine runs at once
/// ([`std::thread::available_parallelism`]), since more only cost memory
/// and time (results do not depend on it) and an absurd count would never
/// finish starting. The note says when the count was lowered.
pub fn worker_threads(requested: usize) -> (usize, Option<String>) {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    match requested {
        0 => (cores, None),
        n if n <= cores => (n, None),
        n => (
            cores,
            Some(format!(
                "{n} threads asked for; this machine runs {cores} at once: using {cores} (results do not depend on it)"
            )),
        ),
    }
}

/// Build `sc` and run it, writing `summary.json`, `history.csv` and frames
/// into `opts.out_dir`. Returns the summary that was written. A generated
/// packing's preparation (deposit, growth) is shown with its step count
/// and ETA, and stopped by a stop request.
pub fn run(sc: &Scenario, opts: &RunOptions) -> Result<Value, RunError> {
    run_on(sc, opts, Arc::new(Solo))
}

/// [`run`] on the ranks of `comm`: every rank calls it with the same
/// scenario and options. On one rank it is [`run`]; on several, a granular
/// scenario is divided over them ([`crate::decomp`]) with outputs bitwise
/// those of one rank, written by rank 0 (which returns the summary; the
/// others return `Null`, or [`RunError::OnRank0`] when rank 0 failed); so
/// is a coupled one, its bodies on every rank
/// ([`crate::decomp::near_bodies`]). Continuum scenarios, and the coupled
/// schemes that step the discs in phases (predicted, staggered), are
/// refused on several ranks.
pub fn run_on(
    sc: &Scenario,
    opts: &RunOptions,
    comm: Arc<dyn Comm>,
) -> Result<serde_json::Value, RunError> {
    let (root, ranks) = (comm.rank() == 0, comm.size());
    // rank 0 writes the files: it holds the output directory
    let prepared = root.then(|| session::prepare_out_dir(opts)).transpose();
    let _held = ranks::agree(&*comm, prepared)?;
    let t0 = Instant::now();
    // every rank prepares the same packing (it is deterministic)
    let bed = prepare_packing(sc, opts, opts.quiet || !root)?;
    let spin = progress::spinner("building the model", opts.quiet || !root);
    let rows = bed.as_ref().map(|b| &b.rows[..]);
    let (model, start, restart) = build_model(sc, opts, rows, &comm)?;
    spin.finish_and_clear();
    let build_s = t0.elapsed().as_secs_f64();
    let purpose = bed
        .as_ref()
        .map_or(build::BuildFor::Run, |b| build::BuildFor::Prepared(&b.rows));
    let removed = build::removed_discs(sc, purpose).map_err(|p| sc.located(vec![p]))?;
    // the bed's discs are in the model now: the summary counts them
    let bed = bed.map(|b| {
        let discs = b.rows.len();
        (
            discs,
            Bed {
                rows: Vec::new(),
                ..b
            },
        )
    });
    let probes = sc.probes(&model)?;
    let last_step = std::cell::Cell::new(model.step);
    let run = Run {
        sc,
        opts,
        probes,
        build_s,
        restart,
        last_step: &last_step,
        bed,
        removed,
    };
    let result = match model.system {
        System::Granular(ref g) if ranks > 1 => match ranks::discs_refusal(g) {
            Some(why) => Err(RunError::Ranks(why.into())),
            None => ranks::run(run, model, comm, start),
        },
        System::Continuum { .. } if ranks > 1 => Err(RunError::Ranks(format!(
            "a continuum scenario (bodies without discs) does not run on several ranks: run it with one process (not under mpirun -np {ranks})"
        ))),
        System::Continuum { .. } => continuum::run(run, model),
        System::Granular(_) => granular::run(run, model),
        System::Coupled(_) => coupled::run(run, model, comm),
    };
    if let Err(e @ (RunError::Io(_) | RunError::OutDir { .. })) = &result {
        // say so in summary.json if the disk still takes it; the files
        // already written are whole (history.csv cut back to its last row)
        let summary = serde_json::json!({
            "status": "failed",
            "error": e.to_string(),
            "last_step": last_step.get(),
        });
        let _ = crate::output::write_json(&opts.out_dir.join("summary.json"), &summary);
    }
    result
}

/// The model this rank runs (restored from `opts.restart`), how its
/// discs are divided over the ranks, and the checkpoint: a granular run
/// on several ranks builds (or restores) only the discs each rank holds;
/// otherwise every rank builds (and restores) the whole.
fn build_model(
    sc: &Scenario,
    opts: &RunOptions,
    bed: Option<&[crate::dem::packing::DiscRow]>,
    comm: &Arc<dyn Comm>,
) -> Result<(Model, ranks::Start, Option<Checkpoint>), RunError> {
    if comm.size() > 1 {
        match &opts.restart {
            None => {
                if let Some((m, cut)) = sc.build_part(bed, &**comm)? {
                    return Ok((m, ranks::Start::Fresh(cut), None));
                }
            }
            Some(path) => {
                if let Some(sk) = sc.part_skeleton(bed)? {
                    let (m, d, ck) = checkpoint::read_part(path, sc, sk, comm.clone())?;
                    return Ok((m, ranks::Start::Restored(Box::new(d)), Some(ck)));
                }
            }
        }
    }
    let mut model = match bed {
        Some(rows) => sc.build_prepared(rows)?,
        None => sc.build()?,
    };
    let restart = match &opts.restart {
        Some(path) => {
            let mut ck = Checkpoint::read(path, sc)?;
            ck.restore(&mut model)?;
            Some(ck)
        }
        None => None,
    };
    Ok((model, ranks::Start::Whole, restart))
}

/// The scenario's packing preparation, if any: read from its cache, or
/// stepped with a progress bar (steps, ETA) that a stop request ends
/// within a step — `summary.json` then records the interruption.
fn prepare_packing(sc: &Scenario, opts: &RunOptions, quiet: bool) -> Result<Option<Bed>, RunError> {
    let Some(prep) = build::preparation(sc) else {
        return Ok(None);
    };
    // every problem of the scenario before any step
    let problems = sc.validate();
    if !problems.is_empty() {
        return Err(sc.located(problems).into());
    }
    let t0 = Instant::now();
    // made at the first step: a bed read from its cache takes none
    let mut bar = None;
    let stop = opts.stop.clone();
    let signal = || stop.as_ref().map_or(0, |s| s.load(Ordering::Relaxed));
    let result = prepare(sc, &mut |step| {
        bar.get_or_insert_with(|| progress::Progress::labelled(prep.what(), prep.steps, quiet))
            .update(step, f64::NAN);
        signal() == 0
    });
    if let Some(b) = &bar {
        b.finish();
    }
    match result {
        Ok(bed) => {
            if let Some(e) = bed.as_ref().and_then(|b| b.cache_error.as_ref()) {
                eprintln!(
                    "warning: the prepared packing could not be saved in its cache ({e}); the run goes on with it"
                );
            }
            if let Some(b) = &bed
                && !quiet
            {
                let n = b.rows.len();
                match (&b.read_from, &b.written_to) {
                    (Some(f), _) => {
                        eprintln!("{}: {n} discs read from {}", prep.what(), f.display())
                    }
                    (None, w) => eprintln!(
                        "{}: {n} discs, {} steps in {:.1} s{}",
                        prep.what(),
                        prep.steps,
                        t0.elapsed().as_secs_f64(),
                        w.as_ref()
                            .map_or(String::new(), |w| format!("; saved in {}", w.display()))
                    ),
                }
            }
            Ok(bed)
        }
        Err(PrepareError::Invalid(p)) => Err(sc.located(vec![p]).into()),
        Err(PrepareError::Stopped { step, steps }) => {
            let signal = signal();
            // a restart's directory keeps the stopped run's summary
            if opts.restart.is_none() {
                let summary = json!({
                    "status": "interrupted",
                    "during": "preparation",
                    "signal": signal,
                    "preparation": { "method": prep.what(), "steps_done": step, "steps": steps },
                    "last_step": 0,
                });
                crate::output::write_json(&opts.out_dir.join("summary.json"), &summary)?;
            }
            Err(RunError::InterruptedPreparing {
                signal,
                step,
                steps,
            })
        }
    }
}

/// What a driver gets besides the model.
struct Run<'a> {
    sc: &'a Scenario,
    opts: &'a RunOptions,
    /// The bound probes, in scenario order.
    probes: Vec<(String, crate::model::Probe)>,
    /// Seconds to build the model.
    build_s: f64,
    /// The checkpoint the model was restored from.
    restart: Option<Checkpoint>,
    /// The last step taken (for the summary of a run that fails).
    last_step: &'a std::cell::Cell<usize>,
    /// The prepared packing, if the scenario has one: its disc count, and
    /// the bed without its discs (built into the model).
    bed: Option<(usize, Bed)>,
    /// Discs removed for each body with `overlapping_discs = "remove"`.
    removed: Vec<(String, usize)>,
}

impl Run<'_> {
    /// Add what every granular and coupled summary shares: the probes'
    /// extrema (over the rows of `history.csv`), the preparation and the
    /// discs removed for bodies.
    fn annotate(&self, summary: &mut Value) -> Result<(), RunError> {
        let names: Vec<&str> = self.probes.iter().map(|p| p.0.as_str()).collect();
        let path = self.opts.out_dir.join("history.csv");
        let ext = crate::output::csv::extrema(&path, &names)?;
        summary["probes"] = self
            .probes
            .iter()
            .zip(ext)
            .filter_map(|((n, p), e)| {
                let mut e = json!(e?);
                if let Some(s) = p.sign() {
                    e["sign"] = json!(s);
                }
                Some((n.clone(), e))
            })
            .collect::<serde_json::Map<_, _>>()
            .into();
        if let (Some((discs, b)), Some(p)) = (&self.bed, build::preparation(self.sc)) {
            summary["preparation"] = json!({
                "method": p.what(),
                "steps": p.steps,
                "discs": discs,
                "cache_read": b.read_from,
                "cache_written": b.written_to,
                "cache_error": b.cache_error,
            });
        }
        if !self.removed.is_empty() {
            summary["removed_discs"] = self
                .removed
                .iter()
                .map(|(b, n)| (b.clone(), json!(n)))
                .collect::<serde_json::Map<_, _>>()
                .into();
        }
        Ok(())
    }
}

/// What `efgdem check` prints: sizes, coverage, time-step diagnostics, the
/// memory estimate and the packing preparation `run` will do. No time
/// stepping: the model is built without the deposit or growth of a
/// generated packing ([`Scenario::build_unprepared`]), and a run that
/// would not fit in the machine's memory is refused before anything is
/// allocated.
pub fn check(sc: &Scenario) -> Result<String, RunError> {
    let problems = sc.validate();
    if !problems.is_empty() {
        return Err(sc.located(problems).into());
    }
    let located = |p| sc.located(vec![p]);
    let cached = crate::scenario::prepare::cached(sc).map_err(located)?;
    let model = match &cached {
        Some(rows) => sc.build_prepared(rows)?,
        None => sc.build_unprepared()?,
    };
    let mut s = match &model.system {
        System::Continuum { .. } => continuum::check(sc, &model),
        System::Granular(_) => granular::check(sc, &model),
        System::Coupled(_) => coupled::check(&model),
    };
    if !s.ends_with('\n') {
        s.push('\n');
    }
    let prep = build::preparation(sc);
    match (&prep, &cached) {
        (Some(p), Some(rows)) => s.push_str(&format!(
            "preparation: {} read from its cache ({} discs; the discs above are those)\n",
            p.what(),
            rows.len()
        )),
        (Some(p), None) => s.push_str(&format!(
            "preparation: {p}; the discs above are the generated ones, before it\n"
        )),
        _ => {}
    }
    let purpose = match &cached {
        Some(rows) => build::BuildFor::Prepared(rows),
        None => build::BuildFor::Check,
    };
    for (body, n) in build::removed_discs(sc, purpose).map_err(located)? {
        match (&prep, &cached) {
            (Some(p), None) => s.push_str(&format!(
                "body `{body}`: placed after {}; the discs it then overlaps will be removed\n",
                p.what()
            )),
            _ => s.push_str(&format!(
                "body `{body}`: {n} disc(s) overlapping it will be removed\n"
            )),
        }
    }
    let limit = build::memory_limit().map_or_else(|| "unknown".to_string(), |(_, what)| what);
    s.push_str(&format!(
        "memory: {} (estimate; {limit})",
        build::memory_estimate(sc)
    ));
    Ok(s)
}

/// The model's bodies' names.
fn body_names(model: &Model) -> Vec<String> {
    (0..model.n_bodies())
        .map(|i| model.body(i).name().to_string())
        .collect()
}
