//! A uniform grid of the segments of one boundary chain, rebuilt every step
//! from the chain's current points: a disc then tests only the segments in
//! the cells around it instead of the whole chain (the transfer's cost
//! grows with the contacts, not with contacts × boundary points).

use crate::continuum::BoundaryChain;
use crate::geom::Vec2;

/// Segments binned by the cells their bounding box (grown by `reach`)
/// covers.
#[derive(Debug, Default)]
pub struct SegmentGrid {
    /// Lower-left corner of the bounding box of the chain's current points.
    pub chain_lo: Vec2,
    /// Upper-right corner of the same box.
    pub chain_hi: Vec2,
    lo: Vec2,
    cell: f64,
    nx: usize,
    ny: usize,
    /// Per cell `start[c]..start[c + 1]` into `segs`.
    start: Vec<u32>,
    segs: Vec<u32>,
    count: Vec<u32>,
}

impl SegmentGrid {
    /// Nothing binned yet.
    pub fn is_empty(&self) -> bool {
        self.nx == 0
    }

    /// Bin the segments of `chain`; a disc centre within `reach` of a
    /// segment finds it in its own cell. Cells of about `reach`, at most a
    /// few per segment.
    pub fn rebuild(&mut self, chain: &BoundaryChain, reach: f64) {
        let pts = &chain.current;
        let nseg = chain.segments();
        let (mut lo, mut hi) = (Vec2::new(f64::MAX, f64::MAX), Vec2::new(f64::MIN, f64::MIN));
        for p in pts {
            lo = Vec2::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = Vec2::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        let mean = if nseg > 0 {
            pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum::<f64>() / nseg as f64
        } else {
            1.0
        };
        (self.chain_lo, self.chain_hi) = (lo, hi);
        let ext = hi - lo;
        // cells no smaller than the reach or a segment, and no more than
        // ~16 per segment over the box
        let mut cell = reach.max(mean).max(f64::MIN_POSITIVE);
        while (ext.x / cell + 3.0) * (ext.y / cell + 3.0) > 16.0 * (nseg as f64 + 64.0) {
            cell *= 2.0;
        }
        self.cell = cell;
        self.lo = lo - Vec2::new(reach + cell, reach + cell);
        self.nx = ((ext.x + 2.0 * (reach + cell)) / cell) as usize + 1;
        self.ny = ((ext.y + 2.0 * (reach + cell)) / cell) as usize + 1;
        let ncell = self.nx * self.ny;
        self.count.clear();
        self.count.resize(ncell + 1, 0);
        for pass in 0..2 {
            if pass == 1 {
                let mut acc = 0u32;
                self.start.clear();
                self.start.push(0);
                for c in 0..ncell {
                    acc += self.count[c];
                    self.start.push(acc);
                    self.count[c] = self.start[c];
                }
                self.segs.clear();
                self.segs.resize(acc as usize, 0);
            }
            for i in 0..nseg {
                let (a, b) = (pts[i], pts[i + 1]);
                let (x0, y0) = self.cell_of(Vec2::new(a.x.min(b.x) - reach, a.y.min(b.y) - reach));
                let (x1, y1) = self.cell_of(Vec2::new(a.x.max(b.x) + reach, a.y.max(b.y) + reach));
                for cy in y0..=y1 {
                    for cx in x0..=x1 {
                        let c = cy * self.nx + cx;
                        if pass == 0 {
                            self.count[c] += 1;
                        } else {
                            self.segs[self.count[c] as usize] = i as u32;
                            self.count[c] += 1;
                        }
                    }
                }
            }
        }
    }

    fn cell_of(&self, p: Vec2) -> (usize, usize) {
        let x = ((p.x - self.lo.x) / self.cell).max(0.0) as usize;
        let y = ((p.y - self.lo.y) / self.cell).max(0.0) as usize;
        (x.min(self.nx - 1), y.min(self.ny - 1))
    }

    /// The segments within `reach` of `p` (and possibly a few more),
    /// ascending; empty when `p` is outside the grid.
    pub fn near(&self, p: Vec2) -> &[u32] {
        if self.nx == 0
            || p.x < self.lo.x
            || p.y < self.lo.y
            || p.x >= self.lo.x + self.nx as f64 * self.cell
            || p.y >= self.lo.y + self.ny as f64 * self.cell
        {
            return &[];
        }
        let (x, y) = self.cell_of(p);
        let c = y * self.nx + x;
        &self.segs[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coupling::interface::{detect, detect_near};

    /// Every disc finds through the grid the contact the whole chain gives.
    #[test]
    fn grid_detection_equals_whole_chain_detection() {
        let pts: Vec<Vec2> = (0..200)
            .map(|i| {
                let t = i as f64 * 0.05;
                Vec2::new(t, 0.3 * (3.0 * t).sin())
            })
            .rev()
            .collect();
        let chain = BoundaryChain::new(pts);
        let r = 0.07;
        let mut g = SegmentGrid::default();
        g.rebuild(&chain, 2.0 * r);
        let mut found = 0;
        for k in 0..4000 {
            let c = Vec2::new(
                -0.5 + 11.0 * (k as f64 * 0.618).fract(),
                -0.6 + 1.2 * (k as f64 * 0.377).fract(),
            );
            let a = detect(&chain, c, r);
            let b = detect_near(&chain, c, r, g.near(c).iter().map(|&i| i as usize));
            assert_eq!(a, b, "{c:?}");
            found += a.is_some() as usize;
        }
        assert!(found > 100);
    }
}
