//! `[granular]` and `[[wall]]`: discs, their damping and rigid walls.
//! Filled in by the DEM work (issue 3).

use super::{Problems, Scenario};
use serde::Deserialize;

/// The granular assembly.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularSpec {
    /// Default contact material of the discs (a `[[material]]` name).
    pub material: String,
}

/// A rigid wall segment.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    pub name: String,
    pub from: [f64; 2],
    pub to: [f64; 2],
}

/// Semantic checks of `[granular]` and every `[[wall]]`.
pub fn validate(sc: &Scenario, p: &mut Problems) {
    let _ = (sc, p);
}
