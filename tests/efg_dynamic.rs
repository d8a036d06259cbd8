//! Validation 4: free vibration of a slender cantilever (L/H = 20) released
//! from its static deflection under a tip load.

use efgdem::Vec2;
use efgdem::efg::{EfgBody, ShapeRow};
use efgdem::scenario;

const L: f64 = 10.0;
const H: f64 = 0.5;
const E: f64 = 1.0e7;
const RHO: f64 = 1.0;

fn euler_bernoulli_period() -> f64 {
    let ei = E * H.powi(3) / 12.0;
    let w = 1.8751f64.powi(2) * (ei / (RHO * H * L.powi(4))).sqrt();
    2.0 * std::f64::consts::PI / w
}

struct Run {
    t: Vec<f64>,
    tip: Vec<f64>,
    energy: Vec<f64>,
}

fn run(nodes: [usize; 2], gamma: f64, beta: f64, steps_per_period: f64, steps: usize) -> Run {
    let src = format!(
        r#"
[simulation]
analysis = "dynamic"
dt = {dt}
steps = {steps}
[[body]]
name = "beam"
rectangle = {{ origin = [0.0, {y0}], size = [{L}, {H}] }}
nodes = {nodes:?}
elastic = {{ E = {E}, nu = 0.3, density = {RHO}, plane = "stress" }}
newmark = {{ gamma = {gamma}, beta = {beta} }}
initial = {{ static_under = ["tip"] }}
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
name = "tip"
edge = "right"
parabolic_shear = -1.0
"#,
        y0 = -H / 2.0,
        dt = euler_bernoulli_period() / steps_per_period
    );
    let sc = scenario::parse(&src, "vib.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut b = EfgBody::new(&sc.body[0].params(), sc.simulation.gravity).unwrap();
    b.solve_static().unwrap();
    let dt = euler_bernoulli_period() / steps_per_period;
    b.start_dynamic(dt).unwrap();
    let mut row = ShapeRow::new();
    b.shape_row(Vec2::new(L, 0.0), &mut row).unwrap();
    let mut r = Run {
        t: vec![0.0],
        tip: vec![b.sample_row(&row).u.y],
        energy: vec![b.kinetic_energy() + b.strain_energy()],
    };
    for _ in 0..steps {
        b.advance().unwrap();
        r.t.push(b.time);
        r.tip.push(b.sample_row(&row).u.y);
        let nm = b.newmark().unwrap();
        r.energy
            .push(nm.kinetic_energy(&b.state) + nm.strain_energy(&b.state));
    }
    r
}

/// Mean period from upward zero crossings (linear interpolation).
fn period(r: &Run) -> f64 {
    let mut c = vec![];
    for k in 1..r.tip.len() {
        let (a, b) = (r.tip[k - 1], r.tip[k]);
        if a < 0.0 && b >= 0.0 {
            c.push(r.t[k - 1] + (r.t[k] - r.t[k - 1]) * (-a) / (b - a));
        }
    }
    (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64
}

/// Successive negative peaks |min u_y| (one per period).
fn troughs(r: &Run) -> Vec<f64> {
    let mut p = vec![r.tip[0].abs()];
    for k in 1..r.tip.len() - 1 {
        if r.tip[k] < 0.0 && r.tip[k] <= r.tip[k - 1] && r.tip[k] < r.tip[k + 1] {
            p.push(r.tip[k].abs());
        }
    }
    p
}

#[test]
fn free_vibration_average_acceleration() {
    let r = run([81, 5], 0.5, 0.25, 100.0, 1000);
    let t1 = euler_bernoulli_period();
    let t = period(&r);
    let e0 = r.energy[0];
    let drift = r
        .energy
        .iter()
        .map(|e| (e - e0).abs() / e0)
        .fold(0.0, f64::max);
    println!(
        "period {t:.6} vs Euler–Bernoulli {t1:.6}: {:+.3} %; energy drift {drift:.2e} over 1000 steps",
        100.0 * (t - t1) / t1
    );
    assert!((t - t1).abs() < 0.02 * t1);
    assert!(drift < 1e-6);
}

#[test]
fn free_vibration_paper_newmark_is_dissipative() {
    let r = run([81, 5], 1.5, 0.8, 100.0, 600);
    let p = troughs(&r);
    let ratios: Vec<f64> = p.windows(2).map(|w| w[1] / w[0]).collect();
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    let t1 = euler_bernoulli_period();
    println!(
        "γ = 1.5, β = 0.8, Δt = T₁/100: amplitude ratio per period {mean:.4} (decay {:.1} % per period), peaks {p:?}; period {:.5} vs {t1:.5}",
        100.0 * (1.0 - mean),
        period(&r)
    );
    // the docs quote "about 18 % amplitude loss per period" (measured
    // 18.4 %: ratio 0.816); 16–20 % is what they may round to
    assert!(
        (0.80..0.84).contains(&mean),
        "γ = 1.5: amplitude ratio per period {mean}, the docs say about 0.82"
    );
    let e_end = *r.energy.last().unwrap();
    assert!(e_end < 0.5 * r.energy[0]);
}
