//! Node sets and background integration of polygon bodies: a regular grid
//! at spacing `h` clipped to Ω (grid nodes closer than `h/2` to the
//! boundary dropped), nodes along every boundary segment at spacing ≤ `h`
//! (all vertices included), and the constrained Delaunay triangulation of
//! these nodes with the boundary pieces as constraints, which covers Ω
//! exactly: there are no cut cells, every Gauss point is inside Ω.

use crate::continuum::quadrature::{self, QuadPoint};
use crate::geom::Vec2;
use crate::geom::polygon::Domain;
use crate::geom::triangulate::triangulate;

/// Nodes and triangles of a polygon body.
#[derive(Debug, Clone)]
pub struct PolygonMesh {
    /// The domain.
    pub domain: Domain,
    /// Node spacing `h`.
    pub spacing: f64,
    /// Node positions: boundary nodes first (loop by loop), then the grid.
    pub nodes: Vec<Vec2>,
    /// Per loop, per segment: the nodes along it, from its start vertex to
    /// its end vertex (both included).
    pub segment_nodes: Vec<Vec<Vec<usize>>>,
    /// Triangles (counter-clockwise) of the integration triangulation.
    pub triangles: Vec<[usize; 3]>,
}

impl PolygonMesh {
    /// Nodes and triangulation of `domain` at spacing `h`.
    pub fn new(domain: &Domain, h: f64) -> Result<PolygonMesh, String> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(format!("spacing must be positive, not {h}"));
        }
        let mut nodes: Vec<Vec2> = Vec::new();
        let mut segment_nodes = Vec::with_capacity(domain.loops.len());
        let mut constraints = Vec::new();
        for l in &domain.loops {
            let n = l.len();
            let first = nodes.len();
            let mut segs = Vec::with_capacity(n);
            for i in 0..n {
                let (a, b) = l.segment(i);
                let m = ((b - a).norm() / h).ceil().max(1.0) as usize;
                let mut ids = Vec::with_capacity(m + 1);
                ids.push(nodes.len());
                nodes.push(a);
                for k in 1..m {
                    ids.push(nodes.len());
                    nodes.push(a + (b - a) * (k as f64 / m as f64));
                }
                // the end vertex is the next segment's start (first for the last)
                ids.push(if i + 1 == n { first } else { nodes.len() });
                segs.push(ids);
            }
            for ids in &segs {
                for w in ids.windows(2) {
                    constraints.push([w[0], w[1]]);
                }
            }
            segment_nodes.push(segs);
        }
        let (lo, hi) = domain.bounds();
        let nx = ((hi.x - lo.x) / h).floor() as usize;
        let ny = ((hi.y - lo.y) / h).floor() as usize;
        // centre the grid in the bounding box
        let ox = lo.x + 0.5 * ((hi.x - lo.x) - nx as f64 * h);
        let oy = lo.y + 0.5 * ((hi.y - lo.y) - ny as f64 * h);
        for j in 0..=ny {
            for i in 0..=nx {
                let p = Vec2::new(ox + i as f64 * h, oy + j as f64 * h);
                if domain.contains(p) && domain.boundary_distance(p) >= 0.5 * h {
                    nodes.push(p);
                }
            }
        }
        let triangles = triangulate(&nodes, &constraints, domain).map_err(|e| e.to_string())?;
        Ok(PolygonMesh {
            domain: domain.clone(),
            spacing: h,
            nodes,
            segment_nodes,
            triangles,
        })
    }

    /// Gauss points of the triangles: Dunavant's degree-5 rule on each
    /// triangle split into `sub²` sub-triangles.
    pub fn domain_points(&self, sub: usize) -> Vec<QuadPoint> {
        let tris: Vec<[Vec2; 3]> = self
            .triangles
            .iter()
            .map(|t| t.map(|i| self.nodes[i]))
            .collect();
        let mut out = Vec::with_capacity(tris.len() * 7 * sub * sub);
        quadrature::triangle_points(&tris, sub, &mut out);
        out
    }

    /// The boundary pieces (between consecutive boundary nodes) of the
    /// segments `(loop, segment)`, each `(a, b)` with the body on the left.
    pub fn pieces(&self, segments: &[(usize, usize)]) -> Vec<(Vec2, Vec2)> {
        let mut out = Vec::new();
        for &(l, s) in segments {
            for w in self.segment_nodes[l][s].windows(2) {
                out.push((self.nodes[w[0]], self.nodes[w[1]]));
            }
        }
        out
    }

    /// Every boundary piece of every loop.
    pub fn all_segments(&self) -> Vec<(usize, usize)> {
        self.segment_nodes
            .iter()
            .enumerate()
            .flat_map(|(l, segs)| (0..segs.len()).map(move |s| (l, s)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangles_cover_an_l_shape_with_a_hole_exactly() {
        let outline: Vec<Vec2> = [
            [0.0, 0.0],
            [4.0, 0.0],
            [4.0, 2.0],
            [2.0, 2.0],
            [2.0, 4.0],
            [0.0, 4.0],
        ]
        .iter()
        .map(|&p| p.into())
        .collect();
        let hole = crate::geom::polygon::circle(Vec2::new(1.0, 1.0), 0.5, 16);
        let d = Domain::new(outline, vec![hole], vec![]).unwrap();
        let m = PolygonMesh::new(&d, 0.25).unwrap();
        let q = m.domain_points(1);
        let area: f64 = q.iter().map(|p| p.w).sum();
        assert!(
            (area - d.area()).abs() < 1e-12 * d.area(),
            "{area} vs {}",
            d.area()
        );
        assert!((d.area() - (12.0 - d.loops[1].signed_area2().abs() * 0.5)).abs() < 1e-12);
        assert!(q.iter().all(|p| d.contains(p.x)));
    }
}
