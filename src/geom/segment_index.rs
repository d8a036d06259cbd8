//! The segments of closed loops in an R-tree (the `rstar` crate), so that
//! the queries a polygon body makes of its boundary — is a point inside,
//! how far is the boundary, which segments are near a box — cost
//! `O(log N)` plus what they find instead of `O(N)` each: a 1 000-segment
//! hole or a 10 000-vertex outline is prepared in `O(N log N)`.

use super::Vec2;
use super::polygon::{Loop, on_segment};
use rstar::{AABB, PointDistance, RTree, RTreeObject};

/// One segment `a → b` of loop `lp` (segment `seg` of it).
#[derive(Debug, Clone, Copy)]
pub struct Segment {
    /// Start.
    pub a: Vec2,
    /// End.
    pub b: Vec2,
    /// The loop (0 outline, k hole k).
    pub lp: usize,
    /// The segment of the loop.
    pub seg: usize,
}

impl RTreeObject for Segment {
    type Envelope = AABB<[f64; 2]>;
    fn envelope(&self) -> Self::Envelope {
        AABB::from_corners(self.a.to_array(), self.b.to_array())
    }
}

impl PointDistance for Segment {
    fn distance_2(&self, p: &[f64; 2]) -> f64 {
        let p = Vec2::new(p[0], p[1]);
        (p - super::closest_on_segment(p, self.a, self.b).1).norm2()
    }
}

/// The boxes a segment passes through ([`SegmentIndex::along`]).
struct Along {
    a: Vec2,
    b: Vec2,
    tol: f64,
}

impl Along {
    /// Does the segment meet the box (widened by the tolerance)? The boxes
    /// overlap and the box's corners are not all strictly on one side of
    /// the segment's line.
    fn meets(&self, e: &AABB<[f64; 2]>) -> bool {
        let (lo, hi) = (e.lower(), e.upper());
        let (lo, hi) = (
            Vec2::new(lo[0] - self.tol, lo[1] - self.tol),
            Vec2::new(hi[0] + self.tol, hi[1] + self.tol),
        );
        let (a, b) = (self.a, self.b);
        if a.x.max(b.x) < lo.x || a.x.min(b.x) > hi.x || a.y.max(b.y) < lo.y || a.y.min(b.y) > hi.y
        {
            return false;
        }
        let d = b - a;
        let side = |x: f64, y: f64| d.cross(Vec2::new(x, y) - a);
        let s = [
            side(lo.x, lo.y),
            side(hi.x, lo.y),
            side(lo.x, hi.y),
            side(hi.x, hi.y),
        ];
        !(s.iter().all(|&v| v > 0.0) || s.iter().all(|&v| v < 0.0))
    }
}

impl rstar::SelectionFunction<Segment> for Along {
    fn should_unpack_parent(&self, e: &AABB<[f64; 2]>) -> bool {
        self.meets(e)
    }
    fn should_unpack_leaf(&self, s: &Segment) -> bool {
        self.meets(&s.envelope())
    }
}

/// The segments of a set of loops, indexed.
#[derive(Clone)]
pub struct SegmentIndex {
    tree: RTree<Segment>,
    /// Largest x of every segment (the end of a ray cast to +x).
    x_max: f64,
    /// Reach of the point-on-segment tolerance ([`on_segment`]): boxes
    /// are widened by it so no segment within tolerance is missed.
    tol: f64,
}

impl std::fmt::Debug for SegmentIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "SegmentIndex({} segments)", self.tree.size())
    }
}

impl SegmentIndex {
    /// Index every segment of `loops` (segment `i` of a loop from point `i`
    /// to point `i + 1`, as stored).
    pub fn new(loops: &[Loop]) -> SegmentIndex {
        let segs: Vec<Segment> = loops
            .iter()
            .enumerate()
            .flat_map(|(lp, l)| {
                (0..l.len()).map(move |seg| {
                    let (a, b) = l.segment(seg);
                    Segment { a, b, lp, seg }
                })
            })
            .collect();
        let x_max = segs
            .iter()
            .map(|s| s.a.x.max(s.b.x))
            .fold(f64::NEG_INFINITY, f64::max);
        let longest = segs.iter().map(|s| (s.b - s.a).norm()).fold(0.0, f64::max);
        SegmentIndex {
            tree: RTree::bulk_load(segs),
            x_max,
            tol: 1e-9 * longest,
        }
    }

