//! Node sets and background integration of polygon bodies: a regular grid
//! at spacing `h` clipped to Ω (grid nodes closer than `h/2` to the
//! boundary dropped), nodes along every boundary segment at spacing ≤ `h`
//! (all vertices included), and the constrained Delaunay triangulation of
//! these nodes with the boundary pieces as constraints, which covers Ω
//! exactly: there are no cut cells, every Gauss point is inside Ω.
//!
//! **Refinement near edges** ([`Refine`], [`PolygonMesh::refined`]): a
//! graded size field `s(x) = min(h, min_r [h_r + G · max(0, d_r(x) − w_r)])`
//! (`d_r` the distance to refinement `r`'s segments, `w_r` its band width,
//! `G` = [`GRADING`]) sets the local spacing: boundary nodes are placed at
//! equal steps of `∫ ds / s` along each segment, and interior nodes come
//! from nested grids at spacings `h_r, 2h_r, 4h_r, …, h` (all anchored at
//! the `h` grid's origin), a grid point of level `s_k` being kept where
//! `s_k` is the largest level `≤ s(x)`, it is `s_k/2` clear of the boundary
//! and no kept node is closer than `s_k/2`. The spacing thus changes by at
//! most a factor 2 from one zone to the next, and over a distance of a few
//! nodes, instead of jumping from `h_r` to `h` at the band's edge. Each node
//! keeps its own spacing `h_I` (support `d_max · h_I`). The triangles follow
//! the node density; each is cut into `sub · k` per side, `k` from the
//! smallest support that reaches it ([`PolygonMesh::domain_points`]).

use crate::continuum::quadrature::{self, QuadPoint};
use crate::continuum::{CrackShape, Refine};
use crate::geom::Vec2;
use crate::geom::crack::{self, Crack, End};
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
    /// Each node's spacing `h_I` (its support half-width is `d_max · h_I`):
    /// `h` for every node of an unrefined mesh.
    pub node_spacing: Vec<f64>,
    /// `d_max` of a refined mesh (its quadrature adapts to the supports);
    /// `None` without refinement.
    pub refined_d_max: Option<f64>,
    /// Per loop, per segment: the nodes along it, from its start vertex to
    /// its end vertex (both included).
    pub segment_nodes: Vec<Vec<Vec<usize>>>,
    /// Triangles (counter-clockwise) of the integration triangulation.
    pub triangles: Vec<[usize; 3]>,
    /// Where each node stands in the geometry: its position, but for a
    /// crack's face node the point of the crack it stands off from
    /// ([`FACE_OFFSET`]); the triangles' corners, exactly.
    pub place: Vec<Vec2>,
    /// The cracks: stations and face nodes ([`CrackNodes`]).
    pub cracks: Vec<CrackNodes>,
}

/// A crack of a mesh: its polyline through the node stations and, per
/// station, the node on each face.
#[derive(Debug, Clone, PartialEq)]
pub struct CrackNodes {
    /// The crack as given (its vertices).
    pub crack: Crack,
    /// Its two ends.
    pub ends: [End; 2],
    /// Stations along the crack, from `points[0]` to the last point (the
    /// crack's vertices among them).
    pub stations: Vec<Vec2>,
    /// Per station: the node on the left face (left of the direction of
    /// the polyline) and the node on the right face; one node at a tip.
    pub nodes: Vec<[usize; 2]>,
}

impl CrackNodes {
    /// The stations with their tip flags, as the visibility criterion
    /// takes them ([`Support::with_cracks`](super::support::Support::with_cracks)).
    pub fn opaque(&self) -> (Vec<Vec2>, [bool; 2]) {
        (self.stations.clone(), self.ends.map(|e| e == End::Tip))
    }
}

