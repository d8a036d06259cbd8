//! The evolving state of a [`Granular`] assembly, for checkpoint/restart.
//!
//! Saved: the clock; every disc's kinematics and last force in the present
//! slot order, with the slot → id map; the walls' positions, velocities
//! and forces (a servo or strain-rate wall keeps nothing else: its next
//! velocity follows from the next step's force and the walls' ends, and
//! a servo with integral action its integral velocity); the
//! contact list (pairs in their sorted order, shear and rolling histories,
//! disc–wall pairs) and the Verlet bookkeeping that
//! decides when the list is rebuilt and when the discs are renumbered
//! (positions at the last rebuild, rebuild counter, largest displacement
//! since); the parallel bonds ([`BondList`]: the intact bonds with their
//! forces, keyed by disc ids, and the broken ones); the clumps' rigid-body
//! state ([`ClumpState`]; their members and shapes are rebuilt). Restored onto an
//! assembly built from the same scenario, the
//! assembly then steps bitwise as the one the state was saved from: the
//! same pairs summed in the same order, the same rebuild steps.
//!
//! Not saved, because the build makes them the same again or each step
//! rewrites them before reading them: the discs' constants (radius, mass,
//! inertia, fixity, material — moved to the saved slot order on restore),
//! the contact laws and wall motions, the skin, the cross-pair index of
//! the sweep blocks and the pairs' `√m_eff` (recomputed from the pairs by
//! the code that built them), the grid's cells (rebuilt at each list
//! rebuild), per-step buffers, the external forces of the next step
//! (cleared by every step) and `store_forces` (the driver's choice).

use super::Granular;
use super::bonds::BondList;
use super::broadphase::WallPair;
use crate::continuum::StateError;
use crate::geom::Vec2;

/// A wall's moving state.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallState {
    /// First end.
    pub a: Vec2,
    /// Second end.
    pub b: Vec2,
    /// Velocity during the last step.
    pub vel: Vec2,
    /// Force of the discs in the last step.
    pub force: Vec2,
    /// Integral velocity of a servo with integral action.
    pub integral: f64,
}

impl From<&super::walls::Wall> for WallState {
    fn from(w: &super::walls::Wall) -> WallState {
        WallState {
            a: w.a,
            b: w.b,
            vel: w.vel,
            force: w.force,
            integral: w.integral,
        }
    }
}

/// A disc–wall pair with its histories (as [`WallPair`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallPairState {
    /// Slot of the disc.
    pub disc: u32,
    /// Index of the wall.
    pub wall: u32,
    /// Shear force history.
    pub fs: f64,
    /// Rolling-spring history.
    pub mr: f64,
}

/// The clumps' rigid-body state ([`super::clumps::Clumps`]), by clump.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClumpState {
    /// Centres of mass.
    pub pos: Vec<Vec2>,
    /// Velocities (half step).
    pub vel: Vec<Vec2>,
    /// Rotations.
    pub theta: Vec<f64>,
    /// Spins (half step).
    pub omega: Vec<f64>,
    /// Resultant forces of the last step.
    pub force: Vec<Vec2>,
    /// Resultant moments of the last step.
    pub torque: Vec<f64>,
}

/// Everything that changes while a [`Granular`] steps (module docs).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GranularState {
    /// Steps done.
    pub step: usize,
    /// Time reached.
    pub time: f64,
    /// Largest disc displacement since the last rebuild.
    pub max_disp: f64,
    /// Scenario id of the disc in each slot.
    pub id: Vec<u32>,
    /// Positions, by slot.
    pub pos: Vec<Vec2>,
    /// Velocities (half step), by slot.
    pub vel: Vec<Vec2>,
    /// Rotations, by slot.
    pub theta: Vec<f64>,
    /// Spins (half step), by slot.
    pub omega: Vec<f64>,
    /// Resultant forces of the last step that stored them, by slot.
    pub force: Vec<Vec2>,
    /// Resultant moments, by slot.
    pub torque: Vec<f64>,
    /// The walls, in scenario order.
    pub walls: Vec<WallState>,
    /// Listed disc–disc pairs `(i, j)`, `i < j` (slots), sorted.
    pub pairs: Vec<[u32; 2]>,
    /// Shear history of each pair.
    pub shear: Vec<f64>,
    /// Rolling resistance in use (the list keeps `roll`).
    pub rolling: bool,
    /// Rolling-spring history of each pair (empty without rolling).
    pub roll: Vec<f64>,
    /// Listed disc–wall pairs, sorted by `(disc, wall)`.
    pub wall_pairs: Vec<WallPairState>,
    /// Disc positions at the last rebuild (empty before the first).
    pub ref_pos: Vec<Vec2>,
    /// Walls' ends `[a, b]` at the last rebuild.
    pub wall_ref: Vec<[Vec2; 2]>,
    /// Rebuilds so far (every `reorder_every`-th renumbers the discs).
    pub rebuilds: usize,
    /// A rebuild is due before the next force computation.
    pub stale: bool,
    /// The parallel bonds (empty without bonds).
    pub bonds: BondList,
    /// The clumps (empty without clumps).
    pub clumps: ClumpState,
}

