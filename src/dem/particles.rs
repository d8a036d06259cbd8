//! Discs in structure-of-arrays form (§2.3 of the paper).
//!
//! Each quantity is its own array, indexed by the disc's *slot*. Planar
//! vectors are stored as [`Vec2`] (x and y side by side: the contact kernel
//! always reads both). Slots are permuted from time to time so that discs
//! close in space are close in memory (see [`Particles::permute`]); the
//! scenario's numbering is kept in [`Particles::id`] and its inverse
//! [`Particles::slot`].

use crate::geom::Vec2;

/// Fixity flag: the x velocity is prescribed (not changed by forces).
pub const FIX_X: u8 = 1;
/// Fixity flag: the y velocity is prescribed.
pub const FIX_Y: u8 = 2;
/// Fixity flag: the spin is prescribed (rotation locked when it is zero).
pub const FIX_ROT: u8 = 4;
/// Flag: the slot holds a *ghost*, a copy of a disc that another part of
/// a decomposed assembly advances. Its contacts with the other discs are
/// evaluated (for their sake) but it is not advanced, takes no part in
/// the displacement and stability checks, has no wall contacts, and two
/// ghosts are never paired.
pub const GHOST: u8 = 8;
/// Flag, set only within one step: the disc is *held* — its contacts are
/// summed in the sweep but it is advanced after it, once forces still
/// being computed beside the sweep are known ([`super::Granular::hold`]).
pub const HELD: u8 = 16;

/// The discs of a granular assembly.
#[derive(Debug, Clone, Default)]
pub struct Particles {
    /// Centre position at time t (after a step: t + Δt).
    pub pos: Vec<Vec2>,
    /// Velocity at the half step t − Δt/2 (Eq. 53).
    pub vel: Vec<Vec2>,
    /// Rotation θ (Eq. 51).
    pub theta: Vec<f64>,
    /// Spin ω at the half step (Eq. 54), counter-clockwise positive.
    pub omega: Vec<f64>,
    /// Radius r.
    pub radius: Vec<f64>,
    /// m = ρ π r² t.
    pub mass: Vec<f64>,
    /// I = m r² / 2 (a solid cylinder about its axis).
    pub inertia: Vec<f64>,
    /// 1/m (0 for an immovable disc).
    pub inv_mass: Vec<f64>,
    /// 1/I.
    pub inv_inertia: Vec<f64>,
    /// Resultant force of the current step (contacts + external; gravity is
    /// added during integration).
    pub force: Vec<Vec2>,
    /// Resultant moment about the centre (ERRATA E12).
    pub torque: Vec<f64>,
    /// Bit set of [`FIX_X`], [`FIX_Y`], [`FIX_ROT`].
    pub fixity: Vec<u8>,
    /// Index into the assembly's material table.
    pub material: Vec<u16>,
    /// Scenario number (0-based) of the disc in each slot.
    pub id: Vec<u32>,
    /// Slot of each scenario disc: `slot[id[k]] == k` (sparse in a part
    /// of a larger assembly: [`SlotIndex`]).
    pub slot: SlotIndex,
    /// Clump of the disc in each slot ([`super::clumps::NO_CLUMP`]: none).
    pub clump: Vec<u32>,
}

impl Particles {
    /// Number of discs.
    pub fn len(&self) -> usize {
        self.pos.len()
    }
    /// No discs.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }
    /// Is the disc in `slot` a [`GHOST`] (another part's disc)?
    pub fn is_ghost(&self, slot: usize) -> bool {
        self.fixity[slot] & GHOST != 0
    }
    /// The slot of disc `id` if this assembly holds it as its own (not
    /// as a ghost).
    pub fn own_slot(&self, id: usize) -> Option<usize> {
        let s = *self.slot.get(id)? as usize;
        (s < self.len() && !self.is_ghost(s)).then_some(s)
    }

    /// No discs, with room for `n` (an assembly's arrays are then
    /// allocated once, at their size: no growth by doubling, whose copies
    /// would set the peak memory of a large model's build).
    pub fn with_capacity(n: usize) -> Self {
        Particles {
            pos: Vec::with_capacity(n),
            vel: Vec::with_capacity(n),
            theta: Vec::with_capacity(n),
            omega: Vec::with_capacity(n),
            radius: Vec::with_capacity(n),
            mass: Vec::with_capacity(n),
            inertia: Vec::with_capacity(n),
            inv_mass: Vec::with_capacity(n),
            inv_inertia: Vec::with_capacity(n),
            force: Vec::with_capacity(n),
            torque: Vec::with_capacity(n),
            fixity: Vec::with_capacity(n),
            material: Vec::with_capacity(n),
            id: Vec::with_capacity(n),
            slot: SlotIndex::with_capacity(n),
            clump: Vec::with_capacity(n),
        }
    }

