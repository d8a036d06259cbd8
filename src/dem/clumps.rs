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

/// The clumps of an assembly, and each one's rigid-body state.
#[derive(Debug, Clone, Default)]
pub struct Clumps {
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
    /// Members of clump c: `members[first[c]..first[c + 1]]` (disc ids).
    pub first: Vec<u32>,
    /// Disc ids of the members, clump by clump.
    pub members: Vec<u32>,
    /// Each member's centre relative to X at θ = 0.
    pub offset: Vec<Vec2>,
    /// `(sin θ, cos θ)` of each clump, from its last advance.
    rot: Vec<(f64, f64)>,
    /// Slot of each member (as `members`) in the slot order of `n_slots`
    /// discs (empty: to be found again, [`invalidate`](Self::invalidate)).
    slots: Vec<u32>,
    n_slots: usize,
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
    /// the number of discs changed.
    fn refresh_slots(&mut self, p: &Particles) {
        if self.slots.len() != self.members.len() || self.n_slots != p.len() {
            self.slots = self.members.iter().map(|&id| p.slot[id as usize]).collect();
            self.n_slots = p.len();
        }
    }

    /// Disc ids of clump `c`'s members.
    pub fn members_of(&self, c: usize) -> &[u32] {
        &self.members[self.first[c] as usize..self.first[c + 1] as usize]
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
        self.place(c, p);
        Ok(c)
    }

    /// `(sin θ, cos θ)` of every clump from its `theta` (after the clumps'
    /// state was set from a saved one; a step keeps them itself).
    pub(super) fn refresh_rotations(&mut self) {
        self.rot = self.theta.iter().map(|t| t.sin_cos()).collect();
    }

    /// Put clump `c`'s members where its rigid motion takes them.
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

    /// Centre and velocity of the member of clump `c` at offset `o`
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

    /// [`gather`](Self::gather) for clump `c`, in member order.
    #[inline(always)]
    fn gathered(&self, c: usize, p: &Particles) -> (Vec2, f64) {
        let slots = self.members_of(c).iter().map(|&id| p.slot[id as usize]);
        member_sum(self.pos[c], slots, |k| p.pos[k], (&p.force, &p.torque))
    }

    /// Advance every clump by one step under its [`gather`](Self::gather)ed
    /// force with [`integrate::advance`] and place its members (module
    /// docs).
    pub fn advance(&mut self, p: &mut Particles, g: Vec2, damping: BodyDamping, dt: f64) {
        self.pass(p, false, &[], (g, damping, dt), f64::INFINITY);
    }

    /// One step of every clump after a contact sweep that left its
    /// members' forces in `particles.force`/`torque` and did not move
    /// them: [`gather`](Self::gather) and [`advance`](Self::advance), the
    /// same values. Returns the members' largest squared displacement
    /// from `ref_pos` (0 when it is not one per disc) and whether a member
    /// failed the step check `v·v ≤ max_v2 r²` (or is not finite).
    pub fn step(
        &mut self,
        p: &mut Particles,
        ref_pos: &[Vec2],
        motion: (Vec2, BodyDamping, f64),
        max_v2: f64,
    ) -> (f64, bool) {
        self.pass(p, true, ref_pos, motion, max_v2)
    }

