//! A growth path against an analytical one (`examples/crack_path.toml`):
//! a crack under `K_I`, a small `K_II` and a T-stress — the two-term
//! near-tip field prescribed on the outline of a square around the tip —
//! grows by the maximum hoop-stress criterion, and its path is compared
//! with the first-order path of Cotterell & Rice (1980, "Slightly curved
//! or kinked cracks", Int. J. Fract. 16:155–169; [`cotterell_rice_path`]).
//!
//! **The bound.** The growth takes straight pieces of Δa, the first along
//! the initial kink, so it cannot follow the curve closer than that first
//! chord does: `δ₁ = |λ(Δa) − Δa tan θ_c|` (θ_c the hoop-stress kink of
//! the prescribed K). The analytical path is first order in `K_II/K_I`;
//! its slopes carry a relative error of order `(2K_II/K_I)²`, so over a
//! run x it may be off by `(2K_II/K_I)² x`. The computed tips must lie
//! within `δ₁ + (2K_II/K_I)² x` of it — and, to show the T-stress is
//! followed, the last tip must lie 4 times closer to it than to the
//! straight path of the same K without T-stress.

use efgdem::continuum::WilliamsSpec;
#[allow(dead_code)]
mod common;

use efgdem::continuum::crack_tip::{cotterell_rice_path, max_hoop_stress};
use efgdem::efg::EfgBody;
use efgdem::geom::Vec2;

const EXAMPLE: &str = include_str!("../examples/crack_path.toml");

/// The example with node spacing `h`, crack spacing `hc`, `n` increments
/// and T-stress `t`: its field and the crack tips after each increment.
fn grow(h: f64, hc: f64, n: usize, t: f64) -> (WilliamsSpec, f64, Vec<Vec2>) {
    let src = EXAMPLE
        .replace("spacing = 0.05\n", &format!("spacing = {h}\n"))
        .replace("spacing = 0.01 ", &format!("spacing = {hc} "))
        .replace("max_increments = 6", &format!("max_increments = {n}"))
        .replace("T = -1.0e6", &format!("T = {t:e}"));
    let sc = efgdem::scenario::parse(&src, "crack_path.toml").unwrap();
    let p = sc.body[0].params();
    let w = p.bc.iter().find_map(|b| b.williams).unwrap();
    let mut b = EfgBody::new(&p, sc.simulation.gravity).unwrap();
    let g = b.solve_static_growing().unwrap();
    assert_eq!(g.len(), n);
    let pts = b.cracks()[0].crack.points.clone();
    (w, 5.0 * hc, pts.into_iter().filter(|q| q.x > 0.0).collect())
}

/// The distance check of the module doc; returns the largest
/// `|y − λ(x)|` over the bound.
fn check_path(h: f64, hc: f64, n: usize) -> f64 {
    let (w, da, tips) = grow(h, hc, n, -1.0e6);
    let k = [w.k1, w.k2];
    let (theta, _) = max_hoop_stress(k);
    let d1 = (cotterell_rice_path(k, w.t, da) - da * theta.tan()).abs();
    let second = (2.0 * w.k2 / w.k1).powi(2);
    let mut worst: f64 = 0.0;
    for q in &tips {
        let r = cotterell_rice_path(k, w.t, q.x);
        let bound = d1 + second * q.x;
        println!(
            "x {:.4}: y {:.5}, analytical {r:.5}, difference {:.5} (bound {bound:.5})",
            q.x,
            q.y,
            q.y - r
        );
        assert!((q.y - r).abs() <= bound, "{q:?}: {r}");
        worst = worst.max((q.y - r).abs() / bound);
    }
    let end = tips.last().unwrap();
    let straight = cotterell_rice_path(k, 0.0, end.x);
    let off = (end.y - cotterell_rice_path(k, w.t, end.x)).abs();
    println!(
        "last tip {:.5} from the straight path, {off:.5} from the analytical one",
        (end.y - straight).abs()
    );
    assert!((end.y - straight).abs() > 4.0 * off);
    worst
}

/// The path of the example at half its resolution (Δa = 0.1, three
/// increments) within the bound of the module doc.
#[test]
fn crack_path_follows_cotterell_and_rice() {
    let worst = check_path(0.1, 0.02, 3);
    println!("largest difference: {worst:.2} of the bound");
}

/// The example as it is (Δa = 0.05, six increments): within the bound.
#[test]
#[ignore = "the example at full resolution: 10–20 s; the normal tests take it at half"]
fn crack_path_example_follows_cotterell_and_rice() {
    let worst = check_path(0.05, 0.01, 6);
    println!("largest difference: {worst:.2} of the bound");
}

/// Without T-stress the crack kinks once and runs on straight (local
/// symmetry: `K_II` vanishes at the kinked tip), along the hoop-stress
/// kink within 2 % of the run.
#[test]
fn without_t_stress_the_kinked_crack_runs_straight() {
    let (w, _, tips) = grow(0.1, 0.02, 3, 0.0);
    let (theta, _) = max_hoop_stress([w.k1, w.k2]);
    for q in &tips {
        let y = q.x * theta.tan();
        println!("x {:.4}: y {:.5}, straight {y:.5}", q.x, q.y);
        assert!((q.y - y).abs() < 0.02 * q.norm(), "{q:?}");
    }
}

/// The exact-field boundary conditions from a scenario file: `efgdem
/// check` accepts the example (`williams`) and the same body with
/// `griffith`, and refuses a `williams` with an unknown key (file, line,
/// exit 2).
#[test]
fn exact_field_conditions_pass_the_scenario_check() {
    let dir = common::tmpdir("crack-path-check");
    let check = |tag: &str, src: &str| {
        let f = dir.join(format!("{tag}.toml"));
        std::fs::write(&f, src).unwrap();
        common::bin()
            .args(["check", f.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let williams = "williams = { KI = 1.0e6, KII = 5.0e4, T = -1.0e6 }";
    assert!(EXAMPLE.contains(williams));
    assert!(check("w", EXAMPLE).status.success());
    let g = EXAMPLE.replace(williams, "griffith = { S = 1.0e6, a = 1.0, beta = 30.0 }");
    assert!(check("g", &g).status.success());
    let bad = check(
        "bad",
        &EXAMPLE.replace("T = -1.0e6", "T = -1.0e6, beta = 3.0"),
    );
    let err = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(bad.status.code(), Some(2), "{err}");
    assert!(err.contains("bad.toml:") && err.contains("beta"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}
