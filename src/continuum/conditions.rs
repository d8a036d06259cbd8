//! Boundary conditions on the edges of a rectangular body: prescribed
//! displacements (fixed, values, linear fields, motions, the Timoshenko
//! field) and loads (uniform or parabolic-shear tractions).

use super::drive::{DriveLaw, DrivePhase, ServoSpec};
use super::table::Table;
use super::timoshenko::Timoshenko;
use crate::geom::Vec2;
use serde::Deserialize;

/// An edge of the rectangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Edge {
    /// `x = x₀` (reference configuration).
    Left,
    /// `x = x₀ + width`.
    Right,
    /// `y = y₀ + height`.
    Top,
    /// `y = y₀`.
    Bottom,
}

impl Edge {
    /// The four edges, counter-clockwise from the bottom.
    pub const ALL: [Edge; 4] = [Edge::Bottom, Edge::Right, Edge::Top, Edge::Left];

    /// The edge's name in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Edge::Left => "left",
            Edge::Right => "right",
            Edge::Top => "top",
            Edge::Bottom => "bottom",
        }
    }
}

/// The edge a condition acts on, by name: `left`, `right`, `top`, `bottom`
/// on a rectangle ([`Edge`]), or a named edge of a polygon body
/// ([`crate::geom::polygon::NamedEdge`]).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Deserialize)]
#[serde(transparent)]
pub struct EdgeName(pub String);

impl EdgeName {
    /// The rectangle's edge of this name, if it is one of the four.
    pub fn side(&self) -> Option<Edge> {
        Edge::ALL.into_iter().find(|e| e.name() == self.0)
    }
    /// The name.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl From<Edge> for EdgeName {
    fn from(e: Edge) -> Self {
        EdgeName(e.name().to_string())
    }
}

impl From<&str> for EdgeName {
    fn from(e: &str) -> Self {
        EdgeName(e.to_string())
    }
}

impl std::fmt::Display for EdgeName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// One boundary condition on one edge: exactly one of `fixed`, `ux`/`uy`,
/// `timoshenko` (prescribed displacement, penalty), `traction`,
/// `parabolic_shear` (loads).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeCondition {
    /// The edge the condition acts on (Γu or Γt): a rectangle's side or a
    /// polygon body's named edge.
    pub edge: EdgeName,
    /// Optional name, used by `initial.static_under`.
    pub name: Option<String>,
    /// Both components zero.
    #[serde(default)]
    pub fixed: bool,
    /// Prescribed x displacement (the other component stays free if absent).
    pub ux: Option<Prescribed>,
    /// Prescribed y displacement.
    pub uy: Option<Prescribed>,
    /// Both components from the exact Timoshenko cantilever field.
    pub timoshenko: Option<TimoshenkoSpec>,
    /// Uniform traction `[tx, ty]` (force per unit area of the edge face).
    pub traction: Option<[f64; 2]>,
    /// Normal pressure `p`: traction `−p n` (n the outward normal), positive
    /// pushing into the body.
    pub pressure: Option<f64>,
    /// The exact Kirsch traction `σ·n` of an infinite plate with a circular
    /// hole (centre at the origin) under uniaxial tension along x.
    pub kirsch: Option<KirschSpec>,
    /// Both components from the exact displacement of Griffith's inclined
    /// crack in an infinite plate ([`super::griffith`]).
    pub griffith: Option<GriffithSpec>,
    /// Both components from the near-tip field (`K_I`, `K_II`, T-stress)
    /// of a straight crack along the negative x axis with its tip at the
    /// origin ([`super::crack_tip::k_t_displacement`]).
    pub williams: Option<WilliamsSpec>,
    /// Parabolic shear traction with resultant `P` (force per unit thickness)
    /// along the edge, `τ = 3P/(2D)·(1 − 4s²/D²)`, s from the edge centre.
    pub parabolic_shear: Option<f64>,
    /// A load's multiplier in time (`traction` or `parabolic_shear` times
    /// `table(t)`, [`Table`]); `None`: constant.
    pub table: Option<Table>,
}

/// `[[body.load]]`: a point load at a material point (reference
/// coordinates), optionally times a table in time.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLoad {
    /// Optional name (messages; `initial.static_under` does not take
    /// point loads).
    pub name: Option<String>,
    /// The material point `[x, y]` (reference configuration, inside the
    /// body).
    pub point: [f64; 2],
    /// The force `[fx, fy]` (N: the resultant on the body's thickness, as
    /// the disc–body contact forces).
    pub force: [f64; 2],
    /// Multiplier in time; `None`: constant.
    pub table: Option<Table>,
}

