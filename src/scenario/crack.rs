//! `[[body.crack]]` and `[body.fracture]`: cracks in an EFG body and
//! their growth.
//!
//! ```toml
//! [[body.crack]]
//! points = [[0.0, 0.5], [0.2, 0.5]]   # a mouth on the boundary, a tip inside
//! spacing = 0.01                      # node spacing along the crack
//! width = 0.04                        # width of the refined band (default 4 × spacing)
//! friction = 0.6                      # of the faces in contact (default 0)
//! face_stiffness = 1.0e14             # Pa/m (default 100 E / spacing)
//! [body.fracture]
//! toughness = 2.0e6                   # K_Ic
//! increment = 0.02                    # Δa (default: 5 × the tip's node spacing)
//! max_increments = 50
//! every = 10                          # dynamic runs: look every 10 steps
//! ```
//! Every field is documented in `docs/scenario.md`.

use super::Problems;
use super::body::{BodySpec, Method};
use crate::continuum::{CrackShape, Fracture};
use crate::efg::body::rectangle_polygon;
use crate::geom::Vec2;
use crate::geom::crack::{Crack, check};
use crate::geom::polygon::Domain;
use serde::Deserialize;

/// One crack of a body.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CrackSpec {
    /// The polyline: each end a tip inside the body or a mouth on its
    /// boundary (at least one tip).
    pub points: Vec<[f64; 2]>,
    /// Node spacing along the crack (default: the body's).
    pub spacing: Option<f64>,
    /// Width of the band at `spacing` on each side (default 4 × spacing).
    pub width: Option<f64>,
    /// Friction coefficient of the faces in contact (default 0).
    #[serde(default)]
    pub friction: f64,
    /// Stiffness of the faces in contact, stress per length (default
    /// 100 E / the crack's node spacing).
    pub face_stiffness: Option<f64>,
}

/// Crack growth by the maximum hoop-stress criterion.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FractureSpec {
    /// Fracture toughness `K_Ic` (stress·√length).
    pub toughness: f64,
    /// Length added to a tip per growth (default: the outer radius of the
    /// tip's interaction-integral ring, 5 × its node spacing).
    pub increment: Option<f64>,
    /// Most increments per tip over the run (default 50).
    #[serde(default = "default_max_increments")]
    pub max_increments: usize,
    /// Dynamic runs: look at the tips every this many steps (default 1).
    #[serde(default = "one")]
    pub every: usize,
}

fn default_max_increments() -> usize {
    50
}
fn one() -> usize {
    1
}

impl CrackSpec {
    /// The physics' crack shape.
    pub fn shape(&self) -> CrackShape {
        CrackShape {
            crack: Crack::new(self.points.iter().map(|&p| p.into()).collect()),
            spacing: self.spacing,
            width: self.width.unwrap_or(4.0 * self.spacing.unwrap_or(0.0)),
            friction: self.friction,
            face_stiffness: self.face_stiffness,
        }
    }
}

impl FractureSpec {
    /// The physics' growth parameters.
    pub fn params(&self) -> Fracture {
        Fracture {
            toughness: self.toughness,
            increment: self.increment,
            max_increments: self.max_increments,
            every: self.every,
        }
    }
}

/// The domain a body's cracks live in (its polygon, or its rectangle as
/// the polygon it is meshed as) and its node spacing; `None` when the
/// body's own checks fail.
fn body_domain(b: &BodySpec, polygon: Option<&Domain>) -> Option<(Domain, f64)> {
    match (polygon, b.spacing) {
        (Some(d), Some(h)) => Some((d.clone(), h)),
        (Some(_), None) => None,
        (None, _) => rectangle_polygon(&b.rectangle, b.nodes)
            .ok()
            .map(|p| (p.domain, p.spacing)),
    }
}

/// Checks of body `i`'s cracks and growth.
pub fn validate(i: usize, b: &BodySpec, polygon: Option<&Domain>, p: &mut Problems) {
    let at = |f: &str| format!("body.{i}.{f}");
    if b.crack.is_empty() {
        p.check(
            b.fracture.is_none(),
            at("fracture"),
            "crack growth needs at least one `[[body.crack]]`",
        );
        return;
    }
    if b.method != Method::Efg {
        p.push(
            at("crack"),
            "cracks are for EFG bodies (the meshfree shape functions follow them); use `method = \"efg\"`",
        );
        return;
    }
    let Some((domain, h)) = body_domain(b, polygon) else {
        return;
    };
    for (k, c) in b.crack.iter().enumerate() {
        let at = |f: &str| format!("body.{i}.crack.{k}.{f}");
        if let Some(sp) = c.spacing {
            let ok = sp.is_finite() && sp > 0.0 && sp < h;
            p.check(
                ok,
                at("spacing"),
                format!("must be > 0 and below the body's node spacing {h} (got {sp})"),
            );
        }
        p.check(
            c.friction.is_finite() && c.friction >= 0.0,
            at("friction"),
            format!("must be a finite number ≥ 0 (got {})", c.friction),
        );
        if let Some(k) = c.face_stiffness {
            p.positive(k, at("face_stiffness"));
        }
        if let Some(w) = c.width {
            let ok = w.is_finite() && w > 0.0;
            p.check(
                ok,
                at("width"),
                format!("must be a finite number > 0 (got {w})"),
            );
            p.check(
                c.spacing.is_some(),
                at("width"),
                "`width` is the width of the band at `spacing`: give `spacing` too",
            );
        }
        if let Some(sp) = c.spacing
            && sp > 0.0
        {
            let d = domain.area();
            let len: f64 = c
                .points
                .windows(2)
                .map(|w| (Vec2::from(w[1]) - Vec2::from(w[0])).norm())
                .sum();
            let w = c.width.unwrap_or(4.0 * sp);
            let n = d.min(2.0 * (w + h) * (len + 2.0 * w)) / (sp * sp);
            p.check(
                n <= 5e6,
                at("spacing"),
                format!("about {n:.1e} nodes along the crack: at most 5·10⁶"),
            );
        }
    }
    let cracks: Vec<Crack> = b.crack.iter().map(|c| c.shape().crack).collect();
    if let Err(e) = check(&domain, &cracks) {
        p.push(format!("body.{i}.crack.{}.points", e.crack), e.message);
    }
    if let Some(f) = &b.fracture {
        let at = |f: &str| format!("body.{i}.fracture.{f}");
        p.positive(f.toughness, at("toughness"));
        if let Some(da) = f.increment {
            p.check(
                da.is_finite() && da > 0.0 && da >= 0.5 * smallest_spacing(b, h),
                at("increment"),
                format!(
                    "must be a finite number of at least half the crack's node spacing ({}) (got {da})",
                    0.5 * smallest_spacing(b, h)
                ),
            );
        }
        p.check(
            (1..=10_000).contains(&f.max_increments),
            at("max_increments"),
            format!("must be between 1 and 10000 (got {})", f.max_increments),
        );
        p.check(
            f.every >= 1,
            at("every"),
            "must be ≥ 1 (steps between looks at the tips)",
        );
    }
}

/// The finest crack spacing of a body (its own spacing if none is finer).
fn smallest_spacing(b: &BodySpec, h: f64) -> f64 {
    b.crack.iter().filter_map(|c| c.spacing).fold(h, f64::min)
}
