//! Support domains: sizes `d_mI = d_max · c_I` per direction (Eqs. 7–8) and
//! a bin grid that returns, for any point, the nodes whose support covers it.

use crate::geom::Vec2;

/// Nodes with their rectangular supports and a neighbour-lookup bin grid.
#[derive(Debug, Clone)]
pub struct Support {
    /// Per node `[x_I, y_I, d_mx, d_my]` (position and support half-widths).
    pub node: Vec<[f64; 4]>,
    /// Per node `[1/d_mx, 1/d_my]`.
    pub inv_half: Vec<[f64; 2]>,
    /// Bin grid over the union of the supports.
    origin: Vec2,
    inv_bin: [f64; 2],
    nbins: [usize; 2],
    /// CSR: nodes whose (closed) support rectangle overlaps bin `b` are
    /// `items[start[b]..start[b + 1]]`, in increasing node order.
    start: Vec<u32>,
    items: Vec<u32>,
    /// Boundary segments that hide points from nodes (polygon bodies; `None`
    /// for rectangles, whose supports are never cut).
    pub visibility: Option<Visibility>,
}

/// The visibility criterion (Belytschko, Lu & Gu 1994, "Element-free
/// Galerkin methods", IJNME 37; Belytschko, Krongauz, Organ, Fleming &
/// Krysl 1996, "Meshless methods: an overview and recent developments",
/// CMAME 139, §5.1): the boundary is opaque, so the weight of node `I` at
/// `x` is zero when the segment `x_I → x` properly crosses a boundary
/// segment (touching or running along one is not a crossing, so boundary
/// nodes see along their own edges). Supports do not reach across holes,
/// slots or re-entrant corners. Per node, only the segments whose bounding
/// box meets the node's support rectangle are tested.
///
/// With `diffraction` (the default for polygon bodies) a hidden point gets
/// the weight of the diffraction method (Organ, Fleming, Terry & Belytschko
/// 1996, "Continuous meshless approximations for nonconvex bodies by
/// diffraction and transparency", Comput. Mech. 18; Belytschko et al. 1996
/// §5.2) with λ = 1: the distance `x_I → x` is replaced by the length of
/// the shortest path bent around one boundary vertex `x_c` that sees both,
/// `s₁ + s₂(x)`, i.e. the offset `x − x_I` is scaled by
/// `f = (s₁ + s₂)/s₀`. The weight is then continuous across the shadow
/// line (`f = 1` there, `∇f = 0`), which the Galerkin patch test needs; pure
/// visibility cuts the weight and fails it (measured: 4e-2 stress error on
/// an L-shape).
#[derive(Debug, Clone)]
pub struct Visibility {
    /// The boundary segments.
    pub segments: Vec<(Vec2, Vec2)>,
    /// Bend hidden rays around boundary vertices (diffraction) instead of
    /// cutting them (pure visibility).
    pub diffraction: bool,
    /// The domain: a ray between two boundary points that crosses no
    /// segment may still run outside Ω (across a notch); its midpoint
    /// decides.
    pub domain: crate::geom::polygon::Domain,
    /// The number of the first segment of each loop in `segments`.
    first: Vec<usize>,
    /// CSR: segments near node `k` are `items[start[k]..start[k + 1]]`,
    /// increasing.
    start: Vec<u32>,
    items: Vec<u32>,
    /// CSR per node: boundary vertices reachable from `x_I` with their
    /// geodesic distance (shortest path inside Ω̄, bent at vertices).
    geo_start: Vec<u32>,
    geo: Vec<(Corner, f64)>,
}

impl Visibility {
    /// Segments that meet the support of node `k`.
    pub fn near(&self, k: usize) -> &[u32] {
        &self.items[self.start[k] as usize..self.start[k + 1] as usize]
    }
}

/// A boundary vertex and its neighbours along its loop.
#[derive(Debug, Clone, Copy)]
struct Corner {
    at: Vec2,
    prev: Vec2,
    next: Vec2,
}

impl Corner {
    /// Does the boundary turn away from the body at the vertex (the body
    /// is on the left of the loops)? A shortest path inside Ω̄ bends only
    /// at such vertices.
    fn reflex(&self) -> bool {
        crate::geom::polygon::orient(self.prev, self.at, self.next) < 0
    }

