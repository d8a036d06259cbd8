//! Clumps: rigid bodies made of overlapping discs.
//!
//! A clump's member discs keep their own slots in [`Particles`] (the
//! contact search, the contact laws, the walls, the bonds and the output
//! see them as discs), with [`Particles::clump`] naming their clump. Pairs
//! of discs of the same clump are never listed, so a clump has no
//! contacts within itself. Each step, after the contact forces:
//!
//! 1. the members' forces are summed onto the clump, `F = Σ F_m`,
//!    `M = Σ (M_m + (x_m − X) × F_m)` (in member order: bitwise the same
//!    on any number of threads);
//! 2. the clump advances as one rigid body with the central difference of
//!    the discs ([`integrate::advance`]: gravity `M g`, the body damping);
//! 3. each member is put where the rigid motion takes it:
//!    `x_m = X + R(θ) b_m`, `v_m = V + ω × (x_m − X)`, `θ_m = θ`, `ω_m = ω`.
//!
//! The clump's mass, centre and moment of inertia are those of the *union*
//! of its discs ([`union_shape`]: exact, from the arcs of the union's
//! boundary), not the sum over the discs, which would count the overlaps
//! twice.
//!
//! [`Clumps`] holds its clumps in *rows* that follow the slot order of
//! their members (re-ordered after the discs are renumbered): a fused
//! step ([`Granular::step`](super::Granular::step)) steps the clumps whose
//! members lie in one block of the contact sweep right after that block,
//! their members' data still in the cache, going through the block's
//! rows in order, and the others after the
//! sweep ([`Clumps::step_across`]). A clump keeps its index (the one
//! [`Particles::clump`] names, the files' clump number less one):
//! `id[row]`, `row[id]`. Each clump's step depends on its own state and
//! members only, so neither the rows' order nor where it is stepped
//! changes a result.

use super::BodyDamping;
use super::integrate;
use super::packing::DiscRow;
use super::particles::Particles;
use crate::geom::Vec2;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

/// [`Particles::clump`] of a disc that belongs to no clump.
pub const NO_CLUMP: u32 = u32::MAX;

/// Area, centroid and polar second moment of a union of discs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnionShape {
    /// Area `A`.
    pub area: f64,
    /// Centroid `c = ∫x dA / A`.
    pub centroid: Vec2,
    /// Polar second moment about the centroid, `∫|x − c|² dA`.
    pub polar: f64,
}

/// The angle intervals of circle `k`'s rim that lie outside every other
/// circle of `discs` (`[a, b]`, `0 ≤ a < b ≤ 2π`, sorted). Of two equal
/// circles at the same place the first one's rim is kept.
fn exposed_arcs(discs: &[(Vec2, f64)], k: usize) -> Vec<(f64, f64)> {
    let (ck, rk) = discs[k];
    let mut covered: Vec<(f64, f64)> = Vec::new();
    for (j, &(cj, rj)) in discs.iter().enumerate() {
        if j == k {
            continue;
        }
        let dv = cj - ck;
        let d = dv.norm();
        let same = d == 0.0 && rj == rk;
        if (same && j < k) || (!same && d + rk <= rj) {
            return Vec::new(); // inside circle j
        }
        if same || d >= rk + rj || d + rj <= rk {
            continue; // apart, or circle j inside circle k
        }
        // the chord's half angle seen from k's centre (law of cosines)
        let alpha = ((rk * rk + d * d - rj * rj) / (2.0 * rk * d))
            .clamp(-1.0, 1.0)
            .acos();
        let a = (dv.y.atan2(dv.x) - alpha).rem_euclid(TAU);
        let b = a + 2.0 * alpha;
        if b > TAU {
            covered.push((a, TAU));
            covered.push((0.0, b - TAU));
        } else {
            covered.push((a, b));
        }
    }
    covered.sort_by(|p, q| p.0.total_cmp(&q.0));
    let mut open = Vec::new();
    let mut at = 0.0;
    for (a, b) in covered {
        if a > at {
            open.push((at, a));
        }
        at = f64::max(at, b);
    }
    if at < TAU {
        open.push((at, TAU));
    }
    open
}

