//! `[[body]]`: a continuum body (EFG or bilinear FE) on a rectangle.
//!
//! ```toml
//! [[body]]
//! name = "beam"
//! rectangle = { origin = [0.0, -6.0], size = [48.0, 12.0] }
//! nodes = [33, 9]            # nx × ny, row-major, ≥ 2 each
//! cells = [32, 8]            # background cells (default nodes − 1)
//! gauss = 4                  # n × n Gauss points per cell
//! d_max = 2.0                # support size factor (> 1)
//! elastic = { E = 3.0e7, nu = 0.3, density = 1.0, thickness = 1.0, plane = "stress" }
//! damping = 0.0              # c of Eq. (24): C = (c/ρ) M
//! newmark = { gamma = 0.5, beta = 0.25 }
//! initial = { static_under = ["tip"] }
//! [[body.bc]]
//! edge = "left"
//! timoshenko = { P = -1000.0 }
//! [[body.bc]]
//! name = "tip"
//! edge = "right"
//! parabolic_shear = -1000.0
//! ```
//! Every field is documented in `docs/scenario.md`.

use super::{Analysis, Problems, Scenario};
pub use crate::continuum::{
    BodyParams, Edge, EdgeCondition as BcSpec, EdgeName, Elastic, LinearField, MassKind,
    MotionField, Plane, PointLoad, Prescribed, Rectangle, TimoshenkoSpec,
};
use crate::continuum::{DriveLaw, Measure, ServoSpec, Table, Target};
use crate::continuum::{PolygonShape, Refine};
use crate::geom::Vec2;
use crate::geom::polygon::{Domain, circle};
use serde::Deserialize;

/// One continuum body.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name used by probes and outputs.
    pub name: String,
    /// Discretisation: `"efg"` (default) or `"fem-q4"` (bilinear quads on
    /// the node grid, §4.2.1).
    #[serde(default)]
    pub method: Method,
    /// Mass matrix of a `fem-q4` body: `"consistent"` (default) or
    /// `"lumped"` (row sum). EFG bodies always use the consistent Gram matrix.
    #[serde(default)]
    pub mass: MassKind,
    /// The body's rectangle, `{ origin, size }` or its corners
    /// ([`super::rect`]) (or, for a polygon body, filled in with the
    /// outline's bounding box when the file is parsed).
    #[serde(default, deserialize_with = "super::rect::origin_size")]
    pub rectangle: Rectangle,
    /// Node grid `[nx, ny]` (row-major, x fastest); rectangles only.
    #[serde(default)]
    pub nodes: [usize; 2],
    /// Polygon body (EFG only): the outline's vertices, counter-clockwise.
    pub outline: Option<Vec<[f64; 2]>>,
    /// Holes of a polygon body: vertex lists (counter-clockwise) or circles.
    #[serde(default)]
    pub holes: Vec<HoleSpec>,
    /// Node spacing `h` of a polygon body.
    pub spacing: Option<f64>,
    /// Named edges of a polygon body: `name = { loop = k, segments = [i, j] }`.
    #[serde(default)]
    pub edges: std::collections::BTreeMap<String, EdgeSpec>,
    /// Finer node spacings near named edges of a polygon body.
    #[serde(default)]
    pub refine: Vec<RefineSpec>,
    /// Background integration cells `[cx, cy]`; default `nodes − 1`.
    pub cells: Option<[usize; 2]>,
    /// Gauss points per cell direction (n × n per cell, n per boundary segment).
    #[serde(default = "default_gauss")]
    pub gauss: usize,
    /// Support size factor: `d_mI = d_max · c_I` (Eqs. 7–8).
    #[serde(default = "default_d_max")]
    pub d_max: f64,
    /// `elastic = { E, nu, density, thickness, plane }`.
    pub elastic: Elastic,
    /// Damping coefficient `c` of Eq. (24) (force·time/length⁴): `C = ∫Φᵀ c Φ`.
    #[serde(default)]
    pub damping: f64,
    /// Penalty factor α of Eq. (21) (ERRATA E4); default `1e5 · E`.
    pub penalty: Option<f64>,
    /// Newmark parameters (ERRATA E9); default average acceleration.
    #[serde(default)]
    pub newmark: NewmarkSpec,
    /// Boundary conditions on the edges.
    #[serde(default)]
    pub bc: Vec<BcSpec>,
    /// Point loads at material points (`[[body.load]]`).
    #[serde(default)]
    pub load: Vec<PointLoad>,
    /// Initial state of a dynamic run (default: at rest, undeformed).
    pub initial: Option<InitialSpec>,
    /// Edges that discs can touch (coupled runs), e.g. `["top", "right"]`;
    /// default: all four (one closed chain). Adjacent edges are joined
    /// around their common corner; `[]` gives a body no contact boundary.
    /// Polygon bodies: names of their `edges` (default: every loop).
    #[serde(default = "all_edges")]
    pub contact_edges: Vec<EdgeName>,
    /// Contact material (a `[[material]]` name) of the body's boundary;
    /// default: the disc's own material, as for walls.
    pub contact_material: Option<String>,
    /// Boundary points per node spacing along contact edges (≥ 1): the
    /// contact boundary is the polyline through these points at their true
    /// displaced positions (ERRATA E7). Default 4.
    #[serde(default = "default_contact_refine")]
    pub contact_refine: usize,
    /// Apply `[simulation] gravity` to the body's own mass (default true).
    /// The paper's Example 1 has gravity on the disc only.
    #[serde(default = "yes")]
    pub self_weight: bool,
    /// Cracks (EFG bodies): `[[body.crack]]`.
    #[serde(default)]
    pub crack: Vec<super::crack::CrackSpec>,
    /// Crack growth: `[body.fracture]`.
    pub fracture: Option<super::crack::FractureSpec>,
    /// Coupled runs: what to do with discs the body overlaps when the run
    /// starts (after the preparation of a generated packing): refuse them
    /// (default) or remove them.
    #[serde(default)]
    pub overlapping_discs: OverlappingDiscs,
}

/// `overlapping_discs`: discs a body overlaps at the start of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OverlappingDiscs {
    /// An error (exit 2), located at the body.
    #[default]
    Refuse,
    /// The discs are removed before the run (counted in the run's report
    /// and `summary.json`); the others are numbered from 1 in their order.
    /// A body in the region a `deposit` or `grow` fills is then placed
    /// after the preparation.
    Remove,
}

