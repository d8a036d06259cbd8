//! Polygonal domains: an outline and holes, each a closed loop of straight
//! segments, validated (simple, counter-clockwise outline, holes strictly
//! inside and disjoint), with point-in-domain and segment-crossing tests
//! (the visibility criterion of the EFG supports uses the latter).
//!
//! Storage convention: loop 0 is the outline, counter-clockwise; loops
//! `1..` are the holes, stored **clockwise** (reversed from the user's
//! counter-clockwise input), so the body is on the left of every segment
//! `points[i] → points[i + 1]` and the outward normal is the segment
//! direction rotated by −90°, as the contact chains expect.

use super::Vec2;
use super::segment_index::SegmentIndex;

/// A closed loop: segment `i` runs from `points[i]` to `points[(i + 1) % n]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Loop {
    /// Vertices (no repeated first point).
    pub points: Vec<Vec2>,
}

impl Loop {
    /// Number of segments (= vertices).
    pub fn len(&self) -> usize {
        self.points.len()
    }
    /// No vertex.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
    /// End points of segment `i`.
    pub fn segment(&self, i: usize) -> (Vec2, Vec2) {
        let n = self.points.len();
        (self.points[i % n], self.points[(i + 1) % n])
    }
    /// Twice the signed area (positive counter-clockwise).
    pub fn signed_area2(&self) -> f64 {
        (0..self.len())
            .map(|i| {
                let (a, b) = self.segment(i);
                a.cross(b)
            })
            .sum()
    }
}

/// A named set of boundary segments `(loop, segment)` in storage indexing.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedEdge {
    /// The name bcs and `contact_edges` refer to.
    pub name: String,
    /// `(loop, segment)` pairs, storage indexing (holes reversed).
    pub segments: Vec<(usize, usize)>,
}

/// An outline with holes and named edges: the domain Ω of a polygon body.
#[derive(Debug, Clone)]
pub struct Domain {
    /// Loop 0: outline (CCW); loops 1..: holes (stored CW).
    pub loops: Vec<Loop>,
    /// Named edges.
    pub edges: Vec<NamedEdge>,
    /// The loops' segments, indexed (as stored).
    index: SegmentIndex,
}

impl PartialEq for Domain {
    fn eq(&self, o: &Domain) -> bool {
        // the index is a function of the loops
        self.loops == o.loops && self.edges == o.edges
    }
}

/// Why a polygon was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PolygonError {
    /// Fewer than 3 vertices.
    #[error("{what} has {n} vertices; a loop needs at least 3")]
    TooFew {
        /// Which loop (`outline`, `hole 1`, …).
        what: String,
        /// Vertex count.
        n: usize,
    },
    /// A non-finite coordinate or a zero-length segment.
    #[error("{what}: {message}")]
    Degenerate {
        /// Which loop.
        what: String,
        /// What is wrong.
        message: String,
    },
    /// Two segments of one loop meet away from their common vertex.
    #[error(
        "{what} is not simple: segment {i} ({a:?} → {b:?}) intersects segment {j} ({c:?} → {d:?})"
    )]
    SelfIntersecting {
        /// Which loop.
        what: String,
        /// First segment (user indexing).
        i: usize,
        /// Second segment (user indexing).
        j: usize,
        /// Ends of segment i.
        a: [f64; 2],
        /// Ends of segment i.
        b: [f64; 2],
        /// Ends of segment j.
        c: [f64; 2],
        /// Ends of segment j.
        d: [f64; 2],
    },
    /// A loop given clockwise.
    #[error(
        "{what} is clockwise (signed area {area:.6e} < 0); give the vertices counter-clockwise (body on the left when walking along the outline; holes also counter-clockwise, as seen from their own inside)"
    )]
    Clockwise {
        /// Which loop.
        what: String,
        /// Signed area.
        area: f64,
    },
    /// A hole not strictly inside the outline, or overlapping another hole.
    #[error("{what}")]
    HolePlacement {
        /// What is wrong.
        what: String,
    },
    /// A named edge refers to a loop or segment that does not exist.
    #[error("edge `{name}`: {message}")]
    BadEdge {
        /// Edge name.
        name: String,
        /// What is wrong.
        message: String,
    },
}

fn loop_name(k: usize) -> String {
    if k == 0 {
        "the outline".into()
    } else {
        format!("hole {k}")
    }
}

/// Orientation of `c` relative to the line `a → b`: +1 left, −1 right, 0 on
/// it (within a relative tolerance of `1e-10 · |b − a|`).
#[inline]
pub fn orient(a: Vec2, b: Vec2, c: Vec2) -> i8 {
    let ab = b - a;
    let cr = ab.cross(c - a);
    let tol = 1e-10 * ab.norm2().max((c - a).norm2());
    if cr > tol {
        1
    } else if cr < -tol {
        -1
    } else {
        0
    }
}

