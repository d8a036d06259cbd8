//! Domain decomposition of a granular assembly over ranks (processes that
//! talk through a [`Comm`], e.g. MPI), with results bitwise equal to the
//! undivided assembly on any number of ranks.
//!
//! Each rank holds a [`Decomposed`]: a plain [`Granular`] (its *part*)
//! with the discs whose centres lie in its region ([`regions`]) and the
//! *ghosts*, copies of the discs of other ranks within reach of its region
//! ([`GHOST`]). The physics runs unchanged on the part; this layer keeps
//! the parts consistent:
//!
//! - **Ghosts** carry what the contact law needs (position, velocity,
//!   spin, radius, masses, material) and are refreshed every step from
//!   their owners (position, velocity, spin).
//! - **The same sums as the whole.** The undivided sweep evaluates a pair
//!   with its lower slot first and sums each disc's contacts by ascending
//!   slot of the other disc. A part keeps its discs (ghosts included) in
//!   the order of a global *key* — the slot order of the whole — so that a
//!   pair crossing two regions is evaluated on both ranks with the same
//!   operands in the same orientation, and each disc sums the same terms
//!   in the same order. Keys are the renumbering's order
//!   ([`GridSpec::key`]: cell in strip order, then id), which each owner
//!   computes alone from a grid agreed by all ranks.
//! - **Global decisions globally.** The rebuild of the contact list (the
//!   largest displacement, a maximum: exact in any order), the step check,
//!   and the totals of the walls that follow the state (servo, strain
//!   rate), whose terms are merged from all ranks in key order and summed
//!   as the whole sums them.
//! - **Migration.** At each rebuild the discs that left a region move to
//!   their new owner with everything they carry: their state, the shear
//!   and rolling histories of their disc–disc pairs (keyed by disc ids)
//!   and of their wall pairs. The regions are cut again when the disc
//!   counts drift apart by more than [`Decomposed::balance_threshold`].
//! - **One state.** [`Decomposed::gather`] assembles on rank 0 the
//!   [`GranularState`] the undivided assembly would have (discs in slot
//!   order, sorted pair list, histories, walls): outputs and checkpoints
//!   are made from it, and a checkpoint restarts on any number of ranks
//!   ([`Decomposed::new`] splits a whole assembly;
//!   [`Decomposed::from_restored`] takes a part each rank restored
//!   alone, the same share).

pub mod comm;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod near_bodies;
pub mod regions;

use crate::dem::Granular;
use crate::dem::broadphase::{GridSpec, WallPair};
use crate::dem::particles::{GHOST, Particles, SlotIndex};
use crate::dem::state::{GranularState, WallPairState, WallState};
use crate::geom::Vec2;
pub use comm::{Comm, Solo, Threads, Traffic};
use comm::{Pack, Unpack};
use regions::Subdomains;
use std::sync::Arc;

const GONE: u32 = u32::MAX;
/// Centres per rank sent to cut the regions (a sample when there are more).
const SAMPLE: usize = 50_000;

/// One rank's share of a decomposed granular assembly ([module docs](self)).
pub struct Decomposed {
    /// This rank's discs and ghosts, in key order (see the module docs).
    pub part: Granular,
    comm: Arc<dyn Comm>,
    /// Key of the disc in each slot of `part`.
    key: Vec<u64>,
    regions: Subdomains,
    /// Discs of the whole assembly.
    n_total: usize,
    /// Largest radius of the whole assembly.
    max_radius: f64,
    /// The whole assembly's renumbering period (the part never renumbers
    /// by itself).
    reorder_every: usize,
    /// Recut the regions at a rebuild when the largest disc count exceeds
    /// the mean by more than this fraction (default 0.1).
    pub balance_threshold: f64,
    /// Largest disc count over the mean, minus one, at the last rebuild
    /// (after any recut).
    pub imbalance: f64,
    /// Times the regions were cut again.
    pub recuts: usize,
    /// Discs that arrived at this rank to be owned here (migrations).
    pub arrivals: usize,
    /// Non-zero disc–disc and disc–wall histories (shear or rolling) that
    /// arrived with them.
    pub histories_in: usize,
    /// What this rank sent during the steps ([`begin_step`](Self::begin_step)
    /// and [`advance`](Self::advance): ghosts, migrations, the step's
    /// global values), gathers for the outputs aside.
    pub stepping: Traffic,
    /// Slots of this rank's discs whose ghosts each rank holds.
    halo_send: Vec<(usize, Vec<u32>)>,
    /// Slots of the ghosts each rank refreshes.
    halo_recv: Vec<(usize, Vec<u32>)>,
    /// Walls whose motion follows the state (their totals are global sums
    /// every step).
    follows: Vec<bool>,
}

/// The regions of a fresh division over ranks, cut from the centres of
/// the whole assembly: which discs each rank holds (its own and their
/// ghosts). Every rank computes the same from the same centres.
#[derive(Debug, Clone)]
pub struct Cut {
    /// The ranks' regions.
    pub regions: Subdomains,
    /// Discs of the whole assembly.
    pub n_total: usize,
    /// Largest radius of the whole assembly.
    pub max_radius: f64,
    /// How far from its region a rank holds ghosts: the reach of a pair
    /// plus the skin (since the last rebuild the discs moved by up to half
    /// the skin each: partners listed then are within reach + skin now).
    pub width: f64,
}

impl Cut {
    /// The regions of `ranks` for discs at `pos` (the whole assembly's
    /// centres, in slot order), of largest radius `max_radius`, with the
    /// search grid's `skin`.
    pub fn new(pos: &[Vec2], max_radius: f64, skin: f64, ranks: usize) -> Cut {
        Cut::from_sample(&sample(pos, pos.len()), pos.len(), max_radius, skin, ranks)
    }

    /// [`new`](Self::new) from the centres of the `n_total` discs whose
    /// slot is a multiple of [`sample_stride`]`(n_total)`, in slot order:
    /// the same regions, without the other centres.
    pub fn from_sample(
        sample: &[Vec2],
        n_total: usize,
        max_radius: f64,
        skin: f64,
        ranks: usize,
    ) -> Cut {
        Cut {
            regions: Subdomains::bisect(sample, ranks),
            n_total,
            max_radius,
            width: reach(max_radius, skin) + skin,
        }
    }

    /// Which of the discs at `pos` rank `me` holds ([`holds`](Self::holds)).
    pub fn keeps(&self, pos: &[Vec2], me: usize) -> Vec<bool> {
        pos.iter().map(|&q| self.holds(q, me)).collect()
    }

    /// Whether rank `me` holds a disc at `q`: one of its region, or within
    /// [`width`](Self::width) of it.
    pub fn holds(&self, q: Vec2, me: usize) -> bool {
        self.regions.owner(q) == me || self.regions.regions[me].distance(q) <= self.width
    }
}

