//! Bearing capacity of a strip footing on a cohesionless soil, and the
//! load–settlement curve of a footing test (
//! `examples/strip_footing.toml`, post-processed by
//! `examples/strip_footing_post.rs`).
//!
//! **Theory.** The ultimate pressure of a rough strip footing of width `B`
//! at depth `D` in a soil of unit weight `γ` and friction angle `φ`
//! without cohesion (Terzaghi 1943, with the factors below):
//! `q_u = γ D N_q + ½ γ B N_γ`, where `N_q = e^{π tan φ} tan²(45° + φ/2)`
//! (Prandtl 1921, Reissner 1924) and `N_γ` has no closed form; its common
//! approximations differ by up to a factor of two at φ ≈ 25°
//! ([`NGamma`]). A footing pressed into the surface has `D` = its
//! penetration, so `q_u` grows as it sinks.
//!
//! **The test.** A footing driven down onto a bed: its reaction (the total
//! vertical disc force on it, `contact_fy`) against its travel (`uy` of a
//! point of the footing). The penetration is the travel since the first
//! row with a reaction; the reaction of a bed of discs jumps from row to
//! row as force chains form and buckle, so the curve is the mean (and
//! range) of the reaction over bins of penetration ([`curve`]).

use std::f64::consts::PI;

/// An approximation of the bearing capacity factor `N_γ`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NGamma {
    /// `2 (N_q + 1) tan φ` (Vesić 1973).
    Vesic,
    /// `(N_q − 1) tan(1.4 φ)` (Meyerhof 1963).
    Meyerhof,
    /// `1.5 (N_q − 1) tan φ` (Brinch Hansen 1970).
    Hansen,
    /// `2 (N_q − 1) tan φ` (Eurocode 7, EN 1997-1 Annex D, rough base).
    Eurocode7,
}

impl NGamma {
    /// All four, in the order above.
    pub const ALL: [NGamma; 4] = [
        NGamma::Vesic,
        NGamma::Meyerhof,
        NGamma::Hansen,
        NGamma::Eurocode7,
    ];

    /// The name used in tables and plots.
    pub fn name(self) -> &'static str {
        match self {
            NGamma::Vesic => "Vesić",
            NGamma::Meyerhof => "Meyerhof",
            NGamma::Hansen => "Hansen",
            NGamma::Eurocode7 => "EC7",
        }
    }
}

/// `N_q = e^{π tan φ} tan²(45° + φ/2)`, φ in radians.
pub fn n_q(phi: f64) -> f64 {
    (PI * phi.tan()).exp() * (PI / 4.0 + phi / 2.0).tan().powi(2)
}

/// `N_γ` by `method`, φ in radians.
pub fn n_gamma(phi: f64, method: NGamma) -> f64 {
    let nq = n_q(phi);
    match method {
        NGamma::Vesic => 2.0 * (nq + 1.0) * phi.tan(),
        NGamma::Meyerhof => (nq - 1.0) * (1.4 * phi).tan(),
        NGamma::Hansen => 1.5 * (nq - 1.0) * phi.tan(),
        NGamma::Eurocode7 => 2.0 * (nq - 1.0) * phi.tan(),
    }
}

/// Ultimate pressure `q_u = γ D N_q + ½ γ B N_γ` of a strip footing of
/// width `b` at depth `d` (Pa for γ in N/m³ and lengths in m).
pub fn ultimate_pressure(gamma: f64, b: f64, d: f64, phi: f64, method: NGamma) -> f64 {
    gamma * d * n_q(phi) + 0.5 * gamma * b * n_gamma(phi, method)
}

/// One bin of the load–settlement curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// Mean penetration of the rows in the bin.
    pub penetration: f64,
    /// Mean reaction.
    pub mean: f64,
    /// Smallest and largest reaction of the rows.
    pub min: f64,
    /// See `min`.
    pub max: f64,
    /// Rows in the bin.
    pub rows: usize,
}

/// Rows over which a contact must last to count ([`first_contact`]).
pub const CONTACT_ROWS: usize = 20;

/// Where the footing touches the bed for good: the first row from which
/// the reaction is positive in at least half of the next
/// [`CONTACT_ROWS`] rows (a single disc bouncing off the footing before it
/// reaches the bed does not count).
pub fn first_contact(reaction: &[f64]) -> Option<usize> {
    (0..reaction.len()).find(|&k| {
        let w = &reaction[k..(k + CONTACT_ROWS).min(reaction.len())];
        reaction[k] > 0.0 && 2 * w.iter().filter(|&&f| f > 0.0).count() >= CONTACT_ROWS
    })
}

