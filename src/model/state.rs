//! A complete snapshot of a [`Model`]'s evolving state, for
//! checkpoint/restart: a run of N steps and a run of k steps, saved,
//! restored onto a model built afresh from the same scenario and stepped
//! N − k more, end bitwise equal (on any number of threads).
//!
//! What is saved per kind ([`SystemState`]):
//! - granular: [`GranularState`] — discs in their slot order with the
//!   slot → id map, walls, the contact list with its shear and rolling
//!   histories, the Verlet bookkeeping (reference positions, rebuild
//!   counter, stale flag, largest displacement), parallel bonds, clumps, clock;
//! - continuum: each body's [`BodyState`] — `U`, `U̇`, `Ü`, clock, pending
//!   point loads, work of moving edges, drives (position, velocity, servo
//!   integral, last measurement), work of timed loads, FE support
//!   reactions;
//! - coupled: [`CoupledState`] — the granular state, each body's state with
//!   its boundary Green matrix's DOFs (batch by batch), the disc–body
//!   contacts with their histories and forces, the scheme's counters.
//!
//! What is not: whatever `Scenario::build` computes again from the same
//! scenario, bit for bit (materials and laws, matrices and their factors,
//! shape functions, the discs' radii and masses, prescribed motions, which
//! are functions of the step), and what each step rewrites before reading
//! (scratch buffers, segment grids, timing).
//!
//! [`ModelState::to_bytes`] writes [`STATE_FORMAT_VERSION`] (4 bytes,
//! little endian), the state in the `postcard` format (f64 as their 8
//! bytes: exact) and a CRC-32 of all that (4 bytes, little endian), so
//! that damaged bytes (any single flipped bit, a cut) are refused by
//! [`ModelState::from_bytes`] instead of restored.

use super::{Model, ModelError, System};
use crate::continuum::{BodyState, StateError};
use crate::coupling::state::CoupledState;
use crate::dem::state::GranularState;

/// Version of the byte format of [`ModelState::to_bytes`]; raised whenever
/// a saved type changes.
/// (2: walls keep both ends of the Verlet reference, for joined ends;
/// 3: walls keep the integral velocity of a servo with integral action;
/// 4: bodies keep their drives' state and the work of timed loads;
/// 5: a CRC-32 of the bytes at their end;
/// 6: the compliant sub-cycled scheme's boundary path, the sub-cycling
/// energy guard's count;
/// 7: the granular state keeps the parallel bonds;
/// 8: the coupled state records the automatic scheme's fallback;
/// 9: the granular state keeps the clumps;
/// 10: EFG bodies keep their grown cracks and their faces' friction;
/// 11: the automatic scheme's fallback records the substeps taken on.)
pub const STATE_FORMAT_VERSION: u32 = 11;

/// The evolving state of a model ([module docs](self)).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ModelState {
    /// Steps taken ([`Model::step`]).
    pub step: usize,
    /// The state of what is simulated.
    pub system: SystemState,
}

/// The state of a [`System`] of each kind.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum SystemState {
    /// Continuum bodies, in scenario order.
    Continuum(Vec<BodyState>),
    /// Discs and walls.
    Granular(Box<GranularState>),
    /// Bodies and discs coupled.
    Coupled(Box<CoupledState>),
}

impl SystemState {
    /// The kind, for messages.
    fn kind(&self) -> &'static str {
        match self {
            SystemState::Continuum(_) => "continuum",
            SystemState::Granular(_) => "granular",
            SystemState::Coupled(_) => "coupled",
        }
    }
}

