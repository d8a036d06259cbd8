//! Constrained Delaunay triangulation of a polygon body's nodes (the
//! `spade` crate) with the domain's boundary segments as constraints;
//! triangles outside the outline or inside holes are dropped, so the
//! triangles cover Ω exactly (up to the straight segments that define it).

use super::Vec2;
use super::polygon::Domain;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

/// Why a triangulation failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("triangulation failed: {0}")]
pub struct TriangulationError(pub String);

/// Triangles `[i, j, k]` (counter-clockwise, indices into `points`) of the
/// constrained Delaunay triangulation of `points` with the `constraints`
/// (pairs of point indices, the boundary pieces between consecutive
/// boundary nodes), keeping those whose centroid lies in `domain`.
pub fn triangulate(
    points: &[Vec2],
    constraints: &[[usize; 2]],
    domain: &Domain,
) -> Result<Vec<[usize; 3]>, TriangulationError> {
    // coordinates below spade's smallest magnitude (1.8e-43) become 0: a
    // displacement nothing else can resolve either
    let verts: Vec<Point2<f64>> = points
        .iter()
        .map(|p| spade::mitigate_underflow(Point2::new(p.x, p.y)))
        .collect();
    // an edge whose ends coincide (a crack or side shorter than the
    // coordinates resolve) is no constraint: spade would panic on it
    if let Some(&[a, _]) = constraints.iter().find(|&&[a, b]| verts[a] == verts[b]) {
        return Err(TriangulationError(format!(
            "a constrained edge (a crack or an outline side) has zero length at ({:e}, {:e})",
            points[a].x, points[a].y
        )));
    }
    let cdt =
        ConstrainedDelaunayTriangulation::<Point2<f64>>::bulk_load_cdt(verts, constraints.to_vec())
            .map_err(|e| {
                TriangulationError(match e {
                    spade::InsertionError::TooLarge => format!(
                        "a coordinate is larger than {:e} in magnitude",
                        spade::MAX_ALLOWED_VALUE
                    ),
                    spade::InsertionError::NAN => "a coordinate is not a number".into(),
                    _ => format!(
                        "a coordinate is non-zero but below {:e} in magnitude",
                        spade::MIN_ALLOWED_VALUE
                    ),
                })
            })?;
    if cdt.num_vertices() != points.len() {
        return Err(TriangulationError(format!(
            "{} of {} nodes coincide with others",
            points.len() - cdt.num_vertices(),
            points.len()
        )));
    }
    let mut out = Vec::new();
    for f in cdt.inner_faces() {
        let v = f.vertices().map(|h| h.fix().index());
        let c = (points[v[0]] + points[v[1]] + points[v[2]]) * (1.0 / 3.0);
        if domain.contains(c) {
            let area2 = (points[v[1]] - points[v[0]]).cross(points[v[2]] - points[v[0]]);
            out.push(if area2 >= 0.0 { v } else { [v[0], v[2], v[1]] });
        }
    }
    Ok(out)
}
