//! The contact sweep: one pass over the discs that evaluates every contact
//! and (optionally) advances each disc as soon as its force is complete.
//!
//! Pairs are listed with `i < j` and sorted by `i`, so once the pairs of
//! discs `0..=d` are evaluated, every contact of disc `d` is: its pairs as
//! first disc were just done and its pairs as second disc have a smaller
//! first disc. Disc `d` can then be advanced at once, while its data and
//! its neighbours' are still in the L1 cache: no per-contact force buffer
//! is written and read back, and the discs are streamed through memory once
//! per step instead of three times.
//!
//! The discs are cut into blocks of
//! [`block_size`](super::broadphase::block_size) slots, swept in
//! parallel. A pair whose second disc lies in a later block ("cross" pair,
//! a few per cent of the pairs with the space-filling slot order) is
//! evaluated first, from the state before the step, into a small buffer;
//! each block adds the cross forces of its discs before sweeping. Block
//! boundaries do not depend on the thread count, and every disc sums its
//! forces in a fixed order (cross pairs in list order, then pairs as second
//! disc in the order of the first disc, then pairs as first disc in list
//! order, then walls), so the result is bitwise the same on any number of
//! threads.

use super::bonds::{BondForce, BondLaw, Break, Held, HeldForces};
use super::broadphase::{ContactList, CrossIndex, WallPair};
use super::clumps::{ClumpRows, Discs, NO_CLUMP};
use super::contact::{self, ContactForce, ContactLaw, Side, effective_mass};
use super::integrate;
use super::particles::{GHOST, HELD, Particles};
use super::walls::Wall;
use super::{BodyDamping, Granular};
use crate::geom::Vec2;
use rayon::prelude::*;

thread_local! {
    /// Per-thread accumulators of the block being swept (grown once). A
    /// sweep leaves every entry it used at zero again (each disc takes its
    /// own), so they are not cleared per block; `true` while a sweep runs
    /// (a sweep that panicked left them dirty: cleared at the next).
    static ACC: std::cell::RefCell<(Vec<(Vec2, f64)>, bool)> = const { std::cell::RefCell::new((Vec::new(), false)) };
    /// Per-thread accumulators of the rolling moments (rolling resistance
    /// only), kept as `ACC`.
    static ACC_ROLL: std::cell::RefCell<(Vec<f64>, bool)> = const { std::cell::RefCell::new((Vec::new(), false)) };
    /// Per-thread accumulators of the bond moments on second discs (bonds
    /// only), kept as `ACC`.
    static ACC_BOND: std::cell::RefCell<(Vec<f64>, bool)> = const { std::cell::RefCell::new((Vec::new(), false)) };
    /// Per-thread buffer of what the block's bonds do ([`bond_block`]).
    static BOND_OUT: std::cell::RefCell<Vec<BondForce>> = const { std::cell::RefCell::new(Vec::new()) };
}

type Acc<T> = std::thread::LocalKey<std::cell::RefCell<(Vec<T>, bool)>>;

/// Call `f` with the first `n` entries of the zeroed accumulator `acc`
/// ([`zeroed`]), or with none when not `needed`.
fn with_zeroed<T: Copy + Default + 'static, R>(
    acc: &'static Acc<T>,
    needed: bool,
    n: usize,
    f: impl FnOnce(&mut [T]) -> R,
) -> R {
    if !needed {
        return f(&mut []);
    }
    acc.with_borrow_mut(|cell| {
        let r = f(zeroed(cell, n));
        cell.1 = false;
        r
    })
}

/// The first `n` entries of a zeroed per-thread accumulator, marked in use.
fn zeroed<T: Copy + Default>((v, busy): &mut (Vec<T>, bool), n: usize) -> &mut [T] {
    if *busy {
        v.fill(T::default());
    }
    if v.len() < n {
        v.resize(n, T::default());
    }
    *busy = true;
    &mut v[..n]
}

/// Per-step constants of the sweep.
struct Ctx<'a> {
    laws: &'a [ContactLaw],
    dash: &'a [[f64; 4]],
    wall_laws: &'a [ContactLaw],
    n_mat: usize,
    walls: &'a [Wall],
    first: &'a [u32],
    cross_buf: &'a [(ContactForce, f64)],
    /// Rolling moment and new history of each cross pair (rolling only).
    cross_roll: &'a [(f64, f64)],
    cross_first: &'a [u32],
    cross_in_start: &'a [u32],
    cross_in: &'a [(u32, u32)],
    block: usize,
    gravity: Vec2,
    damping: BodyDamping,
    dt: f64,
    /// Store each disc's force and moment.
    store: bool,
    /// External forces and moments `(slot, f, moment)`, sorted by slot.
    external: &'a [(u32, Vec2, f64)],
    /// `(check_radii/Δt)²`: a disc is flagged when `v·v > max_v2 r²` or
    /// its state is not finite.
    max_v2: f64,
    /// The held bonds of the disc in slot i (as first disc):
    /// `bond_row[i]..bond_row[i + 1]` (empty without bonds).
    bond_row: &'a [u32],
    bond_law: BondLaw,
    /// Step of the bonds (0 in the step they are made).
    bond_dt: f64,
    thickness: f64,
    bond_cross: &'a CrossIndex,
    /// What each cross bond does and its new forces.
    bond_cross_buf: &'a [(BondForce, HeldForces)],
    /// The radius of each held bond (read when one breaks).
    bond_radius: &'a [f64],
    /// Evaluate inner pairs four at a time ([`lanes4`]).
    four_lanes: bool,
    /// The clumps, stepped after the block of their members (`ADVANCE`).
    clumps: Option<ClumpRows<'a>>,
}

/// The discs `lo..lo + pos.len()` with their pairs (as first disc) and
/// wall pairs: what one block owns.
struct Block<'a> {
    lo: usize,
    pos: &'a mut [Vec2],
    vel: &'a mut [Vec2],
    theta: &'a mut [f64],
    omega: &'a mut [f64],
    force: &'a mut [Vec2],
    torque: &'a mut [f64],
    radius: &'a [f64],
    inv_mass: &'a [f64],
    inv_inertia: &'a [f64],
    fixity: &'a [u8],
    material: &'a [u16],
    /// Positions at the last list rebuild (empty: no Verlet check).
    ref_pos: &'a [Vec2],
    /// Second disc of each pair.
    pairs: &'a [u32],
    /// `√m_eff` of each pair (empty: no law needs it, read as 0).
    sm: &'a [f64],
    shear: &'a mut [f64],
    /// Rolling histories (same index as `pairs`; empty without rolling).
    roll: &'a mut [f64],
    walls: &'a mut [WallPair],
    wall_buf: &'a mut [ContactForce],
    /// The held bonds of the block's discs (empty without bonds).
    held: &'a [Held],
    /// Their forces.
    held_f: &'a mut [HeldForces],
    /// Clump of each disc (empty without clumps): a clump's members are
    /// not advanced here (their clump is, after the sweep).
    clump: &'a [u32],
}

impl<'a> Block<'a> {
    /// The same block, borrowed.
    fn reborrow(&mut self) -> Block<'_> {
        Block {
            lo: self.lo,
            pos: self.pos,
            vel: self.vel,
            theta: self.theta,
            omega: self.omega,
            force: self.force,
            torque: self.torque,
            radius: self.radius,
            inv_mass: self.inv_mass,
            inv_inertia: self.inv_inertia,
            fixity: self.fixity,
            material: self.material,
            ref_pos: self.ref_pos,
            pairs: self.pairs,
            sm: self.sm,
            shear: self.shear,
            roll: self.roll,
            walls: self.walls,
            wall_buf: self.wall_buf,
            held: self.held,
            held_f: self.held_f,
            clump: self.clump,
        }
    }

    /// Split before disc slot `at` (absolute).
    fn split(self, at: usize, ctx: &Ctx) -> (Block<'a>, Block<'a>) {
        let k = at - self.lo;
        let first = ctx.first;
        let pair_lo = first[self.lo] as usize;
        let (pos, pos2) = self.pos.split_at_mut(k);
        let (vel, vel2) = self.vel.split_at_mut(k);
        let (theta, theta2) = self.theta.split_at_mut(k);
        let (omega, omega2) = self.omega.split_at_mut(k);
        let (force, force2) = self.force.split_at_mut(k);
        let (torque, torque2) = self.torque.split_at_mut(k);
        let (radius, radius2) = self.radius.split_at(k);
        let (inv_mass, inv_mass2) = self.inv_mass.split_at(k);
        let (inv_inertia, inv_inertia2) = self.inv_inertia.split_at(k);
        let (fixity, fixity2) = self.fixity.split_at(k);
        let (material, material2) = self.material.split_at(k);
        let (ref_pos, ref_pos2) = if self.ref_pos.is_empty() {
            (self.ref_pos, self.ref_pos)
        } else {
            self.ref_pos.split_at(k)
        };
        let kp = first[at] as usize - pair_lo;
        let (pairs, pairs2) = self.pairs.split_at(kp);
        let (sm, sm2) = if self.sm.is_empty() {
            (self.sm, self.sm)
        } else {
            self.sm.split_at(kp)
        };
        let (shear, shear2) = self.shear.split_at_mut(kp);
        let (roll, roll2) = if self.roll.is_empty() {
            (self.roll, &mut [][..])
        } else {
            self.roll.split_at_mut(kp)
        };
        let w = self.walls.partition_point(|q| (q.disc as usize) < at);
        let (walls, walls2) = self.walls.split_at_mut(w);
        let (wall_buf, wall_buf2) = self.wall_buf.split_at_mut(w);
        let (clump, clump2) = if self.clump.is_empty() {
            (self.clump, self.clump)
        } else {
            self.clump.split_at(k)
        };
        let (held, held2, held_f, held_f2) = if self.held.is_empty() {
            (self.held, self.held, self.held_f, &mut [][..])
        } else {
            let r = ctx.bond_row;
            let w = (r[at] - r[self.lo]) as usize;
            let (f, f2) = self.held_f.split_at_mut(w);
            let (h, h2) = self.held.split_at(w);
            (h, h2, f, f2)
        };
        (
            Block {
                lo: self.lo,
                pos,
                vel,
                theta,
                omega,
                force,
                torque,
                radius,
                inv_mass,
                inv_inertia,
                fixity,
                material,
                ref_pos,
                pairs,
                sm,
                shear,
                roll,
                walls,
                wall_buf,
                held,
                held_f,
                clump,
            },
            Block {
                lo: at,
                pos: pos2,
                vel: vel2,
                theta: theta2,
                omega: omega2,
                force: force2,
                torque: torque2,
                radius: radius2,
                inv_mass: inv_mass2,
                inv_inertia: inv_inertia2,
                fixity: fixity2,
                material: material2,
                ref_pos: ref_pos2,
                pairs: pairs2,
                sm: sm2,
                shear: shear2,
                roll: roll2,
                walls: walls2,
                wall_buf: wall_buf2,
                held: held2,
                held_f: held_f2,
                clump: clump2,
            },
        )
    }
}

