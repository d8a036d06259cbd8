//! Contact search: a uniform cell grid with a Verlet skin.
//!
//! The grid's cell is at least the largest diameter plus the skin, so every
//! pair closer than the skin lies in neighbouring cells: the search costs
//! O(N). Pairs whose gap is below the skin are kept in a flat, sorted
//! [`ContactList`] (pair indices + shear history) that is reused until some
//! disc has moved more than half the skin (or a disc and a wall together
//! more than the skin); only then is the grid rebuilt. Every few rebuilds
//! the discs are renumbered in cell order so that neighbours in space are
//! neighbours in memory.
//!
//! Shear histories survive rebuilds and renumberings: the new pair list is
//! merged with the old one on the sorted keys `(i, j)`, `i < j` (slots).

use super::clumps::NO_CLUMP;
use super::contact::{ContactForce, effective_mass};
use super::particles::{GHOST, Particles};
use super::walls::Wall;
use crate::geom::Vec2;
use rayon::prelude::*;

/// A disc–wall pair closer than the skin, its shear history and its
/// rolling-spring history `mr` (the moment on the disc; 0 without rolling
/// resistance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallPair {
    /// Slot of the disc.
    pub disc: u32,
    /// Index of the wall.
    pub wall: u32,
    /// Shear force history along `t = perp(n)`, n from the disc to the wall.
    pub fs: f64,
    /// Rolling-spring history: the moment on the disc.
    pub mr: f64,
}

/// The flat contact arrays (structure of arrays, indexed by pair `k`),
/// and the index of the "cross" pairs whose second disc lies in a later
/// sweep block than the first (see [`sweep`](super::sweep)).
///
/// Disc–disc pairs closer than the skin are stored as a compressed sparse
/// row list over the first disc `i` (slots, `i < j`): the pairs of disc `i`
/// are `k ∈ first[i]..first[i + 1]`, with second discs `j[k]` ascending.
/// So the list is sorted by `(i, j)`; [`pairs`](Self::pairs) yields the
/// `(i, j)` of each `k`. Per pair the sweep reads 4 bytes of list (`j`), 8
/// of shear history, and 8 of `√m_eff` only when a law has critical-ratio
/// dashpots; the list itself is only read during a step.
#[derive(Debug, Clone, Default)]
pub struct ContactList {
    /// Pairs whose first disc is `i`: `first[i]..first[i + 1]` (`n + 1`
    /// offsets; empty before the first build).
    pub first: Vec<u32>,
    /// Second disc (slot) of each pair, ascending within a first disc.
    pub j: Vec<u32>,
    /// `√m_eff = √(m_i m_j/(m_i + m_j))` of each pair when some law has
    /// critical-ratio dashpots ([`needs_mass`](Self::needs_mass)); empty
    /// otherwise.
    pub sqrt_m_eff: Vec<f64>,
    /// Some law needs `√m_eff` (set by the assembly from its laws).
    pub needs_mass: bool,
    /// Shear history of each pair (force along `t = perp(n)`, n from i to
    /// j; 0 when open).
    pub shear: Vec<f64>,
    /// Some law has rolling resistance: `roll` is kept (set by the
    /// assembly from its laws).
    pub rolling: bool,
    /// Rolling-spring history of each pair when `rolling` (the moment on
    /// disc i, [`rolling`](super::contact::rolling); 0 when open); empty
    /// otherwise, so that the sweep without rolling resistance reads and
    /// writes nothing more.
    pub roll: Vec<f64>,
    /// Disc–wall pairs, sorted by `(disc, wall)`.
    pub walls: Vec<WallPair>,
    /// Force of each wall pair in the current step (same index as `walls`).
    pub wall_buf: Vec<ContactForce>,
    /// The cross pairs `(i, k)`: first disc and pair index, ascending.
    pub cross: Vec<(u32, u32)>,
    /// Force and new shear history of each cross pair in the current step.
    pub cross_buf: Vec<(ContactForce, f64)>,
    /// Rolling moment on the first disc and new rolling history of each
    /// cross pair (when `rolling`).
    pub cross_roll: Vec<(f64, f64)>,
    /// Cross pairs whose first disc is in block `b`: `cross_first[b]..cross_first[b + 1]`.
    pub cross_first: Vec<u32>,
    /// Cross pairs whose second disc is in block `b`:
    /// `cross_in[cross_in_start[b]..cross_in_start[b + 1]]`, as
    /// (second disc, index into `cross`), in list order.
    pub cross_in_start: Vec<u32>,
    /// (second disc, index into `cross`) of each cross pair, grouped by the
    /// block of the second disc.
    pub cross_in: Vec<(u32, u32)>,
    /// Discs per sweep block ([`block_size`]).
    pub block: usize,
}