/// `refine = [{ edges = ["name", …], spacing = h_r, width = w }]`: nodes
/// at the finer spacing `h_r` along named edges of a polygon body and
/// within `w` of them, graded to the body's spacing beyond (see
/// [`crate::efg::polygon`]).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RefineSpec {
    /// Named edges of the body.
    pub edges: Vec<String>,
    /// The node spacing near it (smaller than the body's `spacing`).
    pub spacing: f64,
    /// Width of the refined band.
    pub width: f64,
}

/// A hole of a polygon body: its vertices (counter-clockwise), or
/// `{ center = [x, y], radius = r, segments = n }` (a regular n-gon inscribed
/// in the circle, first vertex at angle 0).
#[derive(Debug, Clone, Deserialize)]
#[serde(
    untagged,
    expecting = "a list of [x, y] vertices or { center = [x, y], radius = r, segments = n }"
)]
pub enum HoleSpec {
    /// Vertices.
    Points(Vec<[f64; 2]>),
    /// A circle as a regular polygon.
    Circle(#[serde(deserialize_with = "crate::strict::table")] CircleSpec),
}

/// Most vertices of a polygon body, its outline and holes together
/// (circles count their segments): 100 000. Preparing one costs
/// `O(N log N)`; past that, the boundary is finer than any node spacing
/// a body of this size can have.
pub const MAX_POLYGON_VERTICES: usize = 100_000;

/// `{ center = [x, y], radius = r, segments = n }` (`centre` is the same
/// field).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircleSpec {
    /// Centre.
    #[serde(alias = "centre")]
    pub center: [f64; 2],
    /// Radius.
    pub radius: f64,
    /// Number of segments (default 32).
    #[serde(default = "default_circle_segments")]
    pub segments: usize,
}

fn default_circle_segments() -> usize {
    32
}

/// `{ loop = k, segments = [i, j] }`: segments `i..=j` of loop `k` (0 = the
/// outline, k = hole k; segment i runs from vertex i to vertex i + 1, in
/// the order the vertices are given); `segments` absent: the whole loop.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EdgeSpec {
    /// The loop: 0 outline, k ≥ 1 hole k.
    #[serde(rename = "loop")]
    pub lp: usize,
    /// First and last segment (inclusive); may wrap around (`[5, 1]`).
    pub segments: Option<[usize; 2]>,
}

impl BodySpec {
    /// Is this a polygon body (`outline` given)?
    pub fn is_polygon(&self) -> bool {
        self.outline.is_some()
    }

    /// The validated polygon domain with its named edges (the user's
    /// `edges`, plus `outline` and `hole1`, `hole2`, … for whole loops
    /// unless the user took those names): `Err((field, message))`.
    pub fn domain(&self) -> Result<Option<Domain>, (String, String)> {
        let Some(outline) = &self.outline else {
            return Ok(None);
        };
        // the vertices first, so that an absurd count is refused before
        // anything is allocated for it
        let mut total = outline.len();
        for (k, h) in self.holes.iter().enumerate() {
            let (n, field) = match h {
                HoleSpec::Points(p) => (p.len(), format!("holes.{k}")),
                HoleSpec::Circle(c) => (c.segments, format!("holes.{k}.segments")),
            };
            total = total.saturating_add(n);
            if total > MAX_POLYGON_VERTICES {
                return Err((
                    field,
                    format!(
                        "{n} vertices/segments: a polygon body has at most {MAX_POLYGON_VERTICES} vertices in all (outline and holes)"
                    ),
                ));
            }
        }
        if outline.len() > MAX_POLYGON_VERTICES {
            return Err((
                "outline".into(),
                format!(
                    "{} vertices: a polygon body has at most {MAX_POLYGON_VERTICES} vertices in all (outline and holes)",
                    outline.len()
                ),
            ));
        }
        let outline: Vec<Vec2> = outline.iter().map(|&p| p.into()).collect();
        let mut holes = Vec::with_capacity(self.holes.len());
        for (k, h) in self.holes.iter().enumerate() {
            holes.push(match h {
                HoleSpec::Points(p) => p.iter().map(|&q| q.into()).collect(),
                HoleSpec::Circle(c) => {
                    if !(c.radius > 0.0 && c.radius.is_finite()) {
                        return Err((
                            format!("holes.{k}.radius"),
                            format!("a circle needs a finite radius > 0 (got {})", c.radius),
                        ));
                    }
                    if c.segments < 3 {
                        return Err((
                            format!("holes.{k}.segments"),
                            format!("a circle needs at least 3 segments (got {})", c.segments),
                        ));
                    }
                    circle(c.center.into(), c.radius, c.segments)
                }
            });
        }
        let sizes: Vec<usize> = std::iter::once(outline.len())
            .chain(holes.iter().map(Vec::len))
            .collect();
        let mut edges = Vec::new();
        for (name, e) in &self.edges {
            let Some(&n) = sizes.get(e.lp) else {
                return Err((
                    format!("edges.{name}.loop"),
                    format!(
                        "loop {} does not exist (0 = outline, 1..{} = holes)",
                        e.lp,
                        sizes.len() - 1
                    ),
                ));
            };
            let segs: Vec<(usize, usize)> = match e.segments {
                None => (0..n).map(|i| (e.lp, i)).collect(),
                Some([i, j]) if i < n && j < n => {
                    let len = (j + n - i) % n + 1;
                    (0..len).map(|t| (e.lp, (i + t) % n)).collect()
                }
                Some(r) => {
                    return Err((
                        format!("edges.{name}.segments"),
                        format!("loop {} has segments 0..={}, not {r:?}", e.lp, n - 1),
                    ));
                }
            };
            edges.push((name.clone(), segs));
        }
        for (k, &n) in sizes.iter().enumerate() {
            let name = if k == 0 {
                "outline".to_string()
            } else {
                format!("hole{k}")
            };
            if !self.edges.contains_key(&name) {
                edges.push((name, (0..n).map(|i| (k, i)).collect()));
            }
        }
        Domain::new(outline, holes, edges).map(Some).map_err(|e| {
            (
                if e.to_string().contains("hole") {
                    "holes"
                } else {
                    "outline"
                }
                .to_string(),
                e.to_string(),
            )
        })
    }
}

fn yes() -> bool {
    true
}

fn all_edges() -> Vec<EdgeName> {
    Edge::ALL.map(EdgeName::from).to_vec()
}

impl BodySpec {
    /// The rectangle's contact edges (names that are not one of the four
    /// sides are left out; validation reports them).
    pub fn contact_sides(&self) -> Vec<Edge> {
        self.contact_edges
            .iter()
            .filter_map(EdgeName::side)
            .collect()
    }
    /// Are the contact edges the default (every edge / every loop)?
    pub fn default_contact_edges(&self) -> bool {
        self.contact_edges == all_edges()
    }
}

