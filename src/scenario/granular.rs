//! `[granular]` and `[[wall]]`: discs, their damping and rigid walls.
//!
//! ```toml
//! [granular]
//! material = "disc"            # default material of the discs
//! thickness = 1.0              # discs are cylinders: m = ρπr²t, I = m r²/2
//! discs = [[50.0, 250.0, 50.0], [150.0, 250.0, 50.0]]   # inline [x, y, r]
//! # discs = { csv = "discs.csv" }                         # x,y,r[,material]
//! # discs = { generate = "hex", box = [[0, 0], [100, 50]], radius = 1.0 }
//! # discs = { generate = "random", box = [[0, 0], [100, 200]], radius = [0.8, 1.2],
//! #           count = 5000, seed = 7, method = "deposit" }
//! damping = { kind = "contact-viscous", beta = 0.1 }
//!
//! [[wall]]
//! name = "right"
//! from = [300.0, 0.0]
//! to = [300.0, 300.0]
//! velocity = [-0.12, 0.0]
//! until_step = 40
//!
//! [[wall]]
//! name = "top"
//! from = [0.0, 300.0]
//! to = [300.0, 300.0]
//! servo = { stress = 1.0e5, max_velocity = 0.1 }   # or strain_rate = 0.5
//! ```
//!
//! Servo and strain-rate walls move along their inward normal (towards
//! the discs' centroid, or the opposite wall); an end of a wall lying on
//! one of them is joined to it ([`joined_ends`]).

use super::{Invalid, Problems, Scenario};
use crate::dem::Granular;
use crate::dem::walls::{Servo, Wall, WallMotion, WallPhase};
use crate::geom::Vec2;
use serde::Deserialize;
use std::path::PathBuf;

fn one() -> f64 {
    1.0
}

/// The granular assembly.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularSpec {
    /// Default contact material of the discs (a `[[material]]` name).
    pub material: String,
    /// Disc thickness t (default 1): `m = ρπr²t`, `I = m r²/2`.
    #[serde(default = "one")]
    pub thickness: f64,
    /// Where the discs come from.
    pub discs: DiscsSpec,
    /// Damping, named explicitly (default: none).
    #[serde(default)]
    pub damping: DampingSpec,
    /// Verlet skin of the contact search (default 0.1 × largest radius).
    pub skin: Option<f64>,
    /// Initial velocity of every disc (default at rest).
    pub velocity: Option<[f64; 2]>,
    /// Accept discs that overlap each other, a wall or a body at the start
    /// by more than 1e-3 of the smaller radius (a pre-stressed packing,
    /// e.g. a settled bed read from CSV). Default false: such a start state
    /// is an error. Packings generated with `method = "deposit"` or
    /// `"grow"` are settled by efgdem: their overlaps with each other and
    /// the walls are accepted, not with a body (the preparation does not
    /// see the bodies).
    #[serde(default)]
    pub allow_overlap: bool,
    /// Keep only the discs lying wholly inside this circle, once the
    /// packing is made (generated, prepared or read): a round specimen
    /// cut from a packing grown in a box. Default: every disc.
    pub keep: Option<KeepCircle>,
}

/// `keep = { centre = [x, y], radius = R }`: a circle of the discs to keep.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeepCircle {
    /// Its centre (`center` is the same field).
    #[serde(alias = "center")]
    pub centre: [f64; 2],
    /// Its radius.
    pub radius: f64,
}

impl KeepCircle {
    /// Whether the disc of centre `pos` and radius `r` lies inside.
    pub fn holds(&self, pos: Vec2, r: f64) -> bool {
        (pos - Vec2::from(self.centre)).norm() + r <= self.radius
    }
}

/// The discs: inline `[x, y, r]` rows or a table (CSV file or generator).
#[derive(Debug, Clone, Deserialize)]
#[serde(
    untagged,
    expecting = "a list of [x, y, r] rows, or a table { csv = \"file\" } or { generate = \"square\" | \"hex\" | \"random\", box = [[x0, y0], [x1, y1]], radius = r | [rmin, rmax], count, seed, method = \"loose\" | \"deposit\" | \"grow\", jitter, settle_steps } (no other keys)"
)]
pub enum DiscsSpec {
    /// `[x, y, r]` per disc, disc k (1-based) on row k.
    Inline(Vec<[f64; 3]>),
    /// A CSV file or a generator.
    Table(#[serde(deserialize_with = "crate::strict::table")] DiscsTable),
}

/// `discs = { ... }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiscsTable {
    /// CSV file with columns `x,y,r[,material]` (header line optional).
    pub csv: Option<PathBuf>,
    /// Generated packing.
    pub generate: Option<Generator>,
    /// Box `[[x0, y0], [x1, y1]]` (or `{ origin, size }`,
    /// [`super::rect`]) to fill.
    #[serde(rename = "box", default, deserialize_with = "super::rect::corners")]
    pub region: Option<[[f64; 2]; 2]>,
    /// One radius, or `[rmin, rmax]` for radii uniform in the range.
    pub radius: Option<Radius>,
    /// Number of discs (default: as many as the box holds).
    pub count: Option<usize>,
    /// Seed of the random generator (default 1).
    #[serde(default = "seed1")]
    pub seed: u64,
    /// `random` only: `loose` (jittered sites, no overlap), `deposit`
    /// (loose, then settled under gravity inside the box) or `grow` (random
    /// centres, radii grown from small to their final size without gravity:
    /// fills the box, packing fractions up to 0.85).
    #[serde(default)]
    pub method: Packing,
    /// Random displacement of lattice sites as a fraction of the free gap
    /// (0–1; default 0 for lattices, 1 for random).
    pub jitter: Option<f64>,
    /// `deposit` / `grow`: DEM steps of the settling or growth (default 20 000).
    pub settle_steps: Option<usize>,
    /// `deposit` / `grow`: the `[[material]]` whose contact law the
    /// preparation uses (default: the discs' own, `[granular] material`);
    /// e.g. a frictionless one for a dense packing that does not depend on
    /// the friction of the run.
    pub settle_material: Option<String>,
    /// `deposit` / `grow`: a file (relative to the scenario) that keeps the
    /// prepared packing: written by the first run, read by the next ones
    /// when what determines the packing is unchanged, refused otherwise
    /// ([`super::prepare`]).
    pub cache: Option<PathBuf>,
}