/// Discs per sweep block for `n` discs: the largest power of two from 512
/// to 4096 that still gives at least 16 blocks (so that two or more
/// threads stay balanced). Larger blocks have fewer cross pairs (their
/// number goes with the blocks' perimeter), which are the costly ones:
/// 100 000 dense discs run 8 % faster with 4096 than with 512. Depends on
/// `n` only, never on the thread count.
pub fn block_size(n: usize) -> usize {
    let mut b = 512;
    while b < 4096 && n / (2 * b) >= 16 {
        b *= 2;
    }
    b
}

impl ContactList {
    /// Number of listed disc–disc pairs.
    pub fn len(&self) -> usize {
        self.j.len()
    }

    /// No disc–disc pair is listed.
    pub fn is_empty(&self) -> bool {
        self.j.is_empty()
    }

    /// `(i, j)` of each listed pair, in list order (`k = 0, 1, …`).
    pub fn pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.first.windows(2).enumerate().flat_map(move |(i, w)| {
            self.j[w[0] as usize..w[1] as usize]
                .iter()
                .map(move |&j| (i, j as usize))
        })
    }

    /// A list of `n` discs and no pairs.
    fn empty_rows(&mut self, n: usize) {
        self.first.clear();
        self.first.resize(n + 1, 0);
    }

    /// Set the pairs from `(i, j)` keys sorted by `(i, j)` (a saved state)
    /// with their histories, for `n` discs; `√m_eff` and the cross index
    /// follow.
    pub(crate) fn set_pairs(&mut self, n: usize, keys: &[[u32; 2]], p: &Particles) {
        self.empty_rows(n);
        for &[i, _] in keys {
            self.first[i as usize + 1] += 1;
        }
        for d in 0..n {
            self.first[d + 1] += self.first[d];
        }
        self.j = keys.iter().map(|&[_, j]| j).collect();
        self.finish(p);
    }

    /// After `first`, `j` and the histories are set: `√m_eff` when needed
    /// and the cross index.
    pub(crate) fn finish(&mut self, p: &Particles) {
        self.sqrt_m_eff = Vec::new();
        if self.needs_mass {
            let mut sm = vec![0.0; self.j.len()];
            let (first, j) = (&self.first, &self.j);
            sm.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
                let k0 = c * CHUNK;
                let mut i = first.partition_point(|&f| (f as usize) <= k0) - 1;
                for (k, o) in out.iter_mut().enumerate() {
                    while first[i + 1] as usize <= k0 + k {
                        i += 1;
                    }
                    let jj = j[k0 + k] as usize;
                    *o = effective_mass(p.inv_mass[i], p.inv_mass[jj]).sqrt();
                }
            });
            self.sqrt_m_eff = sm;
        }
        self.index_cross(p.len());
    }

    /// Index the cross pairs of the sweep blocks (after `first` and `j`
    /// were built for `n` discs).
    pub(crate) fn index_cross(&mut self, n: usize) {
        let bs = block_size(n);
        self.block = bs;
        let j = &self.j;
        let c = CrossIndex::build(n, bs, &self.first, |k| j[k]);
        (self.cross, self.cross_first) = (c.pairs, c.first);
        (self.cross_in_start, self.cross_in) = (c.in_start, c.incoming);
        self.cross_buf.clear();
        self.cross_buf
            .resize(self.cross.len(), (ContactForce::default(), 0.0));
        self.cross_roll.clear();
        if self.rolling {
            self.cross_roll.resize(self.cross.len(), (0.0, 0.0));
        }
    }

    /// Bytes held (capacity).
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        (self.first.capacity() + self.j.capacity() + self.cross_first.capacity()) * 4
            + (self.sqrt_m_eff.capacity() + self.shear.capacity() + self.roll.capacity()) * 8
            + (self.cross.capacity() + self.cross_in.capacity()) * 8
            + self.cross_roll.capacity() * 16
            + self.cross_in_start.capacity() * 4
            + self.cross_buf.capacity() * size_of::<(ContactForce, f64)>()
            + self.walls.capacity() * size_of::<WallPair>()
            + self.wall_buf.capacity() * size_of::<ContactForce>()
    }

    /// Index of the pair of slots `(a, b)` in any order, if it is listed.
    pub fn find(&self, a: u32, b: u32) -> Option<usize> {
        let (i, j) = if a < b { (a, b) } else { (b, a) };
        let lo = *self.first.get(i as usize)? as usize;
        let hi = *self.first.get(i as usize + 1)? as usize;
        self.j[lo..hi].binary_search(&j).ok().map(|k| lo + k)
    }

    /// Renumber the discs (`new_of_old[old slot]`): every pair gets the new
    /// slots of its discs (in order, `i < j`; a rolling history flips sign
    /// when its pair's order flips), the list is sorted again, and the
    /// wall pairs follow. `√m_eff` and the cross index are left stale (a
    /// rebuild follows).
    fn renumber(&mut self, new_of_old: &[u32]) {
        self.remap(new_of_old, new_of_old.len(), &[], &[], |_, _| true);
    }

    /// Move the list onto a new set of `n` discs: the disc in old slot `s`
    /// is now in slot `new_of_old[s]`, or gone when that is `u32::MAX` (its
    /// pairs are dropped); `extra` pairs `(a, b, shear, rolling moment on
    /// a)` and `extra_walls` (in new slots) are added, e.g. the histories
    /// a disc brings along when it joins the set; old pairs `(i, j)` (old
    /// slots) for which `keep(i, j)` is false are dropped. The pairs are ordered
    /// `i < j` again (a rolling history flips sign when its pair's order
    /// flips) and sorted; the wall pairs likewise. `√m_eff` and the cross
    /// index are left stale (a rebuild follows).
    pub fn remap(
        &mut self,
        new_of_old: &[u32],
        n: usize,
        extra: &[(u32, u32, f64, f64)],
        extra_walls: &[WallPair],
        keep: impl Fn(u32, u32) -> bool,
    ) {
        const GONE: u32 = u32::MAX;
        if self.first.len() != new_of_old.len() + 1 {
            // never built (or built for other discs): nothing to carry over
            self.empty_rows(new_of_old.len());
            self.j.clear();
            self.shear.clear();
            self.roll.clear();
            self.walls.clear();
        }
        let m = self.j.len();
        let rolling = self.rolling && self.roll.len() == m;
        // (first, second, flipped) of old pair k of disc i, None when dropped
        let key = |i: usize, k: usize| {
            let (a, b) = (new_of_old[i], new_of_old[self.j[k] as usize]);
            (a != GONE && b != GONE && keep(i as u32, self.j[k])).then_some((
                a.min(b),
                a.max(b),
                a > b,
            ))
        };
        let old_rows = new_of_old.len();
        // counting sort by the new first disc
        let mut first = vec![0u32; n + 1];
        for i in 0..old_rows {
            for k in self.first[i] as usize..self.first[i + 1] as usize {
                if let Some((a, _, _)) = key(i, k) {
                    first[a as usize + 1] += 1;
                }
            }
        }
        for &(a, b, _, _) in extra {
            first[a.min(b) as usize + 1] += 1;
        }
        for d in 0..n {
            first[d + 1] += first[d];
        }
        let total = first[n] as usize;
        let mut fill = first.clone();
        let mut j = vec![0u32; total];
        let mut shear = vec![0.0; total];
        let mut roll = vec![0.0; if self.rolling { total } else { 0 }];
        let mut put = |a: u32, b: u32, fs: f64, mr: f64| {
            let at = fill[a as usize] as usize;
            fill[a as usize] += 1;
            j[at] = b;
            shear[at] = fs;
            if !roll.is_empty() {
                roll[at] = mr;
            }
        };
        for i in 0..old_rows {
            for k in self.first[i] as usize..self.first[i + 1] as usize {
                if let Some((a, b, flip)) = key(i, k) {
                    let mr = if !rolling {
                        0.0
                    } else if flip {
                        -self.roll[k]
                    } else {
                        self.roll[k]
                    };
                    put(a, b, self.shear[k], mr);
                }
            }
        }
        for &(a, b, fs, mr) in extra {
            put(a.min(b), a.max(b), fs, if a > b { -mr } else { mr });
        }
        drop(fill);
        // sort each row by j (rows are short: insertion sort)
        for r in first.windows(2) {
            let (lo, hi) = (r[0] as usize, r[1] as usize);
            for a in lo + 1..hi {
                let mut b = a;
                while b > lo && j[b - 1] > j[b] {
                    j.swap(b - 1, b);
                    shear.swap(b - 1, b);
                    if !roll.is_empty() {
                        roll.swap(b - 1, b);
                    }
                    b -= 1;
                }
            }
        }
        (self.first, self.j, self.shear, self.roll) = (first, j, shear, roll);
        self.walls.retain_mut(|w| {
            w.disc = new_of_old[w.disc as usize];
            w.disc != GONE
        });
        self.walls.extend_from_slice(extra_walls);
        self.walls.sort_unstable_by_key(|w| (w.disc, w.wall));
    }
}