fn bad(m: String) -> StateError {
    StateError::new(m)
}

impl Granular {
    /// Everything that changes while the assembly steps
    /// ([`GranularState`]). Call between steps.
    pub fn save_state(&self) -> GranularState {
        let p = &self.particles;
        let c = &self.contacts;
        GranularState {
            step: self.step,
            time: self.time,
            max_disp: self.max_disp,
            id: p.id.clone(),
            pos: p.pos.clone(),
            vel: p.vel.clone(),
            theta: p.theta.clone(),
            omega: p.omega.clone(),
            force: p.force.clone(),
            torque: p.torque.clone(),
            walls: self.walls.iter().map(WallState::from).collect(),
            pairs: c.pairs().map(|(i, j)| [i as u32, j as u32]).collect(),
            shear: c.shear.clone(),
            rolling: c.rolling,
            roll: c.roll.clone(),
            wall_pairs: c
                .walls
                .iter()
                .map(|w| WallPairState {
                    disc: w.disc,
                    wall: w.wall,
                    fs: w.fs,
                    mr: w.mr,
                })
                .collect(),
            ref_pos: self.grid.ref_pos.clone(),
            wall_ref: self.grid.wall_ref.clone(),
            rebuilds: self.grid.rebuilds,
            stale: self.grid.stale,
            bonds: self.bonds.list().into_owned(),
            clumps: ClumpState {
                pos: self.clumps.by_id(&self.clumps.pos),
                vel: self.clumps.by_id(&self.clumps.vel),
                theta: self.clumps.by_id(&self.clumps.theta),
                omega: self.clumps.by_id(&self.clumps.omega),
                force: self.clumps.by_id(&self.clumps.force),
                torque: self.clumps.by_id(&self.clumps.torque),
            },
        }
    }

    /// Restore a [`save_state`](Self::save_state) of an assembly built
    /// from the same scenario: the discs are moved to the saved slots (in
    /// place: the arrays keep their buffers), their state and the contact
    /// list replaced. A state of another assembly (disc or wall count,
    /// rolling resistance, an inconsistent list) is refused and the
    /// assembly left unchanged. A part of a larger assembly (its discs
    /// indexed among the whole's ids, [`SlotIndex::of_part`]) takes the
    /// state of the same part: its discs by id, its pairs and wall pairs
    /// in its own slots.
    ///
    /// [`SlotIndex::of_part`]: super::particles::SlotIndex::of_part
    pub fn restore_state(&mut self, s: &GranularState) -> Result<(), StateError> {
        let order = self.check_discs(s)?;
        self.check_state(s)?;
        // move each disc's constants to its saved slot
        let p = &mut self.particles;
        p.permute(&order);
        p.pos.copy_from_slice(&s.pos);
        p.vel.copy_from_slice(&s.vel);
        p.theta.copy_from_slice(&s.theta);
        p.omega.copy_from_slice(&s.omega);
        p.force.copy_from_slice(&s.force);
        p.torque.copy_from_slice(&s.torque);
        self.restore_rest(s);
        Ok(())
    }

    /// [`restore_state`](Self::restore_state) of an assembly whose discs
    /// are in their saved slots with their saved values already (a part
    /// read from a checkpoint straight into place, without a second copy
    /// of its discs): all but the discs' arrays of `s` (not read; empty).
    pub fn restore_state_around_discs(&mut self, s: &GranularState) -> Result<(), StateError> {
        self.check_state(s)?;
        self.restore_rest(s);
        Ok(())
    }

    /// [`restore_state`](Self::restore_state) after the discs: walls,
    /// clock, contact list, Verlet bookkeeping, bonds, clumps.
    fn restore_rest(&mut self, s: &GranularState) {
        let n = self.particles.len();
        for (w, ws) in self.walls.iter_mut().zip(&s.walls) {
            (w.a, w.b, w.vel, w.force, w.integral) = (ws.a, ws.b, ws.vel, ws.force, ws.integral);
        }
        self.step = s.step;
        self.time = s.time;
        self.max_disp = s.max_disp;
        self.external.clear();
        self.last_check = None;
        let c = &mut self.contacts;
        let p = &self.particles;
        c.shear.clone_from(&s.shear);
        c.roll.clone_from(&s.roll);
        c.set_pairs(n, &s.pairs, p);
        c.walls.clear();
        c.walls.extend(s.wall_pairs.iter().map(|w| WallPair {
            disc: w.disc,
            wall: w.wall,
            fs: w.fs,
            mr: w.mr,
        }));
        c.wall_buf.clear();
        c.wall_buf.resize(c.walls.len(), Default::default());
        self.grid.ref_pos.clone_from(&s.ref_pos);
        self.grid.wall_ref.clone_from(&s.wall_ref);
        self.grid.rebuilds = s.rebuilds;
        self.grid.stale = s.stale;
        self.bonds.replace_list(&s.bonds);
        let c = &mut self.clumps;
        c.invalidate();
        c.pos = c.in_rows(&s.clumps.pos);
        c.vel = c.in_rows(&s.clumps.vel);
        c.theta = c.in_rows(&s.clumps.theta);
        c.omega = c.in_rows(&s.clumps.omega);
        c.force = c.in_rows(&s.clumps.force);
        c.torque = c.in_rows(&s.clumps.torque);
        c.refresh_rotations();
    }