/// Face nodes stand this fraction of their spacing off the crack, on
/// their side: the visibility criterion tells the two faces apart by
/// position alone (a ray between the faces crosses the crack), and the
/// offset is far below any length the discretisation resolves.
pub const FACE_OFFSET: f64 = 1e-6;

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
            node_spacing: vec![h; nodes.len()],
            refined_d_max: None,
            place: nodes.clone(),
            nodes,
            segment_nodes,
            triangles,
            cracks: Vec::new(),
        })
    }

    /// Nodes and triangulation of `domain` at spacing `h`, finer near the
    /// segments of `refine` (module doc); `d_max` is the support factor
    /// (for the quadrature). Without refinements this is [`new`](Self::new).
    pub fn refined(
        domain: &Domain,
        h: f64,
        refine: &[Refine],
        d_max: f64,
    ) -> Result<PolygonMesh, String> {
        Self::cracked(domain, h, refine, &[], d_max)
    }

    /// [`refined`](Self::refined) with cracks: the domain is split at each
    /// mouth (so that it is a vertex), nodes are placed along every crack
    /// at the local spacing (a pair per station, one on each face,
    /// [`FACE_OFFSET`] off it; one node at a tip), grid nodes keep clear of
    /// the cracks as of the boundary, and the triangulation has the crack
    /// pieces as constraints (no triangle straddles a crack; each corner on
    /// a crack is the face node of the triangle's side).
    pub fn cracked(
        domain: &Domain,
        h: f64,
        refine: &[Refine],
        cracks: &[CrackShape],
        d_max: f64,
    ) -> Result<PolygonMesh, String> {
        if refine.is_empty() && cracks.is_empty() {
            return PolygonMesh::new(domain, h);
        }
        if !(h > 0.0 && h.is_finite()) {
            return Err(format!("spacing must be positive, not {h}"));
        }
        let list: Vec<Crack> = cracks.iter().map(|c| c.crack.clone()).collect();
        let (domain, refine) = split_at_mouths(domain, refine, &list)?;
        let domain = &domain;
        let refine = &refine[..];
        for c in cracks {
            if let Some(sp) = c.spacing
                && !(sp > 0.0 && sp < h && c.width > 0.0 && c.width.is_finite())
            {
                return Err(format!(
                    "crack spacing {sp} must be in (0, {h}) and width {} > 0",
                    c.width
                ));
            }
        }
        for r in refine {
            if !(r.spacing > 0.0 && r.spacing < h && r.width > 0.0 && r.width.is_finite()) {
                return Err(format!(
                    "refinement spacing {} must be in (0, {h}) and width {} > 0",
                    r.spacing, r.width
                ));
            }
            if let Some(&(l, i)) = r
                .segments
                .iter()
                .find(|&&(l, i)| l >= domain.loops.len() || i >= domain.loops[l].len())
            {
                return Err(format!("refinement names no segment ({l}, {i})"));
            }
        }
        let mut bands: Vec<Band> = refine
            .iter()
            .map(|r| Band {
                segments: r
                    .segments
                    .iter()
                    .map(|&(l, i)| domain.loops[l].segment(i))
                    .collect(),
                spacing: r.spacing,
                width: r.width,
            })
            .collect();
        for c in cracks {
            if let Some(spacing) = c.spacing {
                bands.push(Band {
                    segments: (0..c.crack.pieces()).map(|i| c.crack.piece(i)).collect(),
                    spacing,
                    width: c.width,
                });
            }
        }
        let size = SizeField { h, bands: &bands };
        let mut nodes: Vec<Vec2> = Vec::new();
        let mut node_spacing: Vec<f64> = Vec::new();
        let mut segment_nodes = Vec::with_capacity(domain.loops.len());
        for l in &domain.loops {
            let n = l.len();
            let first = nodes.len();
            let mut segs = Vec::with_capacity(n);
            for i in 0..n {
                let (a, b) = l.segment(i);
                let mut ids = vec![nodes.len()];
                nodes.push(a);
                node_spacing.push(size.at(a));
                for t in size.stations(a, b) {
                    let p = a + (b - a) * t;
                    ids.push(nodes.len());
                    nodes.push(p);
                    node_spacing.push(size.at(p));
                }
                ids.push(if i + 1 == n { first } else { nodes.len() });
                segs.push(ids);
            }
            for ids in &segs {
                for w in ids.windows(2) {
                    // a boundary node's spacing: at least its pieces' lengths
                    let d = (nodes[w[1]] - nodes[w[0]]).norm();
                    node_spacing[w[0]] = node_spacing[w[0]].max(d);
                    node_spacing[w[1]] = node_spacing[w[1]].max(d);
                }
            }
            segment_nodes.push(segs);
        }
        let n_boundary = nodes.len();
        let crack_nodes = crack_face_nodes(
            &list,
            domain,
            &size,
            &mut nodes,
            &mut node_spacing,
            &mut segment_nodes,
            n_boundary,
        )?;
        // the levels, finest first: h_r·2^k below h, then h
        let finest = bands.iter().map(|r| r.spacing).fold(h, f64::min);
        let mut levels = Vec::new();
        let mut s = finest;
        while s < h * (1.0 - 1e-9) {
            levels.push(s);
            s *= 2.0;
        }
        levels.push(h);
        let level_of = |s: f64| -> usize {
            levels
                .iter()
                .rposition(|&l| l <= s * (1.0 + 1e-9))
                .unwrap_or(0)
        };
        let (lo, hi) = domain.bounds();
        // the h grid's origin (as in `new`), shared by every level
        let nx = ((hi.x - lo.x) / h).floor();
        let ny = ((hi.y - lo.y) / h).floor();
        let o = Vec2::new(
            lo.x + 0.5 * ((hi.x - lo.x) - nx * h),
            lo.y + 0.5 * ((hi.y - lo.y) - ny * h),
        );
        let mut bins = Bins::new(lo, finest);
        for (k, p) in nodes.iter().enumerate() {
            bins.insert(*p, k);
        }
        for (k, &sk) in levels.iter().enumerate() {
            // where level k can occur: near a refinement (s(x) < 2 s_k)
            // or, for the coarsest, anywhere
            let boxes: Vec<(Vec2, Vec2)> = if k + 1 == levels.len() {
                vec![(lo, hi)]
            } else {
                bands
                    .iter()
                    .filter(|r| r.spacing < 2.0 * sk)
                    .map(|r| {
                        let reach = r.width + (2.0 * sk - r.spacing) / GRADING;
                        let (mut a, mut b) = (hi, lo);
                        for &(p, q) in &r.segments {
                            for v in [p, q] {
                                a = Vec2::new(a.x.min(v.x), a.y.min(v.y));
                                b = Vec2::new(b.x.max(v.x), b.y.max(v.y));
                            }
                        }
                        let e = Vec2::new(reach, reach);
                        (a - e, b + e)
                    })
                    .collect()
            };
            for (a, b) in boxes {
                let (a, b) = (
                    Vec2::new(a.x.max(lo.x), a.y.max(lo.y)),
                    Vec2::new(b.x.min(hi.x), b.y.min(hi.y)),
                );
                let (i0, i1) = (
                    ((a.x - o.x) / sk).floor() as i64,
                    ((b.x - o.x) / sk).ceil() as i64,
                );
                let (j0, j1) = (
                    ((a.y - o.y) / sk).floor() as i64,
                    ((b.y - o.y) / sk).ceil() as i64,
                );
                for j in j0..=j1 {
                    for i in i0..=i1 {
                        let p = Vec2::new(o.x + i as f64 * sk, o.y + j as f64 * sk);
                        if !domain.contains(p)
                            || level_of(size.at(p)) != k
                            || domain.boundary_distance(p) < 0.5 * sk
                            || list.iter().any(|c| c.distance(p) < 0.5 * sk)
                            || bins.any_within(&nodes, p, 0.5 * sk)
                        {
                            continue;
                        }
                        bins.insert(p, nodes.len());
                        nodes.push(p);
                        node_spacing.push(size.at(p));
                    }
                }
            }
        }
        let (place, triangles) = crack_triangles(&nodes, &segment_nodes, &crack_nodes, domain)?;
        Ok(PolygonMesh {
            domain: domain.clone(),
            spacing: h,
            nodes,
            node_spacing,
            refined_d_max: Some(d_max),
            segment_nodes,
            triangles,
            place,
            cracks: crack_nodes,
        })
    }

    /// Gauss points of the triangles: Dunavant's degree-5 rule on each
    /// triangle split into `sub²` sub-triangles.
    ///
    /// A refined mesh splits each triangle into `(sub · k)²`, with
    /// `k = ⌈ℓ / (c · h_min)⌉`, `ℓ` the triangle's longest side and `h_min`
    /// the smallest spacing `h_I` of the nodes whose support (half-width
    /// `d_max · h_I`) meets the triangle's bounding box; `c` =
    /// [`UNIFORM_PIECE`] where all those supports have the same spacing
    /// (pieces as in a uniform mesh at `h_min`, `k = 1` in the mesh's
    /// uniform zones), [`GRADED_PIECE`] where they differ (in and near the
    /// graded zone, where the shape functions vary faster). Judging by the
    /// triangle's corners only is not enough: the refined L-shape's patch
    /// test then gave 1.9e−4. Splitting by the triangle's own corners does not
    /// suffice: at a change of spacing, small supports of fine nodes reach
    /// into triangles whose corners are all coarse.
    pub fn domain_points(&self, sub: usize) -> Vec<QuadPoint> {
        let tris: Vec<[Vec2; 3]> = self
            .triangles
            .iter()
            .map(|t| t.map(|i| self.place[i]))
            .collect();
        let mut out = Vec::with_capacity(tris.len() * 7 * sub * sub);
        let Some(d_max) = self.refined_d_max else {
            quadrature::triangle_points(&tris, sub, &mut out);
            return out;
        };
        let tips: Vec<Vec2> = self
            .cracks
            .iter()
            .flat_map(|c| {
                [
                    (0, c.stations[0]),
                    (1, *c.stations.last().expect("≥ 2 stations")),
                ]
                .into_iter()
                .filter(|&(e, _)| c.ends[e] == End::Tip)
                .map(|(_, p)| p)
            })
            .collect();
        let (lo, _) = self.domain.bounds();
        let reach = d_max * self.spacing;
        let mut bins = Bins::new(lo, reach);
        for (k, p) in self.nodes.iter().enumerate() {
            bins.insert(*p, k);
        }
        for tri in &tris {
            let (mut a, mut b) = (tri[0], tri[0]);
            for v in &tri[1..] {
                a = Vec2::new(a.x.min(v.x), a.y.min(v.y));
                b = Vec2::new(b.x.max(v.x), b.y.max(v.y));
            }
            let (mut h_min, mut h_max) = (f64::INFINITY, 0.0f64);
            bins.visit(a, b, |k| {
                let (p, d) = (self.nodes[k], d_max * self.node_spacing[k]);
                if p.x + d > a.x && p.x - d < b.x && p.y + d > a.y && p.y - d < b.y {
                    h_min = h_min.min(self.node_spacing[k]);
                    h_max = h_max.max(self.node_spacing[k]);
                }
            });
            let longest = (0..3)
                .map(|k| (tri[(k + 1) % 3] - tri[k]).norm())
                .fold(0.0, f64::max);
            let mut per = if h_max <= h_min * (1.0 + 1e-6) {
                UNIFORM_PIECE
            } else {
                GRADED_PIECE
            };
            let near_tip = tips.iter().any(|&p| {
                (0..3).any(|k| {
                    let q = crate::geom::closest_on_segment(p, tri[k], tri[(k + 1) % 3]).1;
                    (q - p).norm() < d_max * h_min
                })
            });
            if near_tip {
                per = per.min(TIP_PIECE);
            }
            let k = (longest / (per * h_min)).ceil().max(1.0) as usize;
            quadrature::triangle_points(std::slice::from_ref(tri), sub * k, &mut out);
        }
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

/// Quadrature of a refined mesh: longest piece side, in units of the
/// smallest support spacing `h_min`, of a triangle whose supports all have
/// the same spacing (as in a uniform mesh: its triangles are not split
/// further, `√2 h < 1.5 h`).
pub const UNIFORM_PIECE: f64 = 1.5;

/// Quadrature of a refined mesh: longest piece side, in units of `h_min`,
/// of a triangle met by supports of different spacings (the graded zone):
/// the holed-square patch test measured 8.5e−4 / 1.8e−4 / 2.6e−5 stress
/// error at 1.5 / 0.75 / 0.5.
pub const GRADED_PIECE: f64 = 0.5;

/// Quadrature near a crack tip (triangles closer to a tip than `d_max ·
/// h_min`, where the diffraction bends the weights sharply): longest
/// piece side in units of `h_min`. A uniaxial stress along a crack (which
/// the crack leaves uniform) is reproduced to 6e−4 of the stress at 1.5
/// (the uniform piece), 4e−5 at 0.25 (6 × 6-point rule, h = 0.1 of the
/// crack's half-length).
pub const TIP_PIECE: f64 = 0.25;

/// Growth of the refined size field per unit distance beyond a band:
/// `s(x) = h_r + G · (d − w)`, so neighbouring node rows differ in spacing
/// by a factor of about `1 + G`.
pub const GRADING: f64 = 0.5;

/// A refined band: segments, the spacing near them and the band's width.
struct Band {
    segments: Vec<(Vec2, Vec2)>,
    spacing: f64,
    width: f64,
}

/// The graded size field `s(x)` of a refined mesh (module doc).
struct SizeField<'a> {
    h: f64,
    bands: &'a [Band],
}