    /// Room for `n` more discs in every array, or the allocation error
    /// (a run too large for the memory it may use is refused with it
    /// instead of aborting the process).
    pub fn try_reserve(&mut self, n: usize) -> Result<(), std::collections::TryReserveError> {
        self.pos.try_reserve_exact(n)?;
        self.vel.try_reserve_exact(n)?;
        self.theta.try_reserve_exact(n)?;
        self.omega.try_reserve_exact(n)?;
        self.radius.try_reserve_exact(n)?;
        self.mass.try_reserve_exact(n)?;
        self.inertia.try_reserve_exact(n)?;
        self.inv_mass.try_reserve_exact(n)?;
        self.inv_inertia.try_reserve_exact(n)?;
        self.force.try_reserve_exact(n)?;
        self.torque.try_reserve_exact(n)?;
        self.fixity.try_reserve_exact(n)?;
        self.material.try_reserve_exact(n)?;
        self.id.try_reserve_exact(n)?;
        self.clump.try_reserve_exact(n)?;
        self.slot.try_reserve_exact(n)
    }

    /// Mass `m = ρ π r² t` and moment of inertia `I = m r²/2` of a disc of
    /// radius `r`, density `rho` and thickness `thickness`.
    pub fn mass_of(r: f64, rho: f64, thickness: f64) -> (f64, f64) {
        let m = rho * std::f64::consts::PI * r * r * thickness;
        (m, 0.5 * m * r * r)
    }

    /// Append a disc of radius `r`, density `rho` and thickness `t` at rest
    /// ([`mass_of`](Self::mass_of)).
    pub fn push(&mut self, pos: Vec2, r: f64, rho: f64, thickness: f64, material: u16) {
        let (m, inertia) = Self::mass_of(r, rho, thickness);
        let k = self.len() as u32;
        self.pos.push(pos);
        self.vel.push(Vec2::ZERO);
        self.theta.push(0.0);
        self.omega.push(0.0);
        self.radius.push(r);
        self.mass.push(m);
        self.inertia.push(inertia);
        self.inv_mass.push(if m > 0.0 { 1.0 / m } else { 0.0 });
        self.inv_inertia
            .push(if inertia > 0.0 { 1.0 / inertia } else { 0.0 });
        self.force.push(Vec2::ZERO);
        self.torque.push(0.0);
        self.fixity.push(0);
        self.material.push(material);
        self.id.push(k);
        self.slot.push(k);
        self.clump.push(super::clumps::NO_CLUMP);
    }

    /// Largest radius (0 when empty).
    pub fn max_radius(&self) -> f64 {
        self.radius.iter().copied().fold(0.0, f64::max)
    }

    /// Smallest mass among discs that move.
    pub fn min_mass(&self) -> f64 {
        self.mass
            .iter()
            .copied()
            .filter(|&m| m > 0.0)
            .fold(f64::INFINITY, f64::min)
    }

    /// Reorder slots: the disc now in slot `k` is the one that was in slot
    /// `order[k]`. Returns `new_slot_of_old` (the inverse permutation), which
    /// callers use to remap contact keys. The arrays are permuted in place:
    /// their buffers keep their address for the life of the assembly (the
    /// Python bindings hand out zero-copy views of them).
    pub fn permute(&mut self, order: &[u32]) -> Vec<u32> {
        fn apply<T: Copy>(v: &mut [T], order: &[u32]) {
            let out: Vec<T> = order.iter().map(|&o| v[o as usize]).collect();
            v.copy_from_slice(&out);
        }
        apply(&mut self.pos, order);
        apply(&mut self.vel, order);
        apply(&mut self.theta, order);
        apply(&mut self.omega, order);
        apply(&mut self.radius, order);
        apply(&mut self.mass, order);
        apply(&mut self.inertia, order);
        apply(&mut self.inv_mass, order);
        apply(&mut self.inv_inertia, order);
        apply(&mut self.force, order);
        apply(&mut self.torque, order);
        apply(&mut self.fixity, order);
        apply(&mut self.material, order);
        apply(&mut self.id, order);
        apply(&mut self.clump, order);
        let mut new_of_old = vec![0u32; order.len()];
        for (k, &o) in order.iter().enumerate() {
            new_of_old[o as usize] = k as u32;
        }
        for (k, &id) in self.id.iter().enumerate() {
            self.slot[id as usize] = k as u32;
        }
        new_of_old
    }