/// The load–settlement curve from rows of the footing's vertical
/// displacement `uy` (down negative) and its reaction (up positive): the
/// rows from the first contact ([`first_contact`]) on, binned by penetration `-(uy − uy₀)` in
/// bins of width `bin` from 0; empty bins are left out. Rows whose
/// penetration decreases again (a footing lifted) fall into their bins like
/// the others.
pub fn curve(uy: &[f64], reaction: &[f64], bin: f64) -> Vec<CurvePoint> {
    let Some(k0) = first_contact(reaction) else {
        return Vec::new();
    };
    let mut bins: Vec<Option<CurvePoint>> = Vec::new();
    for (u, &f) in uy[k0..].iter().zip(&reaction[k0..]) {
        let s = -(u - uy[k0]);
        let k = (s / bin).floor().max(0.0) as usize;
        if bins.len() <= k {
            bins.resize(k + 1, None);
        }
        let b = bins[k].get_or_insert(CurvePoint {
            penetration: 0.0,
            mean: 0.0,
            min: f,
            max: f,
            rows: 0,
        });
        b.penetration += s;
        b.mean += f;
        b.min = b.min.min(f);
        b.max = b.max.max(f);
        b.rows += 1;
    }
    bins.into_iter()
        .flatten()
        .map(|mut b| {
            b.penetration /= b.rows as f64;
            b.mean /= b.rows as f64;
            b
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deg(d: f64) -> f64 {
        d.to_radians()
    }

    /// Published tables (Das, Principles of Foundation Engineering, tables
    /// of N_q and of Vesić's, Meyerhof's and Hansen's N_γ), to their 4
    /// digits.
    #[test]
    fn factors_match_the_published_tables() {
        let close = |a: f64, b: f64| (a - b).abs() < 0.006 * b.max(1.0);
        assert!(close(n_q(deg(20.0)), 6.40));
        assert!(close(n_q(deg(30.0)), 18.40));
        assert!(close(n_q(deg(40.0)), 64.20));
        assert!(close(n_gamma(deg(20.0), NGamma::Vesic), 5.39));
        assert!(close(n_gamma(deg(30.0), NGamma::Vesic), 22.40));
        assert!(close(n_gamma(deg(40.0), NGamma::Vesic), 109.41));
        assert!(close(n_gamma(deg(20.0), NGamma::Meyerhof), 2.87));
        assert!(close(n_gamma(deg(30.0), NGamma::Meyerhof), 15.67));
        assert!(close(n_gamma(deg(20.0), NGamma::Hansen), 2.95));
        assert!(close(n_gamma(deg(30.0), NGamma::Hansen), 15.07));
        assert!(close(n_gamma(deg(40.0), NGamma::Hansen), 79.54));
        // φ = 0: N_q = 1, N_γ = 0 (Vesić's is 0 too: tan 0)
        assert!((n_q(0.0) - 1.0).abs() < 1e-15);
        for m in NGamma::ALL {
            assert!(n_gamma(0.0, m).abs() < 1e-15);
        }
        // q_u: ½ γ B N_γ plus γ D N_q
        let q = ultimate_pressure(2.0e4, 0.04, 0.002, deg(30.0), NGamma::Vesic);
        assert!((q - (2.0e4 * 0.002 * n_q(deg(30.0)) + 0.5 * 2.0e4 * 0.04 * 22.40)).abs() < 1.0);
    }

    #[test]
    fn curve_bins_from_the_first_contact() {
        // the footing falls 1 mm before touching (a disc bounces off it on
        // the way: one row), then sinks 0.04 mm per row with a reaction of
        // 1 N per 0.001 mm, ±1 N alternately
        let mut uy = Vec::new();
        let mut f = Vec::new();
        for k in 0..40 {
            uy.push(-2.5e-5 * k as f64);
            f.push(if k == 2 { 5.0 } else { 0.0 });
        }
        for k in 0..100 {
            let s = 4e-5 * k as f64;
            uy.push(-1e-3 - s);
            f.push(1e6 * s + if k % 2 == 0 { 1.0 } else { -1.0 } + 1e-9);
        }
        assert_eq!(first_contact(&f), Some(40));
        let c = curve(&uy, &f, 1e-3);
        assert_eq!(c.len(), 4);
        // bin 0: rows at 0, 0.04, …, 0.96 mm
        assert_eq!(c[0].rows, 25);
        assert!((c[0].penetration - 4.8e-4).abs() < 1e-15);
        assert!((c[0].mean - (480.0 + 1.0 / 25.0)).abs() < 1e-6);
        assert!((c[0].min - 1.0).abs() < 1e-6 && (c[0].max - 961.0).abs() < 1e-6);
        assert_eq!(c.iter().map(|b| b.rows).sum::<usize>(), 100);
        // no contact, no curve
        assert!(curve(&uy[..40], &f[..40], 1e-3).is_empty());
    }
}
