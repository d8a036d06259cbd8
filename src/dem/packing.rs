//! Packings: discs on lattices, gravity deposition and radius growth in a
//! box. Plain parameters in, disc rows out.

use super::contact::{ContactLaw, SlipNormal};
use super::particles::Particles;
use super::walls::{Wall, WallMotion};
use super::{BodyDamping, DemError, Granular};
use crate::geom::Vec2;

/// One disc of a packing: centre, radius and an optional material name.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscRow {
    /// Centre.
    pub pos: Vec2,
    /// Radius.
    pub r: f64,
    /// Name of the disc material; `None`: the section's default.
    pub material: Option<String>,
}

/// Lattice of a generated packing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lattice {
    /// Rows `2 r_max (1 + gap)` apart, sites above each other.
    Square,
    /// Rows `√3 r_max (1 + gap)` apart, every other row shifted by half a
    /// spacing (triangular lattice).
    Hex,
}

/// Number of lattice sites [`lattice_packing`] finds in the box `[lo, hi]`
/// for discs of largest radius `r_max` (as a float: a huge box holds more
/// discs than a `usize` counts; 0 if not even one fits). Nothing is
/// allocated: the memory of a run is estimated from it before generating.
pub fn lattice_capacity(lattice: Lattice, lo: Vec2, hi: Vec2, r_max: f64, gap: f64) -> f64 {
    let s = 2.0 * r_max * (1.0 + gap);
    let (w, h) = (hi.x - lo.x, hi.y - lo.y);
    if !(w >= 2.0 * r_max && h >= 2.0 * r_max) {
        return 0.0;
    }
    let row_dy = match lattice {
        Lattice::Square => s,
        Lattice::Hex => s * 3f64.sqrt() / 2.0,
    };
    let ny = ((h - s) / row_dy).floor() + 1.0;
    let nx = ((w - s) / s).floor() + 1.0;
    let v = ny * nx;
    if v.is_nan() {
        f64::INFINITY
    } else {
        v.max(0.0)
    }
}

/// Discs on a square or hexagonal lattice filling the box `[lo, hi]`, row
/// by row from the bottom, at most `count` of them.
///
/// Sites are `2 r_max (1 + gap)` apart; radii are uniform in
/// `[r_min, r_max]` (seeded); each disc is moved at random by up to
/// `jitter` × its free play inside its site (`spacing/2 − r`), so discs
/// never overlap at the start. Reproducible by `seed`.
#[allow(clippy::too_many_arguments)]
pub fn lattice_packing(
    lattice: Lattice,
    lo: Vec2,
    hi: Vec2,
    radii: (f64, f64),
    count: Option<usize>,
    gap: f64,
    jitter: f64,
    seed: u64,
) -> Result<Vec<DiscRow>, String> {
    let mut out = Vec::new();
    let mut put = |pos, r| {
        out.push(DiscRow {
            pos,
            r,
            material: None,
        })
    };
    lattice_each(lattice, lo, hi, radii, count, gap, jitter, seed, &mut put)?;
    Ok(out)
}

/// The discs of [`lattice_packing`] handed to `put` (centre, radius) one
/// at a time in its order, without a list of them: the same discs,
/// bitwise. Returns how many there are.
#[allow(clippy::too_many_arguments)]
pub fn lattice_each(
    lattice: Lattice,
    lo: Vec2,
    hi: Vec2,
    (r_min, r_max): (f64, f64),
    count: Option<usize>,
    gap: f64,
    jitter: f64,
    seed: u64,
    put: &mut dyn FnMut(Vec2, f64),
) -> Result<usize, String> {
    let s = 2.0 * r_max * (1.0 + gap);
    let (w, h) = (hi.x - lo.x, hi.y - lo.y);
    if w < 2.0 * r_max || h < 2.0 * r_max {
        return Err(format!(
            "the box {w} × {h} is smaller than one disc of diameter {}",
            2.0 * r_max
        ));
    }
    let row_dy = match lattice {
        Lattice::Square => s,
        Lattice::Hex => s * 3f64.sqrt() / 2.0,
    };
    let half = 0.5 * s;
    // saturating: a radius tiny against the box gives more rows than a
    // `usize` counts (the rows are only walked up to `count`)
    let ny = (((h - s) / row_dy).floor() as usize).saturating_add(1);
    let mut rng = oorandom::Rand64::new(seed as u128);
    let mut made = 0;
    let want = count.unwrap_or(usize::MAX);
    'rows: for j in 0..ny {
        let shift = if lattice == Lattice::Hex && j % 2 == 1 {
            half
        } else {
            0.0
        };
        let nx = (((w - s - shift) / s).floor() + 1.0).max(0.0) as usize;
        for i in 0..nx {
            if made >= want {
                break 'rows;
            }
            let centre = Vec2::new(
                lo.x + half + shift + s * i as f64,
                lo.y + half + row_dy * j as f64,
            );
            let r = if r_max > r_min {
                r_min + (r_max - r_min) * rng.rand_float()
            } else {
                r_max
            };
            let play = (half - r).max(0.0) * jitter;
            let offset = if play > 0.0 {
                let a = std::f64::consts::TAU * rng.rand_float();
                let d = play * rng.rand_float().sqrt();
                Vec2::new(d * a.cos(), d * a.sin())
            } else {
                Vec2::ZERO
            };
            put(centre + offset, r);
            made += 1;
        }
    }
    if let Some(c) = count
        && made < c
    {
        return Err(format!(
            "the box holds only {made} discs of radius ≤ {r_max} at this spacing, {c} requested"
        ));
    }
    Ok(made)
}

