//! What the coupling needs from a continuum body: its current contact
//! boundary, the velocity of a boundary material point, point loads, and one
//! time step. Two implementations: the EFG body and (for comparison) the
//! bilinear FE body, so the coupling never knows which one it talks to.

use crate::geom::Vec2;

/// A polyline on the body's contact boundary, oriented with the body on its
/// left (counter-clockwise around the body), so the outward normal of a
/// segment `a → b` is `(b − a)` rotated by −90°.
#[derive(Debug, Clone, Default)]
pub struct BoundaryChain {
    /// Material (reference) coordinates of the chain's points.
    pub reference: Vec<Vec2>,
    /// Current (true, displaced) positions of the same points (ERRATA E7:
    /// interpolated displacements, not raw EFG nodal parameters).
    pub current: Vec<Vec2>,
}

impl BoundaryChain {
    /// A chain at rest: current = reference.
    pub fn new(reference: Vec<Vec2>) -> Self {
        BoundaryChain {
            current: reference.clone(),
            reference,
        }
    }

    /// Number of segments.
    pub fn segments(&self) -> usize {
        self.reference.len().saturating_sub(1)
    }

    /// Material point at parameter `s ∈ [0, 1]` of segment `seg`.
    pub fn material_point(&self, seg: usize, s: f64) -> Vec2 {
        let a = self.reference[seg];
        a + (self.reference[seg + 1] - a) * s
    }
}