    /// Does the line through the vertex and `q` leave both neighbours on
    /// one side (or on it)? A shortest path inside Ω̄ that bends at the
    /// vertex wraps around it: it arrives and leaves along such lines.
    fn tangent(&self, q: Vec2) -> bool {
        use crate::geom::polygon::orient;
        orient(q, self.at, self.prev) * orient(q, self.at, self.next) >= 0
    }
}

/// `c_I` per direction for a tensor grid with coordinates `xs`, `ys`: the
/// larger of the two gaps to the neighbouring grid lines ("characteristic
/// length" of the text after Eq. 5). Returns `(c_x per column, c_y per row)`.
pub fn grid_spacing(xs: &[f64], ys: &[f64]) -> (Vec<f64>, Vec<f64>) {
    fn gaps(v: &[f64]) -> Vec<f64> {
        (0..v.len())
            .map(|i| {
                let l = if i > 0 { v[i] - v[i - 1] } else { 0.0 };
                let r = if i + 1 < v.len() {
                    v[i + 1] - v[i]
                } else {
                    0.0
                };
                l.max(r)
            })
            .collect()
    }
    (gaps(xs), gaps(ys))
}

impl Support {
    /// Supports of a row-major tensor grid of nodes (`xs` fastest), with
    /// `d_mI = d_max · c_I` per direction.
    pub fn for_grid(xs: &[f64], ys: &[f64], d_max: f64) -> Support {
        let (cx, cy) = grid_spacing(xs, ys);
        let mut node = Vec::with_capacity(xs.len() * ys.len());
        for (j, &y) in ys.iter().enumerate() {
            for (i, &x) in xs.iter().enumerate() {
                node.push([x, y, d_max * cx[i], d_max * cy[j]]);
            }
        }
        Support::new(node)
    }