impl ModelState {
    /// The state as bytes: [`STATE_FORMAT_VERSION`] (u32, little endian),
    /// the `postcard` encoding, the CRC-32 of both (u32, little endian).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = STATE_FORMAT_VERSION.to_le_bytes().to_vec();
        // postcard cannot fail on these types (no maps, no unsized data)
        postcard::to_io(self, &mut out).expect("postcard encodes a model state");
        out.extend_from_slice(&crc32fast::hash(&out).to_le_bytes());
        out
    }

    /// A state from [`to_bytes`](Self::to_bytes); refused when the version
    /// differs, the checksum does not match (damaged or cut bytes), the
    /// bytes are malformed, or bytes are left over.
    pub fn from_bytes(bytes: &[u8]) -> Result<ModelState, StateError> {
        let Some((head, _)) = bytes.split_first_chunk::<4>() else {
            return Err(StateError::new("a model state of fewer than 4 bytes"));
        };
        let version = u32::from_le_bytes(*head);
        if version != STATE_FORMAT_VERSION {
            return Err(StateError::new(format!(
                "a model state of format version {version}; this build reads version {STATE_FORMAT_VERSION}"
            )));
        }
        let Some((content, crc)) = bytes.split_last_chunk::<4>().filter(|(c, _)| c.len() >= 4)
        else {
            return Err(StateError::new("a model state cut short"));
        };
        if crc32fast::hash(content) != u32::from_le_bytes(*crc) {
            return Err(StateError::new(
                "a damaged model state: its bytes do not match their checksum (altered or cut short since save_state)",
            ));
        }
        let (s, rest) = postcard::take_from_bytes::<ModelState>(&content[4..])
            .map_err(|e| StateError::new(format!("a malformed model state: {e}")))?;
        if !rest.is_empty() {
            return Err(StateError::new(format!(
                "a model state with {} bytes left over",
                rest.len()
            )));
        }
        Ok(s)
    }
}

impl Model {
    /// Everything that changes while the model steps ([`ModelState`]).
    /// Call between steps, with the bodies settled: after
    /// [`step_deferring`](Model::step_deferring), call
    /// [`settle`](Model::settle) first (a state without the pending body
    /// ends would not continue the run; asserted).
    pub fn save_state(&self) -> ModelState {
        if let System::Coupled(m) = &self.system {
            assert!(
                m.is_settled(),
                "save_state after step_deferring: call Model::settle first"
            );
        }
        let system = match &self.system {
            System::Continuum { bodies, .. } => {
                SystemState::Continuum(bodies.iter().map(|b| b.save_state()).collect())
            }
            System::Granular(g) => SystemState::Granular(Box::new(g.save_state())),
            System::Coupled(m) => SystemState::Coupled(Box::new(m.save_state())),
        };
        ModelState {
            step: self.step,
            system,
        }
    }

    /// Restore a [`save_state`](Self::save_state) onto a model built from
    /// the same scenario (freshly, or stepped: it does not matter). The
    /// model then steps bitwise as the one the state was saved from. A
    /// state of another kind or of other sizes (discs, walls, bodies and
    /// their DOFs) is refused with [`ModelError::State`], and the model is
    /// left as it was.
    pub fn restore_state(&mut self, s: &ModelState) -> Result<(), ModelError> {
        let kind = |sys: &System| match sys {
            System::Continuum { .. } => "continuum",
            System::Granular(_) => "granular",
            System::Coupled(_) => "coupled",
        };
        let (have, want) = (kind(&self.system), s.system.kind());
        if have != want {
            return Err(StateError::new(format!(
                "a {want} model's state cannot be restored onto a {have} model"
            ))
            .into());
        }
        let backup = self.save_state();
        if let Err(e) = self.restore_parts(s) {
            // put back what was restored before the part that refused
            let _ = self.restore_parts(&backup);
            return Err(e.into());
        }
        Ok(())
    }

    fn restore_parts(&mut self, s: &ModelState) -> Result<(), StateError> {
        match (&mut self.system, &s.system) {
            (System::Continuum { bodies, .. }, SystemState::Continuum(saved)) => {
                if saved.len() != bodies.len() {
                    return Err(StateError::new(format!(
                        "the saved state has {} bodies, the model {}",
                        saved.len(),
                        bodies.len()
                    )));
                }
                for (b, bs) in bodies.iter_mut().zip(saved) {
                    b.restore_state(bs)?;
                }
            }
            (System::Granular(g), SystemState::Granular(gs)) => g.restore_state(gs)?,
            (System::Coupled(m), SystemState::Coupled(cs)) => m.restore_state(cs)?,
            _ => unreachable!("kinds checked by restore_state"),
        }
        self.step = s.step;
        Ok(())
    }
}
