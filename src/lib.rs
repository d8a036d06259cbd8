//! # efgdem — element-free Galerkin continua coupled with discrete elements
//!
//! A Rust implementation of Wang, Deng, Taheri & Ge (2020), *A mesh-free
//! approach for multiscale modeling in continuum–granular systems*, with the
//! the paper's misprints corrected: the doc comments cite each correction by
//! its tag ("ERRATA E1" … "E13"), explained in the manual's theory page,
//! `docs/theory.md#errata` (anchors `#e1` … `#e13`).
//!
//! ## A disc on a beam, in code
//!
//! Build a scenario (the same one a TOML file describes, with the same
//! defaults and checks), build the model, step it and read the state:
//!
//! ```
//! use efgdem::scenario::Scenario;
//! use efgdem::scenario::body::{BcSpec, BodySpec, Edge, Elastic};
//! use efgdem::scenario::Material;
//! use std::ops::ControlFlow;
//!
//! let beam = BodySpec::new("beam", [0.0, -0.1], [1.0, 0.2], [20, 4],
//!         Elastic::new(2.1e8, 0.3).density(2000.0).thickness(0.025))
//!     .bc(BcSpec::fixed(Edge::Left))
//!     .self_weight(false);
//! let scenario = Scenario::new()
//!     .dt(1e-4)
//!     .end_time(0.12)
//!     .gravity(0.0, -9.81)
//!     .add_material(Material::new("disc", 1000.0, 1e6, 1e6).friction(0.5))
//!     .discs("disc", &[[0.9, 0.2, 0.05]])
//!     .add_body(beam);
//! let mut model = scenario.build().expect("a valid scenario");
//!
//! // fall 0.05 m onto the beam: first contact after √(2 · 0.05 / g) ≈ 0.101 s
//! let mut first_contact = None;
//! model.run_until(0.12, |m| {
//!     if first_contact.is_none() && !m.contacts().is_empty() {
//!         first_contact = Some(m.time());
//!     }
//!     ControlFlow::Continue(())
//! })?;
//! let t = first_contact.expect("the disc reaches the beam");
//! assert!((t - 0.101).abs() < 2e-3, "first contact at {t}");
//!
//! // the beam's tip has moved down, the disc is where the discs are
//! let tip = model.body(0).sample(efgdem::Vec2::new(1.0, 0.1))?;
//! assert!(tip.u.y < 0.0);
//! let discs = model.granular().expect("discs");
//! assert_eq!(discs.particles.len(), 1);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Files: [`scenario::load`] reads a TOML scenario (errors read
//! `file:line: field: message`); [`run::run`] runs it end to end and writes
//! what `efgdem run` writes; [`output`] has the writers.
//!
//! ## Layers
//! Each module uses only the ones above it in this list (checked by
//! `tests/layering.rs`):
//! 1. [`geom`], [`sparse`]: points, segments; sparse Cholesky (faer).
//! 2. [`continuum`]: what EFG and FE bodies share — body parameters, edge
//!    conditions, material, quadrature, Newmark, the boundary Green matrix
//!    and the [`continuum::Continuum`] trait the coupling talks to.
//! 3. [`efg`], [`fem`], [`dem`]: the physics (plain parameters in, state
//!    out; no files).
//! 4. [`coupling`]: disc–boundary contacts, through `Continuum` only.
//!    [`decomp`]: a granular assembly divided over ranks (MPI), bitwise
//!    equal to the whole.
//! 5. [`model`]: the [`model::Model`] users step and read.
//! 6. [`scenario`]: the TOML format — parse, validate, build a `Model`.
//! 7. [`output`]: history CSV, ParaView files, JSON, plots, progress.
//! 8. [`run`], then [`study`], [`reproduce`], [`biaxial`] and [`geotech`]: drivers and
//!    post-processing.

#![warn(missing_docs)]

pub mod biaxial;
pub mod continuum;
pub mod coupling;
pub mod decomp;
pub mod dem;
pub mod efg;
pub mod fem;
pub mod geom;
pub mod geotech;
pub mod model;
pub mod output;
pub mod reproduce;
pub mod run;
pub mod scenario;
pub mod sparse;
pub mod strict;
pub mod study;

pub use geom::Vec2;
pub use model::Model;
pub use scenario::Scenario;
