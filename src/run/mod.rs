//! Drivers: run a scenario end to end (what `efgdem run` and `check` do),
//! writing `history.csv`, `summary.json` and ParaView frames.

mod continuum;
mod coupled;
mod granular;

use crate::model::{Model, ModelError, System};
use crate::scenario::{Scenario, ScenarioError, build};
use std::path::PathBuf;
use std::time::Instant;

/// Options of `efgdem run` that are not part of the scenario.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output directory (created if missing).
    pub out_dir: PathBuf,
    /// No progress bar.
    pub quiet: bool,
}

/// Why a run failed.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario is invalid or cannot be built (exit code 2).
    #[error(transparent)]
    Scenario(#[from] ScenarioError),
    /// Writing an output file failed.
    #[error("i/o: {0}")]
    Io(#[from] std::io::Error),
    /// A step or solve of the model failed.
    #[error(transparent)]
    Model(#[from] ModelError),
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

/// Build `sc` and run it, writing `summary.json`, `history.csv` and frames
/// into `opts.out_dir`. Returns the summary that was written.
pub fn run(sc: &Scenario, opts: &RunOptions) -> Result<serde_json::Value, RunError> {
    std::fs::create_dir_all(&opts.out_dir)?;
    let t0 = Instant::now();
    let model = sc.build()?;
    let build_s = t0.elapsed().as_secs_f64();
    let probes = sc.probes(&model)?;
    match model.system {
        System::Continuum { .. } => continuum::run(sc, model, probes, build_s, opts),
        System::Granular(_) => granular::run(sc, model, probes, build_s, opts),
        System::Coupled(_) => coupled::run(sc, model, probes, build_s, opts),
    }
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
    let machine = build::machine_memory().map_or_else(|| "unknown".to_string(), build::human_bytes);
    s.push_str(&format!(
        "memory: {} (estimate; machine: {machine})",
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
