//! The bilinear FE body alone: patch test (exact) and Timoshenko cantilever
//! convergence (issue 5, validation 1).
#![allow(clippy::needless_range_loop)]

use efgdem::Vec2;
use efgdem::fem::{FemBody, q4};
use efgdem::scenario;

fn body(toml: &str) -> FemBody {
    let sc = scenario::parse(toml, "test.toml").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sc.body[0].method, scenario::body::Method::FemQ4);
    FemBody::new(&sc.body[0].params(), sc.simulation.gravity).unwrap()
}

const LIN: &str = r#"ux = { linear = [1e-3, 2e-3, 3e-3] }
uy = { linear = [-1e-3, 1e-3, -2e-3] }"#;

/// Patch test: the linear field imposed on all four edges; returns the worst
/// relative error (displacement, stress) at 11 × 11 points, boundary included.
fn patch(nodes: [usize; 2], plane: &str, mass: &str) -> (f64, f64) {
    let bcs: String = ["left", "right", "top", "bottom"]
        .iter()
        .map(|e| format!("[[body.bc]]\nedge = \"{e}\"\n{LIN}\n"))
        .collect();
    let src = format!(
        r#"
[simulation]
analysis = "static"
[[body]]
name = "patch"
method = "fem-q4"
mass = "{mass}"
rectangle = {{ origin = [-1.0, 0.5], size = [2.0, 1.5] }}
nodes = {nodes:?}
elastic = {{ E = 1000.0, nu = 0.25, plane = "{plane}", density = 1.0 }}
{bcs}"#
    );
    let mut b = body(&src);
    b.solve_static().unwrap();
    let se = b.material.stress([2e-3, -2e-3, 4e-3]);
    let smax = se.iter().fold(0.0f64, |m, s| m.max(s.abs()));
    let (mut eu, mut es) = (0.0f64, 0.0f64);
    for j in 0..=10 {
        for i in 0..=10 {
            let p = Vec2::new(-1.0 + 0.2 * i as f64, 0.5 + 0.15 * j as f64);
            let s = b.sample(p).unwrap();
            let u = [
                1e-3 * (1.0 + 2.0 * p.x + 3.0 * p.y),
                1e-3 * (-1.0 + p.x - 2.0 * p.y),
            ];
            eu = eu.max((s.u.x - u[0]).abs().max((s.u.y - u[1]).abs()) / 1e-2);
            for k in 0..3 {
                es = es.max((s.stress[k] - se[k]).abs() / smax);
            }
        }
    }
    println!(
        "FE patch test {nodes:?} plane {plane}, {mass} mass: displacement {eu:.2e}, stress {es:.2e}"
    );
    (eu, es)
}

#[test]
fn patch_test_is_exact() {
    for (nodes, plane, mass) in [
        ([9, 7], "stress", "consistent"),
        ([5, 4], "strain", "lumped"),
        ([2, 2], "stress", "consistent"),
    ] {
        let (eu, es) = patch(nodes, plane, mass);
        assert!(eu < 1e-10 && es < 1e-10, "{eu:e} {es:e}");
    }
}

