//! Scenarios assembled in code: constructors with the file format's
//! defaults and chainable setters, so that a Rust user writes what a TOML
//! file would say and gets the same validation ([`Scenario::build`]).
//!
//! Every constructor starts from the TOML defaults themselves (it
//! deserialises the smallest valid table), so a scenario built here and
//! the same scenario read from a file are identical.

use super::body::{BcSpec, BodySpec, Edge, Elastic, Method, Rectangle};
use super::granular::{DampingSpec, DiscsSpec, GranularSpec, WallSpec};
use super::{Analysis, Material, Probe, Scenario};
use serde::de::DeserializeOwned;

/// `T` with every default of the format, from a minimal TOML table.
fn defaults<T: DeserializeOwned>(toml_text: &str) -> T {
    toml::from_str(toml_text).expect("the built-in minimal table is valid")
}

impl Default for Scenario {
    fn default() -> Self {
        defaults("")
    }
}

impl Scenario {
    /// An empty scenario (every section at its default).
    pub fn new() -> Self {
        Self::default()
    }
    /// `[simulation] dt`.
    pub fn dt(mut self, dt: f64) -> Self {
        self.simulation.dt = Some(dt);
        self
    }
    /// `[simulation] steps`.
    pub fn steps(mut self, n: usize) -> Self {
        self.simulation.steps = Some(n);
        self
    }
    /// `[simulation] end_time`.
    pub fn end_time(mut self, t: f64) -> Self {
        self.simulation.end_time = Some(t);
        self
    }
    /// `[simulation] gravity`.
    pub fn gravity(mut self, gx: f64, gy: f64) -> Self {
        self.simulation.gravity = [gx, gy];
        self
    }
    /// `[simulation] analysis = "static"` (continuum bodies only).
    pub fn static_analysis(mut self) -> Self {
        self.simulation.analysis = Analysis::Static;
        self
    }
    /// A `[[material]]`.
    pub fn add_material(mut self, m: Material) -> Self {
        self.material.push(m);
        self
    }
    /// `[granular]` with inline discs `[x, y, r]` of `material`.
    pub fn discs(mut self, material: &str, rows: &[[f64; 3]]) -> Self {
        self.granular = Some(GranularSpec::inline(material, rows));
        self
    }
    /// `[granular]` in full.
    pub fn granular(mut self, g: GranularSpec) -> Self {
        self.granular = Some(g);
        self
    }
    /// A `[[wall]]`.
    pub fn add_wall(mut self, w: WallSpec) -> Self {
        self.wall.push(w);
        self
    }
    /// A `[[body]]`.
    pub fn add_body(mut self, b: BodySpec) -> Self {
        self.body.push(b);
        self
    }
    /// A `[[probe]]`.
    pub fn add_probe(mut self, p: Probe) -> Self {
        self.probe.push(p);
        self
    }
}

impl Material {
    /// A contact material: density and stiffnesses; no friction, no cohesion.
    pub fn new(name: &str, density: f64, kn: f64, ks: f64) -> Self {
        let mut m: Material = defaults("name = \"\"");
        m.name = name.to_string();
        m.density = density;
        m.kn = kn;
        m.ks = ks;
        m
    }
    /// Friction coefficient `tan φ`.
    pub fn friction(mut self, mu: f64) -> Self {
        self.friction = mu;
        self
    }
    /// Cohesion `c`.
    pub fn cohesion(mut self, c: f64) -> Self {
        self.cohesion = c;
        self
    }
}

impl GranularSpec {
    /// Inline discs `[x, y, r]` of `material`, thickness 1, no damping.
    pub fn inline(material: &str, rows: &[[f64; 3]]) -> Self {
        let mut g: GranularSpec = defaults("material = \"\"\ndiscs = []");
        g.material = material.to_string();
        g.discs = DiscsSpec::Inline(rows.to_vec());
        g
    }
    /// Disc thickness t.
    pub fn thickness(mut self, t: f64) -> Self {
        self.thickness = t;
        self
    }
    /// Damping of the assembly.
    pub fn damping(mut self, d: DampingSpec) -> Self {
        self.damping = d;
        self
    }
}

impl WallSpec {
    /// A fixed wall from `from` to `to`.
    pub fn new(name: &str, from: [f64; 2], to: [f64; 2]) -> Self {
        let mut w: WallSpec = defaults("name = \"\"\nfrom = [0, 0]\nto = [1, 0]");
        w.name = name.to_string();
        w.from = from;
        w.to = to;
        w
    }
    /// Constant velocity.
    pub fn velocity(mut self, v: [f64; 2]) -> Self {
        self.velocity = Some(v);
        self
    }
}

impl BodySpec {
    /// An EFG body on the rectangle `origin`, `size` with `nodes` and the
    /// format's defaults (4 × 4 Gauss points, `d_max = 2`, average
    /// acceleration, every edge a contact edge, self-weight on).
    pub fn new(
        name: &str,
        origin: [f64; 2],
        size: [f64; 2],
        nodes: [usize; 2],
        elastic: Elastic,
    ) -> Self {
        let mut b: BodySpec = defaults(
            "name = \"\"\nrectangle = { origin = [0, 0], size = [1, 1] }\nnodes = [2, 2]\nelastic = { E = 1.0, nu = 0.0 }",
        );
        b.name = name.to_string();
        b.rectangle = Rectangle { origin, size };
        b.nodes = nodes;
        b.elastic = elastic;
        b
    }
    /// Bilinear finite elements on the node grid instead of EFG.
    pub fn fem_q4(mut self) -> Self {
        self.method = Method::FemQ4;
        self
    }
    /// Newmark γ and β.
    pub fn newmark(mut self, gamma: f64, beta: f64) -> Self {
        self.newmark.gamma = gamma;
        self.newmark.beta = beta;
        self
    }
    /// A boundary condition.
    pub fn bc(mut self, bc: BcSpec) -> Self {
        self.bc.push(bc);
        self
    }
    /// Remove the discs the body overlaps when the run starts (after the
    /// preparation of a generated packing) instead of refusing them
    /// (`overlapping_discs = "remove"`).
    pub fn remove_overlapping_discs(mut self) -> Self {
        self.overlapping_discs = super::body::OverlappingDiscs::Remove;
        self
    }
    /// The edges discs can touch.
    pub fn contact_edges(mut self, edges: &[Edge]) -> Self {
        self.contact_edges = edges.iter().map(|&e| e.into()).collect();
        self
    }
    /// Gravity on the body's own mass.
    pub fn self_weight(mut self, on: bool) -> Self {
        self.self_weight = on;
        self
    }
}

impl Probe {
    fn named(name: &str, quantity: &str) -> Self {
        let mut p: Probe = defaults("name = \"\"\nquantity = \"\"");
        p.name = name.to_string();
        p.quantity = quantity.to_string();
        p
    }
    /// `quantity` (`ux`, `sxx`, …) at `point` of body `body`.
    pub fn body_point(name: &str, body: &str, point: [f64; 2], quantity: &str) -> Self {
        Probe {
            body: Some(body.to_string()),
            point: Some(point),
            ..Self::named(name, quantity)
        }
    }
    /// `quantity` (`x`, `vy`, …; `ux`, `uy` in coupled runs) of disc `disc`
    /// (numbered from 1).
    pub fn disc(name: &str, disc: usize, quantity: &str) -> Self {
        Probe {
            disc: Some(disc),
            ..Self::named(name, quantity)
        }
    }
    /// An assembly-wide quantity (`kinetic`, `contacts`, …).
    pub fn global(name: &str, quantity: &str) -> Self {
        Self::named(name, quantity)
    }
}