/// Where a disc of a new part comes from.
#[derive(Clone, Copy)]
enum Src {
    /// A slot of the present part.
    Old(u32),
    /// Record `k` received.
    Got(u32),
}

/// A disc received from another rank.
struct Record {
    id: u32,
    key: u64,
    owned: bool,
    pos: Vec2,
    vel: Vec2,
    theta: f64,
    omega: f64,
    radius: f64,
    mass: f64,
    inertia: f64,
    inv_mass: f64,
    inv_inertia: f64,
    force: Vec2,
    torque: f64,
    fixity: u8,
    material: u16,
}

/// What a rank receives at a migration: discs, and the pair histories
/// `(id, id, shear, rolling)` and wall histories `(id, wall, shear,
/// rolling)` of those it will own.
struct Arrivals {
    records: Vec<Record>,
    pairs: Vec<(u32, u32, f64, f64)>,
    walls: Vec<(u32, u32, f64, f64)>,
}

impl Arrivals {
    /// The buffers `got` from every rank (`me`'s own is empty).
    fn unpack(got: &[Vec<u8>], me: usize) -> Arrivals {
        let mut a = Arrivals {
            records: Vec::new(),
            pairs: Vec::new(),
            walls: Vec::new(),
        };
        for (r, b) in got.iter().enumerate() {
            if r == me || b.is_empty() {
                continue;
            }
            let mut u = Unpack(b);
            for _ in 0..u.u32() {
                a.records.push(unpack_disc(&mut u));
            }
            for _ in 0..u.u32() {
                let (i, j) = (u.u32(), u.u32());
                a.pairs.push((i, j, u.f64(), u.f64()));
            }
            for _ in 0..u.u32() {
                let (d, w) = (u.u32(), u.u32());
                a.walls.push((d, w, u.f64(), u.f64()));
            }
        }
        a
    }
}

/// The pair histories `pairs` and wall histories `walls` (by disc ids)
/// that arrived, in the slots of `p` (those of discs it holds), the pairs
/// sorted and once each.
#[allow(clippy::type_complexity)]
fn arriving_histories(
    p: &Particles,
    pairs: &[(u32, u32, f64, f64)],
    walls: &[(u32, u32, f64, f64)],
) -> (Vec<(u32, u32, f64, f64)>, Vec<WallPair>) {
    let slot_now = |id: u32| p.slot.get(id as usize).copied().unwrap_or(GONE);
    let mut extra: Vec<(u32, u32, f64, f64)> = pairs
        .iter()
        .filter_map(|&(a, b, fs, mr)| {
            let (sa, sb) = (slot_now(a), slot_now(b));
            (sa != GONE && sb != GONE).then_some((sa, sb, fs, mr))
        })
        .collect();
    extra.sort_unstable_by_key(|e| (e.0.min(e.1), e.0.max(e.1)));
    extra.dedup_by_key(|e| (e.0.min(e.1), e.0.max(e.1)));
    let extra_walls = walls
        .iter()
        .filter_map(|&(d, wall, fs, mr)| {
            let s = slot_now(d);
            (s != GONE).then_some(WallPair {
                disc: s,
                wall,
                fs,
                mr,
            })
        })
        .collect();
    (extra, extra_walls)
}

impl Decomposed {
    /// This rank's share of `whole` (an assembly every rank built the
    /// same, fresh or restored from a state): regions cut from its discs,
    /// the discs of this rank's region and their ghosts, the contact list
    /// and histories of those discs.
    pub fn new(whole: &Granular, comm: Arc<dyn Comm>) -> Decomposed {
        let p = &whole.particles;
        let n = p.len();
        let cut = Cut::new(&p.pos, p.max_radius(), whole.grid.skin, comm.size());
        let me = comm.rank();
        let keep = cut.keeps(&p.pos, me);
        let local: Vec<u32> = (0..n as u32).filter(|&s| keep[s as usize]).collect();
        drop(keep);
        let sources: Vec<Src> = local.iter().map(|&s| Src::Old(s)).collect();
        let mut particles = Particles::default();
        regather(&mut particles, Some(p), &sources, &[], n);
        let mut part = whole.with_discs(particles);
        part.grid.stale = whole.grid.stale;
        part.max_disp = whole.max_disp;
        if whole.grid.ref_pos.len() == n {
            part.grid.ref_pos = local
                .iter()
                .map(|&s| whole.grid.ref_pos[s as usize])
                .collect();
        }
        let keys = local.iter().map(|&s| s as u64).collect();
        let mut d = Decomposed::start(part, keys, cut, whole.grid.reorder_every, comm);
        if whole.contacts.first.len() == n + 1 {
            let mut new_of_old = vec![GONE; n];
            for (k, &s) in local.iter().enumerate() {
                new_of_old[s as usize] = k as u32;
            }
            let regions = &d.regions;
            let mine = |s: u32| regions.owner(p.pos[s as usize]) == me;
            let mut list = whole.contacts.clone();
            list.remap(&new_of_old, local.len(), &[], &[], |i, j| {
                mine(i) || mine(j)
            });
            let part = &mut d.part;
            list.walls
                .retain(|w| part.particles.fixity[w.disc as usize] & GHOST == 0);
            list.wall_buf = vec![Default::default(); list.walls.len()];
            list.finish(&part.particles);
            part.contacts = list;
        }
        d
    }

    /// This rank's share of a fresh assembly built in parts: `built` holds
    /// the discs `cut` [keeps](Cut::keeps) for this rank (their ids those
    /// of the whole, which are also their keys: the whole's slots), with
    /// the whole's walls, laws and clock, no contact list yet. Bitwise the
    /// share [`new`](Self::new) takes of the whole.
    /// `built` is left without discs.
    pub fn from_part(built: &mut Granular, cut: Cut, comm: Arc<dyn Comm>) -> Decomposed {
        let particles = std::mem::take(&mut built.particles);
        let keys = particles.id.iter().map(|&i| i as u64).collect();
        let mut part = built.with_discs(particles);
        part.grid.stale = built.grid.stale;
        part.max_disp = built.max_disp;
        Decomposed::start(part, keys, cut, built.grid.reorder_every, comm)
    }

    /// This rank's share of an assembly restored in parts: `part` holds
    /// the discs `cut` [keeps](Cut::keeps) for this rank of a saved whole,
    /// in its slot order (`keys`: their slots in it), restored with the
    /// pairs that have a disc of this rank's region and the wall pairs of
    /// those discs. Bitwise the share [`new`](Self::new) takes of the
    /// whole restored.
    pub fn from_restored(
        part: Granular,
        keys: Vec<u64>,
        cut: Cut,
        comm: Arc<dyn Comm>,
    ) -> Decomposed {
        let reorder_every = part.grid.reorder_every;
        Decomposed::start(part, keys, cut, reorder_every, comm)
    }

