//! Parallel bonds between discs: the bonded-particle model of Potyondy &
//! Cundall (2004), in 2D.
//!
//! A parallel bond is a finite piece of cement between two discs a and b:
//! a strip of half-width `R̄ = λ̄ min(r_a, r_b)` across the contact, through
//! the disc thickness t, acting in parallel with the linear contact law
//! (the grains still touch). With the unit normal `n` from a to b and
//! `t = perp(n)`, the bond carries a normal force `F_n` (compression
//! positive), a shear force `F_s` along t and a moment `M` (on a; b gets
//! the opposite), updated from the relative motion of the step
//! (Potyondy & Cundall 2004, Eqs. 6–9):
//!
//! ```text
//! A = 2 R̄ t,   I = (2/3) R̄³ t          (area and second moment of the strip)
//! ΔF_n =  k̄_n A Δu_n,   Δu_n = (v_a − v_b)·n Δt
//! ΔF_s = −k̄_s A Δu_s,   Δu_s = [(v_a − v_b)·t + ω_a l_a + ω_b l_b] Δt
//! ΔM   = −k̄_n I Δθ,     Δθ  = (ω_a − ω_b) Δt
//! ```
//!
//! `k̄_n`, `k̄_s` are stiffnesses per area (stress per length). The lever
//! arms `l_a = d r_a/(r_a + r_b)`, `l_b = d r_b/(r_a + r_b)` put the bond's
//! centre on the line of centres (d apart), dividing it as the radii:
//! `l_a + l_b = d`, so a rigid rotation of the pair shears nothing, and
//! the same arms give the moments `l_a F_s` and `l_b F_s` of the shear
//! force (the pair is work-consistent). The force on a is
//! `−F_n n + F_s t`, its moment `l_a F_s + M`; b gets `−(−F_n n + F_s t)`
//! and `l_b F_s − M`.
//!
//! Strength (beam theory on the strip): the largest tensile stress and the
//! shear stress are
//!
//! ```text
//! σ = −F_n/A + |M| R̄/I,   τ = |F_s|/A
//! ```
//!
//! and the bond breaks, in tension, when `σ ≥ σ_c`, else in shear when
//! `τ ≥ τ_c` — a fixed shear strength, or the cohesion–friction strength
//! `τ_c = c + σ_n tan φ` with the mean normal stress `σ_n = F_n/A`
//! (compression positive, as PFC's `pb` model). Strengths may scatter
//! from bond to bond (normal, seeded by the pair of disc ids: the same on
//! any thread count, rank or restart). A broken bond is removed; it exerts
//! no force in the step it breaks, and the energy it held,
//! `F_n²/(2k̄_nA) + F_s²/(2k̄_sA) + M²/(2k̄_nI)` ([`bond_energy`]; taken
//! between its forces before and after the step, [`released`]), is
//! *released* (counted in the energy account). A bond made at step n has
//! zero force in the state of step n.
//!
//! # Data layout (MPI-ready)
//!
//! A bond is plain data keyed by the *ids* of its discs, never by slots
//! ([`BondList`]): the pair `(a, b)`, `a < b`, its radius, its two
//! strengths and its three forces, in arrays indexed by the bond, sorted
//! by `(a, b)`. So a bond can be sent with its discs to another rank
//! and merged into that rank's list. What a step works on is derived from
//! the list (`Bonds::refresh`, after the discs are renumbered or the
//! list changes): the bonds *held* in the slot order of their discs, in
//! rows over the smaller slot like the contact list — only what a step
//! reads (`Held`, 80 bytes of constants), with their forces beside them in that
//! orientation. The contact sweep steps them block by block (a block's
//! bonds just before its discs, from the state before the step, two at a
//! time in SIMD lanes with the scalar operations; a bond whose second
//! disc lies in a later block ahead of the sweep, as the contacts do).
//! Every disc sums its bonds in that fixed order, so the result does not
//! depend on the number of threads or on where the bonds are stored. The
//! list takes the new forces only when it is read ([`Bonds::list`],
//! [`Bonds::sync`]; a checkpoint, an output) or the bonds are held anew
//! (the discs renumbered, a bond broken).

#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
pub(super) mod lanes;

use super::broadphase::CrossIndex;
use super::contact::Side;
use super::particles::Particles;
use crate::geom::Vec2;
use rayon::prelude::*;

/// Shear strength of a bond.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ShearStrength {
    /// A fixed strength `τ_c` (stress).
    Fixed(f64),
    /// Cohesion–friction: `τ_c = c + σ_n tan φ`, σ_n the bond's mean normal
    /// stress (compression positive).
    Coulomb {
        /// Cohesion c (stress).
        cohesion: f64,
        /// tan φ of the friction angle φ.
        tan_phi: f64,
    },
}