impl Granular {
    /// Evaluate every contact; with `ADVANCE`, also advance each disc by
    /// one step (central difference) as soon as its force is complete.
    /// Leaves the contact force and moment of each disc in
    /// `particles.force`/`torque` and each wall contact in `wall_buf`.
    /// Returns the largest disc displacement since the last rebuild
    /// (`ADVANCE` only; infinity when there is no reference), and whether
    /// some disc failed the check of [`Granular::check_radii`] after its
    /// advance (`ADVANCE` only).
    pub(super) fn sweep<const ADVANCE: bool>(&mut self) -> (f64, bool) {
        // a list built for another set of discs (or never built) is rebuilt
        if self.contacts.first.len() != self.particles.len() + 1 {
            self.grid.stale = true;
            self.prepare_contacts();
        }
        // the bonds, held in slot order and evaluated in the sweep with
        // the contacts; those reaching into a later block ahead of it
        let bonded = !self.bonds.list.is_empty();
        let mut broken = vec![];
        let fresh = std::mem::take(&mut self.bonds.list.fresh);
        let dt = if fresh { 0.0 } else { self.dt };
        if bonded {
            self.bonds
                .refresh(&self.particles, self.contacts.block, self.thickness);
            broken = self.bonds.step_cross(&self.particles, self.thickness, dt);
        }
        let (max_disp, bad, brk) = if self.contacts.rolling {
            self.sweep_with::<ADVANCE, true>(dt)
        } else {
            self.sweep_with::<ADVANCE, false>(dt)
        };
        if bonded {
            broken.extend(brk);
            self.bonds.finish_step(broken, self.step, self.time);
        }
        (max_disp, bad)
    }

    /// [`sweep`](Self::sweep) with (`ROLL`) or without rolling resistance:
    /// without, the kernels are those before rolling resistance existed
    /// (bitwise the same results, nothing more read or written). `bond_dt`:
    /// the bonds' step (0 in the step they are made); returns also the
    /// bonds that broke.
    fn sweep_with<const ADVANCE: bool, const ROLL: bool>(
        &mut self,
        bond_dt: f64,
    ) -> (f64, bool, Vec<Break>) {
        let n = self.particles.len();
        let max_v2 = self.check_v2();
        let ContactList {
            j: pairs,
            sqrt_m_eff: sm,
            shear,
            roll,
            first,
            walls: wall_pairs,
            wall_buf,
            cross,
            cross_buf,
            cross_roll,
            cross_first,
            cross_in_start,
            cross_in,
            block,
            ..
        } = &mut self.contacts;
        let nm = self.materials.len();
        let bonded = !self.bonds.list.is_empty();
        // the clumps are stepped after the block of their members
        let clumped = !self.clumps.is_empty();
        let clumps = if ADVANCE && clumped {
            self.clumps.prepare(&self.particles, *block);
            let motion = (self.gravity, self.damping, self.dt);
            Some(self.clumps.rows(motion, max_v2))
        } else {
            None
        };
        if ROLL {
            // lists built before rolling was switched on start from zero
            roll.resize(pairs.len(), 0.0);
            cross_roll.resize(cross.len(), (0.0, 0.0));
            cross_pairs_roll(
                &self.particles,
                &self.laws,
                &self.dash,
                nm,
                pairs,
                sm,
                shear,
                roll,
                cross,
                cross_buf,
                cross_roll,
                self.dt,
            );
        } else {
            cross_pairs(
                &self.particles,
                &self.laws,
                &self.dash,
                nm,
                pairs,
                sm,
                shear,
                cross,
                cross_buf,
                self.dt,
            );
        }
        let ctx = Ctx {
            laws: &self.laws,
            dash: &self.dash,
            wall_laws: &self.wall_laws,
            n_mat: nm,
            walls: &self.walls,
            first,
            cross_buf,
            cross_roll,
            cross_first,
            cross_in_start,
            cross_in,
            block: *block,
            gravity: self.gravity,
            damping: self.damping,
            dt: self.dt,
            // a clump sums its members' stored forces after their block
            // (or after the sweep)
            store: !ADVANCE || self.store_forces || clumped,
            external: &self.external,
            max_v2,
            bond_row: if bonded { &self.bonds.row } else { &[] },
            bond_law: self.bonds.law,
            bond_dt,
            thickness: self.thickness,
            bond_cross: &self.bonds.cross,
            bond_cross_buf: &self.bonds.cross_buf,
            bond_radius: &self.bonds.held_r,
            #[cfg(target_arch = "x86_64")]
            four_lanes: lanes4::available(),
            #[cfg(not(target_arch = "x86_64"))]
            four_lanes: false,
            clumps,
        };
        let p = &mut self.particles;
        let ref_pos: &[Vec2] = if ADVANCE && self.grid.ref_pos.len() == n {
            &self.grid.ref_pos
        } else {
            &[]
        };
        let all = Block {
            lo: 0,
            pos: &mut p.pos,
            vel: &mut p.vel,
            theta: &mut p.theta,
            omega: &mut p.omega,
            force: &mut p.force,
            torque: &mut p.torque,
            radius: &p.radius,
            inv_mass: &p.inv_mass,
            inv_inertia: &p.inv_inertia,
            fixity: &p.fixity,
            material: &p.material,
            ref_pos,
            pairs,
            sm,
            shear,
            roll: if ROLL { roll } else { &mut [] },
            walls: wall_pairs,
            wall_buf,
            held: if ctx.bond_row.is_empty() {
                &[]
            } else {
                &self.bonds.held
            },
            held_f: if ctx.bond_row.is_empty() {
                &mut []
            } else {
                &mut self.bonds.held_f
            },
            clump: if clumped { &p.clump } else { &[] },
        };
        let has_ref = !ref_pos.is_empty();
        let (max2, bad, broken) = sweep_blocks::<ADVANCE, ROLL>(0..n.div_ceil(*block), all, &ctx);
        let max_disp = if has_ref { max2.sqrt() } else { f64::INFINITY };
        (max_disp, bad, broken)
    }
}

/// Cross pairs per parallel task: about a microsecond of work, so that the
/// few hundred cross pairs of a 10 000-disc step still split evenly over
/// two threads (256 left two thirds of them to one thread).
const CROSS_GRAIN: usize = 64;

/// Evaluate the cross pairs (second disc in a later block) from the state
/// before the step: force and new shear history into `cross_buf`.
#[allow(clippy::too_many_arguments)]
fn cross_pairs(
    p: &Particles,
    laws: &[ContactLaw],
    dash: &[[f64; 4]],
    nm: usize,
    pairs: &[u32],
    sm: &[f64],
    shear: &[f64],
    cross: &[(u32, u32)],
    cross_buf: &mut [(ContactForce, f64)],
    dt: f64,
) {
    let kin = Kin::whole(p);
    cross
        .par_iter()
        .zip(cross_buf.par_iter_mut())
        .with_min_len(CROSS_GRAIN)
        .for_each(|(&(i, k), out)| {
            let k = k as usize;
            let mut fs = shear[k];
            let (i, j) = (i as usize, pairs[k] as usize);
            let l = p.material[i] as usize * nm + p.material[j] as usize;
            let cf = pair_contact(kin, i, j, &laws[l], &dash[l], sm_at(sm, k), &mut fs, dt);
            *out = (cf, fs);
        });
}

/// [`cross_pairs`] with rolling resistance: also the rolling moment on
/// the first disc and the new rolling history into `cross_roll`.
#[allow(clippy::too_many_arguments)]
fn cross_pairs_roll(
    p: &Particles,
    laws: &[ContactLaw],
    dash: &[[f64; 4]],
    nm: usize,
    pairs: &[u32],
    sm: &[f64],
    shear: &[f64],
    roll: &[f64],
    cross: &[(u32, u32)],
    cross_buf: &mut [(ContactForce, f64)],
    cross_roll: &mut [(f64, f64)],
    dt: f64,
) {
    let kin = Kin::whole(p);
    let inert = Inert {
        inv_mass: &p.inv_mass,
        inv_inertia: &p.inv_inertia,
    };
    cross
        .par_iter()
        .zip(cross_buf.par_iter_mut().zip(cross_roll.par_iter_mut()))
        .with_min_len(CROSS_GRAIN)
        .for_each(|(&(i, k), (out, out_r))| {
            let k = k as usize;
            let mut fs = shear[k];
            let mut mr = roll[k];
            let (i, j) = (i as usize, pairs[k] as usize);
            let q = sm_at(sm, k);
            let l = p.material[i] as usize * nm + p.material[j] as usize;
            let (cf, m) = pair_contact_roll(
                kin, inert, i, j, &laws[l], &dash[l], q, &mut fs, &mut mr, dt,
            );
            *out = (cf, fs);
            *out_r = (m, mr);
        });
}

