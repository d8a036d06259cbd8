//! Driver for granular-only scenarios (discs and walls).

use super::DemError;
use crate::run::RunOptions;
use crate::scenario::Scenario;

pub fn run(_sc: &Scenario, _opts: &RunOptions) -> Result<serde_json::Value, DemError> {
    Err(DemError::Input("not yet".into()))
}

pub fn check(_sc: &Scenario) -> Result<String, DemError> {
    Err(DemError::Input("not yet".into()))
}