/// `[∫ A dφ, ∫ x dA, ∫ y dA, ∫ x² dA, ∫ y² dA]` contributed by the arc
/// `φ ∈ [p, q]` of the circle of centre `(a, b)` and radius `r` to the
/// boundary integrals of Green's theorem: `A = ½∮(x dy − y dx)`,
/// `∫x dA = ∮ x²/2 dy`, `∫y dA = −∮ y²/2 dx`, `∫x² dA = ∮ x³/3 dy`,
/// `∫y² dA = −∮ y³/3 dx`, with `x = a + r cos φ`, `y = b + r sin φ`
/// integrated in closed form.
fn arc_moments(centre: Vec2, r: f64, p: f64, q: f64) -> [f64; 5] {
    let (a, b) = (centre.x, centre.y);
    // antiderivatives of cosⁿ and sinⁿ, n = 1..4, between p and q
    let span = |f: &dyn Fn(f64) -> f64| f(q) - f(p);
    let c1 = span(&|t| t.sin());
    let s1 = span(&|t| -t.cos());
    let c2 = span(&|t| t / 2.0 + (2.0 * t).sin() / 4.0);
    let s2 = span(&|t| t / 2.0 - (2.0 * t).sin() / 4.0);
    let c3 = span(&|t| t.sin() - t.sin().powi(3) / 3.0);
    let s3 = span(&|t| -t.cos() + t.cos().powi(3) / 3.0);
    let c4 = span(&|t| 3.0 * t / 8.0 + (2.0 * t).sin() / 4.0 + (4.0 * t).sin() / 32.0);
    let s4 = span(&|t| 3.0 * t / 8.0 - (2.0 * t).sin() / 4.0 + (4.0 * t).sin() / 32.0);
    [
        0.5 * (r * r * (q - p) + a * r * c1 + b * r * s1),
        0.5 * r * (a * a * c1 + 2.0 * a * r * c2 + r * r * c3),
        0.5 * r * (b * b * s1 + 2.0 * b * r * s2 + r * r * s3),
        r / 3.0 * (a.powi(3) * c1 + 3.0 * a * a * r * c2 + 3.0 * a * r * r * c3 + r.powi(3) * c4),
        r / 3.0 * (b.powi(3) * s1 + 3.0 * b * b * r * s2 + 3.0 * b * r * r * s3 + r.powi(3) * s4),
    ]
}

/// Area, centroid and polar moment of the union of the discs `(centre,
/// radius)`, exact: the union's boundary is made of the arcs of each
/// circle that lie outside all the others (`exposed_arcs`), and area,
/// first and second moments are boundary integrals (Green's theorem)
/// that have closed forms on a circular arc (`arc_moments`). Computed
/// about the first disc's centre (no cancellation far from the origin).
pub fn union_shape(discs: &[(Vec2, f64)]) -> UnionShape {
    let Some(&(o, _)) = discs.first() else {
        return UnionShape {
            area: 0.0,
            centroid: Vec2::ZERO,
            polar: 0.0,
        };
    };
    let local: Vec<(Vec2, f64)> = discs.iter().map(|&(c, r)| (c - o, r)).collect();
    let mut m = [0.0; 5];
    for (k, &(c, r)) in local.iter().enumerate() {
        for (p, q) in exposed_arcs(&local, k) {
            for (acc, v) in m.iter_mut().zip(arc_moments(c, r, p, q)) {
                *acc += v;
            }
        }
    }
    let [area, mx, my, ixx, iyy] = m;
    let c = Vec2::new(mx / area, my / area);
    UnionShape {
        area,
        centroid: o + c,
        polar: ixx + iyy - area * c.norm2(),
    }
}

/// The clumps of an assembly, and each one's rigid-body state, by row
/// (module docs; [`by_id`](Self::by_id) gives an array in clump order).
#[derive(Debug, Clone, Default)]
pub struct Clumps {
    /// Index of the clump in each row.
    pub id: Vec<u32>,
    /// Row of each clump.
    pub row: Vec<u32>,
    /// Centre of mass X.
    pub pos: Vec<Vec2>,
    /// Velocity at the half step.
    pub vel: Vec<Vec2>,
    /// Rotation θ since the clump was made.
    pub theta: Vec<f64>,
    /// Spin ω at the half step, counter-clockwise positive.
    pub omega: Vec<f64>,
    /// Mass `ρ t A` of the union of the members.
    pub mass: Vec<f64>,
    /// Moment of inertia `ρ t ∫|x − X|² dA` of the union about X.
    pub inertia: Vec<f64>,
    /// Resultant contact (and external) force of the last step.
    pub force: Vec<Vec2>,
    /// Resultant moment about X of the last step.
    pub torque: Vec<f64>,
    /// Members of the clump in row r: `members[first[r]..first[r + 1]]`
    /// (disc ids).
    pub first: Vec<u32>,
    /// Disc ids of the members, row by row.
    pub members: Vec<u32>,
    /// Each member's centre relative to X at θ = 0.
    pub offset: Vec<Vec2>,
    /// `(sin θ, cos θ)` of each clump, from its last advance.
    rot: Vec<(f64, f64)>,
    /// Slot of each member (as `members`) in the slot order of `n_slots`
    /// discs (empty: to be found again, [`invalidate`](Self::invalidate)).
    slots: Vec<u32>,
    n_slots: usize,
    /// The lowest and the highest slot of each row's members.
    lead: Vec<u32>,
    last: Vec<u32>,
    /// The rows whose members lie in more than one block of
    /// `across_block` slots ([`prepare`](Self::prepare)).
    across: Vec<u32>,
    across_block: usize,
}