impl SizeField<'_> {
    /// `s(p)`.
    fn at(&self, p: Vec2) -> f64 {
        self.bands.iter().fold(self.h, |s, r| {
            let d = r
                .segments
                .iter()
                .map(|&(a, b)| (p - crate::geom::closest_on_segment(p, a, b).1).norm())
                .fold(f64::INFINITY, f64::min);
            s.min(r.spacing + GRADING * (d - r.width).max(0.0))
        })
    }

    /// Interior stations `t ∈ (0, 1)` of boundary nodes on `a → b`: `N =
    /// ⌈∫ ds/s⌉` pieces of equal `∫ ds/s` (trapezoidal on a fine sampling),
    /// so that no piece is longer than about the local `s`.
    fn stations(&self, a: Vec2, b: Vec2) -> Vec<f64> {
        let len = (b - a).norm();
        let finest = self.bands.iter().map(|r| r.spacing).fold(self.h, f64::min);
        let m = ((8.0 * len / finest).ceil() as usize).clamp(1, 1 << 20);
        let mut cum = vec![0.0; m + 1];
        let mut prev = 1.0 / self.at(a);
        for j in 1..=m {
            let cur = 1.0 / self.at(a + (b - a) * (j as f64 / m as f64));
            cum[j] = cum[j - 1] + 0.5 * (prev + cur) * len / m as f64;
            prev = cur;
        }
        let total = cum[m];
        let n = (total * (1.0 - 1e-9)).ceil().max(1.0) as usize;
        let mut out = Vec::with_capacity(n.saturating_sub(1));
        let mut j = 0;
        for k in 1..n {
            let target = total * k as f64 / n as f64;
            while cum[j + 1] < target {
                j += 1;
            }
            let f = (target - cum[j]) / (cum[j + 1] - cum[j]);
            out.push((j as f64 + f) / m as f64);
        }
        out
    }
}