fn seed1() -> u64 {
    1
}

/// `generate = "…"`: the kind of generated packing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Generator {
    /// Square lattice, sites `2 r_max` apart.
    Square,
    /// Hexagonal (triangular) lattice, sites `2 r_max` apart.
    Hex,
    /// Random: hexagonal sites `2.2 r_max` apart (gap 0.1), jittered by
    /// their full free play; [`Packing`] says what happens next.
    Random,
}

/// `method = "…"` of a `random` packing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Packing {
    /// The jittered sites as they are (no overlap).
    #[default]
    Loose,
    /// Settled under gravity inside the box.
    Deposit,
    /// Random centres, radii grown to their final size (no gravity).
    Grow,
}

/// `radius = r` or `radius = [rmin, rmax]`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(untagged, expecting = "a radius r > 0 or a range [rmin, rmax]")]
pub enum Radius {
    /// Every disc of radius r.
    One(f64),
    /// Radii uniform in `[rmin, rmax]`.
    Range([f64; 2]),
}

impl Radius {
    /// `(rmin, rmax)`; `(r, r)` for one radius.
    pub fn range(self) -> (f64, f64) {
        match self {
            Radius::One(r) => (r, r),
            Radius::Range([a, b]) => (a, b),
        }
    }
}

/// Damping of the assembly. ERRATA E6: the paper's "damping coefficient"
/// is ambiguous, so the kind is always named.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Default)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum DampingSpec {
    /// No damping (default).
    #[default]
    None,
    /// Stiffness-proportional dashpots: `c_n = β k_n` (Cundall & Strack),
    /// optional shear `c_s = β_s k_s`.
    ContactViscous {
        /// β of the normal dashpot, `c_n = β k_n` (time units).
        beta: f64,
        /// β_s of the shear dashpot, `c_s = β_s k_s` (default 0).
        #[serde(default)]
        beta_shear: f64,
        /// Clamp the total normal force at zero (no dashpot pull).
        #[serde(default)]
        no_tension: bool,
    },
    /// Dashpots at a fraction ζ of critical, `c = ζ 2√(k m_eff)`.
    CriticalRatio {
        /// ζ_n of the normal dashpot, 0 ≤ ζ < 1.
        zeta: f64,
        /// ζ_s of the shear dashpot (default 0).
        #[serde(default)]
        zeta_shear: f64,
        /// Clamp the total normal force at zero (no dashpot pull).
        #[serde(default)]
        no_tension: bool,
    },
    /// Cundall's non-viscous local damping `F ← F − α|F| sign(v)`.
    Local {
        /// α, 0 ≤ α < 1.
        alpha: f64,
    },
    /// Global mass damping of Eqs. (33)–(34), coefficients c and c*.
    Global {
        /// `c` of Eq. (33) (force per velocity).
        c: f64,
        /// `c*` of Eq. (34) (moment per angular velocity; default 0).
        #[serde(default)]
        c_rot: f64,
    },
}

/// Human text: the kind as the scenario names it and its parameters.
impl std::fmt::Display for DampingSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let tension = |no_tension: bool| {
            if no_tension {
                "; total normal force clamped at zero (no_tension)"
            } else {
                ""
            }
        };
        match *self {
            DampingSpec::None => write!(f, "none"),
            DampingSpec::ContactViscous {
                beta,
                beta_shear,
                no_tension,
            } => write!(
                f,
                "contact-viscous: normal dashpot c_n = β k_n with β = {beta}, shear β_s = {beta_shear}{}",
                tension(no_tension)
            ),
            DampingSpec::CriticalRatio {
                zeta,
                zeta_shear,
                no_tension,
            } => write!(
                f,
                "critical-ratio: normal dashpot at ζ = {zeta} of critical, shear ζ_s = {zeta_shear}{}",
                tension(no_tension)
            ),
            DampingSpec::Local { alpha } => {
                write!(f, "local (Cundall's non-viscous) with α = {alpha}")
            }
            DampingSpec::Global { c, c_rot } => {
                write!(f, "global mass damping c = {c}, c* = {c_rot}")
            }
        }
    }
}

