//! The parameters of a continuum body on a rectangle, shared by the EFG
//! and FE methods: geometry, elasticity, boundary conditions, Newmark.
//! Plain data; the scenario builds them from a `[[body]]` section (the
//! value types derive serde's `Deserialize` so that the scenario can embed
//! them, but nothing here knows the file).

use super::conditions::{Edge, EdgeCondition, PointLoad};
use serde::Deserialize;

fn one() -> f64 {
    1.0
}

/// Consistent (`∫ρNᵀN`) or lumped (row-sum) mass matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum MassKind {
    /// `M_IJ = ∫_Ω Φ_Iᵀ ρ Φ_J dΩ` (Eq. 23).
    #[default]
    Consistent,
    /// Diagonal: each row of the consistent matrix summed onto the
    /// diagonal (FE bodies only).
    Lumped,
}

/// An axis-aligned rectangle in the reference configuration: the domain Ω
/// of a body.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Rectangle {
    /// Lower-left corner.
    pub origin: [f64; 2],
    /// Width and height.
    pub size: [f64; 2],
}

/// A polygon domain (EFG bodies only): outline, holes and named edges,
/// and the node spacing `h`.
#[derive(Debug, Clone)]
pub struct PolygonShape {
    /// The validated domain.
    pub domain: crate::geom::polygon::Domain,
    /// Node spacing `h` (grid and boundary nodes).
    pub spacing: f64,
    /// Finer node spacings near named edges.
    pub refine: Vec<Refine>,
}

/// A finer node spacing near some boundary segments of a polygon body:
/// nodes at `spacing` along them and on a grid within `width` of them.
#[derive(Debug, Clone, PartialEq)]
pub struct Refine {
    /// The segments `(loop, segment)` refined near.
    pub segments: Vec<(usize, usize)>,
    /// The node spacing there (< the body's `spacing`).
    pub spacing: f64,
    /// Width of the refined band along the segments.
    pub width: f64,
}

/// A crack in an EFG body ([`crate::geom::crack`]): its polyline and an
/// optional finer node spacing along it.
#[derive(Debug, Clone, PartialEq)]
pub struct CrackShape {
    /// The polyline (ends: tips inside the body, or a mouth on its
    /// boundary).
    pub crack: crate::geom::crack::Crack,
    /// Node spacing along the crack and within `width` of it, graded to
    /// the body's spacing beyond (as [`Refine`]); `None`: the body's.
    pub spacing: Option<f64>,
    /// Width of the refined band along the crack.
    pub width: f64,
    /// Friction coefficient of the faces in contact.
    pub friction: f64,
    /// Stiffness of the faces in contact, stress per length (`None`:
    /// `100 E / h` with `h` the crack's station spacing: overlaps far
    /// below the node spacing, a well-conditioned contact solve).
    pub face_stiffness: Option<f64>,
}

/// Crack growth in an EFG body with cracks ([`crate::efg::growth`]): a tip
/// grows when the equivalent stress intensity factor of the maximum
/// hoop-stress criterion reaches the toughness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fracture {
    /// Fracture toughness `K_Ic` (stress·√length).
    pub toughness: f64,
    /// Length Δa added to a tip per growth; `None`: the outer radius of the
    /// tip's interaction-integral ring (5 × the tip's node spacing).
    pub increment: Option<f64>,
    /// Most growth increments per tip over a run.
    pub max_increments: usize,
    /// In time-stepped runs, look at the tips every `every` steps.
    pub every: usize,
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
    /// Plane stress (default) or plane strain: which `D` (Eq. 31 or 32).
    #[serde(default)]
    pub plane: Plane,
}

impl Elastic {
    /// Young's modulus and Poisson's ratio with the other fields at their
    /// defaults (the `#[serde(default)]`s above): density 0, thickness 1,
    /// plane stress.
    pub fn new(e: f64, nu: f64) -> Self {
        Elastic {
            e,
            nu,
            density: 0.0,
            thickness: one(),
            plane: Plane::default(),
        }
    }
    /// Mass density.
    pub fn density(mut self, rho: f64) -> Self {
        self.density = rho;
        self
    }
    /// Out-of-plane thickness.
    pub fn thickness(mut self, t: f64) -> Self {
        self.thickness = t;
        self
    }
    /// Plane strain instead of plane stress.
    pub fn plane_strain(mut self) -> Self {
        self.plane = Plane::Strain;
        self
    }
}

