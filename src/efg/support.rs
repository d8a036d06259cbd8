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
        (p.x - n[0]).abs() * inv[0] < 1.0 && (p.y - n[1]).abs() * inv[1] < 1.0
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
