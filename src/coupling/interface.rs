//! Disc–boundary contact detection on a body's contact boundary (§2.4.1,
//! Figs. 4–5), on the body's true displaced boundary (ERRATA E7).
//!
//! The paper finds the nearest boundary node, then the adjacent segment
//! whose far node is nearer (Fig. 4), and distinguishes particle–segment
//! contacts (Fig. 5a) from particle–point contacts (Fig. 5b) so that a disc
//! sitting on a node is not counted twice. The same result, robust to ties
//! and to uneven node spacing, is the *closest feature* of the polyline:
//! the closest point `H` of the whole chain to the disc centre `O` lies
//! either inside one segment (particle–segment) or on a vertex
//! (particle–point). Each disc gets at most one contact per chain, and the
//! contact is keyed by `(disc, chain)`, so a disc sliding from one segment
//! to the next keeps its shear history.

use crate::continuum::{BoundaryChain, ChainStiffness};
use crate::geom::{Vec2, closest_on_segment};

/// Which primitive of the boundary the disc touches (Fig. 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Feature {
    /// Inside segment `i` (between chain points `i` and `i + 1`), Fig. 5a.
    Segment(usize),
    /// On chain point `j`, Fig. 5b.
    Point(usize),
}

/// A disc touching a boundary chain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touch {
    /// The segment or chain point touched (Fig. 5).
    pub feature: Feature,
    /// Segment holding the contact point and the parameter `s ∈ [0, 1]` on
    /// it (for a point contact: an adjacent segment, `s` = 0 or 1).
    pub seg: usize,
    /// Parameter `s ∈ [0, 1]` of `H` on segment `seg`, from its first point.
    pub s: f64,
    /// Contact point `H` on the current boundary.
    pub point: Vec2,
    /// Unit normal from the boundary towards the disc centre.
    pub normal: Vec2,
    /// Overlap `δ = r − (O − H)·n` (> 0 when in contact; > r when the
    /// centre has passed through the boundary).
    pub overlap: f64,
    /// Material (reference) coordinates `X_H` of the contact point: where the
    /// body's shape functions are evaluated for the velocity of `H` and for
    /// distributing the reaction (Eqs. 41, 46, ERRATA E7).
    pub material: Vec2,
}

impl Touch {
    /// The geometric stiffness of a segment contact carrying the normal
    /// force `force` (elastic, ≥ 0) from a disc centred at `centre`, for the
    /// body's implicit step ([`ChainStiffness`] on chain `index`).
    ///
    /// Why: the overlap `δ = r − g`, `g = (O − A)·ν`, depends on the turn of
    /// the segment `A → B` as well as on the motion of `H`. Over a step with
    /// the disc fixed, for increments `ΔA`, `ΔB` of the segment ends,
    /// `φ = ν·(ΔB − ΔA)/L` (the segment's turn) and `τ = t·((1 − s)ΔA + sΔB)`
    /// (the tangential motion of `H`), the second variation of the contact
    /// energy `½ k_n δ²` is `k_n (Δg)² + F_n (g φ² − 2 τ φ)`. The first term
    /// is the normal spring of [`super::implicit::Linear`] (normal fixed over
    /// the step); the second is this stiffness. Left out, it acts one step
    /// late — the next step's detection turns the normal and moves `H` along
    /// the boundary by `g φ` — and a stiffness that acts late is a negative
    /// dashpot of about `F_n g Δt` on the boundary's rotation: energy grows
    /// in the fast local rotations of a refined body, at a free corner
    /// first, where they are softest. Taken into the step (the body solves
    /// with `A + V C Vᵀ`), the turn of the normal is implicit like the
    /// overlap, whatever the body's resolution.
    ///
    /// A point contact (Fig. 5b) has `g = |O − H|` and the radial normal:
    /// its geometric stiffness `−F_n/g` on the vertex's tangential motion is
    /// negative and, acting late, only dissipates (a dashpot of about
    /// `F_n Δt/g`, 0.03 N s/m in Example 1 at Δt = 1e-5 s); `None`. Also
    /// `None` without force or with the centre inside the body.
    pub fn geometric_stiffness(
        &self,
        chain: &BoundaryChain,
        index: usize,
        centre: Vec2,
        force: f64,
    ) -> Option<ChainStiffness> {
        let Feature::Segment(i) = self.feature else {
            return None;
        };
        let gap = (centre - self.point).dot(self.normal);
        let (a, b) = (chain.current[i], chain.current[i + 1]);
        let l = (b - a).norm();
        if !(force > 0.0 && gap > 0.0 && l > 0.0) {
            return None;
        }
        let (t, nu, s) = ((b - a) * (1.0 / l), self.normal, self.s);
        Some(ChainStiffness {
            chain: index,
            psi: [
                [(i, nu * (-1.0 / l)), (i + 1, nu * (1.0 / l))],
                [(i, t * (1.0 - s)), (i + 1, t * s)],
            ],
            c: [[force * gap, -force], [-force, 0.0]],
        })
    }
}

