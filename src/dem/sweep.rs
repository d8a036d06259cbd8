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

use super::broadphase::{ContactList, Pair, WallPair};
use super::contact::{self, ContactForce, ContactLaw, Side, effective_mass};
use super::integrate;
use super::particles::Particles;
use super::walls::Wall;
use super::{BodyDamping, Granular};
use crate::geom::Vec2;
use rayon::prelude::*;

thread_local! {
    /// Per-thread accumulators of the block being swept (grown once).
    static ACC: std::cell::RefCell<Vec<(Vec2, f64)>> = const { std::cell::RefCell::new(Vec::new()) };
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
    cross_first: &'a [u32],
    cross_in_start: &'a [u32],
    cross_in: &'a [(u32, u32)],
    block: usize,
    gravity: Vec2,
    damping: BodyDamping,
    dt: f64,
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
    pairs: &'a mut [Pair],
    walls: &'a mut [WallPair],
    wall_buf: &'a mut [ContactForce],
}

impl<'a> Block<'a> {
    /// Split before disc slot `at` (absolute).
    fn split(self, at: usize, first: &[u32], pair_lo: usize) -> (Block<'a>, Block<'a>) {
        let k = at - self.lo;
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
        let (pairs, pairs2) = self.pairs.split_at_mut(first[at] as usize - pair_lo);
        let w = self.walls.partition_point(|q| (q.disc as usize) < at);
        let (walls, walls2) = self.walls.split_at_mut(w);
        let (wall_buf, wall_buf2) = self.wall_buf.split_at_mut(w);
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
                walls,
                wall_buf,
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
                walls: walls2,
                wall_buf: wall_buf2,
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
    /// (`ADVANCE` only; infinity when there is no reference).
    pub(super) fn sweep<const ADVANCE: bool>(&mut self) -> f64 {
        // a list built for another set of discs (or never built) is rebuilt
        if self.contacts.first.len() != self.particles.len() + 1 {
            self.grid.stale = true;
            self.prepare_contacts();
        }
        let n = self.particles.len();
        let ContactList {
            pairs,
            first,
            walls: wall_pairs,
            wall_buf,
            cross,
            cross_buf,
            cross_first,
            cross_in_start,
            cross_in,
            block,
        } = &mut self.contacts;
        let nm = self.materials.len();
        cross_pairs(
            &self.particles,
            &self.laws,
            &self.dash,
            nm,
            pairs,
            cross,
            cross_buf,
            self.dt,
        );
        let ctx = Ctx {
            laws: &self.laws,
            dash: &self.dash,
            wall_laws: &self.wall_laws,
            n_mat: nm,
            walls: &self.walls,
            first,
            cross_buf,
            cross_first,
            cross_in_start,
            cross_in,
            block: *block,
            gravity: self.gravity,
            damping: self.damping,
            dt: self.dt,
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
            walls: wall_pairs,
            wall_buf,
        };
        let has_ref = !ref_pos.is_empty();
        let max2 = sweep_blocks::<ADVANCE>(0..n.div_ceil(*block), all, &ctx);
        if has_ref { max2.sqrt() } else { f64::INFINITY }
    }
}

/// Evaluate the cross pairs (second disc in a later block) from the state
/// before the step: force and new shear history into `cross_buf`.
#[allow(clippy::too_many_arguments)]
fn cross_pairs(
    p: &Particles,
    laws: &[ContactLaw],
    dash: &[[f64; 4]],
    nm: usize,
    pairs: &[Pair],
    cross: &[u32],
    cross_buf: &mut [(ContactForce, f64)],
    dt: f64,
) {
    let kin = Kin::whole(p);
    cross
        .par_iter()
        .zip(cross_buf.par_iter_mut())
        .with_min_len(256)
        .for_each(|(&k, out)| {
            let mut q = pairs[k as usize];
            let (i, j) = (q.i as usize, q.j as usize);
            let l = p.material[i] as usize * nm + p.material[j] as usize;
            let cf = pair_contact(kin, i, j, &laws[l], &dash[l], &mut q, dt);
            *out = (cf, q.fs);
        });
}

/// Split the block range in halves and sweep them in parallel; returns the
/// largest squared displacement (an exact max: thread-count independent).
fn sweep_blocks<const ADVANCE: bool>(blocks: std::ops::Range<usize>, all: Block, ctx: &Ctx) -> f64 {
    if blocks.len() <= 1 {
        return if blocks.is_empty() {
            0.0
        } else {
            sweep_block::<ADVANCE>(blocks.start, all, ctx)
        };
    }
    let mid = blocks.start + blocks.len() / 2;
    let pair_lo = ctx.first[all.lo] as usize;
    let (a, b) = all.split(mid * ctx.block, ctx.first, pair_lo);
    let (x, y) = rayon::join(
        || sweep_blocks::<ADVANCE>(blocks.start..mid, a, ctx),
        || sweep_blocks::<ADVANCE>(mid..blocks.end, b, ctx),
    );
    x.max(y)
}

/// Sweep one block: its discs in slot order, each one's contacts, then (with
/// `ADVANCE`) the disc's step.
fn sweep_block<const ADVANCE: bool>(blk: usize, b: Block, ctx: &Ctx) -> f64 {
    ACC.with_borrow_mut(|acc| {
        acc.clear();
        acc.resize(b.pos.len(), (Vec2::ZERO, 0.0));
        sweep_block_in::<ADVANCE>(blk, b, acc, ctx)
    })
}

#[inline(never)]
fn sweep_block_in<const ADVANCE: bool>(
    blk: usize,
    b: Block,
    acc: &mut [(Vec2, f64)],
    ctx: &Ctx,
) -> f64 {
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
        walls,
        wall_buf,
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
    }
    let mut ck = ctx.cross_first[blk] as usize;
    let pair_lo = ctx.first[lo] as usize;
    let mut pk = 0usize;
    let mut wk = 0usize;
    let mut m2 = 0.0f64;
    let single = ctx.n_mat == 1;
    // the single-material law, looked up once
    let (law0, dash0) = match (ctx.laws.first(), ctx.dash.first()) {
        (Some(l), Some(d)) if single => (*l, *d),
        _ => (ContactLaw::default(), [0.0; 4]),
    };
    for d in 0..n {
        let (mut sf, mut st) = acc[d];
        let end = ctx.first[lo + d + 1] as usize - pair_lo;
        for q in &mut pairs[pk..end] {
            let j = q.j as usize;
            let cf = if j >= hi {
                let (cf, fs) = ctx.cross_buf[ck];
                ck += 1;
                q.fs = fs;
                cf
            } else {
                let jl = j - lo;
                let kin = Kin {
                    pos,
                    vel,
                    omega,
                    radius,
                };
                let cf = if single {
                    pair_contact(kin, d, jl, &law0, &dash0, q, ctx.dt)
                } else {
                    let l = material[d] as usize * ctx.n_mat + material[jl] as usize;
                    pair_contact(kin, d, jl, &ctx.laws[l], &ctx.dash[l], q, ctx.dt)
                };
                let a = &mut acc[jl];
                a.0 -= cf.f;
                a.1 += cf.fs;
                cf
            };
            sf += cf.f;
            st += cf.fs;
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
            let cf = wall_contact(disc, inv_mass[d], &ctx.walls[w], law, &mut q.fs, ctx.dt);
            wall_buf[wk] = cf;
            sf += cf.f;
            st += cf.fs;
            wk += 1;
        }
        let tq = radius[d] * st;
        force[d] = sf;
        torque[d] = tq;
        if ADVANCE {
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
        }
    }
    m2
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

/// One disc–disc contact between the discs at `i` and `j` of `p`.
#[inline(always)]
fn pair_contact(
    p: Kin,
    i: usize,
    j: usize,
    law: &ContactLaw,
    dash: &[f64; 4],
    q: &mut Pair,
    dt: f64,
) -> ContactForce {
    let (pi, pj) = (p.pos[i], p.pos[j]);
    let (ri, rj) = (p.radius[i], p.radius[j]);
    let rsum = ri + rj;
    let d = pj - pi;
    let d2 = d.norm2();
    if d2 >= rsum * rsum {
        q.fs = 0.0;
        return ContactForce::default();
    }
    let (n, dist) = if d2 > 0.0 {
        let dist = d2.sqrt();
        (d * (1.0 / dist), dist)
    } else {
        (Vec2::new(1.0, 0.0), 0.0)
    };
    contact::evaluate(
        law,
        n,
        rsum - dist,
        &Side {
            pos: pi,
            vel: p.vel[i],
            omega: p.omega[i],
            radius: ri,
        },
        &Side {
            pos: pj,
            vel: p.vel[j],
            omega: p.omega[j],
            radius: rj,
        },
        (
            dash[0] + dash[1] * q.sqrt_m_eff,
            dash[2] + dash[3] * q.sqrt_m_eff,
        ),
        &mut q.fs,
        dt,
    )
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
    let x = disc.pos;
    let r = disc.radius;
    let c = w.closest(x);
    let dd = c - x;
    let d2 = dd.norm2();
    if d2 >= r * r {
        *fs = 0.0;
        return ContactForce::default();
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
    contact::evaluate(
        law,
        n,
        r - dist,
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