/// `domain` with a vertex at every crack mouth that is not one yet (the
/// boundary nodes then split there), and `refine`'s segments renumbered.
fn split_at_mouths(
    domain: &Domain,
    refine: &[Refine],
    cracks: &[Crack],
) -> Result<(Domain, Vec<Refine>), String> {
    let ends = crack::check(domain, cracks).map_err(|e| e.to_string())?;
    let mut d = domain.clone();
    let mut refine = refine.to_vec();
    for (c, e) in cracks.iter().zip(&ends) {
        for (k, end) in e.iter().enumerate() {
            if !matches!(end, End::Mouth(..)) {
                continue;
            }
            let p = c.end(k).0;
            if d.loops.iter().any(|l| l.points.contains(&p)) {
                continue;
            }
            let Some((l, s)) = d.loops.iter().enumerate().find_map(|(l, lp)| {
                (0..lp.len())
                    .find(|&s| {
                        let (a, b) = lp.segment(s);
                        crate::geom::polygon::on_segment(a, b, p)
                    })
                    .map(|s| (l, s))
            }) else {
                continue;
            };
            d = crack::split(&d, l, s, p);
            for r in &mut refine {
                r.segments = r
                    .segments
                    .iter()
                    .flat_map(|&x| crack::split_index(x, l, s))
                    .collect();
            }
        }
    }
    Ok((d, refine))
}