/// `slip_normal` of a `[[material]]`: which normal force caps the shear
/// force (and the rolling moment).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SlipNormalSpec {
    /// `μ max(0, k_n δ + c_n δ̇) + c` (Eqs. 35, 37; Yade, LAMMPS).
    #[default]
    Total,
    /// `μ k_n δ + c` (PFC's linear model).
    Elastic,
}

/// The default `slip_normal`.
pub fn total() -> String {
    "total".into()
}

/// A material's `slip_normal` (`None` if it is neither `"total"` nor
/// `"elastic"`; the validation reports that).
pub fn slip_normal(m: &super::Material) -> Option<SlipNormalSpec> {
    match m.slip_normal.as_str() {
        "total" => Some(SlipNormalSpec::Total),
        "elastic" => Some(SlipNormalSpec::Elastic),
        _ => None,
    }
}

/// Checks of a material's issue-13 fields, `slip_normal` and rolling
/// resistance (`at` gives the field's path).
pub fn validate_contact_fields(m: &super::Material, at: &dyn Fn(&str) -> String, p: &mut Problems) {
    p.check(
        slip_normal(m).is_some(),
        at("slip_normal"),
        format!(
            "must be \"total\" (the Coulomb cap uses spring + dashpot, the default) or \"elastic\" (spring only, PFC) (got \"{}\")",
            m.slip_normal
        ),
    );
    p.non_negative(m.rolling_friction, at("rolling_friction"));
    p.positive(m.rolling_stiffness, at("rolling_stiffness"));
    p.check(
        m.rolling_damping.is_finite() && (0.0..=1.0).contains(&m.rolling_damping),
        at("rolling_damping"),
        format!(
            "must be in [0, 1] (a fraction of the critical rolling dashpot; got {})",
            m.rolling_damping
        ),
    );
}

/// A rigid wall segment.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSpec {
    /// Unique name (probes and outputs refer to it).
    pub name: String,
    /// First end point at t = 0.
    pub from: [f64; 2],
    /// Second end point at t = 0.
    pub to: [f64; 2],
    /// Contact material of the wall (default: the disc's).
    pub material: Option<String>,
    /// Constant velocity (default: at rest) ...
    pub velocity: Option<[f64; 2]>,
    /// ... during the first `until_step` steps (default: all).
    pub until_step: Option<usize>,
    /// Or a piecewise-linear velocity history `[[t, vx, vy], ...]`.
    pub history: Option<Vec<[f64; 3]>>,
    /// Or hold a normal stress by moving along the normal (servo control).
    pub servo: Option<ServoSpec>,
    /// Or move so that the distance to the opposite (parallel) wall
    /// changes at this true strain rate (1/s, compression positive).
    pub strain_rate: Option<f64>,
    /// Or one motion after another, each until a step number.
    pub phases: Option<Vec<PhaseSpec>>,
}

/// One entry of a wall's `phases = [{ until_step = N, servo = {…} }, …]`:
/// a motion (`velocity`, `history`, `servo`, `strain_rate`, or none: at
/// rest) during the steps up to `until_step` ([`WallPhase`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseSpec {
    /// The phase lasts while fewer steps than this have been done (from
    /// the start of the run); required on every phase but the last.
    pub until_step: Option<usize>,
    /// Constant velocity during the phase.
    pub velocity: Option<[f64; 2]>,
    /// Or a piecewise-linear velocity history `[[t, vx, vy], ...]` (t the
    /// run's time).
    pub history: Option<Vec<[f64; 3]>>,
    /// Or a servo holding a normal stress.
    pub servo: Option<ServoSpec>,
    /// Or a true strain rate of the distance to the opposite wall.
    pub strain_rate: Option<f64>,
}

/// The motion fields of a wall or of one of its phases.
#[derive(Clone, Copy)]
struct MotionFields<'a> {
    velocity: Option<[f64; 2]>,
    /// `until_step` of a constant velocity (a wall's own field; a phase's
    /// bounds the phase instead).
    until_step: Option<usize>,
    history: Option<&'a Vec<[f64; 3]>>,
    servo: Option<&'a ServoSpec>,
    strain_rate: Option<f64>,
}

impl<'a> MotionFields<'a> {
    fn of_wall(w: &'a WallSpec) -> Self {
        MotionFields {
            velocity: w.velocity,
            until_step: w.until_step,
            history: w.history.as_ref(),
            servo: w.servo.as_ref(),
            strain_rate: w.strain_rate,
        }
    }

    fn of_phase(p: &'a PhaseSpec) -> Self {
        MotionFields {
            velocity: p.velocity,
            until_step: None,
            history: p.history.as_ref(),
            servo: p.servo.as_ref(),
            strain_rate: p.strain_rate,
        }
    }

    /// Servo or strain rate: moves by a law of the state.
    fn follows_state(&self) -> bool {
        self.servo.is_some() || self.strain_rate.is_some()
    }
}

impl WallSpec {
    /// Does the wall move by a servo or a strain rate, in some phase?
    pub fn follows_state(&self) -> bool {
        MotionFields::of_wall(self).follows_state()
            || self
                .phases
                .iter()
                .flatten()
                .any(|p| MotionFields::of_phase(p).follows_state())
    }