impl Clumps {
    /// Number of clumps.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// No clumps.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// The member slots need finding again (the discs were renumbered).
    pub fn invalidate(&mut self) {
        self.slots.clear();
    }

    /// Each member's slot (as `members`), found again if invalidated or
    /// the number of discs changed, and the rows put in the slot order of
    /// the members ([`follow_slots`](Self::follow_slots)).
    fn refresh_slots(&mut self, p: &Particles) {
        if self.slots.len() != self.members.len() || self.n_slots != p.len() {
            self.slots = self.members.iter().map(|&id| p.slot[id as usize]).collect();
            self.n_slots = p.len();
            self.follow_slots();
        }
    }

    /// Order the rows by the lowest slot of their members (when they are
    /// not in that order already): each clump's members then lie after
    /// those of the row before, about where the last ones were.
    fn follow_slots(&mut self) {
        fn spans(c: &Clumps) -> (Vec<u32>, Vec<u32>) {
            c.first
                .windows(2)
                .map(|w| {
                    let s = &c.slots[w[0] as usize..w[1] as usize];
                    let lo = s.iter().copied().min().unwrap_or(0);
                    (lo, s.iter().copied().max().unwrap_or(0))
                })
                .unzip()
        }
        (self.lead, self.last) = spans(self);
        if self.lead.is_sorted() {
            return;
        }
        let mut order: Vec<u32> = (0..self.len() as u32).collect();
        order.sort_unstable_by_key(|&r| self.lead[r as usize]);
        self.permute(&order);
        (self.lead, self.last) = spans(self);
    }

    /// Re-hold the rows: row r takes what row `order[r]` held.
    fn permute(&mut self, order: &[u32]) {
        fn apply<T: Copy>(v: &mut Vec<T>, order: &[u32]) {
            *v = order.iter().map(|&o| v[o as usize]).collect();
        }
        apply(&mut self.id, order);
        apply(&mut self.pos, order);
        apply(&mut self.vel, order);
        apply(&mut self.theta, order);
        apply(&mut self.omega, order);
        apply(&mut self.mass, order);
        apply(&mut self.inertia, order);
        apply(&mut self.force, order);
        apply(&mut self.torque, order);
        apply(&mut self.rot, order);
        let held = self.slots.len() == self.members.len();
        let (mut first, mut members, mut offset, mut slots) = (
            Vec::with_capacity(self.first.len()),
            Vec::with_capacity(self.members.len()),
            Vec::with_capacity(self.members.len()),
            Vec::with_capacity(self.slots.len()),
        );
        first.push(0);
        for &o in order {
            let m = self.first[o as usize] as usize..self.first[o as usize + 1] as usize;
            members.extend_from_slice(&self.members[m.clone()]);
            offset.extend_from_slice(&self.offset[m.clone()]);
            if held {
                slots.extend_from_slice(&self.slots[m]);
            }
            first.push(members.len() as u32);
        }
        (self.first, self.members, self.offset, self.slots) = (first, members, offset, slots);
        for (r, &c) in self.id.iter().enumerate() {
            self.row[c as usize] = r as u32;
        }
    }

    /// Row of clump `c`.
    pub fn row_of(&self, c: usize) -> usize {
        self.row[c] as usize
    }

    /// `v`, one value per row, in clump order.
    pub fn by_id<T: Copy>(&self, v: &[T]) -> Vec<T> {
        self.row.iter().map(|&r| v[r as usize]).collect()
    }

    /// `v`, one value per clump in clump order, by row.
    pub fn in_rows<T: Copy>(&self, v: &[T]) -> Vec<T> {
        self.id.iter().map(|&c| v[c as usize]).collect()
    }

    /// `(first, members)` in clump order: clump c's members (disc ids)
    /// are `members[first[c]..first[c + 1]]` (`first` is `[0]` without
    /// clumps).
    pub fn members_by_id(&self) -> (Vec<u32>, Vec<u32>) {
        let mut first = Vec::with_capacity(self.len() + 1);
        let mut members = Vec::with_capacity(self.members.len());
        first.push(0);
        for c in 0..self.len() {
            members.extend_from_slice(self.members_of(c));
            first.push(members.len() as u32);
        }
        (first, members)
    }

    /// Disc ids of clump `c`'s members.
    pub fn members_of(&self, c: usize) -> &[u32] {
        self.members_in(self.row_of(c))
    }

    /// Disc ids of the members of the clump in row `r`.
    fn members_in(&self, r: usize) -> &[u32] {
        &self.members[self.first[r] as usize..self.first[r + 1] as usize]
    }

