//! A granular run restarted on several ranks: each rank reads of the
//! checkpoint only its part — the regions are cut from the positions at
//! the sample stride, as a fresh division of the restored whole cuts them
//! ([`Cut::new`]), then each rank passes over the positions to find the
//! discs it holds and reads only their other values, and only the pairs
//! with a disc of its region. The part is bitwise the share
//! [`Decomposed::new`] takes of the whole restored on every rank.

use super::layout::{Arrays, Col, Raw};
use super::{Checkpoint, Opened};
use crate::decomp::{Comm, Cut, Decomposed, sample_stride};
use crate::dem::Granular;
use crate::dem::particles::{Particles, SlotIndex};
use crate::dem::state::{GranularState, WallPairState};
use crate::geom::Vec2;
use crate::model::{Model, System, SystemState};
use crate::run::RunError;
use crate::scenario::{PartSkeleton, Scenario};
use std::fs::File;
use std::path::Path;
use std::sync::Arc;

/// This rank's part of the granular run of `sc` restarted from the
/// checkpoint at `path` (collective; `skeleton` the scenario's
/// [`PartSkeleton`]): the model without discs (on rank 0 with the whole's
/// start positions when frames are written), the rank's share, and the
/// checkpoint's other values. Rank 0 checks the file's CRC-32; a refusal
/// on any rank (a damaged file, another scenario) is every rank's, with
/// the message of the first rank that refused.
pub(in crate::run) fn read_part(
    path: &Path,
    sc: &Scenario,
    skeleton: PartSkeleton,
    comm: Arc<dyn Comm>,
) -> Result<(Model, Decomposed, Checkpoint), RunError> {
    let bad = |message: String| RunError::Restart {
        path: path.to_path_buf(),
        message,
    };
    let root = comm.rank() == 0;
    let opened = Opened::open(path, sc, root);
    let mut o = agreed(&*comm, opened).map_err(bad)?;
    let part = part_of(&mut o, &skeleton, &*comm, sc.output.vtk_every != 0);
    let (part, keys, cut, start) = agreed(&*comm, part).map_err(bad)?;
    let n_total = skeleton.n_total;
    let mut model = skeleton.model;
    model.step = o.state.step;
    let System::Granular(g) = &mut model.system else {
        unreachable!("a granular skeleton")
    };
    // no discs, the whole's ids (the probes are bound to them)
    let none = Particles {
        slot: SlotIndex::of_part(n_total, &[]),
        ..Particles::default()
    };
    **g = part.with_discs(none);
    g.set_start(start);
    let d = Decomposed::from_restored(part, keys, cut, comm);
    Ok((model, d, o.into_checkpoint(None)))
}

/// `r` if every rank's is `Ok` (collective), else the first refusal.
fn agreed<T>(comm: &dyn Comm, r: Result<T, String>) -> Result<T, String> {
    let mine: Vec<u8> = match &r {
        Ok(_) => Vec::new(),
        Err(m) => std::iter::once(1).chain(m.bytes()).collect(),
    };
    match comm.all_gather(&mine).iter().find(|b| !b.is_empty()) {
        Some(b) => Err(String::from_utf8_lossy(&b[1..]).into_owned()),
        None => r,
    }
}

/// Whether bit `i` of `bits` is set.
fn bit(bits: &[u64], i: u32) -> bool {
    bits.get(i as usize / 64)
        .is_some_and(|w| (w >> (i % 64)) & 1 != 0)
}

/// The discs this rank holds: their slots in the whole (ascending), their
/// positions, and a bit per slot of the whole for those it owns.
struct Held {
    slots: Vec<u32>,
    pos: Vec<Vec2>,
    owned: Vec<u64>,
}

impl Held {
    /// The part's slot of the whole's slot `s`, if held.
    fn local(&self, s: u32) -> Option<u32> {
        self.slots.binary_search(&s).ok().map(|k| k as u32)
    }
}

/// The regions cut from the saved positions at the sample stride (those
/// [`Cut::new`] takes), and the discs `me` holds.
fn held(
    a: &mut Arrays<File>,
    sk: &PartSkeleton,
    skin: f64,
    comm: &dyn Comm,
) -> std::io::Result<(Cut, Held)> {
    let n = sk.n_total;
    let mut sample = Vec::with_capacity(n.div_ceil(sample_stride(n)));
    a.each(Col::Pos, (0..n).step_by(sample_stride(n)), |_, q| {
        sample.push(q)
    })?;
    let cut = Cut::from_sample(&sample, n, sk.max_radius, skin, comm.size());
    drop(sample);
    let me = comm.rank();
    let mut h = Held {
        slots: Vec::new(),
        pos: Vec::new(),
        owned: vec![0; n.div_ceil(64)],
    };
    a.each(Col::Pos, 0..n, |s, q: Vec2| {
        if cut.holds(q, me) {
            h.slots.push(s as u32);
            h.pos.push(q);
            if cut.regions.owner(q) == me {
                h.owned[s / 64] |= 1 << (s % 64);
            }
        }
    })?;
    Ok((cut, h))
}

