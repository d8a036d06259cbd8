//! Generators: node grids for bodies, particle packings for the granular assembly.

use crate::geom::Vec2;

/// One disc of a packing: centre, radius and an optional material name.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscRow {
    pub pos: Vec2,
    pub r: f64,
    pub material: Option<String>,
}

/// Lattice of a generated packing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lattice {
    Square,
    Hex,
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
    (r_min, r_max): (f64, f64),
    count: Option<usize>,
    gap: f64,
    jitter: f64,
    seed: u64,
) -> Result<Vec<DiscRow>, String> {
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
    let ny = ((h - s) / row_dy).floor() as usize + 1;
    let mut rng = oorandom::Rand64::new(seed as u128);
    let mut out = Vec::new();
    let want = count.unwrap_or(usize::MAX);
    'rows: for j in 0..ny {
        let shift = if lattice == Lattice::Hex && j % 2 == 1 {
            half
        } else {
            0.0
        };
        let nx = ((w - s - shift) / s).floor() as isize + 1;
        for i in 0..nx.max(0) as usize {
            if out.len() >= want {
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
            out.push(DiscRow {
                pos: centre + offset,
                r,
                material: None,
            });
        }
    }
    if let Some(c) = count
        && out.len() < c
    {
        return Err(format!(
            "the box holds only {} discs of radius ≤ {r_max} at this spacing, {c} requested",
            out.len()
        ));
    }
    Ok(out)
}

/// Read discs from CSV text: `x,y,r[,material]` per line, an optional
/// header line, `#` comments and blank lines ignored. Errors name the line.
pub fn discs_from_csv(text: &str) -> Result<Vec<DiscRow>, String> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if out.is_empty() && f[0].parse::<f64>().is_err() && k == first_data_line(text) {
            continue; // header
        }
        if f.len() < 3 || f.len() > 4 {
            return Err(format!(
                "line {}: expected x,y,r[,material], got {} fields",
                k + 1,
                f.len()
            ));
        }
        let num = |s: &str, what: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("line {}: {what} `{s}` is not a finite number", k + 1))
        };
        let (x, y, r) = (num(f[0], "x")?, num(f[1], "y")?, num(f[2], "r")?);
        if r <= 0.0 {
            return Err(format!("line {}: radius must be > 0 (got {r})", k + 1));
        }
        out.push(DiscRow {
            pos: Vec2::new(x, y),
            r,
            material: f.get(3).filter(|s| !s.is_empty()).map(|s| s.to_string()),
        });
    }
    if out.is_empty() {
        return Err("no discs in the file".into());
    }
    Ok(out)
}

fn first_data_line(text: &str) -> usize {
    text.lines()
        .position(|l| {
            let l = l.trim();
            !l.is_empty() && !l.starts_with('#')
        })
        .unwrap_or(0)
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
    fn csv_with_header_and_errors() {
        let d = discs_from_csv("x,y,r\n0,0,1\n# c\n2.5,0,1,glass\n").unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(d[1].material.as_deref(), Some("glass"));
        let e = discs_from_csv("0,0,1\n1,abc,1\n").unwrap_err();
        assert!(e.contains("line 2"), "{e}");
        assert!(discs_from_csv("0,0,-1\n").is_err());
    }
}
