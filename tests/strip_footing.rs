//! Fast sanity test of the strip footing example (issue 15, example 2):
//! `examples/strip_footing.toml` at a quarter of its bed (1 300 discs, a
//! 20 mm footing), the same material, phases and servo. The full example
//! and its comparison with the bearing capacity are in the README.

#[allow(dead_code)]
mod common;

use efgdem::geotech::bearing::{self, NGamma};
use efgdem::output::csv::History;

/// The example, smaller: every edit must apply.
fn small() -> String {
    let mut s = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/strip_footing.toml"
    ))
    .unwrap();
    for (a, b) in [
        ("[[0.0, 0.0], [0.24, 0.075]]", "[[0.0, 0.0], [0.1, 0.03]]"),
        ("count = 7800", "count = 1290"),
        ("to = [0.24, 0.0]", "to = [0.1, 0.0]"),
        ("from = [0.24, 0.0]", "from = [0.1, 0.0]"),
        ("to = [0.24, 0.12]", "to = [0.1, 0.06]"),
        ("to = [0.0, 0.12]", "to = [0.0, 0.06]"),
        (
            "origin = [0.1, 0.077], size = [0.04, 0.012]",
            "origin = [0.04, 0.032], size = [0.02, 0.008]",
        ),
        ("nodes = [21, 7]", "nodes = [11, 5]"),
        ("point = [0.12, 0.089]", "point = [0.05, 0.04]"),
        (
            "[[0.01, 0.005], [0.08, 0.06]]",
            "[[0.002, 0.002], [0.03, 0.025]]",
        ),
        ("until_step = 10000 }", "until_step = 5000 }"),
        (
            "until_step = 20000, velocity = -0.2",
            "until_step = 12000, velocity = -0.2",
        ),
        ("until_step = 42857", "until_step = 25000"),
        (
            "[[0.06, 60.0], [0.14, 300.0]]",
            "[[0.035, 10.0], [0.07, 150.0]]",
        ),
        ("end_time = 0.14", "end_time = 0.07"),
        ("vtk_every = 20000", "vtk_every = 0"),
    ] {
        assert!(s.contains(a), "the example no longer has `{a}`");
        s = s.replace(a, b);
    }
    s
}

#[test]
fn a_small_footing_sinks_calmly_and_its_load_is_near_the_bearing_capacity() {
    let dir = common::tmpdir("strip-footing");
    let f = dir.join("small.toml");
    std::fs::write(&f, small()).unwrap();
    let out = dir.join("out");
    common::run(&f, &out);
    let h = History::read(&out.join("history.csv")).unwrap();
    let f = h.values("reaction").unwrap();
    let uy = h.values("settlement").unwrap();
    let v = h.values("drive_v").unwrap();
    let kin = h.values("E_kin_body").unwrap();
    let n = h.values("bed_porosity").unwrap();
    let k0 = bearing::first_contact(&f).expect("the footing reaches the bed");
    // it touches during the push at 0.05 m/s, not before (the grown bed's
    // relaxation throws discs up: the footing waits above them)
    let t = h.values("t").unwrap();
    assert!(t[k0] > 0.5 * 12000.0 * 1.4e-6, "contact at t = {}", t[k0]);
    // the footing (1 kg-ish per m: 2400 × 0.02 × 0.008 = 0.384 kg) stays a
    // rigid body moving at most at 0.2 m/s: its kinetic energy stays below
    // ½ m (0.2 m/s)² × 2 — a servo on a γ = ½ body grows it without bound
    let bound = 0.384 * 0.2 * 0.2;
    let worst = kin.iter().fold(0.0, |a: f64, &b| a.max(b));
    assert!(worst < bound, "E_kin of the footing up to {worst} J");
    // the target (150 N) is beyond what the bed carries: the footing ends
    // sinking at the servo's largest velocity
    let last = &v[v.len() - 20..];
    assert!(
        last.iter().filter(|&&x| x <= -0.05 + 1e-12).count() >= 10,
        "{last:?}"
    );
    // the load where it fails, against q_u = γDN_q + ½γBN_γ with the
    // biaxial example's φ_peak = 23.7° and Meyerhof's N_γ, over the
    // penetration past 5 % of B: a factor of two either way (B = 13 grain
    // diameters: grain-scale effects; the theories' N_γ differ by 1.7 here)
    let porosity = n[..k0].iter().sum::<f64>() / k0 as f64;
    assert!((0.12..0.25).contains(&porosity), "porosity {porosity}");
    let gamma = 2650.0 * (1.0 - porosity) * 9.81;
    let b = 0.02;
    let c = bearing::curve(&uy, &f, 2.5e-4);
    let seated: Vec<_> = c.iter().filter(|p| p.penetration >= 0.05 * b).collect();
    assert!(seated.len() >= 3, "{c:?}");
    let ratio = seated
        .iter()
        .map(|p| {
            p.mean
                / (bearing::ultimate_pressure(
                    gamma,
                    b,
                    p.penetration,
                    23.7f64.to_radians(),
                    NGamma::Meyerhof,
                ) * b)
        })
        .sum::<f64>()
        / seated.len() as f64;
    eprintln!(
        "contact at t = {:.4} s, porosity {porosity:.3}, E_kin of the footing ≤ {worst:.2e} J, measured / Meyerhof = {ratio:.2}",
        t[k0]
    );
    assert!((0.5..2.0).contains(&ratio), "measured / theory = {ratio}");
}
