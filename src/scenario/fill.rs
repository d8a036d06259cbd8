//! Where a preparation will put its discs, known before it runs: a body
//! there would end up with discs inside it (the preparation does not see
//! the bodies), which `check` and `run` report before spending any step.
//!
//! - `method = "grow"` fills the whole `box`.
//! - `method = "deposit"` settles the discs to the bottom of the box (along
//!   gravity). However they pack, they cover at least the depth at which
//!   the box holds their area at the densest packing of discs,
//!   `π/(2√3)` ≈ 0.907 (hexagonal, equal discs; the small overlaps that
//!   carry the weight are far below the margin). A body reaching into that
//!   layer is certainly in the bed. The surface itself lies higher, where
//!   the discs' area fills the box at the packing fraction of a random
//!   deposit, about 0.65 (short, frictional) to 0.85 (frictionless); the
//!   message gives that range.
//!
//! A body with `overlapping_discs = "remove"` is placed after the
//! preparation instead: it is not reported.

use super::body::{BodySpec, OverlappingDiscs};
use super::build::preparation;
use super::granular::{DiscsSpec, Packing};
use super::{Invalid, Scenario};
use crate::dem::packing::DiscRow;
use crate::geom::Vec2;
use crate::geom::polygon::{clip_half_plane, signed_area2};

/// The packing fraction below which no packing of discs can be:
/// hexagonal packing of equal discs, `π/(2√3)`.
pub const DENSEST: f64 = 0.906_899_682_117_108_9;

/// The range of packing fractions of a random gravity deposit of discs
/// (frictional, polydisperse: looser; frictionless: denser), for the
/// estimated surface.
pub const DEPOSIT_RANGE: [f64; 2] = [0.65, 0.85];

/// The layer a deposit fills: its direction `up` (against gravity) and the
/// box's lowest point along it.
struct Layer {
    corners: [Vec2; 4],
    up: Vec2,
    bottom: f64,
    /// Height of the box along `up`.
    height: f64,
}

impl Layer {
    fn new(lo: Vec2, hi: Vec2, gravity: [f64; 2]) -> Layer {
        let g = Vec2::from(gravity);
        let up = if g.norm2() > 0.0 {
            g * (-1.0 / g.norm())
        } else {
            Vec2::new(0.0, 1.0)
        };
        let corners = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
        let levels = corners.map(|c| up.dot(c));
        let bottom = levels.iter().copied().fold(f64::INFINITY, f64::min);
        let top = levels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Layer {
            corners,
            up,
            bottom,
            height: top - bottom,
        }
    }

    /// The part of the box up to `h` above its bottom.
    fn below(&self, h: f64) -> Vec<Vec2> {
        clip_half_plane(&self.corners, self.up, self.bottom + h)
    }

    /// The height at which the part of the box below holds `area`
    /// (bisection; the whole box when it holds less).
    fn height_holding(&self, area: f64) -> f64 {
        let (mut a, mut b) = (0.0, self.height);
        if 0.5 * signed_area2(&self.below(b)) <= area {
            return b;
        }
        for _ in 0..100 {
            let m = 0.5 * (a + b);
            if 0.5 * signed_area2(&self.below(m)) < area {
                a = m;
            } else {
                b = m;
            }
        }
        b
    }

    /// `h` above the bottom as the user reads it: `y ≈ …` when gravity is
    /// along −y, else the depth along gravity.
    fn describe(&self, h: f64) -> String {
        if self.up == Vec2::new(0.0, 1.0) {
            format!("y ≈ {:.4}", self.bottom + h)
        } else {
            format!("{h:.4} above the box's lowest corner (along −gravity)")
        }
    }
}

/// The loops of a body: its rectangle, or its polygon's outline and holes
/// (holes clockwise, so that signed areas subtract them).
fn loops(b: &BodySpec) -> Vec<Vec<Vec2>> {
    match b.domain().ok().flatten() {
        Some(d) => d.loops.into_iter().map(|l| l.points).collect(),
        None => {
            let lo = Vec2::from(b.rectangle.origin);
            let hi = lo + Vec2::from(b.rectangle.size);
            vec![vec![lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)]]
        }
    }
}