    /// Copy the discs in `slots` (in that order) into `out`, replacing its
    /// discs: a view of a few discs (their slot index left empty, their
    /// clump fields dropped). `out`'s buffers are reused.
    pub fn select_into(&self, slots: &[u32], out: &mut Particles) {
        fn pick<T: Copy>(from: &[T], slots: &[u32], to: &mut Vec<T>) {
            to.clear();
            to.extend(slots.iter().map(|&s| from[s as usize]));
        }
        pick(&self.pos, slots, &mut out.pos);
        pick(&self.vel, slots, &mut out.vel);
        pick(&self.theta, slots, &mut out.theta);
        pick(&self.omega, slots, &mut out.omega);
        pick(&self.radius, slots, &mut out.radius);
        pick(&self.mass, slots, &mut out.mass);
        pick(&self.inertia, slots, &mut out.inertia);
        pick(&self.inv_mass, slots, &mut out.inv_mass);
        pick(&self.inv_inertia, slots, &mut out.inv_inertia);
        pick(&self.force, slots, &mut out.force);
        pick(&self.torque, slots, &mut out.torque);
        pick(&self.fixity, slots, &mut out.fixity);
        pick(&self.material, slots, &mut out.material);
        pick(&self.id, slots, &mut out.id);
        out.slot = SlotIndex::default();
        out.clump.clear();
    }

    /// Release the arrays' spare capacity (an assembly's discs are all
    /// pushed before it starts; [`permute`](Self::permute) keeps the
    /// buffers as they are).
    pub fn shrink_to_fit(&mut self) {
        self.pos.shrink_to_fit();
        self.vel.shrink_to_fit();
        self.theta.shrink_to_fit();
        self.omega.shrink_to_fit();
        self.radius.shrink_to_fit();
        self.mass.shrink_to_fit();
        self.inertia.shrink_to_fit();
        self.inv_mass.shrink_to_fit();
        self.inv_inertia.shrink_to_fit();
        self.force.shrink_to_fit();
        self.torque.shrink_to_fit();
        self.fixity.shrink_to_fit();
        self.material.shrink_to_fit();
        self.id.shrink_to_fit();
        self.slot.shrink_to_fit();
        self.clump.shrink_to_fit();
    }

    /// Bytes held by the per-disc arrays (capacity, not length).
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        self.pos.capacity() * size_of::<Vec2>() * 3
            + self.theta.capacity() * size_of::<f64>() * 8
            + self.fixity.capacity()
            + self.material.capacity() * 2
            + self.id.capacity() * 4 * 2
            + self.slot.heap_bytes()
    }
}

/// The slot of each disc id ([`Particles::slot`]), [`ABSENT`] for an id
/// the assembly does not hold. *Dense*, a slot per id (an assembly's own
/// numbering, or its ids pushed in order); or *sparse*, for a part of a
/// larger assembly whose ids it holds only some of
/// ([`of_part`](Self::of_part)): a bit per id of the whole with a count
/// per 64 ids, and a slot per id held (about 4.2 bytes per disc held and
/// 0.2 per disc of the whole, against 4 per disc of the whole).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SlotIndex {
    /// Dense: the slot of each id. Sparse: the slot of each id held, in
    /// id order.
    slots: Vec<u32>,
    /// Sparse: whether each id of the whole is held, 64 to a word.
    held: Vec<u64>,
    /// Sparse: how many ids are held before each word of `held`.
    before: Vec<u32>,
    /// Sparse: the ids of the whole (dense: `slots.len()`).
    ids: usize,
    sparse: bool,
}

/// The slot of an id the assembly does not hold.
pub const ABSENT: u32 = u32::MAX;

impl SlotIndex {
    /// The sparse index of a part holding the discs `id` (slot by slot)
    /// of an assembly of `n_total` discs.
    pub fn of_part(n_total: usize, id: &[u32]) -> SlotIndex {
        let words = n_total.div_ceil(64);
        let mut held = vec![0u64; words];
        for &i in id {
            held[i as usize / 64] |= 1 << (i % 64);
        }
        let mut before = Vec::with_capacity(words);
        let mut count = 0u32;
        for w in &held {
            before.push(count);
            count += w.count_ones();
        }
        let mut x = SlotIndex {
            slots: vec![ABSENT; id.len()],
            held,
            before,
            ids: n_total,
            sparse: true,
        };
        for (s, &i) in id.iter().enumerate() {
            let k = x.rank(i as usize).expect("a held id");
            x.slots[k] = s as u32;
        }
        x
    }