    /// The steps `[from, until)` (`None`: to the end) during which the
    /// wall follows a strain rate, with the rate and the field path of
    /// that rate below `wall.i.`.
    pub fn strain_rate_spans(&self) -> Vec<(usize, Option<usize>, f64, String)> {
        let mut out = vec![];
        if let Some(r) = self.strain_rate {
            out.push((0, None, r, "strain_rate".to_string()));
        }
        let mut from = 0;
        for (k, p) in self.phases.iter().flatten().enumerate() {
            if let Some(r) = p.strain_rate {
                out.push((from, p.until_step, r, format!("phases.{k}.strain_rate")));
            }
            from = p.until_step.unwrap_or(usize::MAX);
        }
        out
    }
}

/// `servo = { stress = σ, max_velocity = v, gain = G, relaxation = α }`
/// of a `[[wall]]` ([`Servo`]).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoSpec {
    /// Target normal stress σ (Pa, compression positive).
    pub stress: f64,
    /// Largest speed of the wall (m/s).
    pub max_velocity: f64,
    /// Gain G (m/s per N); default automatic `α/(Σk_n Δt)`.
    pub gain: Option<f64>,
    /// Relaxation factor α of the automatic gain (default 0.5).
    #[serde(default = "half")]
    pub relaxation: f64,
    /// Integral action β (default 0: proportional only).
    #[serde(default)]
    pub integral: f64,
}

fn half() -> f64 {
    0.5
}

/// Two walls are parallel when the sine of their angle is below this.
const PARALLEL: f64 = 1e-9;

fn ends(w: &WallSpec) -> (Vec2, Vec2, Vec2, f64) {
    let (a, b) = (Vec2::from(w.from), Vec2::from(w.to));
    let l = (b - a).norm();
    (a, b, (b - a) * (1.0 / l), l)
}

/// The wall opposite wall `i`: the nearest wall parallel to it, not on its
/// line (by the distance between the lines).
pub fn opposite_wall(sc: &Scenario, i: usize) -> Option<usize> {
    let (a, _, u, l) = ends(&sc.wall[i]);
    let mut best: Option<(usize, f64)> = None;
    for (j, w) in sc.wall.iter().enumerate() {
        if j == i || w.from == w.to {
            continue;
        }
        let (aj, _, uj, _) = ends(w);
        let d = (aj - a).dot(u.perp()).abs();
        if u.cross(uj).abs() <= PARALLEL && d > 1e-9 * l && best.is_none_or(|(_, b)| d < b) {
            best = Some((j, d));
        }
    }
    best.map(|(j, _)| j)
}

/// The walls that the ends `from` and `to` of wall `i` are joined to: a
/// servo or strain-rate wall, not parallel to it, on which the end lies
/// (within 10⁻⁹ of the shorter of the two lengths: a tolerance of the
/// longer would join a short wall's end to a very long wall metres away).
pub fn joined_ends(sc: &Scenario, i: usize) -> [Option<u32>; 2] {
    let (a, b, u, l) = ends(&sc.wall[i]);
    let on = |p: Vec2| {
        sc.wall.iter().enumerate().position(|(j, w)| {
            if j == i || w.from == w.to || !w.follows_state() {
                return false;
            }
            let (aj, bj, uj, lj) = ends(w);
            u.cross(uj).abs() > PARALLEL
                && (crate::geom::closest_on_segment(p, aj, bj).1 - p).norm() <= 1e-9 * l.min(lj)
        })
    };
    [on(a).map(|j| j as u32), on(b).map(|j| j as u32)]
}

/// The centroid of `n` discs whose centres sum to `sum` (added in slot
/// order from zero); the origin for none.
pub fn centroid(sum: Vec2, n: usize) -> Vec2 {
    if n == 0 {
        Vec2::ZERO
    } else {
        sum * (1.0 / n as f64)
    }
}

/// The walls of the scenario, with their motions, inward normals (towards
/// the discs' `centroid` ([`centroid`]), or the opposite wall of a
/// strain-rate wall) and joined ends.
pub fn walls(sc: &Scenario, centroid: Vec2) -> Result<Vec<Wall>, Invalid> {
    let mut out = Vec::new();
    for (wi, w) in sc.wall.iter().enumerate() {
        let at = |f: &str| format!("wall.{wi}.{f}");
        let (motion, facing) = match &w.phases {
            None => motion(
                sc,
                wi,
                MotionFields::of_wall(w),
                (0, None),
                &at("strain_rate"),
            )?,
            Some(phases) => {
                let mut out = Vec::with_capacity(phases.len());
                let mut facing = None;
                let mut from = 0;
                for (k, p) in phases.iter().enumerate() {
                    let (m, f) = motion(
                        sc,
                        wi,
                        MotionFields::of_phase(p),
                        (from, p.until_step),
                        &at(&format!("phases.{k}.strain_rate")),
                    )?;
                    facing = facing.or(f);
                    out.push(WallPhase {
                        until_step: p.until_step,
                        motion: m,
                    });
                    from = p.until_step.unwrap_or(usize::MAX);
                }
                (WallMotion::Phases(out), facing)
            }
        };
        let inward_to = facing.unwrap_or(centroid);
        let mut wall = Wall::new(&w.name, Vec2::from(w.from), Vec2::from(w.to), motion);
        if (inward_to - wall.a).dot(wall.inward) < 0.0 {
            wall.inward = -wall.inward;
        }
        wall.joins = joined_ends(sc, wi);
        if let Some(m) = &w.material {
            wall.material = Some(
                sc.material
                    .iter()
                    .position(|x| &x.name == m)
                    .ok_or_else(|| Invalid {
                        path: at("material"),
                        message: format!("no [[material]] named `{m}`"),
                    })? as u16,
            );
        }
        out.push(wall);
    }
    Ok(out)
}