/// Split the block range in halves and sweep them in parallel; returns the
/// largest squared displacement (an exact max: thread-count independent),
/// whether a disc failed the step check and the bonds that broke (in block
/// order).
fn sweep_blocks<const ADVANCE: bool, const ROLL: bool>(
    blocks: std::ops::Range<usize>,
    all: Block,
    ctx: &Ctx,
) -> (f64, bool, Vec<Break>) {
    if blocks.len() <= 1 {
        return if blocks.is_empty() {
            (0.0, false, vec![])
        } else {
            sweep_block::<ADVANCE, ROLL>(blocks.start, all, ctx)
        };
    }
    let mid = blocks.start + blocks.len() / 2;
    let (a, b) = all.split(mid * ctx.block, ctx);
    let (mut x, y) = rayon::join(
        || sweep_blocks::<ADVANCE, ROLL>(blocks.start..mid, a, ctx),
        || sweep_blocks::<ADVANCE, ROLL>(mid..blocks.end, b, ctx),
    );
    x.2.extend(y.2);
    (x.0.max(y.0), x.1 || y.1, x.2)
}

/// Sweep one block: its discs in slot order, each one's contacts and
/// bonds, then (with `ADVANCE`) the disc's step.
fn sweep_block<const ADVANCE: bool, const ROLL: bool>(
    blk: usize,
    b: Block,
    ctx: &Ctx,
) -> (f64, bool, Vec<Break>) {
    let n = b.pos.len();
    let bonded = !ctx.bond_row.is_empty();
    let mut b = b;
    let (m2, bad, broken) = with_zeroed(&ACC, true, n, |acc| {
        with_zeroed(&ACC_ROLL, ROLL, n, |acc_r| {
            with_zeroed(&ACC_BOND, bonded, n, |acc_b| {
                sweep_block_in::<ADVANCE, ROLL>(blk, b.reborrow(), acc, acc_r, acc_b, ctx)
            })
        })
    });
    let Some(rows) = ctx.clumps.as_ref().filter(|_| ADVANCE) else {
        return (m2, bad, broken);
    };
    let ref_pos = if b.ref_pos.is_empty() {
        std::ptr::null()
    } else {
        b.ref_pos.as_ptr()
    };
    let discs = Discs::block(
        b.lo,
        (b.pos, b.vel, b.theta, b.omega),
        (b.force, b.torque, b.radius),
        ref_pos,
    );
    // SAFETY: the block's discs are this task's, all swept; the blocks of
    // the sweep do not overlap
    let (c2, c_bad) = unsafe { rows.step_block(b.lo, b.lo + n, &discs) };
    (m2.max(c2), bad || c_bad, broken)
}

#[inline(never)]
fn sweep_block_in<const ADVANCE: bool, const ROLL: bool>(
    blk: usize,
    b: Block,
    acc: &mut [(Vec2, f64)],
    acc_r: &mut [f64],
    acc_b: &mut [f64],
    ctx: &Ctx,
) -> (f64, bool, Vec<Break>) {
    let Block {
        lo,
        pos,
        vel,
        theta,
        omega,
        force,
        torque,
        radius,
        inv_mass,
        inv_inertia,
        fixity,
        material,
        ref_pos,
        pairs,
        sm,
        shear,
        roll,
        walls,
        wall_buf,
        held,
        held_f,
        clump,
    } = b;
    let n = pos.len();
    let hi = lo + n;
    // every slice of the block has length n (checked once, so that the
    // loop below indexes without bounds checks on the hot arrays)
    let (vel, theta, omega, force, torque) = (
        &mut vel[..n],
        &mut theta[..n],
        &mut omega[..n],
        &mut force[..n],
        &mut torque[..n],
    );
    let (radius, inv_mass, inv_inertia, fixity, material) = (
        &radius[..n],
        &inv_mass[..n],
        &inv_inertia[..n],
        &fixity[..n],
        &material[..n],
    );
    // `acc`: contributions to discs not yet reached, in L1/L2 (the force
    // and torque arrays are only written, once per disc)
    let acc = &mut acc[..n];
    // cross pairs whose second disc is here (their first disc is in an
    // earlier block), in list order
    let (a, e) = (
        ctx.cross_in_start[blk] as usize,
        ctx.cross_in_start[blk + 1] as usize,
    );
    for &(j, k) in &ctx.cross_in[a..e] {
        let (cf, _) = ctx.cross_buf[k as usize];
        let a = &mut acc[j as usize - lo];
        a.0 -= cf.f;
        a.1 += cf.fs;
        if ROLL {
            acc_r[j as usize - lo] -= ctx.cross_roll[k as usize].0;
        }
    }
    // the bonds, before any disc advances
    let bonded = !ctx.bond_row.is_empty();
    let broken = if bonded {
        let kin = Kin {
            pos,
            vel,
            omega,
            radius,
        };
        bond_block(blk, lo, kin, (held, held_f), acc, acc_b, ctx)
    } else {
        vec![]
    };
    let mut ck = ctx.cross_first[blk] as usize;
    let pair_lo = ctx.first[lo] as usize;
    let mut pk = 0usize;
    let mut wk = 0usize;
    let mut ek = ctx.external.partition_point(|e| (e.0 as usize) < lo);
    let mut m2 = 0.0f64;
    let mut bad = false;
    let single = ctx.n_mat == 1;
    // the single-material law, looked up once
    let (law0, dash0) = match (ctx.laws.first(), ctx.dash.first()) {
        (Some(l), Some(d)) if single => (*l, *d),
        _ => (ContactLaw::default(), [0.0; 4]),
    };
    // inner pairs evaluated ahead, four at a time: `ahead[k − ahead_lo]`
    // for `ahead_lo ≤ k < ahead_hi` (their histories already written)
    let four = single && !ROLL && ctx.four_lanes;
    let (mut ahead_lo, mut ahead_hi) = (0usize, 0usize);
    let mut ahead = [ContactForce::default(); 4];
    for d in 0..n {
        // taken: the accumulators are left at zero for the next block
        let (mut sf, mut st) = std::mem::take(&mut acc[d]);
        // rolling moments on d (ROLL only)
        let mut sr = if ROLL {
            std::mem::take(&mut acc_r[d])
        } else {
            0.0
        };
        let end = ctx.first[lo + d + 1] as usize - pair_lo;
        let mut k = pk;
        while k < end {
            let j = pairs[k] as usize;
            if j >= hi {
                let (cf, fs) = ctx.cross_buf[ck];
                if ROLL {
                    let (m, mr) = ctx.cross_roll[ck];
                    roll[k] = mr;
                    sr += m;
                }
                ck += 1;
                shear[k] = fs;
                sf += cf.f;
                st += cf.fs;
                k += 1;
                continue;
            }
            let jl = j - lo;
            let kin = Kin {
                pos,
                vel,
                omega,
                radius,
            };
            if ROLL {
                let inert = Inert {
                    inv_mass,
                    inv_inertia,
                };
                // two inner pairs side by side, as below
                #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
                if single && k + 1 < end && (pairs[k + 1] as usize) < hi {
                    let j2 = pairs[k + 1] as usize - lo;
                    if let Some((cf, fs, m, mr)) = lanes::pair_contacts_roll(
                        kin,
                        inert,
                        [d, d],
                        [jl, j2],
                        [shear[k], shear[k + 1]],
                        [roll[k], roll[k + 1]],
                        [sm_at(sm, k), sm_at(sm, k + 1)],
                        &law0,
                        &dash0,
                        ctx.dt,
                    ) {
                        shear[k] = fs[0];
                        shear[k + 1] = fs[1];
                        roll[k] = mr[0];
                        roll[k + 1] = mr[1];
                        for (jx, c, m) in [(jl, cf[0], m[0]), (j2, cf[1], m[1])] {
                            let a = &mut acc[jx];
                            a.0 -= c.f;
                            a.1 += c.fs;
                            acc_r[jx] -= m;
                            sf += c.f;
                            st += c.fs;
                            sr += m;
                        }
                        k += 2;
                        continue;
                    }
                }
                let (q, fs, mr) = (sm_at(sm, k), &mut shear[k], &mut roll[k]);
                let (cf, m) = if single {
                    pair_contact_roll(kin, inert, d, jl, &law0, &dash0, q, fs, mr, ctx.dt)
                } else {
                    let l = material[d] as usize * ctx.n_mat + material[jl] as usize;
                    let (law, dash) = (&ctx.laws[l], &ctx.dash[l]);
                    pair_contact_roll(kin, inert, d, jl, law, dash, q, fs, mr, ctx.dt)
                };
                let a = &mut acc[jl];
                a.0 -= cf.f;
                a.1 += cf.fs;
                acc_r[jl] -= m;
                sf += cf.f;
                st += cf.fs;
                sr += m;
                k += 1;
                continue;
            }
            #[cfg(target_arch = "x86_64")]
            if four {
                if k >= ahead_hi {
                    let f = Four {
                        first: ctx.first,
                        pair_lo,
                        lo,
                        hi,
                    };
                    if let Some(r) = f.batch(kin, pairs, sm, shear, d, k, &law0, &dash0, ctx.dt) {
                        (ahead, ahead_lo, ahead_hi) = (r, k, k + 4);
                    }
                }
                if k < ahead_hi {
                    let c = ahead[k - ahead_lo];
                    let a = &mut acc[jl];
                    a.0 -= c.f;
                    a.1 += c.fs;
                    sf += c.f;
                    st += c.fs;
                    k += 1;
                    continue;
                }
            }
            // two inner pairs of disc d side by side when the lanes apply
            #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
            if single && k + 1 < end && (pairs[k + 1] as usize) < hi {
                let j2 = pairs[k + 1] as usize - lo;
                if let Some((cf, fs)) = lanes::pair_contacts(
                    kin,
                    [d, d],
                    [jl, j2],
                    [shear[k], shear[k + 1]],
                    [sm_at(sm, k), sm_at(sm, k + 1)],
                    &law0,
                    &dash0,
                    ctx.dt,
                ) {
                    shear[k] = fs[0];
                    shear[k + 1] = fs[1];
                    for (jx, c) in [(jl, cf[0]), (j2, cf[1])] {
                        let a = &mut acc[jx];
                        a.0 -= c.f;
                        a.1 += c.fs;
                        sf += c.f;
                        st += c.fs;
                    }
                    k += 2;
                    continue;
                }
            }
            let (q, fs) = (sm_at(sm, k), &mut shear[k]);
            let cf = if single {
                pair_contact(kin, d, jl, &law0, &dash0, q, fs, ctx.dt)
            } else {
                let l = material[d] as usize * ctx.n_mat + material[jl] as usize;
                pair_contact(kin, d, jl, &ctx.laws[l], &ctx.dash[l], q, fs, ctx.dt)
            };
            let a = &mut acc[jl];
            a.0 -= cf.f;
            a.1 += cf.fs;
            sf += cf.f;
            st += cf.fs;
            k += 1;
        }
        pk = end;
        while wk < walls.len() && walls[wk].disc as usize == lo + d {
            let q = &mut walls[wk];
            let w = q.wall as usize;
            let law = &ctx.wall_laws[w * ctx.n_mat + material[d] as usize];
            let disc = Side {
                pos: pos[d],
                vel: vel[d],
                omega: omega[d],
                radius: radius[d],
            };
            let cf = if ROLL {
                let (im, ii) = (inv_mass[d], inv_inertia[d]);
                let (cf, m) = wall_contact_roll(disc, im, ii, &ctx.walls[w], law, q, ctx.dt);
                sr += m;
                cf
            } else {
                wall_contact(disc, inv_mass[d], &ctx.walls[w], law, &mut q.fs, ctx.dt)
            };
            wall_buf[wk] = cf;
            sf += cf.f;
            st += cf.fs;
            wk += 1;
        }
        let mut tq = radius[d] * st;
        if ROLL {
            tq += sr;
        }
        if bonded {
            tq += std::mem::take(&mut acc_b[d]);
        }
        add_external(ctx.external, &mut ek, lo + d, &mut sf, &mut tq);
        // a held disc's sums wait for the forces computed beside the
        // sweep (`Granular::release_held` advances it)
        if ctx.store || fixity[d] & HELD != 0 {
            force[d] = sf;
            torque[d] = tq;
        }
        if ADVANCE && fixity[d] & (GHOST | HELD) == 0 && (clump.is_empty() || clump[d] == NO_CLUMP)
        {
            integrate::advance(
                &mut pos[d],
                &mut vel[d],
                &mut theta[d],
                &mut omega[d],
                sf,
                tq,
                inv_mass[d],
                inv_inertia[d],
                fixity[d],
                ctx.gravity,
                ctx.damping,
                ctx.dt,
            );
            if !ref_pos.is_empty() {
                let d2 = (pos[d] - ref_pos[d]).norm2();
                m2 = if d2 > m2 { d2 } else { m2 };
            }
            // the model's per-step check, while the disc is in registers
            bad |= !integrate::passes_check(pos[d], vel[d], omega[d], radius[d], ctx.max_v2);
        }
    }
    (m2, bad, broken)
}

