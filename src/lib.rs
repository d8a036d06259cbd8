//! # efgdem — element-free Galerkin continua coupled with discrete elements
//!
//! A Rust implementation of Wang, Deng, Taheri & Ge (2020), *A mesh-free
//! approach for multiscale modeling in continuum–granular systems*, with the
//! corrections listed in `shared/paper/ERRATA.md` (tags E1–E13 in the doc
//! comments).
//!
//! Layout (one concept per module):
//! - [`geom`]: `Vec2` and point–segment queries.
//! - [`efg`]: the EFG continuum (weight, shape, support, quadrature, assembly).
//! - [`newmark`]: implicit Newmark time integration with a factor-once solve.
//! - [`dem`]: the discrete-element granular assembly.
//! - [`scenario`]: the TOML scenario format, validation with file:line errors.
//! - [`output`]: history CSV, ParaView files, summary JSON.
//! - [`run`]: runs a scenario end to end (what `efgdem run` does).

pub mod continuum;
pub mod coupling;
pub mod dem;
pub mod efg;
pub mod fem;
pub mod geom;
pub mod model;
pub mod output;
pub mod reproduce;
pub mod run;
pub mod scenario;
pub mod sparse;
pub mod study;

pub use geom::Vec2;