    /// Join the discs `ids` (scenario numbers, 0-based) into a new clump:
    /// mass, centre and inertia of the union of the discs ([`union_shape`],
    /// with the members' `ρt = m/(πr²)`), the mass-weighted mean velocity
    /// and mean spin of the members, members moved onto that rigid motion.
    /// Refused: fewer than two discs, a disc already in a clump, a disc
    /// with a fixity, members of different `ρt`.
    pub fn add(&mut self, p: &mut Particles, ids: &[usize]) -> Result<usize, String> {
        if ids.len() < 2 {
            return Err(format!(
                "a clump needs two discs or more, got {}",
                ids.len()
            ));
        }
        let c = self.len();
        let slots: Vec<usize> = ids
            .iter()
            .map(|&id| {
                if id >= p.len() {
                    Err(format!("no disc {} (there are {})", id + 1, p.len()))
                } else {
                    Ok(p.slot[id] as usize)
                }
            })
            .collect::<Result<_, _>>()?;
        let rho_t = |s: usize| p.mass[s] / (PI * p.radius[s] * p.radius[s]);
        let rho = rho_t(slots[0]);
        for (&id, &s) in ids.iter().zip(&slots) {
            if p.clump[s] != NO_CLUMP {
                return Err(format!(
                    "disc {} is already in clump {}",
                    id + 1,
                    p.clump[s] + 1
                ));
            }
            if p.fixity[s] != 0 {
                return Err(format!(
                    "disc {} has a fixity: a clump moves as a whole",
                    id + 1
                ));
            }
            if ((rho_t(s) - rho) / rho).abs() > 1e-12 {
                return Err(format!(
                    "disc {} has another density than disc {}: a clump is of one density",
                    id + 1,
                    ids[0] + 1
                ));
            }
        }
        let shape = union_shape(
            &slots
                .iter()
                .map(|&s| (p.pos[s], p.radius[s]))
                .collect::<Vec<_>>(),
        );
        let (mass, inertia) = (rho * shape.area, rho * shape.polar);
        let m_sum: f64 = slots.iter().map(|&s| p.mass[s]).sum();
        let vel = slots
            .iter()
            .fold(Vec2::ZERO, |v, &s| v + p.vel[s] * p.mass[s])
            * (1.0 / m_sum);
        let omega = slots.iter().map(|&s| p.omega[s]).sum::<f64>() / slots.len() as f64;
        if self.first.is_empty() {
            self.first.push(0);
        }
        for (&id, &s) in ids.iter().zip(&slots) {
            self.members.push(id as u32);
            self.offset.push(p.pos[s] - shape.centroid);
            p.clump[s] = c as u32;
            p.inv_mass[s] = 1.0 / mass;
            p.inv_inertia[s] = 1.0 / inertia;
        }
        self.first.push(self.members.len() as u32);
        self.id.push(c as u32);
        self.row.push(c as u32);
        self.pos.push(shape.centroid);
        self.vel.push(vel);
        self.theta.push(0.0);
        self.omega.push(omega);
        self.mass.push(mass);
        self.inertia.push(inertia);
        self.force.push(Vec2::ZERO);
        self.torque.push(0.0);
        self.rot.push((0.0, 1.0));
        self.invalidate();
        self.place(self.row_of(c), p);
        Ok(c)
    }

    /// `(sin θ, cos θ)` of every clump from its `theta` (after the clumps'
    /// state was set from a saved one; a step keeps them itself).
    pub(super) fn refresh_rotations(&mut self) {
        self.rot = self.theta.iter().map(|t| t.sin_cos()).collect();
    }

    /// Put the members of the clump in row `c` where its rigid motion
    /// takes them.
    fn place(&self, c: usize, p: &mut Particles) {
        let (a, b) = (self.first[c] as usize, self.first[c + 1] as usize);
        for (&id, &o) in self.members[a..b].iter().zip(&self.offset[a..b]) {
            let k = p.slot[id as usize] as usize;
            let (x, v) = self.member_motion(c, o);
            p.pos[k] = x;
            p.vel[k] = v;
            p.theta[k] = self.theta[c];
            p.omega[k] = self.omega[c];
        }
    }

    /// Centre and velocity of the member of the clump in row `c` at offset `o`
    /// ([`rigid_motion`]).
    #[inline(always)]
    fn member_motion(&self, c: usize, o: Vec2) -> (Vec2, Vec2) {
        rigid_motion(self.pos[c], self.vel[c], self.omega[c], self.rot[c], o)
    }

    /// Sum each clump's members' forces (`particles.force`/`torque`,
    /// complete for the step) onto the clump, about its centre, with the
    /// members where they are at the start of the step: call before the
    /// discs are advanced.
    pub fn gather(&mut self, p: &Particles) {
        for c in 0..self.len() {
            (self.force[c], self.torque[c]) = self.gathered(c, p);
        }
    }