/// `kirsch = { S = σ, a = radius }`: the exact field of an infinite plate
/// with a traction-free circular hole of radius `a` centred at the origin
/// under uniaxial tension `σ` along x at infinity (Kirsch 1898).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KirschSpec {
    /// Remote tension σ along x.
    #[serde(rename = "S")]
    pub s: f64,
    /// Hole radius.
    pub a: f64,
}

/// `griffith = { S = σ, a = half-length, beta = β }`: the exact field of
/// a straight crack of length `2a` centred at the origin, at `β` degrees
/// to the x axis, in an infinite plate under remote tension `σ` along y.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GriffithSpec {
    /// Remote tension σ along y.
    #[serde(rename = "S")]
    pub s: f64,
    /// Half-length of the crack.
    pub a: f64,
    /// Angle of the crack to the x axis, degrees.
    pub beta: f64,
}

impl GriffithSpec {
    /// The field in a material of modulus `e`, Poisson's ratio `nu`.
    pub fn field(&self, el: &super::Elastic) -> super::griffith::Griffith {
        let (mu, kappa) = super::griffith::mu_kappa(el.e, el.nu, el.plane == super::Plane::Strain);
        super::griffith::Griffith {
            s: self.s,
            a: self.a,
            beta: self.beta.to_radians(),
            mu,
            kappa,
        }
    }
}

/// `williams = { KI = K_I, KII = K_II, T = T }`: the two-term near-tip
/// field of a straight crack along the negative x axis with its tip at
/// the origin (Williams' `√r` terms and the uniform T-stress along the
/// crack).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WilliamsSpec {
    /// Mode I stress intensity factor (Pa·√m).
    #[serde(rename = "KI")]
    pub k1: f64,
    /// Mode II stress intensity factor (Pa·√m).
    #[serde(rename = "KII")]
    pub k2: f64,
    /// The T-stress, `σ_xx` along the crack (Pa).
    #[serde(rename = "T")]
    pub t: f64,
}

/// A prescribed displacement component: a number, `{ linear = [a, b, c] }`
/// for `a + b x + c y`, or a drive that changes in time
/// ([`super::drive`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(
    untagged,
    expecting = "a number, { linear = [a, b, c] } (a + b x + c y), { linear = [a, b, c], table = [[t, s], …] }, { velocity = v, until_step = N }, { table = [[t, u], …] }, { velocity_table = [[t, v], …] }, { servo = { force, gain, max_velocity, … } } or { phases = [ … ] } (no other keys)"
)]
pub enum Prescribed {
    /// A constant ū.
    Value(f64),
    /// `ū = a + b x + c y` at the reference position.
    Linear(#[serde(deserialize_with = "crate::strict::table")] LinearField),
    /// An edge moving at constant velocity for `until_step` steps: `ū` is
    /// [`MotionField::displacement`], zero at t = 0.
    Motion(#[serde(deserialize_with = "crate::strict::table")] MotionField),
    /// `ū = (a + b x + c y) · table(t)`: a linear field scaled in time
    /// (e.g. a base rotating about its toe).
    ScaledLinear(#[serde(deserialize_with = "crate::strict::table")] ScaledLinear),
    /// `ū = table(t)` along the edge.
    Table(#[serde(deserialize_with = "crate::strict::table")] TableField),
    /// `ū = ∫₀ᵗ table`: a prescribed velocity, integrated exactly.
    VelocityTable(#[serde(deserialize_with = "crate::strict::table")] VelocityTableField),
    /// A servo holding a target force on the body.
    Servo(#[serde(deserialize_with = "crate::strict::table")] ServoField),
    /// One motion after another (constant velocity, servo, rest).
    Phases(#[serde(deserialize_with = "crate::strict::table")] PhasesField),
}

/// `{ linear = [a, b, c], table = [[t, s], …] }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScaledLinear {
    /// Coefficients `[a, b, c]` of `a + b x + c y`.
    pub linear: [f64; 3],
    /// The multiplier `s(t)`.
    pub table: Table,
}

/// `{ table = [[t, u], …] }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TableField {
    /// The displacement in time.
    pub table: Table,
}

/// `{ velocity_table = [[t, v], …] }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityTableField {
    /// The velocity in time.
    pub velocity_table: Table,
}

/// `{ servo = { … } }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoField {
    /// The servo.
    pub servo: ServoSpec,
}

/// `{ phases = [ { until_step, velocity | servo }, … ] }`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhasesField {
    /// The phases, in order.
    pub phases: Vec<DrivePhase>,
}

/// `{ velocity = v, until_step = N }`: the edge moves with velocity `v`
/// (displacement `v t`) during the first `N` steps (all steps if absent),
/// then stays where it is — e.g. an edge following a rigid plate.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionField {
    /// Velocity `v` of the prescribed component (length per time; sign
    /// along +x or +y).
    pub velocity: f64,
    /// Number of steps after which the edge stops; `None`: never.
    pub until_step: Option<usize>,
}

impl MotionField {
    /// Displacement after `steps` steps of `dt`.
    pub fn displacement(&self, steps: usize, dt: f64) -> f64 {
        let n = self.until_step.map_or(steps, |u| steps.min(u));
        self.velocity * n as f64 * dt
    }
}

/// `{ linear = [a, b, c] }`: the field `a + b x + c y`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearField {
    /// Coefficients `[a, b, c]` of `a + b x + c y`.
    pub linear: [f64; 3],
}

