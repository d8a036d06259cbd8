//! `[bonds]`: parallel bonds between the discs (bonded-particle model).
//!
//! ```toml
//! [bonds]
//! kn = 2.0e11            # normal stiffness per area k̄_n (stress / length)
//! ks = 1.0e11            # shear stiffness per area k̄_s
//! radius_factor = 1.0    # λ̄: bond radius R̄ = λ̄ min(r_a, r_b)
//! tensile = 5.0e6        # tensile strength σ_c (stress)
//! shear = 8.0e6          # shear strength τ_c; or cohesion + friction_angle:
//! # cohesion = 5.0e6     # τ_c = c + σ_n tan φ
//! # friction_angle = 30  # φ in degrees (default 0)
//! scatter = 0.1          # coefficient of variation of the strengths (default 0)
//! seed = 1               # of the scatter
//! gap = 1.0e-3           # bond pairs closer than gap × min(r_a, r_b) (default 1e-3)
//! at_step = 0            # when the bonds are made (default 0: at the start)
//! # region = [[0, 0], [1, 2]]   # only pairs with both centres in this box
//! # materials = ["rock"]        # only pairs of discs of these materials
//! ```
//!
//! The law and the rule are [`crate::dem::bonds`]'s.

use super::{Problems, Scenario};
use crate::dem::bonds::{BondLaw, BondRule, ShearStrength};
use crate::geom::Vec2;
use serde::Deserialize;

/// `[bonds]` (see the module docs).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BondsSpec {
    /// Normal stiffness per area k̄_n.
    pub kn: f64,
    /// Shear stiffness per area k̄_s.
    pub ks: f64,
    /// λ̄ (default 1).
    #[serde(default = "one")]
    pub radius_factor: f64,
    /// Tensile strength σ_c (`inf`: never breaks in tension).
    pub tensile: f64,
    /// Fixed shear strength τ_c.
    pub shear: Option<f64>,
    /// Cohesion c of a cohesion–friction shear strength.
    pub cohesion: Option<f64>,
    /// Friction angle φ (degrees) of a cohesion–friction shear strength.
    pub friction_angle: Option<f64>,
    /// Coefficient of variation of the strengths (default 0).
    #[serde(default)]
    pub scatter: f64,
    /// Seed of the scatter (default 1).
    #[serde(default = "seed1")]
    pub seed: u64,
    /// Largest gap of a bonded pair, a fraction of the smaller radius
    /// (default 1e-3).
    #[serde(default = "gap")]
    pub gap: f64,
    /// Step at whose start the bonds are made (default 0).
    #[serde(default)]
    pub at_step: usize,
    /// Only pairs with both centres in this box.
    pub region: Option<[[f64; 2]; 2]>,
    /// Only pairs of discs of these materials (default: any).
    #[serde(default)]
    pub materials: Vec<String>,
}

fn one() -> f64 {
    1.0
}

fn seed1() -> u64 {
    1
}

fn gap() -> f64 {
    1e-3
}

/// A strength: `> 0`, `inf` allowed (never breaks).
fn strength(p: &mut Problems, value: f64, path: &str) {
    p.check(
        value > 0.0,
        path,
        format!("must be > 0 (a stress; `inf` for a bond that never breaks so; got {value})"),
    );
}

/// Check `[bonds]`.
pub fn validate(sc: &Scenario, p: &mut Problems) {
    let Some(b) = &sc.bonds else { return };
    let at = |f: &str| format!("bonds.{f}");
    p.check(
        sc.granular.is_some(),
        "bonds",
        "bonds join discs: the scenario needs a [granular] section",
    );
    p.positive(b.kn, at("kn"));
    p.positive(b.ks, at("ks"));
    p.positive(b.radius_factor, at("radius_factor"));
    strength(p, b.tensile, &at("tensile"));
    match (b.shear, b.cohesion) {
        (Some(s), None) => {
            strength(p, s, &at("shear"));
            p.check(
                b.friction_angle.is_none(),
                at("friction_angle"),
                "goes with `cohesion` (a cohesion–friction strength), not with a fixed `shear`",
            );
        }
        (None, Some(c)) => {
            p.non_negative(c, at("cohesion"));
            let phi = b.friction_angle.unwrap_or(0.0);
            p.check(
                (0.0..90.0).contains(&phi),
                at("friction_angle"),
                format!("must be in [0, 90) degrees (got {phi})"),
            );
        }
        _ => p.push(
            "bonds",
            "give the shear strength: `shear` (fixed τ_c) or `cohesion` (with `friction_angle`), one of the two",
        ),
    }
    p.check(
        b.scatter.is_finite() && (0.0..=0.3).contains(&b.scatter),
        at("scatter"),
        format!(
            "must be in [0, 0.3] (a coefficient of variation; the strengths are clipped at ±3 standard deviations and must stay > 0; got {})",
            b.scatter
        ),
    );
    p.check(
        b.gap.is_finite() && (0.0..=1.0).contains(&b.gap),
        at("gap"),
        format!(
            "must be in [0, 1] (a fraction of the smaller radius; got {})",
            b.gap
        ),
    );
    if let Some([lo, hi]) = b.region {
        p.check(
            lo.iter().chain(&hi).all(|x| x.is_finite()) && lo[0] < hi[0] && lo[1] < hi[1],
            at("region"),
            "must be [[x0, y0], [x1, y1]] with x0 < x1, y0 < y1",
        );
    }
    for (i, m) in b.materials.iter().enumerate() {
        p.check(
            sc.material(m).is_some(),
            format!("bonds.materials.{i}"),
            format!("no [[material]] named `{m}`"),
        );
    }
}

/// The bond law and rule of a valid `[bonds]`.
pub fn law_and_rule(sc: &Scenario, b: &BondsSpec) -> (BondLaw, BondRule) {
    let shear = match (b.shear, b.cohesion) {
        (Some(s), _) => ShearStrength::Fixed(s),
        (None, c) => ShearStrength::Coulomb {
            cohesion: c.unwrap_or(0.0),
            tan_phi: b.friction_angle.unwrap_or(0.0).to_radians().tan(),
        },
    };
    let law = BondLaw {
        radius_factor: b.radius_factor,
        kn: b.kn,
        ks: b.ks,
        tensile: b.tensile,
        shear,
        scatter: b.scatter,
        seed: b.seed,
    };
    let index = |m: &String| sc.material.iter().position(|x| &x.name == m);
    let rule = BondRule {
        at_step: b.at_step,
        gap: b.gap,
        region: b.region.map(|[lo, hi]| (Vec2::from(lo), Vec2::from(hi))),
        materials: b
            .materials
            .iter()
            .filter_map(|m| index(m).map(|i| i as u16))
            .collect(),
    };
    (law, rule)
}