    /// [`gather`](Self::gather) for the clump in row `c`, in member order.
    #[inline(always)]
    fn gathered(&self, c: usize, p: &Particles) -> (Vec2, f64) {
        let slots = self.members_in(c).iter().map(|&id| p.slot[id as usize]);
        member_sum(self.pos[c], slots, |k| (p.pos[k], p.force[k], p.torque[k]))
    }

    /// Advance every clump by one step under its [`gather`](Self::gather)ed
    /// force with [`integrate::advance`] and place its members (module
    /// docs).
    pub fn advance(&mut self, p: &mut Particles, g: Vec2, damping: BodyDamping, dt: f64) {
        self.pass(p, false, &[], (g, damping, dt), f64::INFINITY);
    }

    /// Make ready for a step in the contact sweep ([`rows`](Self::rows)
    /// stepped block by block with [`ClumpRows::step_block`], then
    /// [`step_across`](Self::step_across)) with blocks of `block` slots:
    /// the member slots found, the rows in their order, the clumps whose
    /// members lie in more than one block listed.
    pub(super) fn prepare(&mut self, p: &Particles, block: usize) {
        let fresh = self.slots.len() != self.members.len() || self.n_slots != p.len();
        self.refresh_slots(p);
        if fresh || self.across_block != block {
            let b = block.max(1) as u32;
            self.across = (0..self.len() as u32)
                .filter(|&r| self.lead[r as usize] / b != self.last[r as usize] / b)
                .collect();
            self.across_block = block;
        }
    }

