//! Crack growth in EFG bodies: the first increment along the maximum
//! hoop-stress direction, a growth path, the state carried over.

use efgdem::continuum::crack_tip::max_hoop_stress;
use efgdem::continuum::{
    BodyParams, CrackShape, EdgeCondition, Elastic, Fracture, GriffithSpec, PolygonShape, Rectangle,
};
use efgdem::efg::EfgBody;
use efgdem::geom::Vec2;
use efgdem::geom::crack::Crack;
use efgdem::geom::polygon::Domain;

#[allow(dead_code)]
mod common;

fn square(half: f64) -> Domain {
    let sq = [[-half, -half], [half, -half], [half, half], [-half, half]]
        .iter()
        .map(|&p| p.into())
        .collect();
    Domain::new(
        sq,
        vec![],
        vec![("out".into(), (0..4).map(|i| (0, i)).collect())],
    )
    .unwrap()
}

fn plate(domain: Domain, h: f64, bc: Vec<EdgeCondition>) -> BodyParams {
    let (lo, hi) = domain.bounds();
    let mut p = BodyParams::new(
        "plate",
        Rectangle {
            origin: lo.to_array(),
            size: (hi - lo).to_array(),
        },
        [2, 2],
        Elastic::new(1000.0, 0.3),
    );
    p.polygon = Some(PolygonShape {
        domain,
        spacing: h,
        refine: Vec::new(),
    });
    p.bc = bc;
    p.self_weight = false;
    p
}

/// Griffith's crack at `beta` (degrees) with the exact displacement on the
/// outline of a square of side 4 (h = 0.2, h/4 within 0.2 of the crack),
/// growing with toughness `kic`.
fn griffith(beta: f64, kic: f64, increment: Option<f64>) -> (EfgBody, [f64; 2]) {
    let spec = GriffithSpec {
        s: 1.0,
        a: 1.0,
        beta,
    };
    let mut p = plate(
        square(2.0),
        0.2,
        vec![EdgeCondition {
            griffith: Some(spec),
            ..EdgeCondition::on("out")
        }],
    );
    p.penalty = Some(1e7 * p.elastic.e);
    let (s, c) = beta.to_radians().sin_cos();
    p.cracks.push(CrackShape {
        crack: Crack::new(vec![Vec2::new(-c, -s), Vec2::new(c, s)]),
        spacing: Some(0.05),
        width: 0.2,
        friction: 0.0,
        face_stiffness: None,
    });
    p.fracture = Some(Fracture {
        toughness: kic,
        increment,
        max_increments: 100,
        every: 1,
    });
    let el = p.elastic;
    let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    b.solve_static().unwrap();
    (b, spec.field(&el).k())
}

/// The first increment of a mixed-mode crack (Griffith's at 30°, 45°,
/// 60°) runs within 2° of the maximum hoop-stress direction of the exact
/// `K_I`, `K_II` (Erdogan & Sih 1963), at both tips (the directions the
/// criterion finds; at 45° the body grows and the new pieces are checked);
/// a crack below its toughness does not grow.
#[test]
fn first_increment_follows_the_maximum_hoop_stress() {
    for beta in [30.0, 45.0, 60.0] {
        let (mut b, k) = griffith(beta, 1e-3, None);
        let (theta, _) = max_hoop_stress(k);
        for s in b.tip_states().unwrap() {
            let err = (s.theta - theta).to_degrees();
            println!(
                "β = {beta}°: tip {} kinks by {:.3}° (exact K: {:.3}°), error {err:.3}°",
                s.tip.end,
                s.theta.to_degrees(),
                theta.to_degrees()
            );
            assert!(err.abs() < 2.0, "{err}");
        }
        if beta != 45.0 {
            continue;
        }
        let g = b.grow().unwrap();
        assert_eq!(g.len(), 2);
        for gr in &g {
            // the tips run out from the crack's centre, the origin
            let dir = gr.from * (1.0 / gr.from.norm());
            let step = gr.to - gr.from;
            let angle = dir.cross(step).atan2(dir.dot(step));
            assert!((angle - theta).to_degrees().abs() < 2.0, "{angle}");
            assert!((step.norm() - b.default_ring(gr.tip).outer).abs() < 1e-12);
        }
        assert_eq!(b.cracks()[0].crack.points.len(), 4);
        assert!(b.fracture_energy > 0.0);
    }
    let (mut b, k) = griffith(30.0, 1e3, None);
    assert!(max_hoop_stress(k).1 < 1e3);
    assert!(b.grow().unwrap().is_empty());
}