/// Do the open segments `a b` and `c d` cross properly (each one's end points
/// strictly on opposite sides of the other)? Touching, ending on the other
/// segment and collinear overlap are not crossings.
#[inline]
pub fn properly_cross(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let o1 = orient(a, b, c);
    let o2 = orient(a, b, d);
    if o1 * o2 >= 0 {
        return false;
    }
    let o3 = orient(c, d, a);
    let o4 = orient(c, d, b);
    o3 * o4 < 0
}

/// Is `p` on the closed segment `a b` (within the [`orient`] tolerance)?
pub fn on_segment(a: Vec2, b: Vec2, p: Vec2) -> bool {
    orient(a, b, p) == 0 && {
        let ab = b - a;
        let t = (p - a).dot(ab) / ab.norm2();
        (-1e-12..=1.0 + 1e-12).contains(&t)
    }
}

/// Do the closed segments `a b` and `c d` share any point?
pub fn segments_meet(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    properly_cross(a, b, c, d)
        || on_segment(a, b, c)
        || on_segment(a, b, d)
        || on_segment(c, d, a)
        || on_segment(c, d, b)
}

/// Is `p` strictly inside the closed loop (crossing number; points on the
/// loop count as outside)?
pub fn inside_loop(points: &[Vec2], p: Vec2) -> bool {
    let n = points.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        if on_segment(a, b, p) {
            return false;
        }
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if x > p.x {
                inside = !inside;
            }
        }
    }
    inside
}

impl Domain {
    /// Validate and store an outline and holes, all given counter-clockwise
    /// (holes as seen from their own inside). Holes are stored reversed
    /// (clockwise). `edges` name segment sets in the user's indexing
    /// (`(loop, segment)` with segment `i` from vertex `i` to `i + 1`); they
    /// are mapped to storage indexing.
    pub fn new(
        outline: Vec<Vec2>,
        holes: Vec<Vec<Vec2>>,
        edges: Vec<(String, Vec<(usize, usize)>)>,
    ) -> Result<Domain, PolygonError> {
        let user: Vec<Loop> = std::iter::once(outline)
            .chain(holes)
            .map(|points| Loop { points })
            .collect();
        for (k, l) in user.iter().enumerate() {
            check_loop_points(l, &loop_name(k))?;
        }
        let index = SegmentIndex::new(&user);
        for (k, l) in user.iter().enumerate() {
            check_simple(l, k, &index, &loop_name(k))?;
        }
        check_holes(&user, &index)?;
        let loops: Vec<Loop> = user
            .iter()
            .enumerate()
            .map(|(k, l)| {
                let mut points = l.points.clone();
                if k > 0 {
                    points.reverse();
                }
                Loop { points }
            })
            .collect();
        let mut named = Vec::with_capacity(edges.len());
        for (name, segs) in edges {
            let mut out = Vec::with_capacity(segs.len());
            for (k, i) in segs {
                let Some(l) = loops.get(k) else {
                    return Err(PolygonError::BadEdge {
                        name,
                        message: format!(
                            "loop {k} does not exist (0 = outline, 1.. = holes; the body has {} loop(s))",
                            loops.len()
                        ),
                    });
                };
                let n = l.len();
                if i >= n {
                    return Err(PolygonError::BadEdge {
                        name,
                        message: format!("{} has segments 0..{}, not {i}", loop_name(k), n - 1),
                    });
                }
                // user segment i of a hole (p_i → p_{i+1}) is stored
                // reversed as segment (n − 2 − i) mod n
                let s = if k == 0 { i } else { (2 * n - 2 - i) % n };
                out.push((k, s));
            }
            named.push(NamedEdge {
                name,
                segments: out,
            });
        }
        let index = SegmentIndex::new(&loops);
        Ok(Domain {
            loops,
            edges: named,
            index,
        })
    }

    /// Is `p` inside Ω (strictly inside the outline and outside every hole;
    /// points on the boundary count as outside)? The crossing number over
    /// every loop: the holes lie inside the outline and apart, so an odd
    /// count means inside the outline and in no hole.
    pub fn contains(&self, p: Vec2) -> bool {
        !self.index.on_boundary(p) && self.index.crossings(p).count() % 2 == 1
    }

    /// The boundary segments, indexed (storage indexing: holes reversed).
    pub fn index(&self) -> &SegmentIndex {
        &self.index
    }