/// Outward unit normal of the segment `a → b` of a chain that has the body
/// on its left.
#[inline]
pub fn outward_normal(a: Vec2, b: Vec2) -> Vec2 {
    let t = b - a;
    let l = t.norm();
    if l > 0.0 {
        Vec2::new(t.y / l, -t.x / l)
    } else {
        Vec2::ZERO
    }
}

/// The contact of a disc (centre `c`, radius `r`) with `chain`, if any.
/// Cost: linear in the number of segments; the caller prunes with a
/// bounding-box test when chains are long.
pub fn detect(chain: &BoundaryChain, c: Vec2, r: f64) -> Option<Touch> {
    detect_near(chain, c, r, 0..chain.segments())
}

/// [`detect`] over the segments `near` (ascending) only: the same result
/// when they include every segment within `2r` of `c` (e.g. from a
/// [`SegmentGrid`](super::segments::SegmentGrid)).
pub fn detect_near(
    chain: &BoundaryChain,
    c: Vec2,
    r: f64,
    near: impl IntoIterator<Item = usize>,
) -> Option<Touch> {
    let pts = &chain.current;
    let nseg = chain.segments();
    // Closest point over the whole chain; on a tie the first segment wins,
    // which makes a point contact at a shared vertex unique.
    let mut best: Option<(usize, f64, Vec2, f64)> = None;
    for i in near {
        let (s, q) = closest_on_segment(c, pts[i], pts[i + 1]);
        let d2 = (c - q).norm2();
        if best.is_none_or(|b| d2 < b.3) {
            best = Some((i, s, q, d2));
        }
    }
    let (seg, s, point, d2) = best?;
    if d2 > r * r * 4.0 {
        return None; // far away, whatever the side
    }
    let vertex = if s <= 0.0 {
        Some(seg)
    } else if s >= 1.0 {
        Some(seg + 1)
    } else {
        None
    };
    let (feature, outward) = match vertex {
        None => (
            Feature::Segment(seg),
            outward_normal(pts[seg], pts[seg + 1]),
        ),
        Some(j) => {
            // Mean outward normal of the segments meeting at vertex j (both
            // ends of a closed chain are the same vertex, where its last
            // and first segments meet)
            let closed = chain.is_closed();
            let before = if j > 0 {
                Some(j - 1)
            } else {
                closed.then_some(nseg - 1)
            };
            let after = if j < nseg {
                Some(j)
            } else {
                closed.then_some(0)
            };
            let mut n = Vec2::ZERO;
            for i in before.into_iter().chain(after) {
                n += outward_normal(pts[i], pts[i + 1]);
            }
            let l = n.norm();
            (Feature::Point(j), if l > 0.0 { n * (1.0 / l) } else { n })
        }
    };
    let d = c - point;
    let dist = d2.sqrt();
    let (normal, gap) = match feature {
        // A segment contact: the normal is the segment's own normal; the
        // signed gap is negative when the centre is inside the body.
        Feature::Segment(_) => (outward, d.dot(outward)),
        // A point contact: the normal points from the vertex to the centre
        // (Fig. 5b), unless the centre is inside the body.
        Feature::Point(_) => {
            if dist > 1e-12 * r && d.dot(outward) >= 0.0 {
                (d * (1.0 / dist), dist)
            } else {
                (outward, -dist)
            }
        }
    };
    let overlap = r - gap;
    (overlap > 0.0).then(|| Touch {
        feature,
        seg,
        s,
        point,
        normal,
        overlap,
        material: chain.material_point(seg, s),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Top edge of a body occupying y < 0, traversed right to left so the
    /// body is on the left (counter-clockwise around the body).
    fn top_edge(n: usize) -> BoundaryChain {
        BoundaryChain::new((0..n).rev().map(|i| Vec2::new(i as f64, 0.0)).collect())
    }

    #[test]
    fn disc_above_a_segment_is_a_segment_contact() {
        let ch = top_edge(5);
        let t = detect(&ch, Vec2::new(2.3, 0.4), 0.5).unwrap();
        assert!(matches!(t.feature, Feature::Segment(_)));
        assert!((t.overlap - 0.1).abs() < 1e-14);
        assert!((t.normal - Vec2::new(0.0, 1.0)).norm() < 1e-14);
        assert!((t.point - Vec2::new(2.3, 0.0)).norm() < 1e-14);
        assert!((t.material - Vec2::new(2.3, 0.0)).norm() < 1e-14);
    }

    #[test]
    fn disc_on_a_node_gets_exactly_one_point_contact() {
        let ch = top_edge(5);
        let t = detect(&ch, Vec2::new(2.0, 0.45), 0.5).unwrap();
        assert_eq!(t.feature, Feature::Point(2));
        assert!((t.overlap - 0.05).abs() < 1e-14);
        assert!((t.normal - Vec2::new(0.0, 1.0)).norm() < 1e-14);
    }

    #[test]
    fn sliding_across_nodes_keeps_overlap_and_normal_continuous() {
        let ch = top_edge(6);
        let mut prev: Option<Touch> = None;
        for k in 0..=400 {
            let x = 0.5 + 4.0 * k as f64 / 400.0;
            let t = detect(&ch, Vec2::new(x, 0.4), 0.5).unwrap();
            assert!((t.overlap - 0.1).abs() < 1e-14, "x = {x}");
            assert!((t.normal - Vec2::new(0.0, 1.0)).norm() < 1e-14);
            if let Some(p) = prev {
                assert!((t.point - p.point).norm() < 0.011 + 1e-12);
            }
            prev = Some(t);
        }
    }

    #[test]
    fn convex_corner_gives_a_point_contact_with_a_radial_normal() {
        // Body [0,1]×[-1,0]: chain goes up the right edge then left along the top.
        let ch = BoundaryChain::new(vec![
            Vec2::new(1.0, -1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ]);
        let c = Vec2::new(1.3, 0.4);
        let t = detect(&ch, c, 0.6).unwrap();
        assert_eq!(t.feature, Feature::Point(1));
        assert!((t.overlap - (0.6 - 0.5)).abs() < 1e-14);
        assert!((t.normal - Vec2::new(0.6, 0.8)).norm() < 1e-14);
        // Just inside the end, above the top: a segment contact on the top.
        let t = detect(&ch, Vec2::new(1.0 - 1e-6, 0.05), 0.1).unwrap();
        assert_eq!(t.feature, Feature::Segment(1));
        assert!((t.overlap - 0.05).abs() < 1e-14);
    }

    /// The geometric stiffness plus the normal spring is the second
    /// variation of the contact energy `½ k_n δ²` in the motion of the
    /// segment's ends (central differences of the exact overlap, a tilted
    /// segment, the contact point off its middle).
    #[test]
    fn geometric_stiffness_is_the_rest_of_the_energy_hessian() {
        let (a, b) = (Vec2::new(1.0, 0.2), Vec2::new(-0.5, 0.5));
        let ch = BoundaryChain::new(vec![a, b, Vec2::new(-1.5, 0.4)]);
        let (o, r, kn) = (Vec2::new(0.62, 0.81), 0.6, 1e3);
        let t = detect(&ch, o, r).unwrap();
        assert_eq!(t.feature, Feature::Segment(0));
        let force = kn * t.overlap;
        let k = t.geometric_stiffness(&ch, 7, o, force).unwrap();
        assert_eq!(k.chain, 7);
        // exact overlap with the ends moved by (da, db)
        let energy = |da: Vec2, db: Vec2| {
            let (a1, b1) = (a + da, b + db);
            let gap = (o - a1).dot(outward_normal(a1, b1));
            0.5 * kn * (r - gap).powi(2)
        };
        for dir in [
            [Vec2::new(1.0, 0.0), Vec2::ZERO],
            [Vec2::new(0.3, -0.7), Vec2::new(-0.2, 0.9)],
            [Vec2::new(0.0, 1.0), Vec2::new(0.0, -1.0)],
            [Vec2::new(-0.6, 0.1), Vec2::new(0.4, 0.5)],
        ] {
            let h = 1e-4;
            let fd = (energy(dir[0] * h, dir[1] * h) - 2.0 * energy(Vec2::ZERO, Vec2::ZERO)
                + energy(dir[0] * -h, dir[1] * -h))
                / (h * h);
            let dg = -t.normal.dot(dir[0] * (1.0 - t.s) + dir[1] * t.s);
            let psi = k
                .psi
                .map(|p| p.iter().map(|&(i, c)| c.dot(dir[i])).sum::<f64>());
            let mut quad = kn * dg * dg;
            for (x, row) in k.c.iter().enumerate() {
                for (y, c) in row.iter().enumerate() {
                    quad += c * psi[x] * psi[y];
                }
            }
            assert!((fd - quad).abs() < 1e-5 * kn, "{dir:?}: {fd} vs {quad}");
        }
        // point contacts, no force, the centre inside: none
        let corner =
            BoundaryChain::new(vec![Vec2::new(1.0, -1.0), Vec2::new(1.0, 0.0), Vec2::ZERO]);
        let c = Vec2::new(1.3, 0.4);
        let tp = detect(&corner, c, 0.6).unwrap();
        assert!(tp.geometric_stiffness(&corner, 0, c, 1.0).is_none());
        assert!(t.geometric_stiffness(&ch, 0, o, 0.0).is_none());
    }

    /// Both ends of a closed chain are one convex corner: a disc beside it
    /// (its centre level with the bottom edge, just below its extension)
    /// gets the corner's radial normal, not the bottom edge's normal with
    /// the centre taken as inside (an overlap of r + distance: found in a
    /// footing run, a force of 2 k_n r for one step and 7 J created).
    #[test]
    fn both_ends_of_a_closed_chain_are_one_corner() {
        // the unit square, counter-clockwise from its bottom-left corner
        let ch = BoundaryChain::new(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.0, 0.0),
        ]);
        assert!(ch.is_closed());
        for c in [
            Vec2::new(-0.3, -1e-9),
            Vec2::new(-0.3, 1e-9),
            Vec2::new(-1e-9, -0.3),
        ] {
            let t = detect(&ch, c, 0.31).unwrap();
            assert!(
                matches!(t.feature, Feature::Point(0) | Feature::Point(4)),
                "{c:?}"
            );
            assert!(
                (t.overlap - (0.31 - c.norm())).abs() < 1e-12,
                "{c:?}: {}",
                t.overlap
            );
            assert!((t.normal - c * (1.0 / c.norm())).norm() < 1e-8, "{c:?}");
        }
        // an open chain's end keeps its one segment's normal (above its
        // extension the centre counts as inside)
        let open = BoundaryChain::new(ch.reference[..4].to_vec());
        assert!(!open.is_closed());
        let t = detect(&open, Vec2::new(-0.3, 1e-9), 0.31).unwrap();
        assert!((t.overlap - (0.31 + 0.3)).abs() < 1e-8);
    }

    #[test]
    fn centre_through_the_boundary_has_overlap_beyond_the_radius() {
        let ch = top_edge(5);
        let t = detect(&ch, Vec2::new(2.5, -0.1), 0.5).unwrap();
        assert!((t.overlap - 0.6).abs() < 1e-14);
        assert!((t.normal - Vec2::new(0.0, 1.0)).norm() < 1e-14);
    }

    #[test]
    fn no_contact_when_apart_and_material_point_follows_reference() {
        let mut ch = top_edge(3);
        assert!(detect(&ch, Vec2::new(1.0, 0.6), 0.5).is_none());
        // Deform: shift current positions down by 0.2; the material point of
        // a contact is still the reference point.
        for p in &mut ch.current {
            p.y -= 0.2;
        }
        let t = detect(&ch, Vec2::new(0.5, 0.2), 0.5).unwrap();
        assert!((t.overlap - 0.1).abs() < 1e-14);
        assert!((t.material - Vec2::new(0.5, 0.0)).norm() < 1e-14);
    }
}