    /// One pass over the clumps, in parallel: each one's members' forces
    /// summed (with `gather`, [`gathered`](Self::gathered)'s sums), the
    /// clump advanced, its members placed and checked (as
    /// [`step`](Self::step)), reading and writing its members at their
    /// slots, found once per slot order. Each clump works on its own state
    /// and members: the same on any number of threads.
    fn pass(
        &mut self,
        p: &mut Particles,
        gather: bool,
        ref_pos: &[Vec2],
        (g, damping, dt): (Vec2, BodyDamping, f64),
        max_v2: f64,
    ) -> (f64, bool) {
        self.refresh_slots(p);
        let has_ref = ref_pos.len() == p.len();
        let discs = MembersMut {
            pos: p.pos.as_mut_ptr(),
            vel: p.vel.as_mut_ptr(),
            theta: p.theta.as_mut_ptr(),
            omega: p.omega.as_mut_ptr(),
        };
        let (force, torque, radius) = (&p.force, &p.torque, &p.radius);
        let (first, slots, offset) = (&self.first, &self.slots, &self.offset);
        (
            &mut self.pos,
            &mut self.vel,
            &mut self.theta,
            &mut self.omega,
            &mut self.rot,
            &mut self.force,
            &mut self.torque,
            (&self.mass, &self.inertia),
        )
            .into_par_iter()
            .enumerate()
            .with_min_len(256)
            .map(|(c, (x, v, th, w, rot, f, t, (&m, &i)))| {
                let (a, b) = (first[c] as usize, first[c + 1] as usize);
                let members = (&slots[a..b], &offset[a..b]);
                if gather {
                    // SAFETY: a slot below the number of discs
                    // (`refresh_slots`), of this clump's member only.
                    let at = |s: usize| unsafe { discs.pos(s) };
                    (*f, *t) = member_sum(*x, members.0.iter().copied(), at, (force, torque));
                }
                integrate::advance(x, v, th, w, *f, *t, 1.0 / m, 1.0 / i, 0, g, damping, dt);
                *rot = th.sin_cos();
                let (mut m2, mut bad) = (0.0f64, false);
                for (&s, &o) in members.0.iter().zip(members.1) {
                    let s = s as usize;
                    let (xm, vm) = rigid_motion(*x, *v, *w, *rot, o);
                    // SAFETY: as above: no other clump reads or writes
                    // this member's slot.
                    unsafe { discs.set(s, xm, vm, *th, *w) };
                    if has_ref {
                        m2 = m2.max((xm - ref_pos[s]).norm2());
                    }
                    bad |= !integrate::passes_check(xm, vm, *w, radius[s], max_v2);
                }
                (m2, bad)
            })
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
            + self.rot.capacity() * size_of::<(f64, f64)>()
    }
}

/// The force and the moment about `x` of the members in `slots`, at
/// `pos(slot)`, in member order: what a clump at `x` receives.
#[inline(always)]
fn member_sum(
    x: Vec2,
    slots: impl Iterator<Item = u32>,
    pos: impl Fn(usize) -> Vec2,
    (force, torque): (&[Vec2], &[f64]),
) -> (Vec2, f64) {
    let (mut f, mut t) = (Vec2::ZERO, 0.0);
    for s in slots {
        let s = s as usize;
        f += force[s];
        t += torque[s] + (pos(s) - x).cross(force[s]);
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

/// The members' positions, velocities, rotations and spins, written by
/// [`Clumps::pass`] clump by clump in parallel: a disc is a member of one
/// clump at most ([`Clumps::add`]), so no two clumps touch the same slot.
struct MembersMut {
    pos: *mut Vec2,
    vel: *mut Vec2,
    theta: *mut f64,
    omega: *mut f64,
}

impl MembersMut {
    /// The position of the disc in slot `s`.
    ///
    /// # Safety
    /// `s` is a slot of the discs, and no other thread writes it.
    #[inline(always)]
    unsafe fn pos(&self, s: usize) -> Vec2 {
        // SAFETY: as the caller promises.
        unsafe { *self.pos.add(s) }
    }

    /// Set the position, velocity, rotation and spin of the disc in slot
    /// `s`.
    ///
    /// # Safety
    /// `s` is a slot of the discs, and no other thread reads or writes it.
    #[inline(always)]
    unsafe fn set(&self, s: usize, x: Vec2, v: Vec2, theta: f64, omega: f64) {
        // SAFETY: as the caller promises.
        unsafe {
            *self.pos.add(s) = x;
            *self.vel.add(s) = v;
            *self.theta.add(s) = theta;
            *self.omega.add(s) = omega;
        }
    }
}

// SAFETY: the pointers are used by one clump per slot (see above).
unsafe impl Sync for MembersMut {}
unsafe impl Send for MembersMut {}

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