    /// Every segment whose bounding box meets the box `[lo, hi]` widened
    /// by the tolerance.
    pub fn in_box(&self, lo: Vec2, hi: Vec2) -> impl Iterator<Item = &Segment> {
        let e = AABB::from_corners(
            [lo.x - self.tol, lo.y - self.tol],
            [hi.x + self.tol, hi.y + self.tol],
        );
        self.tree.locate_in_envelope_intersecting(&e)
    }

    /// Every segment near the segment `a b` (bounding boxes meet).
    pub fn near_segment(&self, a: Vec2, b: Vec2) -> impl Iterator<Item = &Segment> {
        self.in_box(
            Vec2::new(a.x.min(b.x), a.y.min(b.y)),
            Vec2::new(a.x.max(b.x), a.y.max(b.y)),
        )
    }

    /// Every segment whose bounding box the segment `a b` passes through
    /// (widened by the tolerance): the candidates for crossing it. The
    /// tree is searched along the segment itself, not its bounding box,
    /// so a path running beside a dense boundary finds few.
    pub fn along(&self, a: Vec2, b: Vec2) -> impl Iterator<Item = &Segment> {
        self.tree.locate_with_selection_function(Along {
            a,
            b,
            tol: self.tol,
        })
    }

    /// Is `p` on a segment (within the [`on_segment`] tolerance)?
    pub fn on_boundary(&self, p: Vec2) -> bool {
        self.in_box(p, p).any(|s| on_segment(s.a, s.b, p))
    }

    /// The segments a ray from `p` towards +x crosses (the crossing-number
    /// rule: one end strictly above `p`, the other not, the crossing right
    /// of `p`), each as its loop.
    pub fn crossings(&self, p: Vec2) -> impl Iterator<Item = usize> + '_ {
        let e = AABB::from_corners([p.x - self.tol, p.y], [self.x_max.max(p.x), p.y]);
        self.tree
            .locate_in_envelope_intersecting(&e)
            .filter(move |s| {
                let (a, b) = (s.a, s.b);
                (a.y > p.y) != (b.y > p.y) && a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) > p.x
            })
            .map(|s| s.lp)
    }

    /// Distance from `p` to the nearest segment (∞ without segments).
    pub fn distance(&self, p: Vec2) -> f64 {
        self.tree
            .nearest_neighbor(&p.to_array())
            .map_or(f64::INFINITY, |s| {
                (p - super::closest_on_segment(p, s.a, s.b).1).norm()
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::polygon::{circle, inside_loop};

    #[test]
    fn queries_agree_with_a_scan_of_every_segment() {
        let outline = Loop {
            points: vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(4.0, 0.0),
                Vec2::new(4.0, 2.0),
                Vec2::new(2.0, 2.0),
                Vec2::new(2.0, 4.0),
                Vec2::new(0.0, 4.0),
            ],
        };
        let mut hole = circle(Vec2::new(1.0, 1.0), 0.5, 100);
        hole.reverse();
        let loops = [outline, Loop { points: hole }];
        let idx = SegmentIndex::new(&loops);
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..3000 {
            // random points, and points exactly on vertices and segments
            let p = match k % 3 {
                0 => Vec2::new(-0.5 + 5.0 * next(), -0.5 + 5.0 * next()),
                1 => loops[k % 2].points[k % loops[k % 2].len()],
                _ => {
                    let l = &loops[k % 2];
                    let (a, b) = l.segment(k % l.len());
                    a + (b - a) * next()
                }
            };
            let on = loops
                .iter()
                .any(|l| (0..l.len()).any(|i| on_segment(l.segment(i).0, l.segment(i).1, p)));
            assert_eq!(idx.on_boundary(p), on, "{p:?}");
            for (lp, l) in loops.iter().enumerate() {
                if !on {
                    let odd = idx.crossings(p).filter(|&m| m == lp).count() % 2 == 1;
                    assert_eq!(odd, inside_loop(&l.points, p), "{p:?} loop {lp}");
                }
            }
            let scan = loops
                .iter()
                .flat_map(|l| (0..l.len()).map(|i| l.segment(i)))
                .map(|(a, b)| (p - crate::geom::closest_on_segment(p, a, b).1).norm())
                .fold(f64::INFINITY, f64::min);
            assert_eq!(idx.distance(p), scan);
        }
    }
}
