//! The element-free Galerkin continuum (§2.1–2.2 of the paper).

pub mod run;

/// Errors of the DEM.
#[derive(Debug, thiserror::Error)]
pub enum DemError {
    #[error("DEM assemblies are not implemented yet")]
    NotImplemented,
}
