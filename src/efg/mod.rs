//! The element-free Galerkin continuum (§2.1–2.2 of the paper).
//!
//! - [`weight`]: cubic spline weight (Eq. 5, ERRATA E1) on rectangular supports (E2).
//! - [`support`]: support sizes `d_max · c_I` and the neighbour lookup.
//! - [`shape`]: MLS shape functions and exact derivatives (ERRATA E3).
//! - [`assemble`]: K, M (via the Gram matrix), C, penalty (E4, E5), in parallel.
//! - [`penalty`]: the penalty points: `K^α`, `F^α(t)`, the springs' energy and force.
//! - [`body`]: [`EfgBody`], built from a scenario `[[body]]`.
//! - [`face_contact`]: contact of closing crack faces (penalty, Coulomb friction).
//! - [`fracture`]: stress intensity factors at the tips of its cracks.
//! - [`growth`]: cracks that grow by the maximum hoop-stress criterion.

pub mod assemble;
pub mod body;
pub mod boundary;
pub mod face_contact;
pub mod fracture;
pub mod growth;
pub mod penalty;
pub mod polygon;
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
        /// Name of the body.
        body: String,
        /// Its support size factor (raise it to cover the point).
        d_max: f64,
        /// The point and its covering nodes.
        #[source]
        source: CoverageError,
    },
    /// A sparse factorisation or solve failed (e.g. K̄ singular: the body
    /// is not supported).
    #[error(transparent)]
    Solve(#[from] crate::sparse::SparseError),
    /// The contact of closing crack faces did not settle.
    #[error("body `{body}`: {source}")]
    FaceContact {
        /// Name of the body.
        body: String,
        /// The solve's last residual.
        #[source]
        source: face_contact::Unsettled,
    },
    /// A step was asked for before [`EfgBody::start_dynamic`].
    #[error("advance() called before start_dynamic()")]
    NotStarted,
    /// Invalid parameters (node grid, time step, density).
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