/// Area of the body inside the convex region `region` (counter-clockwise).
fn area_inside(b: &BodySpec, region: &[Vec2]) -> f64 {
    let n = region.len();
    let clipped = |l: Vec<Vec2>| {
        (0..n).fold(l, |l, i| {
            let (a, c) = (region[i], region[(i + 1) % n]);
            // inside = left of a → c: (c − a) × (x − a) ≥ 0
            let normal = -(c - a).perp();
            clip_half_plane(&l, normal, normal.dot(a))
        })
    };
    0.5 * loops(b)
        .into_iter()
        .map(|l| signed_area2(&clipped(l)))
        .sum::<f64>()
}

/// Bodies (without `overlapping_discs = "remove"`) in the region the
/// scenario's deposit or growth will certainly fill with the discs `rows`
/// (as generated: their radii are final): the first one as an error at
/// its `rectangle` or `outline`, with what to do. `Ok` without such a
/// preparation.
pub fn check_bodies(sc: &Scenario, rows: &[DiscRow]) -> Result<(), Invalid> {
    let (Some(prep), Some(g)) = (preparation(sc), sc.granular.as_ref()) else {
        return Ok(());
    };
    let DiscsSpec::Table(t) = &g.discs else {
        return Ok(());
    };
    let Some([a, b]) = t.region else {
        return Ok(());
    };
    let (lo, hi) = (Vec2::from(a), Vec2::from(b));
    let layer = Layer::new(lo, hi, sc.simulation.gravity);
    let area: f64 = rows.iter().map(|r| std::f64::consts::PI * r.r * r.r).sum();
    let (region, what) = match prep.method {
        Packing::Grow => (
            layer.below(layer.height),
            "the radius growth of [granular] discs fills its whole `box`".to_string(),
        ),
        _ => {
            let h = layer.height_holding(area / DENSEST);
            let surface = DEPOSIT_RANGE.map(|f| layer.height_holding(area / f));
            (
                layer.below(h),
                format!(
                    "the gravity deposit of [granular] discs fills the box at least up to {} (their area at the densest packing of discs); its surface will be near {} (packing fraction {}) to {} ({})",
                    layer.describe(h),
                    layer.describe(surface[1]),
                    DEPOSIT_RANGE[1],
                    layer.describe(surface[0]),
                    DEPOSIT_RANGE[0],
                ),
            )
        }
    };
    for (i, body) in sc.body.iter().enumerate() {
        if body.overlapping_discs == OverlappingDiscs::Remove {
            continue;
        }
        let own: f64 = loops(body).iter().map(|l| 0.5 * signed_area2(l)).sum();
        if area_inside(body, &region) > 1e-9 * own {
            let field = if body.is_polygon() {
                "outline"
            } else {
                "rectangle"
            };
            return Err(Invalid {
                path: format!("body.{i}.{field}"),
                message: format!(
                    "body `{}` lies where discs will be: {what}, and the preparation does not see the bodies. Set `overlapping_discs = \"remove\"` on the body to place it after the preparation, removing the discs it then overlaps, or move it out of that region",
                    body.name
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_layer_holds_the_area_asked_for() {
        let l = Layer::new(Vec2::new(0.0, 0.0), Vec2::new(2.0, 1.0), [0.0, -9.81]);
        assert_eq!((l.bottom, l.height), (0.0, 1.0));
        assert!((l.height_holding(0.5) - 0.25).abs() < 1e-12);
        assert_eq!(l.height_holding(5.0), 1.0);
        // gravity along +x: the layer grows from the right side
        let l = Layer::new(Vec2::new(0.0, 0.0), Vec2::new(2.0, 1.0), [1.0, 0.0]);
        assert!((l.height_holding(0.5) - 0.5).abs() < 1e-12);
        let r = l.below(0.5);
        assert!(r.iter().all(|p| p.x >= 1.5 - 1e-12));
    }
}