/// The "cross" pairs of a list of pairs in rows over their first disc
/// (`i < j`, j ascending within a row: the contact list, the held bonds):
/// those whose second disc lies in a later sweep block than the first,
/// evaluated ahead of the sweep ([`sweep`](super::sweep)).
#[derive(Debug, Clone, Default)]
pub struct CrossIndex {
    /// Discs per sweep block.
    pub block: usize,
    /// The cross pairs `(i, k)`: first disc and pair index, ascending.
    pub pairs: Vec<(u32, u32)>,
    /// Cross pairs whose first disc is in block `b`: `first[b]..first[b + 1]`.
    pub first: Vec<u32>,
    /// Cross pairs whose second disc is in block `b`:
    /// `incoming[in_start[b]..in_start[b + 1]]`.
    pub in_start: Vec<u32>,
    /// (second disc, index into `pairs`) of each cross pair, grouped by the
    /// block of the second disc, in list order.
    pub incoming: Vec<(u32, u32)>,
}

impl CrossIndex {
    /// The cross pairs of the rows `first` (`n + 1` offsets; `j(k)` the
    /// second disc of pair k) for blocks of `bs` discs.
    pub fn build(n: usize, bs: usize, first: &[u32], j: impl Fn(usize) -> u32 + Sync) -> Self {
        let nb = n.div_ceil(bs);
        let per_block: Vec<Vec<(u32, u32)>> = (0..nb)
            .into_par_iter()
            .map(|b| {
                let hi = ((b + 1) * bs).min(n);
                let mut out = Vec::new();
                for i in b * bs..hi {
                    let (p0, p1) = (first[i] as usize, first[i + 1] as usize);
                    // j ascending: the cross pairs end the row
                    let c0 = (p0..p1).find(|&k| j(k) as usize >= hi).unwrap_or(p1);
                    out.extend((c0..p1).map(|k| (i as u32, k as u32)));
                }
                out
            })
            .collect();
        let mut c = CrossIndex {
            block: bs,
            first: vec![0],
            in_start: vec![0; nb + 1],
            ..Default::default()
        };
        for p in &per_block {
            c.pairs.extend_from_slice(p);
            c.first.push(c.pairs.len() as u32);
            for &(_, k) in p {
                c.in_start[j(k as usize) as usize / bs + 1] += 1;
            }
        }
        for b in 0..nb {
            c.in_start[b + 1] += c.in_start[b];
        }
        c.incoming.resize(c.pairs.len(), (0, 0));
        let mut fill: Vec<u32> = c.in_start[..nb].to_vec();
        for (x, &(_, k)) in c.pairs.iter().enumerate() {
            let jj = j(k as usize);
            let f = &mut fill[jj as usize / bs];
            c.incoming[*f as usize] = (jj, x as u32);
            *f += 1;
        }
        c
    }