/// Watches a preparation: called after every step with the steps done;
/// returning `false` stops it ([`DemError::Stopped`]).
pub type Watch<'a> = &'a mut dyn FnMut(usize) -> bool;

/// Settle `rows` in the box `[lo, hi]` (four fixed walls) under `gravity`
/// for `steps` steps at 0.15 × the critical step, with local damping 0.3
/// and a normal dashpot at ζ = 0.3 added to `law` (with the elastic
/// Coulomb cap, so that this settling aid adds no friction). Returns the
/// settled discs in the input order.
#[allow(clippy::too_many_arguments)]
pub fn settle_in_box(
    rows: &[DiscRow],
    lo: Vec2,
    hi: Vec2,
    law: ContactLaw,
    density: f64,
    thickness: f64,
    gravity: Vec2,
    steps: usize,
    watch: Watch,
) -> Result<Vec<DiscRow>, DemError> {
    let mut p = Particles::with_capacity(rows.len());
    for r in rows {
        p.push(r.pos, r.r, density, thickness, 0);
    }
    let corners = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
    let walls = (0..4)
        .map(|k| Wall::new("box", corners[k], corners[(k + 1) % 4], WallMotion::Fixed))
        .collect();
    let mut law = law;
    law.zeta_n = 0.3;
    // the settling dashpot is a numerical aid: it must not add friction
    law.slip_normal = SlipNormal::Elastic;
    let mut gr = Granular::new(p, vec![law], walls, 1.0);
    gr.dt = 0.15 * gr.critical_dt();
    gr.gravity = gravity;
    gr.damping = BodyDamping::Local { alpha: 0.3 };
    for n in 1..=steps {
        gr.step();
        if !watch(n) {
            return Err(DemError::Stopped { step: n });
        }
    }
    gr.check_finite()?;
    let p = &gr.particles;
    Ok((0..p.len())
        .map(|id| {
            let s = p.slot[id] as usize;
            DiscRow {
                pos: p.pos[s],
                r: p.radius[s],
                material: rows[id].material.clone(),
            }
        })
        .collect())
}

/// Radius growth: `count` centres uniform in the box (seeded), final radii
/// uniform in `[r_min, r_max]`; the radii start at the scale that gives a
/// packing fraction of 0.3 and grow linearly to their final size over 70 %
/// of `steps` DEM steps (no gravity, local damping 0.7, normal dashpot
/// ζ = 0.3 with the elastic Coulomb cap, four fixed walls), then the
/// packing relaxes for the rest.
#[allow(clippy::too_many_arguments)]
pub fn grow_in_box(
    lo: Vec2,
    hi: Vec2,
    (r_min, r_max): (f64, f64),
    count: usize,
    seed: u64,
    steps: usize,
    law: ContactLaw,
    density: f64,
    thickness: f64,
    watch: Watch,
) -> Result<Vec<DiscRow>, DemError> {
    let mut law = law;
    law.zeta_n = 0.3;
    // the settling dashpot is a numerical aid: it must not add friction
    law.slip_normal = SlipNormal::Elastic;
    let mats = vec![law];
    let mut rng = oorandom::Rand64::new(seed as u128);
    let r_final: Vec<f64> = (0..count)
        .map(|_| r_min + (r_max - r_min) * rng.rand_float())
        .collect();
    let area: f64 = r_final.iter().map(|r| std::f64::consts::PI * r * r).sum();
    let ext = hi - lo;
    let phi = area / (ext.x * ext.y);
    if phi > 0.85 {
        return Err(DemError::Input(format!(
            "{count} discs of radius {r_min}…{r_max} fill {:.0} % of the box; radius growth reaches at most 85 %",
            100.0 * phi
        )));
    }
    let s0 = (0.3 / phi).sqrt().min(1.0);
    let mut p = Particles::default();
    for &r in &r_final {
        let x = lo.x + r_max + (ext.x - 2.0 * r_max).max(0.0) * rng.rand_float();
        let y = lo.y + r_max + (ext.y - 2.0 * r_max).max(0.0) * rng.rand_float();
        // mass of the final disc: the critical step stays that of the end state
        p.push(Vec2::new(x, y), r, density, thickness, 0);
    }
    for (r, rf) in p.radius.iter_mut().zip(&r_final) {
        *r = rf * s0;
    }
    let corners = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
    let walls = (0..4)
        .map(|k| Wall::new("box", corners[k], corners[(k + 1) % 4], WallMotion::Fixed))
        .collect();
    let mut gr = Granular::new(p, mats, walls, 1.0);
    gr.dt = 0.15 * gr.critical_dt();
    gr.damping = BodyDamping::Local { alpha: 0.7 };
    gr.set_skin(0.1 * r_max);
    let grow_steps = (0.7 * steps as f64) as usize;
    for n in 0..steps {
        if n <= grow_steps {
            let s = s0 + (1.0 - s0) * (n as f64 / grow_steps.max(1) as f64);
            let p = &mut gr.particles;
            for (r, &id) in p.radius.iter_mut().zip(&p.id) {
                *r = r_final[id as usize] * s;
            }
            // radii grow by ≪ skin/2 in 10 steps: rebuild every 10 steps
            if n % 10 == 0 {
                gr.grid.stale = true;
            }
        }
        gr.step();
        if !watch(n + 1) {
            return Err(DemError::Stopped { step: n + 1 });
        }
    }
    gr.check_finite()?;
    let p = &gr.particles;
    Ok((0..count)
        .map(|id| {
            let k = p.slot[id] as usize;
            DiscRow {
                pos: p.pos[k],
                r: r_final[id],
                material: None,
            }
        })
        .collect())
}

