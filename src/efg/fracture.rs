//! Stress intensity factors at the crack tips of an EFG body: the
//! interaction integral ([`crate::continuum::crack_tip`]) over the body's
//! own integration triangles (constrained by the crack, so none straddles
//! it), refined in the ring, with the MLS stress and displacement gradient.

use super::EfgError;
use super::body::EfgBody;
use super::shape::ShapeRow;
use crate::continuum::Plane;
use crate::continuum::crack_tip::{Ring, TipSample, interaction_integral};
use crate::continuum::quadrature::{QuadPoint, triangle_points};
use crate::geom::Vec2;
use crate::geom::crack::End;

/// A crack tip of a body: crack `crack`, end `end` (0: its first point,
/// 1: its last).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tip {
    /// Index of the crack.
    pub crack: usize,
    /// Which end.
    pub end: usize,
}

/// Default ring of the interaction integral around a tip, in units of the
/// tip node's spacing `h_tip`: `q` falls from 1 at `RING[0]·h_tip` to 0 at
/// `RING[1]·h_tip` (clamped to the room the tip has).
pub const RING: [f64; 2] = [2.0, 5.0];

/// Sub-triangles across the ring's width: triangles that meet the ring are
/// split until their pieces are at most `(outer − inner)/RING_PIECES`.
pub const RING_PIECES: f64 = 8.0;

impl EfgBody {
    /// The tips of the body's cracks, crack by crack.
    pub fn tips(&self) -> Vec<Tip> {
        self.cracks()
            .iter()
            .enumerate()
            .flat_map(|(k, c)| {
                (0..2)
                    .filter(move |&e| c.ends[e] == End::Tip)
                    .map(move |end| Tip { crack: k, end })
            })
            .collect()
    }

    /// Position and unit direction of advance of a tip.
    pub fn tip_frame(&self, tip: Tip) -> (Vec2, Vec2) {
        self.cracks()[tip.crack].crack.end(tip.end)
    }

    /// The spacing of the node at a tip.
    pub fn tip_spacing(&self, tip: Tip) -> f64 {
        let c = &self.cracks()[tip.crack];
        let j = if tip.end == 0 { 0 } else { c.nodes.len() - 1 };
        self.mesh
            .as_ref()
            .map_or(0.0, |m| m.node_spacing[c.nodes[j][0]])
    }

    /// The default ring of a tip ([`RING`]), its outer radius at most
    /// 0.9 × the distance to the boundary and to the crack's other end.
    pub fn default_ring(&self, tip: Tip) -> Ring {
        let h = self.tip_spacing(tip);
        let (p, _) = self.tip_frame(tip);
        let c = &self.cracks()[tip.crack].crack;
        let other = c.end(1 - tip.end).0;
        let mut room = (other - p).norm();
        if let Some(m) = &self.mesh {
            room = room.min(m.domain.boundary_distance(p));
            for (k, o) in self.cracks().iter().enumerate() {
                if k != tip.crack {
                    room = room.min(o.crack.distance(p));
                }
            }
        }
        let outer = (RING[1] * h).min(0.9 * room);
        Ring {
            inner: outer * RING[0] / RING[1],
            outer,
        }
    }

    /// `[K_I, K_II]` at `tip` from the interaction integral over `ring`
    /// (the present displacement; plane stress or strain as the body).
    pub fn stress_intensity(&self, tip: Tip, ring: Ring) -> Result<[f64; 2], EfgError> {
        let (p, dir) = self.tip_frame(tip);
        let points = self.ring_points(p, ring)?;
        let mut row = ShapeRow::new();
        let mut err = None;
        let sample = |x: Vec2| -> Option<TipSample> {
            match self.shape_row(x, &mut row) {
                Ok(()) => Some(self.tip_sample(&row)),
                Err(e) => {
                    err.get_or_insert(e);
                    None
                }
            }
        };
        let m = &self.material;
        let k = interaction_integral(
            p,
            dir,
            ring,
            &points,
            sample,
            &self.faces.face_forces(
                self.material.thickness,
                (
                    tip.crack,
                    tip.end as f64 * self.cracks()[tip.crack].crack.length(),
                ),
            ),
            (m.e, m.nu, m.plane == Plane::Strain),
        );
        match err {
            Some(e) => Err(e),
            None => Ok(k),
        }
    }

    /// Stress and displacement gradient from a shape row.
    fn tip_sample(&self, row: &ShapeRow) -> TipSample {
        let u = &self.state.u;
        let mut g = [[0.0; 2]; 2];
        for k in 0..row.len() {
            let i = row.idx[k] as usize;
            for c in 0..2 {
                g[c][0] += row.dx[k] * u[2 * i + c];
                g[c][1] += row.dy[k] * u[2 * i + c];
            }
        }
        let s = self.material.stress([g[0][0], g[1][1], g[0][1] + g[1][0]]);
        (s, g)
    }

    /// Quadrature points `(x, w)` of the triangles that meet the ring
    /// around `p`, split into pieces of about `(outer − inner)/RING_PIECES`.
    /// A ring so small against the triangles it meets that a triangle
    /// would need more than `MAX_PIECES` pieces a side is refused: its tip
    /// is too close to the boundary, another crack or its crack's other
    /// end for the integral to mean anything (and the points would not fit
    /// in memory).
    fn ring_points(&self, p: Vec2, ring: Ring) -> Result<Vec<(Vec2, f64)>, EfgError> {
        const MAX_PIECES: f64 = 64.0;
        let Some(mesh) = &self.mesh else {
            return Ok(Vec::new());
        };
        let piece = (ring.outer - ring.inner) / RING_PIECES;
        let mut out: Vec<QuadPoint> = Vec::new();
        for t in &mesh.triangles {
            let tri = t.map(|i| mesh.points[i]);
            let far = tri.iter().map(|v| (*v - p).norm()).fold(0.0, f64::max);
            let near = (0..3)
                .map(|k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    (p - crate::geom::closest_on_segment(p, a, b).1).norm()
                })
                .fold(f64::INFINITY, f64::min);
            let inside = {
                let s = |a: Vec2, b: Vec2| (b - a).cross(p - a) >= 0.0;
                s(tri[0], tri[1]) && s(tri[1], tri[2]) && s(tri[2], tri[0])
            };
            let near = if inside { 0.0 } else { near };
            if near >= ring.outer || far <= ring.inner {
                continue;
            }
            let longest = (0..3)
                .map(|k| (tri[(k + 1) % 3] - tri[k]).norm())
                .fold(0.0, f64::max);
            let sub = (longest / piece).ceil().max(1.0);
            if sub.is_nan() || sub > MAX_PIECES {
                return Err(EfgError::Invalid(format!(
                    "body `{}`: crack tip at ({:.6}, {:.6}): the ring of its interaction integral \
                     (outer radius {:.3e} m) is too small against the triangles it meets ({longest:.3e} m \
                     a side): the tip is too close to the body's boundary, another crack \
                     or the crack's other end",
                    self.name, p.x, p.y, ring.outer
                )));
            }
            triangle_points(std::slice::from_ref(&tri), sub as usize, &mut out);
        }
        Ok(out.into_iter().map(|q| (q.x, q.w)).collect())
    }
}
