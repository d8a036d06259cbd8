//! A uniform grid of the segments of one boundary chain, binned from the
//! chain's points (again once they have moved more than a skin): a disc
//! then tests only the segments in the cells around it instead of the whole
//! chain (the transfer's cost grows with the contacts, not with contacts ×
//! boundary points).

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
    /// The chain's points when binned by [`bin`](Self::bin), and the reach
    /// and the growth of the box it was binned with.
    binned: Vec<Vec2>,
    cover: (f64, f64),
}

impl SegmentGrid {
    /// Nothing binned yet.
    pub fn is_empty(&self) -> bool {
        self.nx == 0
    }

    /// A grid for `chain` with `reach` and its box (`chain_lo`, `chain_hi`)
    /// grown by `grow`: the grid kept while the chain's points have moved
    /// less than the `slack` it was binned with (a Verlet skin: the grid
    /// then still holds every segment within `reach` of a disc, and the box
    /// every point grown by `grow`), else binned anew with `slack` added
    /// to both. Returns whether it was binned. The grid answers supersets
    /// of the segments near a point, so contacts found through it do not
    /// depend on when it was binned.
    pub fn bin(&mut self, chain: &BoundaryChain, reach: f64, grow: f64, slack: f64) -> bool {
        let pts = &chain.current;
        if !self.is_empty() && self.binned.len() == pts.len() {
            let moved = (pts.iter().zip(&self.binned))
                .map(|(p, q)| (*p - *q).norm2())
                .fold(0.0f64, f64::max)
                .sqrt();
            if moved + reach <= self.cover.0 && moved + grow <= self.cover.1 {
                return false;
            }
        }
        self.rebuild(chain, reach + slack);
        let e = Vec2::new(grow + slack, grow + slack);
        (self.chain_lo, self.chain_hi) = (self.chain_lo - e, self.chain_hi + e);
        self.binned.clone_from(pts);
        self.cover = (reach + slack, grow + slack);
        true
    }

    /// Bin the segments of `chain`; a disc centre within `reach` of a
    /// segment finds it in its own cell. Cells of about `reach`, at most a
    /// few per segment.
    fn rebuild(&mut self, chain: &BoundaryChain, reach: f64) {
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

    /// Discs of radius `r` spread over the chain's region find through `g`
    /// the contact the whole chain gives (and over a hundred find one).
    fn finds_what_the_chain_gives(chain: &BoundaryChain, g: &SegmentGrid, r: f64) {
        let mut found = 0;
        for k in 0..4000 {
            let c = Vec2::new(
                -0.5 + 11.0 * (k as f64 * 0.618).fract(),
                -0.6 + 1.2 * (k as f64 * 0.377).fract(),
            );
            let a = detect(chain, c, r);
            let b = detect_near(chain, c, r, g.near(c).iter().map(|&i| i as usize));
            assert_eq!(a, b, "{c:?}");
            found += a.is_some() as usize;
        }
        assert!(found > 100);
    }

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
        finds_what_the_chain_gives(&chain, &g, r);
    }

    /// A grid kept while the chain moves within its skin finds what the
    /// whole chain gives at the chain's new place; beyond the skin it is
    /// binned again.
    #[test]
    fn a_grid_kept_within_its_skin_still_finds_every_contact() {
        let wave = |shift: Vec2| {
            let pts = (0..200).map(|i| {
                let t = i as f64 * 0.05;
                Vec2::new(t, 0.3 * (3.0 * t).sin()) + shift
            });
            BoundaryChain::new(pts.collect())
        };
        let (r, skin) = (0.07, 0.02);
        let mut g = SegmentGrid::default();
        assert!(g.bin(&wave(Vec2::ZERO), 2.0 * r, 0.0, skin));
        // moved 0.019 < skin: kept, and still exact
        let moved = wave(Vec2::new(0.011, -0.0155));
        assert!(!g.bin(&moved, 2.0 * r, 0.0, skin));
        finds_what_the_chain_gives(&moved, &g, r);
        // the box still holds the moved points
        let far = (Vec2::new(f64::MAX, f64::MAX), Vec2::new(f64::MIN, f64::MIN));
        let (lo, hi) = moved.current.iter().fold(far, |(l, h), p| {
            (
                Vec2::new(l.x.min(p.x), l.y.min(p.y)),
                Vec2::new(h.x.max(p.x), h.y.max(p.y)),
            )
        });
        assert!(g.chain_lo.x <= lo.x && g.chain_lo.y <= lo.y);
        assert!(g.chain_hi.x >= hi.x && g.chain_hi.y >= hi.y);
        // beyond the skin, or asked for a reach beyond the skin: binned again
        let away = wave(Vec2::new(0.0, 0.021));
        assert!(g.bin(&away, 2.0 * r, 0.0, skin));
        assert!(!g.bin(&away, 2.0 * r + 0.019, 0.0, skin));
        assert!(g.bin(&away, 2.0 * r + 0.021, 0.0, skin));
    }
}
