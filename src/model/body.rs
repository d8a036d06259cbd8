//! A continuum body of either method (EFG or bilinear FE), and a borrowed
//! view of one that samples its true fields.

use crate::continuum::newmark::State;
use crate::continuum::{BodyState, Sample, StateError};
use crate::efg::assemble::PointShapes;
use crate::efg::{EfgBody, EfgError, ShapeRow};

/// An error of a body of either method.
#[derive(Debug, thiserror::Error)]
pub enum BodyError {
    /// From an EFG body.
    #[error(transparent)]
    Efg(#[from] EfgError),
    /// From an FE body.
    #[error(transparent)]
    Fem(#[from] FemError),
}

use crate::fem::body::Located;
use crate::fem::{FemBody, FemError};
use crate::geom::Vec2;

/// A continuum body of either method, driven the same way.
pub enum Body {
    /// An element-free Galerkin body.
    Efg(Box<EfgBody>),
    /// A bilinear (Q4) finite-element body.
    Fem(Box<FemBody>),
}

impl Body {
    /// Name (for messages and outputs).
    pub fn name(&self) -> &str {
        match self {
            Body::Efg(b) => &b.name,
            Body::Fem(b) => &b.name,
        }
    }
    /// Time reached.
    pub fn time(&self) -> f64 {
        match self {
            Body::Efg(b) => b.time,
            Body::Fem(b) => b.time,
        }
    }
    /// Static solve under the permanent and released loads (and the
    /// accumulated point loads); the state becomes `(U, 0, 0)`.
    pub fn solve_static(&mut self) -> Result<(), BodyError> {
        match self {
            Body::Efg(b) => Ok(b.solve_static_growing().map(drop)?),
            Body::Fem(b) => Ok(b.solve_static()?),
        }
    }
    /// Set Δt, factor the Newmark matrix once and compute the initial
    /// acceleration (ERRATA E8).
    pub fn start_dynamic(&mut self, dt: f64) -> Result<(), BodyError> {
        match self {
            Body::Efg(b) => Ok(b.start_dynamic(dt)?),
            Body::Fem(b) => Ok(b.start_dynamic(dt)?),
        }
    }
    /// One Newmark step with the permanent and accumulated point loads;
    /// then, for an EFG body with crack growth, the tips grow if due.
    pub fn advance(&mut self) -> Result<(), BodyError> {
        match self {
            Body::Efg(b) => {
                b.advance()?;
                Ok(b.grow_if_due(&[]).map(drop)?)
            }
            Body::Fem(b) => Ok(b.advance()?),
        }
    }
    /// Kinetic energy `½ U̇ᵀ M U̇`.
    pub fn kinetic_energy(&self) -> f64 {
        match self {
            Body::Efg(b) => b.kinetic_energy(),
            Body::Fem(b) => b.kinetic_energy(),
        }
    }
    /// Strain energy (EFG: including the penalty springs).
    pub fn strain_energy(&self) -> f64 {
        match self {
            Body::Efg(b) => b.strain_energy(),
            Body::Fem(b) => b.strain_energy(),
        }
    }
    /// Everything that changes while the body steps (checkpoint/restart).
    pub fn save_state(&self) -> BodyState {
        match self {
            Body::Efg(b) => b.save_state(),
            Body::Fem(b) => b.save_state(),
        }
    }
    /// Restore a [`save_state`](Self::save_state) of a body built from the
    /// same parameters (name and sizes checked).
    pub fn restore_state(&mut self, s: &BodyState) -> Result<(), StateError> {
        match self {
            Body::Efg(b) => b.restore_state(s),
            Body::Fem(b) => b.restore_state(s),
        }
    }
    /// Borrow as a [`BodyRef`].
    pub fn view(&self) -> BodyRef<'_> {
        match self {
            Body::Efg(b) => BodyRef::Efg(b),
            Body::Fem(b) => BodyRef::Fem(b),
        }
    }
}

/// A borrowed body of either method: what probes and frames need (the
/// bodies of a coupled model live inside it as
/// [`Continuum`](crate::continuum::Continuum)s).
#[derive(Clone, Copy)]
pub enum BodyRef<'a> {
    /// An EFG body.
    Efg(&'a EfgBody),
    /// An FE body.
    Fem(&'a FemBody),
}

impl<'a> BodyRef<'a> {
    /// Name (for messages and outputs).
    pub fn name(self) -> &'a str {
        match self {
            BodyRef::Efg(b) => &b.name,
            BodyRef::Fem(b) => &b.name,
        }
    }
    /// Kinetic energy `½ U̇ᵀ M U̇`.
    pub fn kinetic_energy(self) -> f64 {
        match self {
            BodyRef::Efg(b) => b.kinetic_energy(),
            BodyRef::Fem(b) => b.kinetic_energy(),
        }
    }
    /// Strain energy (EFG: including the penalty springs).
    pub fn strain_energy(self) -> f64 {
        match self {
            BodyRef::Efg(b) => b.strain_energy(),
            BodyRef::Fem(b) => b.strain_energy(),
        }
    }
    /// The Newmark integrator (a dynamic body).
    pub fn newmark(self) -> Option<&'a crate::continuum::newmark::Newmark> {
        match self {
            BodyRef::Efg(b) => b.newmark(),
            BodyRef::Fem(b) => b.newmark(),
        }
    }
    /// Number of nodes.
    pub fn n_nodes(self) -> usize {
        match self {
            BodyRef::Efg(b) => b.n_nodes(),
            BodyRef::Fem(b) => b.n_nodes(),
        }
    }
    /// How many times the body was rebuilt by crack growth: a point bound
    /// in another generation must be bound again.
    pub fn generation(self) -> usize {
        match self {
            BodyRef::Efg(b) => b.generation(),
            BodyRef::Fem(_) => 0,
        }
    }
    /// Bind a sampling point: a shape row (EFG) or an element (FE).
    pub fn bind(self, p: Vec2) -> Result<At, BodyError> {
        match self {
            BodyRef::Efg(b) => {
                let mut r = ShapeRow::new();
                b.shape_row(p, &mut r)?;
                Ok(At::Row(r))
            }
            BodyRef::Fem(b) => Ok(At::Element(b.locate(p)?)),
        }
    }
    /// The true fields at a point bound by [`bind`](Self::bind) on this
    /// same body (panics if bound by a body of the other method).
    pub fn sample_at(self, at: &At) -> Sample {
        match (self, at) {
            (BodyRef::Efg(b), At::Row(r)) => b.sample_row(r),
            (BodyRef::Fem(b), At::Element(l)) => b.sample_located(l),
            _ => unreachable!("a probe is bound by its own body"),
        }
    }
    /// The true fields at reference point `p` (displacement, velocity,
    /// strain, stress).
    pub fn sample(self, p: Vec2) -> Result<Sample, BodyError> {
        Ok(self.sample_at(&self.bind(p)?))
    }
    /// The Newmark state `U`, `U̇`, `Ü` (nodal parameters).
    pub fn state(self) -> &'a State {
        match self {
            BodyRef::Efg(b) => &b.state,
            BodyRef::Fem(b) => &b.state,
        }
    }
    /// Reference position of node `i`.
    pub fn node(self, i: usize) -> Vec2 {
        match self {
            BodyRef::Efg(b) => b.node(i),
            BodyRef::Fem(b) => b.node(i),
        }
    }
    /// The drives (prescribed components that change in time) with their
    /// component (0: x, 1: y), in build order.
    pub fn drives(self) -> Vec<(usize, crate::continuum::DriveState)> {
        match self {
            BodyRef::Efg(b) => b.drives().map(|(c, d)| (c, *d)).collect(),
            BodyRef::Fem(b) => b.drives.iter().map(|(c, d)| (*c, d.state)).collect(),
        }
    }
    /// Per-body data for frames: EFG nodal shape rows (FE needs none).
    pub fn frame_data(self) -> Result<Option<PointShapes>, BodyError> {
        match self {
            BodyRef::Efg(b) => Ok(Some(b.nodal_shapes()?)),
            BodyRef::Fem(_) => Ok(None),
        }
    }
}

/// A sampling point bound to a body.
#[derive(Debug)]
pub enum At {
    /// EFG: the shape functions `φ_J(x)` of the covering nodes.
    Row(ShapeRow),
    /// FE: the element and parent coordinates of the point.
    Element(Located),
}