/// The material of the parallel bonds of an assembly.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BondLaw {
    /// Radius multiplier λ̄: `R̄ = λ̄ min(r_a, r_b)`.
    pub radius_factor: f64,
    /// Normal stiffness per area `k̄_n` (stress per length).
    pub kn: f64,
    /// Shear stiffness per area `k̄_s`.
    pub ks: f64,
    /// Mean tensile strength σ_c (stress).
    pub tensile: f64,
    /// Shear strength (its mean; the cohesion of a cohesion–friction one).
    pub shear: ShearStrength,
    /// Coefficient of variation of the strengths: each bond's σ_c and τ_c
    /// (or c) are the means times `1 + scatter · z`, z standard normal
    /// clipped to ±3 (0: every bond has the means).
    pub scatter: f64,
    /// Seed of the scatter.
    pub seed: u64,
}

impl Default for BondLaw {
    fn default() -> Self {
        BondLaw {
            radius_factor: 1.0,
            kn: 0.0,
            ks: 0.0,
            tensile: f64::INFINITY,
            shear: ShearStrength::Fixed(f64::INFINITY),
            scatter: 0.0,
            seed: 1,
        }
    }
}

/// Which pairs are bonded, and when.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BondRule {
    /// Bond at the start of this step (0: before the first step).
    pub at_step: usize,
    /// Bond pairs whose gap `d − r_a − r_b` is below `gap × min(r_a, r_b)`
    /// (touching and overlapping pairs included).
    pub gap: f64,
    /// Only pairs whose two centres lie in this box `(lo, hi)`.
    pub region: Option<(Vec2, Vec2)>,
    /// Only pairs whose two discs are of these materials (empty: any).
    pub materials: Vec<u16>,
}

/// How a bond broke.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum BreakMode {
    /// The largest tensile stress reached σ_c.
    Tension,
    /// The shear stress reached τ_c.
    Shear,
}

impl BreakMode {
    /// `tension` or `shear`.
    pub fn name(self) -> &'static str {
        match self {
            BreakMode::Tension => "tension",
            BreakMode::Shear => "shear",
        }
    }
}

/// A broken bond: the crack it leaves.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BrokenBond {
    /// Steps done before the step in which it broke.
    pub step: usize,
    /// Time of the state it broke in (`step × Δt`).
    pub time: f64,
    /// Disc ids (0-based), `a < b`.
    pub a: u32,
    /// Second disc id.
    pub b: u32,
    /// The bond's centre then.
    pub pos: Vec2,
    /// Unit normal from a to b then (the crack runs along `perp(normal)`).
    pub normal: Vec2,
    /// The bond's radius R̄ (half the crack's length).
    pub radius: f64,
    /// Tension or shear.
    pub mode: BreakMode,
    /// Energy the bond held when it broke.
    pub energy: f64,
}

/// The bonds of an assembly and their history: plain arrays keyed by disc
/// ids (see the module docs), everything a checkpoint saves.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BondList {
    /// First disc id of each bond (`a < b`); bonds sorted by `(a, b)`.
    pub a: Vec<u32>,
    /// Second disc id.
    pub b: Vec<u32>,
    /// Bond radius R̄.
    pub radius: Vec<f64>,
    /// Tensile strength σ_c of each bond.
    pub tensile: Vec<f64>,
    /// Shear strength τ_c (or cohesion c) of each bond.
    pub shear: Vec<f64>,
    /// Normal force F_n (compression positive).
    pub fn_: Vec<f64>,
    /// Shear force F_s along `t = perp(n)`.
    pub fs: Vec<f64>,
    /// Moment M on disc a.
    pub moment: Vec<f64>,
    /// The rule has been applied.
    pub created: bool,
    /// The bonds were made in this step: its increment is not theirs.
    pub fresh: bool,
    /// Number of bonds made by the rule.
    pub made: usize,
    /// Every bond broken so far, in the order they broke (a step's in
    /// `(a, b)` order).
    pub broken: Vec<BrokenBond>,
    /// Energy released by broken bonds so far.
    pub released: f64,
}

/// Keep the elements `k` of `v` for which `keep[k]` holds (in order).
fn keep_only<T>(v: &mut Vec<T>, keep: &[bool]) {
    let mut k = 0;
    v.retain(|_| {
        k += 1;
        keep[k - 1]
    });
}

impl BondList {
    /// Number of intact bonds.
    pub fn len(&self) -> usize {
        self.a.len()
    }

    /// No intact bond.
    pub fn is_empty(&self) -> bool {
        self.a.is_empty()
    }

    /// Keep the bonds for which `keep(k)` holds (in order).
    fn retain(&mut self, keep: &[bool]) {
        keep_only(&mut self.a, keep);
        keep_only(&mut self.b, keep);
        keep_only(&mut self.radius, keep);
        keep_only(&mut self.tensile, keep);
        keep_only(&mut self.shear, keep);
        keep_only(&mut self.fn_, keep);
        keep_only(&mut self.fs, keep);
        keep_only(&mut self.moment, keep);
    }