    /// All boundary segments `(a, b)`, loop by loop, body on the left.
    pub fn segments(&self) -> impl Iterator<Item = (Vec2, Vec2)> + '_ {
        self.loops
            .iter()
            .flat_map(|l| (0..l.len()).map(move |i| l.segment(i)))
    }

    /// The named edge `name`.
    pub fn edge(&self, name: &str) -> Option<&NamedEdge> {
        self.edges.iter().find(|e| e.name == name)
    }

    /// Distance from `p` to the nearest boundary segment.
    pub fn boundary_distance(&self, p: Vec2) -> f64 {
        self.index.distance(p)
    }

    /// Lower-left and upper-right corners of the outline's bounding box.
    pub fn bounds(&self) -> (Vec2, Vec2) {
        let mut lo = Vec2::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        for p in &self.loops[0].points {
            lo.x = lo.x.min(p.x);
            lo.y = lo.y.min(p.y);
            hi.x = hi.x.max(p.x);
            hi.y = hi.y.max(p.y);
        }
        (lo, hi)
    }

    /// Area of Ω.
    pub fn area(&self) -> f64 {
        0.5 * self.loops.iter().map(Loop::signed_area2).sum::<f64>()
    }
}

/// Is `p` strictly inside loop `lp` of `index` (crossing number; a point
/// on the loop is not)?
fn inside(index: &SegmentIndex, lp: usize, p: Vec2) -> bool {
    !index
        .in_box(p, p)
        .any(|s| s.lp == lp && on_segment(s.a, s.b, p))
        && index.crossings(p).filter(|&m| m == lp).count() % 2 == 1
}

/// The first `(i, j)` (by `i`, then `j`) with segment `i` of loop `a`
/// meeting segment `j` of a loop `b` in `others`, with its `b`, the
/// smallest `b` first.
fn first_meeting(
    loops: &[Loop],
    index: &SegmentIndex,
    a: usize,
    others: std::ops::Range<usize>,
) -> Option<(usize, usize, usize)> {
    (0..loops[a].len())
        .filter_map(|i| {
            let (p, q) = loops[a].segment(i);
            index
                .near_segment(p, q)
                .filter(|s| others.contains(&s.lp) && segments_meet(p, q, s.a, s.b))
                .map(|s| (s.lp, i, s.seg))
                .min()
        })
        .min()
}

/// Holes strictly inside the outline, apart from each other.
fn check_holes(user: &[Loop], index: &SegmentIndex) -> Result<(), PolygonError> {
    for (k, h) in user.iter().enumerate().skip(1) {
        for (i, &p) in h.points.iter().enumerate() {
            if !inside(index, 0, p) {
                return Err(PolygonError::HolePlacement {
                    what: format!(
                        "hole {k} is not strictly inside the outline: its vertex {i} ({}, {}) is outside or on it",
                        p.x, p.y
                    ),
                });
            }
        }
        if let Some((_, i, j)) = first_meeting(user, index, k, 0..1) {
            return Err(PolygonError::HolePlacement {
                what: format!(
                    "hole {k} is not strictly inside the outline: its segment {i} meets the outline's segment {j}"
                ),
            });
        }
        if let Some((m, i, j)) = first_meeting(user, index, k, 1..k) {
            return Err(PolygonError::HolePlacement {
                what: format!(
                    "holes {m} and {k} overlap: segment {j} of hole {m} meets segment {i} of hole {k}"
                ),
            });
        }
    }
    // apart and not crossing: a hole inside another has its first vertex
    // inside it
    for (k, h) in user.iter().enumerate().skip(1) {
        let mut odd = std::collections::BTreeMap::new();
        for m in index.crossings(h.points[0]).filter(|&m| m != 0 && m != k) {
            *odd.entry(m).or_insert(0usize) += 1;
        }
        if let Some((&m, _)) = odd.iter().find(|(_, c)| *c % 2 == 1) {
            let (m, k) = (m.min(k), m.max(k));
            return Err(PolygonError::HolePlacement {
                what: format!("holes {m} and {k} overlap: one lies inside the other"),
            });
        }
    }
    Ok(())
}

/// At least 3 vertices, all finite, no zero-length segment.
fn check_loop_points(l: &Loop, what: &str) -> Result<(), PolygonError> {
    let n = l.len();
    if n < 3 {
        return Err(PolygonError::TooFew {
            what: what.into(),
            n,
        });
    }
    if let Some(p) = l
        .points
        .iter()
        .find(|p| !(p.x.is_finite() && p.y.is_finite()))
    {
        return Err(PolygonError::Degenerate {
            what: what.into(),
            message: format!("non-finite vertex ({}, {})", p.x, p.y),
        });
    }
    for i in 0..n {
        let (a, b) = l.segment(i);
        if a == b {
            return Err(PolygonError::Degenerate {
                what: what.into(),
                message: format!("segment {i} has zero length (vertex {i} repeated)"),
            });
        }
    }
    Ok(())
}

