//! Contact traction profile along one edge of a rectangular body: the
//! normal and shear tractions the discs exert on the edge, binned by the
//! position along it (the depth, on a vertical wall) and averaged over
//! the states it is given (the grains chatter; one state is noisy).
//!
//! From the disc–body contacts of the coupling ([`BodyContact`]): the force
//! on the body is minus the force on the disc (spring and dashpot, the
//! same force the `contact_fx`/`contact_fy` probes sum), applied at the
//! contact point. A contact belongs to the edge whose outward normal (in
//! the reference configuration) is closest to the direction disc → body
//! reversed, `−n` (a contact at a corner vertex goes to one of its two
//! edges by its normal); it falls into the bin of its coordinate along the
//! edge (x on the bottom and top, y on the left and right), clamped to the
//! first or last bin when a deformed boundary puts it a little outside.
//!
//! Per bin of length `Δs` and a body of thickness `t`, averaged over the
//! `N` states added:
//! - normal traction `p = (1/N) Σ_states Σ_contacts F·(−n_out) / (Δs t)`,
//!   compression positive (an earth pressure);
//! - shear traction `τ = (1/N) Σ Σ F·e_s / (Δs t)` along the edge's
//!   coordinate direction `e_s` (+x or +y): on a vertical wall, grains
//!   that drag it down give `τ < 0`.
//!
//! The sum over the bins of `p Δs t (−n_out) + τ Δs t e_s` is the
//! resultant of the contacts on the edge, which for a body whose every
//! contact is on this edge is the time average of its `contact_fx`,
//! `contact_fy` probes.

use crate::continuum::{Edge, Rectangle};
use crate::coupling::BodyContact;
use crate::geom::Vec2;

/// Why a profile cannot be set up.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TractionError {
    /// No bins, or an empty or reversed range.
    #[error(
        "a traction profile needs bins ≥ 1 and a range from < to (got {bins} bins on [{from}, {to}])"
    )]
    Range {
        /// Bins asked for.
        bins: usize,
        /// Start of the range.
        from: f64,
        /// End of the range.
        to: f64,
    },
    /// Thickness not positive.
    #[error("a traction profile needs a thickness > 0 (got {0})")]
    Thickness(f64),
}

/// One bin of an averaged profile.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TractionBin {
    /// Start of the bin (coordinate along the edge: x or y).
    pub from: f64,
    /// End of the bin.
    pub to: f64,
    /// Normal traction on the body, compression positive (Pa).
    pub normal: f64,
    /// Shear traction on the body along +x (bottom, top) or +y (left,
    /// right) (Pa).
    pub shear: f64,
    /// Mean number of contacts in the bin per state.
    pub contacts: f64,
}

impl TractionBin {
    /// Middle of the bin.
    pub fn mid(&self) -> f64 {
        0.5 * (self.from + self.to)
    }
}

/// The outward unit normal of a rectangle's edge.
pub fn outward_normal(edge: Edge) -> Vec2 {
    match edge {
        Edge::Left => Vec2::new(-1.0, 0.0),
        Edge::Right => Vec2::new(1.0, 0.0),
        Edge::Bottom => Vec2::new(0.0, -1.0),
        Edge::Top => Vec2::new(0.0, 1.0),
    }
}

/// The coordinate direction along an edge: +x (bottom, top), +y (left,
/// right).
pub fn edge_direction(edge: Edge) -> Vec2 {
    match edge {
        Edge::Left | Edge::Right => Vec2::new(0.0, 1.0),
        Edge::Bottom | Edge::Top => Vec2::new(1.0, 0.0),
    }
}

/// The edge a contact with unit normal `n` (disc → body) presses on: the
/// one whose outward normal is closest to `−n` (ties go to the first of
/// [`Edge::ALL`]).
pub fn edge_of(n: Vec2) -> Edge {
    let mut best = (Edge::ALL[0], f64::NEG_INFINITY);
    for e in Edge::ALL {
        let d = -n.dot(outward_normal(e));
        if d > best.1 {
            best = (e, d);
        }
    }
    best.0
}

/// Accumulated tractions of the contacts of one body on one of its edges.
#[derive(Debug, Clone)]
pub struct EdgeTraction {
    /// Body index (in the model's order).
    pub body: usize,
    /// The edge.
    pub edge: Edge,
    /// Start of the binned range (coordinate along the edge).
    pub from: f64,
    /// End of the binned range.
    pub to: f64,
    /// Body thickness t (the contact forces are per t).
    pub thickness: f64,
    /// Σ over states and contacts of the normal force, per bin.
    normal: Vec<f64>,
    /// Σ of the shear force, per bin.
    shear: Vec<f64>,
    /// Σ of the contact counts, per bin.
    count: Vec<u64>,
    /// States added.
    samples: usize,
}

