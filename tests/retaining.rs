//! Earth pressure coefficients of the retaining wall (issue 15 §1;
//! `efgdem::geotech::retaining`) against published values.

use efgdem::geotech::retaining::{coulomb_ka, jaky_k0, rankine_ka};

#[test]
fn jaky_and_rankine_closed_forms() {
    // K₀ = 1 − sin 30° = 0.5; K_a(30°) = 1/3, K_a(20°) = tan²35° = 0.4903
    assert!((jaky_k0(30.0) - 0.5).abs() < 1e-12);
    assert!((rankine_ka(30.0) - 1.0 / 3.0).abs() < 1e-12);
    assert!((rankine_ka(20.0) - 35f64.to_radians().tan().powi(2)).abs() < 1e-12);
}

#[test]
fn coulomb_without_wall_friction_is_rankine() {
    for phi in [15.0, 21.4, 23.7, 30.0, 40.0] {
        assert!(
            (coulomb_ka(phi, 0.0) - rankine_ka(phi)).abs() < 1e-12,
            "φ = {phi}"
        );
    }
}

#[test]
fn coulomb_matches_the_published_table() {
    // Das, Principles of Foundation Engineering, Coulomb's K_a for a
    // vertical wall and a horizontal backfill, φ = 30° row (4 decimals)
    for (delta, ka) in [
        (5.0, 0.3189),
        (10.0, 0.3085),
        (15.0, 0.3014),
        (20.0, 0.2973),
    ] {
        let k = coulomb_ka(30.0, delta);
        assert!((k - ka).abs() < 1e-4, "δ = {delta}: {k} vs {ka}");
    }
}

#[test]
fn coulomb_is_the_largest_trial_wedge_thrust() {
    // Coulomb's construction: a planar wedge at ρ from the horizontal,
    // weight W = γH²/(2 tan ρ), the reaction on the slip plane at φ to its
    // normal and the wall's at δ: P = W sin(ρ − φ)/sin(90° + δ + φ − ρ);
    // K_a = max over ρ of 2P/(γH²)
    for (phi, delta) in [(21.4f64, 0.0f64), (23.7, 6.0), (30.0, 20.0), (40.0, 25.0)] {
        let (p, d) = (phi.to_radians(), delta.to_radians());
        let best = (1..200_000)
            .map(|i| p + (std::f64::consts::FRAC_PI_2 - p) * i as f64 / 200_000.0)
            .map(|r| (r - p).sin() / (std::f64::consts::FRAC_PI_2 + d + p - r).sin() / r.tan())
            .fold(0.0, f64::max);
        let k = coulomb_ka(phi, delta);
        assert!(
            (k - best).abs() < 1e-6 * k,
            "φ = {phi}, δ = {delta}: {k} vs {best}"
        );
    }
}

#[test]
fn coulomb_horizontal_thrust_falls_with_wall_friction() {
    // the horizontal component K_a cos δ of a rough wall is below Rankine
    let phi = 25.0;
    let mut last = rankine_ka(phi);
    for delta in [5.0, 10.0, 15.0, 20.0] {
        let kh = coulomb_ka(phi, delta) * f64::to_radians(delta).cos();
        assert!(kh < last, "δ = {delta}: {kh} ≥ {last}");
        last = kh;
    }
}