/// Carrying a body's state over to a body of the same cracks (the `L²`
/// projection onto the same shape functions) gives back its parameters.
#[test]
fn projection_onto_the_same_body_is_the_identity() {
    let (b, _) = griffith(30.0, 1.0, None);
    let mut c = EfgBody::new(&b.spec, [0.0, 0.0]).unwrap();
    c.take_state_of(&b).unwrap();
    let scale = b.state.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let err = b
        .state
        .u
        .iter()
        .zip(&c.state.u)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    println!("projection error {:.2e} of {scale:.2e}", err);
    assert!(err < 1e-8 * scale, "{err}");
}

/// An edge-cracked strip (width 1, height 2, crack from the left side at
/// mid-height to `a`) held at fixed grips: top and bottom sides moved
/// apart by ±δ (and held in x). Mode I by symmetry.
fn fixed_grips(a: f64) -> EfgBody {
    let d = Domain::new(
        [[0.0, -1.0], [1.0, -1.0], [1.0, 1.0], [0.0, 1.0]]
            .iter()
            .map(|&p| p.into())
            .collect(),
        vec![],
        vec![
            ("bottom".into(), vec![(0, 0)]),
            ("top".into(), vec![(0, 2)]),
        ],
    )
    .unwrap();
    let grip = |edge: &str, uy: f64| EdgeCondition {
        ux: Some(efgdem::continuum::Prescribed::Value(0.0)),
        uy: Some(efgdem::continuum::Prescribed::Value(uy)),
        ..EdgeCondition::on(edge)
    };
    let mut p = plate(d, 0.05, vec![grip("bottom", -1e-3), grip("top", 1e-3)]);
    p.elastic.plane = efgdem::continuum::Plane::Strain;
    p.penalty = Some(1e7 * p.elastic.e);
    p.cracks.push(CrackShape {
        crack: Crack::new(vec![Vec2::new(0.0, 0.0), Vec2::new(a, 0.0)]),
        spacing: Some(0.0125),
        width: 0.05,
        friction: 0.0,
        face_stiffness: None,
    });
    p.fracture = Some(Fracture {
        toughness: 1e-9,
        increment: None,
        max_increments: 1,
        every: 1,
    });
    let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    b.solve_static().unwrap();
    b
}

/// At fixed grips the energy a crack releases as it grows by Δa is the
/// drop of the stored energy, `Π(a) − Π(a + Δa) = ∫ G t da` (Griffith;
/// Irwin's `G = K_I²/E′`): the drop between the solutions before and after
/// one growth matches the trapezoidal `½ (G(a) + G(a + Δa)) Δa t` of the
/// interaction-integral `K_I` at both lengths, and the growth books that
/// drop as the fracture energy (its new piece opens as it is cut, the
/// body relaxing to the new equilibrium); the crack runs straight ahead
/// (mode I).
#[test]
fn growth_releases_the_energy_the_body_loses_at_fixed_grips() {
    let mut b = fixed_grips(0.4);
    let stored = |b: &EfgBody| b.strain_energy();
    let (pi0, s0) = (stored(&b), b.tip_states().unwrap()[0]);
    let g = b.grow().unwrap();
    assert_eq!(g.len(), 1);
    b.solve_static().unwrap();
    let (pi1, s1) = (stored(&b), b.tip_states().unwrap()[0]);
    let m = &b.material;
    let ep = m.e / (1.0 - m.nu * m.nu);
    let gr = |s: &efgdem::efg::growth::TipState| (s.k[0].powi(2) + s.k[1].powi(2)) / ep;
    let da = (g[0].to - g[0].from).norm();
    let t = m.thickness;
    let trapezoid = 0.5 * (gr(&s0) + gr(&s1)) * da * t;
    let drop = pi0 - pi1;
    println!(
        "Δa {da}: Π drop {drop:.6e}, trapezoid ∫G t da {trapezoid:.6e} ({:+.3} %), booked {:.6e}, G(a) {:.4e} → G(a+Δa) {:.4e}, kink {:.4}°",
        100.0 * (drop / trapezoid - 1.0),
        b.fracture_energy,
        gr(&s0),
        gr(&s1),
        g[0].theta.to_degrees()
    );
    assert!((drop / trapezoid - 1.0).abs() < 0.005);
    // the growth books what the body lost (its new piece opened under the
    // grips: the drop of its stored energy), not the estimate G(a) Δa t
    assert!((b.fracture_energy / trapezoid - 1.0).abs() < 0.005);
    assert!((b.fracture_energy / drop - 1.0).abs() < 1e-6);
    assert!(g[0].theta.to_degrees().abs() < 0.1);
    assert!((g[0].to.y).abs() < 1e-3 * da);
}

