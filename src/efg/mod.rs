//! The element-free Galerkin continuum (§2.1–2.2 of the paper).
//!
//! - [`weight`]: cubic spline weight (Eq. 5, ERRATA E1) on rectangular supports (E2).
//! - [`support`]: support sizes `d_max · c_I` and the neighbour lookup.
//! - [`shape`]: MLS shape functions and exact derivatives (ERRATA E3).
//! - [`assemble`]: K, M (via the Gram matrix), C, penalty (E4, E5), in parallel.
//! - [`penalty`]: the penalty points: `K^α`, `F^α(t)`, the springs' energy and force.
//! - [`body`]: [`EfgBody`], built from a scenario `[[body]]`.

pub mod assemble;
pub mod body;
pub mod boundary;
pub mod penalty;
pub mod shape;
pub mod support;
pub mod weight;

pub use crate::continuum::Sample;
pub use body::EfgBody;
pub use shape::{CoverageError, ShapeRow};

/// Errors of the EFG continuum.
#[derive(Debug, thiserror::Error)]
pub enum EfgError {
    /// A point without enough covering nodes (MLS moment matrix singular).
    #[error("body `{body}`: {source} (d_max = {d_max})")]
    Coverage {
        body: String,
        d_max: f64,
        #[source]
        source: CoverageError,
    },
    #[error(transparent)]
    Solve(#[from] crate::sparse::SparseError),
    #[error("advance() called before start_dynamic()")]
    NotStarted,
    #[error("{0}")]
    Invalid(String),
}

impl EfgError {
    pub(crate) fn coverage(e: CoverageError, d_max: f64, body: &str) -> Self {
        EfgError::Coverage {
            body: body.to_string(),
            d_max,
            source: e,
        }
    }
}