impl Prescribed {
    /// The value at the reference point `(x, y)`: the constant, the linear
    /// field, or 0 for a motion (the motion's `v t` is added per step by
    /// the body, see [`MotionField::displacement`]).
    pub fn at(&self, x: f64, y: f64) -> f64 {
        match *self {
            Prescribed::Value(v) => v,
            Prescribed::Linear(LinearField { linear: [a, b, c] }) => a + b * x + c * y,
            _ => 0.0,
        }
    }
    /// All numbers finite (tables are checked by [`Table::problem`]).
    pub fn finite(&self) -> bool {
        match self {
            Prescribed::Value(v) => v.is_finite(),
            Prescribed::Linear(l) => l.linear.iter().all(|v| v.is_finite()),
            Prescribed::Motion(m) => m.velocity.is_finite(),
            Prescribed::ScaledLinear(l) => l.linear.iter().all(|v| v.is_finite()),
            _ => true,
        }
    }
    /// The drive of a component that changes in time, if it is one.
    pub fn drive_law(&self) -> Option<DriveLaw> {
        match self {
            Prescribed::Value(_) | Prescribed::Linear(_) => None,
            Prescribed::Motion(m) => Some(DriveLaw::Velocity(*m)),
            Prescribed::ScaledLinear(l) => Some(DriveLaw::Table(l.table.clone())),
            Prescribed::Table(t) => Some(DriveLaw::Table(t.table.clone())),
            Prescribed::VelocityTable(t) => Some(DriveLaw::VelocityTable(t.velocity_table.clone())),
            Prescribed::Servo(s) => Some(DriveLaw::Servo(s.servo.clone())),
            Prescribed::Phases(p) => Some(DriveLaw::Phases(p.phases.clone())),
        }
    }
    /// The scale `s(x, y)` of the drive at a point: `a + b x + c y` for a
    /// scaled linear field, 1 otherwise (a rigid translation).
    pub fn drive_scale(&self, x: f64, y: f64) -> f64 {
        match self {
            Prescribed::ScaledLinear(ScaledLinear {
                linear: [a, b, c], ..
            }) => a + b * x + c * y,
            _ => 1.0,
        }
    }
}

/// The exact field of a cantilever clamped at the left edge of the body's
/// rectangle with end shear `P` at the right edge (Timoshenko & Goodier).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimoshenkoSpec {
    /// End shear `P` (force per unit thickness; positive along +y).
    #[serde(rename = "P")]
    pub p: f64,
}

impl EdgeCondition {
    /// A condition on `edge` with nothing prescribed or loaded yet (fill in
    /// one of the fields with struct-update syntax).
    pub fn on(edge: impl Into<EdgeName>) -> Self {
        EdgeCondition {
            edge: edge.into(),
            name: None,
            fixed: false,
            ux: None,
            uy: None,
            timoshenko: None,
            griffith: None,
            williams: None,
            traction: None,
            pressure: None,
            kirsch: None,
            parabolic_shear: None,
            table: None,
        }
    }

    /// Both displacement components zero on `edge`.
    pub fn fixed(edge: impl Into<EdgeName>) -> Self {
        EdgeCondition {
            fixed: true,
            ..EdgeCondition::on(edge)
        }
    }

    /// A uniform traction `[tx, ty]` on `edge`.
    pub fn traction(edge: impl Into<EdgeName>, t: [f64; 2]) -> Self {
        EdgeCondition {
            traction: Some(t),
            ..EdgeCondition::on(edge)
        }
    }

    /// Is this a load (traction) rather than a prescribed displacement?
    pub fn is_load(&self) -> bool {
        self.traction.is_some()
            || self.parabolic_shear.is_some()
            || self.pressure.is_some()
            || self.kirsch.is_some()
    }

    /// The rectangle's side this condition is on, or an error naming the
    /// unknown edge (rectangular bodies only know the four sides).
    pub fn side(&self) -> Result<Edge, String> {
        self.edge.side().ok_or_else(|| {
            format!(
                "edge `{}` is not an edge of a rectangle (left, right, top, bottom)",
                self.edge
            )
        })
    }
}