/// The motion of wall `wi` given by `f`, during the steps `span` (for a
/// phase; `(0, None)` otherwise), and the point its inward normal must
/// face when the motion decides it (a strain-rate wall: its opposite
/// wall). `rate_at`: the path of the strain rate, for errors. Two facing
/// walls that follow a strain rate over the same steps take half each.
fn motion(
    sc: &Scenario,
    wi: usize,
    f: MotionFields,
    span: (usize, Option<usize>),
    rate_at: &str,
) -> Result<(WallMotion, Option<Vec2>), Invalid> {
    if let Some(s) = f.servo {
        return Ok((
            WallMotion::Servo(Servo {
                stress: s.stress,
                gain: s.gain,
                relaxation: s.relaxation,
                max_velocity: s.max_velocity,
                integral: s.integral,
            }),
            None,
        ));
    }
    if let Some(rate) = f.strain_rate {
        let opposite = opposite_wall(sc, wi).ok_or_else(|| Invalid {
            path: rate_at.to_string(),
            message: "needs a parallel wall opposite this one".into(),
        })?;
        let both = opposite_wall(sc, opposite) == Some(wi)
            && sc.wall[opposite]
                .strain_rate_spans()
                .iter()
                .any(|&(a, b, _, _)| (a, b) == span);
        return Ok((
            WallMotion::StrainRate {
                rate,
                opposite,
                share: if both { 0.5 } else { 1.0 },
            },
            Some(Vec2::from(sc.wall[opposite].from)),
        ));
    }
    let m = match (f.velocity, f.history) {
        (Some(v), _) => WallMotion::Constant {
            velocity: Vec2::from(v),
            until_step: f.until_step,
        },
        (None, Some(h)) => {
            WallMotion::Piecewise(h.iter().map(|r| (r[0], Vec2::new(r[1], r[2]))).collect())
        }
        (None, None) => WallMotion::Fixed,
    };
    Ok((m, None))
}

/// Fraction of the smallest radius a servo or strain-rate wall may move in
/// one step (faster, it could pass through a disc).
pub const WALL_STEP_LIMIT: f64 = 0.1;

/// Servo walls at `max_velocity` and strain-rate walls at their starting
/// speed must move less than [`WALL_STEP_LIMIT`] × the smallest radius per
/// step.
pub fn check_wall_speeds(sc: &Scenario, g: &Granular) -> Result<(), Invalid> {
    let rmin = g
        .particles
        .radius
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    for (wi, w) in g.walls.iter().enumerate() {
        let motions: Vec<(&WallMotion, String)> = match &w.motion {
            WallMotion::Phases(phases) => phases
                .iter()
                .enumerate()
                .map(|(k, p)| (&p.motion, format!("phases.{k}.")))
                .collect(),
            m => vec![(m, String::new())],
        };
        for (m, phase) in motions {
            let (speed, field) = match m {
                WallMotion::Servo(s) => (s.max_velocity, "servo.max_velocity"),
                WallMotion::StrainRate {
                    rate,
                    opposite,
                    share,
                } => {
                    // at the distance of the start (a phase: of t = 0)
                    let d = (g.walls[*opposite].a - w.a).dot(w.inward);
                    ((share * rate * d).abs(), "strain_rate")
                }
                _ => continue,
            };
            let step = speed * g.dt;
            if step > WALL_STEP_LIMIT * rmin {
                return Err(Invalid {
                    path: format!("wall.{wi}.{phase}{field}"),
                    message: format!(
                        "wall `{}` would move {step:e} per step (speed {speed:e} × dt {:e}), more than {WALL_STEP_LIMIT} × the smallest radius {rmin:e}: lower it (or dt)",
                        sc.wall[wi].name, g.dt
                    ),
                });
            }
        }
    }
    Ok(())
}

// Probe quantities a granular run knows, and what each needs.

/// Normal force between two discs (`contact = [a, b]`): `k_n δ` or with
/// the dashpot.
pub const CONTACT_QUANTITIES: &[&str] = &["normal_elastic", "normal_total"];
/// Force of the discs on a wall and its first end point (`wall = "name"`).
pub const WALL_QUANTITIES: &[&str] = &[
    "wall_fx",
    "wall_fy",
    "wall_x",
    "wall_y",
    "wall_stress",
    "wall_length",
];
/// State of one disc (`disc = k`, 1-based).
pub const DISC_QUANTITIES: &[&str] = &["x", "y", "vx", "vy", "theta", "omega"];
/// Assembly-wide energies and the number of touching contacts (no target).
pub const GLOBAL_QUANTITIES: &[&str] = &[
    "kinetic",
    "rotational",
    "spring",
    "gravity_energy",
    "total_energy",
    "contacts",
];