fn default_contact_refine() -> usize {
    4
}

fn default_gauss() -> usize {
    4
}
fn default_d_max() -> f64 {
    2.0
}

impl BodySpec {
    /// The physics' parameters of this body.
    pub fn params(&self) -> BodyParams {
        BodyParams {
            name: self.name.clone(),
            rectangle: self.rectangle,
            polygon: self.domain().ok().flatten().map(|domain| PolygonShape {
                refine: self
                    .refine
                    .iter()
                    .map(|r| Refine {
                        segments: r
                            .edges
                            .iter()
                            .filter_map(|e| domain.edge(e))
                            .flat_map(|e| e.segments.iter().copied())
                            .collect(),
                        spacing: r.spacing,
                        width: r.width,
                    })
                    .collect(),
                domain,
                spacing: self.spacing.unwrap_or(0.0),
            }),
            nodes: self.nodes,
            cells: self.cells,
            gauss: self.gauss,
            d_max: self.d_max,
            elastic: self.elastic,
            damping: self.damping,
            penalty: self.penalty,
            newmark: [self.newmark.gamma, self.newmark.beta],
            mass: self.mass,
            bc: self.bc.clone(),
            static_under: self
                .initial
                .as_ref()
                .map_or_else(Vec::new, |i| i.static_under.clone()),
            self_weight: self.self_weight,
            loads: self.load.clone(),
            cracks: self.crack.iter().map(|c| c.shape()).collect(),
            fracture: self.fracture.as_ref().map(|f| f.params()),
        }
    }
}

/// `method = "…"`: how a body is discretised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Element-free Galerkin (§2.1–2.2), the default.
    #[default]
    Efg,
    /// 4-node bilinear finite elements on the node grid.
    FemQ4,
}

/// Newmark γ and β (ERRATA E9: the paper's β₁ = γ, β₂ = 2β).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NewmarkSpec {
    /// γ (default ½); the paper's β₁ = 1.5.
    pub gamma: f64,
    /// β (default ¼); the paper's β₂ = 1.6 is β = 0.8.
    pub beta: f64,
}

impl Default for NewmarkSpec {
    fn default() -> Self {
        NewmarkSpec {
            gamma: 0.5,
            beta: 0.25,
        }
    }
}

/// `initial = { static_under = ["tip"] }`: start a dynamic run from the
/// static equilibrium under the permanent loads plus the named loads (bc
/// names, or `"gravity"`), which are then released at t = 0.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    /// Loads (bc names or `"gravity"`) applied for the initial static
    /// state only.
    pub static_under: Vec<String>,
}

/// Quantities a `[[probe]]` can sample in a body at `point`.
pub const POINT_QUANTITIES: &[&str] = &[
    "ux", "uy", "vx", "vy", "exx", "eyy", "gxy", "sxx", "syy", "sxy",
];
/// Body-wide quantities (no `point`).
pub const BODY_QUANTITIES: &[&str] = &["kinetic_energy", "strain_energy", "total_energy"];
/// Coupled runs: the total force of the discs on a body (no `point`), e.g.
/// a footing's reaction.
pub const CONTACT_FORCE_QUANTITIES: &[&str] = &["contact_fx", "contact_fy"];
/// A body's drive (its first bc component `ux`/`uy` that changes in time):
/// position, velocity, measured force (no `point`).
pub const DRIVE_QUANTITIES: &[&str] = &[
    "drive_ux", "drive_uy", "drive_vx", "drive_vy", "drive_fx", "drive_fy",
];

/// Crack quantities of an EFG body (no `point`; `crack = n`, `tip = 1|2`):
/// stress intensity factors `K_I`, `K_II` and `K_eq` at a tip, the crack's
/// length, the energy released by growth.
pub const CRACK_QUANTITIES: &[&str] = &["k1", "k2", "k_eq", "crack_length", "fracture_energy"];

/// Is `pr` a probe of a body? In a continuum-only run every point quantity
/// is; in a coupled run a probe belongs to a body when it has a `point` or
/// a body-wide quantity (so `vx` of a disc stays a disc probe).
pub fn is_body_probe(pr: &crate::scenario::Probe, continuum_only: bool) -> bool {
    let q = pr.quantity.as_str();
    BODY_QUANTITIES.contains(&q)
        || CRACK_QUANTITIES.contains(&q)
        || DRIVE_QUANTITIES.contains(&q)
        || (!continuum_only && CONTACT_FORCE_QUANTITIES.contains(&q))
        || (POINT_QUANTITIES.contains(&q) && (continuum_only || pr.point.is_some()))
}

/// Largest magnitude of a body's coordinates (`rectangle.origin` and
/// `size`): products of several lengths (moments of inertia, the exact
/// Timoshenko field, energies) must stay finite.
pub const MAX_COORDINATE: f64 = 1e30;

/// Largest ratio of the node spacings along x and y: beyond it the
/// stiffness matrix is too ill-conditioned to be trusted (the Timoshenko
/// cantilever's energy error passes 50 % at a ratio of 10³, and K̄ can no
/// longer be factored at 10⁵).
pub const MAX_SPACING_RATIO: f64 = 1e3;

/// Largest prescribed displacement relative to the body's size, and
/// largest load relative to the stiffness (traction / E): a "strain" of a
/// million is no linear-elastic state, and the solution overflows long
/// before ±1e300 (which wrote NaN to `history.csv`).
pub const MAX_RELATIVE_MAGNITUDE: f64 = 1e6;