/// Plane stress (Eq. 31) or plane strain (Eq. 32).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Plane {
    /// Plane stress, `σ_zz = 0` (Eq. 31).
    #[default]
    Stress,
    /// Plane strain, `ε_zz = 0` (Eq. 32).
    Strain,
}

/// As the scenario names it: `stress` or `strain`.
impl std::fmt::Display for Plane {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Plane::Stress => "stress",
            Plane::Strain => "strain",
        })
    }
}

/// Everything needed to build a body (EFG or FE) on a rectangle.
#[derive(Debug, Clone)]
pub struct BodyParams {
    /// Name used in messages and outputs.
    pub name: String,
    /// The body's rectangle (for a polygon body: the outline's bounding box).
    pub rectangle: Rectangle,
    /// A polygon domain instead of the rectangle (EFG only).
    pub polygon: Option<PolygonShape>,
    /// Node grid `[nx, ny]` (row-major, x fastest), ≥ 2 each.
    pub nodes: [usize; 2],
    /// Background integration cells `[cx, cy]` (EFG); default `nodes − 1`.
    pub cells: Option<[usize; 2]>,
    /// Gauss points per cell direction (n × n per cell, n per boundary segment).
    pub gauss: usize,
    /// Support size factor: `d_mI = d_max · c_I` (Eqs. 7–8, EFG).
    pub d_max: f64,
    /// Elastic constants, density, thickness and plane assumption.
    pub elastic: Elastic,
    /// Damping coefficient `c` of Eq. (24): `C = ∫Φᵀ c Φ`.
    pub damping: f64,
    /// Penalty factor α of Eq. (21) (ERRATA E4, EFG); default `1e5 · E`.
    pub penalty: Option<f64>,
    /// Newmark γ and β (ERRATA E9).
    pub newmark: [f64; 2],
    /// Mass matrix of an FE body (EFG bodies always use the consistent one).
    pub mass: MassKind,
    /// Boundary conditions on the edges.
    pub bc: Vec<EdgeCondition>,
    /// Loads (bc names or `"gravity"`) applied for the initial static state
    /// only and released at t = 0.
    pub static_under: Vec<String>,
    /// Apply gravity to the body's own mass.
    pub self_weight: bool,
    /// Point loads at material points (`[[body.load]]`).
    pub loads: Vec<PointLoad>,
    /// Cracks (EFG only); a rectangle with cracks is meshed as a polygon
    /// of spacing `min(width/(nx − 1), height/(ny − 1))`.
    pub cracks: Vec<CrackShape>,
    /// Crack growth (`None`: the cracks stay as they are).
    pub fracture: Option<Fracture>,
}

impl BodyParams {
    /// A body on `rectangle` (origin, size) with `nodes` and `elastic`, and
    /// the defaults of the scenario format: 4 × 4 Gauss points, `d_max = 2`,
    /// no damping, average-acceleration Newmark, consistent mass, no
    /// boundary conditions, self-weight on.
    pub fn new(name: &str, rectangle: Rectangle, nodes: [usize; 2], elastic: Elastic) -> Self {
        BodyParams {
            name: name.to_string(),
            rectangle,
            polygon: None,
            nodes,
            cells: None,
            gauss: 4,
            d_max: 2.0,
            elastic,
            damping: 0.0,
            penalty: None,
            newmark: [0.5, 0.25],
            mass: MassKind::Consistent,
            bc: Vec::new(),
            static_under: Vec::new(),
            self_weight: true,
            loads: Vec::new(),
            cracks: Vec::new(),
            fracture: None,
        }
    }

    /// Is the load `name` (a bc name or `"gravity"`) applied for the
    /// initial static state only?
    pub fn is_released(&self, name: &str) -> bool {
        self.static_under.iter().any(|s| s == name)
    }

    /// End points of an edge of the rectangle (left/right bottom → top,
    /// bottom/top left → right).
    pub fn edge_ends(&self, e: Edge) -> (crate::geom::Vec2, crate::geom::Vec2) {
        super::conditions::edge_ends(self.rectangle.origin.into(), self.rectangle.size.into(), e)
    }
}