/// Add the external forces and moments of the disc in `slot` to `f` and
/// `t`, in order: those of `ext` (sorted by slot) from `*k` on, `*k` moved
/// past them.
#[inline(always)]
pub(super) fn add_external(
    ext: &[(u32, Vec2, f64)],
    k: &mut usize,
    slot: usize,
    f: &mut Vec2,
    t: &mut f64,
) {
    while *k < ext.len() && ext[*k].0 as usize == slot {
        *f += ext[*k].1;
        *t += ext[*k].2;
        *k += 1;
    }
}

/// The bonds of block `blk` (discs `lo..`, their data in `kin`, their held
/// bonds `held`), from the state before the step, in a pass of their own
/// before the block's discs are swept: the forces and moments on the
/// block's discs into `acc` and `acc_b` (bond by bond in slot order, each
/// bond's cross part from the cross buffer), the held forces updated.
/// Returns the bonds that broke. The bonds are stepped [`BOND_CHUNK`] at
/// a time into a buffer (independent of each other: the processor
/// overlaps them), then summed onto the discs in the same order.
#[inline(never)]
fn bond_block(
    blk: usize,
    lo: usize,
    kin: Kin,
    (held, held_f): (&[Held], &mut [HeldForces]),
    acc: &mut [(Vec2, f64)],
    acc_b: &mut [f64],
    ctx: &Ctx,
) -> Vec<Break> {
    let n = kin.pos.len();
    let (acc, acc_b) = (&mut acc[..n], &mut acc_b[..n]);
    let bx = ctx.bond_cross;
    // cross bonds whose second disc is here
    let (a, e) = (bx.in_start[blk] as usize, bx.in_start[blk + 1] as usize);
    for &(j, c) in &bx.incoming[a..e] {
        let bf = &ctx.bond_cross_buf[c as usize].0;
        acc[j as usize - lo].0 -= bf.f;
        acc_b[j as usize - lo] += bf.mb;
    }
    let mut ck = bx.first[blk] as usize;
    let w0 = ctx.bond_row[lo] as usize;
    let mut broken = vec![];
    let held_f = &mut held_f[..held.len()];
    BOND_OUT.with_borrow_mut(|out| {
        out.resize(BOND_CHUNK, BondForce::default());
        // in chunks that stay in the L1 cache between the two passes
        for c in (0..held.len()).step_by(BOND_CHUNK) {
            let e = held.len().min(c + BOND_CHUNK);
            let (h, out) = (&held[c..e], &mut out[..e - c]);
            let at = (lo, w0 + c, &mut ck);
            bond_forces(kin, (h, &mut held_f[c..e]), out, at, &mut broken, ctx);
            // what a bond of disc d and disc j does, in bond order: j's
            // part (an inner bond's; a cross bond's was added above), then d's
            for (h, bf) in h.iter().zip(out.iter()) {
                let (d, j) = (h.i as usize - lo, h.j as usize - lo);
                if j < n {
                    acc[j].0 -= bf.f;
                    acc_b[j] += bf.mb;
                }
                acc[d].0 += bf.f;
                acc_b[d] += bf.ma;
            }
        }
    });
    broken
}

/// Bonds stepped at a time before they are summed ([`bond_block`]).
const BOND_CHUNK: usize = 256;

/// What the bonds `held` of a block with its first disc at slot `lo`
/// do ([`bond_block`]) into `out`, their held forces updated; `w0`: where
/// `held` starts among all held bonds, `ck`: the next cross bond. The
/// bonds that broke are added to `broken`.
#[inline(always)]
fn bond_forces(
    kin: Kin,
    (held, held_f): (&[Held], &mut [HeldForces]),
    out: &mut [BondForce],
    (lo, w0, ck): (usize, usize, &mut usize),
    broken: &mut Vec<Break>,
    ctx: &Ctx,
) {
    let n = kin.pos.len();
    let law = &ctx.bond_law;
    let (t, dt, rad) = (ctx.thickness, ctx.bond_dt, ctx.bond_radius);
    let ends = |h: &Held| (h.i as usize - lo, h.j as usize - lo);
    let mut w = 0;
    while w < held.len() {
        let (d, j) = ends(&held[w]);
        if j >= n {
            let (bf, f_new) = ctx.bond_cross_buf[*ck];
            *ck += 1;
            held_f[w] = f_new;
            out[w] = bf;
            w += 1;
            continue;
        }
        // two inner bonds side by side (all from the state before the step)
        #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
        if let Some(h2) = held.get(w + 1).filter(|h| (h.j as usize) < lo + n) {
            let (d2, j2) = ends(h2);
            let (si, sj) = sides(kin, d, j);
            let (si2, sj2) = sides(kin, d2, j2);
            let two = super::bonds::lanes::step2(
                [&held[w], h2],
                &mut held_f[w..w + 2],
                [si, si2],
                [sj, sj2],
                law,
                dt,
                &mut out[w..w + 2],
            );
            if let Some(intact) = two {
                // a bond that may break: the scalar step
                for l in (0..2).filter(|l| intact & (1 << l) == 0) {
                    let (d, j) = ends(&held[w + l]);
                    let (si, sj) = sides(kin, d, j);
                    let f = &mut held_f[w + l];
                    let (bf, brk) = held[w + l].step(w0 + w + l, f, &si, &sj, law, rad, t, dt);
                    broken.extend(brk);
                    out[w + l] = bf;
                }
                w += 2;
                continue;
            }
        }
        let (si, sj) = sides(kin, d, j);
        let (bf, brk) = held[w].step(w0 + w, &mut held_f[w], &si, &sj, law, rad, t, dt);
        broken.extend(brk);
        out[w] = bf;
        w += 1;
    }
}

/// Where a block's pairs and discs are, for [`lanes4`]'s batches.
#[cfg(target_arch = "x86_64")]
struct Four<'a> {
    first: &'a [u32],
    pair_lo: usize,
    lo: usize,
    hi: usize,
}

#[cfg(target_arch = "x86_64")]
impl Four<'_> {
    /// The block's pairs `k..k + 4` (local numbering; `d` the first disc
    /// of pair `k`) evaluated at once when all four are inner pairs with
    /// distinct centres: their forces, their new histories written. Pairs
    /// of later discs read only discs not yet advanced (every disc of the
    /// batch is at least `d`), so the values are those of the one-by-one
    /// sweep, and the caller adds them in the same order.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn batch(
        &self,
        kin: Kin,
        pairs: &[u32],
        sm: &[f64],
        shear: &mut [f64],
        d: usize,
        k: usize,
        law: &ContactLaw,
        dash: &[f64; 4],
        dt: f64,
    ) -> Option<[ContactForce; 4]> {
        let ks = pairs.get(k..k + 4)?;
        let (mut ix, mut jx) = ([0usize; 4], [0usize; 4]);
        let mut e = d;
        for (l, &j) in ks.iter().enumerate() {
            if j as usize >= self.hi {
                return None;
            }
            while self.first[self.lo + e + 1] as usize - self.pair_lo <= k + l {
                e += 1;
            }
            ix[l] = e;
            jx[l] = j as usize - self.lo;
        }
        let fs = [shear[k], shear[k + 1], shear[k + 2], shear[k + 3]];
        let q = std::array::from_fn(|l| sm_at(sm, k + l));
        // SAFETY: the sweep asks for batches only when `lanes4::available()`.
        let (cf, fs_new) = unsafe { lanes4::pair_contacts(kin, ix, jx, fs, q, law, dash, dt) }?;
        shear[k..k + 4].copy_from_slice(&fs_new);
        Some(cf)
    }
}

