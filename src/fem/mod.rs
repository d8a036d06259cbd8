//! Bilinear finite elements on the EFG node grid, for the FE–DE comparison
//! of §4.2.1 (the mesh coincides with the EFG background grid).
//!
//! - [`q4`]: the element (shape functions, 2 × 2 Gauss stiffness, mass).
//! - [`body`]: [`FemBody`], built from a scenario `[[body]]` with
//!   `method = "fem-q4"`; prescribed displacements (fixed or moving)
//!   imposed exactly on nodes.
//! - [`boundary`]: [`FemContinuum`], the body as the coupling sees it
//!   (contact chains, element shape functions at contact points).

pub mod body;
pub mod boundary;
pub mod q4;

pub use body::FemBody;
pub use boundary::FemContinuum;

/// Errors of the FE continuum.
#[derive(Debug, thiserror::Error)]
pub enum FemError {
    /// A point asked for lies in no element.
    #[error("body `{body}`: the point {point:?} is outside the body")]
    Outside {
        /// Name of the body.
        body: String,
        /// The point (reference coordinates).
        point: [f64; 2],
    },
    /// A sparse factorisation or solve failed.
    #[error(transparent)]
    Solve(#[from] crate::sparse::SparseError),
    /// A step was asked for before [`FemBody::start_dynamic`].
    #[error("advance() called before start_dynamic()")]
    NotStarted,
    /// Invalid parameters (node grid, time step, density).
    #[error("{0}")]
    Invalid(String),
}