    /// Bytes held (capacity).
    pub fn heap_bytes(&self) -> usize {
        (self.pairs.capacity() + self.incoming.capacity()) * 8
            + (self.first.capacity() + self.in_start.capacity()) * 4
    }
}

/// The grid and the Verlet-list bookkeeping.
#[derive(Debug, Clone, Default)]
pub struct NeighbourGrid {
    /// Verlet skin: pairs with a gap below it are listed.
    pub skin: f64,
    /// Renumber the discs in cell order every this many rebuilds (0 = never).
    pub reorder_every: usize,
    /// Positions at the last rebuild.
    pub ref_pos: Vec<Vec2>,
    /// Wall end points `[a, b]` at the last rebuild.
    pub wall_ref: Vec<[Vec2; 2]>,
    /// Number of rebuilds so far.
    pub rebuilds: usize,
    /// Force a rebuild before the next force computation.
    pub stale: bool,
    cell_of: Vec<u32>,
    cell_start: Vec<u32>,
    cell_items: Vec<u32>,
    nx: usize,
    ny: usize,
    origin: Vec2,
    h: f64,
}

const CHUNK: usize = 4096;
/// Width in cells of the strips of the disc ordering.
const STRIP: usize = 16;

/// The box `(lo, hi)` of the finite centres in `pos` (`lo > hi` when there
/// is none); min and max are exact, so the box is the same on any number
/// of threads, and boxes of parts combine by min and max.
pub fn centre_bounds(pos: &[Vec2]) -> (Vec2, Vec2) {
    let none = (
        Vec2::new(f64::INFINITY, f64::INFINITY),
        Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    let join = |(a, b): (Vec2, Vec2), (c, d): (Vec2, Vec2)| {
        (
            Vec2::new(a.x.min(c.x), a.y.min(c.y)),
            Vec2::new(b.x.max(d.x), b.y.max(d.y)),
        )
    };
    pos.par_iter()
        .with_min_len(CHUNK)
        .filter(|q| q.x.is_finite() && q.y.is_finite())
        .map(|&q| (q, q))
        .reduce(|| none, join)
}

/// A uniform cell grid over a box of disc centres: its origin, cell size
/// and number of cells. The contact search bins the discs on it, and the
/// renumbering orders them by [`key`](Self::key) on it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GridSpec {
    /// Lower-left corner.
    pub origin: Vec2,
    /// Cell size.
    pub h: f64,
    /// Cells along x.
    pub nx: usize,
    /// Cells along y.
    pub ny: usize,
}