/// Element-level patch test on a distorted quadrilateral: the nodal values of
/// a linear field give the exact constant strain at every Gauss point, and
/// `K_e u` equals the consistent nodal forces of the constant stress
/// (boundary integral of σ·n with the linear edge functions).
#[test]
fn distorted_element_reproduces_linear_field() {
    let xy = [[0.0, 0.0], [2.0, 0.3], [2.4, 1.7], [-0.2, 1.2]];
    let (e_, nu) = (1000.0, 0.25);
    let c = e_ / (1.0 - nu * nu);
    let d = [
        [c, c * nu, 0.0],
        [c * nu, c, 0.0],
        [0.0, 0.0, c * (1.0 - nu) / 2.0],
    ];
    let field = |p: [f64; 2]| {
        [
            1e-3 * (1.0 + 2.0 * p[0] + 3.0 * p[1]),
            1e-3 * (-1.0 + p[0] - 2.0 * p[1]),
        ]
    };
    let strain = [2e-3, -2e-3, 4e-3];
    let mut u = [0.0; 8];
    for a in 0..4 {
        let f = field(xy[a]);
        u[2 * a] = f[0];
        u[2 * a + 1] = f[1];
    }
    let mut worst = 0.0f64;
    for &(xi, eta) in &[(-0.5, 0.3), (0.9, -0.9), (0.0, 0.0), (0.7, 0.2)] {
        let (g, _) = q4::gradients(&xy, xi, eta);
        let mut e = [0.0; 3];
        for a in 0..4 {
            e[0] += g[a][0] * u[2 * a];
            e[1] += g[a][1] * u[2 * a + 1];
            e[2] += g[a][1] * u[2 * a] + g[a][0] * u[2 * a + 1];
        }
        for k in 0..3 {
            worst = worst.max((e[k] - strain[k]).abs() / 4e-3);
        }
    }
    // K_e u = ∮ Nᵀ σ·n ds: for a constant σ each edge a→b gives half of
    // σ·n·|ab| to each of its two nodes.
    let t = 0.7;
    let k = q4::stiffness(&xy, &d, t);
    let s = [
        d[0][0] * strain[0] + d[0][1] * strain[1],
        d[1][0] * strain[0] + d[1][1] * strain[1],
        d[2][2] * strain[2],
    ];
    let mut f_ex = [0.0; 8];
    for a in 0..4 {
        let b = (a + 1) % 4;
        // outward normal × length of a counter-clockwise edge: (dy, −dx)
        let (dx, dy) = (xy[b][0] - xy[a][0], xy[b][1] - xy[a][1]);
        let tr = [s[0] * dy - s[2] * dx, s[2] * dy - s[1] * dx];
        for n in [a, b] {
            f_ex[2 * n] += 0.5 * t * tr[0];
            f_ex[2 * n + 1] += 0.5 * t * tr[1];
        }
    }
    let fmax = f_ex.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for r in 0..8 {
        let f: f64 = (0..8).map(|c| k[r][c] * u[c]).sum();
        worst = worst.max((f - f_ex[r]).abs() / fmax);
    }
    println!("distorted element patch test: {worst:.2e}");
    assert!(worst < 1e-10, "{worst:e}");
}

fn timoshenko(nodes: [usize; 2]) -> (f64, f64, f64) {
    let src = format!(
        r#"
[simulation]
analysis = "static"
[[body]]
name = "beam"
method = "fem-q4"
rectangle = {{ origin = [0.0, -6.0], size = [48.0, 12.0] }}
nodes = {nodes:?}
elastic = {{ E = 3.0e7, nu = 0.3, thickness = 1.0, plane = "stress" }}
[[body.bc]]
edge = "left"
timoshenko = {{ P = -1000.0 }}
[[body.bc]]
edge = "right"
parabolic_shear = -1000.0
"#
    );
    let mut b = body(&src);
    b.solve_static().unwrap();
    let t = b.timoshenko.unwrap();
    let tip = b.sample(Vec2::new(48.0, 0.0)).unwrap().u.y;
    let exact = t.tip_deflection();
    let err = b
        .energy_error(|p| t.stress(p), [2 * (nodes[0] - 1), 2 * (nodes[1] - 1)], 3)
        .unwrap();
    (tip, (tip - exact) / exact, err)
}

/// Tip deflection error < 1 % at 64 × 16 elements, monotone convergence
/// from below (Q4 is too stiff in bending), energy error O(h).
#[test]
fn timoshenko_cantilever_converges() {
    let mut prev = f64::INFINITY;
    println!("elements | tip u_y | rel. error | energy-norm error");
    for k in [1usize, 2, 4, 8] {
        let nodes = [8 * k + 1, 2 * k + 1];
        let (tip, e, en) = timoshenko(nodes);
        println!(
            "{:>3} × {:<3} | {tip:.6e} | {e:+.3e} | {en:.3e}",
            nodes[0] - 1,
            nodes[1] - 1
        );
        assert!(e < 0.0 && e.abs() < prev, "error must decrease: {e}");
        prev = e.abs();
        if k == 8 {
            assert!(e.abs() < 0.01, "64 × 16 elements: {e}");
        }
    }
}