    /// The share of `part` (discs with their `keys`, in key order, owned
    /// or not), the ghosts flagged and indexed.
    fn start(
        mut part: Granular,
        key: Vec<u64>,
        cut: Cut,
        reorder_every: usize,
        comm: Arc<dyn Comm>,
    ) -> Decomposed {
        let me = comm.rank();
        let p = &mut part.particles;
        for s in 0..p.len() {
            if cut.regions.owner(p.pos[s]) != me {
                p.fixity[s] |= GHOST;
            }
        }
        part.grid.reorder_every = 0;
        let follows = part
            .walls
            .iter()
            .map(|w| w.motion.follows_state())
            .collect();
        let mut d = Decomposed {
            part,
            comm,
            key,
            regions: cut.regions,
            n_total: cut.n_total,
            max_radius: cut.max_radius,
            reorder_every,
            balance_threshold: 0.1,
            imbalance: 0.0,
            recuts: 0,
            arrivals: 0,
            histories_in: 0,
            stepping: Traffic::default(),
            halo_send: Vec::new(),
            halo_recv: Vec::new(),
            follows,
        };
        d.index_halo(cut.width);
        d.imbalance = d.measure_imbalance(&d.owned_counts());
        d
    }

    /// The whole assembly's critical step and time-step warning
    /// ([`Granular::critical_step`], [`Granular::dt_warning`]) with the
    /// disc–body laws `bodies`, collective: from the discs that decide it
    /// (each rank's lightest, the first of each material, its first
    /// three), merged in key order as the whole's slots.
    pub fn critical_step(
        &self,
        bodies: &[crate::dem::contact::ContactLaw],
    ) -> (crate::dem::critical::Critical, Option<String>) {
        let p = &self.part.particles;
        let owned: Vec<usize> = (0..p.len()).filter(|&s| p.fixity[s] & GHOST == 0).collect();
        let mut pick: Vec<usize> = owned.iter().copied().take(3).collect();
        let lightest = owned
            .iter()
            .min_by(|&&a, &&b| p.mass[a].total_cmp(&p.mass[b]));
        pick.extend(lightest);
        let mut seen = vec![false; self.part.materials.len()];
        for &s in &owned {
            if !std::mem::replace(&mut seen[p.material[s] as usize], true) {
                pick.push(s);
            }
        }
        let mut b = Pack::default();
        for &s in &pick {
            b.u64(self.key[s]);
            b.f64(p.mass[s]);
            b.f64(p.radius[s]);
            b.u16(p.material[s]);
        }
        let mut all: Vec<(u64, f64, f64, u16)> = Vec::new();
        for b in self.comm.all_gather(&b.0) {
            let mut u = Unpack(&b);
            while !u.is_empty() {
                all.push((u.u64(), u.f64(), u.f64(), u.u16()));
            }
        }
        all.sort_by_key(|e| e.0);
        all.dedup_by_key(|e| e.0);
        let few = Particles {
            pos: vec![Vec2::ZERO; all.len()],
            mass: all.iter().map(|e| e.1).collect(),
            radius: all.iter().map(|e| e.2).collect(),
            material: all.iter().map(|e| e.3).collect(),
            ..Particles::default()
        };
        let g = self.part.with_discs(few);
        (g.critical_step(bodies), g.dt_warning(bodies))
    }

    /// Sum the totals of every wall over the ranks each step, not only of
    /// those whose motion follows the state (a coupled run's energy
    /// account takes the work of every wall each step).
    pub fn sum_every_wall(&mut self) {
        self.follows.iter_mut().for_each(|f| *f = true);
    }

    /// Key of the disc in each slot of the part.
    pub fn keys(&self) -> &[u64] {
        &self.key
    }

    /// Largest radius of the whole assembly.
    pub fn max_radius(&self) -> f64 {
        self.max_radius
    }

    /// The communicator.
    pub fn comm(&self) -> &dyn Comm {
        &*self.comm
    }

    /// Discs of the whole assembly.
    pub fn total(&self) -> usize {
        self.n_total
    }

    /// Discs this rank owns (ghosts not counted).
    pub fn owned(&self) -> usize {
        self.part
            .particles
            .fixity
            .iter()
            .filter(|&&f| f & GHOST == 0)
            .count()
    }

    /// Ghosts this rank holds.
    pub fn ghosts(&self) -> usize {
        self.part.particles.len() - self.owned()
    }

    /// Rebuild the contact list now if the whole assembly would
    /// (collective): before the first record of a run.
    pub fn prepare(&mut self) {
        if self
            .part
            .grid
            .needs_rebuild(self.part.max_disp, &self.part.walls)
        {
            self.rebuild();
        }
    }

    /// One time step of the whole assembly (collective): ghosts refreshed
    /// (or the list rebuilt with migration when the whole would rebuild
    /// it), the part stepped, the global values agreed. `flag` is any
    /// per-rank condition to be or-ed over the ranks (e.g. a stop
    /// request). Returns whether every disc passed the step check, and the
    /// flag of any rank.
    pub fn step(&mut self, flag: bool) -> (bool, bool) {
        self.begin_step();
        self.advance(flag)
    }

    /// The first part of [`step`](Self::step) (collective): the ghosts
    /// refreshed, or the list rebuilt with migration when the whole would
    /// rebuild it (the slots may change).
    pub fn begin_step(&mut self) {
        self.metered(|d| {
            if d.part.grid.needs_rebuild(d.part.max_disp, &d.part.walls) {
                d.rebuild();
            } else {
                d.refresh_ghosts();
            }
        })
    }

    /// `f`, its traffic added to [`stepping`](Self::stepping).
    fn metered<T>(&mut self, f: impl FnOnce(&mut Self) -> T) -> T {
        let t0 = self.comm.traffic();
        let r = f(self);
        let t1 = self.comm.traffic();
        self.stepping.bytes += t1.bytes - t0.bytes;
        self.stepping.messages += t1.messages - t0.messages;
        self.stepping.seconds += t1.seconds - t0.seconds;
        r
    }

    /// The rest of [`step`](Self::step) after
    /// [`begin_step`](Self::begin_step) (collective).
    pub fn advance(&mut self, flag: bool) -> (bool, bool) {
        let bad = self.part.advance_discs();
        self.metered(|d| d.agree(bad, flag))
    }