impl GridSpec {
    /// The grid for `n` discs whose finite centres span `(lo, hi)`
    /// ([`centre_bounds`]), radii up to `max_radius`, Verlet skin `skin`:
    /// cells of the largest diameter plus the skin. However far apart the
    /// discs are (after an instability: 1e19 and more, up to an extent that
    /// overflows to infinity), the cell count stays at most ~4 per disc:
    /// the cell grows by doubling until the grid fits, and a grid that
    /// cannot fit (infinite extent) is a single cell. A disc with a
    /// non-finite centre goes to the first cell.
    pub fn new(lo: Vec2, hi: Vec2, max_radius: f64, skin: f64, n: usize) -> GridSpec {
        let (lo, hi) = if lo.x <= hi.x && lo.y <= hi.y {
            (lo, hi)
        } else {
            // no disc, or none with a finite centre
            (Vec2::ZERO, Vec2::ZERO)
        };
        let mut h = (2.0 * max_radius + skin).max(1e-300);
        if !h.is_finite() {
            h = f64::MAX;
        }
        let ext = hi - lo; // may overflow to +∞ for centres near ±f64::MAX
        // Cap the number of cells at ~4 per disc (a disc flying far away
        // must not blow up the grid). Counted in floating point: an extent
        // of 1e19 cells must not wrap around in `usize`.
        let max_cells = (4 * n + 16) as f64;
        let cells = |e: f64, h: f64| (e / h).floor() + 1.0;
        loop {
            let (fx, fy) = (cells(ext.x, h), cells(ext.y, h));
            if fx.is_finite() && fy.is_finite() && fx * fy <= max_cells {
                return GridSpec {
                    origin: lo,
                    h,
                    nx: fx as usize,
                    ny: fy as usize,
                };
            }
            if h >= f64::MAX / 2.0 {
                // an infinite extent: one cell (every pair is tested)
                return GridSpec {
                    origin: lo,
                    h,
                    nx: 1,
                    ny: 1,
                };
            }
            h *= 2.0;
        }
    }

    /// The cell of centre `q` (row-major).
    #[inline]
    pub fn cell(&self, q: Vec2) -> u32 {
        let cx = (((q.x - self.origin.x) / self.h) as usize).min(self.nx - 1);
        let cy = (((q.y - self.origin.y) / self.h) as usize).min(self.ny - 1);
        (cy * self.nx + cx) as u32
    }

    /// Rank of cell `c` in the disc ordering: vertical strips of
    /// `STRIP` cells, row by row inside a strip.
    pub fn strip_rank(&self, c: u32) -> u64 {
        let (cx, cy) = (c as usize % self.nx, c as usize / self.nx);
        let x0 = cx / STRIP * STRIP;
        let w = STRIP.min(self.nx - x0);
        (x0 * self.ny + cy * w + (cx - x0)) as u64
    }

    /// The renumbering's order of the disc with id `id` at `q`: by cell in
    /// strip order, then by id. It depends on the disc alone, so the
    /// parts of a decomposed assembly order their discs as the whole.
    pub fn key(&self, q: Vec2, id: u32) -> u64 {
        self.strip_rank(self.cell(q)) << 32 | id as u64
    }
}

impl NeighbourGrid {
    /// An empty grid with Verlet skin `skin` (stale: built at the first step).
    pub fn new(skin: f64) -> Self {
        NeighbourGrid {
            skin,
            reorder_every: 8,
            stale: true,
            ..Default::default()
        }
    }

    /// Bytes held (capacity).
    pub fn heap_bytes(&self) -> usize {
        self.ref_pos.capacity() * 16
            + (self.cell_of.capacity() + self.cell_start.capacity() + self.cell_items.capacity())
                * 4
    }

    /// Does the list have to be rebuilt? `max_disp` is the largest disc
    /// displacement since the last rebuild.
    pub fn needs_rebuild(&self, max_disp: f64, walls: &[Wall]) -> bool {
        if self.stale {
            return true;
        }
        // a translated wall moved by |Δa| everywhere; a wall whose joined
        // ends slide along its line, by at most max(|Δa|, |Δb|)
        let wmax = walls
            .iter()
            .zip(&self.wall_ref)
            .map(|(w, r)| {
                let da = (w.a - r[0]).norm();
                if w.is_joined() {
                    da.max((w.b - r[1]).norm())
                } else {
                    da
                }
            })
            .fold(0.0, f64::max);
        2.0 * max_disp > self.skin || max_disp + wmax > self.skin
    }

