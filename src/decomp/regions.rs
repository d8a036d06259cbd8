//! Subdomains by recursive coordinate bisection: the plane is cut in two
//! along the longer side of the discs' box so that each side gets discs in
//! proportion to its ranks, then each side again, down to one rank per
//! region. Every rank computes the same cuts from the same sample of disc
//! centres, so no rank has to be told them.

use crate::geom::Vec2;

/// An axis-aligned region `[lo, hi)` (sides may be infinite).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// Lower-left corner.
    pub lo: Vec2,
    /// Upper-right corner (excluded).
    pub hi: Vec2,
}

impl Region {
    /// The whole plane.
    pub const ALL: Region = Region {
        lo: Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        hi: Vec2::new(f64::INFINITY, f64::INFINITY),
    };

    /// Distance from `q` to the region (0 inside; NaN for a NaN point).
    pub fn distance(&self, q: Vec2) -> f64 {
        let dx = (self.lo.x - q.x).max(q.x - self.hi.x).max(0.0);
        let dy = (self.lo.y - q.y).max(q.y - self.hi.y).max(0.0);
        if dx == 0.0 && dy == 0.0 {
            // also a NaN point, whose comparisons all failed
            return if q.x.is_nan() || q.y.is_nan() {
                f64::NAN
            } else {
                0.0
            };
        }
        dx.hypot(dy)
    }
}

/// One node of the bisection tree.
#[derive(Debug, Clone, PartialEq)]
enum Node {
    Leaf(usize),
    /// Points with coordinate `axis` below `cut` go to `left`.
    Split {
        y: bool,
        cut: f64,
        left: usize,
        right: usize,
    },
}

/// The region of each rank, and the tree that finds a point's rank.
#[derive(Debug, Clone, PartialEq)]
pub struct Subdomains {
    /// Region of each rank.
    pub regions: Vec<Region>,
    nodes: Vec<Node>,
}

impl Subdomains {
    /// Cut the plane into `ranks` regions holding about equal numbers of
    /// the `points` (a sample of the disc centres; non-finite ones are
    /// ignored). Ranks may get empty regions when there are fewer points
    /// than ranks.
    pub fn bisect(points: &[Vec2], ranks: usize) -> Subdomains {
        let mut pts: Vec<Vec2> = points
            .iter()
            .copied()
            .filter(|q| q.x.is_finite() && q.y.is_finite())
            .collect();
        let mut s = Subdomains {
            regions: vec![Region::ALL; ranks.max(1)],
            nodes: Vec::new(),
        };
        s.split(&mut pts, Region::ALL, 0..ranks.max(1));
        s
    }

    fn split(&mut self, pts: &mut [Vec2], region: Region, ranks: std::ops::Range<usize>) -> usize {
        let at = self.nodes.len();
        let p = ranks.len();
        if p == 1 {
            self.regions[ranks.start] = region;
            self.nodes.push(Node::Leaf(ranks.start));
            return at;
        }
        self.nodes.push(Node::Leaf(ranks.start)); // replaced below
        let (lo, hi) = pts.iter().fold(
            (
                Vec2::new(f64::INFINITY, f64::INFINITY),
                Vec2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
            ),
            |(a, b), q| {
                (
                    Vec2::new(a.x.min(q.x), a.y.min(q.y)),
                    Vec2::new(b.x.max(q.x), b.y.max(q.y)),
                )
            },
        );
        let y = hi.y - lo.y > hi.x - lo.x;
        let coord = |q: &Vec2| if y { q.y } else { q.x };
        pts.sort_unstable_by(|a, b| coord(a).total_cmp(&coord(b)));
        let pl = p / 2;
        let k = (pts.len() * pl + p / 2) / p;
        let cut = match (pts.is_empty(), pts.get(k)) {
            (true, _) => 0.0,
            (false, Some(q)) => coord(q),
            (false, None) => f64::INFINITY,
        };
        // points equal to the cut go right, with the point at k
        let k = pts.partition_point(|q| coord(q) < cut);
        let (a, b) = pts.split_at_mut(k);
        let (mut rl, mut rr) = (region, region);
        if y {
            rl.hi.y = cut;
            rr.lo.y = cut;
        } else {
            rl.hi.x = cut;
            rr.lo.x = cut;
        }
        let left = self.split(a, rl, ranks.start..ranks.start + pl);
        let right = self.split(b, rr, ranks.start + pl..ranks.end);
        self.nodes[at] = Node::Split {
            y,
            cut,
            left,
            right,
        };
        at
    }

    /// The rank whose region holds `q` (a non-finite point goes to some
    /// rank, always the same).
    pub fn owner(&self, q: Vec2) -> usize {
        let mut n = 0;
        loop {
            match self.nodes[n] {
                Node::Leaf(r) => return r,
                Node::Split {
                    y,
                    cut,
                    left,
                    right,
                } => {
                    let c = if y { q.y } else { q.x };
                    n = if c < cut { left } else { right };
                }
            }
        }
    }

    /// The ranks other than `owner` whose region is within `width` of `q`
    /// (they hold a ghost of a disc at `q`), ascending.
    pub fn near(&self, q: Vec2, owner: usize, width: f64, out: &mut Vec<usize>) {
        out.clear();
        // deep inside its own region: no other region is near
        let own = &self.regions[owner];
        let depth = (q.x - own.lo.x)
            .min(own.hi.x - q.x)
            .min(q.y - own.lo.y)
            .min(own.hi.y - q.y);
        if depth > width {
            return;
        }
        for (r, reg) in self.regions.iter().enumerate() {
            if r != owner && reg.distance(q) <= width {
                out.push(r);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bisection_balances_and_covers_the_plane() {
        let pts: Vec<Vec2> = (0..1000)
            .map(|k| Vec2::new((k % 50) as f64, (k / 50) as f64 * 0.5))
            .collect();
        for ranks in 1..=5 {
            let s = Subdomains::bisect(&pts, ranks);
            let mut count = vec![0usize; ranks];
            for q in &pts {
                let r = s.owner(*q);
                assert_eq!(s.regions[r].distance(*q), 0.0);
                count[r] += 1;
            }
            let (min, max) = (count.iter().min().unwrap(), count.iter().max().unwrap());
            assert!(max - min <= 50, "{ranks} ranks: {count:?}");
            // the regions tile the plane: a point far out has one owner
            let far = Vec2::new(1e9, -1e9);
            assert_eq!(s.regions[s.owner(far)].distance(far), 0.0);
        }
    }

    #[test]
    fn fewer_points_than_ranks_leave_ranks_empty() {
        let pts = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)];
        let s = Subdomains::bisect(&pts, 4);
        let owners: Vec<usize> = pts.iter().map(|q| s.owner(*q)).collect();
        assert_ne!(owners[0], owners[1]);
        let s = Subdomains::bisect(&[], 3);
        assert!(s.owner(Vec2::new(5.0, 5.0)) < 3);
        let mut near = Vec::new();
        s.near(Vec2::new(f64::NAN, 0.0), 0, 1.0, &mut near);
        assert!(near.is_empty());
    }
}