/// The per-disc arrays the disc–disc kernel reads, cut to one length so
/// that a single index check covers all of them.
#[derive(Clone, Copy)]
struct Kin<'a> {
    pos: &'a [Vec2],
    vel: &'a [Vec2],
    omega: &'a [f64],
    radius: &'a [f64],
}

impl<'a> Kin<'a> {
    fn whole(p: &'a Particles) -> Self {
        Kin {
            pos: &p.pos,
            vel: &p.vel,
            omega: &p.omega,
            radius: &p.radius,
        }
    }
}

/// Inverse masses and inertias (the rolling dashpot's `I_r`).
#[derive(Clone, Copy)]
struct Inert<'a> {
    inv_mass: &'a [f64],
    inv_inertia: &'a [f64],
}

/// Unit normal from disc i to disc j and their overlap, `None` when apart.
#[inline(always)]
fn pair_geometry(p: Kin, i: usize, j: usize) -> Option<(Vec2, f64)> {
    let (pi, pj) = (p.pos[i], p.pos[j]);
    let rsum = p.radius[i] + p.radius[j];
    let d = pj - pi;
    let d2 = d.norm2();
    if d2 >= rsum * rsum {
        return None;
    }
    let (n, dist) = if d2 > 0.0 {
        let dist = d2.sqrt();
        (d * (1.0 / dist), dist)
    } else {
        (Vec2::new(1.0, 0.0), 0.0)
    };
    Some((n, rsum - dist))
}

/// The two sides of a disc–disc contact.
#[inline(always)]
fn sides(p: Kin, i: usize, j: usize) -> (Side, Side) {
    (
        Side {
            pos: p.pos[i],
            vel: p.vel[i],
            omega: p.omega[i],
            radius: p.radius[i],
        },
        Side {
            pos: p.pos[j],
            vel: p.vel[j],
            omega: p.omega[j],
            radius: p.radius[j],
        },
    )
}

/// Dashpot coefficients of a pair from the law's terms and `√m_eff`.
#[inline(always)]
fn pair_dashpots(dash: &[f64; 4], sm: f64) -> (f64, f64) {
    (dash[0] + dash[1] * sm, dash[2] + dash[3] * sm)
}

/// `√m_eff` of pair `k`, 0 when no law needs it (the list keeps none; the
/// dashpot terms that would multiply it are then 0).
#[inline(always)]
fn sm_at(sm: &[f64], k: usize) -> f64 {
    if sm.is_empty() { 0.0 } else { sm[k] }
}

/// One disc–disc contact between the discs at `i` and `j` of `p`; `fs` is
/// the pair's shear history.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn pair_contact(
    p: Kin,
    i: usize,
    j: usize,
    law: &ContactLaw,
    dash: &[f64; 4],
    q: f64,
    fs: &mut f64,
    dt: f64,
) -> ContactForce {
    let Some((n, delta)) = pair_geometry(p, i, j) else {
        *fs = 0.0;
        return ContactForce::default();
    };
    let (si, sj) = sides(p, i, j);
    contact::evaluate(law, n, delta, &si, &sj, pair_dashpots(dash, q), fs, dt)
}

/// [`pair_contact`] with rolling resistance: also the rolling moment on
/// disc i (j gets its opposite), `mr` the pair's rolling history
/// ([`contact::rolling`], relative rotation `ω_i − ω_j`, rolling radius
/// `r_i r_j/(r_i + r_j)`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn pair_contact_roll(
    p: Kin,
    m: Inert,
    i: usize,
    j: usize,
    law: &ContactLaw,
    dash: &[f64; 4],
    q: f64,
    fs: &mut f64,
    mr: &mut f64,
    dt: f64,
) -> (ContactForce, f64) {
    let Some((n, delta)) = pair_geometry(p, i, j) else {
        *fs = 0.0;
        *mr = 0.0;
        return (ContactForce::default(), 0.0);
    };
    let (si, sj) = sides(p, i, j);
    let (cf, fn_cap) =
        contact::evaluate_capped(law, n, delta, &si, &sj, pair_dashpots(dash, q), fs, dt);
    if !law.rolling() {
        *mr = 0.0;
        return (cf, 0.0);
    }
    let rbar = contact::rolling_radius(si.radius, sj.radius);
    let c_r = if law.roll_damping != 0.0 {
        let a_i = contact::contact_inertia(m.inv_mass[i], m.inv_inertia[i], si.radius);
        let a_j = contact::contact_inertia(m.inv_mass[j], m.inv_inertia[j], sj.radius);
        contact::rolling_dashpot(law, law.roll_kr(rbar), a_i, a_j)
    } else {
        0.0
    };
    let omega_rel = si.omega - sj.omega;
    let mom = contact::rolling(law, rbar, fn_cap, omega_rel, c_r, mr, dt);
    (cf, mom)
}

/// One disc–wall contact: the wall is side j with zero radius, the normal
/// points from the disc centre to the closest point of the wall.
#[inline(always)]
fn wall_contact(
    disc: Side,
    inv_mass: f64,
    w: &Wall,
    law: &ContactLaw,
    fs: &mut f64,
    dt: f64,
) -> ContactForce {
    let Some((n, delta, c)) = wall_geometry(&disc, w) else {
        *fs = 0.0;
        return ContactForce::default();
    };
    contact::evaluate(
        law,
        n,
        delta,
        &disc,
        &Side {
            pos: c,
            vel: w.vel,
            omega: 0.0,
            radius: 0.0,
        },
        law.dashpots(effective_mass(inv_mass, 0.0)),
        fs,
        dt,
    )
}

/// [`wall_contact`] with rolling resistance: also the rolling moment on
/// the disc (relative rotation `ω_i`, rolling radius `r`), the histories
/// in `q`.
#[inline(always)]
fn wall_contact_roll(
    disc: Side,
    inv_mass: f64,
    inv_inertia: f64,
    w: &Wall,
    law: &ContactLaw,
    q: &mut WallPair,
    dt: f64,
) -> (ContactForce, f64) {
    let Some((n, delta, c)) = wall_geometry(&disc, w) else {
        q.fs = 0.0;
        q.mr = 0.0;
        return (ContactForce::default(), 0.0);
    };
    let (cf, fn_cap) = contact::evaluate_capped(
        law,
        n,
        delta,
        &disc,
        &Side {
            pos: c,
            vel: w.vel,
            omega: 0.0,
            radius: 0.0,
        },
        law.dashpots(effective_mass(inv_mass, 0.0)),
        &mut q.fs,
        dt,
    );
    if !law.rolling() {
        q.mr = 0.0;
        return (cf, 0.0);
    }
    let r = disc.radius;
    let c_r = if law.roll_damping != 0.0 {
        let a = contact::contact_inertia(inv_mass, inv_inertia, r);
        contact::rolling_dashpot(law, law.roll_kr(r), a, (0.0, 1.0))
    } else {
        0.0
    };
    let mom = contact::rolling(law, r, fn_cap, disc.omega, c_r, &mut q.mr, dt);
    (cf, mom)
}

/// Unit normal from the disc centre to the closest point `c` of the wall,
/// the overlap and `c`; `None` when apart.
#[inline(always)]
fn wall_geometry(disc: &Side, w: &Wall) -> Option<(Vec2, f64, Vec2)> {
    let x = disc.pos;
    let r = disc.radius;
    let c = w.closest(x);
    let dd = c - x;
    let d2 = dd.norm2();
    if d2 >= r * r {
        return None;
    }
    let dist = d2.sqrt();
    let n = if dist > 0.0 {
        dd * (1.0 / dist)
    } else {
        // centre on the wall: push along the wall's left normal
        let t = w.b - w.a;
        let l = t.norm();
        if l > 0.0 {
            t.perp() * (-1.0 / l)
        } else {
            Vec2::new(1.0, 0.0)
        }
    };
    Some((n, r - dist, c))
}

/// Two disc–disc contacts in the two lanes of SSE2 registers (baseline on
/// x86-64). Every lane performs exactly the IEEE operations of
/// [`pair_contact`] and [`contact::evaluate`] (with rolling resistance:
/// [`pair_contact_roll`] and [`contact::rolling`]), in the same order (no
/// fused multiply–add), so the results are bitwise those of the scalar
/// code.
///
/// The intrinsics are `unsafe` only because they require SSE2, which the
/// `cfg` guarantees is enabled for the whole build.
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
pub(super) mod lanes {
    use super::{ContactForce, ContactLaw, Inert, Kin};
    use crate::dem::contact::SlipNormal;
    use crate::geom::Vec2;
    use std::arch::x86_64::*;

    /// `(a, b)` in the two lanes (the bonds' lanes use it too).
    #[inline(always)]
    pub(in crate::dem) fn set(a: f64, b: f64) -> __m128d {
        // SAFETY: SSE2 is enabled (module cfg).
        unsafe { _mm_set_pd(b, a) }
    }

    /// The two lanes.
    #[inline(always)]
    pub(in crate::dem) fn get(v: __m128d) -> [f64; 2] {
        // SAFETY: SSE2 is enabled (module cfg).
        unsafe { [_mm_cvtsd_f64(v), _mm_cvtsd_f64(_mm_unpackhi_pd(v, v))] }
    }

