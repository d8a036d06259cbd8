//! The element-free Galerkin continuum (§2.1–2.2 of the paper).

pub mod run;

/// Errors of the EFG continuum.
#[derive(Debug, thiserror::Error)]
pub enum EfgError {
    #[error("EFG bodies are not implemented yet")]
    NotImplemented,
}