impl EdgeTraction {
    /// `bins` equal bins over `[from, to]` of the coordinate along `edge`
    /// of body `body`, whose thickness is `thickness`.
    pub fn new(
        body: usize,
        edge: Edge,
        from: f64,
        to: f64,
        bins: usize,
        thickness: f64,
    ) -> Result<Self, TractionError> {
        if bins == 0
            || from.is_nan()
            || to.is_nan()
            || from >= to
            || !from.is_finite()
            || !to.is_finite()
        {
            return Err(TractionError::Range { bins, from, to });
        }
        if thickness.is_nan() || thickness <= 0.0 || !thickness.is_finite() {
            return Err(TractionError::Thickness(thickness));
        }
        Ok(EdgeTraction {
            body,
            edge,
            from,
            to,
            thickness,
            normal: vec![0.0; bins],
            shear: vec![0.0; bins],
            count: vec![0; bins],
            samples: 0,
        })
    }

    /// `bins` bins over the whole edge of the rectangle `rect`.
    pub fn whole_edge(
        body: usize,
        rect: &Rectangle,
        edge: Edge,
        bins: usize,
        thickness: f64,
    ) -> Result<Self, TractionError> {
        let [x0, y0] = rect.origin;
        let [w, h] = rect.size;
        let (from, to) = match edge {
            Edge::Left | Edge::Right => (y0, y0 + h),
            Edge::Bottom | Edge::Top => (x0, x0 + w),
        };
        Self::new(body, edge, from, to, bins, thickness)
    }

    /// Number of bins.
    pub fn bins(&self) -> usize {
        self.normal.len()
    }

    /// Number of states added since the last [`reset`](Self::reset).
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Bin of coordinate `s`, clamped to the range.
    fn bin(&self, s: f64) -> usize {
        let n = self.bins();
        let k = ((s - self.from) / (self.to - self.from) * n as f64).floor();
        if k.is_nan() || k < 0.0 {
            0
        } else {
            (k as usize).min(n - 1)
        }
    }

    /// Add one state: the disc–body contacts of the model (all bodies;
    /// those of other bodies and other edges are skipped). No allocation.
    pub fn add(&mut self, contacts: &[BodyContact]) {
        let out = outward_normal(self.edge);
        let dir = edge_direction(self.edge);
        for c in contacts {
            if c.body as usize != self.body || edge_of(c.normal) != self.edge {
                continue;
            }
            let f = -c.force; // on the body
            let k = self.bin(c.point.dot(dir));
            self.normal[k] += -f.dot(out);
            self.shear[k] += f.dot(dir);
            self.count[k] += 1;
        }
        self.samples += 1;
    }

    /// Forget the states added (start a new averaging window).
    pub fn reset(&mut self) {
        self.normal.iter_mut().for_each(|v| *v = 0.0);
        self.shear.iter_mut().for_each(|v| *v = 0.0);
        self.count.iter_mut().for_each(|v| *v = 0);
        self.samples = 0;
    }

    /// The averaged profile (all zero before any state is added).
    pub fn profile(&self) -> Vec<TractionBin> {
        let n = self.bins();
        let ds = (self.to - self.from) / n as f64;
        let per = if self.samples > 0 {
            1.0 / self.samples as f64
        } else {
            0.0
        };
        let area = ds * self.thickness;
        (0..n)
            .map(|k| TractionBin {
                from: self.from + k as f64 * ds,
                to: if k + 1 == n {
                    self.to
                } else {
                    self.from + (k + 1) as f64 * ds
                },
                normal: self.normal[k] * per / area,
                shear: self.shear[k] * per / area,
                contacts: self.count[k] as f64 * per,
            })
            .collect()
    }