    /// The global values of the step (collective): the largest
    /// displacement, the step check, the totals of the walls that follow
    /// the state; the part's step finished with them.
    fn agree(&mut self, bad: bool, flag: bool) -> (bool, bool) {
        let mut out = Pack::default();
        // a rank without discs has no displacement (the sweep's infinity
        // means "no reference")
        out.f64(if self.part.particles.is_empty() {
            0.0
        } else {
            self.part.max_disp
        });
        out.u8(bad as u8 | (flag as u8) << 1);
        let terms: Vec<_> = self.part.wall_terms().collect();
        for t in terms.iter().filter(|t| self.follows[t.wall as usize]) {
            pack_term(&mut out, self.key[t.disc as usize], t);
        }
        let all = self.comm.all_gather(&out.0);
        let (mut max_disp, mut bad, mut any) = (0.0f64, false, false);
        let mut merged = Vec::new();
        for b in &all {
            let mut u = Unpack(b);
            let m = u.f64();
            // as the undivided sweep: a NaN displacement never wins
            max_disp = max_disp.max(m);
            let f = u.u8();
            bad |= f & 1 != 0;
            any |= f & 2 != 0;
            while !u.is_empty() {
                merged.push(unpack_term(&mut u));
            }
        }
        self.part.max_disp = max_disp;
        merged.sort_by_key(|(k, t)| (*k, t.wall));
        let follows = &self.follows;
        let others = terms.iter().filter(|t| !follows[t.wall as usize]);
        self.part
            .set_wall_totals(merged.iter().map(|(_, t)| t).chain(others));
        self.part.finish_step(!bad);
        (!bad, any)
    }

    /// Make the part ready for outputs reduced over the ranks (shares of
    /// probes, `crate::model::probe::share`), collective: the ghosts
    /// refreshed from their owners and every wall's totals summed as the
    /// whole sums them (terms merged in key order). The steps are not
    /// changed by it.
    pub fn ready_outputs(&mut self) {
        self.refresh_ghosts();
        let mut out = Pack::default();
        for t in self.part.wall_terms() {
            pack_term(&mut out, self.key[t.disc as usize], &t);
        }
        let all = self.comm.all_gather(&out.0);
        let mut merged = Vec::new();
        for b in &all {
            let mut u = Unpack(b);
            while !u.is_empty() {
                merged.push(unpack_term(&mut u));
            }
        }
        merged.sort_by_key(|(k, t)| (*k, t.wall));
        self.part.set_wall_totals(merged.iter().map(|(_, t)| t));
    }

    /// Refresh every ghost from its owner: position, velocity, spin.
    fn refresh_ghosts(&mut self) {
        const B: usize = 40;
        let p = &self.part.particles;
        let sends: Vec<(usize, Vec<u8>)> = self
            .halo_send
            .iter()
            .map(|(r, slots)| {
                let mut b = Pack(Vec::with_capacity(slots.len() * B));
                for &s in slots {
                    let s = s as usize;
                    b.vec2(p.pos[s]);
                    b.vec2(p.vel[s]);
                    b.f64(p.omega[s]);
                }
                (*r, b.0)
            })
            .collect();
        let mut bufs: Vec<(usize, Vec<u8>)> = self
            .halo_recv
            .iter()
            .map(|(r, slots)| (*r, vec![0u8; slots.len() * B]))
            .collect();
        {
            let send: Vec<(usize, &[u8])> = sends.iter().map(|(r, b)| (*r, &b[..])).collect();
            let mut recv: Vec<(usize, &mut [u8])> =
                bufs.iter_mut().map(|(r, b)| (*r, &mut b[..])).collect();
            self.comm.exchange(&send, &mut recv);
        }
        let p = &mut self.part.particles;
        for ((_, slots), (_, b)) in self.halo_recv.iter().zip(&bufs) {
            let mut u = Unpack(b);
            for &s in slots {
                let s = s as usize;
                p.pos[s] = u.vec2();
                p.vel[s] = u.vec2();
                p.omega[s] = u.f64();
            }
        }
    }

    /// The halo lists from the present part: each owned disc (in slot
    /// order) goes to the ranks whose region is within `width`, each ghost
    /// comes from the owner of its position's region.
    fn index_halo(&mut self, width: f64) {
        let size = self.comm.size();
        let me = self.comm.rank();
        let mut send = vec![Vec::new(); size];
        let mut recv = vec![Vec::new(); size];
        let mut near = Vec::new();
        let p = &self.part.particles;
        for s in 0..p.len() {
            if p.fixity[s] & GHOST != 0 {
                recv[self.regions.owner(p.pos[s])].push(s as u32);
            } else {
                self.regions.near(p.pos[s], me, width, &mut near);
                for &r in &near {
                    send[r].push(s as u32);
                }
            }
        }
        let keep = |v: Vec<Vec<u32>>| {
            v.into_iter()
                .enumerate()
                .filter(|(r, l)| *r != me && !l.is_empty())
                .collect()
        };
        self.halo_send = keep(send);
        self.halo_recv = keep(recv);
    }

    /// Owned discs of every rank (collective).
    fn owned_counts(&self) -> Vec<u64> {
        let mine = (self.owned() as u64).to_le_bytes();
        self.comm
            .all_gather(&mine)
            .iter()
            .map(|b| Unpack(b).u64())
            .collect()
    }

    fn measure_imbalance(&self, counts: &[u64]) -> f64 {
        let mean = self.n_total as f64 / counts.len() as f64;
        let max = counts.iter().copied().max().unwrap_or(0) as f64;
        if mean > 0.0 { max / mean - 1.0 } else { 0.0 }
    }

    /// The collective rebuild: regions recut if unbalanced, keys renewed
    /// when the whole would renumber, discs migrated to their owners with
    /// their histories, ghosts sent, the part's list rebuilt.
    fn rebuild(&mut self) {
        let size = self.comm.size();
        let skin = self.part.grid.skin;
        let width = reach(self.max_radius, skin);
        // counts and the box of the owned centres, from every rank
        let (lo, hi) = owned_bounds(&self.part.particles);
        // and how many discs each region would own now
        let mut mine = vec![0u64; size];
        let p = &self.part.particles;
        for s in (0..p.len()).filter(|&s| p.fixity[s] & GHOST == 0) {
            mine[self.regions.owner(p.pos[s])] += 1;
        }
        let mut b = Pack::default();
        mine.iter().for_each(|&c| b.u64(c));
        b.vec2(lo);
        b.vec2(hi);
        let all = self.comm.all_gather(&b.0);
        let (mut glo, mut ghi) = (lo, hi);
        let mut counts = vec![0u64; size];
        for b in &all {
            let mut u = Unpack(b);
            counts.iter_mut().for_each(|c| *c += u.u64());
            let (l, h) = (u.vec2(), u.vec2());
            glo = Vec2::new(glo.x.min(l.x), glo.y.min(l.y));
            ghi = Vec2::new(ghi.x.max(h.x), ghi.y.max(h.y));
        }
        if self.measure_imbalance(&counts) > self.balance_threshold {
            self.recut();
        }
        if self.reorder_every > 0 && self.part.grid.rebuilds.is_multiple_of(self.reorder_every) {
            let spec = GridSpec::new(glo, ghi, self.max_radius, skin, self.n_total);
            let p = &self.part.particles;
            for s in 0..p.len() {
                if p.fixity[s] & GHOST == 0 {
                    self.key[s] = spec.key(p.pos[s], p.id[s]);
                }
            }
        }
        self.migrate(width);
        self.part.grid.stale = true;
        self.part.prepare_contacts();
        self.index_halo(width);
        self.imbalance = self.measure_imbalance(&self.owned_counts());
    }