/// End points of an edge of the rectangle `origin`, `size` (counter-clockwise
/// order is not implied: left/right go bottom → top, bottom/top left → right).
pub fn edge_ends(origin: Vec2, size: Vec2, e: Edge) -> (Vec2, Vec2) {
    let (x0, y0, x1, y1) = (origin.x, origin.y, origin.x + size.x, origin.y + size.y);
    match e {
        Edge::Left => (Vec2::new(x0, y0), Vec2::new(x0, y1)),
        Edge::Right => (Vec2::new(x1, y0), Vec2::new(x1, y1)),
        Edge::Bottom => (Vec2::new(x0, y0), Vec2::new(x1, y0)),
        Edge::Top => (Vec2::new(x0, y1), Vec2::new(x1, y1)),
    }
}

/// Which components a displacement bc constrains.
pub fn constrained(bc: &EdgeCondition) -> (bool, bool) {
    if bc.fixed || bc.timoshenko.is_some() || bc.griffith.is_some() || bc.williams.is_some() {
        (true, true)
    } else {
        (bc.ux.is_some(), bc.uy.is_some())
    }
}

/// The prescribed displacement `ū` of a bc at `x` (`el`: the body's
/// elasticity, for the exact fields that depend on it).
pub fn prescribed(
    bc: &EdgeCondition,
    x: Vec2,
    tim: Option<&Timoshenko>,
    el: &super::Elastic,
) -> [f64; 2] {
    if let (Some(_), Some(t)) = (bc.timoshenko, tim) {
        return t.displacement(x);
    }
    if let Some(g) = bc.griffith {
        return g.field(el).displacement(x);
    }
    if let Some(w) = bc.williams {
        let (mu, kappa) = super::crack_tip::mu_kappa(el.e, el.nu, el.plane == super::Plane::Strain);
        return super::crack_tip::k_t_displacement([w.k1, w.k2], w.t, x, mu, kappa);
    }
    [
        bc.ux.as_ref().map_or(0.0, |v| v.at(x.x, x.y)),
        bc.uy.as_ref().map_or(0.0, |v| v.at(x.x, x.y)),
    ]
}

/// The traction `t̄` of a load bc at the point `x` of its edge `a → b`
/// (Eq. 27, boundary term): uniform, or the parabolic shear
/// `τ = 3P/(2D)·(1 − 4s²/D²)` with `s` measured from the edge centre.
pub fn traction_at(bc: &EdgeCondition, a: Vec2, b: Vec2, x: Vec2) -> [f64; 2] {
    let n = match bc.edge.side() {
        Some(Edge::Left) => Vec2::new(-1.0, 0.0),
        Some(Edge::Right) => Vec2::new(1.0, 0.0),
        Some(Edge::Bottom) => Vec2::new(0.0, -1.0),
        Some(Edge::Top) => Vec2::new(0.0, 1.0),
        None => {
            let d = b - a;
            Vec2::new(d.y, -d.x) * (1.0 / d.norm())
        }
    };
    traction_normal(bc, a, b, x, n)
}

/// [`traction_at`] with the edge's outward unit normal `n` given (polygon
/// bodies): also the pressure `−p n` and the Kirsch traction `σ·n`.
pub fn traction_normal(bc: &EdgeCondition, a: Vec2, b: Vec2, x: Vec2, n: Vec2) -> [f64; 2] {
    if let Some(tv) = bc.traction {
        return tv;
    }
    if let Some(p) = bc.pressure {
        return [-p * n.x, -p * n.y];
    }
    if let Some(k) = bc.kirsch {
        let s = super::kirsch::Kirsch::new(k.s, k.a).stress(x);
        return [s[0] * n.x + s[2] * n.y, s[2] * n.x + s[1] * n.y];
    }
    let len = (b - a).norm();
    let mid = (a + b) * 0.5;
    let p = bc.parabolic_shear.unwrap_or(0.0);
    let s = (x - mid).norm();
    let tau = 1.5 * p / len * (1.0 - 4.0 * s * s / (len * len));
    match bc.edge.side() {
        Some(Edge::Left | Edge::Right) => [0.0, tau],
        _ => [tau, 0.0],
    }
}

/// The exact Timoshenko cantilever field of the body if one of its bcs uses
/// it (clamped at the left edge, centre line at mid-height).
pub fn timoshenko_of(spec: &super::BodyParams) -> Option<Timoshenko> {
    let (origin, size) = (spec.rectangle.origin, spec.rectangle.size);
    let el = spec.elastic;
    spec.bc.iter().find_map(|bc| {
        bc.timoshenko.map(|ts| {
            Timoshenko::new(
                ts.p,
                size[0],
                size[1],
                el.e,
                el.nu,
                el.plane == super::Plane::Strain,
                origin[0],
                origin[1] + 0.5 * size[1],
            )
        })
    })
}