    /// Is the list consistent for `n` discs (equal lengths, sorted pairs
    /// `a < b < n`)?
    pub fn check(&self, n: usize) -> Result<(), String> {
        let m = self.a.len();
        if [
            self.b.len(),
            self.radius.len(),
            self.tensile.len(),
            self.shear.len(),
            self.fn_.len(),
            self.fs.len(),
            self.moment.len(),
        ]
        .iter()
        .any(|&l| l != m)
        {
            return Err("the bond arrays differ in length".into());
        }
        let pairs_ok = self
            .a
            .iter()
            .zip(&self.b)
            .all(|(&a, &b)| a < b && (b as usize) < n);
        let sorted = (1..m).all(|k| (self.a[k - 1], self.b[k - 1]) < (self.a[k], self.b[k]));
        if !pairs_ok || !sorted {
            return Err("the bonds are not sorted pairs of disc ids".into());
        }
        Ok(())
    }
}

/// What one bond does in a step: the force on its first disc (the
/// second gets its opposite) and the moments on the two.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BondForce {
    /// Force on the first disc.
    pub f: Vec2,
    /// Moment on the first disc.
    pub ma: f64,
    /// Moment on the second disc.
    pub mb: f64,
}

/// Area `A = 2R̄t` and second moment `I = (2/3)R̄³t` of a bond of radius
/// `r` through thickness `t`.
#[inline(always)]
pub fn section(r: f64, t: f64) -> (f64, f64) {
    (2.0 * r * t, 2.0 / 3.0 * r * r * r * t)
}

/// Energy stored in a bond with forces `(F_n, F_s, M)`, area A and second
/// moment I: `F_n²/(2k̄_nA) + F_s²/(2k̄_sA) + M²/(2k̄_nI)`.
#[inline]
pub fn bond_energy(law: &BondLaw, (fn_, fs, m): (f64, f64, f64), a: f64, i: f64) -> f64 {
    let mut e = 0.0;
    if law.kn > 0.0 {
        e += 0.5 * fn_ * fn_ / (law.kn * a) + 0.5 * m * m / (law.kn * i);
    }
    if law.ks > 0.0 {
        e += 0.5 * fs * fs / (law.ks * a);
    }
    e
}

/// The energy a bond releases when it breaks in a step that took its
/// forces from `old` to `new`: `F_old F_new/(2k)` per component. This is
/// the product form that closes the central difference's discrete energy
/// balance exactly for a linear spring: with the kinetic energy taken as
/// `½ m v_{n−½}·v_{n+½}` and a spring's energy `½ k x_n²`, the stored
/// energy is conserved step by step, and a spring removed at step n (its
/// force no longer applied from x_n on) takes `½ k x_{n−1} x_n` with it.
/// It differs from `F_new²/(2k)` by one step's increment.
#[inline]
pub fn released(
    law: &BondLaw,
    (n0, s0, m0): (f64, f64, f64),
    (n1, s1, m1): (f64, f64, f64),
    (a, i): (f64, f64),
) -> f64 {
    let mut e = 0.0;
    if law.kn > 0.0 {
        e += 0.5 * n0 * n1 / (law.kn * a) + 0.5 * m0 * m1 / (law.kn * i);
    }
    if law.ks > 0.0 {
        e += 0.5 * s0 * s1 / (law.ks * a);
    }
    e
}

/// The largest tensile stress `σ = −F_n/A + |M|R̄/I` and the shear stress
/// `τ = |F_s|/A` of a bond.
#[inline(always)]
pub fn stresses(fn_: f64, fs: f64, m: f64, r: f64, a: f64, i: f64) -> (f64, f64) {
    (-fn_ / a + m.abs() * r / i, fs.abs() / a)
}

/// Does a bond with these forces break, and how? Tension first
/// (`σ ≥ σ_c`), then shear (`τ ≥ τ_c`, `τ_c = c + σ_n tan φ` for a
/// cohesion–friction strength).
#[inline(always)]
pub fn breaks(
    law: &BondLaw,
    (fn_, fs, m): (f64, f64, f64),
    r: f64,
    (a, i): (f64, f64),
    tensile: f64,
    shear: f64,
) -> Option<BreakMode> {
    let (sigma, tau) = stresses(fn_, fs, m, r, a, i);
    let tau_c = match law.shear {
        ShearStrength::Fixed(_) => shear,
        ShearStrength::Coulomb { tan_phi, .. } => shear + fn_ / a * tan_phi,
    };
    if sigma >= tensile {
        Some(BreakMode::Tension)
    } else if tau >= tau_c {
        Some(BreakMode::Shear)
    } else {
        None
    }
}