    /// Cut the regions again from a sample of every rank's centres.
    fn recut(&mut self) {
        let p = &self.part.particles;
        let owned = (0..p.len()).filter(|&s| p.fixity[s] & GHOST == 0);
        let stride = self.n_total.div_ceil(SAMPLE * self.comm.size()).max(1);
        let mut b = Pack::default();
        for s in owned.step_by(stride) {
            b.vec2(p.pos[s]);
        }
        let mut pts = Vec::new();
        for b in self.comm.all_gather(&b.0) {
            let mut u = Unpack(&b);
            while !u.is_empty() {
                pts.push(u.vec2());
            }
        }
        let new = Subdomains::bisect(&pts, self.comm.size());
        if new != self.regions {
            self.regions = new;
            self.recuts += 1;
        }
    }

    /// Send each owned disc to its owner (with its pair and wall
    /// histories) and to the ranks that need it as a ghost; rebuild the
    /// part's discs in key order from what stays and what arrives, with
    /// the contact list moved onto them. Beyond the part, a rank holds
    /// a few bytes per disc while it does (its new order, the old ghost
    /// flags; the columns are rearranged in place).
    fn migrate(&mut self, width: f64) {
        let me = self.comm.rank();
        let (send, mut keep) = self.outgoing(width);
        let got = self.comm.all_to_all(send);
        let arrived = Arrivals::unpack(&got, me);
        drop(got);
        keep.extend((0..arrived.records.len() as u32).map(Src::Got));
        self.arrivals += arrived.records.iter().filter(|r| r.owned).count();
        let live = |e: &&(u32, u32, f64, f64)| e.2 != 0.0 || e.3 != 0.0;
        self.histories_in += arrived.pairs.iter().filter(live).count();
        self.histories_in += arrived.walls.iter().filter(live).count();
        // the new order: by key (a disc has one key, and one entry here)
        let records = &arrived.records;
        let key_of = |s: &Src| match *s {
            Src::Old(k) => self.key[k as usize],
            Src::Got(g) => records[g as usize].key,
        };
        keep.sort_unstable_by_key(key_of);
        // the keys in their new order, in place
        let taken = taken_slots(&keep, self.key.len());
        gather_in_place(&mut self.key, &keep, records, |r| r.key, &taken);
        drop(taken);
        // what is read of the old part after its columns are replaced
        let p = &self.part.particles;
        let old_slot = |id: u32| p.slot.get(id as usize).copied().unwrap_or(GONE);
        // a disc that arrives again (it was a ghost here): its old slot
        let again: Vec<(u32, u32)> = (keep.iter().enumerate())
            .filter_map(|(k, src)| match *src {
                Src::Got(g) => Some((old_slot(records[g as usize].id), k as u32)),
                Src::Old(_) => None,
            })
            .filter(|e| e.0 != GONE)
            .collect();
        // the arriving pair histories, unless this rank had the pair
        let was_owned = |s: u32| s != GONE && p.fixity[s as usize] & GHOST == 0;
        let pair_recs: Vec<(u32, u32, f64, f64)> = (arrived.pairs.iter())
            .filter(|(a, b, _, _)| !was_owned(old_slot(*a)) && !was_owned(old_slot(*b)))
            .copied()
            .collect();
        let old_fixity = p.fixity.clone();
        let mut np = std::mem::take(&mut self.part.particles);
        regather(&mut np, None, &keep, records, self.n_total);
        // a disc is owned here when its centre is in this rank's region
        for (f, &q) in np.fixity.iter_mut().zip(&np.pos) {
            *f &= !GHOST;
            if self.regions.owner(q) != me {
                *f |= GHOST;
            }
        }
        // old slot → new slot
        let mut new_of_old = vec![GONE; old_fixity.len()];
        for (k, src) in keep.iter().enumerate() {
            if let Src::Old(s) = *src {
                new_of_old[s as usize] = k as u32;
            }
        }
        drop(keep);
        again.iter().for_each(|&(s, k)| new_of_old[s as usize] = k);
        let mut list = std::mem::take(&mut self.part.contacts);
        let (extra, extra_walls) = arriving_histories(&np, &pair_recs, &arrived.walls);
        let ghost_old = |s: u32| old_fixity[s as usize] & GHOST != 0;
        list.remap(&new_of_old, np.len(), &extra, &extra_walls, |i, j| {
            !(ghost_old(i) && ghost_old(j))
        });
        self.part.particles = np;
        self.part.contacts = list;
    }

    /// What this rank sends at a migration (a buffer per rank: the discs,
    /// then the pair and wall histories of those that change owner) and
    /// the slots of the discs it keeps, owned or as ghosts.
    fn outgoing(&self, width: f64) -> (Vec<Vec<u8>>, Vec<Src>) {
        let me = self.comm.rank();
        let size = self.comm.size();
        let p = &self.part.particles;
        let n = p.len();
        let mut discs: Vec<Pack> = (0..size).map(|_| Pack::default()).collect();
        let mut counts = vec![0u32; size];
        // per old slot: the new owner (owned discs), else GONE
        let mut dest = vec![GONE; n];
        let mut keep: Vec<Src> = Vec::new();
        let mut near = Vec::new();
        for (s, dest) in dest.iter_mut().enumerate() {
            if p.fixity[s] & GHOST != 0 {
                continue;
            }
            let o = self.regions.owner(p.pos[s]);
            *dest = o as u32;
            self.regions.near(p.pos[s], o, width, &mut near);
            if o == me {
                keep.push(Src::Old(s as u32));
            } else {
                pack_disc(&mut discs[o], p, s, self.key[s], true);
                counts[o] += 1;
            }
            for &r in &near {
                if r == me {
                    keep.push(Src::Old(s as u32));
                } else {
                    pack_disc(&mut discs[r], p, s, self.key[s], false);
                    counts[r] += 1;
                }
            }
        }
        let (pairs, walls) = self.moving_histories(&dest);
        let send = (0..size)
            .map(|r| {
                if r == me {
                    return Vec::new();
                }
                let mut b = Pack::default();
                b.u32(counts[r]);
                b.0.extend_from_slice(&discs[r].0);
                b.0.extend_from_slice(&pairs[r].0);
                b.0.extend_from_slice(&walls[r].0);
                b.0
            })
            .collect();
        (send, keep)
    }