/// Loop `k` (indexed in `index`) is simple — no two segments meet except
/// neighbours at their shared vertex, and those do not fold back — and
/// counter-clockwise. The first offending pair (by `i`, then `j`) is
/// reported.
fn check_simple(l: &Loop, k: usize, index: &SegmentIndex, what: &str) -> Result<(), PolygonError> {
    let n = l.len();
    let bad_pair = |i: usize, j: usize| {
        let ((a, b), (c, d)) = (l.segment(i), l.segment(j));
        let adjacent = j == i + 1 || (i == 0 && j == n - 1);
        if adjacent {
            // share one vertex: bad only if they fold back on each other
            let (shared, p, q) = if j == i + 1 { (b, a, d) } else { (a, b, c) };
            orient(shared, p, q) == 0 && (p - shared).dot(q - shared) > 0.0
        } else {
            segments_meet(a, b, c, d)
        }
    };
    let first = (0..n).find_map(|i| {
        let (a, b) = l.segment(i);
        index
            .near_segment(a, b)
            .filter(|s| s.lp == k && s.seg > i && bad_pair(i, s.seg))
            .map(|s| s.seg)
            .min()
            .map(|j| (i, j))
    });
    if let Some((i, j)) = first {
        let ((a, b), (c, d)) = (l.segment(i), l.segment(j));
        return Err(PolygonError::SelfIntersecting {
            what: what.into(),
            i,
            j,
            a: a.to_array(),
            b: b.to_array(),
            c: c.to_array(),
            d: d.to_array(),
        });
    }
    let area = 0.5 * l.signed_area2();
    if area <= 0.0 {
        return Err(PolygonError::Clockwise {
            what: what.into(),
            area,
        });
    }
    Ok(())
}

/// A regular polygon approximating a circle: `segments` vertices,
/// counter-clockwise, the first at angle 0.
pub fn circle(center: Vec2, radius: f64, segments: usize) -> Vec<Vec2> {
    (0..segments)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / segments as f64;
            center + Vec2::new(t.cos(), t.sin()) * radius
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(p: &[[f64; 2]]) -> Vec<Vec2> {
        p.iter().map(|&a| a.into()).collect()
    }

    #[test]
    fn validation_messages() {
        let sq = v(&[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]);
        let cw: Vec<Vec2> = sq.iter().rev().copied().collect();
        assert!(matches!(
            Domain::new(cw, vec![], vec![]),
            Err(PolygonError::Clockwise { .. })
        ));
        let bow = v(&[[0.0, 0.0], [4.0, 4.0], [4.0, 0.0], [0.0, 4.0]]);
        assert!(matches!(
            Domain::new(bow, vec![], vec![]),
            Err(PolygonError::SelfIntersecting { .. })
        ));
        let out = circle(Vec2::new(5.0, 2.0), 0.5, 8);
        let e = Domain::new(sq.clone(), vec![out], vec![]).unwrap_err();
        assert!(e.to_string().contains("not strictly inside"), "{e}");
        let h1 = circle(Vec2::new(1.5, 2.0), 0.8, 8);
        let h2 = circle(Vec2::new(2.5, 2.0), 0.8, 8);
        let e = Domain::new(sq.clone(), vec![h1.clone(), h2], vec![]).unwrap_err();
        assert!(e.to_string().contains("overlap"), "{e}");
        let d = Domain::new(sq, vec![h1], vec![("h".into(), vec![(1, 0)])]).unwrap();
        assert!(d.loops[1].signed_area2() < 0.0);
        assert!(d.contains(Vec2::new(3.5, 3.5)));
        assert!(!d.contains(Vec2::new(1.5, 2.0)));
        assert!(!d.contains(Vec2::new(5.0, 2.0)));
        // user segment 0 of the hole, reversed: same end points
        let (a, b) = d.loops[1].segment(d.edge("h").unwrap().segments[0].1);
        let c = circle(Vec2::new(1.5, 2.0), 0.8, 8);
        assert_eq!((a, b), (c[1], c[0]));
    }

    #[test]
    fn crossing_ignores_touching_and_collinear() {
        let (a, b) = (Vec2::new(0.0, 0.0), Vec2::new(2.0, 0.0));
        assert!(properly_cross(
            a,
            b,
            Vec2::new(1.0, -1.0),
            Vec2::new(1.0, 1.0)
        ));
        assert!(!properly_cross(
            a,
            b,
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0)
        ));
        assert!(!properly_cross(
            a,
            b,
            Vec2::new(1.0, 0.0),
            Vec2::new(3.0, 0.0)
        ));
    }
}