    /// Where in `slots` the slot of `id` is.
    #[inline]
    fn rank(&self, id: usize) -> Option<usize> {
        if !self.sparse {
            return (id < self.slots.len()).then_some(id);
        }
        let w = *self.held.get(id / 64)?;
        let bit = 1u64 << (id % 64);
        (w & bit != 0)
            .then(|| self.before[id / 64] as usize + (w & (bit - 1)).count_ones() as usize)
    }

    /// The slot of `id`: `None` beyond the ids, or for an id a part does
    /// not hold (a dense index gives [`ABSENT`] for those).
    #[inline]
    pub fn get(&self, id: usize) -> Option<&u32> {
        self.rank(id).map(|k| &self.slots[k])
    }

    /// Number of ids covered (a part's: those of its whole).
    pub fn len(&self) -> usize {
        if self.sparse {
            self.ids
        } else {
            self.slots.len()
        }
    }

    /// No ids.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The slots of the ids held, in id order.
    pub fn iter(&self) -> std::slice::Iter<'_, u32> {
        self.slots.iter()
    }

    /// An empty dense index with room for `n` ids.
    pub fn with_capacity(n: usize) -> SlotIndex {
        SlotIndex {
            slots: Vec::with_capacity(n),
            ..SlotIndex::default()
        }
    }

    /// Append the slot of the next id (a dense index).
    pub fn push(&mut self, slot: u32) {
        assert!(!self.sparse, "a part's slot index is made whole");
        self.slots.push(slot);
    }

    /// Room for `n` more ids (a dense index).
    pub fn try_reserve_exact(&mut self, n: usize) -> Result<(), std::collections::TryReserveError> {
        self.slots.try_reserve_exact(n)
    }

    /// Release spare capacity.
    pub fn shrink_to_fit(&mut self) {
        self.slots.shrink_to_fit();
    }

    /// Bytes held (capacity).
    pub fn heap_bytes(&self) -> usize {
        self.slots.capacity() * 4 + self.held.capacity() * 8 + self.before.capacity() * 4
    }
}

impl std::ops::Index<usize> for SlotIndex {
    type Output = u32;
    /// The slot of `id` ([`ABSENT`] for an id a part does not hold).
    #[inline]
    fn index(&self, id: usize) -> &u32 {
        match self.rank(id) {
            Some(k) => &self.slots[k],
            None if self.sparse && id < self.ids => &ABSENT,
            None => panic!("disc id {id} beyond the {} ids", self.len()),
        }
    }
}

impl std::ops::IndexMut<usize> for SlotIndex {
    /// The slot of `id`, which the index holds.
    #[inline]
    fn index_mut(&mut self, id: usize) -> &mut u32 {
        let k = self
            .rank(id)
            .unwrap_or_else(|| panic!("disc id {id} is not held here"));
        &mut self.slots[k]
    }
}

impl<const N: usize> PartialEq<[u32; N]> for SlotIndex {
    fn eq(&self, other: &[u32; N]) -> bool {
        !self.sparse && self.slots == other
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permute_reorders_in_place() {
        let mut p = Particles::default();
        for k in 0..5 {
            p.push(Vec2::new(k as f64, 0.0), 1.0 + k as f64, 1.0, 1.0, 0);
        }
        p.shrink_to_fit();
        let (pos, id, radius) = (p.pos.as_ptr(), p.id.as_ptr(), p.radius.as_ptr());
        let new_of_old = p.permute(&[3, 0, 4, 1, 2]);
        assert_eq!(p.id, [3, 0, 4, 1, 2]);
        assert_eq!(p.pos[0], Vec2::new(3.0, 0.0));
        assert_eq!(p.radius[2], 5.0);
        assert_eq!(new_of_old, [1, 3, 4, 0, 2]);
        assert_eq!(p.slot, [1, 3, 4, 0, 2]);
        // the buffers stay where they were (zero-copy views rely on it)
        assert_eq!(
            (p.pos.as_ptr(), p.id.as_ptr(), p.radius.as_ptr()),
            (pos, id, radius)
        );
    }
}