/// The face nodes of `cracks` (module doc of [`PolygonMesh::cracked`]):
/// stations at the local spacing along each piece; per station a node on
/// each face [`FACE_OFFSET`] off the crack (offset along the mean normal
/// of the pieces that meet there), one node at a tip; at a mouth, the
/// boundary node at the mouth becomes the node of the face on the side of
/// the segment that starts there, and a new node stands for the other face
/// (ending the segment before), each moved along its segment.
fn crack_face_nodes(
    cracks: &[Crack],
    domain: &Domain,
    size: &SizeField,
    nodes: &mut Vec<Vec2>,
    node_spacing: &mut Vec<f64>,
    segment_nodes: &mut [Vec<Vec<usize>>],
    n_boundary: usize,
) -> Result<Vec<CrackNodes>, String> {
    let ends = crack::check(domain, cracks).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(cracks.len());
    for (c, ends) in cracks.iter().zip(ends) {
        let mut stations = Vec::new();
        let mut vertex = Vec::new(); // the piece index of a crack vertex
        for i in 0..c.pieces() {
            let (a, b) = c.piece(i);
            stations.push(a);
            vertex.push(Some(i));
            for t in size.stations(a, b) {
                stations.push(a + (b - a) * t);
                vertex.push(None);
            }
        }
        stations.push(*c.points.last().expect("a crack has ≥ 2 points"));
        vertex.push(Some(c.pieces()));
        let m = stations.len();
        let unit = |d: Vec2| d * (1.0 / d.norm());
        let mut ids = Vec::with_capacity(m);
        for j in 0..m {
            let p = stations[j];
            let h_j = size.at(p);
            let end = if j == 0 {
                Some(ends[0])
            } else if j + 1 == m {
                Some(ends[1])
            } else {
                None
            };
            // the unit normal to the left of the crack's direction here
            let left = match vertex[j] {
                Some(i) if i > 0 && i < c.pieces() => {
                    let (a, b) = c.piece(i - 1);
                    let (_, d) = c.piece(i);
                    let n = unit(b - a).perp() + unit(d - b).perp();
                    unit(n)
                }
                _ => {
                    let k = j.min(m - 2);
                    unit(stations[k + 1] - stations[k]).perp()
                }
            };
            let spacing = |k: usize| {
                let mut s = h_j;
                if k > 0 {
                    s = s.max((stations[k] - stations[k - 1]).norm());
                }
                if k + 1 < m {
                    s = s.max((stations[k + 1] - stations[k]).norm());
                }
                s
            };
            match end {
                Some(End::Tip) => {
                    ids.push([nodes.len(); 2]);
                    nodes.push(p);
                    node_spacing.push(spacing(j));
                }
                Some(End::Mouth(..)) => {
                    let Some(id) = (0..n_boundary).find(|&i| nodes[i] == p) else {
                        return Err(format!(
                            "crack mouth ({}, {}) has no boundary node",
                            p.x, p.y
                        ));
                    };
                    let (l, v) = segment_nodes
                        .iter()
                        .enumerate()
                        .find_map(|(l, segs)| {
                            segs.iter().position(|ids| ids[0] == id).map(|v| (l, v))
                        })
                        .ok_or_else(|| "crack mouth off the loops".to_string())?;
                    let n = segment_nodes[l].len();
                    let prev = (v + n - 1) % n;
                    let after = nodes[segment_nodes[l][v][1]];
                    let before = {
                        let s = &segment_nodes[l][prev];
                        nodes[s[s.len() - 2]]
                    };
                    let d = FACE_OFFSET * h_j;
                    nodes[id] = p + unit(after - p) * d;
                    let other = nodes.len();
                    nodes.push(p + unit(before - p) * d);
                    node_spacing.push(node_spacing[id]);
                    *segment_nodes[l][prev].last_mut().expect("≥ 2 nodes") = other;
                    let inner = stations[if j == 0 { 1 } else { m - 2 }];
                    // left of the crack's direction (from points[0] on)
                    let (a, b) = if j == 0 { (p, inner) } else { (inner, p) };
                    let id_left = crate::geom::polygon::orient(a, b, nodes[id]) > 0;
                    ids.push(if id_left { [id, other] } else { [other, id] });
                }
                None => {
                    let d = left * (FACE_OFFSET * h_j);
                    ids.push([nodes.len(), nodes.len() + 1]);
                    nodes.push(p + d);
                    nodes.push(p - d);
                    node_spacing.push(spacing(j));
                    node_spacing.push(spacing(j));
                }
            }
        }
        out.push(CrackNodes {
            crack: c.clone(),
            ends,
            stations,
            nodes: ids,
        });
    }
    Ok(out)
}

