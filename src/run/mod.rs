//! Drivers: run a scenario end to end (what `efgdem run` and `check` do),
//! writing `history.csv`, `summary.json` and ParaView frames.

pub mod checkpoint;
mod continuum;
mod coupled;
mod granular;
pub mod memory;
pub mod progress;
mod session;

use crate::model::{Model, ModelError, System};
use crate::scenario::{Scenario, ScenarioError, build};
use checkpoint::Checkpoint;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicUsize;
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
            | RunError::Model(ModelError::State(_) | ModelError::Static | ModelError::Usage(_)) => {
                2
            }
            RunError::Io(_) | RunError::OutDir { .. } => 1,
            RunError::Model(_) => 3,
            RunError::Interrupted { signal, .. } => 128 + (*signal as u8 & 0x7f),
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
/// into `opts.out_dir`. Returns the summary that was written.
pub fn run(sc: &Scenario, opts: &RunOptions) -> Result<serde_json::Value, RunError> {
    let _held = session::prepare_out_dir(opts)?;
    let t0 = Instant::now();
    let what = match build::preparation(sc) {
        Some(p) => format!("building the model: {} ({} DEM steps)", p.what(), p.steps),
        None => "building the model".to_string(),
    };
    let spin = progress::spinner(&what, opts.quiet);
    let mut model = sc.build()?;
    let restart = match &opts.restart {
        Some(path) => {
            let ck = Checkpoint::read(path, sc)?;
            ck.restore(&mut model)?;
            Some(ck)
        }
        None => None,
    };
    spin.finish_and_clear();
    let build_s = t0.elapsed().as_secs_f64();
    let probes = sc.probes(&model)?;
    let last_step = std::cell::Cell::new(model.step);
    let run = Run {
        sc,
        opts,
        probes,
        build_s,
        restart,
        last_step: &last_step,
    };
    let result = match model.system {
        System::Continuum { .. } => continuum::run(run, model),
        System::Granular(_) => granular::run(run, model),
        System::Coupled(_) => coupled::run(run, model),
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
}

/// What `efgdem check` prints: sizes, coverage, time-step diagnostics, the
/// memory estimate and the packing preparation `run` will do. No time
/// stepping: the model is built without the deposit or growth of a
/// generated packing ([`Scenario::build_unprepared`]), and a run that
/// would not fit in the machine's memory is refused before anything is
/// allocated.
pub fn check(sc: &Scenario) -> Result<String, RunError> {
    let model = sc.build_unprepared()?;
    let mut s = match &model.system {
        System::Continuum { .. } => continuum::check(sc, &model),
        System::Granular(_) => granular::check(sc, &model),
        System::Coupled(_) => coupled::check(&model),
    };
    if !s.ends_with('\n') {
        s.push('\n');
    }
    if let Some(p) = build::preparation(sc) {
        s.push_str(&format!(
            "preparation: {p}; the discs above are the generated ones, before it\n"
        ));
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