    /// Bin the discs (counting sort, stable in slot order) on the grid
    /// [`GridSpec::new`] makes for their finite centres.
    fn bin(&mut self, p: &Particles) {
        let n = p.len();
        let (lo, hi) = centre_bounds(&p.pos);
        let spec = GridSpec::new(lo, hi, p.max_radius(), self.skin, n);
        (self.origin, self.h, self.nx, self.ny) = (spec.origin, spec.h, spec.nx, spec.ny);
        let ncell = self.nx * self.ny;
        self.cell_of.clear();
        self.cell_of
            .par_extend(p.pos.par_iter().with_min_len(CHUNK).map(|&q| spec.cell(q)));
        self.cell_start.clear();
        self.cell_start.resize(ncell + 1, 0);
        for &c in &self.cell_of {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..ncell {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.cell_items.clear();
        self.cell_items.resize(n, 0);
        let mut fill = self.cell_start.clone();
        for (k, &c) in self.cell_of.iter().enumerate() {
            self.cell_items[fill[c as usize] as usize] = k as u32;
            fill[c as usize] += 1;
        }
    }

    /// Discs in cell order along vertical strips of [`STRIP`] cells (row by
    /// row inside a strip): a disc's neighbours in the cell rows above and
    /// below are then a few dozen slots away instead of a whole grid row,
    /// which keeps the contact kernel's reads of disc j in L1/L2.
    ///
    /// Inside a cell the discs go by id: the order is that of
    /// [`GridSpec::key`], which depends on each disc alone (not on the
    /// order before), so the parts of a decomposed assembly agree on it.
    fn strip_order(&self, id: &[u32]) -> Vec<u32> {
        let mut order = Vec::with_capacity(self.cell_items.len());
        for x0 in (0..self.nx).step_by(STRIP) {
            for cy in 0..self.ny {
                for cx in x0..(x0 + STRIP).min(self.nx) {
                    let c = cy * self.nx + cx;
                    let (a, b) = (self.cell_start[c] as usize, self.cell_start[c + 1] as usize);
                    let at = order.len();
                    order.extend_from_slice(&self.cell_items[a..b]);
                    // a few discs per cell: insertion sort by id
                    let cell = &mut order[at..];
                    for x in 1..cell.len() {
                        let mut y = x;
                        while y > 0 && id[cell[y - 1] as usize] > id[cell[y] as usize] {
                            cell.swap(y - 1, y);
                            y -= 1;
                        }
                    }
                }
            }
        }
        order
    }

    /// Rebuild the pair lists (and renumber the discs every
    /// `reorder_every` rebuilds), carrying shear histories over.
    ///
    /// Memory: `√m_eff` is dropped first (it is recomputed), and the new
    /// list is built beside the old one only as long as the histories are
    /// merged, so the peak is about the steady list twice.
    pub fn rebuild(&mut self, p: &mut Particles, walls: &[Wall], list: &mut ContactList) {
        list.sqrt_m_eff = Vec::new();
        list.cross_buf = Vec::new();
        list.cross_roll = Vec::new();
        self.bin(p);
        if self.reorder_every > 0 && self.rebuilds.is_multiple_of(self.reorder_every) {
            let order = self.strip_order(&p.id);
            let new_of_old = p.permute(&order);
            drop(order);
            list.renumber(&new_of_old);
            drop(new_of_old);
            self.bin(p);
        }
        self.rebuilds += 1;
        self.search(p, list);
        self.search_walls(p, walls, list);
        list.finish(p);
        self.ref_pos.clear();
        self.ref_pos.extend_from_slice(&p.pos);
        self.wall_ref = walls.iter().map(|w| [w.a, w.b]).collect();
        self.stale = false;
    }

    /// Disc–disc candidates: for each disc, the discs of higher slot in the
    /// 3×3 neighbouring cells with a gap below the skin (sorted), in
    /// parallel over chunks of discs; then each disc's new row is merged
    /// with its old row to keep the shear (and rolling) histories.
    fn search(&self, p: &Particles, list: &mut ContactList) {
        let n = p.len();
        let skin = self.skin;
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        let chunks: Vec<(Vec<u32>, Vec<u32>)> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let lo = c * CHUNK;
                let hi = (lo + CHUNK).min(n);
                let mut counts = Vec::with_capacity(hi - lo);
                let mut js = Vec::with_capacity(3 * (hi - lo));
                for i in lo..hi {
                    let start = js.len();
                    let pi = p.pos[i];
                    let ri = p.radius[i];
                    let ci = p.clump[i];
                    let ghost = p.fixity[i] & GHOST != 0;
                    let cell = self.cell_of[i] as isize;
                    let (cx, cy) = (cell % nx, cell / nx);
                    for yy in (cy - 1).max(0)..=(cy + 1).min(ny - 1) {
                        for xx in (cx - 1).max(0)..=(cx + 1).min(nx - 1) {
                            let cc = (yy * nx + xx) as usize;
                            let (a, b) = (self.cell_start[cc], self.cell_start[cc + 1]);
                            for &j in &self.cell_items[a as usize..b as usize] {
                                // no contacts within a clump, none between ghosts
                                if (j as usize) <= i
                                    || (ci != NO_CLUMP && p.clump[j as usize] == ci)
                                    || ghost && p.fixity[j as usize] & GHOST != 0
                                {
                                    continue;
                                }
                                let reach = ri + p.radius[j as usize] + skin;
                                if (p.pos[j as usize] - pi).norm2() < reach * reach {
                                    js.push(j);
                                }
                            }
                        }
                    }
                    js[start..].sort_unstable();
                    counts.push((js.len() - start) as u32);
                }
                (counts, js)
            })
            .collect();
        // the new rows: offsets, then the second discs chunk by chunk
        let mut first = Vec::with_capacity(n + 1);
        first.push(0u32);
        for (counts, _) in &chunks {
            for &c in counts {
                first.push(first[first.len() - 1] + c);
            }
        }
        let total = first[n] as usize;
        let mut j = vec![0u32; total];
        {
            let mut rest = &mut j[..];
            let mut parts = Vec::with_capacity(chunks.len());
            for (_, js) in &chunks {
                let (a, b) = rest.split_at_mut(js.len());
                parts.push(a);
                rest = b;
            }
            parts
                .into_par_iter()
                .zip(chunks.par_iter())
                .for_each(|(out, (_, js))| out.copy_from_slice(js));
        }
        drop(chunks);
        // histories: merge each disc's new row with its old one
        let old_ok = list.first.len() == n + 1;
        let rolling = list.rolling;
        let roll_kept = old_ok && list.roll.len() == list.j.len();
        let mut shear = vec![0.0; total];
        let mut roll = vec![0.0; if rolling { total } else { 0 }];
        if old_ok {
            let old = &*list;
            let merge = |lo: usize, hi: usize, sh: &mut [f64], ro: &mut [f64]| {
                let base = first[lo] as usize;
                for i in lo..hi {
                    let (o0, o1) = (old.first[i] as usize, old.first[i + 1] as usize);
                    let mut o = o0;
                    for k in first[i] as usize..first[i + 1] as usize {
                        let jj = j[k];
                        while o < o1 && old.j[o] < jj {
                            o += 1;
                        }
                        if o < o1 && old.j[o] == jj {
                            sh[k - base] = old.shear[o];
                            if roll_kept && !ro.is_empty() {
                                ro[k - base] = old.roll[o];
                            }
                        }
                    }
                }
            };
            // split the new histories at chunk boundaries of the discs
            let mut tasks = Vec::with_capacity(n.div_ceil(CHUNK));
            let (mut sh_rest, mut ro_rest) = (&mut shear[..], &mut roll[..]);
            for c in 0..n.div_ceil(CHUNK) {
                let (lo, hi) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
                let len = (first[hi] - first[lo]) as usize;
                let (a, b) = sh_rest.split_at_mut(len);
                sh_rest = b;
                let (ra, rb) = if rolling {
                    ro_rest.split_at_mut(len)
                } else {
                    (&mut [][..], ro_rest)
                };
                ro_rest = rb;
                tasks.push((lo, hi, a, ra));
            }
            tasks
                .into_par_iter()
                .for_each(|(lo, hi, sh, ro)| merge(lo, hi, sh, ro));
        }
        list.first = first;
        list.j = j;
        list.shear = shear;
        list.roll = roll;
    }

