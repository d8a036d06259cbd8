//! The discs that may touch one boundary chain: a Verlet list around the
//! chain's bounding box, so that the transfer's detection visits the discs
//! near a body instead of every disc of the bed each step.
//!
//! At a refresh the list takes every disc whose circle (radius grown by the
//! contact margin) comes within `s` of the chain's box grown by `s`. It
//! stays valid while
//! - the DEM has not rebuilt its neighbour list (slots are only renumbered
//!   then),
//! - no disc has moved more than `s` since the refresh — bounded by the
//!   DEM's largest displacement since its last rebuild now plus at the
//!   refresh, both measured from the same reference positions,
//! - the chain's current box lies inside the grown box.
//!
//! Then a disc whose circle meets the current box was, at the refresh,
//! within `s` of the grown box (it moved at most `s`): every disc the full
//! scan would test is in the list, and the list is in ascending slot order,
//! so detection finds the same contacts in the same order, bitwise.

use crate::dem::particles::Particles;
use crate::geom::Vec2;

/// The candidate discs of one chain.
#[derive(Debug, Default)]
pub struct Candidates {
    /// Slots, ascending.
    pub slots: Vec<u32>,
    /// The DEM's rebuild count at the refresh (`None`: never refreshed).
    rebuilds: Option<usize>,
    /// The DEM's largest displacement since its rebuild, at the refresh.
    disp: f64,
    /// Grown box of the refresh.
    lo: Vec2,
    hi: Vec2,
    /// Growth `s` and the radius factor `1 + margin` of the refresh.
    s: f64,
    grow: f64,
}