    /// The contacts of the inner pairs `(ix[l], jx[l])` with shear
    /// histories `fs` and cached `√m_eff` `sm`: forces and new histories,
    /// or `None` if a pair has coincident centres (left to the scalar path).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn pair_contacts(
        p: Kin,
        ix: [usize; 2],
        jx: [usize; 2],
        fs: [f64; 2],
        sm: [f64; 2],
        law: &ContactLaw,
        dash: &[f64; 4],
        dt: f64,
    ) -> Option<([ContactForce; 2], [f64; 2])> {
        let no = Inert {
            inv_mass: &[],
            inv_inertia: &[],
        };
        pair_contacts_in::<false>(p, no, ix, jx, fs, [0.0; 2], sm, law, dash, dt)
            .map(|(cf, fs, _, _)| (cf, fs))
    }

    /// [`pair_contacts`] with rolling resistance: also the rolling moments
    /// on disc i and the new rolling histories (`mr` the old ones).
    #[inline(always)]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    pub(super) fn pair_contacts_roll(
        p: Kin,
        m: Inert,
        ix: [usize; 2],
        jx: [usize; 2],
        fs: [f64; 2],
        mr: [f64; 2],
        sm: [f64; 2],
        law: &ContactLaw,
        dash: &[f64; 4],
        dt: f64,
    ) -> Option<([ContactForce; 2], [f64; 2], [f64; 2], [f64; 2])> {
        pair_contacts_in::<true>(p, m, ix, jx, fs, mr, sm, law, dash, dt)
    }

    #[inline(always)]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn pair_contacts_in<const ROLL: bool>(
        p: Kin,
        m: Inert,
        ix: [usize; 2],
        jx: [usize; 2],
        fs: [f64; 2],
        mr: [f64; 2],
        sm: [f64; 2],
        law: &ContactLaw,
        dash: &[f64; 4],
        dt: f64,
    ) -> Option<([ContactForce; 2], [f64; 2], [f64; 2], [f64; 2])> {
        // SAFETY: SSE2 is enabled (module cfg); no memory is accessed
        // through pointers.
        let (fx, fy, fs_tot, fs_new, mom, mr_new) = unsafe {
            let [i1, i2] = ix;
            let [j1, j2] = jx;
            let (pi1, pi2, pj1, pj2) = (p.pos[i1], p.pos[i2], p.pos[j1], p.pos[j2]);
            let (vi1, vi2, vj1, vj2) = (p.vel[i1], p.vel[i2], p.vel[j1], p.vel[j2]);
            let ri = set(p.radius[i1], p.radius[i2]);
            let rj = set(p.radius[j1], p.radius[j2]);
            let rsum = _mm_add_pd(ri, rj);
            // d = pj − pi, d² = dx dx + dy dy
            let dx = _mm_sub_pd(set(pj1.x, pj2.x), set(pi1.x, pi2.x));
            let dy = _mm_sub_pd(set(pj1.y, pj2.y), set(pi1.y, pi2.y));
            let d2 = _mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy));
            let touch = _mm_cmplt_pd(d2, _mm_mul_pd(rsum, rsum));
            if _mm_movemask_pd(_mm_cmpeq_pd(d2, _mm_setzero_pd())) != 0 {
                return None;
            }
            let dist = _mm_sqrt_pd(d2);
            let inv = _mm_div_pd(_mm_set1_pd(1.0), dist);
            let nx = _mm_mul_pd(dx, inv);
            let ny = _mm_mul_pd(dy, inv);
            let delta = _mm_sub_pd(rsum, dist);
            let sm = set(sm[0], sm[1]);
            let cn = _mm_add_pd(_mm_set1_pd(dash[0]), _mm_mul_pd(_mm_set1_pd(dash[1]), sm));
            let cs = _mm_add_pd(_mm_set1_pd(dash[2]), _mm_mul_pd(_mm_set1_pd(dash[3]), sm));
            // t = perp(n) = (−ny, nx); dv = vi − vj
            let zero = _mm_setzero_pd();
            // negation flips the sign bit (as `-x` does; 0 − x would turn −0 into +0)
            let sign = _mm_set1_pd(-0.0);
            let tx = _mm_xor_pd(ny, sign);
            let dvx = _mm_sub_pd(set(vi1.x, vi2.x), set(vj1.x, vj2.x));
            let dvy = _mm_sub_pd(set(vi1.y, vi2.y), set(vj1.y, vj2.y));
            let vn = _mm_add_pd(_mm_mul_pd(dvx, nx), _mm_mul_pd(dvy, ny));
            let wi = set(p.omega[i1], p.omega[i2]);
            let wj = set(p.omega[j1], p.omega[j2]);
            let vt = _mm_add_pd(
                _mm_add_pd(
                    _mm_add_pd(_mm_mul_pd(dvx, tx), _mm_mul_pd(dvy, nx)),
                    _mm_mul_pd(wi, ri),
                ),
                _mm_mul_pd(wj, rj),
            );
            let fn_el = _mm_mul_pd(_mm_set1_pd(law.kn), delta);
            let mut fn_tot = _mm_add_pd(fn_el, _mm_mul_pd(cn, vn));
            if law.no_tension {
                fn_tot = _mm_andnot_pd(_mm_cmplt_pd(fn_tot, zero), fn_tot);
            }
            let fs0 = set(fs[0], fs[1]);
            let trial = _mm_sub_pd(
                fs0,
                _mm_mul_pd(_mm_mul_pd(_mm_set1_pd(law.ks), vt), _mm_set1_pd(dt)),
            );
            // the cap's normal force: k_n δ, or max(0, F_n,total) as the
            // scalar select `if fn_tot > 0 { fn_tot } else { 0 }` (maxpd
            // returns its second operand unless the first is greater)
            let fn_cap = match law.slip_normal {
                SlipNormal::Elastic => fn_el,
                SlipNormal::Total => _mm_max_pd(fn_tot, zero),
            };
            let cap = _mm_add_pd(
                _mm_mul_pd(_mm_set1_pd(law.mu), fn_cap),
                _mm_set1_pd(law.cohesion),
            );
            // if trial > cap { cap } else { trial }, then if < −cap { −cap }
            let capped = _mm_min_pd(cap, trial);
            let capped = _mm_max_pd(_mm_xor_pd(cap, sign), capped);
            let damp = _mm_and_pd(_mm_cmpeq_pd(capped, trial), _mm_mul_pd(cs, vt));
            let fs_tot = _mm_sub_pd(capped, damp);
            // f = n (−F_n) + t F_s
            let neg_fn = _mm_xor_pd(fn_tot, sign);
            let fx = _mm_add_pd(_mm_mul_pd(nx, neg_fn), _mm_mul_pd(tx, fs_tot));
            let fy = _mm_add_pd(_mm_mul_pd(ny, neg_fn), _mm_mul_pd(nx, fs_tot));
            let (fx, fy) = (get(_mm_and_pd(touch, fx)), get(_mm_and_pd(touch, fy)));
            let fs_tot = get(_mm_and_pd(touch, fs_tot));
            let fs_new = get(_mm_and_pd(touch, capped));
            // rolling resistance, as contact::rolling (ROLL only)
            let (mom, mr_new) = if ROLL && law.rolling() {
                // r̄ = r_i r_j/(r_i + r_j), k_r = β_r k_s r̄², limit μ_r r̄ F_n
                let rbar = _mm_div_pd(_mm_mul_pd(ri, rj), rsum);
                let kr = _mm_mul_pd(
                    _mm_mul_pd(_mm_set1_pd(law.roll_stiffness * law.ks), rbar),
                    rbar,
                );
                let limit = _mm_mul_pd(_mm_mul_pd(_mm_set1_pd(law.mu_roll), rbar), fn_cap);
                let c_r = if law.roll_damping != 0.0 {
                    // 1/(I + m r²) = n/d, n = ii·im, d = im + r² ii; (0, 1)
                    // where d = 0 (contact::contact_inertia)
                    let a = |k: [usize; 2], r: __m128d| {
                        let im = set(m.inv_mass[k[0]], m.inv_mass[k[1]]);
                        let ii = set(m.inv_inertia[k[0]], m.inv_inertia[k[1]]);
                        let d = _mm_add_pd(im, _mm_mul_pd(_mm_mul_pd(r, r), ii));
                        let pos = _mm_cmpgt_pd(d, zero);
                        let one = _mm_set1_pd(1.0);
                        (
                            _mm_and_pd(pos, _mm_mul_pd(ii, im)),
                            _mm_or_pd(_mm_and_pd(pos, d), _mm_andnot_pd(pos, one)),
                        )
                    };
                    let ((ni, di), (nj, dj)) = (a(ix, ri), a(jx, rj));
                    let s = _mm_add_pd(_mm_mul_pd(ni, dj), _mm_mul_pd(nj, di));
                    let c = _mm_mul_pd(
                        _mm_set1_pd(law.roll_damping * 2.0),
                        _mm_sqrt_pd(_mm_div_pd(_mm_mul_pd(kr, _mm_mul_pd(di, dj)), s)),
                    );
                    _mm_and_pd(_mm_cmpgt_pd(s, zero), c)
                } else {
                    zero
                };
                let w_rel = _mm_sub_pd(wi, wj);
                let trial = _mm_sub_pd(
                    set(mr[0], mr[1]),
                    _mm_mul_pd(_mm_mul_pd(kr, w_rel), _mm_set1_pd(dt)),
                );
                let capped = _mm_min_pd(limit, trial);
                let capped = _mm_max_pd(_mm_xor_pd(limit, sign), capped);
                let damp = _mm_and_pd(_mm_cmpeq_pd(capped, trial), _mm_mul_pd(c_r, w_rel));
                (
                    get(_mm_and_pd(touch, _mm_sub_pd(capped, damp))),
                    get(_mm_and_pd(touch, capped)),
                )
            } else {
                ([0.0; 2], [0.0; 2])
            };
            (fx, fy, fs_tot, fs_new, mom, mr_new)
        };
        Some((
            [
                ContactForce {
                    f: Vec2::new(fx[0], fy[0]),
                    fs: fs_tot[0],
                },
                ContactForce {
                    f: Vec2::new(fx[1], fy[1]),
                    fs: fs_tot[1],
                },
            ],
            fs_new,
            mom,
            mr_new,
        ))
    }
}