/// Side of the crack through `stations` that the point `c` near station
/// `j` is on: 0 left (of the polyline's direction), 1 right.
fn side_at(stations: &[Vec2], j: usize, c: Vec2) -> usize {
    let m = stations.len();
    let p = stations[j];
    let left = if j == 0 || j + 1 == m {
        let k = j.min(m - 2);
        crate::geom::polygon::orient(stations[k], stations[k + 1], c) > 0
    } else {
        // the left wedge: from the outgoing piece counter-clockwise to the
        // incoming one reversed
        let ang = |d: Vec2, r: Vec2| {
            let a = r.cross(d).atan2(r.dot(d));
            if a < 0.0 {
                a + std::f64::consts::TAU
            } else {
                a
            }
        };
        let out = stations[j + 1] - p;
        ang(c - p, out) < ang(stations[j - 1] - p, out)
    };
    if left { 0 } else { 1 }
}

/// The triangulation of a mesh with cracks: every node at its place (face
/// nodes at their station, one vertex per station), the boundary pieces
/// and the crack pieces as constraints; a triangle's corner at a crack
/// station is the face node of the triangle's side. Returns the places and
/// the triangles (node indices).
fn crack_triangles(
    nodes: &[Vec2],
    segment_nodes: &[Vec<Vec<usize>>],
    cracks: &[CrackNodes],
    domain: &Domain,
) -> Result<(Vec<Vec2>, Vec<[usize; 3]>), String> {
    let mut place = nodes.to_vec();
    // the node standing for each vertex; a station's left node for both
    let mut vertex_of: Vec<usize> = (0..nodes.len()).collect();
    let mut station_of: Vec<Option<(usize, usize)>> = vec![None; nodes.len()];
    for (k, c) in cracks.iter().enumerate() {
        for (j, &[l, r]) in c.nodes.iter().enumerate() {
            place[l] = c.stations[j];
            place[r] = c.stations[j];
            vertex_of[r] = l;
            station_of[l] = Some((k, j));
        }
    }
    let mut index = vec![usize::MAX; nodes.len()];
    let mut verts = Vec::new();
    let mut node_of_vertex = Vec::new();
    for i in 0..nodes.len() {
        if vertex_of[i] == i {
            index[i] = verts.len();
            verts.push(place[i]);
            node_of_vertex.push(i);
        }
    }
    let vid = |i: usize| index[vertex_of[i]];
    let mut constraints = Vec::new();
    for segs in segment_nodes {
        for ids in segs {
            for w in ids.windows(2) {
                constraints.push([vid(w[0]), vid(w[1])]);
            }
        }
    }
    for c in cracks {
        for w in c.nodes.windows(2) {
            constraints.push([vid(w[0][0]), vid(w[1][0])]);
        }
    }
    let tris = triangulate(&verts, &constraints, domain).map_err(|e| e.to_string())?;
    let triangles = tris
        .into_iter()
        .map(|t| {
            let centroid = (verts[t[0]] + verts[t[1]] + verts[t[2]]) * (1.0 / 3.0);
            t.map(|v| {
                let n = node_of_vertex[v];
                match station_of[n] {
                    Some((k, j)) => {
                        let c = &cracks[k];
                        c.nodes[j][side_at(&c.stations, j, centroid)]
                    }
                    None => n,
                }
            })
        })
        .collect();
    Ok((place, triangles))
}

