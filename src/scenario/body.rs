//! `[[body]]`: a continuum body (EFG, later bilinear FE).
//! Filled in by the EFG work (issue 2).

use super::{Problems, Scenario};
use serde::Deserialize;

/// One continuum body.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name used by probes and outputs.
    pub name: String,
}

/// Semantic checks of every `[[body]]`.
pub fn validate(sc: &Scenario, p: &mut Problems) {
    let _ = (sc, p);
}
