//! `initial = { static_under = [...] }` in a coupled run starts the body
//! from its static equilibrium under the named loads, released at t = 0 —
//! as in a continuum-only run (it used to drop the loads without solving
//! the static state, so the body started undeformed and at rest).

use efgdem::Vec2;
use efgdem::model::Model;
use efgdem::scenario;

/// A cantilever pushed down at its tip for the initial state, then
/// released; with `discs`, a disc far above it (a coupled run, no
/// contact during the steps).
fn beam(discs: bool, method: &str) -> Model {
    let granular = if discs {
        r#"
[[material]]
name = "m"
density = 1000.0
kn = 1e6
ks = 1e6
[granular]
material = "m"
discs = [[2.0, 5.0, 0.05]]
"#
    } else {
        ""
    };
    let src = format!(
        r#"
[simulation]
analysis = "dynamic"
dt = 2e-3
steps = 400
{granular}
[[body]]
name = "beam"
method = "{method}"
rectangle = {{ origin = [0.0, -0.25], size = [4.0, 0.5] }}
nodes = [17, 5]
elastic = {{ E = 1e7, nu = 0.3, density = 100.0, plane = "stress" }}
initial = {{ static_under = ["push"] }}
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
name = "push"
edge = "right"
traction = [0.0, -1000.0]
"#
    );
    scenario::parse(&src, "beam.toml").unwrap().build().unwrap()
}

fn tip_history(mut m: Model) -> Vec<f64> {
    let at = m.body(0).bind(Vec2::new(4.0, 0.0)).unwrap();
    let mut tip = vec![m.body(0).sample_at(&at).u.y];
    for _ in 0..400 {
        m.step().unwrap();
        tip.push(m.body(0).sample_at(&at).u.y);
    }
    tip
}

#[test]
fn a_coupled_body_starts_from_its_initial_static_state() {
    for method in ["efg", "fem-q4"] {
        let alone = tip_history(beam(false, method));
        let coupled = tip_history(beam(true, method));
        // Euler–Bernoulli: δ = P L³ / (3 E I) with P = 1000 × 0.5, I = h³/12
        let exact = -500.0 * 4f64.powi(3) / (3.0 * 1e7 * 0.5f64.powi(3) / 12.0);
        assert!(
            (alone[0] / exact - 1.0).abs() < 0.1,
            "{method}: static tip {:.4e} vs beam theory {exact:.4e}",
            alone[0]
        );
        // released: it swings up from there
        assert!(alone.iter().any(|&u| u > 0.5 * alone[0].abs()), "{method}");
        for (k, (a, c)) in alone.iter().zip(&coupled).enumerate() {
            assert!(
                (a - c).abs() <= 1e-12 * alone[0].abs(),
                "{method} step {k}: alone {a:e}, coupled {c:e}"
            );
        }
    }
}