/// Four disc–disc contacts in the four lanes of AVX2 registers, chosen at
/// run time when asked for ([`lanes4::available`]), the two-lane kernel
/// otherwise.
/// Every lane performs exactly the IEEE operations of [`pair_contact`]
/// and [`contact::evaluate`] in the same order (no fused multiply–add), so
/// the results are bitwise those of the scalar code and of the two-lane
/// kernel: the instruction set changes no result.
#[cfg(target_arch = "x86_64")]
pub(super) mod lanes4 {
    use super::{ContactForce, ContactLaw, Kin};
    use crate::dem::contact::SlipNormal;
    use crate::geom::Vec2;
    use std::arch::x86_64::*;
    use std::sync::atomic::{AtomicBool, Ordering};

    /// Use the four-lane kernel (on a processor with AVX2): set by
    /// `EFGDEM_LANES=4` in the environment, or by tests.
    static ENABLED: AtomicBool = AtomicBool::new(false);

    /// The four-lane kernel was asked for (`EFGDEM_LANES=4`, or
    /// [`enable`]) and the processor has AVX2. Not the default: on the
    /// machines measured so far it is slower than the two-lane kernel
    /// (gathering four pairs' discs costs more than the wider arithmetic
    /// saves); the results are the same.
    pub(crate) fn available() -> bool {
        static ASKED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        let asked =
            *ASKED.get_or_init(|| std::env::var("EFGDEM_LANES").is_ok_and(|v| v.trim() == "4"));
        (asked || ENABLED.load(Ordering::Relaxed)) && std::arch::is_x86_feature_detected!("avx2")
    }

    /// Enable or disable the four-lane kernel (tests).
    #[cfg(test)]
    pub(crate) fn enable(on: bool) {
        ENABLED.store(on, Ordering::Relaxed);
    }

