//! Driver for continuum-only scenarios (static or dynamic).

use super::EfgError;
use crate::run::RunOptions;
use crate::scenario::Scenario;

pub fn run(_sc: &Scenario, _opts: &RunOptions) -> Result<serde_json::Value, EfgError> {
    Err(EfgError::Invalid("not yet".into()))
}

pub fn check(_sc: &Scenario) -> Result<String, EfgError> {
    Err(EfgError::Invalid("not yet".into()))
}
