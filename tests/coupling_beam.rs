//! Coupled EFG–DE and FE–DE validation on the beam of the paper's Example 1.

use efgdem::scenario::parse;

/// Example 1's beam and disc, with the disc at `x` on the top surface and
/// the given damping lines.
fn scenario(x: f64, extra_sim: &str, disc_damping: &str, body_damping: f64) -> String {
    format!(
        r#"
[simulation]
dt = 1.0e-4
steps = 1
gravity = [0.0, -9.81]
{extra_sim}

[[material]]
name = "disc"
density = 1000.0
kn = 1.0e6
ks = 1.0e6
friction = 0.5

[granular]
material = "disc"
thickness = 1.0
discs = [[{x}, 0.15, 0.05]]
damping = {disc_damping}

[[body]]
name = "beam"
rectangle = {{ origin = [0.0, -0.1], size = [1.0, 0.2] }}
nodes = [20, 4]
elastic = {{ E = 2.1e8, nu = 0.3, density = 2000.0, thickness = 0.025, plane = "stress" }}
damping = {body_damping}
newmark = {{ gamma = 1.5, beta = 0.8 }}
self_weight = false
contact_edges = ["top", "right"]
[[body.bc]]
edge = "left"
fixed = true
"#
    )
}

/// Example 1's disc at `x` on the beam (`method` line added to the body),
/// damped until at rest: 40 000 steps. Checks that one contact carries the
/// disc's weight to 1e-4 and returns the scenario, the model and m g.
fn rest_disc_on_beam(
    x: f64,
    method: &str,
) -> (
    efgdem::scenario::Scenario,
    efgdem::coupling::CoupledModel,
    f64,
) {
    let src = scenario(x, "", r#"{ kind = "local", alpha = 0.7 }"#, 6.4e4)
        .replace("name = \"beam\"\n", &format!("name = \"beam\"\n{method}\n"));
    let sc = parse(&src, "static.toml").unwrap();
    let mut b = sc.build().unwrap().into_coupled().unwrap();
    let m = &mut b;
    let weight = m.granular.particles.mass[0] * 9.81;
    // A free disc would roll down the tilted beam end ((2/3) g sin θ, which
    // friction cannot stop); lock its rotation so that friction holds it.
    m.granular.particles.fixity[0] = efgdem::dem::particles::FIX_ROT;
    for _ in 0..40_000 {
        m.step().unwrap();
    }
    assert_eq!(m.contacts.len(), 1, "the disc rests on the beam");
    let f = m.contacts[0].force;
    let rel = (f.y - weight).abs() / weight;
    eprintln!("contact force {f:?} vs m g = {weight}: {rel:.1e}");
    assert!(
        rel < 1e-4,
        "vertical contact force {} vs m g = {weight}: {rel:e}",
        f.y
    );
    (sc, b, weight)
}

/// Issue 4, validation 3 — static limit: a disc resting on the beam, with
/// damping until at rest, is carried by a contact force equal to its
/// weight, and the beam deflects as Timoshenko beam theory says for a point
/// load m g at the disc's position. Run with the paper's dissipative
/// Newmark (γ = 1.5, β = 0.8), which also helps the body come to rest.
#[test]
fn disc_resting_on_the_beam_reaches_the_static_solution() {
    let a = 0.95; // load position: the disc lies fully on the beam
    let (_, b, weight) = rest_disc_on_beam(a, "");
    let m = &b;
    // beam theory (bending + shear, κ = 5/6) for a load P at x = a, at x = L
    let (e, nu, t, h, l) = (2.1e8, 0.3, 0.025, 0.2, 1.0);
    let i = t * h * h * h / 12.0;
    let g = e / (2.0 * (1.0 + nu));
    let p = weight;
    let exact = p * a * a * (3.0 * l - a) / (6.0 * e * i) + p * a / (5.0 / 6.0 * g * t * h);
    let beam = m.bodies[0]
        .as_any()
        .downcast_ref::<efgdem::efg::boundary::EfgContinuum>()
        .unwrap();
    let tip = -beam.body.sample(efgdem::Vec2::new(l, 0.0)).unwrap().u.y;
    let err = (tip - exact).abs() / exact;
    eprintln!(
        "tip deflection {tip:.6e} vs beam theory {exact:.6e}: {:.3} %",
        100.0 * err
    );
    assert!(
        err < 0.02,
        "tip deflection {tip} vs {exact}: {:.2} %",
        100.0 * err
    );
}

/// Issue 5 — the same static limit with the beam as bilinear FE (Q4 on the
/// 20 × 4 node grid): the contact carries the disc's weight, and the tip
/// deflection is the FE body's own static solution under the contact force
/// at the contact point (Q4 is stiffer in bending than beam theory, so
/// beam theory is not the reference here).
#[test]
fn disc_resting_on_an_fe_beam_reaches_its_static_solution() {
    use efgdem::Vec2;
    use efgdem::fem::{FemBody, FemContinuum};
    let (sc, b, _) = rest_disc_on_beam(0.95, "method = \"fem-q4\"");
    let m = &b;
    let contact = m.contacts[0];
    let beam = m.bodies[0].as_any().downcast_ref::<FemContinuum>().unwrap();
    let tip_at = Vec2::new(1.0, 0.0);
    let tip = beam.body.sample(tip_at).unwrap().u.y;
    // the material point under the contact: X = x − u(X), by fixed point
    let on_top = |p: Vec2| Vec2::new(p.x, 0.1);
    let mut x = on_top(contact.point);
    for _ in 0..5 {
        x = on_top(contact.point - beam.body.sample(x).unwrap().u);
    }
    let mut reference = FemBody::new(&sc.body[0].params(), sc.simulation.gravity).unwrap();
    reference.add_point_load(x, -contact.force).unwrap();
    reference.solve_static().unwrap();
    let expect = reference.sample(tip_at).unwrap().u.y;
    let err = (tip - expect).abs() / expect.abs();
    eprintln!("FE beam: tip {tip:.6e} vs static FE {expect:.6e}: {err:.2e}");
    assert!(err < 1e-3, "{tip} vs {expect}: {err:e}");
}