/// Number of discs the scenario describes, if known without generating.
pub fn inline_count(g: &GranularSpec) -> Option<usize> {
    match &g.discs {
        DiscsSpec::Inline(v) => Some(v.len()),
        _ => None,
    }
}

/// Semantic checks of `[granular]` and every `[[wall]]`.
pub fn validate(sc: &Scenario, p: &mut Problems) {
    let Some(g) = &sc.granular else {
        p.check(
            sc.wall.is_empty(),
            "wall",
            "walls need a [granular] section (discs)",
        );
        return;
    };
    match sc.material(&g.material) {
        None => p.push(
            "granular.material",
            format!("no [[material]] named `{}`", g.material),
        ),
        Some(m) => {
            let i = sc
                .material
                .iter()
                .position(|x| x.name == m.name)
                .unwrap_or(0);
            p.positive(m.density, format!("material.{i}.density"));
            p.positive(m.kn, format!("material.{i}.kn"));
        }
    }
    p.positive(g.thickness, "granular.thickness");
    if let Some(k) = &g.keep {
        p.check(
            k.centre.iter().all(|v| v.is_finite()),
            "granular.keep.centre",
            "must be two finite numbers",
        );
        p.positive(k.radius, "granular.keep.radius");
    }
    if let Some(s) = g.skin {
        p.positive(s, "granular.skin");
    }
    if let Some(v) = g.velocity {
        p.check(
            v.iter().all(|x| x.is_finite()),
            "granular.velocity",
            "must be two finite numbers",
        );
    }
    match &g.discs {
        DiscsSpec::Inline(rows) => {
            p.check(
                !rows.is_empty(),
                "granular.discs",
                "the list of discs is empty",
            );
            for (k, r) in rows.iter().enumerate() {
                p.check(
                    r[0].is_finite() && r[1].is_finite() && r[2].is_finite() && r[2] > 0.0,
                    format!("granular.discs.{k}"),
                    format!(
                        "disc {}: [x, y, r] must be finite with r > 0 (got {r:?})",
                        k + 1
                    ),
                );
            }
        }
        DiscsSpec::Table(t) => {
            validate_table(t, p);
            if let Some(m) = &t.settle_material {
                match sc.material.iter().position(|x| &x.name == m) {
                    None => p.push(
                        "granular.discs.settle_material",
                        format!("no [[material]] named `{m}`"),
                    ),
                    // the preparation's contacts use it: a stiffness is needed
                    Some(i) => p.check(
                        sc.material[i].kn.is_finite() && sc.material[i].kn > 0.0,
                        format!("material.{i}.kn"),
                        format!(
                            "material `{m}` is the packing's settle_material: its contacts need kn > 0 (got {})",
                            sc.material[i].kn
                        ),
                    ),
                }
            }
        }
    }
    match g.damping {
        DampingSpec::None => {}
        DampingSpec::ContactViscous {
            beta, beta_shear, ..
        } => {
            p.non_negative(beta, "granular.damping.beta");
            p.non_negative(beta_shear, "granular.damping.beta_shear");
        }
        DampingSpec::CriticalRatio {
            zeta, zeta_shear, ..
        } => {
            for (v, f) in [(zeta, "zeta"), (zeta_shear, "zeta_shear")] {
                p.check(
                    v.is_finite() && (0.0..1.0).contains(&v),
                    format!("granular.damping.{f}"),
                    format!("must be in [0, 1) (got {v})"),
                );
            }
        }
        DampingSpec::Local { alpha } => p.check(
            alpha.is_finite() && (0.0..1.0).contains(&alpha),
            "granular.damping.alpha",
            format!("must be in [0, 1) (got {alpha})"),
        ),
        DampingSpec::Global { c, c_rot } => {
            p.non_negative(c, "granular.damping.c");
            p.non_negative(c_rot, "granular.damping.c_rot");
        }
    }
    let mut names = std::collections::HashSet::new();
    for (i, w) in sc.wall.iter().enumerate() {
        let at = |f: &str| format!("wall.{i}.{f}");
        p.check(
            names.insert(w.name.as_str()),
            at("name"),
            format!("wall `{}` is defined twice", w.name),
        );
        let finite = w.from.iter().chain(&w.to).all(|x| x.is_finite());
        for (end, xy) in [("from", w.from), ("to", w.to)] {
            p.check(
                xy.iter().all(|x| x.is_finite()),
                at(end),
                format!("must be two finite numbers (got {xy:?})"),
            );
        }
        p.check(
            !finite || w.from != w.to,
            at("to"),
            "the wall has zero length (from == to)",
        );
        if let Some(m) = &w.material {
            p.check(
                sc.material(m).is_some(),
                at("material"),
                format!("no [[material]] named `{m}`"),
            );
        }
        p.check(
            w.until_step.is_none() || w.velocity.is_some(),
            at("until_step"),
            "`until_step` needs a `velocity`",
        );
        validate_motion(sc, i, "", MotionFields::of_wall(w), p);
        if let Some(phases) = &w.phases {
            validate_phases(sc, i, w, phases, p);
        }
    }
    validate_probes(sc, p);
}