    /// Disc–wall candidates: each disc against each wall's bounding box
    /// (enlarged by the disc's reach), then the exact distance; in parallel
    /// over chunks of discs, histories carried over from the old list.
    fn search_walls(&self, p: &Particles, walls: &[Wall], list: &mut ContactList) {
        let old = std::mem::take(&mut list.walls);
        let reach_max = p.max_radius() + self.skin;
        let boxes: Vec<(Vec2, Vec2)> = walls
            .iter()
            .map(|w| {
                (
                    Vec2::new(w.a.x.min(w.b.x) - reach_max, w.a.y.min(w.b.y) - reach_max),
                    Vec2::new(w.a.x.max(w.b.x) + reach_max, w.a.y.max(w.b.y) + reach_max),
                )
            })
            .collect();
        let n = p.len();
        let chunks: Vec<Vec<WallPair>> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let (lo, hi) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
                let mut o = old.partition_point(|q| (q.disc as usize) < lo);
                let mut out = Vec::new();
                for d in lo..hi {
                    if p.fixity[d] & GHOST != 0 {
                        continue;
                    }
                    let (q, r) = (p.pos[d], p.radius[d]);
                    for (w, wall) in walls.iter().enumerate() {
                        let (blo, bhi) = boxes[w];
                        if q.x < blo.x || q.x > bhi.x || q.y < blo.y || q.y > bhi.y {
                            continue;
                        }
                        let reach = r + self.skin;
                        if (wall.closest(q) - q).norm2() < reach * reach {
                            let key = (d as u32, w as u32);
                            while o < old.len() && (old[o].disc, old[o].wall) < key {
                                o += 1;
                            }
                            let (fs, mr) = if o < old.len() && (old[o].disc, old[o].wall) == key {
                                (old[o].fs, old[o].mr)
                            } else {
                                (0.0, 0.0)
                            };
                            out.push(WallPair {
                                disc: key.0,
                                wall: key.1,
                                fs,
                                mr,
                            });
                        }
                    }
                }
                out
            })
            .collect();
        list.walls = chunks.concat();
        list.wall_buf.clear();
        list.wall_buf
            .resize(list.walls.len(), ContactForce::default());
    }
}

