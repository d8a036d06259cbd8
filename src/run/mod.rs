//! Run a scenario end to end: pick the driver from the sections present.

use crate::scenario::Scenario;
use std::path::PathBuf;

/// Options of `efgdem run` that are not part of the scenario.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Output directory (created if missing).
    pub out_dir: PathBuf,
    /// No progress bar.
    pub quiet: bool,
}

/// Why a run failed after the scenario was accepted.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("i/o: {0}")]
    Io(#[from] std::io::Error),
    #[error(transparent)]
    Efg(#[from] crate::efg::EfgError),
    #[error(transparent)]
    Dem(#[from] crate::dem::DemError),
    #[error(transparent)]
    Coupling(#[from] crate::coupling::CouplingError),
}

/// Which kind of run a scenario describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Continuum bodies only.
    Continuum,
    /// Discs (and walls) only.
    Granular,
    /// Both: the coupled EFG–DE problem.
    Coupled,
}

pub fn kind(sc: &Scenario) -> Kind {
    match (sc.body.is_empty(), sc.granular.is_some()) {
        (false, false) => Kind::Continuum,
        (true, _) => Kind::Granular,
        (false, true) => Kind::Coupled,
    }
}

/// Run `sc`, writing `summary.json`, `history.csv` and frames into
/// `opts.out_dir`. Returns the summary that was written.
pub fn run(sc: &Scenario, opts: &RunOptions) -> Result<serde_json::Value, RunError> {
    std::fs::create_dir_all(&opts.out_dir)?;
    match kind(sc) {
        Kind::Continuum => Ok(crate::efg::run::run(sc, opts)?),
        Kind::Granular => Ok(crate::dem::run::run(sc, opts)?),
        Kind::Coupled => Ok(crate::coupling::run::run(sc, opts)?),
    }
}

/// What `efgdem check` prints: sizes, coverage, time-step diagnostics.
pub fn check(sc: &Scenario) -> Result<String, RunError> {
    match kind(sc) {
        Kind::Continuum => Ok(crate::efg::run::check(sc)?),
        Kind::Granular => Ok(crate::dem::run::check(sc)?),
        Kind::Coupled => Ok(crate::coupling::run::check(sc)?),
    }
}