    /// The histories of the discs that move (`dest`: the new owner of each
    /// slot, [`GONE`] for a ghost): every pair and wall pair of theirs, for
    /// their new owner, each buffer led by its count.
    fn moving_histories(&self, dest: &[u32]) -> (Vec<Pack>, Vec<Pack>) {
        let (me, size) = (self.comm.rank(), self.comm.size());
        let p = &self.part.particles;
        let mut pairs: Vec<Pack> = (0..size).map(|_| Pack::default()).collect();
        let mut npairs = vec![0u32; size];
        let c = &self.part.contacts;
        let rolling = c.rolling && c.roll.len() == c.len();
        for (k, (i, j)) in c.pairs().enumerate() {
            let (oi, oj) = (dest[i], dest[j]);
            let mut put = |o: u32| {
                let b = &mut pairs[o as usize];
                b.u32(p.id[i]);
                b.u32(p.id[j]);
                b.f64(c.shear[k]);
                b.f64(if rolling { c.roll[k] } else { 0.0 });
                npairs[o as usize] += 1;
            };
            if oi != GONE && oi as usize != me {
                put(oi);
            }
            if oj != GONE && oj as usize != me && oj != oi {
                put(oj);
            }
        }
        let mut walls: Vec<Pack> = (0..size).map(|_| Pack::default()).collect();
        let mut nwalls = vec![0u32; size];
        for w in &c.walls {
            let o = dest[w.disc as usize];
            if o != GONE && o as usize != me {
                let b = &mut walls[o as usize];
                b.u32(p.id[w.disc as usize]);
                b.u32(w.wall);
                b.f64(w.fs);
                b.f64(w.mr);
                nwalls[o as usize] += 1;
            }
        }
        let led = |count: u32, body: Pack| {
            let mut b = Pack::default();
            b.u32(count);
            b.0.extend_from_slice(&body.0);
            b
        };
        let pairs = pairs.into_iter().zip(npairs).map(|(b, c)| led(c, b));
        let walls = walls.into_iter().zip(nwalls).map(|(b, c)| led(c, b));
        (pairs.collect(), walls.collect())
    }

    /// The undivided assembly as it would be now, assembled on rank 0
    /// (`None` on the other ranks; collective) from `skeleton` (an
    /// assembly of the run without discs, the whole's
    /// [`with_same_discs`](Granular::with_same_discs)): discs in slot (key) order, the
    /// pair list, histories, walls with their global totals. Rank 0 holds
    /// it only as long as the caller keeps it (frames, checkpoints).
    pub fn gather_whole(&self, skeleton: &Granular) -> Option<Granular> {
        let (state, particles) = self.gather_parts()?;
        let mut whole = skeleton.with_same_discs(particles);
        whole
            .restore_state(&state)
            .expect("the gathered state fits the gathered discs");
        Some(whole)
    }

    /// The state the undivided assembly would have now, assembled on rank
    /// 0 (`None` on the other ranks); collective. Discs in slot (key)
    /// order, the pair list sorted, walls with their global totals.
    pub fn gather(&self) -> Option<GranularState> {
        self.gather_parts().map(|(state, _)| state)
    }

    /// [`gather`](Self::gather), and the discs with their constants.
    fn gather_parts(&self) -> Option<(GranularState, Particles)> {
        let me = self.comm.rank();
        let g = &self.part;
        let p = &g.particles;
        let c = &g.contacts;
        let n = p.len();
        let has_ref = g.grid.ref_pos.len() == n;
        let rolling = c.rolling;
        let mut b = Pack::default();
        let owned: Vec<usize> = (0..n).filter(|&s| p.fixity[s] & GHOST == 0).collect();
        b.u32(owned.len() as u32);
        for &s in &owned {
            pack_disc(&mut b, p, s, self.key[s], true);
            b.vec2(if has_ref {
                g.grid.ref_pos[s]
            } else {
                Vec2::ZERO
            });
        }
        let mine = |&(_, (i, _)): &(usize, (usize, usize))| p.fixity[i] & GHOST == 0;
        b.u32(c.pairs().enumerate().filter(mine).count() as u32);
        for (k, (i, j)) in c.pairs().enumerate().filter(mine) {
            b.u64(self.key[i]);
            b.u64(self.key[j]);
            b.f64(c.shear[k]);
            b.f64(if rolling && c.roll.len() == c.len() {
                c.roll[k]
            } else {
                0.0
            });
        }
        b.u32(c.walls.len() as u32);
        for w in &c.walls {
            b.u64(self.key[w.disc as usize]);
            b.u32(w.wall);
            b.f64(w.fs);
            b.f64(w.mr);
        }
        let terms: Vec<_> = g.wall_terms().collect();
        b.u32(terms.len() as u32);
        for t in &terms {
            pack_term(&mut b, self.key[t.disc as usize], t);
        }
        let mut send = vec![Vec::new(); self.comm.size()];
        send[0] = b.0;
        let got = self.comm.all_to_all(send);
        (me == 0).then(|| self.assemble(&got, has_ref))
    }

    /// [`gather`](Self::gather) on rank 0: every rank's records merged.
    fn assemble(&self, got: &[Vec<u8>], has_ref: bool) -> (GranularState, Particles) {
        let g = &self.part;
        let rolling = g.contacts.rolling;
        let mut discs: Vec<(Record, Vec2)> = Vec::with_capacity(self.n_total);
        let mut pairs: Vec<(u64, u64, f64, f64)> = Vec::new();
        let mut wall_pairs: Vec<(u64, u32, f64, f64)> = Vec::new();
        let mut terms = Vec::new();
        for b in got {
            let mut u = Unpack(b);
            for _ in 0..u.u32() {
                let r = unpack_disc(&mut u);
                discs.push((r, u.vec2()));
            }
            for _ in 0..u.u32() {
                pairs.push((u.u64(), u.u64(), u.f64(), u.f64()));
            }
            for _ in 0..u.u32() {
                wall_pairs.push((u.u64(), u.u32(), u.f64(), u.f64()));
            }
            for _ in 0..u.u32() {
                terms.push(unpack_term(&mut u));
            }
        }
        discs.sort_unstable_by_key(|d| d.0.key);
        let keys: Vec<u64> = discs.iter().map(|d| d.0.key).collect();
        let slot = |k: u64| keys.partition_point(|&x| x < k) as u32;
        let mut pk: Vec<([u32; 2], f64, f64)> = pairs
            .iter()
            .map(|&(a, b, fs, mr)| ([slot(a), slot(b)], fs, mr))
            .collect();
        drop(pairs);
        pk.sort_unstable_by_key(|e| e.0);
        let mut wp: Vec<WallPairState> = wall_pairs
            .iter()
            .map(|&(k, wall, fs, mr)| WallPairState {
                disc: slot(k),
                wall,
                fs,
                mr,
            })
            .collect();
        wp.sort_unstable_by_key(|w| (w.disc, w.wall));
        terms.sort_by_key(|(k, t)| (*k, t.wall));
        let mut walls = g.walls.clone();
        {
            // the totals as the whole sums them
            let mut tmp = g.with_discs(Particles::default());
            tmp.walls = std::mem::take(&mut walls);
            tmp.set_wall_totals(terms.iter().map(|(_, t)| t));
            walls = tmp.walls;
        }
        let ref_pos = if has_ref {
            discs.iter().map(|d| d.1).collect()
        } else {
            Vec::new()
        };
        let records: Vec<Record> = discs.into_iter().map(|d| d.0).collect();
        let sources: Vec<Src> = (0..records.len() as u32).map(Src::Got).collect();
        let mut particles = Particles::default();
        regather(&mut particles, None, &sources, &records, self.n_total);
        drop(records);
        let p = &particles;
        let state = GranularState {
            // bonded and clumped assemblies are not decomposed
            bonds: Default::default(),
            clumps: Default::default(),
            step: g.step,
            time: g.time,
            max_disp: g.max_disp,
            id: p.id.clone(),
            pos: p.pos.clone(),
            vel: p.vel.clone(),
            theta: p.theta.clone(),
            omega: p.omega.clone(),
            force: p.force.clone(),
            torque: p.torque.clone(),
            walls: walls.iter().map(WallState::from).collect(),
            pairs: pk.iter().map(|e| e.0).collect(),
            shear: pk.iter().map(|e| e.1).collect(),
            rolling,
            roll: if rolling {
                pk.iter().map(|e| e.2).collect()
            } else {
                Vec::new()
            },
            wall_pairs: wp,
            ref_pos,
            wall_ref: g.grid.wall_ref.clone(),
            rebuilds: g.grid.rebuilds,
            stale: g.grid.stale,
        };
        (state, particles)
    }