/// Checks of absurd magnitudes in a body: coordinates, node spacing,
/// prescribed displacements and loads (see the constants above).
fn validate_magnitudes(sc: &Scenario, i: usize, b: &BodySpec, p: &mut Problems) {
    let at = |f: &str| format!("body.{i}.{f}");
    let (o, size) = (b.rectangle.origin, b.rectangle.size);
    let finite = o.iter().chain(&size).all(|v| v.is_finite()) && size.iter().all(|&v| v > 0.0);
    if !finite {
        return; // reported by the caller
    }
    let t = b.elastic.thickness;
    p.check(
        !t.is_finite() || t <= MAX_COORDINATE,
        at("elastic.thickness"),
        format!("a length: at most {MAX_COORDINATE:e} (got {t:e})"),
    );
    let within = o.iter().chain(&size).all(|v| v.abs() <= MAX_COORDINATE);
    p.check(
        within,
        at("rectangle"),
        format!(
            "coordinates and sizes must be at most {MAX_COORDINATE:e} in magnitude (got origin {o:?}, size {size:?}): choose a length unit in which the body is of order 1"
        ),
    );
    if !within {
        return;
    }
    if b.nodes[0] >= 2 && b.nodes[1] >= 2 {
        let hx = size[0] / (b.nodes[0] - 1) as f64;
        let hy = size[1] / (b.nodes[1] - 1) as f64;
        let ratio = (hx / hy).max(hy / hx);
        p.check(
            ratio <= MAX_SPACING_RATIO,
            at("rectangle.size"),
            format!(
                "the node spacing is {hx:.3e} along x and {hy:.3e} along y (size / (nodes − 1)), {ratio:.1e} times apart; at most {MAX_SPACING_RATIO:e} is accepted (the stiffness matrix is too ill-conditioned to be trusted beyond): give the nodes in proportion to the sides"
            ),
        );
    }
    let length = size[0].max(size[1]);
    let (e, rho) = (b.elastic.e, b.elastic.density);
    let g = sc.simulation.gravity;
    let weight = rho * g[0].hypot(g[1]) * length;
    if b.self_weight && e.is_finite() && e > 0.0 && rho.is_finite() && weight.is_finite() {
        p.check(
            weight <= MAX_RELATIVE_MAGNITUDE * e,
            "simulation.gravity",
            format!(
                "the self-weight of body `{}` (ρ |g| × size = {weight:e}, as a stress) is more than {MAX_RELATIVE_MAGNITUDE:e} × E = {e:e}: no linear-elastic state, and the solution overflows",
                b.name
            ),
        );
    }
    let corners = [
        (o[0], o[1]),
        (o[0] + size[0], o[1]),
        (o[0], o[1] + size[1]),
        (o[0] + size[0], o[1] + size[1]),
    ];
    for (k, bc) in b.bc.iter().enumerate() {
        let at = |f: &str| format!("body.{i}.bc.{k}.{f}");
        for (f, v) in [("ux", &bc.ux), ("uy", &bc.uy)] {
            let Some(v) = v.as_ref().filter(|v| v.finite()) else {
                continue;
            };
            let largest = corners
                .iter()
                .map(|&(x, y)| v.at(x, y).abs())
                .fold(0.0, f64::max);
            p.check(
                largest <= MAX_RELATIVE_MAGNITUDE * length,
                at(f),
                format!(
                    "a prescribed displacement of {largest:e} is more than {MAX_RELATIVE_MAGNITUDE:e} × the body's size ({length:e}): no linear-elastic state, and the solution overflows"
                ),
            );
        }
        if !(e.is_finite() && e > 0.0) {
            continue;
        }
        let stress = |f: &str, s: f64| {
            (
                s.abs() <= MAX_RELATIVE_MAGNITUDE * e,
                at(f),
                format!(
                    "a load of {:e} (as a stress) is more than {MAX_RELATIVE_MAGNITUDE:e} × E = {e:e}: no linear-elastic state, and the solution overflows",
                    s.abs()
                ),
            )
        };
        let mut loads = Vec::new();
        let times = bc
            .table
            .as_ref()
            .filter(|tb| tb.problem().is_none())
            .map_or(1.0, |tb| tb.max_abs());
        if let Some(t) = bc.traction.filter(|t| t.iter().all(|v| v.is_finite())) {
            loads.push(stress("traction", t[0].abs().max(t[1].abs()) * times));
        }
        if let Some(s) = bc.parabolic_shear.filter(|s| s.is_finite()) {
            loads.push(stress("parabolic_shear", s / length));
        }
        if let Some(t) = bc.timoshenko.filter(|t| t.p.is_finite()) {
            loads.push(stress("timoshenko.P", t.p / length));
        }
        for (ok, path, message) in loads {
            p.check(ok, path, message);
        }
    }
    if e.is_finite() && e > 0.0 && t.is_finite() && t > 0.0 {
        for (k, pl) in b.load.iter().enumerate() {
            let times = pl
                .table
                .as_ref()
                .filter(|tb| tb.problem().is_none())
                .map_or(1.0, |tb| tb.max_abs());
            // as a stress over the body's size and thickness
            let s = pl.force[0].abs().max(pl.force[1].abs()) * times / (length * t);
            p.check(
                !s.is_finite() || s <= MAX_RELATIVE_MAGNITUDE * e,
                format!("body.{i}.load.{k}.force"),
                format!(
                    "a load of {s:e} (as a stress over the body's size and thickness) is more than {MAX_RELATIVE_MAGNITUDE:e} × E = {e:e}: no linear-elastic state, and the solution overflows"
                ),
            );
        }
    }
}