/// The pairs with a disc that `h` owns (both discs held), in the part's
/// slots, and their indices in the whole's list; `None` when the list is
/// not sorted or out of range (a damaged file).
#[allow(clippy::type_complexity)]
fn pairs_of(a: &mut Arrays<File>, h: &Held) -> std::io::Result<Option<(Vec<[u32; 2]>, Vec<u32>)>> {
    let n = a.table.discs;
    let (mut pairs, mut ks) = (Vec::new(), Vec::new());
    let (mut ok, mut last) = (true, None);
    let m = a.table.len(Col::Pairs);
    a.each(Col::Pairs, 0..m, |k, [i, j]: [u32; 2]| {
        ok &= i < j && (j as u64) < n && last < Some((i, j));
        last = Some((i, j));
        if ok
            && (bit(&h.owned, i) || bit(&h.owned, j))
            && let (Some(x), Some(y)) = (h.local(i), h.local(j))
        {
            pairs.push([x, y]);
            ks.push(k as u32);
        }
    })?;
    Ok(ok.then_some((pairs, ks)))
}

/// This rank's part restored, its keys (the whole's slots), the regions
/// and the whole's start positions (on rank 0 with `frames`); the
/// refusal's message.
#[allow(clippy::type_complexity)]
fn part_of(
    o: &mut Opened,
    sk: &PartSkeleton,
    comm: &dyn Comm,
    frames: bool,
) -> Result<(Granular, Vec<u64>, Cut, Vec<Vec2>), String> {
    let damaged = |e: std::io::Error| format!("damaged checkpoint: {e}");
    let (SystemState::Granular(whole), Some(a)) = (&o.state.system, o.arrays.as_mut()) else {
        return Err("the checkpoint is not of a granular model".into());
    };
    let n = a.table.discs;
    if n != sk.n_total as u64 {
        return Err(format!(
            "the saved state has {n} discs, the model {}",
            sk.n_total
        ));
    }
    let System::Granular(g) = &sk.model.system else {
        unreachable!("a granular skeleton")
    };
    let (cut, mut h) = held(a, sk, g.grid.skin, comm).map_err(damaged)?;
    let start = frames && comm.rank() == 0;
    let (p, start) = discs_of(a, sk, &mut h, start)?;
    let (pairs, ks) = pairs_of(a, &h)
        .map_err(damaged)?
        .ok_or("damaged checkpoint: its pairs are not sorted or out of range")?;
    let wall_pairs = (whole.wall_pairs.iter())
        .filter(|w| bit(&h.owned, w.disc))
        .filter_map(|w| h.local(w.disc).map(|disc| WallPairState { disc, ..*w }))
        .collect();
    let (t, s) = (a.table, &h.slots);
    let rest = GranularState {
        ref_pos: match t.ref_pos {
            true => a.pick(Col::RefPos, s).map_err(damaged)?,
            false => Vec::new(),
        },
        shear: a.pick(Col::Shear, &ks).map_err(damaged)?,
        roll: match t.roll {
            true => a.pick(Col::Roll, &ks).map_err(damaged)?,
            false => Vec::new(),
        },
        pairs,
        wall_pairs,
        ..whole.as_ref().clone()
    };
    let mut g = g.with_discs(p);
    g.restore_state_around_discs(&rest)
        .map_err(|e| e.to_string())?;
    let keys = h.slots.iter().map(|&s| s as u64).collect();
    Ok((g, keys, cut, start))
}

/// The discs `h` holds as the scenario makes them, in their saved order
/// with their saved values read into place (`h.pos` taken); the whole's
/// start positions if `start`.
fn discs_of(
    a: &mut Arrays<File>,
    sk: &PartSkeleton,
    h: &mut Held,
    start: bool,
) -> Result<(Particles, Vec<Vec2>), String> {
    let damaged = |e: std::io::Error| format!("damaged checkpoint: {e}");
    let ids: Vec<u32> = a.pick(Col::Id, &h.slots).map_err(damaged)?;
    let mut sorted = ids.clone();
    sorted.sort_unstable();
    let n = sk.n_total as u64;
    if sorted.windows(2).any(|w| w[0] == w[1]) || sorted.last().is_some_and(|&i| i as u64 >= n) {
        return Err("damaged checkpoint: the saved disc ids are not a permutation".into());
    }
    let (mut p, start) = sk.discs(&sorted, start).map_err(|e| e.to_string())?;
    drop(sorted);
    // each disc's constants to its saved slot, then its saved values
    let order: Vec<u32> = ids.iter().map(|&id| p.slot[id as usize]).collect();
    drop(ids);
    p.permute(&order);
    drop(order);
    p.pos = std::mem::take(&mut h.pos);
    let s = &h.slots;
    fill(a, Col::Vel, s, &mut p.vel).map_err(damaged)?;
    fill(a, Col::Theta, s, &mut p.theta).map_err(damaged)?;
    fill(a, Col::Omega, s, &mut p.omega).map_err(damaged)?;
    fill(a, Col::Force, s, &mut p.force).map_err(damaged)?;
    fill(a, Col::Torque, s, &mut p.torque).map_err(damaged)?;
    Ok((p, start))
}

/// `v[k]` the element of `c` at `slots[k]`, for each `k`.
fn fill<T: Raw>(a: &mut Arrays<File>, c: Col, slots: &[u32], v: &mut [T]) -> std::io::Result<()> {
    let mut k = 0;
    a.each(c, slots.iter().map(|&s| s as usize), |_, x| {
        v[k] = x;
        k += 1;
    })
}