    /// Position and radius of the discs with ids `ids`, on rank 0 (`None`
    /// on the others); collective. Each rank sends those it owns: a file
    /// of every disc is written a range of ids at a time, without the
    /// whole assembly on any rank.
    pub fn gather_ids(&self, ids: std::ops::Range<usize>) -> Option<Vec<(Vec2, f64)>> {
        let p = &self.part.particles;
        let mut b = Pack::default();
        for id in ids.clone() {
            if let Some(s) = p.own_slot(id) {
                b.u32(id as u32);
                b.vec2(p.pos[s]);
                b.f64(p.radius[s]);
            }
        }
        let mut send = vec![Vec::new(); self.comm.size()];
        send[0] = b.0;
        let got = self.comm.all_to_all(send);
        if self.comm.rank() != 0 {
            return None;
        }
        let mut out = vec![(Vec2::ZERO, f64::NAN); ids.len()];
        for b in &got {
            let mut u = Unpack(b);
            while !u.is_empty() {
                let id = u.u32() as usize;
                out[id - ids.start] = (u.vec2(), u.f64());
            }
        }
        Some(out)
    }
}

/// The box of the finite centres of the discs `p` owns (not its ghosts),
/// as [`centre_bounds`](crate::dem::broadphase::centre_bounds) of them,
/// without a list of them.
fn owned_bounds(p: &Particles) -> (Vec2, Vec2) {
    let none = (
        Vec2::new(f64::INFINITY, f64::INFINITY),
        Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    (0..p.len())
        .filter(|&s| p.fixity[s] & GHOST == 0)
        .map(|s| p.pos[s])
        .filter(|q| q.x.is_finite() && q.y.is_finite())
        .fold(none, |(a, b), q| {
            (
                Vec2::new(a.x.min(q.x), a.y.min(q.y)),
                Vec2::new(b.x.max(q.x), b.y.max(q.y)),
            )
        })
}

/// Reach of a disc: the largest centre distance of a listed pair.
fn reach(max_radius: f64, skin: f64) -> f64 {
    2.0 * max_radius + skin
}

/// The stride of the centres of `n` discs that cut the regions: at most
/// `SAMPLE` (50 000) of them, evenly strided from the first.
pub fn sample_stride(n: usize) -> usize {
    n.div_ceil(SAMPLE).max(1)
}

/// At most [`SAMPLE`] of the centres ([`sample_stride`]).
fn sample(pos: &[Vec2], n: usize) -> Vec<Vec2> {
    pos.iter().step_by(sample_stride(n)).copied().collect()
}

/// The discs of a new part into `p`: each from a slot of `old` (of `p`
/// itself when `None`, whose columns are then rearranged in place one at
/// a time: no second column is made) or a received
/// record; `slot` indexes the part's ids among the `n_total` of the whole
/// assembly ([`SlotIndex::of_part`]).
fn regather(
    p: &mut Particles,
    old: Option<&Particles>,
    sources: &[Src],
    got: &[Record],
    n_total: usize,
) {
    // the old slots some source takes (when the columns are replaced in
    // place)
    let taken = match old {
        Some(_) => Vec::new(),
        None => taken_slots(sources, p.len()),
    };
    let col = Col(&taken);
    let (s, g) = (sources, got);
    col.put(&mut p.id, old.map(|o| &o.id), s, g, |r| r.id);
    col.put(&mut p.pos, old.map(|o| &o.pos), s, g, |r| r.pos);
    col.put(&mut p.vel, old.map(|o| &o.vel), s, g, |r| r.vel);
    col.put(&mut p.theta, old.map(|o| &o.theta), s, g, |r| r.theta);
    col.put(&mut p.omega, old.map(|o| &o.omega), s, g, |r| r.omega);
    col.put(&mut p.radius, old.map(|o| &o.radius), s, g, |r| r.radius);
    col.put(&mut p.mass, old.map(|o| &o.mass), s, g, |r| r.mass);
    col.put(&mut p.inertia, old.map(|o| &o.inertia), s, g, |r| r.inertia);
    col.put(&mut p.inv_mass, old.map(|o| &o.inv_mass), s, g, |r| {
        r.inv_mass
    });
    let inv_inertia = old.map(|o| &o.inv_inertia);
    col.put(&mut p.inv_inertia, inv_inertia, s, g, |r| r.inv_inertia);
    col.put(&mut p.force, old.map(|o| &o.force), s, g, |r| r.force);
    col.put(&mut p.torque, old.map(|o| &o.torque), s, g, |r| r.torque);
    col.put(&mut p.fixity, old.map(|o| &o.fixity), s, g, |r| r.fixity);
    col.put(&mut p.material, old.map(|o| &o.material), s, g, |r| {
        r.material
    });
    // clumped assemblies are not decomposed
    // in place: the old part's are not kept beside the new ones
    p.clump.clear();
    p.clump.resize(p.id.len(), crate::dem::clumps::NO_CLUMP);
    // the ids of the part among those of the whole (the old index let go
    // first)
    p.slot = Default::default();
    p.slot = SlotIndex::of_part(n_total, &p.id);
}

/// A column of a new part made from `sources` ([`regather`]): from the
/// old part's column, or in place ([`gather_in_place`], the old slots
/// some source takes marked in the bits held).
struct Col<'a>(&'a [u64]);