/// After a mixed-mode crack (Griffith's at 45°, `K_II = K_I`) has kinked
/// once along the maximum hoop-stress direction, its new tips are
/// (nearly) in pure mode I: the kinked crack runs on almost straight
/// (the principle of local symmetry, Goldstein & Salganik 1974; to first
/// order in the kink length the maximum hoop-stress kink has `K_II* = 0`,
/// Cotterell & Rice 1980).
#[test]
fn a_kinked_crack_runs_on_in_mode_one() {
    let (mut b, k) = griffith(45.0, 1e-3, None);
    let g = b.grow().unwrap();
    assert_eq!(g.len(), 2);
    b.solve_static().unwrap();
    for s in b.tip_states().unwrap() {
        println!(
            "before: K_II/K_I = {:.3}; after the kink: K_I {:.4} K_II {:.4} (K_II/K_I {:.4}), next kink {:.3}°",
            k[1] / k[0],
            s.k[0],
            s.k[1],
            s.k[1] / s.k[0],
            s.theta.to_degrees()
        );
        assert!((s.k[1] / s.k[0]).abs() < 0.02, "{:?}", s.k);
        assert!(s.theta.to_degrees().abs() < 2.0);
    }
}

/// The single-edge-cracked plate of `examples/cracked_plate.toml`, dynamic:
/// the traction arrives as a stress wave and the crack grows when the
/// tip's `K_eq` reaches the toughness, looked at every 5 steps.
const DYNAMIC_PLATE: &str = r#"
[simulation]
analysis = "dynamic"
dt = 2.0e-6
steps = 60

[[body]]
name = "plate"
rectangle = { origin = [0.0, 0.0], size = [0.1, 0.2] }
nodes = [11, 21]
elastic = { E = 30.0e9, nu = 0.2, density = 2400.0, thickness = 0.05, plane = "strain" }
self_weight = false

[[body.crack]]
points = [[0.0, 0.1], [0.03, 0.1]]
spacing = 0.0025

[body.fracture]
toughness = 1.0e6
max_increments = 3
every = 5

[[body.bc]]
edge = "bottom"
fixed = true

[[body.bc]]
edge = "top"
traction = [0.0, 3.0e6]
"#;

fn build(src: &str) -> efgdem::model::Model {
    efgdem::scenario::parse(src, "<crack>")
        .unwrap()
        .build()
        .unwrap()
}

fn efg(m: &efgdem::model::Model) -> &EfgBody {
    match m.body(0) {
        efgdem::model::body::BodyRef::Efg(b) => b,
        _ => unreachable!(),
    }
}

/// A dynamic run whose crack grows restarts bitwise from a checkpoint
/// taken after a growth (the body is rebuilt with the grown crack before
/// its state is restored), and runs bitwise the same on 1 and 2 threads.
#[test]
fn growing_crack_restarts_bitwise_on_any_thread_count() {
    use efgdem::model::ModelState;
    let (n, k) = (60, 33);
    let whole: Vec<(Vec<u8>, Vec<[usize; 2]>, usize)> = [1, 2]
        .into_iter()
        .map(|t| {
            common::on_threads(t, || {
                let mut a = build(DYNAMIC_PLATE);
                let mut first = 0;
                for s in 1..=n {
                    a.step().unwrap();
                    if first == 0 && efg(&a).generation() > 0 {
                        first = s;
                    }
                }
                (a.save_state().to_bytes(), efg(&a).increments.clone(), first)
            })
        })
        .collect();
    println!(
        "increments {:?}, first growth at step {}",
        whole[0].1, whole[0].2
    );
    assert!(whole[0].0 == whole[1].0, "1 and 2 threads agree");
    assert!(whole[0].2 > 0 && whole[0].2 < k, "a growth before the save");
    assert!(whole[0].1[0][1] > 1, "and growths after it");
    assert!(whole[0].1[0][1] >= 2, "{:?}", whole[0].1);
    let mut b = build(DYNAMIC_PLATE);
    for _ in 0..k {
        b.step().unwrap();
    }
    let bytes = b.save_state().to_bytes();
    let mut c = build(DYNAMIC_PLATE);
    c.restore_state(&ModelState::from_bytes(&bytes).unwrap())
        .unwrap();
    assert_eq!(efg(&c).cracks()[0].crack, efg(&b).cracks()[0].crack);
    for _ in k..n {
        c.step().unwrap();
    }
    assert!(
        c.save_state().to_bytes() == whole[0].0,
        "restart is bitwise"
    );
}