/// The motion fields `f` of wall `i` (`phase`: `""`, or `"phases.k."`
/// for a phase): one motion only, sensible numbers, a strain-rate wall
/// with a wall opposite it (and the same rate over the same steps if that
/// one follows a strain rate too).
fn validate_motion(sc: &Scenario, i: usize, phase: &str, f: MotionFields, p: &mut Problems) {
    let at = |x: &str| format!("wall.{i}.{phase}{x}");
    let w = &sc.wall[i];
    if let Some(v) = f.velocity {
        p.check(
            v.iter().all(|x| x.is_finite()),
            at("velocity"),
            "must be two finite numbers",
        );
    }
    let kinds = [
        f.velocity.is_some(),
        f.history.is_some(),
        f.servo.is_some(),
        f.strain_rate.is_some(),
    ];
    if kinds.iter().filter(|&&k| k).count() > 1 && f.follows_state() {
        p.push(
            at(if f.servo.is_some() {
                "servo"
            } else {
                "strain_rate"
            }),
            "give one motion: `velocity`, `history`, `servo` or `strain_rate`",
        );
    }
    if let Some(s) = f.servo {
        p.non_negative(s.stress, at("servo.stress"));
        p.positive(s.max_velocity, at("servo.max_velocity"));
        if let Some(g) = s.gain {
            p.positive(g, at("servo.gain"));
        }
        p.check(
            s.relaxation.is_finite() && s.relaxation > 0.0 && s.relaxation <= 1.0,
            at("servo.relaxation"),
            format!("must be in (0, 1] (got {})", s.relaxation),
        );
        p.check(
            s.integral.is_finite() && (0.0..1.0).contains(&s.integral),
            at("servo.integral"),
            format!(
                "must be in [0, 1) (the fraction of the proportional velocity added to the integral per step; 1 and above do not settle; got {})",
                s.integral
            ),
        );
    }
    if let Some(h) = f.history {
        p.check(
            f.velocity.is_none(),
            at("history"),
            "give either `velocity` or `history`, not both",
        );
        p.check(
            !h.is_empty(),
            at("history"),
            "needs at least one [t, vx, vy] point",
        );
        p.check(
            h.iter().all(|r| r.iter().all(|x| x.is_finite()))
                && h.windows(2).all(|w| w[1][0] >= w[0][0]),
            at("history"),
            "points [t, vx, vy] must be finite with t non-decreasing",
        );
    }
    if let Some(rate) = f.strain_rate {
        p.check(
            rate.is_finite(),
            at("strain_rate"),
            format!("must be a finite number (got {rate})"),
        );
        if w.from == w.to {
            return;
        }
        match opposite_wall(sc, i) {
            None => p.push(
                at("strain_rate"),
                "needs a wall parallel to this one, opposite it: the rate is of the distance between the two",
            ),
            Some(j) if opposite_wall(sc, j) == Some(i) => {
                // this motion's steps
                let mine = w
                    .strain_rate_spans()
                    .into_iter()
                    .find(|s| s.3 == format!("{phase}strain_rate"));
                let o = &sc.wall[j];
                for (a, b, r, _) in o.strain_rate_spans() {
                    let Some((a0, b0, _, _)) = mine else { break };
                    let overlap = a < b0.unwrap_or(usize::MAX) && a0 < b.unwrap_or(usize::MAX);
                    if !overlap {
                        continue;
                    }
                    let steps = |a: usize, b: Option<usize>| match b {
                        Some(b) => format!("steps {a}..{b}"),
                        None => format!("steps {a}.."),
                    };
                    p.check(
                        r == rate && (a, b) == (a0, b0),
                        at("strain_rate"),
                        format!(
                            "the opposite wall `{}` has strain_rate = {r} over {}, this wall {rate} over {}: two facing strain-rate walls share one rate (give both the same, over the same steps)",
                            o.name,
                            steps(a, b),
                            steps(a0, b0)
                        ),
                    );
                }
            }
            Some(_) => {}
        }
    }
}

/// `phases` of wall `i`: instead of the wall's own motion fields, each
/// phase a valid motion, `until_step` on every phase but the last and
/// increasing.
fn validate_phases(sc: &Scenario, i: usize, w: &WallSpec, phases: &[PhaseSpec], p: &mut Problems) {
    let at = |x: &str| format!("wall.{i}.{x}");
    let own = MotionFields::of_wall(w);
    p.check(
        own.velocity.is_none()
            && own.until_step.is_none()
            && own.history.is_none()
            && !own.follows_state(),
        at("phases"),
        "give the motion either in `phases` or as the wall's own `velocity`, `until_step`, `history`, `servo` or `strain_rate`, not both",
    );
    p.check(
        !phases.is_empty(),
        at("phases"),
        "needs at least one phase, e.g. [{ until_step = 1000, servo = { stress = 1.0e5, max_velocity = 0.1 } }, { strain_rate = 0.5 }]",
    );
    let mut from = 0;
    for (k, ph) in phases.iter().enumerate() {
        let pre = format!("phases.{k}.");
        validate_motion(sc, i, &pre, MotionFields::of_phase(ph), p);
        match ph.until_step {
            None => p.check(
                k + 1 == phases.len(),
                at(&format!("{pre}until_step")),
                "every phase but the last needs `until_step` (the step at which the next phase begins)",
            ),
            Some(n) => {
                p.check(
                    n > from,
                    at(&format!("{pre}until_step")),
                    format!(
                        "must be greater than {from} (the step at which this phase begins; got {n})"
                    ),
                );
                from = n;
            }
        }
    }
}

