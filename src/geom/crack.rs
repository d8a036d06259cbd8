//! Cracks in a polygon domain: polylines of zero width inside Ω. An end
//! strictly inside Ω is a **tip**; an end on the boundary is a **mouth**
//! (an edge crack). A crack has at least one tip (a crack from boundary to
//! boundary would cut the body in two).
//!
//! The faces of a crack are traction-free boundaries: the EFG supports do
//! not reach across a crack ([`crate::efg::support::Visibility`]), except
//! around its tips by diffraction.

use super::Vec2;
use super::polygon::{Domain, on_segment, orient, properly_cross, segments_meet};

/// A crack: a polyline `points[0] → … → points[n−1]`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Crack {
    /// The vertices, from one end to the other (≥ 2).
    pub points: Vec<Vec2>,
}

/// What an end of a crack is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// Strictly inside Ω: the crack front.
    Tip,
    /// On boundary segment `(loop, segment)` (storage indexing) of Ω.
    Mouth(usize, usize),
}

/// Why a crack was refused: `crack` (0-based) and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("crack {crack}: {message}")]
pub struct CrackError {
    /// Index of the crack in the body's list.
    pub crack: usize,
    /// What is wrong.
    pub message: String,
}

impl Crack {
    /// A crack through `points`.
    pub fn new(points: Vec<Vec2>) -> Crack {
        Crack { points }
    }
    /// Number of pieces (straight segments).
    pub fn pieces(&self) -> usize {
        self.points.len().saturating_sub(1)
    }
    /// End points of piece `i`.
    pub fn piece(&self, i: usize) -> (Vec2, Vec2) {
        (self.points[i], self.points[i + 1])
    }
    /// Length along the polyline.
    pub fn length(&self) -> f64 {
        (0..self.pieces())
            .map(|i| {
                let (a, b) = self.piece(i);
                (b - a).norm()
            })
            .sum()
    }
    /// Distance from `p` to the polyline.
    pub fn distance(&self, p: Vec2) -> f64 {
        (0..self.pieces())
            .map(|i| {
                let (a, b) = self.piece(i);
                (p - super::closest_on_segment(p, a, b).1).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }
    /// The end `e` (0: `points[0]`, 1: the last point) and the unit
    /// direction in which the crack runs out of it (from the end's piece
    /// towards the end: the direction a tip advances).
    pub fn end(&self, e: usize) -> (Vec2, Vec2) {
        let n = self.points.len();
        let (a, b) = if e == 0 {
            (self.points[1], self.points[0])
        } else {
            (self.points[n - 2], self.points[n - 1])
        };
        let d = b - a;
        (b, d * (1.0 / d.norm()))
    }
}

/// Validate `cracks` in `domain`: each crack has ≥ 2 finite, distinct
/// points (further apart than 10⁻⁹ of the body's size), does not cross
/// itself, another crack or the boundary, its inner vertices are strictly
/// inside Ω, and each end is a tip or a mouth (at least one tip). Returns
/// each crack's two ends.
pub fn check(domain: &Domain, cracks: &[Crack]) -> Result<Vec<[End; 2]>, CrackError> {
    let mut out = Vec::with_capacity(cracks.len());
    let (lo, hi) = domain.bounds();
    let size = (hi - lo).norm();
    for (k, c) in cracks.iter().enumerate() {
        let err = |message: String| CrackError { crack: k, message };
        let n = c.points.len();
        if n < 2 {
            return Err(err(format!("has {n} point(s); a crack needs at least 2")));
        }
        if let Some((i, p)) = c
            .points
            .iter()
            .enumerate()
            .find(|(_, p)| !(p.x.is_finite() && p.y.is_finite()))
        {
            return Err(err(format!("point {i} ({}, {}) is not finite", p.x, p.y)));
        }
        // closer than a 10⁻⁹ of the body's size: no node resolves the piece
        let tiny = 1e-9 * size;
        if let Some(i) = (0..n - 1).find(|&i| (c.points[i + 1] - c.points[i]).norm() <= tiny) {
            return Err(err(format!(
                "points {i} and {} coincide (closer than 1e-9 × the body's size, {tiny:e})",
                i + 1
            )));
        }
        for i in 0..n - 1 {
            let (a, b) = c.piece(i);
            for j in i + 1..n - 1 {
                let (p, q) = c.piece(j);
                let bad = if j == i + 1 {
                    orient(a, b, q) == 0 && (q - b).dot(a - b) > 0.0
                } else {
                    segments_meet(a, b, p, q)
                };
                if bad {
                    return Err(err(format!("pieces {i} and {j} cross or overlap")));
                }
            }
        }
        for (i, &p) in c.points.iter().enumerate().take(n - 1).skip(1) {
            if !domain.contains(p) {
                return Err(err(format!(
                    "point {i} ({}, {}) is not inside the body",
                    p.x, p.y
                )));
            }
        }
        let end = |e: usize| -> Result<End, CrackError> {
            let p = if e == 0 { c.points[0] } else { c.points[n - 1] };
            if domain.contains(p) {
                return Ok(End::Tip);
            }
            let on = domain.loops.iter().enumerate().find_map(|(l, lp)| {
                (0..lp.len())
                    .find(|&s| {
                        let (a, b) = lp.segment(s);
                        on_segment(a, b, p)
                    })
                    .map(|s| (l, s))
            });
            let Some((l, s)) = on else {
                return Err(err(format!(
                    "point {} ({}, {}) is outside the body: an end is a tip inside the body or a mouth on its boundary",
                    if e == 0 { 0 } else { n - 1 },
                    p.x,
                    p.y
                )));
            };
            // the piece must enter Ω from the mouth
            let q = if e == 0 { c.points[1] } else { c.points[n - 2] };
            let probe = p + (q - p) * 1e-3;
            if !domain.contains(probe) {
                return Err(err(format!(
                    "the end ({}, {}) is on the boundary but the crack does not run into the body from it",
                    p.x, p.y
                )));
            }
            Ok(End::Mouth(l, s))
        };
        let ends = [end(0)?, end(1)?];
        if ends.iter().all(|e| matches!(e, End::Mouth(..))) {
            return Err(err(
                "both ends are on the boundary: the crack would cut the body in two (at least one end must be a tip inside the body)".into(),
            ));
        }
        // no piece meets the boundary except at a mouth
        for i in 0..n - 1 {
            let (a, b) = c.piece(i);
            for (s0, s1) in domain.segments() {
                if !segments_meet(a, b, s0, s1) {
                    continue;
                }
                let at_mouth = |p: Vec2, e: usize| {
                    matches!(ends[e], End::Mouth(..))
                        && on_segment(s0, s1, p)
                        && !properly_cross(a, b, s0, s1)
                };
                let only_mouth = (i == 0 && at_mouth(a, 0) && !on_segment(s0, s1, b))
                    || (i == n - 2 && at_mouth(b, 1) && !on_segment(s0, s1, a));
                if !only_mouth {
                    return Err(err(format!(
                        "piece {i} ({}, {}) → ({}, {}) meets the boundary",
                        a.x, a.y, b.x, b.y
                    )));
                }
            }
        }
        for (m, o) in cracks.iter().enumerate().take(k) {
            for i in 0..n - 1 {
                let (a, b) = c.piece(i);
                for j in 0..o.pieces() {
                    let (p, q) = o.piece(j);
                    if segments_meet(a, b, p, q) {
                        return Err(err(format!(
                            "piece {i} meets piece {j} of crack {m} (cracks may not meet)"
                        )));
                    }
                }
            }
        }
        out.push(ends);
    }
    Ok(out)
}

/// `domain` with a vertex inserted at `p` on segment `s` of loop `l`
/// (storage indexing): segment `s` becomes `s` and `s + 1`, later segments
/// of the loop shift by one; named edges follow (an edge holding `s`
/// holds both halves). `map` renumbers other `(loop, segment)` lists the
/// same way.
pub fn split(domain: &Domain, l: usize, s: usize, p: Vec2) -> Domain {
    let mut d = domain.clone();
    d.loops[l].points.insert(s + 1, p);
    for e in &mut d.edges {
        e.segments = e
            .segments
            .iter()
            .flat_map(|&seg| split_index(seg, l, s))
            .collect();
    }
    d
}

/// The segments that `(loop, segment)` becomes after [`split`] at
/// segment `s` of loop `l`.
pub fn split_index((k, i): (usize, usize), l: usize, s: usize) -> Vec<(usize, usize)> {
    if k != l || i < s {
        vec![(k, i)]
    } else if i == s {
        vec![(k, s), (k, s + 1)]
    } else {
        vec![(k, i + 1)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Domain {
        let o = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]
            .iter()
            .map(|&p| p.into())
            .collect();
        Domain::new(o, vec![], vec![("left".into(), vec![(0, 3)])]).unwrap()
    }

    fn c(p: &[[f64; 2]]) -> Crack {
        Crack::new(p.iter().map(|&q| q.into()).collect())
    }

    #[test]
    fn ends_are_tips_or_mouths() {
        let d = square();
        let e = check(
            &d,
            &[c(&[[1.0, 1.0], [2.0, 2.0]]), c(&[[0.0, 3.0], [1.0, 3.0]])],
        )
        .unwrap();
        assert_eq!(e[0], [End::Tip, End::Tip]);
        assert_eq!(e[1], [End::Mouth(0, 3), End::Tip]);
    }

    #[test]
    fn bad_cracks_are_located() {
        let d = square();
        let msg = |cr: Vec<Crack>| check(&d, &cr).unwrap_err().to_string();
        assert!(msg(vec![c(&[[1.0, 1.0]])]).contains("at least 2"));
        assert!(msg(vec![c(&[[1.0, 1.0], [5.0, 1.0]])]).contains("outside the body"));
        assert!(msg(vec![c(&[[0.0, 1.0], [4.0, 1.0]])]).contains("cut the body in two"));
        assert!(msg(vec![c(&[[1.0, 1.0], [3.0, 1.0], [2.0, 1.0]])]).contains("cross or overlap"));
        assert!(
            msg(vec![
                c(&[[1.0, 1.0], [3.0, 3.0]]),
                c(&[[1.0, 3.0], [3.0, 1.0]])
            ])
            .starts_with("crack 1: piece 0 meets piece 0 of crack 0")
        );
        // inner vertex outside, piece leaving and re-entering the body
        assert!(msg(vec![c(&[[1.0, 1.0], [5.0, 2.0], [2.0, 3.0]])]).contains("point 1"));
        assert!(msg(vec![c(&[[0.0, 2.0], [-1.0, 2.0]])]).contains("does not run into"));
    }

    #[test]
    fn split_renumbers_named_edges() {
        let d = square();
        let s = split(&d, 0, 3, Vec2::new(0.0, 2.0));
        assert_eq!(s.loops[0].len(), 5);
        assert_eq!(s.edge("left").unwrap().segments, vec![(0, 3), (0, 4)]);
        assert!((s.area() - 16.0).abs() < 1e-12);
    }
}