    /// The contacts of the inner pairs `(ix[l], jx[l])` with shear
    /// histories `fs` and cached `√m_eff` `sm`: forces and new histories,
    /// or `None` if a pair has coincident centres (left to the scalar path).
    ///
    /// # Safety
    /// The processor must have AVX2 ([`available`]).
    #[target_feature(enable = "avx2")]
    #[allow(clippy::too_many_arguments)]
    pub(super) unsafe fn pair_contacts(
        p: Kin,
        ix: [usize; 4],
        jx: [usize; 4],
        fs: [f64; 4],
        sm: [f64; 4],
        law: &ContactLaw,
        dash: &[f64; 4],
        dt: f64,
    ) -> Option<([ContactForce; 4], [f64; 4])> {
        // lane expressions expanded in place (closures would not be
        // compiled for AVX2 and not inlined)
        macro_rules! get {
            ($l:ident => $e:expr) => {
                _mm256_set_pd(
                    {
                        let $l = 3;
                        $e
                    },
                    {
                        let $l = 2;
                        $e
                    },
                    {
                        let $l = 1;
                        $e
                    },
                    {
                        let $l = 0;
                        $e
                    },
                )
            };
        }
        macro_rules! out {
            ($v:expr) => {{
                let mut a = [0.0; 4];
                // SAFETY: `a` holds four f64.
                unsafe { _mm256_storeu_pd(a.as_mut_ptr(), $v) };
                a
            }};
        }
        // per lane (x, y) pairs in 128-bit halves, subtracted as the scalar
        // code does, then transposed to (x₀..x₃), (y₀..y₃)
        macro_rules! xy {
            ($v:expr, $a:expr, $b:expr) => {{
                // SAFETY: in bounds (indexed), `Vec2` is two f64 (repr(C)).
                let pair = |l: usize| unsafe {
                    _mm_sub_pd(
                        _mm_loadu_pd(&$v[$a[l]].x as *const f64),
                        _mm_loadu_pd(&$v[$b[l]].x as *const f64),
                    )
                };
                let (p0, p1, p2, p3) = (pair(0), pair(1), pair(2), pair(3));
                let lo = _mm256_insertf128_pd::<1>(_mm256_castpd128_pd256(p0), p2);
                let hi = _mm256_insertf128_pd::<1>(_mm256_castpd128_pd256(p1), p3);
                (_mm256_unpacklo_pd(lo, hi), _mm256_unpackhi_pd(lo, hi))
            }};
        }
        let ri = get!(l => p.radius[ix[l]]);
        let rj = get!(l => p.radius[jx[l]]);
        let rsum = _mm256_add_pd(ri, rj);
        // d = pj − pi, d² = dx dx + dy dy
        let (dx, dy) = xy!(p.pos, jx, ix);
        let d2 = _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy));
        let zero = _mm256_setzero_pd();
        let touch = _mm256_cmp_pd::<_CMP_LT_OS>(d2, _mm256_mul_pd(rsum, rsum));
        if _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_EQ_OQ>(d2, zero)) != 0 {
            return None;
        }
        let dist = _mm256_sqrt_pd(d2);
        let inv = _mm256_div_pd(_mm256_set1_pd(1.0), dist);
        let nx = _mm256_mul_pd(dx, inv);
        let ny = _mm256_mul_pd(dy, inv);
        let delta = _mm256_sub_pd(rsum, dist);
        // SAFETY: four f64.
        let sm = unsafe { _mm256_loadu_pd(sm.as_ptr()) };
        let cn = _mm256_add_pd(
            _mm256_set1_pd(dash[0]),
            _mm256_mul_pd(_mm256_set1_pd(dash[1]), sm),
        );
        let cs = _mm256_add_pd(
            _mm256_set1_pd(dash[2]),
            _mm256_mul_pd(_mm256_set1_pd(dash[3]), sm),
        );
        // t = perp(n) = (−ny, nx); dv = vi − vj; negation flips the sign bit
        let sign = _mm256_set1_pd(-0.0);
        let tx = _mm256_xor_pd(ny, sign);
        let (dvx, dvy) = xy!(p.vel, ix, jx);
        let vn = _mm256_add_pd(_mm256_mul_pd(dvx, nx), _mm256_mul_pd(dvy, ny));
        let wi = get!(l => p.omega[ix[l]]);
        let wj = get!(l => p.omega[jx[l]]);
        let vt = _mm256_add_pd(
            _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(dvx, tx), _mm256_mul_pd(dvy, nx)),
                _mm256_mul_pd(wi, ri),
            ),
            _mm256_mul_pd(wj, rj),
        );
        let fn_el = _mm256_mul_pd(_mm256_set1_pd(law.kn), delta);
        let mut fn_tot = _mm256_add_pd(fn_el, _mm256_mul_pd(cn, vn));
        if law.no_tension {
            fn_tot = _mm256_andnot_pd(_mm256_cmp_pd::<_CMP_LT_OS>(fn_tot, zero), fn_tot);
        }
        let trial = _mm256_sub_pd(
            // SAFETY: four f64.
            unsafe { _mm256_loadu_pd(fs.as_ptr()) },
            _mm256_mul_pd(
                _mm256_mul_pd(_mm256_set1_pd(law.ks), vt),
                _mm256_set1_pd(dt),
            ),
        );
        // as the two-lane kernel: max/min return their second operand
        // unless the first is greater/smaller (the scalar selects)
        let fn_cap = match law.slip_normal {
            SlipNormal::Elastic => fn_el,
            SlipNormal::Total => _mm256_max_pd(fn_tot, zero),
        };
        let cap = _mm256_add_pd(
            _mm256_mul_pd(_mm256_set1_pd(law.mu), fn_cap),
            _mm256_set1_pd(law.cohesion),
        );
        let capped = _mm256_min_pd(cap, trial);
        let capped = _mm256_max_pd(_mm256_xor_pd(cap, sign), capped);
        let damp = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_EQ_OQ>(capped, trial),
            _mm256_mul_pd(cs, vt),
        );
        let fs_tot = _mm256_sub_pd(capped, damp);
        // f = n (−F_n) + t F_s
        let neg_fn = _mm256_xor_pd(fn_tot, sign);
        let fx = _mm256_add_pd(_mm256_mul_pd(nx, neg_fn), _mm256_mul_pd(tx, fs_tot));
        let fy = _mm256_add_pd(_mm256_mul_pd(ny, neg_fn), _mm256_mul_pd(nx, fs_tot));
        let (fx, fy) = (
            out!(_mm256_and_pd(touch, fx)),
            out!(_mm256_and_pd(touch, fy)),
        );
        let fs_tot = out!(_mm256_and_pd(touch, fs_tot));
        let fs_new = out!(_mm256_and_pd(touch, capped));
        let cf = |l: usize| ContactForce {
            f: Vec2::new(fx[l], fy[l]),
            fs: fs_tot[l],
        };
        Some(([cf(0), cf(1), cf(2), cf(3)], fs_new))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` discs in a 2.5 × 2.5 square with random velocities, spins and
    /// radii, and a random contact law (friction, cohesion, shear dashpot,
    /// the no-tension clamp and the slip normal varied with `case`): the
    /// cases of the lane tests.
    /// `n` random discs (positions, velocities, spins, radii, drawn in
    /// that order) for the lane kernel tests.
    #[allow(dead_code)] // on processors without the lane kernels
    fn random_discs(
        u: &mut impl FnMut(f64, f64) -> f64,
        n: usize,
    ) -> (Vec<Vec2>, Vec<Vec2>, Vec<f64>, Vec<f64>) {
        let pos = (0..n)
            .map(|_| Vec2::new(u(0.0, 2.5), u(0.0, 2.5)))
            .collect();
        let vel = (0..n)
            .map(|_| Vec2::new(u(-3.0, 3.0), u(-3.0, 3.0)))
            .collect();
        let omega = (0..n).map(|_| u(-5.0, 5.0)).collect();
        let radius = (0..n).map(|_| u(0.8, 1.2)).collect();
        (pos, vel, omega, radius)
    }

    #[allow(dead_code)] // on processors without the lane kernels
    fn random_case(
        u: &mut impl FnMut(f64, f64) -> f64,
        n: usize,
        case: usize,
    ) -> (Vec<Vec2>, Vec<Vec2>, Vec<f64>, Vec<f64>, ContactLaw) {
        let (pos, vel, omega, radius) = random_discs(u, n);
        let law = ContactLaw {
            kn: 1.0e4,
            ks: u(0.5e4, 1.0e4),
            mu: if case.is_multiple_of(5) {
                0.0
            } else {
                u(0.1, 0.8)
            },
            cohesion: if case.is_multiple_of(3) {
                u(0.0, 50.0)
            } else {
                0.0
            },
            beta_n: u(0.0, 1e-3),
            zeta_n: u(0.0, 0.3),
            zeta_s: if case.is_multiple_of(2) {
                u(0.0, 0.2)
            } else {
                0.0
            },
            no_tension: case % 4 == 1,
            slip_normal: if case % 7 < 4 {
                contact::SlipNormal::Total
            } else {
                contact::SlipNormal::Elastic
            },
            ..Default::default()
        };
        (pos, vel, omega, radius, law)
    }

    /// The two-lane kernel gives bitwise the scalar kernel's forces and
    /// shear histories: touching and separated pairs, sticking and sliding,
    /// with and without cohesion, dashpots and the no-tension clamp, with
    /// the total or the elastic normal force in the Coulomb cap.
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    #[test]
    fn two_lanes_equal_the_scalar_contact_bitwise() {
        let mut rng = oorandom::Rand64::new(7);
        let mut u = |a: f64, b: f64| a + (b - a) * rng.rand_float();
        let mut cases = 0;
        for case in 0..4000 {
            let n = 4;
            let (pos, vel, omega, radius, law) = random_case(&mut u, n, case);
            let kin = Kin {
                pos: &pos,
                vel: &vel,
                omega: &omega,
                radius: &radius,
            };
            let dash = law.dashpot_terms();
            let q = [0.7, 0.7];
            let mut fs = [u(-300.0, 300.0), u(-300.0, 300.0)];
            let dt = 1e-3;
            let lanes = lanes::pair_contacts(kin, [0, 2], [1, 3], fs, [0.7, 0.7], &law, &dash, dt)
                .expect("distinct centres");
            for (l, (i, j)) in [(0, 1), (2, 3)].into_iter().enumerate() {
                let cf = pair_contact(kin, i, j, &law, &dash, q[l], &mut fs[l], dt);
                let bits = |c: &ContactForce| [c.f.x.to_bits(), c.f.y.to_bits(), c.fs.to_bits()];
                assert_eq!(bits(&cf), bits(&lanes.0[l]), "case {case} lane {l}");
                assert_eq!(
                    fs[l].to_bits(),
                    lanes.1[l].to_bits(),
                    "case {case} lane {l}"
                );
                cases += usize::from(cf.f != Vec2::ZERO);
            }
        }
        assert!(cases > 1000, "touching cases: {cases}");
    }

    /// The four-lane kernel gives bitwise the scalar kernel's forces and
    /// shear histories (the cases of the two-lane test, four pairs at once).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn four_lanes_equal_the_scalar_contact_bitwise() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = oorandom::Rand64::new(11);
        let mut u = |a: f64, b: f64| a + (b - a) * rng.rand_float();
        let mut touching = 0;
        for case in 0..2000 {
            let n = 8;
            let (pos, vel, omega, radius, law) = random_case(&mut u, n, case);
            let kin = Kin {
                pos: &pos,
                vel: &vel,
                omega: &omega,
                radius: &radius,
            };
            let dash = law.dashpot_terms();
            let q = [0.7, 0.5, 0.9, 0.6];
            let mut fs: [f64; 4] = std::array::from_fn(|_| u(-300.0, 300.0));
            let dt = 1e-3;
            let (ix, jx) = ([0, 2, 4, 6], [1, 3, 5, 7]);
            // SAFETY: AVX2 checked above.
            let lanes = unsafe { lanes4::pair_contacts(kin, ix, jx, fs, q, &law, &dash, dt) }
                .expect("distinct centres");
            for l in 0..4 {
                let cf = pair_contact(kin, ix[l], jx[l], &law, &dash, q[l], &mut fs[l], dt);
                let bits = |c: &ContactForce| [c.f.x.to_bits(), c.f.y.to_bits(), c.fs.to_bits()];
                assert_eq!(bits(&cf), bits(&lanes.0[l]), "case {case} lane {l}");
                assert_eq!(
                    fs[l].to_bits(),
                    lanes.1[l].to_bits(),
                    "case {case} lane {l}"
                );
                touching += usize::from(cf.f != Vec2::ZERO);
            }
        }
        assert!(touching > 1000, "touching cases: {touching}");
    }

    /// A whole run with the four-lane kernel is bitwise the run with the
    /// two-lane one (pairs evaluated ahead of their disc, forces summed in
    /// the same order), on 1 and 2 threads.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn four_lane_sweep_equals_the_two_lane_sweep_bitwise() {
        use crate::dem::packing::{Lattice, lattice_packing};
        use crate::dem::particles::Particles;
        use crate::dem::walls::{Wall, WallMotion};
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let (lo, hi) = (Vec2::ZERO, Vec2::new(150.0, 60.0));
        let rows = lattice_packing(Lattice::Hex, lo, hi, (0.8, 1.2), Some(1500), 0.02, 0.5, 3)
            .expect("fits");
        let run = |four: bool, threads: usize| {
            let mut p = Particles::with_capacity(rows.len());
            for r in &rows {
                p.push(r.pos, r.r, 1.0, 1.0, 0);
            }
            let c = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
            let walls = (0..4)
                .map(|k| Wall::new("box", c[k], c[(k + 1) % 4], WallMotion::Fixed))
                .collect();
            let law = ContactLaw {
                kn: 1.0e6,
                ks: 1.0e6,
                mu: 0.5,
                zeta_n: 0.2,
                ..Default::default()
            };
            let mut g = Granular::new(p, vec![law], walls, 1.0);
            g.dt = 0.15 * g.critical_dt();
            g.gravity = Vec2::new(0.0, -98.1);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            lanes4::enable(four);
            pool.install(|| (0..1500).for_each(|_| g.step()));
            lanes4::enable(false);
            let p = &g.particles;
            let mut bits: Vec<u64> = Vec::new();
            for k in 0..p.len() {
                bits.extend([p.pos[k].x, p.pos[k].y, p.vel[k].x, p.omega[k]].map(f64::to_bits));
            }
            (bits, g.contacts.len())
        };
        let (reference, pairs) = run(false, 1);
        assert!(pairs > 1000, "listed pairs: {pairs}");
        assert!(run(true, 1).0 == reference);
        assert!(run(true, 2).0 == reference);
    }

    /// The same with rolling resistance: forces, shear and rolling
    /// histories and rolling moments of the two-lane kernel are bitwise
    /// those of [`pair_contact_roll`] (at and below the limit, with and
    /// without the rolling dashpot, fixed discs, μ_r = 0).
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    #[test]
    fn two_lanes_with_rolling_equal_the_scalar_contact_bitwise() {
        let mut rng = oorandom::Rand64::new(11);
        let mut u = |a: f64, b: f64| a + (b - a) * rng.rand_float();
        let (mut touching, mut moment) = (0, 0);
        for case in 0..4000 {
            let n = 4;
            let (pos, vel, omega, radius) = random_discs(&mut u, n);
            // some discs fixed (inverse mass and inertia 0)
            let inv_mass: Vec<f64> = (0..n)
                .map(|k| {
                    if (case + k) % 5 == 0 {
                        0.0
                    } else {
                        u(0.2, 2.0)
                    }
                })
                .collect();
            let inv_inertia: Vec<f64> = inv_mass.iter().map(|&im| im * u(1.0, 3.0)).collect();
            let kin = Kin {
                pos: &pos,
                vel: &vel,
                omega: &omega,
                radius: &radius,
            };
            let inert = Inert {
                inv_mass: &inv_mass,
                inv_inertia: &inv_inertia,
            };
            let law = ContactLaw {
                kn: 1.0e4,
                ks: u(0.5e4, 1.0e4),
                mu: u(0.1, 0.8),
                zeta_n: u(0.0, 0.3),
                slip_normal: if case % 3 == 0 {
                    contact::SlipNormal::Elastic
                } else {
                    contact::SlipNormal::Total
                },
                mu_roll: if case % 7 == 0 { 0.0 } else { u(0.01, 0.5) },
                roll_stiffness: u(0.3, 2.0),
                roll_damping: if case % 2 == 0 { u(0.0, 1.0) } else { 0.0 },
                ..Default::default()
            };
            let dash = law.dashpot_terms();
            let q = [0.7, 0.7];
            let mut fs = [u(-300.0, 300.0), u(-300.0, 300.0)];
            let mut mr = [u(-100.0, 100.0), u(-100.0, 100.0)];
            let dt = 1e-3;
            let (cfl, fsl, ml, mrl) = lanes::pair_contacts_roll(
                kin,
                inert,
                [0, 2],
                [1, 3],
                fs,
                mr,
                [0.7, 0.7],
                &law,
                &dash,
                dt,
            )
            .expect("distinct centres");
            for (l, (i, j)) in [(0, 1), (2, 3)].into_iter().enumerate() {
                let (cf, m) = pair_contact_roll(
                    kin, inert, i, j, &law, &dash, q[l], &mut fs[l], &mut mr[l], dt,
                );
                let bits = |c: &ContactForce| [c.f.x.to_bits(), c.f.y.to_bits(), c.fs.to_bits()];
                assert_eq!(bits(&cf), bits(&cfl[l]), "case {case} lane {l}");
                assert_eq!(fs[l].to_bits(), fsl[l].to_bits(), "case {case} lane {l}");
                assert_eq!(
                    m.to_bits(),
                    ml[l].to_bits(),
                    "case {case} lane {l}: {m} {}",
                    ml[l]
                );
                assert_eq!(mr[l].to_bits(), mrl[l].to_bits(), "case {case} lane {l}");
                touching += usize::from(cf.f != Vec2::ZERO && law.mu_roll > 0.0);
                moment += usize::from(m != 0.0);
            }
        }
        println!("touching with rolling: {touching}, with a rolling moment: {moment}");
        assert!(touching > 1000 && moment > 1000, "{touching} {moment}");
    }
}