#[cfg(test)]
mod tests {
    use super::block_size;
    use crate::dem::Granular;
    use crate::dem::contact::ContactLaw;
    use crate::dem::particles::Particles;
    use crate::dem::walls::{Wall, WallMotion};
    use crate::geom::Vec2;

    /// After an instability discs fly ~1e19 apart; the grid's cell
    /// count was computed in `usize` and wrapped around (index out of bounds
    /// in `bin`). A disc at 1e19, 1e300, ±∞ or NaN must not break the
    /// rebuild, and the discs that still touch are still found.
    #[test]
    fn a_disc_thrown_far_away_does_not_break_the_grid() {
        for far in [1e19, -1e19, 1e300, f64::MAX, f64::INFINITY, f64::NAN] {
            let mut p = Particles::default();
            for k in 0..10 {
                p.push(Vec2::new(1.9 * k as f64, 0.0), 1.0, 1.0, 1.0, 0);
            }
            let law = ContactLaw {
                kn: 1e6,
                ks: 1e6,
                ..Default::default()
            };
            let wall = Wall::new(
                "floor",
                Vec2::new(-5.0, -1.0),
                Vec2::new(50.0, -1.0),
                WallMotion::Fixed,
            );
            let mut g = Granular::new(p, vec![law], vec![wall], 1e-4);
            g.step();
            // one disc far away in x, another far away in both directions
            let (a, b) = (g.slot(3), g.slot(7));
            g.particles.pos[a] = Vec2::new(far, 0.0);
            g.particles.pos[b] = Vec2::new(-far, far);
            g.grid.stale = true;
            g.prepare_contacts();
            g.grid.stale = true;
            g.prepare_contacts(); // a renumbering rebuild too
            // the chain 0-1-2 and 4-5-6 and 8-9 still touch: 2 + 2 + 1 pairs
            let near = g
                .contacts
                .pairs()
                .filter(|&(i, j)| {
                    g.particles.pos[i].x.is_finite()
                        && g.particles.pos[j].x.is_finite()
                        && (g.particles.pos[i] - g.particles.pos[j]).norm() < 2.0
                })
                .count();
            assert_eq!(near, 5, "far = {far}");
            let ncells = g.grid.nx * g.grid.ny;
            assert!(
                (1..=4 * 10 + 16).contains(&ncells),
                "far = {far}: {ncells} cells"
            );
        }
    }

    /// Powers of two in [512, 4096], at least 16 blocks once n allows it.
    #[test]
    fn block_size_grows_with_n_but_keeps_16_blocks() {
        assert_eq!(block_size(0), 512);
        assert_eq!(block_size(10_000), 512);
        assert_eq!(block_size(16_384), 1024);
        assert_eq!(block_size(100_000), 4096);
        assert_eq!(block_size(10_000_000), 4096);
        for n in [20_000, 40_000, 70_000, 100_000, 150_000] {
            let b = block_size(n);
            assert!(b.is_power_of_two() && (512..=4096).contains(&b));
            assert!(n / b >= 16, "{n}: {b}");
        }
    }
}