    /// The rows for a step (after [`prepare`](Self::prepare)): the clumps
    /// gather their members' forces, advance under them (gravity `g`,
    /// `damping`, step `dt`) and check their members against `max_v2`.
    pub(super) fn rows(
        &mut self,
        (g, damping, dt): (Vec2, BodyDamping, f64),
        max_v2: f64,
    ) -> ClumpRows<'_> {
        ClumpRows {
            pos: self.pos.as_mut_ptr(),
            vel: self.vel.as_mut_ptr(),
            theta: self.theta.as_mut_ptr(),
            omega: self.omega.as_mut_ptr(),
            rot: self.rot.as_mut_ptr(),
            force: self.force.as_mut_ptr(),
            torque: self.torque.as_mut_ptr(),
            mass: &self.mass,
            inertia: &self.inertia,
            first: &self.first,
            slots: &self.slots,
            offset: &self.offset,
            lead: &self.lead,
            last: &self.last,
            motion: (g, damping, dt),
            max_v2,
        }
    }

    /// The step of the clumps that the sweep's blocks left (members in
    /// more than one block), after the sweep
    /// left their members' forces in `particles.force`/`torque`:
    /// [`gather`](Self::gather) and [`advance`](Self::advance), the same
    /// values. Returns the members' largest squared displacement from
    /// `ref_pos` (0 when it is not one per disc) and whether a member
    /// failed the step check `v·v ≤ max_v2 r²` (or is not finite).
    pub fn step_across(
        &mut self,
        p: &mut Particles,
        ref_pos: &[Vec2],
        motion: (Vec2, BodyDamping, f64),
        max_v2: f64,
    ) -> (f64, bool) {
        let across = std::mem::take(&mut self.across);
        let out = {
            let rows = self.rows(motion, max_v2);
            let discs = Discs::whole(p, ref_pos);
            across
                .par_iter()
                .with_min_len(256)
                // SAFETY: each row once; its members are its own
                // (`Discs`), at slots below the number of discs
                .map(|&r| unsafe { rows.step_row(r as usize, true, &discs) })
                .reduce(|| (0.0, false), |a, b| (a.0.max(b.0), a.1 || b.1))
        };
        self.across = across;
        out
    }

    /// One pass over the clumps, in parallel: each one's members' forces
    /// summed (with `gather`, [`gathered`](Self::gathered)'s sums), the
    /// clump advanced, its members placed and checked
    /// ([`ClumpRows::step_row`]), reading and writing its members at their
    /// slots, found once per slot order. Each clump works on its own state
    /// and members: the same on any number of threads.
    fn pass(
        &mut self,
        p: &mut Particles,
        gather: bool,
        ref_pos: &[Vec2],
        motion: (Vec2, BodyDamping, f64),
        max_v2: f64,
    ) -> (f64, bool) {
        self.refresh_slots(p);
        let rows = self.rows(motion, max_v2);
        let discs = Discs::whole(p, ref_pos);
        (0..rows.mass.len())
            .into_par_iter()
            .with_min_len(256)
            // SAFETY: as in `step_across`
            .map(|r| unsafe { rows.step_row(r, gather, &discs) })
            .reduce(|| (0.0, false), |a, b| (a.0.max(b.0), a.1 || b.1))
    }

    /// The smallest effective mass of a contact on a clump,
    /// `1/(1/M + R²/I)` with `R` the farthest reach of a member's rim from
    /// the centre (a force at the rim, at right angles to the arm): the
    /// mass that sets a clump's critical step (infinity without clumps).
    pub fn min_effective_mass(&self, p: &Particles) -> f64 {
        (0..self.len())
            .map(|c| {
                let (a, b) = (self.first[c] as usize, self.first[c + 1] as usize);
                let reach = self.members[a..b]
                    .iter()
                    .zip(&self.offset[a..b])
                    .map(|(&id, o)| o.norm() + p.radius[p.slot[id as usize] as usize])
                    .fold(0.0, f64::max);
                1.0 / (1.0 / self.mass[c] + reach * reach / self.inertia[c])
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Is every clump's state finite?
    pub fn is_finite(&self) -> bool {
        self.pos
            .iter()
            .chain(&self.vel)
            .all(|v| v.x.is_finite() && v.y.is_finite())
            && self.theta.iter().chain(&self.omega).all(|v| v.is_finite())
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of;
        (self.pos.capacity() * 3 + self.offset.capacity()) * size_of::<Vec2>()
            + self.theta.capacity() * 5 * size_of::<f64>()
            + (self.first.capacity() + self.members.capacity() + self.slots.capacity()) * 4
            + (self.id.capacity() + self.row.capacity()) * 4
            + (self.lead.capacity() + self.last.capacity() + self.across.capacity()) * 4
            + self.rot.capacity() * size_of::<(f64, f64)>()
    }
}

/// The force and the moment about `x` of the members in `slots`, whose
/// position, force and moment are `at(slot)`, in member order: what a
/// clump at `x` receives.
#[inline(always)]
fn member_sum(
    x: Vec2,
    slots: impl Iterator<Item = u32>,
    at: impl Fn(usize) -> (Vec2, Vec2, f64),
) -> (Vec2, f64) {
    let (mut f, mut t) = (Vec2::ZERO, 0.0);
    for s in slots {
        let (pos, force, torque) = at(s as usize);
        f += force;
        t += torque + (pos - x).cross(force);
    }
    (f, t)
}

/// Centre and velocity of the member at offset `o` of a clump at `x`
/// with velocity `v`, spin `w` and `(sin θ, cos θ)` `rot`:
/// `x_m = x + R(θ) o`, `v_m = v + ω × (x_m − x)`.
#[inline(always)]
fn rigid_motion(x: Vec2, v: Vec2, w: f64, (s, co): (f64, f64), o: Vec2) -> (Vec2, Vec2) {
    let r = Vec2::new(co * o.x - s * o.y, s * o.x + co * o.y);
    (x + r, v + r.perp() * w)
}

/// The clumps' rows for one step ([`Clumps::rows`]), each one stepped by
/// [`step_row`](Self::step_row) on one thread: a clump's state is its
/// row's alone.
pub(super) struct ClumpRows<'a> {
    pos: *mut Vec2,
    vel: *mut Vec2,
    theta: *mut f64,
    omega: *mut f64,
    rot: *mut (f64, f64),
    force: *mut Vec2,
    torque: *mut f64,
    mass: &'a [f64],
    inertia: &'a [f64],
    first: &'a [u32],
    slots: &'a [u32],
    offset: &'a [Vec2],
    lead: &'a [u32],
    last: &'a [u32],
    motion: (Vec2, BodyDamping, f64),
    max_v2: f64,
}

impl ClumpRows<'_> {
    /// Step the clump in row `r`: its members' forces summed (with
    /// `gather`, in member order: [`member_sum`]), the clump advanced
    /// ([`integrate::advance`]), its members placed
    /// ([`rigid_motion`]) and checked. Returns the members' largest
    /// squared displacement from their reference (0 without one) and
    /// whether one failed the step check.
    ///
    /// # Safety
    /// `r` is a row that no other thread steps, and `discs` holds its
    /// members' slots, which no other thread touches meanwhile.
    #[inline(always)]
    unsafe fn step_row(&self, r: usize, gather: bool, discs: &Discs) -> (f64, bool) {
        let (a, b) = (self.first[r] as usize, self.first[r + 1] as usize);
        let (slots, offset) = (&self.slots[a..b], &self.offset[a..b]);
        let (g, damping, dt) = self.motion;
        // SAFETY: row r is this thread's (the caller's promise)
        let (x, v, th, w, rot, f, t) = unsafe {
            (
                &mut *self.pos.add(r),
                &mut *self.vel.add(r),
                &mut *self.theta.add(r),
                &mut *self.omega.add(r),
                &mut *self.rot.add(r),
                &mut *self.force.add(r),
                &mut *self.torque.add(r),
            )
        };
        if gather {
            // SAFETY: the members' slots are in `discs` (the caller's promise)
            let at = |s: usize| unsafe { discs.loads(s) };
            (*f, *t) = member_sum(*x, slots.iter().copied(), at);
        }
        let (inv_m, inv_i) = (1.0 / self.mass[r], 1.0 / self.inertia[r]);
        integrate::advance(x, v, th, w, *f, *t, inv_m, inv_i, 0, g, damping, dt);
        *rot = th.sin_cos();
        let (mut m2, mut bad) = (0.0f64, false);
        for (&s, &o) in slots.iter().zip(offset) {
            let (xm, vm) = rigid_motion(*x, *v, *w, *rot, o);
            // SAFETY: as above
            let (d2, r) = unsafe { discs.set(s as usize, xm, vm, *th, *w) };
            m2 = m2.max(d2);
            bad |= !integrate::passes_check(xm, vm, *w, r, self.max_v2);
        }
        (m2, bad)
    }

    /// Step the clumps whose members all lie in the discs `discs` holds,
    /// slots `lo..hi` (one block of the contact sweep, every disc of it
    /// swept: their forces are complete and nothing reads their state any
    /// more this step), as [`step_row`](Self::step_row) with the members'
    /// forces gathered. The clumps with members in other blocks are left
    /// to [`Clumps::step_across`].
    ///
    /// # Safety
    /// No other thread touches the slots `lo..hi` meanwhile, and the
    /// blocks of one step do not overlap (each row's lead slot is in one
    /// block: its row is stepped once).
    pub(super) unsafe fn step_block(&self, lo: usize, hi: usize, discs: &Discs) -> (f64, bool) {
        let rows = self.lead.partition_point(|&s| (s as usize) < lo)
            ..self.lead.partition_point(|&s| (s as usize) < hi);
        let (mut m2, mut bad) = (0.0f64, false);
        for r in rows.filter(|&r| (self.last[r] as usize) < hi) {
            // SAFETY: the row's members are in lo..hi (the caller's promise)
            let (d2, b) = unsafe { self.step_row(r, true, discs) };
            m2 = m2.max(d2);
            bad |= b;
        }
        (m2, bad)
    }
}