/// A uniform bin grid of points (node lookup by neighbourhood).
struct Bins {
    origin: Vec2,
    cell: f64,
    map: std::collections::HashMap<(i64, i64), Vec<usize>>,
}

impl Bins {
    fn new(origin: Vec2, cell: f64) -> Bins {
        Bins {
            origin,
            cell,
            map: std::collections::HashMap::new(),
        }
    }
    fn key(&self, p: Vec2) -> (i64, i64) {
        (
            ((p.x - self.origin.x) / self.cell).floor() as i64,
            ((p.y - self.origin.y) / self.cell).floor() as i64,
        )
    }
    fn insert(&mut self, p: Vec2, k: usize) {
        let key = self.key(p);
        self.map.entry(key).or_default().push(k);
    }
    /// Every point in the bins that meet the box `[a, b]` widened by a cell.
    fn visit(&self, a: Vec2, b: Vec2, mut f: impl FnMut(usize)) {
        let (i0, j0) = self.key(a);
        let (i1, j1) = self.key(b);
        for j in j0 - 1..=j1 + 1 {
            for i in i0 - 1..=i1 + 1 {
                if let Some(v) = self.map.get(&(i, j)) {
                    v.iter().for_each(|&k| f(k));
                }
            }
        }
    }
    /// Is a point closer than `r` to `p`?
    fn any_within(&self, pts: &[Vec2], p: Vec2, r: f64) -> bool {
        let mut hit = false;
        let e = Vec2::new(r, r);
        self.visit(p - e, p + e, |k| hit |= (pts[k] - p).norm() < r);
        hit
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

    #[test]
    fn refined_mesh_is_graded_and_covers_the_domain() {
        let outline: Vec<Vec2> = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]
            .iter()
            .map(|&p| p.into())
            .collect();
        let hole = crate::geom::polygon::circle(Vec2::new(2.0, 2.0), 0.5, 32);
        let d = Domain::new(outline, vec![hole], vec![]).unwrap();
        let (h, hr, w) = (0.4, 0.05, 0.3);
        let r = Refine {
            segments: (0..32).map(|i| (1, i)).collect(),
            spacing: hr,
            width: w,
        };
        let m = PolygonMesh::refined(&d, h, std::slice::from_ref(&r), 2.0).unwrap();
        let plain = PolygonMesh::refined(&d, h, &[], 2.0).unwrap();
        assert_eq!(plain.nodes, PolygonMesh::new(&d, h).unwrap().nodes);
        let q = m.domain_points(1);
        let area: f64 = q.iter().map(|p| p.w).sum();
        assert!((area - d.area()).abs() < 1e-12 * d.area(), "{area}");
        assert!(q.iter().all(|p| d.contains(p.x)));
        let c = Vec2::new(2.0, 2.0);
        for (k, p) in m.nodes.iter().enumerate() {
            // the nearest other node: at least half the node's grid level
            // (which is > s/2), the band's interior nodes at exactly h_r
            let near = m
                .nodes
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != k)
                .map(|(_, q)| (*q - *p).norm())
                .fold(f64::INFINITY, f64::min);
            let dist = (*p - c).norm() - 0.5;
            let s = (hr + GRADING * (dist - w).max(0.0)).min(h);
            assert!(
                (m.node_spacing[k] - s).abs() < 0.02 * s + 0.01 * hr
                    || k < m
                        .segment_nodes
                        .iter()
                        .flatten()
                        .map(Vec::len)
                        .sum::<usize>(),
                "node {k} at {p:?}: h_I = {} vs s = {s}",
                m.node_spacing[k]
            );
            assert!(
                near >= 0.25 * s * (1.0 - 1e-9),
                "node {k} at {p:?}: nearest {near}, s = {s}"
            );
            if dist < w - 0.01 && d.boundary_distance(*p) > hr {
                assert!(
                    near <= hr * 1.0001,
                    "node {k} at {p:?} in the band: nearest {near}"
                );
            }
        }
        // far fewer nodes than a uniform h_r mesh, more than a uniform h one
        let n_fine = d.area() / (hr * hr);
        assert!(m.nodes.len() > plain.nodes.len() + 200 && (m.nodes.len() as f64) < 0.2 * n_fine);
    }
}