impl Candidates {
    /// Keep the list valid for a chain whose current box is `lo..hi`, discs
    /// of radius × `grow` (`1 + margin`), the DEM at `rebuilds` with its
    /// largest displacement `disp` since; `s` is the growth of a refresh.
    /// Returns whether the list was refreshed (one pass over the discs).
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        p: &Particles,
        lo: Vec2,
        hi: Vec2,
        grow: f64,
        rebuilds: usize,
        disp: f64,
        s: f64,
    ) -> bool {
        let inside =
            lo.x >= self.lo.x && lo.y >= self.lo.y && hi.x <= self.hi.x && hi.y <= self.hi.y;
        if self.rebuilds == Some(rebuilds)
            && grow == self.grow
            && disp + self.disp <= self.s
            && inside
        {
            return false;
        }
        let g = Vec2::new(s, s);
        (self.lo, self.hi) = (lo - g, hi + g);
        (self.rebuilds, self.disp, self.s, self.grow) = (Some(rebuilds), disp, s, grow);
        self.slots.clear();
        let (blo, bhi) = (self.lo, self.hi);
        self.slots.extend((0..p.len() as u32).filter(|&d| {
            let (x, rm) = (p.pos[d as usize], p.radius[d as usize] * grow + s);
            x.x + rm >= blo.x && x.x - rm <= bhi.x && x.y + rm >= blo.y && x.y - rm <= bhi.y
        }));
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn discs(xs: &[(f64, f64)]) -> Particles {
        let mut p = Particles::default();
        for &(x, y) in xs {
            p.push(Vec2::new(x, y), 0.1, 1000.0, 1.0, 0);
        }
        p
    }

    #[test]
    fn keeps_every_disc_that_can_reach_the_box_and_refreshes_when_it_must() {
        let mut p = discs(&[(0.0, 0.0), (1.35, 0.5), (1.7, 0.5), (3.0, 3.0)]);
        let (lo, hi) = (Vec2::new(-1.0, -1.0), Vec2::new(1.0, 1.0));
        let mut c = Candidates::default();
        assert!(c.update(&p, lo, hi, 1.0, 0, 0.0, 0.25));
        // grown box [−1.25, 1.25]²: 1.35 − 0.1 − 0.25 ≤ 1.25, 1.7 − 0.35 > 1.25
        assert_eq!(c.slots, vec![0, 1]);
        // nothing changed: kept
        assert!(!c.update(&p, lo, hi, 1.0, 0, 0.1, 0.25));
        // discs moved more than s in total: refreshed
        p.pos[2] = Vec2::new(1.05, 0.5);
        assert!(c.update(&p, lo, hi, 1.0, 0, 0.3, 0.25));
        assert_eq!(c.slots, vec![0, 1, 2]);
        // a disc listed only for its own motion: the box grows to the
        // edge of the grown box and the disc moves s·0.8 towards it
        p.pos[3] = Vec2::new(1.55, 0.5);
        assert!(c.update(&p, lo, hi, 1.0, 0, 0.0, 0.25));
        assert!(c.slots.contains(&3));
        p.pos[3] = Vec2::new(1.35, 0.5);
        assert!(!c.update(&p, lo, Vec2::new(1.25, 1.0), 1.0, 0, 0.2, 0.25));
        // the DEM renumbered: refreshed
        assert!(c.update(&p, lo, hi, 1.0, 1, 0.0, 0.25));
        // the body grew out of the grown box: refreshed
        assert!(!c.update(&p, lo, hi + Vec2::new(0.2, 0.0), 1.0, 1, 0.0, 0.25));
        assert!(c.update(&p, lo, hi + Vec2::new(0.3, 0.0), 1.0, 1, 0.0, 0.25));
        // another margin: refreshed
        assert!(c.update(&p, lo, hi + Vec2::new(0.3, 0.0), 1.1, 1, 0.0, 0.25));
    }

    /// Random walks of discs and of the box, with a DEM-like rebuild rule
    /// (reference positions, rebuild when a disc moved more than half the
    /// skin): at every step the list holds every disc whose circle meets
    /// the box, as a scan of all discs finds them.
    #[test]
    fn never_misses_a_disc_a_full_scan_finds() {
        let mut seed = 12345u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut p = discs(&[]);
        for _ in 0..400 {
            let x = Vec2::new(8.0 * rnd(), 8.0 * rnd());
            p.push(x, 0.1 + 0.1 * rnd().abs(), 1000.0, 1.0, 0);
        }
        let skin = 1.0;
        let mut reference = p.pos.clone();
        let (mut rebuilds, mut refreshes) = (0, 0);
        let (mut lo, mut hi);
        let mut c = Candidates::default();
        for step in 0..3000 {
            for x in &mut p.pos {
                *x += Vec2::new(0.02 * rnd(), 0.02 * rnd());
            }
            // the box swells and shrinks by up to 0.6 on each side
            let k = step as f64;
            lo = Vec2::new(-1.0, -1.0) - Vec2::new(0.3, 0.3) * (1.0 + (k / 50.0).sin());
            hi = Vec2::new(1.0, 0.5) + Vec2::new(0.3, 0.3) * (1.0 + (k / 37.0).sin());
            let mut disp = p
                .pos
                .iter()
                .zip(&reference)
                .map(|(a, b)| (*a - *b).norm())
                .fold(0.0, f64::max);
            if 2.0 * disp > skin {
                reference = p.pos.clone();
                rebuilds += 1;
                disp = 0.0;
            }
            refreshes += c.update(&p, lo, hi, 1.1, rebuilds, disp, skin) as usize;
            let meets = |d: usize| {
                let (x, r) = (p.pos[d], 1.1 * p.radius[d]);
                x.x + r >= lo.x && x.x - r <= hi.x && x.y + r >= lo.y && x.y - r <= hi.y
            };
            let full: Vec<u32> = (0..p.len() as u32).filter(|&d| meets(d as usize)).collect();
            let listed: Vec<u32> = c
                .slots
                .iter()
                .copied()
                .filter(|&d| meets(d as usize))
                .collect();
            assert_eq!(listed, full);
            assert!(!full.is_empty());
        }
        // the list is kept for most steps
        assert!(refreshes < 1500, "{refreshes} refreshes in 3000 steps");
    }
}