// SAFETY: a row is stepped by one thread ([`ClumpRows::step_row`]).
unsafe impl Sync for ClumpRows<'_> {}
unsafe impl Send for ClumpRows<'_> {}

/// The discs a clump's step reads and writes at their slots: all of them,
/// or one block `lo..lo + n` of the contact sweep. A disc is a member of
/// one clump at most ([`Clumps::add`]), so no two clumps touch the same
/// slot.
pub(super) struct Discs {
    lo: usize,
    n: usize,
    pos: *mut Vec2,
    vel: *mut Vec2,
    theta: *mut f64,
    omega: *mut f64,
    force: *const Vec2,
    torque: *const f64,
    radius: *const f64,
    /// Positions at the last list rebuild (null: no reference).
    ref_pos: *const Vec2,
}

impl Discs {
    /// All the discs of `p`, with the reference `ref_pos` if it has one
    /// position per disc.
    fn whole(p: &mut Particles, ref_pos: &[Vec2]) -> Discs {
        let r = if ref_pos.len() == p.len() {
            ref_pos.as_ptr()
        } else {
            std::ptr::null()
        };
        let n = p.len();
        Discs::block(
            0,
            (&mut p.pos, &mut p.vel, &mut p.theta, &mut p.omega),
            (&p.force[..n], &p.torque[..n], &p.radius[..n]),
            r,
        )
    }

    /// The discs `lo..lo + pos.len()`, whose arrays are the slices given
    /// (all of that length), with the reference `ref_pos` (null: none).
    pub(super) fn block(
        lo: usize,
        (pos, vel, theta, omega): (&mut [Vec2], &mut [Vec2], &mut [f64], &mut [f64]),
        (force, torque, radius): (&[Vec2], &[f64], &[f64]),
        ref_pos: *const Vec2,
    ) -> Discs {
        let n = pos.len();
        assert!(
            [vel.len(), force.len()]
                .iter()
                .chain(&[theta.len(), omega.len()])
                .chain(&[torque.len(), radius.len()])
                .all(|&l| l == n)
        );
        Discs {
            lo,
            n,
            pos: pos.as_mut_ptr(),
            vel: vel.as_mut_ptr(),
            theta: theta.as_mut_ptr(),
            omega: omega.as_mut_ptr(),
            force: force.as_ptr(),
            torque: torque.as_ptr(),
            radius: radius.as_ptr(),
            ref_pos,
        }
    }

    /// Position, force and moment of the disc in slot `s`.
    ///
    /// # Safety
    /// `s` is one of the slots held, and no other thread writes it.
    #[inline(always)]
    unsafe fn loads(&self, s: usize) -> (Vec2, Vec2, f64) {
        let k = s - self.lo;
        debug_assert!(k < self.n);
        // SAFETY: as the caller promises.
        unsafe { (*self.pos.add(k), *self.force.add(k), *self.torque.add(k)) }
    }

