//! Polygon EFG bodies (issue 15): patch tests on an L-shape and a holed
//! square, Kirsch's plate with a hole, Lamé's ring under internal
//! pressure, the visibility criterion.

use efgdem::continuum::{
    BodyParams, EdgeCondition, Elastic, KirschSpec, LinearField, PolygonShape, Prescribed,
    Rectangle,
};
use efgdem::efg::EfgBody;
use efgdem::geom::Vec2;
use efgdem::geom::polygon::{Domain, circle};

fn v(p: &[[f64; 2]]) -> Vec<Vec2> {
    p.iter().map(|&a| a.into()).collect()
}

/// All segments of loop `k` of `n` vertices.
fn whole(k: usize, n: usize) -> Vec<(usize, usize)> {
    (0..n).map(|i| (k, i)).collect()
}

fn params(domain: Domain, h: f64, gauss: usize, el: Elastic, bc: Vec<EdgeCondition>) -> BodyParams {
    let (lo, hi) = domain.bounds();
    let mut p = BodyParams::new(
        "poly",
        Rectangle {
            origin: lo.to_array(),
            size: (hi - lo).to_array(),
        },
        [2, 2],
        el,
    );
    p.polygon = Some(PolygonShape { domain, spacing: h });
    p.gauss = gauss;
    p.bc = bc;
    p.self_weight = false;
    // α = 1e8 E: the penalty's O(1/α) boundary error is 5e-4 of the
    // stress at the default 1e5 E (measured on the L-shape)
    p.penalty = Some(1e8 * p.elastic.e);
    p
}

const UX: [f64; 3] = [1e-3, 2e-3, 3e-3];
const UY: [f64; 3] = [-1e-3, 1e-3, -2e-3];

fn linear_bc(edge: &str) -> EdgeCondition {
    EdgeCondition {
        ux: Some(Prescribed::Linear(LinearField { linear: UX })),
        uy: Some(Prescribed::Linear(LinearField { linear: UY })),
        ..EdgeCondition::on(edge)
    }
}

/// Max relative displacement error at the nodes and stress error at the
/// domain Gauss points farther than `h` from the boundary.
fn patch_errors(b: &EfgBody, h: f64) -> (f64, f64) {
    let ex = [UX[1], UY[2], UX[2] + UY[1]];
    let se = b.material.stress(ex);
    let smax = se.iter().fold(0.0f64, |m, s| m.max(s.abs()));
    let mesh = b.mesh.as_ref().unwrap();
    let (mut eu, mut es) = (0.0f64, 0.0f64);
    for q in mesh.domain_points(1) {
        let s = b.sample(q.x).unwrap();
        let p = q.x;
        let u = [
            UX[0] + UX[1] * p.x + UX[2] * p.y,
            UY[0] + UY[1] * p.x + UY[2] * p.y,
        ];
        eu = eu.max((s.u.x - u[0]).abs().max((s.u.y - u[1]).abs()) / 1e-2);
        if mesh.domain.boundary_distance(p) > h {
            for k in 0..3 {
                let e = (s.stress[k] - se[k]).abs() / smax;
                es = es.max(e);
            }
        }
    }
    (eu, es)
}

fn l_shape(h: f64, gauss: usize) -> (f64, f64) {
    let outline = v(&[
        [0.0, 0.0],
        [2.0, 0.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 2.0],
        [0.0, 2.0],
    ]);
    let d = Domain::new(outline, vec![], vec![("outer".into(), whole(0, 6))]).unwrap();
    let p = params(
        d,
        h,
        gauss,
        Elastic::new(1000.0, 0.25),
        vec![linear_bc("outer")],
    );
    let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    b.solve_static().unwrap();
    let e = patch_errors(&b, h);
    println!(
        "L-shape patch, h = {h}, gauss = {gauss}: {} nodes, displacement error {:.2e}, interior stress error {:.2e}",
        b.n_nodes(),
        e.0,
        e.1
    );
    e
}

fn holed_square(h: f64, gauss: usize) -> (f64, f64) {
    let outline = v(&[[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]);
    let hole = circle(Vec2::new(0.1, 0.0), 0.4, 24);
    let d = Domain::new(
        outline,
        vec![hole],
        vec![("outer".into(), whole(0, 4)), ("hole".into(), whole(1, 24))],
    )
    .unwrap();
    let p = params(
        d,
        h,
        gauss,
        Elastic::new(1000.0, 0.25).plane_strain(),
        vec![linear_bc("outer"), linear_bc("hole")],
    );
    let mut b = EfgBody::new(&p, [0.0, 0.0]).unwrap();
    b.solve_static().unwrap();
    let e = patch_errors(&b, h);
    println!(
        "holed square patch, h = {h}, gauss = {gauss}: {} nodes, displacement error {:.2e}, interior stress error {:.2e}",
        b.n_nodes(),
        e.0,
        e.1
    );
    e
}

#[test]
fn patch_test_l_shape() {
    // gauss 5: each triangle split in 4, 28 points
    let (eu, es) = l_shape(0.2, 5);
    assert!(eu < 1e-4 && es < 1e-4, "{eu:.2e} {es:.2e}");
    let (eu, es) = l_shape(0.1, 6);
    assert!(eu < 1e-4 && es < 1e-4, "{eu:.2e} {es:.2e}");
}

#[test]
fn patch_test_holed_square() {
    let (eu, es) = holed_square(0.2, 6);
    assert!(eu < 1e-4 && es < 1e-4, "{eu:.2e} {es:.2e}");
}

#[test]
fn visibility_hides_across_a_slot() {
    use efgdem::efg::support::Support;
    let outline = v(&[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]);
    let slot = v(&[[1.0, 1.95], [3.0, 1.95], [3.0, 2.05], [1.0, 2.05]]);
    let d = Domain::new(outline, vec![slot], vec![]).unwrap();
    let nodes = vec![
        [2.0, 1.8, 0.5, 0.5],
        [2.0, 2.2, 0.5, 0.5],
        [2.3, 1.8, 0.5, 0.5],
    ];
    let (below, above) = (Vec2::new(2.0, 1.85), Vec2::new(2.0, 2.15));
    let plain = Support::new(nodes.clone());
    assert!(plain.covers(0, above) && plain.covers(1, below));
    for diffraction in [false, true] {
        let s = Support::new(nodes.clone()).with_visibility(&d, diffraction);
        assert!(!s.covers(0, above), "node 0 sees across the slot");
        assert!(!s.covers(1, below), "node 1 sees across the slot");
        assert!(s.covers(0, below) && s.covers(2, below) && s.covers(1, above));
    }
    // around the slot's end the diffraction weight bends the distance:
    // node (0.9, 1.9) and the point (1.1, 2.1) see each other only around (1, 2.05)
    let n = vec![[0.8, 1.9, 0.5, 0.5]];
    let p = Vec2::new(1.1, 2.1);
    let vis = Support::new(n.clone()).with_visibility(&d, false);
    let dif = Support::new(n).with_visibility(&d, true);
    assert!(vis.hidden(0, p) && !vis.covers(0, p));
    let (f, _) = dif.diffraction(0, p).unwrap();
    let c = Vec2::new(1.0, 2.05);
    let bent = (c - Vec2::new(0.8, 1.9)).norm() + (p - c).norm();
    assert!(
        (f - bent / (p - Vec2::new(0.8, 1.9)).norm()).abs() < 1e-12,
        "{f}"
    );
    assert!(dif.covers(0, p));
}