    /// The averaged resultant force of the contacts on the edge (per the
    /// thickness t: N for the body's t): `Σ_bins (p (−n_out) + τ e_s) Δs t`.
    pub fn resultant(&self) -> Vec2 {
        let out = outward_normal(self.edge);
        let dir = edge_direction(self.edge);
        let per = if self.samples > 0 {
            1.0 / self.samples as f64
        } else {
            0.0
        };
        let n: f64 = self.normal.iter().sum();
        let s: f64 = self.shear.iter().sum();
        (out * (-n) + dir * s) * per
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coupling::interface::Feature;

    fn contact(
        body: u16,
        point: [f64; 2],
        normal: [f64; 2],
        force_on_disc: [f64; 2],
    ) -> BodyContact {
        BodyContact {
            disc: 0,
            body,
            chain: 0,
            fs: 0.0,
            mr: 0.0,
            moment: 0.0,
            overlap: 1e-6,
            fn_elastic: 0.0,
            fn_total: 0.0,
            force: Vec2::new(force_on_disc[0], force_on_disc[1]),
            point: Vec2::new(point[0], point[1]),
            normal: Vec2::new(normal[0], normal[1]),
            material: Vec2::new(point[0], point[1]),
            feature: Feature::Point(0),
        }
    }

    /// Hand-built contacts on the left face of a wall body (x = 0, y in
    /// [0, 1], 4 bins of 0.25, t = 2): each lands in its bin with the
    /// traction F/(Δs t), the others (another body, another edge) are
    /// skipped, and two states average.
    #[test]
    fn hand_built_contacts_fall_into_their_bins() {
        let mut p = EdgeTraction::new(1, Edge::Left, 0.0, 1.0, 4, 2.0).unwrap();
        // a disc left of the wall pushes it along +x: normal disc→body = +x,
        // force on the disc −10 x̂ (pushed back) and +3 ŷ (the wall drags it
        // up: the body gets −3 ŷ, τ = −3)
        let a = contact(1, [0.0, 0.1], [1.0, 0.0], [-10.0, 3.0]);
        let b = contact(1, [0.0, 0.6], [1.0, 0.0], [-20.0, 0.0]);
        let c = contact(1, [0.0, 0.62], [0.995, 0.0998], [-4.0, -1.0]);
        let other_body = contact(0, [0.0, 0.1], [1.0, 0.0], [-100.0, 0.0]);
        let other_edge = contact(1, [0.5, 1.0], [0.0, -1.0], [0.0, 50.0]);
        let above = contact(1, [0.0, 1.0001], [1.0, 0.0], [-8.0, 0.0]);
        let set = [a, b, c, other_body, other_edge, above];
        p.add(&set);
        let q = p.profile();
        let area = 0.25 * 2.0;
        assert_eq!(q.len(), 4);
        assert!((q[0].normal - 10.0 / area).abs() < 1e-12);
        assert!((q[0].shear - (-3.0) / area).abs() < 1e-12);
        assert!((q[2].normal - 24.0 / area).abs() < 1e-12);
        assert!((q[2].shear - 1.0 / area).abs() < 1e-12);
        assert_eq!(q[1].normal, 0.0);
        assert!((q[3].normal - 8.0 / area).abs() < 1e-12); // clamped in
        assert_eq!(q[2].contacts, 2.0);
        assert!((q[3].mid() - 0.875).abs() < 1e-15);
        // resultant = minus the forces on the discs of the edge's contacts
        let r = p.resultant();
        assert!((r.x - 42.0).abs() < 1e-12 && (r.y - (-3.0 + 1.0)).abs() < 1e-12);
        // a second state with nothing: the average halves
        p.add(&[]);
        assert!((p.profile()[0].normal - 5.0 / area).abs() < 1e-12);
        p.reset();
        assert_eq!(p.samples(), 0);
        assert_eq!(p.profile()[0].normal, 0.0);
    }

    #[test]
    fn edge_of_picks_the_pressed_edge() {
        assert_eq!(edge_of(Vec2::new(1.0, 0.0)), Edge::Left);
        assert_eq!(edge_of(Vec2::new(-1.0, 0.1)), Edge::Right);
        assert_eq!(edge_of(Vec2::new(0.2, -1.0)), Edge::Top);
        assert_eq!(edge_of(Vec2::new(0.0, 1.0)), Edge::Bottom);
    }

    #[test]
    fn bad_ranges_are_errors() {
        assert!(EdgeTraction::new(0, Edge::Left, 1.0, 0.0, 3, 1.0).is_err());
        assert!(EdgeTraction::new(0, Edge::Left, 0.0, 1.0, 0, 1.0).is_err());
        assert!(EdgeTraction::new(0, Edge::Left, 0.0, 1.0, 3, 0.0).is_err());
        let r = Rectangle {
            origin: [1.0, 2.0],
            size: [3.0, 4.0],
        };
        let p = EdgeTraction::whole_edge(0, &r, Edge::Top, 6, 1.0).unwrap();
        assert_eq!((p.from, p.to), (1.0, 4.0));
    }
}