fn validate_table(t: &DiscsTable, p: &mut Problems) {
    let at = |f: &str| format!("granular.discs.{f}");
    match (&t.csv, t.generate) {
        (Some(_), Some(_)) => p.push(at("generate"), "give either `csv` or `generate`, not both"),
        (None, None) => p.push(
            "granular.discs",
            "needs `csv = \"file\"` or `generate = \"square\" | \"hex\" | \"random\"`",
        ),
        (Some(_), None) => {
            for (set, f) in [
                (t.region.is_some(), "box"),
                (t.radius.is_some(), "radius"),
                (t.count.is_some(), "count"),
                (t.cache.is_some(), "cache"),
            ] {
                p.check(!set, at(f), "only for `generate`");
            }
        }
        (None, Some(gen_kind)) => {
            match t.region {
                None => p.push(
                    at("generate"),
                    "a generated packing needs `box = [[x0, y0], [x1, y1]]`",
                ),
                Some([a, b]) => p.check(
                    a.iter().chain(&b).all(|x| x.is_finite()) && b[0] > a[0] && b[1] > a[1],
                    at("box"),
                    "must be [[x0, y0], [x1, y1]] with x1 > x0 and y1 > y0",
                ),
            }
            match t.radius {
                None => p.push(at("generate"), "a generated packing needs `radius`"),
                Some(r) => {
                    let (a, b) = r.range();
                    p.check(
                        a.is_finite() && b.is_finite() && a > 0.0 && b >= a,
                        at("radius"),
                        "must be r > 0 or [rmin, rmax] with 0 < rmin ≤ rmax",
                    );
                }
            }
            if let Some(c) = t.count {
                p.check(c >= 1, at("count"), "must be ≥ 1");
            }
            if let Some(j) = t.jitter {
                p.check(
                    j.is_finite() && (0.0..=1.0).contains(&j),
                    at("jitter"),
                    "must be in [0, 1]",
                );
            }
            p.check(
                t.method == Packing::Loose || gen_kind == Generator::Random,
                at("method"),
                "`method` applies to `generate = \"random\"` only",
            );
            p.check(
                t.settle_material.is_none() || t.method != Packing::Loose,
                at("settle_material"),
                "applies to `method = \"deposit\"` or `\"grow\"` only (the material of the preparation)",
            );
            p.check(
                t.cache.is_none() || t.method != Packing::Loose,
                at("cache"),
                "applies to `method = \"deposit\"` or `\"grow\"` only (it keeps the prepared packing)",
            );
        }
    }
}

/// Disc quantities that only a coupled run records: displacement since t = 0.
pub const COUPLED_DISC_QUANTITIES: &[&str] = &["ux", "uy"];

/// Probes of a granular run; in a coupled run (bodies present) the body
/// probes — those with a `point` or a body-wide quantity — are checked by
/// the body validation instead.
fn validate_probes(sc: &Scenario, p: &mut Problems) {
    let n = sc.granular.as_ref().and_then(inline_count);
    let coupled = !sc.body.is_empty();
    for (i, pr) in sc.probe.iter().enumerate() {
        let at = |f: &str| format!("probe.{i}.{f}");
        let q = pr.quantity.as_str();
        if coupled && crate::scenario::body::is_body_probe(pr, false) {
            continue;
        }
        let disc_ok = |k: usize| k >= 1 && n.is_none_or(|n| k <= n);
        if CONTACT_QUANTITIES.contains(&q) {
            match pr.contact {
                None => p.push(
                    at("quantity"),
                    format!("`{q}` needs `contact = [a, b]` (1-based disc numbers)"),
                ),
                Some([a, b]) => p.check(
                    disc_ok(a) && disc_ok(b) && a != b,
                    at("contact"),
                    format!(
                        "needs two different disc numbers in 1..={}",
                        n.map_or("N".into(), |n| n.to_string())
                    ),
                ),
            }
        } else if WALL_QUANTITIES.contains(&q) {
            match &pr.wall {
                None => p.push(at("quantity"), format!("`{q}` needs `wall = \"name\"`")),
                Some(w) => p.check(
                    sc.wall.iter().any(|x| &x.name == w),
                    at("wall"),
                    format!("no [[wall]] named `{w}`"),
                ),
            }
        } else if DISC_QUANTITIES.contains(&q) || (coupled && COUPLED_DISC_QUANTITIES.contains(&q))
        {
            match pr.disc {
                None => p.push(at("quantity"), format!("`{q}` needs `disc = k` (1-based)")),
                Some(k) => p.check(disc_ok(k), at("disc"), "disc number out of range (1-based)"),
            }
        } else if !GLOBAL_QUANTITIES.contains(&q) {
            p.push(
                at("quantity"),
                format!(
                    "unknown quantity `{q}` for a granular run (allowed: {}, {}, {}, {})",
                    CONTACT_QUANTITIES.join(", "),
                    WALL_QUANTITIES.join(", "),
                    DISC_QUANTITIES.join(", "),
                    GLOBAL_QUANTITIES.join(", ")
                ),
            );
        }
    }
}
