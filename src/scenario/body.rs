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
    /// The body's rectangle.
    pub rectangle: Rectangle,
    /// Node grid `[nx, ny]` (row-major, x fastest).
    pub nodes: [usize; 2],
    /// Background integration cells `[cx, cy]`; default `nodes − 1`.
    pub cells: Option<[usize; 2]>,
    /// Gauss points per cell direction (n × n per cell, n per boundary segment).
    #[serde(default = "default_gauss")]
    pub gauss: usize,
    /// Support size factor: `d_mI = d_max · c_I` (Eqs. 7–8).
    #[serde(default = "default_d_max")]
    pub d_max: f64,
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
    /// Initial state of a dynamic run (default: at rest, undeformed).
    pub initial: Option<InitialSpec>,
    /// Edges that discs can touch (coupled runs), e.g. `["top", "right"]`;
    /// default: all four (one closed chain). Adjacent edges are joined
    /// around their common corner; `[]` gives a body no contact boundary.
    #[serde(default = "all_edges")]
    pub contact_edges: Vec<Edge>,
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
}

fn yes() -> bool {
    true
}

fn all_edges() -> Vec<Edge> {
    Edge::ALL.to_vec()
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
fn one() -> f64 {
    1.0
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    #[default]
    Efg,
    /// 4-node bilinear finite elements on the node grid.
    FemQ4,
}

/// Consistent (`∫ρNᵀN`) or lumped (row-sum) mass matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum MassKind {
    #[default]
    Consistent,
    Lumped,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rectangle {
    /// Lower-left corner.
    pub origin: [f64; 2],
    /// Width and height.
    pub size: [f64; 2],
}

/// Linear isotropic elasticity.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Elastic {
    /// Young's modulus.
    #[serde(rename = "E")]
    pub e: f64,
    /// Poisson's ratio, −1 < ν < 0.5.
    pub nu: f64,
    /// Mass density (needed for dynamics and gravity).
    #[serde(default)]
    pub density: f64,
    /// Out-of-plane thickness t.
    #[serde(default = "one")]
    pub thickness: f64,
    #[serde(default)]
    pub plane: Plane,
}

/// Plane stress (Eq. 31) or plane strain (Eq. 32).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Plane {
    #[default]
    Stress,
    Strain,
}

/// Newmark γ and β (ERRATA E9: the paper's β₁ = γ, β₂ = 2β).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NewmarkSpec {
    pub gamma: f64,
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

/// An edge of the rectangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Edge {
    Left,
    Right,
    Top,
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

/// One boundary condition on one edge: exactly one of `fixed`, `ux`/`uy`,
/// `timoshenko` (prescribed displacement, penalty), `traction`,
/// `parabolic_shear` (loads).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BcSpec {
    pub edge: Edge,
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
    /// Parabolic shear traction with resultant `P` (force per unit thickness)
    /// along the edge, `τ = 3P/(2D)·(1 − 4s²/D²)`, s from the edge centre.
    pub parabolic_shear: Option<f64>,
}

/// A prescribed displacement component: a number, or `{ linear = [a, b, c] }`
/// for `a + b x + c y`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(
    untagged,
    expecting = "a number, { linear = [a, b, c] } (a + b x + c y) or { velocity = v, until_step = N } (no other keys)"
)]
pub enum Prescribed {
    Value(f64),
    Linear(LinearField),
    Motion(MotionField),
}

/// `{ velocity = v, until_step = N }`: the edge moves with velocity `v`
/// (displacement `v t`) during the first `N` steps (all steps if absent),
/// then stays where it is — e.g. an edge following a rigid plate.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionField {
    pub velocity: f64,
    pub until_step: Option<usize>,
}

impl MotionField {
    /// Displacement after `steps` steps of `dt`.
    pub fn displacement(&self, steps: usize, dt: f64) -> f64 {
        let n = self.until_step.map_or(steps, |u| steps.min(u));
        self.velocity * n as f64 * dt
    }
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearField {
    pub linear: [f64; 3],
}

impl Prescribed {
    pub fn at(&self, x: f64, y: f64) -> f64 {
        match *self {
            Prescribed::Value(v) => v,
            Prescribed::Linear(LinearField { linear: [a, b, c] }) => a + b * x + c * y,
            Prescribed::Motion(_) => 0.0,
        }
    }
    fn finite(&self) -> bool {
        match self {
            Prescribed::Value(v) => v.is_finite(),
            Prescribed::Linear(l) => l.linear.iter().all(|v| v.is_finite()),
            Prescribed::Motion(m) => m.velocity.is_finite(),
        }
    }
}

/// The exact field of a cantilever clamped at the left edge of the body's
/// rectangle with end shear `P` at the right edge (Timoshenko & Goodier).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimoshenkoSpec {
    #[serde(rename = "P")]
    pub p: f64,
}

/// `initial = { static_under = ["tip"] }`: start a dynamic run from the
/// static equilibrium under the permanent loads plus the named loads (bc
/// names, or `"gravity"`), which are then released at t = 0.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    pub static_under: Vec<String>,
}

impl BcSpec {
    /// Is this a load (traction) rather than a prescribed displacement?
    pub fn is_load(&self) -> bool {
        self.traction.is_some() || self.parabolic_shear.is_some()
    }
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

/// Is `pr` a probe of a body? In a continuum-only run every point quantity
/// is; in a coupled run a probe belongs to a body when it has a `point` or
/// a body-wide quantity (so `vx` of a disc stays a disc probe).
pub fn is_body_probe(pr: &crate::scenario::Probe, continuum_only: bool) -> bool {
    let q = pr.quantity.as_str();
    BODY_QUANTITIES.contains(&q)
        || (!continuum_only && CONTACT_FORCE_QUANTITIES.contains(&q))
        || (POINT_QUANTITIES.contains(&q) && (continuum_only || pr.point.is_some()))
}

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
        p.check(
            b.nodes[0] >= 2 && b.nodes[1] >= 2,
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
                seen.insert(*e),
                format!("body.{i}.contact_edges.{k}"),
                format!("edge `{e:?}` is listed twice"),
            );
        }
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
            ];
            let n = kinds.iter().filter(|&&x| x).count();
            p.check(
                n == 1,
                at("edge"),
                format!(
                    "give exactly one of `fixed = true`, `ux`/`uy`, `timoshenko`, `traction`, `parabolic_shear` ({n} given)"
                ),
            );
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
            for (f, v) in [("ux", bc.ux), ("uy", bc.uy)] {
                if let Some(v) = v {
                    p.check(v.finite(), at(f), "must be finite");
                }
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
                        "unknown body quantity `{q}`; one of {} (with `point`) or {}",
                        POINT_QUANTITIES.join(", "),
                        BODY_QUANTITIES.join(", ")
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