    /// Build the bin grid for arbitrary nodes `[x, y, d_mx, d_my]`.
    pub fn new(node: Vec<[f64; 4]>) -> Support {
        let mut lo = Vec2::new(f64::INFINITY, f64::INFINITY);
        let mut hi = Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        let mut min_half = [f64::INFINITY; 2];
        for n in &node {
            lo.x = lo.x.min(n[0] - n[2]);
            lo.y = lo.y.min(n[1] - n[3]);
            hi.x = hi.x.max(n[0] + n[2]);
            hi.y = hi.y.max(n[1] + n[3]);
            min_half[0] = min_half[0].min(n[2]);
            min_half[1] = min_half[1].min(n[3]);
        }
        if node.is_empty() {
            lo = Vec2::ZERO;
            hi = Vec2::new(1.0, 1.0);
            min_half = [1.0, 1.0];
        }
        // Bins about half a support wide, at most ~4 bins per node.
        let cap = (4 * node.len()).max(1) as f64;
        let mut bs = [min_half[0] * 0.5, min_half[1] * 0.5];
        loop {
            let nx = ((hi.x - lo.x) / bs[0]).ceil().max(1.0);
            let ny = ((hi.y - lo.y) / bs[1]).ceil().max(1.0);
            if nx * ny <= cap {
                break;
            }
            bs[0] *= 1.5;
            bs[1] *= 1.5;
        }
        let nbins = [
            (((hi.x - lo.x) / bs[0]).ceil() as usize).max(1),
            (((hi.y - lo.y) / bs[1]).ceil() as usize).max(1),
        ];
        let inv_bin = [1.0 / bs[0], 1.0 / bs[1]];
        let inv_half = node.iter().map(|n| [1.0 / n[2], 1.0 / n[3]]).collect();
        let mut s = Support {
            inv_half,
            node,
            origin: lo,
            inv_bin,
            nbins,
            start: Vec::new(),
            items: Vec::new(),
            visibility: None,
        };
        // count, prefix, fill (node order kept within each bin)
        let nb = nbins[0] * nbins[1];
        let mut count = vec![0u32; nb + 1];
        for n in &s.node {
            let (i0, i1, j0, j1) = s.bin_range(n);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    count[j * nbins[0] + i + 1] += 1;
                }
            }
        }
        for b in 0..nb {
            count[b + 1] += count[b];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[nb] as usize];
        for (k, n) in s.node.iter().enumerate() {
            let (i0, i1, j0, j1) = s.bin_range(n);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let b = j * nbins[0] + i;
                    items[fill[b] as usize] = k as u32;
                    fill[b] += 1;
                }
            }
        }
        s.start = count;
        s.items = items;
        s
    }

    fn bin_of(&self, x: f64, axis: usize) -> usize {
        let o = if axis == 0 {
            self.origin.x
        } else {
            self.origin.y
        };
        let t = ((x - o) * self.inv_bin[axis]).floor();
        if t <= 0.0 {
            0
        } else {
            (t as usize).min(self.nbins[axis] - 1)
        }
    }

    fn bin_range(&self, n: &[f64; 4]) -> (usize, usize, usize, usize) {
        (
            self.bin_of(n[0] - n[2], 0),
            self.bin_of(n[0] + n[2], 0),
            self.bin_of(n[1] - n[3], 1),
            self.bin_of(n[1] + n[3], 1),
        )
    }

    /// Make `segments` opaque: the visibility criterion ([`Visibility`]),
    /// or with `diffraction` the diffraction method.
    pub fn with_visibility(
        mut self,
        domain: &crate::geom::polygon::Domain,
        diffraction: bool,
    ) -> Support {
        let segments: Vec<(Vec2, Vec2)> = domain.segments().collect();
        // the global number of segment `seg` of loop `lp`, and its vertices'
        // neighbours along their loop (diffraction bends only where the
        // boundary lets a path wrap around the vertex)
        let first: Vec<usize> = domain
            .loops
            .iter()
            .scan(0, |n, l| {
                let f = *n;
                *n += l.len();
                Some(f)
            })
            .collect();
        let mut start = vec![0u32];
        let mut items = Vec::new();
        for n in &self.node {
            let (lo, hi) = (
                Vec2::new(n[0] - n[2], n[1] - n[3]),
                Vec2::new(n[0] + n[2], n[1] + n[3]),
            );
            let at = items.len();
            items.extend(
                domain
                    .index()
                    .in_box(lo, hi)
                    .filter(|s| {
                        let (a, b) = (s.a, s.b);
                        let (lx, hx) = (a.x.min(b.x), a.x.max(b.x));
                        let (ly, hy) = (a.y.min(b.y), a.y.max(b.y));
                        hx >= lo.x && lx <= hi.x && hy >= lo.y && ly <= hi.y
                    })
                    .map(|s| (first[s.lp] + s.seg) as u32),
            );
            items[at..].sort_unstable();
            start.push(items.len() as u32);
        }
        // per global segment: its loop and number in it
        let owner: Vec<(usize, usize)> = domain
            .loops
            .iter()
            .enumerate()
            .flat_map(|(lp, l)| (0..l.len()).map(move |i| (lp, i)))
            .collect();
        let mut v = Visibility {
            segments,
            diffraction,
            domain: domain.clone(),
            first,
            start,
            items,
            geo_start: vec![0],
            geo: Vec::new(),
        };
        if diffraction {
            for k in 0..self.node.len() {
                let n = self.node[k];
                let xi = Vec2::new(n[0], n[1]);
                let reach = 1.5 * n[2].max(n[3]);
                // the boundary vertices near x_I where a path can bend
                // (reflex: the boundary turns away from the body there)
                let mut verts: Vec<Corner> = Vec::new();
                let mut seen = std::collections::HashSet::new();
                for &s in v.near(k) {
                    let (lp, i) = owner[s as usize];
                    let l = &domain.loops[lp];
                    for j in [i, i + 1] {
                        let corner = Corner {
                            at: l.points[j % l.len()],
                            prev: l.points[(j + l.len() - 1) % l.len()],
                            next: l.points[(j + 1) % l.len()],
                        };
                        let c = corner.at;
                        if c != xi
                            && (c - xi).norm() < reach
                            && corner.reflex()
                            && seen.insert((c.x.to_bits(), c.y.to_bits()))
                        {
                            verts.push(corner);
                        }
                    }
                }
                let geo = Self::geodesics(&v, k, xi, &verts, reach);
                v.geo
                    .extend(verts.into_iter().zip(geo).filter(|(_, d)| *d < reach));
                v.geo_start.push(v.geo.len() as u32);
            }
        }
        self.visibility = Some(v);
        self
    }

    /// Geodesic distances inside Ω̄ from `x_I` (node `k`) to the reflex
    /// vertices `verts` (Dijkstra over the visibility graph, paths shorter
    /// than `reach`; ∞ beyond). A shortest path bends only where it
    /// wraps around a vertex, leaving it along a line that has both of the
    /// vertex's neighbours on one side: only such edges are followed (with
    /// every vertex in reach of a dense boundary — a circle of 1 000
    /// segments — the full graph costs `O(m³)` per node, this `O(m²)`
    /// cheap tests and `O(m)` blocking tests).
    fn geodesics(v: &Visibility, k: usize, xi: Vec2, verts: &[Corner], reach: f64) -> Vec<f64> {
        let m = verts.len();
        let mut dist: Vec<f64> = verts
            .iter()
            .map(|c| {
                if Self::blocked(v, k, xi, c.at) {
                    f64::INFINITY
                } else {
                    (c.at - xi).norm()
                }
            })
            .collect();
        let mut done = vec![false; m];
        for _ in 0..m {
            let Some(i) = (0..m)
                .filter(|&i| !done[i] && dist[i].is_finite())
                .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))
            else {
                break;
            };
            done[i] = true;
            let c = &verts[i];
            for j in 0..m {
                let d = dist[i] + (verts[j].at - c.at).norm();
                if !done[j]
                    && d < dist[j]
                    && d < reach
                    && c.tangent(verts[j].at)
                    && !Self::blocked(v, k, c.at, verts[j].at)
                {
                    dist[j] = d;
                }
            }
        }
        dist
    }

    /// Is `p` hidden from node `k` by the boundary (visibility criterion)?
    /// Always `false` without [`Visibility`].
    #[inline]
    pub fn hidden(&self, k: usize, p: Vec2) -> bool {
        let Some(v) = &self.visibility else {
            return false;
        };
        let n = &self.node[k];
        let xi = Vec2::new(n[0], n[1]);
        Self::blocked(v, k, xi, p)
    }

    /// Is the straight path `a → b` blocked by a boundary segment near
    /// node `k`?
    #[inline]
    fn blocked(v: &Visibility, k: usize, a: Vec2, b: Vec2) -> bool {
        use crate::geom::polygon::{on_segment, properly_cross};
        // the segments near the path, from the domain's index, that are
        // near node k (its sorted list)
        let near = v.near(k);
        let index = v.domain.index();
        let mine = |s: &crate::geom::segment_index::Segment| {
            near.binary_search(&((v.first[s.lp] + s.seg) as u32))
                .is_ok()
        };
        if index
            .along(a, b)
            .any(|s| properly_cross(a, b, s.a, s.b) && mine(s))
        {
            return true;
        }
        // both ends on the boundary: the ray may run outside Ω
        let on = |p: Vec2| {
            index
                .in_box(p, p)
                .any(|s| on_segment(s.a, s.b, p) && mine(s))
        };
        if on(a) && on(b) {
            let m = (a + b) * 0.5;
            let tol = 1e-9 * (b - a).norm();
            return !(v.domain.contains(m) || v.domain.boundary_distance(m) <= tol);
        }
        false
    }

    /// For `p` hidden from node `k`: the diffraction factor
    /// `f = (s₁ + s₂)/s₀` and its gradient `∇f`, where `s₁ + s₂` is the
    /// geodesic distance from `x_I` to `p` inside Ω̄: over the boundary
    /// vertices `x_c` that `p` sees, `s₁` = the precomputed geodesic
    /// distance `x_I → x_c` (shortest path bent at vertices),
    /// `s₂ = |p − x_c|`, `s₀ = |p − x_I|`.
    /// `None` without diffraction or if no vertex sees both.
    pub fn diffraction(&self, k: usize, p: Vec2) -> Option<(f64, [f64; 2])> {
        let v = self.visibility.as_ref().filter(|v| v.diffraction)?;
        // the shortest bent path: its last bend leaves the vertex along a
        // line with the vertex's neighbours on one side (`Corner::tangent`;
        // the others cannot be shorter); candidates by length (ties in
        // their order), the first whose vertex sees p
        let mut paths: Vec<(f64, Vec2)> = v.geo
            [v.geo_start[k] as usize..v.geo_start[k + 1] as usize]
            .iter()
            .filter(|(c, _)| c.tangent(p))
            .map(|(c, g)| (g + (p - c.at).norm(), c.at))
            .collect();
        paths.sort_by(|a, b| a.0.total_cmp(&b.0));
        let best = paths.into_iter().find(|&(_, c)| !Self::blocked(v, k, c, p));
        let n = &self.node[k];
        let xi = Vec2::new(n[0], n[1]);
        let (len, c) = best?;
        let d0 = p - xi;
        let s0 = d0.norm();
        let d2 = p - c;
        let s2 = d2.norm();
        if s0 == 0.0 {
            return None;
        }
        let f = len / s0;
        // ∇f = ∇s₂/s₀ − (s₁ + s₂)∇s₀/s₀² (∇s₂ taken as 0 at p = x_c,
        // where s₂ has a cone point: f is continuous there)
        let g2 = if s2 > 0.0 {
            d2 * (1.0 / (s2 * s0))
        } else {
            Vec2::ZERO
        };
        let g = [
            g2.x - len * d0.x / (s0 * s0 * s0),
            g2.y - len * d0.y / (s0 * s0 * s0),
        ];
        Some((f, g))
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.node.len()
    }
    /// No nodes.
    pub fn is_empty(&self) -> bool {
        self.node.is_empty()
    }

    /// Candidate nodes for point `p` (a superset of the covering nodes,
    /// increasing node order). Empty outside the union of the supports.
    #[inline]
    pub fn candidates(&self, p: Vec2) -> &[u32] {
        let (ox, oy) = (
            (p.x - self.origin.x) * self.inv_bin[0],
            (p.y - self.origin.y) * self.inv_bin[1],
        );
        if !(ox >= 0.0 && oy >= 0.0) || ox >= self.nbins[0] as f64 || oy >= self.nbins[1] as f64 {
            return &[];
        }
        let b = oy as usize * self.nbins[0] + ox as usize;
        &self.items[self.start[b] as usize..self.start[b + 1] as usize]
    }

    /// Does the open support of node `k` contain `p` (weight > 0)?
    #[inline]
    pub fn covers(&self, k: usize, p: Vec2) -> bool {
        // the test `shape_functions` makes (`|Δx| / d_m < 1` with the stored
        // reciprocal), so that counts made with it size its rows exactly:
        // `|Δx| < d_m` differs from it by one rounding at the support's edge
        // (a 42 × 8 node grid had nodes there and overran its row buffer)
        let (n, inv) = (&self.node[k], &self.inv_half[k]);
        (p.x - n[0]).abs() * inv[0] < 1.0
            && (p.y - n[1]).abs() * inv[1] < 1.0
            && (!self.hidden(k, p)
                || self.diffraction(k, p).is_some_and(|(f, _)| {
                    ((p.x - n[0]) * f).abs() * inv[0] < 1.0
                        && ((p.y - n[1]) * f).abs() * inv[1] < 1.0
                }))
    }

    /// Nodes whose support covers `p`, in increasing order, into `out`.
    pub fn covering(&self, p: Vec2, out: &mut Vec<u32>) {
        out.clear();
        out.extend(
            self.candidates(p)
                .iter()
                .copied()
                .filter(|&k| self.covers(k as usize, p)),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookup_matches_brute_force() {
        let xs: Vec<f64> = (0..11)
            .map(|i| i as f64 * 0.3 + 0.01 * (i * i) as f64)
            .collect();
        let ys: Vec<f64> = (0..7).map(|j| -1.0 + j as f64 * 0.5).collect();
        let s = Support::for_grid(&xs, &ys, 2.0);
        let mut out = Vec::new();
        let mut seed = 12345u64;
        for _ in 0..2000 {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let a = (seed >> 11) as f64 / (1u64 << 53) as f64;
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let b = (seed >> 11) as f64 / (1u64 << 53) as f64;
            let p = Vec2::new(-1.0 + a * 6.0, -2.0 + b * 5.0);
            s.covering(p, &mut out);
            let brute: Vec<u32> = (0..s.len() as u32)
                .filter(|&k| s.covers(k as usize, p))
                .collect();
            assert_eq!(out, brute, "at {p:?}");
        }
    }

    #[test]
    fn uniform_grid_support_is_twice_the_spacing() {
        let xs = [0.0, 1.0, 2.0];
        let ys = [0.0, 0.5];
        let s = Support::for_grid(&xs, &ys, 2.0);
        assert_eq!(s.node[1], [1.0, 0.0, 2.0, 1.0]);
    }
}
