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