/// Pairs of discs `(a, b, δ)` (indices into `pos`/`radius`, `a < b`)
/// overlapping by `δ > tol × min(r_a, r_b)`. Sweep along x: O(n log n)
/// plus the pairs whose x ranges meet.
pub fn overlapping_pairs(pos: &[Vec2], radius: &[f64], tol: f64) -> Vec<(usize, usize, f64)> {
    let r_max = radius.iter().fold(0.0f64, |m, &r| m.max(r));
    let mut order: Vec<usize> = (0..pos.len()).collect();
    order.sort_by(|&a, &b| pos[a].x.total_cmp(&pos[b].x));
    let mut out = Vec::new();
    for (k, &a) in order.iter().enumerate() {
        for &b in &order[k + 1..] {
            if pos[b].x - pos[a].x > radius[a] + r_max {
                break;
            }
            let delta = radius[a] + radius[b] - (pos[b] - pos[a]).norm();
            if delta > tol * radius[a].min(radius[b]) {
                out.push((a.min(b), a.max(b), delta));
            }
        }
    }
    out.sort_by_key(|&(a, b, _)| (a, b));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_lattice_touching() {
        let d = lattice_packing(
            Lattice::Square,
            Vec2::new(0.0, 0.0),
            Vec2::new(300.0, 300.0),
            (50.0, 50.0),
            None,
            0.0,
            0.0,
            1,
        )
        .unwrap();
        assert_eq!(d.len(), 9);
        assert_eq!(d[0].pos, Vec2::new(50.0, 50.0));
        assert_eq!(d[8].pos, Vec2::new(250.0, 250.0));
    }

    #[test]
    fn random_packing_has_no_overlap_and_is_reproducible() {
        let gen_ = |seed| {
            lattice_packing(
                Lattice::Hex,
                Vec2::new(0.0, 0.0),
                Vec2::new(40.0, 40.0),
                (0.8, 1.2),
                Some(200),
                0.1,
                1.0,
                seed,
            )
            .unwrap()
        };
        let a = gen_(3);
        assert_eq!(a, gen_(3));
        assert_ne!(a, gen_(4));
        for i in 0..a.len() {
            for j in i + 1..a.len() {
                assert!((a[i].pos - a[j].pos).norm() > a[i].r + a[j].r);
            }
        }
    }

    #[test]
    fn overlapping_pairs_are_found_above_the_tolerance_only() {
        let pos = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.9995, 0.0), // overlaps disc 0 by 5e-4: below the tolerance
            Vec2::new(0.0, 1.99),   // overlaps disc 0 by 1e-2
            Vec2::new(10.0, 0.0),
            Vec2::new(10.0, 0.0), // same centre as disc 3
        ];
        let r = [1.0; 5];
        let found = overlapping_pairs(&pos, &r, 1e-3);
        let pairs: Vec<_> = found.iter().map(|&(a, b, _)| (a, b)).collect();
        assert_eq!(pairs, vec![(0, 2), (3, 4)]);
        assert!((found[0].2 - 0.01).abs() < 1e-12);
        assert_eq!(found[1].2, 2.0);
    }
}
