//! `[clumps]`: rigid clumps of overlapping discs.
//!
//! ```toml
//! [clumps]
//! members = [[1, 2], [3, 4, 5]]   # disc numbers (1-based) joined into one clump each
//! # or: every disc replaced by a clump of this template's discs
//! # template = [[-0.5, 0.0, 0.6], [0.5, 0.0, 0.6]]   # [x, y, r], any units
//! # fit = "inside"     # scaled into the disc's circle (default) or "area": the disc's area
//! # fraction = 1.0     # share of the discs replaced, drawn at random (default 1)
//! # region = [[0, 0], [1, 1]]   # only discs whose centre is in this box
//! # seed = 1           # of the rotations and the draw
//! ```
//!
//! The clumps are [`crate::dem::clumps`]'s.

use super::{Invalid, Problems, Scenario};
use crate::dem::clumps::{Fit, replace_with_template};
use crate::dem::packing::DiscRow;
use crate::geom::Vec2;
use serde::Deserialize;

/// `[clumps]` (see the module docs).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClumpsSpec {
    /// Disc numbers (1-based) of each clump.
    #[serde(default)]
    pub members: Vec<Vec<usize>>,
    /// `[x, y, r]` of the discs of a template that replaces the discs.
    pub template: Option<Vec<[f64; 3]>>,
    /// How the template is scaled onto a disc (default `inside`).
    #[serde(default)]
    pub fit: FitSpec,
    /// Share of the discs replaced (default 1).
    #[serde(default = "one")]
    pub fraction: f64,
    /// Only discs whose centre is in this box.
    pub region: Option<[[f64; 2]; 2]>,
    /// Seed of the rotations and of the draw (default 1).
    #[serde(default = "seed1")]
    pub seed: u64,
}

/// `fit = "inside" | "area"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FitSpec {
    /// Inside the disc's circle.
    #[default]
    Inside,
    /// With the disc's area.
    Area,
}

fn one() -> f64 {
    1.0
}

fn seed1() -> u64 {
    1
}

/// Check `[clumps]`.
pub fn validate(sc: &Scenario, p: &mut Problems) {
    let Some(c) = &sc.clumps else { return };
    p.check(
        sc.granular.is_some(),
        "clumps",
        "clumps are made of discs: the scenario needs a [granular] section",
    );
    p.check(
        c.members.is_empty() != c.template.is_none(),
        "clumps",
        "give `members` (explicit clumps) or `template` (discs replaced by clumps), one of the two",
    );
    let mut seen = std::collections::HashSet::new();
    for (i, m) in c.members.iter().enumerate() {
        let at = format!("clumps.members.{i}");
        p.check(
            m.len() >= 2,
            &at,
            format!("a clump needs two discs or more (got {})", m.len()),
        );
        for (j, &d) in m.iter().enumerate() {
            p.check(d >= 1, format!("{at}.{j}"), "disc numbers start at 1");
            p.check(
                seen.insert(d),
                format!("{at}.{j}"),
                format!("disc {d} is in two clumps"),
            );
        }
    }
    if let Some(t) = &c.template {
        p.check(
            t.len() >= 2,
            "clumps.template",
            format!("a template needs two discs or more (got {})", t.len()),
        );
        for (i, d) in t.iter().enumerate() {
            p.check(
                d.iter().all(|x| x.is_finite()) && d[2] > 0.0,
                format!("clumps.template.{i}"),
                format!("must be [x, y, r], finite, r > 0 (got {d:?})"),
            );
        }
    }
    p.check(
        c.fraction > 0.0 && c.fraction <= 1.0,
        "clumps.fraction",
        format!("must be in (0, 1] (got {})", c.fraction),
    );
    if let Some([lo, hi]) = c.region {
        p.check(
            lo.iter().chain(&hi).all(|x| x.is_finite()) && lo[0] < hi[0] && lo[1] < hi[1],
            "clumps.region",
            "must be [[x0, y0], [x1, y1]] with x0 < x1, y0 < y1",
        );
    }
}

/// The discs with the `[clumps]` template applied, and the disc rows (0-based)
/// of each clump. `removed`: some discs were removed for a body (the
/// disc numbers of `members` would no longer be the scenario's).
pub fn clump_rows(
    sc: &Scenario,
    rows: Vec<DiscRow>,
    removed: bool,
) -> Result<(Vec<DiscRow>, Vec<Vec<usize>>), Invalid> {
    let bad = |path: &str, m: String| Invalid {
        path: path.into(),
        message: m,
    };
    let Some(c) = &sc.clumps else {
        return Ok((rows, Vec::new()));
    };
    let Some(t) = &c.template else {
        if removed {
            return Err(bad(
                "clumps.members",
                "discs were removed for a body (`overlapping_discs = \"remove\"`): the disc numbers of explicit clumps would shift; move the discs off the body instead".into(),
            ));
        }
        for (i, m) in c.members.iter().enumerate() {
            if let Some(j) = m.iter().position(|&d| d > rows.len()) {
                return Err(bad(
                    &format!("clumps.members.{i}.{j}"),
                    format!("no disc {} (there are {})", m[j], rows.len()),
                ));
            }
        }
        let groups = c
            .members
            .iter()
            .map(|m| m.iter().map(|&d| d - 1).collect())
            .collect();
        return Ok((rows, groups));
    };
    let template: Vec<(Vec2, f64)> = t.iter().map(|d| (Vec2::new(d[0], d[1]), d[2])).collect();
    let fit = match c.fit {
        FitSpec::Inside => Fit::Inside,
        FitSpec::Area => Fit::Area,
    };
    // the draw of the replaced discs, one number per disc in row order
    let mut rng = oorandom::Rand64::new(u128::from(c.seed) << 64 | 0x5eed);
    let inside = |x: Vec2| {
        c.region
            .is_none_or(|[lo, hi]| x.x >= lo[0] && x.x <= hi[0] && x.y >= lo[1] && x.y <= hi[1])
    };
    let picked: Vec<bool> = rows
        .iter()
        .map(|r| rng.rand_float() < c.fraction && inside(r.pos))
        .collect();
    Ok(replace_with_template(
        &rows,
        &template,
        fit,
        |k| picked[k],
        c.seed,
    ))
}