    /// Set the position, velocity, rotation and spin of the disc in slot
    /// `s`; returns its squared displacement from the reference (0
    /// without one) and its radius.
    ///
    /// # Safety
    /// `s` is one of the slots held, and no other thread reads or writes it.
    #[inline(always)]
    unsafe fn set(&self, s: usize, x: Vec2, v: Vec2, theta: f64, omega: f64) -> (f64, f64) {
        let k = s - self.lo;
        debug_assert!(k < self.n);
        // SAFETY: as the caller promises.
        unsafe {
            *self.pos.add(k) = x;
            *self.vel.add(k) = v;
            *self.theta.add(k) = theta;
            *self.omega.add(k) = omega;
            let d2 = if self.ref_pos.is_null() {
                0.0
            } else {
                (x - *self.ref_pos.add(k)).norm2()
            };
            (d2, *self.radius.add(k))
        }
    }
}

// SAFETY: a slot is touched by the one clump it belongs to (see above).
unsafe impl Sync for Discs {}
unsafe impl Send for Discs {}

/// How a template is scaled onto the disc it replaces
/// ([`replace_with_template`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Fit {
    /// The clump lies inside the disc's circle, touching it: no new
    /// overlaps with the neighbours; the clump is lighter than the disc.
    #[default]
    Inside,
    /// The clump has the disc's area (and so its mass); it reaches out of
    /// the disc's circle.
    Area,
}

/// Replace the discs `rows[k]` for which `pick(k)` holds by clumps of the
/// template's discs `(centre, radius)`: the template, centred on its
/// union's centroid, scaled by the `fit` and rotated by an angle drawn
/// uniformly in [0, 2π) (seeded: the same packing each time), replaces the
/// disc at its centre; its members take the disc's material. Returns the
/// new rows (the discs that stay and each clump's members in the order
/// of the rows they replace) and each clump's member rows.
pub fn replace_with_template(
    rows: &[DiscRow],
    template: &[(Vec2, f64)],
    fit: Fit,
    pick: impl Fn(usize) -> bool,
    seed: u64,
) -> (Vec<DiscRow>, Vec<Vec<usize>>) {
    let shape = union_shape(template);
    let local: Vec<(Vec2, f64)> = template
        .iter()
        .map(|&(c, r)| (c - shape.centroid, r))
        .collect();
    let reach = local.iter().map(|&(c, r)| c.norm() + r).fold(0.0, f64::max);
    let mut rng = oorandom::Rand64::new(seed as u128);
    let mut out = Vec::with_capacity(rows.len() * template.len());
    let mut groups = Vec::new();
    for (k, row) in rows.iter().enumerate() {
        if !pick(k) {
            out.push(row.clone());
            continue;
        }
        let scale = match fit {
            Fit::Inside => row.r / reach,
            Fit::Area => (PI * row.r * row.r / shape.area).sqrt(),
        };
        let (s, c) = (TAU * rng.rand_float()).sin_cos();
        let first = out.len();
        for &(o, r) in &local {
            let o = o * scale;
            out.push(DiscRow {
                pos: row.pos + Vec2::new(c * o.x - s * o.y, s * o.x + c * o.y),
                r: r * scale,
                material: row.material.clone(),
            });
        }
        groups.push((first..out.len()).collect());
    }
    (out, groups)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_disc_is_a_disc() {
        let s = union_shape(&[(Vec2::new(3.0, -2.0), 1.5)]);
        assert!((s.area - PI * 2.25).abs() < 1e-13);
        assert!((s.centroid - Vec2::new(3.0, -2.0)).norm() < 1e-13);
        assert!((s.polar - PI * 1.5f64.powi(4) / 2.0).abs() < 1e-12);
    }

    #[test]
    fn two_equal_discs_make_the_lens_formula() {
        // union area = 2πr² − lens, lens = 2r² acos(d/2r) − (d/2)√(4r² − d²)
        let (r, d) = (1.0f64, 1.2f64);
        let s = union_shape(&[(Vec2::ZERO, r), (Vec2::new(d, 0.0), r)]);
        let lens = 2.0 * r * r * (d / (2.0 * r)).acos() - 0.5 * d * (4.0 * r * r - d * d).sqrt();
        assert!((s.area - (2.0 * PI * r * r - lens)).abs() < 1e-13);
        assert!((s.centroid - Vec2::new(0.6, 0.0)).norm() < 1e-14);
        // a disc inside another adds nothing; a duplicate adds nothing
        let t = union_shape(&[
            (Vec2::ZERO, 2.0),
            (Vec2::new(0.5, 0.5), 1.0),
            (Vec2::ZERO, 2.0),
        ]);
        assert!((t.area - 4.0 * PI).abs() < 1e-12);
        assert!((t.polar - 8.0 * PI).abs() < 1e-12);
    }
}
