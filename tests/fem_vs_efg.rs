//! FE and EFG bodies on the same node grid (issue 5, validation 2): the
//! Example 1 beam of the paper (1 × 0.2 m, t = 0.025 m, E = 2.1e8 Pa,
//! ν = 0.3, ρ = 2000 kg/m³, plane stress, clamped at x = 0) under a 77 N
//! point load at the top-right corner: static tip deflection and first
//! natural period (free vibration released from the static deflection,
//! γ = 1/2, β = 1/4, period from the up-going zero crossings of the tip
//! deflection), measured the same way for both bodies.

use efgdem::Vec2;
use efgdem::efg::EfgBody;
use efgdem::fem::FemBody;
use efgdem::scenario;

const TIP: Vec2 = Vec2 { x: 1.0, y: 0.2 };
const LOAD: Vec2 = Vec2 { x: 0.0, y: -77.0 };

fn spec(method: &str, nodes: [usize; 2], mass: &str) -> scenario::body::BodySpec {
    let src = format!(
        r#"
[simulation]
analysis = "static"
[[body]]
name = "plate"
method = "{method}"
{mass}
rectangle = {{ origin = [0.0, 0.0], size = [1.0, 0.2] }}
nodes = {nodes:?}
elastic = {{ E = 2.1e8, nu = 0.3, density = 2000.0, thickness = 0.025, plane = "stress" }}
[[body.bc]]
edge = "left"
fixed = true
"#
    );
    scenario::parse(&src, "beam.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .body
        .remove(0)
}

/// Period from the up-going zero crossings of `y(t)` (linear interpolation).
fn period(ys: &[f64], dt: f64) -> f64 {
    let mut cross = vec![];
    for k in 1..ys.len() {
        if ys[k - 1] < 0.0 && ys[k] >= 0.0 {
            cross.push((k as f64 - 1.0 + ys[k - 1] / (ys[k - 1] - ys[k])) * dt);
        }
    }
    assert!(cross.len() >= 2, "not enough oscillations");
    (cross[cross.len() - 1] - cross[0]) / (cross.len() - 1) as f64
}

const DT: f64 = 2.5e-4;
const STEPS: usize = 1600;

/// (static tip u_y, first period) of the EFG body.
fn efg(nodes: [usize; 2]) -> (f64, f64) {
    let mut b = EfgBody::new(&spec("efg", nodes, "").params(), [0.0, 0.0]).unwrap();
    b.add_point_load(TIP, LOAD).unwrap();
    b.solve_static().unwrap();
    let tip = b.sample(TIP).unwrap().u.y;
    b.f_point.iter_mut().for_each(|f| *f = 0.0);
    b.start_dynamic(DT).unwrap();
    let ys: Vec<f64> = (0..STEPS)
        .map(|_| {
            b.advance().unwrap();
            b.sample(TIP).unwrap().u.y
        })
        .collect();
    (tip, period(&ys, DT))
}

/// (static tip u_y, first period) of the FE body.
fn fem(nodes: [usize; 2], mass: &str) -> (f64, f64) {
    let mut b = FemBody::new(&spec("fem-q4", nodes, mass).params(), [0.0, 0.0]).unwrap();
    b.add_point_load(TIP, LOAD).unwrap();
    b.solve_static().unwrap();
    let tip = b.sample(TIP).unwrap().u.y;
    b.f_point.iter_mut().for_each(|f| *f = 0.0);
    b.start_dynamic(DT).unwrap();
    let ys: Vec<f64> = (0..STEPS)
        .map(|_| {
            b.advance().unwrap();
            b.sample(TIP).unwrap().u.y
        })
        .collect();
    (tip, period(&ys, DT))
}

/// Measured (release build): on 20 × 4 nodes the consistent-mass Q4 body is
/// 2.7 % stiffer than EFG at the tip (bilinear elements lock in bending:
/// parasitic shear with only 3 elements through the depth) and its period
/// is 1.1 % shorter; both differences shrink under refinement (40 × 8:
/// −0.9 % and −0.35 %), as both methods converge to the same solution. The
/// issue's 3 % target holds on the paper's grid; the finer grid is checked
/// with a tighter bound to show the gap is discretisation error.
#[test]
fn fem_and_efg_agree_on_example_1_beam() {
    let rel = |a: f64, b: f64| (a - b) / b;
    for (nodes, bound) in [([20, 4], 0.03), ([40, 8], 0.015)] {
        let (te, pe) = efg(nodes);
        let (tf, pf) = fem(nodes, "");
        let (tl, pl) = fem(nodes, "mass = \"lumped\"");
        println!(
            "{nodes:?}: EFG tip {te:.5e} T {pe:.5e} | FE tip {tf:.5e} ({:+.2}%) T {pf:.5e} ({:+.2}%) | FE lumped T {pl:.5e} ({:+.2}%) tip {tl:.3e}",
            100.0 * rel(tf, te),
            100.0 * rel(pf, pe),
            100.0 * rel(pl, pe)
        );
        assert!(rel(tf, te).abs() < bound, "tip: FE {tf} vs EFG {te}");
        assert!(rel(pf, pe).abs() < bound, "period: FE {pf} vs EFG {pe}");
        assert!(
            rel(pl, pe).abs() < bound,
            "period: lumped FE {pl} vs EFG {pe}"
        );
        // Q4 is too stiff: smaller deflection, shorter period
        assert!(tf.abs() < te.abs() && pf < pe);
    }
}