    /// Do the discs of `s` fit this assembly? (Their count, the ids those
    /// of the discs held, each once.) The present slot of the disc of
    /// each saved slot.
    fn check_discs(&self, s: &GranularState) -> Result<Vec<u32>, StateError> {
        let n = self.particles.len();
        if s.id.len() != n {
            return Err(bad(format!(
                "the saved state has {} discs, the model {n}",
                s.id.len()
            )));
        }
        for (what, len) in [
            ("positions", s.pos.len()),
            ("velocities", s.vel.len()),
            ("rotations", s.theta.len()),
            ("spins", s.omega.len()),
            ("forces", s.force.len()),
            ("moments", s.torque.len()),
        ] {
            if len != n {
                return Err(bad(format!("{len} saved disc {what} for {n} discs")));
            }
        }
        self.slots_of(&s.id)
    }

    /// Does the rest of `s` fit this assembly? (Sizes, sorted pairs in
    /// range.)
    fn check_state(&self, s: &GranularState) -> Result<(), StateError> {
        let n = self.particles.len();
        let nw = self.walls.len();
        if s.walls.len() != nw {
            return Err(bad(format!(
                "the saved state has {} walls, the model {nw}",
                s.walls.len()
            )));
        }
        if s.rolling != self.contacts.rolling {
            return Err(bad(format!(
                "the saved state was made {} rolling resistance, the model has {}",
                if s.rolling { "with" } else { "without" },
                if self.contacts.rolling { "it" } else { "none" }
            )));
        }
        let np = s.pairs.len();
        if s.shear.len() != np || !(s.roll.is_empty() || s.roll.len() == np) {
            return Err(bad("the saved pair histories do not match the pairs".into()));
        }
        let pairs_ok = s.pairs.iter().all(|&[i, j]| i < j && (j as usize) < n)
            && s.pairs.windows(2).all(|w| w[0] < w[1]);
        let walls_ok = s
            .wall_pairs
            .iter()
            .all(|w| (w.disc as usize) < n && (w.wall as usize) < nw)
            && s.wall_pairs
                .windows(2)
                .all(|w| (w[0].disc, w[0].wall) < (w[1].disc, w[1].wall));
        if !pairs_ok || !walls_ok {
            return Err(bad(
                "the saved contact list is not sorted or out of range".into()
            ));
        }
        if s.bonds.created && !self.bonds.active() {
            return Err(bad(
                "the saved state has parallel bonds, the model has no bond rule".into(),
            ));
        }
        s.bonds
            .check(n)
            .map_err(|e| bad(format!("the saved bonds: {e}")))?;
        let nc = self.clumps.len();
        let c = &s.clumps;
        if [c.pos.len(), c.vel.len(), c.force.len()]
            .into_iter()
            .chain([c.theta.len(), c.omega.len(), c.torque.len()])
            .any(|len| len != nc)
        {
            return Err(bad(format!(
                "the saved state has {} clumps, the model {nc}",
                c.pos.len()
            )));
        }
        if !(s.ref_pos.is_empty() || s.ref_pos.len() == n)
            || !(s.wall_ref.is_empty() || s.wall_ref.len() == nw)
        {
            return Err(bad(
                "the saved Verlet reference does not match the discs or walls".into(),
            ));
        }
        Ok(())
    }

    /// The present slot of each disc `ids`, if they are those the assembly
    /// holds (all of the whole's, or a part's), each once.
    fn slots_of(&self, ids: &[u32]) -> Result<Vec<u32>, StateError> {
        let p = &self.particles;
        let n = p.len();
        let mut seen = vec![false; n];
        ids.iter()
            .map(|&id| match p.slot.get(id as usize) {
                Some(&k) if (k as usize) < n && !std::mem::replace(&mut seen[k as usize], true) => {
                    Ok(k)
                }
                _ => Err(bad(
                    "the saved disc ids are not those of the discs held".into()
                )),
            })
            .collect()
    }
}