impl Col<'_> {
    fn put<T: Copy + Default>(
        &self,
        dst: &mut Vec<T>,
        old: Option<&Vec<T>>,
        sources: &[Src],
        got: &[Record],
        f: impl Fn(&Record) -> T,
    ) {
        match old {
            Some(old) => {
                *dst = sources
                    .iter()
                    .map(|s| match *s {
                        Src::Old(k) => old[k as usize],
                        Src::Got(k) => f(&got[k as usize]),
                    })
                    .collect()
            }
            None => gather_in_place(dst, sources, got, f, self.0),
        }
    }
}

/// The old slots (of `n`) that some of `sources` takes, a bit each.
fn taken_slots(sources: &[Src], n: usize) -> Vec<u64> {
    let mut t = vec![0u64; n.div_ceil(64)];
    for s in sources {
        if let Src::Old(k) = *s {
            t[k as usize / 64] |= 1 << (k % 64);
        }
    }
    t
}

/// `v[j]` made the old `v[k]` for each `sources[j] = Old(k)` and
/// `f(got[g])` for each `Got(g)`, in place: no second column is made. The
/// moves follow the map's chains (from a slot whose old content no
/// source takes, `taken` marking those some source takes) and then its
/// cycles (through one value held aside); the arrivals come last.
fn gather_in_place<T: Copy + Default>(
    v: &mut Vec<T>,
    sources: &[Src],
    got: &[Record],
    f: impl Fn(&Record) -> T,
    taken: &[u64],
) {
    let (n, m) = (v.len(), sources.len());
    if m > n {
        v.resize(m, T::default());
    }
    let from = |j: usize| match sources.get(j) {
        Some(&Src::Old(k)) => Some(k as usize),
        _ => None,
    };
    let bit = |b: &[u64], i: usize| (b[i / 64] >> (i % 64)) & 1 != 0;
    let mut done = vec![0u64; m.div_ceil(64)];
    for j in 0..m {
        if (j < n && bit(taken, j)) || from(j).is_none() {
            continue;
        }
        // a chain: each slot takes the next one's content, which its
        // slot then no longer needs
        let mut cur = j;
        while let Some(k) = from(cur) {
            v[cur] = v[k];
            done[cur / 64] |= 1 << (cur % 64);
            cur = k;
        }
    }
    for j in 0..m {
        if bit(&done, j) || from(j).is_none() {
            continue;
        }
        // a cycle (every slot left is on one)
        let first = v[j];
        let mut cur = j;
        while let Some(k) = from(cur) {
            done[cur / 64] |= 1 << (cur % 64);
            if k == j {
                v[cur] = first;
                break;
            }
            v[cur] = v[k];
            cur = k;
        }
    }
    for (j, s) in sources.iter().enumerate() {
        if let Src::Got(g) = *s {
            v[j] = f(&got[g as usize]);
        }
    }
    v.truncate(m);
}

fn pack_disc(b: &mut Pack, p: &Particles, s: usize, key: u64, owned: bool) {
    b.u32(p.id[s]);
    b.u64(key);
    b.u8(owned as u8);
    b.vec2(p.pos[s]);
    b.vec2(p.vel[s]);
    b.f64(p.theta[s]);
    b.f64(p.omega[s]);
    b.f64(p.radius[s]);
    b.f64(p.mass[s]);
    b.f64(p.inertia[s]);
    b.f64(p.inv_mass[s]);
    b.f64(p.inv_inertia[s]);
    b.vec2(p.force[s]);
    b.f64(p.torque[s]);
    b.u8(p.fixity[s] & !GHOST);
    b.u16(p.material[s]);
}

fn unpack_disc(u: &mut Unpack) -> Record {
    Record {
        id: u.u32(),
        key: u.u64(),
        owned: u.u8() != 0,
        pos: u.vec2(),
        vel: u.vec2(),
        theta: u.f64(),
        omega: u.f64(),
        radius: u.f64(),
        mass: u.f64(),
        inertia: u.f64(),
        inv_mass: u.f64(),
        inv_inertia: u.f64(),
        force: u.vec2(),
        torque: u.f64(),
        fixity: u.u8(),
        material: u.u16(),
    }
}

fn pack_term(b: &mut Pack, key: u64, t: &crate::dem::WallTerm) {
    b.u64(key);
    b.u32(t.wall);
    b.vec2(t.f);
    b.u8(t.counted as u8);
    b.f64(t.kn);
    b.f64(t.cn);
}

fn unpack_term(u: &mut Unpack) -> (u64, crate::dem::WallTerm) {
    let key = u.u64();
    let wall = u.u32();
    let f = u.vec2();
    let counted = u.u8() != 0;
    let (kn, cn) = (u.f64(), u.f64());
    (
        key,
        crate::dem::WallTerm {
            disc: 0,
            wall,
            f,
            counted,
            kn,
            cn,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The in-place gather is the gather into a new column: chains, cycles,
    /// a fixed point, arrivals, slots let go, a part that grows or
    /// shrinks.
    #[test]
    fn a_column_gathered_in_place_is_the_gathered_column() {
        let rec = |x: u32| Record {
            id: x,
            key: 0,
            owned: true,
            pos: Vec2::ZERO,
            vel: Vec2::ZERO,
            theta: 0.0,
            omega: 0.0,
            radius: 0.0,
            mass: 0.0,
            inertia: 0.0,
            inv_mass: 0.0,
            inv_inertia: 0.0,
            force: Vec2::ZERO,
            torque: 0.0,
            fixity: 0,
            material: 0,
        };
        let got: Vec<Record> = (100..110).map(rec).collect();
        let (o, g) = (Src::Old, Src::Got);
        let cases: Vec<(usize, Vec<Src>)> = vec![
            // a cycle 0→1→2→0, a fixed point, a chain 4←5←6 from a free slot
            (7, vec![o(1), o(2), o(0), o(3), o(5), o(6), g(0)]),
            // grows: old slots move up, arrivals between them
            (4, vec![g(0), o(0), o(1), g(1), o(2), o(3), g(2)]),
            // shrinks: slots let go, the rest moves down, reversed
            (8, vec![o(7), o(5), g(3), o(2), o(0)]),
            (3, vec![g(0), g(1)]),
            (0, vec![g(4), g(5)]),
            (5, vec![]),
        ];
        for (n, sources) in cases {
            let old: Vec<u32> = (0..n as u32).collect();
            let want: Vec<u32> = sources
                .iter()
                .map(|s| match *s {
                    Src::Old(k) => old[k as usize],
                    Src::Got(k) => got[k as usize].id,
                })
                .collect();
            let taken = taken_slots(&sources, n);
            let mut v = old.clone();
            gather_in_place(&mut v, &sources, &got, |r| r.id, &taken);
            assert_eq!(v, want, "{n} slots");
        }
    }
}