/// Checks of a polygon body (`outline`): EFG only, `spacing` instead of
/// `nodes`, contact on all loops.
fn validate_polygon(_sc: &Scenario, i: usize, b: &BodySpec, d: Option<&Domain>, p: &mut Problems) {
    let at = |f: &str| format!("body.{i}.{f}");
    p.check(
        b.method == Method::Efg,
        at("outline"),
        "polygon bodies are EFG only: a `fem-q4` body is a rectangle (`rectangle` and `nodes`)",
    );
    p.check(
        b.nodes == [0, 0] && b.cells.is_none(),
        at("nodes"),
        "a polygon body has no node grid: give `spacing = h` (not `nodes`/`cells`)",
    );
    let bbox_ok = d.is_none_or(|d| {
        let (lo, hi) = d.bounds();
        b.rectangle.origin == lo.to_array() && b.rectangle.size == (hi - lo).to_array()
    });
    p.check(
        bbox_ok,
        at("rectangle"),
        "give either `rectangle` or `outline`, not both",
    );
    match b.spacing {
        None => p.push(
            at("spacing"),
            "a polygon body needs `spacing = h` (node spacing)",
        ),
        Some(h) => {
            p.check(
                h.is_finite() && h > 0.0,
                at("spacing"),
                format!("must be a finite number > 0 (got {h})"),
            );
            if let Some(d) = d
                && h.is_finite()
                && h > 0.0
            {
                let n = d.area() / (h * h);
                p.check(
                    n <= 5e6,
                    at("spacing"),
                    format!("about {n:.1e} nodes: at most 5·10⁶ (raise the spacing)"),
                );
            }
        }
    }
    let h = b.spacing.unwrap_or(f64::INFINITY);
    for (k, r) in b.refine.iter().enumerate() {
        let at = |f: &str| format!("body.{i}.refine.{k}.{f}");
        p.check(
            !r.edges.is_empty(),
            at("edges"),
            "name at least one edge to refine near",
        );
        if let Some(d) = d {
            for (j, e) in r.edges.iter().enumerate() {
                p.check(
                    d.edge(e).is_some(),
                    format!("body.{i}.refine.{k}.edges.{j}"),
                    format!(
                        "unknown edge `{e}` (the polygon's named edges: {})",
                        d.edges
                            .iter()
                            .map(|e| e.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                );
            }
        }
        p.check(
            r.spacing.is_finite() && r.spacing > 0.0 && r.spacing < h,
            at("spacing"),
            format!(
                "must be > 0 and below the body's spacing {h} (got {})",
                r.spacing
            ),
        );
        p.check(
            r.width.is_finite() && r.width > 0.0,
            at("width"),
            format!("must be a finite number > 0 (got {})", r.width),
        );
        if let Some(d) = d
            && r.spacing > 0.0
            && r.width > 0.0
        {
            // the band and the graded transition beyond it, on both sides
            let perimeter: f64 = d.segments().map(|(a, b)| (b - a).norm()).sum();
            let reach =
                r.width + (h.min(1e300) - r.spacing).max(0.0) / crate::efg::polygon::GRADING;
            let n = d.area().min(2.0 * reach * perimeter) / (r.spacing * r.spacing);
            p.check(
                n <= 5e6,
                at("spacing"),
                format!("about {n:.1e} nodes in the band: at most 5·10⁶"),
            );
        }
    }
}

/// Prescribed edge motions (`{ velocity = v, until_step = N }`) that move
/// an edge more than [`MAX_RELATIVE_MAGNITUDE`] × the body's size over a
/// run of `steps` steps of `dt`: `(path, message)` of the first one.
pub fn absurd_motion(sc: &Scenario, steps: usize, dt: f64) -> Option<(String, String)> {
    for (i, b) in sc.body.iter().enumerate() {
        let length = b.rectangle.size[0].max(b.rectangle.size[1]);
        for (k, bc) in b.bc.iter().enumerate() {
            for (f, v) in [("ux", &bc.ux), ("uy", &bc.uy)] {
                let Some(law) = v.as_ref().and_then(|v| v.drive_law()) else {
                    continue;
                };
                // a bound of the drive's travel over the run
                let t = steps as f64 * dt;
                let servo_speed = |s: &ServoSpec| s.max_velocity.unwrap_or(0.0).abs();
                // the largest scale over the rectangle's corners
                let (o, sz) = (b.rectangle.origin, b.rectangle.size);
                let scale = match v {
                    Some(pr @ Prescribed::ScaledLinear(_)) => [0.0, 1.0]
                        .iter()
                        .flat_map(|&i| [0.0, 1.0].map(move |j| (i, j)))
                        .map(|(i, j)| pr.drive_scale(o[0] + i * sz[0], o[1] + j * sz[1]).abs())
                        .fold(0.0, f64::max),
                    _ => 1.0,
                };
                let d = match &law {
                    DriveLaw::Velocity(m) => m.displacement(steps, dt).abs(),
                    DriveLaw::Table(tb) => tb.max_abs() * scale,
                    DriveLaw::VelocityTable(tb) => tb.max_abs() * t.max(tb.end()),
                    DriveLaw::Servo(s) => servo_speed(s) * t,
                    DriveLaw::Phases(ps) => {
                        ps.iter()
                            .map(|p| {
                                p.velocity
                                    .unwrap_or(0.0)
                                    .abs()
                                    .max(p.servo.as_ref().map_or(0.0, servo_speed))
                            })
                            .fold(0.0, f64::max)
                            * t
                    }
                };
                {
                    if d.is_nan() || d > MAX_RELATIVE_MAGNITUDE * length {
                        return Some((
                            format!("body.{i}.bc.{k}.{f}"),
                            format!(
                                "the edge would move by {}{d:e} over the run ({steps} steps of {dt:e}), more than {MAX_RELATIVE_MAGNITUDE:e} × the body's size ({length:e}); set `until_step`, a smaller velocity or smaller table values",
                                if matches!(law, DriveLaw::Velocity(_)) {
                                    ""
                                } else {
                                    "up to "
                                }
                            ),
                        ));
                    }
                }
            }
        }
    }
    None
}

/// A table's problem as a located error.
fn check_table(tb: &Table, at: &str, p: &mut Problems) {
    if let Some(m) = tb.problem() {
        p.push(at, m);
    }
}

/// Checks of a prescribed component that changes in time (tables, servo,
/// phases) at `at` (e.g. `body.0.bc.1.uy`).
fn validate_drive(sc: &Scenario, v: &Prescribed, gamma: f64, at: &str, p: &mut Problems) {
    let coupled = sc.granular.is_some();
    let servo = |sv: &ServoSpec, at: &str, p: &mut Problems| {
        p.check(
            gamma > 0.5,
            at,
            format!(
                "a servo drive needs a dissipative Newmark, γ > ½ (got γ = {gamma}), e.g. `newmark = {{ gamma = 0.6, beta = 0.3025 }}`: with γ = ½ the driven edge rings at the step frequency undamped (the accelerations of a prescribed edge grow after every change of speed) and the servo feeds the ringing (manual: scenario format, \"Servo drives\")"
            ),
        );
        match &sv.force {
            None => p.push(
                format!("{at}.force"),
                "a servo needs a target `force` (N, on the body along the component; a number or a table [[t, F], …])",
            ),
            Some(Target::Value(f)) => p.check(f.is_finite(), format!("{at}.force"), "must be finite"),
            Some(Target::Table(tb)) => check_table(tb, &format!("{at}.force"), p),
        }
        match sv.gain {
            None => p.push(
                format!("{at}.gain"),
                "a servo needs a `gain` G (m/s per N): one step against a stiffness K removes the fraction G K Δt of the force error; choose G ≈ 0.3/(K Δt)",
            ),
            Some(g) => p.check(g.is_finite() && g > 0.0, format!("{at}.gain"), format!("must be > 0 (got {g})")),
        }
        match sv.max_velocity {
            None => p.push(
                format!("{at}.max_velocity"),
                "a servo needs a `max_velocity` (m/s)",
            ),
            Some(v) => p.check(
                v.is_finite() && v > 0.0,
                format!("{at}.max_velocity"),
                format!("must be > 0 (got {v})"),
            ),
        }
        p.check(
            sv.integral.is_finite() && (0.0..1.0).contains(&sv.integral),
            format!("{at}.integral"),
            format!("integral action β must be in [0, 1) (got {})", sv.integral),
        );
        p.check(
            sv.measure != Measure::Contacts || coupled,
            format!("{at}.measure"),
            "`measure = \"contacts\"` needs discs (a coupled run); use `\"edge\"`",
        );
    };
    match v.drive_law() {
        Some(DriveLaw::Table(tb)) => {
            check_table(&tb, &format!("{at}.table"), p);
            // no time step follows a displacement that jumps: say so here
            // rather than let the run blow up and suggest a smaller Δt
            if let Some((t, from, to)) = tb.jump(0.0) {
                p.push(
                    format!("{at}.table"),
                    format!(
                        "a prescribed jump: the table goes from {from} to {to} at once at t = {t} (two points at the same time); a prescribed displacement must be continuous (no time step can follow a jump): ramp it over several steps"
                    ),
                );
            }
        }
        Some(DriveLaw::VelocityTable(tb)) => check_table(&tb, &format!("{at}.velocity_table"), p),
        Some(DriveLaw::Servo(sv)) => servo(&sv, &format!("{at}.servo"), p),
        Some(DriveLaw::Phases(ps)) => {
            p.check(
                !ps.is_empty(),
                format!("{at}.phases"),
                "give at least one phase",
            );
            let mut last = 0;
            for (k, ph) in ps.iter().enumerate() {
                let pat = format!("{at}.phases.{k}");
                p.check(
                    !(ph.velocity.is_some() && ph.servo.is_some()),
                    &pat,
                    "a phase has one motion: `velocity` or `servo` (or neither: at rest)",
                );
                if let Some(v) = ph.velocity {
                    p.check(v.is_finite(), format!("{pat}.velocity"), "must be finite");
                }
                if let Some(sv) = &ph.servo {
                    servo(sv, &format!("{pat}.servo"), p);
                }
                match ph.until_step {
                    None => p.check(
                        k + 1 == ps.len(),
                        format!("{pat}.until_step"),
                        "every phase but the last needs `until_step` (the step at which the next begins)",
                    ),
                    Some(n) => {
                        p.check(
                            n > last || (k == 0 && n > 0),
                            format!("{pat}.until_step"),
                            format!("must increase from phase to phase (got {n} after {last})"),
                        );
                        last = n;
                    }
                }
            }
        }
        _ => {}
    }
}

/// Names of the granular ParaView series (`discs.pvd`, …): a body may not
/// take them.
const RESERVED_NAMES: [&str; 3] = ["discs", "contacts", "walls"];

/// Semantic checks of every `[[body]]` and of the body probes.
pub fn validate(sc: &Scenario, p: &mut Problems) {
    let mut names = std::collections::HashSet::new();
    for (i, b) in sc.body.iter().enumerate() {
        let at = |f: &str| format!("body.{i}.{f}");
        p.check(
            names.insert(b.name.as_str()),
            at("name"),
            format!("body `{}` is defined twice", b.name),
        );
        // the name becomes file names (`<name>.pvd`, `frames/<name>_…`)
        p.check(
            !b.name.is_empty()
                && b.name
                    .chars()
                    .all(|c| c.is_alphanumeric() || "_-.".contains(c))
                && !b.name.starts_with('.'),
            at("name"),
            format!(
                "`{}` is not usable as a file name: use letters, digits, `_`, `-`, `.`",
                b.name
            ),
        );
        p.check(
            !RESERVED_NAMES.contains(&b.name.as_str()),
            at("name"),
            format!(
                "`{}` is the name of the disc frames' series; choose another",
                b.name
            ),
        );
        p.check(
            b.rectangle.origin.iter().all(|v| v.is_finite()),
            at("rectangle.origin"),
            "must be two finite numbers",
        );
        p.check(
            b.rectangle.size.iter().all(|v| v.is_finite() && *v > 0.0),
            at("rectangle.size"),
            format!(
                "must be two finite numbers > 0 (got {:?})",
                b.rectangle.size
            ),
        );
        validate_magnitudes(sc, i, b, p);
        let domain = match b.domain() {
            Ok(d) => d,
            Err((f, m)) => {
                p.push(at(&f), m);
                None
            }
        };
        super::crack::validate(i, b, domain.as_ref(), p);
        if b.is_polygon() {
            validate_polygon(sc, i, b, domain.as_ref(), p);
        } else {
            p.check(
                b.holes.is_empty() && b.edges.is_empty() && b.spacing.is_none() && b.refine.is_empty(),
                at("outline"),
                "`holes`, `edges`, `spacing` and `refine` belong to a polygon body: give `outline` too (or use `rectangle` and `nodes` alone)",
            );
        }
        p.check(
            b.is_polygon() || (b.nodes[0] >= 2 && b.nodes[1] >= 2),
            at("nodes"),
            format!(
                "the node grid needs at least 2 nodes per direction (got {:?}); e.g. [33, 9]",
                b.nodes
            ),
        );
        p.check(
            b.nodes[0].saturating_mul(b.nodes[1]) <= 50_000_000,
            at("nodes"),
            "too many nodes (at most 5·10⁷)",
        );
        if let Some(c) = b.cells {
            p.check(
                c[0] >= 1 && c[1] >= 1 && c[0].saturating_mul(c[1]) <= 50_000_000,
                at("cells"),
                format!("must be ≥ 1 per direction (got {c:?})"),
            );
        }
        let cells = b
            .cells
            .unwrap_or([b.nodes[0].saturating_sub(1), b.nodes[1].saturating_sub(1)]);
        p.check(
            cells[0]
                .saturating_mul(cells[1])
                .saturating_mul(b.gauss.saturating_mul(b.gauss))
                <= 200_000_000,
            at("gauss"),
            "too many Gauss points (cells × gauss² must be ≤ 2·10⁸)",
        );
        p.check(
            (1..=10).contains(&b.gauss),
            at("gauss"),
            format!("must be between 1 and 10 (got {})", b.gauss),
        );
        if b.method == Method::FemQ4 {
            // EFG-only fields: a value other than the default is a mistake
            // (the FE mesh is the node grid, integrated with 2 × 2 Gauss).
            p.check(
                b.cells.is_none_or(|c| c == [b.nodes[0].saturating_sub(1), b.nodes[1].saturating_sub(1)]),
                at("cells"),
                "a `fem-q4` body's elements are the cells of its node grid: omit `cells` (or set it to nodes − 1)",
            );
            p.check(
                b.gauss == default_gauss(),
                at("gauss"),
                "`gauss` is an EFG option: `fem-q4` elements use 2 × 2 Gauss points; omit it",
            );
            p.check(
                b.d_max == default_d_max(),
                at("d_max"),
                "`d_max` is an EFG option (support size): omit it for a `fem-q4` body",
            );
            p.check(
                b.penalty.is_none(),
                at("penalty"),
                "`penalty` is an EFG option: a `fem-q4` body imposes prescribed displacements exactly on its nodes; omit it",
            );
        } else {
            p.check(
                b.mass == MassKind::Consistent,
                at("mass"),
                "`mass = \"lumped\"` is only available for `method = \"fem-q4\"` bodies (EFG uses the consistent Gram matrix)",
            );
        }
        p.check(
            b.d_max.is_finite() && b.d_max > 1.0 && b.d_max <= 10.0,
            at("d_max"),
            format!(
                "must be > 1 (and ≤ 10) so that every point is covered by at least 3 non-collinear nodes; 2.0 is the usual choice (got {})",
                b.d_max
            ),
        );
        let el = &b.elastic;
        p.positive(el.e, at("elastic.E"));
        p.check(
            el.nu.is_finite() && el.nu > -1.0 && el.nu < 0.5,
            at("elastic.nu"),
            format!("Poisson's ratio must satisfy −1 < ν < 0.5 (got {})", el.nu),
        );
        p.non_negative(el.density, at("elastic.density"));
        p.positive(el.thickness, at("elastic.thickness"));
        if sc.simulation.analysis == Analysis::Dynamic {
            p.check(
                el.density > 0.0,
                at("elastic.density"),
                "a dynamic analysis needs a density > 0",
            );
        }
        p.check(
            b.contact_refine >= 1 && b.contact_refine <= 64,
            at("contact_refine"),
            format!("must be between 1 and 64 (got {})", b.contact_refine),
        );
        if let Some(m) = &b.contact_material {
            p.check(
                sc.material(m).is_some(),
                at("contact_material"),
                format!("no [[material]] named `{m}`"),
            );
        }
        let mut seen = std::collections::HashSet::new();
        for (k, e) in b.contact_edges.iter().enumerate() {
            p.check(
                seen.insert(e.clone()),
                format!("body.{i}.contact_edges.{k}"),
                format!("edge `{e}` is listed twice"),
            );
            let known = match &domain {
                Some(d) => d.edge(e.as_str()).is_some() || b.default_contact_edges(),
                None => b.is_polygon() || e.side().is_some(),
            };
            p.check(
                known,
                format!("body.{i}.contact_edges.{k}"),
                format!("unknown edge `{e}`"),
            );
        }
        p.check(
            b.overlapping_discs == OverlappingDiscs::Refuse || sc.granular.is_some(),
            at("overlapping_discs"),
            "`remove` needs discs ([granular]) to remove",
        );
        if b.self_weight && sc.simulation.gravity != [0.0, 0.0] && el.density <= 0.0 {
            p.push(
                at("elastic.density"),
                "gravity is set but the density is 0: give the body a density",
            );
        }
        p.non_negative(b.damping, at("damping"));
        if let Some(a) = b.penalty {
            p.positive(a, at("penalty"));
        }
        let nm = &b.newmark;
        p.check(
            nm.gamma.is_finite() && nm.gamma >= 0.5,
            at("newmark.gamma"),
            format!("γ must be ≥ 1/2 (got {})", nm.gamma),
        );
        p.check(
            nm.beta.is_finite() && nm.beta >= 0.5 * nm.gamma && nm.beta > 0.0,
            at("newmark.beta"),
            format!(
                "β must be ≥ γ/2 for unconditional stability (got β = {}, γ = {})",
                nm.beta, nm.gamma
            ),
        );
        let mut bc_names = std::collections::HashSet::new();
        let mut has_support = false;
        for (k, bc) in b.bc.iter().enumerate() {
            let at = |f: &str| format!("body.{i}.bc.{k}.{f}");
            let kinds = [
                bc.fixed,
                bc.ux.is_some() || bc.uy.is_some(),
                bc.timoshenko.is_some(),
                bc.traction.is_some(),
                bc.parabolic_shear.is_some(),
                bc.pressure.is_some(),
                bc.kirsch.is_some(),
                bc.griffith.is_some(),
                bc.williams.is_some(),
            ];
            let n = kinds.iter().filter(|&&x| x).count();
            p.check(
                n == 1,
                at("edge"),
                format!(
                    "give exactly one of `fixed = true`, `ux`/`uy`, `timoshenko`, `traction`, `parabolic_shear`, `pressure`, `kirsch`, `griffith`, `williams` ({n} given)"
                ),
            );
            match &domain {
                Some(d) => {
                    p.check(
                        d.edge(bc.edge.as_str()).is_some(),
                        at("edge"),
                        format!(
                            "unknown edge `{}`; this polygon body's edges are: {}",
                            bc.edge,
                            d.edges.iter().map(|e| e.name.as_str()).collect::<Vec<_>>().join(", ")
                        ),
                    );
                    p.check(
                        bc.timoshenko.is_none() && bc.parabolic_shear.is_none(),
                        at("edge"),
                        "`timoshenko` and `parabolic_shear` are for rectangular bodies only",
                    );
                }
                None if !b.is_polygon() => p.check(
                    bc.edge.side().is_some(),
                    at("edge"),
                    format!(
                        "unknown edge `{}`: a rectangle's edges are `left`, `right`, `top`, `bottom`",
                        bc.edge
                    ),
                ),
                None => {}
            }
            if let Some(v) = bc.pressure {
                p.check(v.is_finite(), at("pressure"), "must be finite");
            }
            if let Some(k) = bc.kirsch {
                p.check(k.s.is_finite(), at("kirsch.S"), "must be finite");
                p.positive(k.a, at("kirsch.a"));
            }
            if !bc.is_load() && n == 1 {
                has_support = true;
            }
            if let Some(name) = &bc.name {
                p.check(
                    bc_names.insert(name.as_str()) && name != "gravity",
                    at("name"),
                    format!("bc name `{name}` is used twice (or is the reserved `gravity`)"),
                );
            }
            for (f, v) in [("ux", &bc.ux), ("uy", &bc.uy)] {
                if let Some(v) = v {
                    p.check(v.finite(), at(f), "must be finite");
                    validate_drive(sc, v, b.newmark.gamma, &at(f), p);
                }
            }
            if let Some(tb) = &bc.table {
                check_table(tb, &at("table"), p);
                p.check(
                    bc.is_load(),
                    at("table"),
                    "`table` multiplies a load (`traction`, `parabolic_shear`) in time; for a prescribed displacement write `ux`/`uy = { table = [[t, u], …] }`",
                );
                p.check(
                    bc.name.as_deref().is_none_or(|n| {
                        !b.initial
                            .as_ref()
                            .is_some_and(|i| i.static_under.iter().any(|s| s == n))
                    }),
                    at("table"),
                    "a load with a `table` cannot be in `initial.static_under` (released loads are constant)",
                );
            }
            if let Some(t) = &bc.timoshenko {
                p.check(t.p.is_finite(), at("timoshenko.P"), "must be finite");
            }
            if let Some(t) = bc.traction {
                p.check(
                    t.iter().all(|v| v.is_finite()),
                    at("traction"),
                    "must be two finite numbers",
                );
            }
            if let Some(t) = bc.parabolic_shear {
                p.check(t.is_finite(), at("parabolic_shear"), "must be finite");
            }
        }
        for (k, pl) in b.load.iter().enumerate() {
            let at = |f: &str| format!("body.{i}.load.{k}.{f}");
            let (o, s) = (b.rectangle.origin, b.rectangle.size);
            let pt = pl.point;
            let tol = 1e-9 * (s[0].abs() + s[1].abs());
            if !pt.iter().all(|v| v.is_finite()) {
                p.push(at("point"), "must be two finite numbers");
            } else {
                p.check(
                    pt[0] >= o[0] - tol
                        && pt[0] <= o[0] + s[0] + tol
                        && pt[1] >= o[1] - tol
                        && pt[1] <= o[1] + s[1] + tol,
                    at("point"),
                    format!("{pt:?} is outside body `{}`", b.name),
                );
            }
            p.check(
                pl.force.iter().all(|v| v.is_finite()),
                at("force"),
                "must be two finite numbers",
            );
            if let Some(tb) = &pl.table {
                check_table(tb, &at("table"), p);
            }
        }
        p.check(
            has_support,
            at("bc"),
            "the body has no prescribed displacement (`fixed`, `ux`/`uy`, `timoshenko`): its stiffness matrix is singular",
        );
        if let Some(init) = &b.initial {
            for (k, name) in init.static_under.iter().enumerate() {
                let ok = name == "gravity"
                    || b.bc
                        .iter()
                        .any(|bc| bc.is_load() && bc.name.as_deref() == Some(name.as_str()));
                p.check(
                    ok,
                    format!("body.{i}.initial.static_under.{k}"),
                    format!(
                        "`{name}` is not the name of a load bc (traction / parabolic_shear) of this body, nor `gravity`"
                    ),
                );
            }
        }
    }
    if sc.body.is_empty() {
        return;
    }
    let continuum_only = sc.granular.is_none() && sc.wall.is_empty();
    if continuum_only && sc.simulation.analysis == Analysis::Dynamic {
        p.check(
            sc.simulation.dt.is_some(),
            "simulation.dt",
            "a dynamic continuum analysis needs a time step `dt` (or set `analysis = \"static\"`)",
        );
        p.check(
            sc.simulation.steps.is_some() || sc.simulation.end_time.is_some(),
            "simulation",
            "a dynamic analysis needs `steps` or `end_time`",
        );
    }
    for (k, pr) in sc.probe.iter().enumerate() {
        let at = |f: &str| format!("probe.{k}.{f}");
        let q = pr.quantity.as_str();
        let is_body = is_body_probe(pr, continuum_only);
        if !is_body {
            if continuum_only {
                p.push(
                    at("quantity"),
                    format!(
                        "unknown body quantity `{q}`; one of {} (with `point`), {} or {}",
                        POINT_QUANTITIES.join(", "),
                        BODY_QUANTITIES.join(", "),
                        DRIVE_QUANTITIES.join(", ")
                    ),
                );
            }
            continue;
        }
        let body = match &pr.body {
            Some(n) => sc.body.iter().find(|b| &b.name == n),
            None => sc.body.first(),
        };
        if body.is_none() {
            p.push(at("body"), "no body of that name");
        }
        if let (true, Some(b)) = (DRIVE_QUANTITIES.contains(&q), body) {
            let c = if q.ends_with('x') { "ux" } else { "uy" };
            let has = b.bc.iter().any(|bc| {
                let pr = if c == "ux" { &bc.ux } else { &bc.uy };
                !bc.is_load() && !bc.fixed && pr.as_ref().is_some_and(|v| v.drive_law().is_some())
            });
            p.check(
                has,
                at("quantity"),
                format!(
                    "body `{}` has no `{c}` that changes in time (velocity, table, servo, phases) to record",
                    b.name
                ),
            );
        }
        if let (true, Some(b)) = (CRACK_QUANTITIES.contains(&q), body) {
            validate_crack_probe(b, pr, &at, p);
        }
        if POINT_QUANTITIES.contains(&q) {
            match pr.point {
                None => p.push(at("quantity"), format!("`{q}` needs a `point = [x, y]`")),
                Some(pt) => {
                    p.check(
                        pt.iter().all(|v| v.is_finite()),
                        at("point"),
                        "must be two finite numbers",
                    );
                    if let Some(b) = body {
                        let (o, s) = (b.rectangle.origin, b.rectangle.size);
                        let tol = 1e-9 * (s[0].abs() + s[1].abs());
                        p.check(
                            pt[0] >= o[0] - tol
                                && pt[0] <= o[0] + s[0] + tol
                                && pt[1] >= o[1] - tol
                                && pt[1] <= o[1] + s[1] + tol,
                            at("point"),
                            format!("{pt:?} is outside body `{}`", b.name),
                        );
                    }
                }
            }
        }
    }
}

/// Checks of a crack probe of body `b`: the crack exists, the end is a tip.
fn validate_crack_probe(
    b: &BodySpec,
    pr: &crate::scenario::Probe,
    at: &dyn Fn(&str) -> String,
    p: &mut Problems,
) {
    let q = pr.quantity.as_str();
    if q == "fracture_energy" {
        return;
    }
    let k = pr.crack.unwrap_or(1);
    if k == 0 || k > b.crack.len() {
        p.push(
            at("crack"),
            format!(
                "body `{}` has {} crack(s) (`[[body.crack]]`, numbered from 1); got {k}",
                b.name,
                b.crack.len()
            ),
        );
        return;
    }
    if matches!(q, "k1" | "k2" | "k_eq") {
        p.check(
            pr.tip.is_none_or(|t| t == 1 || t == 2),
            at("tip"),
            "1 (the crack's first point) or 2 (its last point)",
        );
    } else {
        p.check(
            pr.tip.is_none(),
            at("tip"),
            format!("`{q}` is a quantity of the whole crack: omit `tip`"),
        );
    }
}