/// SplitMix64: a well-mixed 64-bit hash step.
fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Two standard normal numbers for the pair `(a, b)` under `seed` (Box–
/// Muller on a hash of the three: the same wherever the bond is made).
fn normals(seed: u64, a: u32, b: u32) -> (f64, f64) {
    let h1 = splitmix(seed ^ splitmix(((a as u64) << 32) | b as u64));
    let h2 = splitmix(h1);
    let u1 = ((h1 >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let u2 = (h2 >> 11) as f64 / (1u64 << 53) as f64;
    let r = (-2.0 * u1.ln()).sqrt();
    let phi = 2.0 * std::f64::consts::PI * u2;
    (r * phi.cos(), r * phi.sin())
}

/// The strengths `(σ_c, τ_c or c)` of the bond between discs `a < b`.
pub fn strengths(law: &BondLaw, a: u32, b: u32) -> (f64, f64) {
    let shear = match law.shear {
        ShearStrength::Fixed(t) => t,
        ShearStrength::Coulomb { cohesion, .. } => cohesion,
    };
    if law.scatter == 0.0 {
        return (law.tensile, shear);
    }
    let (z1, z2) = normals(law.seed, a, b);
    let f = |z: f64| 1.0 + law.scatter * z.clamp(-3.0, 3.0);
    (law.tensile * f(z1), shear * f(z2))
}

/// A bond as the contact sweep holds it: in the row of the smaller of its
/// two slots `i < j` (rows by `i`, `j` ascending, as the contact list).
/// Only what a step reads: the bond's constants (80 bytes, read and never
/// written by a step, made once when the bonds are held); its forces are
/// held beside it ([`Bonds::held_f`]), its radius and index in the list
/// apart ([`Bonds::held_r`], [`Bonds::held_key`]), read only when it
/// breaks. Every constant is the value the step's formula would compute
/// first (`k̄_n A` before `k̄_n A v_n Δt`, the arms' ratios before
/// `d r_i/(r_i + r_j)`), so the step is bitwise the one that computes
/// them every time — without its divisions.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Held {
    /// Slots of the first and the second disc.
    pub i: u32,
    pub j: u32,
    /// The arms over the distance: `r_i/(r_i + r_j)`, `r_j/(r_i + r_j)`.
    ci: f64,
    cj: f64,
    /// `k̄_n A`, `k̄_s A` and `k̄_n I` of the bond's section.
    kn_a: f64,
    ks_a: f64,
    kn_i: f64,
    /// Tensile strength σ_c.
    tensile: f64,
    /// Shear strength τ_c (or cohesion c).
    shear: f64,
    /// `1/A` and `R̄/I`: the stresses as products ([`Held::intact`]).
    inv_a: f64,
    r_over_i: f64,
}

/// A held bond's forces in the orientation of its slots — normal from i
/// to j, the moment on i (minus the listed one when i is the bond's b;
/// `F_n` and `F_s` are the same either way): `(F_n, F_s, M on i)`.
pub(super) type HeldForces = (f64, f64, f64);

/// `(F_n, F_s, M)` with the moment's sign turned when `flip` (slot i is
/// the bond's b): the listed forces from the held ones, and back.
fn flipped((fn_, fs, m): HeldForces, flip: bool) -> HeldForces {
    (fn_, fs, if flip { -m } else { m })
}

/// A bond that broke in the sweep: where it is held (`w`), mode, energy
/// released, centre and normal from slot i to slot j (state before the
/// step).
#[derive(Debug, Clone, Copy)]
pub(super) struct Break {
    w: u32,
    mode: BreakMode,
    energy: f64,
    pos: Vec2,
    normal: Vec2,
}

impl Held {
    /// The bond of radius `radius` and strengths `(σ_c, τ_c or c)` between
    /// slots `(i, j)` (radii `(ri, rj)`), through `thickness`.
    pub(super) fn new(
        (i, j): (u32, u32),
        radius: f64,
        (tensile, shear): (f64, f64),
        (ri, rj): (f64, f64),
        law: &BondLaw,
        thickness: f64,
    ) -> Held {
        let (a, inertia) = section(radius, thickness);
        let rs = ri + rj;
        Held {
            i,
            j,
            ci: ri / rs,
            cj: rj / rs,
            kn_a: law.kn * a,
            ks_a: law.ks * a,
            kn_i: law.kn * inertia,
            tensile,
            shear,
            inv_a: 1.0 / a,
            r_over_i: radius / inertia,
        }
    }

    /// One step of the bond held at `w` (radius `radius`) between discs
    /// `si` (slot i) and `sj`, with forces `f`, from the state before the
    /// step: its forces updated ([`bond_step`]) and what it does to the
    /// two discs — nothing, with the [`Break`], when the updated forces
    /// reach its strength ([`breaks`]).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn step(
        &self,
        w: usize,
        f: &mut HeldForces,
        si: &Side,
        sj: &Side,
        law: &BondLaw,
        radius: &[f64],
        thickness: f64,
        dt: f64,
    ) -> (BondForce, Option<Break>) {
        let old = *f;
        let (bf, n, la) = bond_step(si, sj, self, dt, f);
        if self.intact(law, *f) {
            return (bf, None);
        }
        self.breakage(w, old, *f, radius[w], (si.pos, n, la), law, thickness)
            .map_or((bf, None), |b| (BondForce::default(), Some(b)))
    }

    /// The bond's breakage, if its new forces `new` reach its strength
    /// ([`breaks`]); `old`: its forces before the step, `(x_i, n, l_i)`
    /// the centre of disc i, the normal and the arm of i.
    #[cold]
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn breakage(
        &self,
        w: usize,
        old: HeldForces,
        new: HeldForces,
        radius: f64,
        (xi, n, la): (Vec2, Vec2, f64),
        law: &BondLaw,
        thickness: f64,
    ) -> Option<Break> {
        let sec = section(radius, thickness);
        let mode = breaks(law, new, radius, sec, self.tensile, self.shear)?;
        Some(Break {
            w: w as u32,
            mode,
            energy: released(law, old, new, sec),
            pos: xi + n * la,
            normal: n,
        })
    }

    /// Are the bond's stresses clearly below its strengths? The stresses
    /// of [`breaks`] taken as products by `1/A` and `R̄/I` are within a
    /// few ulps of its quotients, so with a margin of `16ε` of the terms
    /// `true` means that [`breaks`] finds the bond intact — without its
    /// divisions, which would cost more than the rest of the bond's step.
    #[inline(always)]
    fn intact(&self, law: &BondLaw, (fn_, fs, m): HeldForces) -> bool {
        const TOL: f64 = 16.0 * f64::EPSILON;
        let (sn, sm) = (-fn_ * self.inv_a, m.abs() * self.r_over_i);
        let tau = fs.abs() * self.inv_a;
        let friction = match law.shear {
            ShearStrength::Fixed(_) => 0.0,
            ShearStrength::Coulomb { tan_phi, .. } => fn_ * self.inv_a * tan_phi,
        };
        // τ_c rounded once more: the relative margin on it (an infinite
        // strength stays infinite)
        let tau_c = self.shear + friction;
        sn + sm + TOL * (sn.abs() + sm) < self.tensile
            && tau + TOL * (tau + friction.abs()) < tau_c * (1.0 - TOL)
    }
}

/// The disc in slot `s` as a side of a bond.
#[inline(always)]
fn side(p: &Particles, s: usize) -> Side {
    Side {
        pos: p.pos[s],
        vel: p.vel[s],
        omega: p.omega[s],
        radius: p.radius[s],
    }
}

/// The parallel bonds of an assembly: law, creation rule, the bond list
/// and what each step derives from it.
#[derive(Debug, Clone, Default)]
pub struct Bonds {
    /// The bonds' material.
    pub law: BondLaw,
    /// Which pairs are bonded and when (`None`: no bonds).
    pub rule: Option<BondRule>,
    /// The bonds and their history (saved by a checkpoint). Its forces
    /// are brought up to date only when read ([`list`](Self::list),
    /// [`sync`](Self::sync)): a step leaves the new forces where the
    /// sweep holds them.
    pub(crate) list: BondList,
    /// Bonds of the disc in slot `i` as the smaller slot:
    /// `held[row[i]..row[i + 1]]` (`n + 1` offsets; empty without bonds).
    pub(super) row: Vec<u32>,
    /// The bonds in slot order, as the sweep evaluates them.
    pub(super) held: Vec<Held>,
    /// Their forces (in `held`'s order and orientation).
    pub(super) held_f: Vec<HeldForces>,
    /// Their radii R̄ (read when a bond breaks).
    pub(super) held_r: Vec<f64>,
    /// Index in the list of each held bond, and whether its slot i is the
    /// bond's b.
    held_key: Vec<(u32, bool)>,
    /// Where each listed bond is held, and whether its slot i is its b.
    at: Vec<(u32, bool)>,
    /// The bonds whose second disc lies in a later sweep block.
    pub(super) cross: CrossIndex,
    /// What each cross bond does in this step and its new forces.
    pub(super) cross_buf: Vec<(BondForce, HeldForces)>,
    /// The disc thickness and the law `held` was built for.
    thickness: f64,
    held_law: BondLaw,
    /// The slots or the list changed since `held` was built.
    stale: bool,
    /// `held_f` holds newer forces than the list.
    dirty: bool,
}

impl Bonds {
    /// Does the assembly have bonds (a rule, whether applied yet or not)?
    pub fn active(&self) -> bool {
        self.rule.is_some()
    }

    /// The index needs rebuilding (the discs were renumbered).
    pub fn invalidate(&mut self) {
        self.stale = true;
    }

    /// The bonds and their history, with the forces of the present state
    /// (a copy when the list's forces are behind the sweep's: see
    /// [`sync`](Self::sync) to bring them up to date in place).
    pub fn list(&self) -> std::borrow::Cow<'_, BondList> {
        if !self.dirty {
            return std::borrow::Cow::Borrowed(&self.list);
        }
        let mut l = self.list.clone();
        self.copy_forces(&mut l);
        std::borrow::Cow::Owned(l)
    }

    /// Every bond broken so far ([`BondList::broken`]).
    pub fn broken(&self) -> &[BrokenBond] {
        &self.list.broken
    }

    /// Bring the list's forces up to date with the last step (a step
    /// leaves them where the sweep holds them, in slot order).
    pub fn sync(&mut self) {
        if self.dirty {
            let mut l = std::mem::take(&mut self.list);
            self.copy_forces(&mut l);
            self.list = l;
            self.dirty = false;
        }
    }

    /// Replace the list (a saved state): the index is rebuilt from it.
    pub(super) fn replace_list(&mut self, list: &BondList) {
        self.list.clone_from(list);
        self.dirty = false;
        self.stale = true;
    }

    /// The held forces into `l`'s force arrays, in list order (in
    /// parallel).
    fn copy_forces(&self, l: &mut BondList) {
        let held_f = &self.held_f;
        (&mut l.fn_, &mut l.fs, &mut l.moment, &self.at)
            .into_par_iter()
            .with_min_len(4096)
            .for_each(|(n, s, m, &(w, flip))| (*n, *s, *m) = flipped(held_f[w as usize], flip));
    }

    /// The forces `(F_n, F_s, M)` of listed bond k in the present state.
    fn forces(&self, k: usize) -> (f64, f64, f64) {
        let l = &self.list;
        if !self.dirty {
            return (l.fn_[k], l.fs[k], l.moment[k]);
        }
        let (w, flip) = self.at[k];
        flipped(self.held_f[w as usize], flip)
    }

    /// Hold the listed bonds in slot order, in rows of `n + 1` offsets,
    /// and index the cross bonds of sweep blocks of `block` discs (if
    /// stale); `thickness`: of the discs.
    pub(super) fn refresh(&mut self, p: &Particles, block: usize, thickness: f64) {
        let n = p.len();
        if !self.stale
            && self.row.len() == n + 1
            && self.cross.block == block
            && self.thickness == thickness
            && self.held_law == self.law
        {
            return;
        }
        // the forces of the last step, from the old order
        self.sync();
        self.stale = false;
        self.thickness = thickness;
        self.held_law = self.law;
        let l = &self.list;
        let ends = |k: usize| {
            let (sa, sb) = (p.slot[l.a[k] as usize], p.slot[l.b[k] as usize]);
            (sa.min(sb), sa.max(sb), sa > sb)
        };
        self.row.clear();
        self.row.resize(n + 1, 0);
        for k in 0..l.len() {
            self.row[ends(k).0 as usize + 1] += 1;
        }
        for d in 0..n {
            self.row[d + 1] += self.row[d];
        }
        // the list's bonds in held order: rows by slot i, j ascending
        let mut fill = self.row.clone();
        let mut order = vec![0u32; l.len()];
        for k in 0..l.len() {
            let i = ends(k).0 as usize;
            order[fill[i] as usize] = k as u32;
            fill[i] += 1;
        }
        for r in self.row.windows(2) {
            order[r[0] as usize..r[1] as usize].sort_unstable_by_key(|&k| ends(k as usize).1);
        }
        self.held.clear();
        self.held_f.clear();
        self.held_r.clear();
        self.held_key.clear();
        self.at.clear();
        self.at.resize(l.len(), (0, false));
        for (w, &k) in order.iter().enumerate() {
            let k = k as usize;
            let (i, j, flip) = ends(k);
            let radii = (p.radius[i as usize], p.radius[j as usize]);
            let strengths = (l.tensile[k], l.shear[k]);
            let h = Held::new((i, j), l.radius[k], strengths, radii, &self.law, thickness);
            self.held.push(h);
            self.held_r.push(l.radius[k]);
            self.held_f
                .push(flipped((l.fn_[k], l.fs[k], l.moment[k]), flip));
            self.held_key.push((k as u32, flip));
            self.at[k] = (w as u32, flip);
        }
        let held = &self.held;
        self.cross = CrossIndex::build(n, block, &self.row, |w| held[w].j);
        self.cross_buf.clear();
        self.cross_buf
            .resize(self.cross.pairs.len(), Default::default());
    }

    /// Step the cross bonds (second disc in a later block) from the state
    /// before the step into `cross_buf`; returns those that broke.
    pub(super) fn step_cross(&mut self, p: &Particles, thickness: f64, dt: f64) -> Vec<Break> {
        let (held, held_f, held_r, law) = (&self.held, &self.held_f, &self.held_r, &self.law);
        self.cross
            .pairs
            .par_iter()
            .zip(self.cross_buf.par_iter_mut())
            .with_min_len(256)
            .filter_map(|(&(i, w), out)| {
                let (w, mut f) = (w as usize, held_f[w as usize]);
                let h = &held[w];
                let (si, sj) = (side(p, i as usize), side(p, h.j as usize));
                let (bf, brk) = h.step(w, &mut f, &si, &sj, law, held_r, thickness, dt);
                *out = (bf, f);
                brk
            })
            .collect()
    }

    /// After the sweep (which left each bond's new forces in `held_f`,
    /// where they stay until read): the bonds that broke (`broken`, in
    /// any order) are removed and recorded in [`BondList::broken`] with
    /// `step` and `time`, in list order.
    pub(super) fn finish_step(&mut self, broken: Vec<Break>, step: usize, time: f64) {
        self.dirty = true;
        if broken.is_empty() {
            return;
        }
        self.sync();
        let l = &mut self.list;
        let mut broken: Vec<(usize, bool, Break)> = broken
            .into_iter()
            .map(|b| {
                let (k, flip) = self.held_key[b.w as usize];
                (k as usize, flip, b)
            })
            .collect();
        broken.sort_unstable_by_key(|b| b.0);
        let mut keep = vec![true; l.len()];
        for &(k, flip, b) in &broken {
            keep[k] = false;
            l.released += b.energy;
            l.broken.push(BrokenBond {
                step,
                time,
                a: l.a[k],
                b: l.b[k],
                pos: b.pos,
                normal: if flip { -b.normal } else { b.normal },
                radius: l.radius[k],
                mode: b.mode,
                energy: b.energy,
            });
        }
        l.retain(&keep);
        self.stale = true;
    }

    /// Apply the rule: bond every pair `(i, j)` of `pairs` (slots) that it
    /// accepts. The bonds are sorted by their disc ids.
    pub fn create(&mut self, p: &Particles, pairs: impl Iterator<Item = (usize, usize)>) {
        self.sync();
        let Some(rule) = &self.rule else { return };
        let inside = |x: Vec2| {
            rule.region
                .is_none_or(|(lo, hi)| x.x >= lo.x && x.x <= hi.x && x.y >= lo.y && x.y <= hi.y)
        };
        let material_ok =
            |s: usize| rule.materials.is_empty() || rule.materials.contains(&p.material[s]);
        let mut made: Vec<(u32, u32)> = pairs
            .filter(|&(i, j)| {
                let (ri, rj) = (p.radius[i], p.radius[j]);
                let gap = (p.pos[j] - p.pos[i]).norm() - ri - rj;
                gap < rule.gap * ri.min(rj)
                    && inside(p.pos[i])
                    && inside(p.pos[j])
                    && material_ok(i)
                    && material_ok(j)
            })
            .map(|(i, j)| {
                let (a, b) = (p.id[i], p.id[j]);
                (a.min(b), a.max(b))
            })
            .collect();
        made.sort_unstable();
        made.dedup();
        let l = &mut self.list;
        l.created = true;
        l.fresh = true;
        l.made = made.len();
        for &(a, b) in &made {
            let (sa, sb) = (p.slot[a as usize] as usize, p.slot[b as usize] as usize);
            let (tensile, shear) = strengths(&self.law, a, b);
            l.a.push(a);
            l.b.push(b);
            l.radius
                .push(self.law.radius_factor * p.radius[sa].min(p.radius[sb]));
            l.tensile.push(tensile);
            l.shear.push(shear);
            l.fn_.push(0.0);
            l.fs.push(0.0);
            l.moment.push(0.0);
        }
        self.stale = true;
    }

    /// Energy stored in the intact bonds.
    pub fn energy(&self, thickness: f64) -> f64 {
        let l = &self.list;
        (0..l.len())
            .map(|k| {
                let (a, i) = section(l.radius[k], thickness);
                bond_energy(&self.law, self.forces(k), a, i)
            })
            .sum()
    }

    /// Bonds broken so far in tension and in shear.
    pub fn broken_counts(&self) -> (usize, usize) {
        let t = self
            .list
            .broken
            .iter()
            .filter(|b| b.mode == BreakMode::Tension)
            .count();
        (t, self.list.broken.len() - t)
    }

    /// The critical time step of the bonded discs alone (known before the
    /// bonds are made): over every disc i, `2√(m_i/k)` with the largest
    /// translational stiffness a bond can give it, `k = max(k̄_n, k̄_s) A_i`
    /// plus `kn_contact` (the contact law in parallel), and `2√(I_i/k_θ)`
    /// with its rotational stiffness `k_θ = k̄_n I_b + k̄_s A_i r_i²`, where
    /// `A_i = 2λ̄ r_i t`, `I_b = (2/3)(λ̄ r_i)³ t` is the largest bond it
    /// can have (`R̄ ≤ λ̄ r_i`); infinity without a bond rule.
    pub fn critical_dt(&self, p: &Particles, thickness: f64, kn_contact: f64) -> f64 {
        if self.rule.is_none() {
            return f64::INFINITY;
        }
        let law = &self.law;
        (0..p.len())
            .map(|s| {
                let r = p.radius[s];
                let (a, ib) = section(law.radius_factor * r, thickness);
                let kt = law.kn.max(law.ks) * a + kn_contact;
                let kr = law.kn * ib + law.ks * a * r * r;
                let mut dt = f64::INFINITY;
                if p.mass[s] > 0.0 && kt > 0.0 {
                    dt = dt.min(2.0 * (p.mass[s] / kt).sqrt());
                }
                if p.inertia[s] > 0.0 && kr > 0.0 {
                    dt = dt.min(2.0 * (p.inertia[s] / kr).sqrt());
                }
                dt
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Bytes held (capacity).
    pub fn heap_bytes(&self) -> usize {
        let l = &self.list;
        (l.a.capacity() + l.b.capacity()) * 4
            + (l.radius.capacity()
                + l.tensile.capacity()
                + l.shear.capacity()
                + l.fn_.capacity()
                + l.fs.capacity()
                + l.moment.capacity())
                * 8
            + l.broken.capacity() * std::mem::size_of::<BrokenBond>()
            + self.held.capacity() * std::mem::size_of::<Held>()
            + self.held_f.capacity() * std::mem::size_of::<HeldForces>()
            + self.held_r.capacity() * 8
            + (self.held_key.capacity() + self.at.capacity()) * 8
            + self.row.capacity() * 4
            + self.cross.heap_bytes()
            + self.cross_buf.capacity() * std::mem::size_of::<(BondForce, HeldForces)>()
    }
}

/// One bond `h` between discs `si` and `sj`, in that orientation (normal
/// n from i to j, `M` the moment on i): update its forces `(F_n, F_s, M)`
/// by the increments of the step (module docs). Returns what it does to
/// the two discs, n and the lever arm `l_i`.
#[inline(always)]
fn bond_step(
    si: &Side,
    sj: &Side,
    h: &Held,
    dt: f64,
    (fn_, fs, m): &mut (f64, f64, f64),
) -> (BondForce, Vec2, f64) {
    let (n, d) = super::contact::normal_between(si.pos, sj.pos);
    let t = n.perp();
    let (la, lb) = (d * h.ci, d * h.cj);
    let dv = si.vel - sj.vel;
    let (wi, wj) = (si.omega, sj.omega);
    let vn = dv.dot(n);
    let vt = dv.dot(t) + wi * la + wj * lb;
    *fn_ += h.kn_a * vn * dt;
    *fs -= h.ks_a * vt * dt;
    *m -= h.kn_i * (wi - wj) * dt;
    let bf = BondForce {
        f: n * -*fn_ + t * *fs,
        ma: la * *fs + *m,
        mb: lb * *fs - *m,
    };
    (bf, n, la)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn section_of_a_unit_strip() {
        let (a, i) = section(0.5, 2.0);
        assert_eq!(a, 2.0);
        // ∫ y² dA over |y| ≤ R̄, thickness t: (2/3) R̄³ t
        assert!((i - 2.0 / 3.0 * 0.125 * 2.0).abs() < 1e-15);
    }

    #[test]
    fn scatter_is_seeded_by_the_pair_and_has_the_asked_spread() {
        let law = BondLaw {
            tensile: 10.0,
            shear: ShearStrength::Fixed(20.0),
            scatter: 0.1,
            seed: 3,
            ..Default::default()
        };
        assert_eq!(strengths(&law, 4, 9), strengths(&law, 4, 9));
        assert_ne!(strengths(&law, 4, 9), strengths(&law, 4, 10));
        let n = 20_000u32;
        let s: Vec<f64> = (0..n).map(|k| strengths(&law, k, k + 1).0).collect();
        let mean = s.iter().sum::<f64>() / n as f64;
        let sd = (s.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        assert!((mean - 10.0).abs() < 0.02, "{mean}");
        assert!((sd - 1.0).abs() < 0.03, "{sd}");
        assert!(s.iter().all(|&x| (7.0..=13.0).contains(&x)));
    }
}
