//! The bilinear FE body coupled with discs (issue 5): contact boundary,
//! implicit contact step, moving edges imposed exactly on the nodes. (A
//! disc resting on an FE cantilever: `tests/coupling_beam.rs`; the
//! nine-disc test with an FE plate from the CLI: `tests/fem_cli.rs`.)
#![allow(clippy::needless_range_loop)]

use efgdem::Vec2;
use efgdem::continuum::Continuum;
use efgdem::fem::{FemBody, FemContinuum};
use efgdem::scenario::{self, body::Edge};

fn fem(src: &str) -> FemBody {
    let sc = scenario::parse(src, "test.toml").unwrap_or_else(|e| panic!("{e}"));
    FemBody::new(&sc.body[0].params(), sc.simulation.gravity).unwrap()
}

/// A 2 × 1 plate, 5 × 3 nodes, clamped on the left; the bottom edge slides
/// to the right (`ux` moving, `uy` fixed).
fn plate(newmark: &str, damping: f64, mass: &str) -> String {
    format!(
        r#"
[simulation]
gravity = [0.0, -9.81]
dt = 0.01
steps = 1
[[body]]
name = "plate"
method = "fem-q4"
mass = "{mass}"
rectangle = {{ origin = [0.0, 0.0], size = [2.0, 1.0] }}
nodes = [5, 3]
elastic = {{ E = 1000.0, nu = 0.3, density = 2.0 }}
damping = {damping}
newmark = {newmark}
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
edge = "bottom"
ux = {{ velocity = 0.3, until_step = 6 }}
uy = 0.0
[[body.bc]]
edge = "right"
traction = [0.5, -2.0]
"#
    )
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// (a) The chain passes through `X + Σ N_a(X) u_a` (nodal values at the
/// nodes, bilinear in between), before and after a step; the point load
/// and the boundary velocity use the same shape functions: power
/// `Fᵀ U̇ = f · v_H`.
#[test]
fn chain_follows_the_displacement_and_point_loads_are_work_consistent() {
    let mut c = FemContinuum::new(
        fem(&plate("{ gamma = 0.5, beta = 0.25 }", 0.0, "consistent")),
        &[Edge::Top, Edge::Right],
        3,
    )
    .unwrap();
    assert_eq!(c.contact_boundary().len(), 1);
    assert_eq!(c.contact_boundary()[0].segments(), 3 * (2 + 4));
    // an arbitrary (non-polynomial) nodal field
    let n = c.body.n_nodes();
    for i in 0..n {
        let x = c.body.node(i);
        c.body.state.u[2 * i] = 1e-2 * (3.0 * x.x + x.y).sin();
        c.body.state.u[2 * i + 1] = 1e-2 * (x.x * x.y).cos();
        c.body.state.v[2 * i] = (1.7 * x.x - x.y).cos();
        c.body.state.v[2 * i + 1] = (x.x + 2.0 * x.y).sin();
    }
    c.refresh();
    let check_chain = |c: &FemContinuum| {
        let ch = &c.contact_boundary()[0];
        for (k, (x, cur)) in ch.reference.iter().zip(&ch.current).enumerate() {
            let u = c.body.sample(*x).unwrap().u;
            assert!((*cur - (*x + u)).norm() < 1e-15, "point {k}");
            if k % 3 == 0 {
                // a node: its nodal value (Kronecker delta)
                let i = (0..n)
                    .find(|&i| (c.body.node(i) - *x).norm() < 1e-12)
                    .unwrap();
                let ui = Vec2::new(c.body.state.u[2 * i], c.body.state.u[2 * i + 1]);
                assert!((*cur - (*x + ui)).norm() < 1e-15);
            }
        }
    };
    check_chain(&c);
    for (p, f) in [
        (Vec2::new(2.0, 0.37), Vec2::new(3.0, -2.0)),
        (Vec2::new(0.8, 1.0), Vec2::new(-1.5, 4.0)),
        (Vec2::new(2.0, 1.0), Vec2::new(0.5, 0.25)),
    ] {
        let v = c.boundary_velocity(0, p);
        assert!((v - c.body.sample(p).unwrap().v).norm() < 1e-15);
        c.body.f_point.iter_mut().for_each(|x| *x = 0.0);
        c.add_point_load(0, p, f);
        let power: f64 = c
            .body
            .f_point
            .iter()
            .zip(&c.body.state.v)
            .map(|(a, b)| a * b)
            .sum();
        assert!(
            (power - f.dot(v)).abs() < 1e-12 * f.norm() * v.norm(),
            "{power} vs {}",
            f.dot(v)
        );
        assert!((c.body.f_point.iter().step_by(2).sum::<f64>() - f.x).abs() < 1e-14);
    }
    // after real steps (moving bottom edge, traction, gravity, a point load)
    c.body.state = efgdem::continuum::newmark::State::zeros(2 * n);
    c.body.f_point.iter_mut().for_each(|x| *x = 0.0);
    c.body.start_dynamic(0.01).unwrap();
    for _ in 0..5 {
        c.add_point_load(0, Vec2::new(1.3, 1.0), Vec2::new(0.0, -1.0));
        c.advance().unwrap();
    }
    check_chain(&c);
    assert!(c.contact_boundary()[0].current[0].x > 2.0);
}

/// (b) The implicit step — `begin_step` (free displacements, compliance
/// `S = N A⁻¹ Nᵀ`) then `finish_step` with point forces — is the plain
/// step with those forces as point loads, to round-off; including a point
/// on a node whose `ux` is prescribed (moving) and `uy` fixed.
#[test]
fn implicit_step_equals_a_step_with_point_loads() {
    for (newmark, damping, mass) in [
        ("{ gamma = 0.5, beta = 0.25 }", 0.0, "consistent"),
        ("{ gamma = 0.6, beta = 0.3025 }", 3.0, "consistent"),
        ("{ gamma = 1.5, beta = 0.8 }", 0.0, "lumped"),
    ] {
        let src = plate(newmark, damping, mass);
        let make = || {
            let mut b = fem(&src);
            b.start_dynamic(0.01).unwrap();
            let mut c = FemContinuum::new(b, &[Edge::Bottom, Edge::Right, Edge::Top], 2).unwrap();
            for _ in 0..3 {
                c.add_point_load(0, Vec2::new(2.0, 0.5), Vec2::new(-1.0, 0.5));
                c.advance().unwrap();
            }
            c
        };
        let (mut a, mut b) = (make(), make());
        let points = [
            (0, Vec2::new(2.0, 0.3)),
            (0, Vec2::new(1.25, 1.0)),
            (0, Vec2::new(0.5, 0.0)), // a node of the moving bottom edge
            (0, Vec2::new(1.1, 0.0)),
        ];
        let forces = [
            Vec2::new(-3.0, 1.0),
            Vec2::new(0.5, -2.0),
            Vec2::new(7.0, -5.0),
            Vec2::new(-1.0, 4.0),
        ];
        let (mut free, mut s) = (Vec::new(), Vec::new());
        a.begin_step(&points, &[], &mut Vec::new(), &mut free)
            .unwrap();
        a.compliance().dense(&mut s);
        let m2 = 2 * points.len();
        // S symmetric; no response at the prescribed DOFs of the edge node
        for i in 0..m2 {
            for j in 0..m2 {
                assert!((s[i * m2 + j] - s[j * m2 + i]).abs() < 1e-12 * s[0].abs());
            }
        }
        for j in 0..m2 {
            assert_eq!(s[4 * m2 + j], 0.0);
            assert_eq!(s[5 * m2 + j], 0.0);
        }
        a.finish_step(&forces).unwrap();
        for (&(c, x), f) in points.iter().zip(forces) {
            b.add_point_load(c, x, f);
        }
        b.advance().unwrap();
        let (sa, sb) = (&a.body.state, &b.body.state);
        for (name, x, y) in [
            ("u", &sa.u, &sb.u),
            ("v", &sa.v, &sb.v),
            ("a", &sa.a, &sb.a),
        ] {
            let d: Vec<f64> = x.iter().zip(y.iter()).map(|(p, q)| p - q).collect();
            let rel = max_abs(&d) / max_abs(y);
            assert!(rel < 1e-12, "{newmark}: {name} differs by {rel:e}");
        }
        // the free displacements plus S f are the displacements reached
        for k in 0..points.len() {
            let mut u = free[k];
            for j in 0..points.len() {
                u.x +=
                    s[2 * k * m2 + 2 * j] * forces[j].x + s[2 * k * m2 + 2 * j + 1] * forces[j].y;
                u.y += s[(2 * k + 1) * m2 + 2 * j] * forces[j].x
                    + s[(2 * k + 1) * m2 + 2 * j + 1] * forces[j].y;
            }
            let got = a.boundary_displacement(0, points[k].1);
            assert!(
                (u - got).norm() < 1e-12 * got.norm(),
                "{k}: {u:?} vs {got:?}"
            );
        }
        // the edge node is where the motion puts it: 0.3 × 4 steps × 0.01
        assert_eq!(a.boundary_displacement(0, points[2].1).x, 0.3 * 4.0 * 0.01);
        assert_eq!(a.boundary_displacement(0, points[2].1).y, 0.0);
    }
}

/// A bar `[0, L] × [0, H]` (ν = 0, `nx × 2` nodes), clamped at x = 0, the
/// end x = L moved at `velocity` for `until` steps, `uy = 0` on the bottom.
fn bar(nx: usize, newmark: &str, damping: f64, velocity: f64, until: usize) -> FemBody {
    fem(&format!(
        r#"
[simulation]
dt = 0.01
steps = 1
[[body]]
name = "bar"
method = "fem-q4"
rectangle = {{ origin = [0.0, 0.0], size = [10.0, 1.0] }}
nodes = [{nx}, 2]
elastic = {{ E = 1000.0, nu = 0.0, density = 1.0, thickness = 0.5 }}
damping = {damping}
newmark = {newmark}
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
edge = "bottom"
uy = 0.0
[[body.bc]]
edge = "right"
ux = {{ velocity = {velocity}, until_step = {until} }}
"#
    ))
}

/// Dense `a x = b` by Gaussian elimination with partial pivoting.
fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            for k in c..n {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// The same bar as an independent 1D computation: linear elements, EA and
/// consistent mass ρA of the full section, mass-proportional damping,
/// Newmark on the unreduced system with the two end displacements imposed
/// by Lagrange multipliers. Returns `(u, v)` after every step.
#[allow(clippy::too_many_arguments)]
fn bar_1d(
    nx: usize,
    gamma: f64,
    beta: f64,
    damping: f64,
    velocity: f64,
    until: usize,
    dt: f64,
    steps: usize,
) -> Vec<(Vec<f64>, Vec<f64>)> {
    let (e, rho, area, l) = (1000.0, 1.0, 0.5, 10.0);
    let h = l / (nx - 1) as f64;
    let mut k = vec![vec![0.0; nx]; nx];
    let mut m = vec![vec![0.0; nx]; nx];
    for el in 0..nx - 1 {
        for (a, b, kk, mm) in [
            (0, 0, 1.0, 2.0),
            (0, 1, -1.0, 1.0),
            (1, 0, -1.0, 1.0),
            (1, 1, 1.0, 2.0),
        ] {
            k[el + a][el + b] += e * area / h * kk;
            m[el + a][el + b] += rho * area * h / 6.0 * mm;
        }
    }
    let cm = damping / rho; // C = (c/ρ) M
    let a1 = 1.0 / (beta * dt * dt);
    let a2 = 1.0 / (beta * dt);
    let a3 = 1.0 / (2.0 * beta) - 1.0;
    let a4 = gamma / (beta * dt);
    let a5 = gamma / beta - 1.0;
    let a6 = dt * (gamma / (2.0 * beta) - 1.0);
    let (mut u, mut v, mut acc) = (vec![0.0; nx], vec![0.0; nx], vec![0.0; nx]);
    let mut out = Vec::new();
    for step in 1..=steps {
        let n = nx + 2;
        let mut aa = vec![vec![0.0; n]; n];
        let mut b = vec![0.0; n];
        for i in 0..nx {
            for j in 0..nx {
                aa[i][j] = k[i][j] + (a1 + a4 * cm) * m[i][j];
                b[i] += m[i][j]
                    * (a1 * u[j]
                        + a2 * v[j]
                        + a3 * acc[j]
                        + cm * (a4 * u[j] + a5 * v[j] + a6 * acc[j]));
            }
        }
        // constraints u_0 = 0, u_{n-1} = v·min(step, until)·dt
        for (r, node, val) in [
            (nx, 0, 0.0),
            (nx + 1, nx - 1, velocity * step.min(until) as f64 * dt),
        ] {
            aa[r][node] = 1.0;
            aa[node][r] = 1.0;
            b[r] = val;
        }
        let x = dense_solve(aa, b);
        for i in 0..nx {
            let a_new = a1 * (x[i] - u[i]) - a2 * v[i] - a3 * acc[i];
            v[i] += dt * ((1.0 - gamma) * acc[i] + gamma * a_new);
            acc[i] = a_new;
            u[i] = x[i];
        }
        out.push((u.clone(), v.clone()));
    }
    out
}

/// (d) A moving edge imposed exactly on the nodes: the FE bar whose end
/// moves at constant velocity, then stops, is the unreduced Newmark system
/// with the end displacement imposed by a Lagrange multiplier (1D, dense)
/// to round-off, at every step, displacements and velocities (the end
/// node's velocity included: Newmark's, 2v, 0, 2v, … for γ = ½).
#[test]
fn moving_edge_matches_an_independent_1d_computation() {
    let (nx, dt, steps, vel, until) = (11, 0.01, 120, 0.02, 40);
    for (gamma, beta, damping) in [(0.5, 0.25, 0.0), (0.6, 0.3025, 2.0), (1.5, 0.8, 0.0)] {
        let mut b = bar(
            nx,
            &format!("{{ gamma = {gamma}, beta = {beta} }}"),
            damping,
            vel,
            until,
        );
        b.start_dynamic(dt).unwrap();
        let reference = bar_1d(nx, gamma, beta, damping, vel, until, dt, steps);
        let scale = vel * until as f64 * dt;
        let mut worst = (0.0f64, 0.0f64);
        for (step, (u1, v1)) in reference.iter().enumerate() {
            b.advance().unwrap();
            for i in 0..nx {
                for j in 0..2 {
                    let node = j * nx + i;
                    worst.0 = worst.0.max((b.state.u[2 * node] - u1[i]).abs() / scale);
                    worst.1 = worst.1.max((b.state.v[2 * node] - v1[i]).abs() / vel);
                    assert!(
                        b.state.u[2 * node + 1].abs() < 1e-13 * scale,
                        "uy {}",
                        b.state.u[2 * node + 1]
                    );
                }
            }
            let end = vel * (step + 1).min(until) as f64 * dt;
            assert_eq!(
                b.state.u[2 * (nx - 1)],
                end,
                "the end is exactly where it is moved"
            );
        }
        eprintln!(
            "moving edge γ = {gamma}, β = {beta}, c = {damping}: FE vs 1D: u {:.1e}, v {:.1e}",
            worst.0, worst.1
        );
        assert!(worst.0 < 1e-12 && worst.1 < 1e-10, "{worst:?}");
    }
}

/// (d) After the end stops (damped bar), the bar comes to rest in the
/// quasi-static state: the linear field `u = d x / L`.
#[test]
fn moving_edge_settles_to_the_linear_static_field() {
    let (dt, vel, until) = (0.01, 0.02, 50);
    let mut b = bar(21, "{ gamma = 0.5, beta = 0.25 }", 5.0, vel, until);
    b.start_dynamic(dt).unwrap();
    for _ in 0..3000 {
        b.advance().unwrap();
    }
    let d = vel * until as f64 * dt;
    let mut err = 0.0f64;
    for i in 0..b.n_nodes() {
        let x = b.node(i);
        err = err.max((b.state.u[2 * i] - d * x.x / 10.0).abs() / d);
        assert!(
            b.state.u[2 * i + 1].abs() < 1e-13 * d,
            "uy {}",
            b.state.u[2 * i + 1]
        );
    }
    eprintln!("bar at rest after the end moved by {d}: max |u − d x/L| / d = {err:.1e}");
    assert!(err < 1e-9, "{err:e}");
    assert!(max_abs(&b.state.v) < 1e-9 * vel);
}

/// The energy account of a moving edge: with γ = ½, β = ¼ and no damping,
/// kinetic + strain energy = work of the loads and of the moving support
/// (trapezoidal reactions), to round-off, every step (2D plate, ν = 0.3,
/// consistent mass, gravity and traction).
#[test]
fn moving_edge_work_balances_the_energy() {
    let mut b = fem(&plate("{ gamma = 0.5, beta = 0.25 }", 0.0, "consistent"));
    b.start_dynamic(0.01).unwrap();
    let mut worst = 0.0f64;
    let mut w_max = 0.0f64;
    for _ in 0..60 {
        b.advance().unwrap();
        let e = b.kinetic_energy() + b.strain_energy();
        w_max = w_max.max(b.work().abs());
        worst = worst.max((e - b.work()).abs());
    }
    eprintln!(
        "moving edge energy balance: |E − W| ≤ {:.1e} of max |W| = {w_max:.3e}",
        worst / w_max
    );
    assert!(worst < 1e-11 * w_max, "{worst:e} vs {w_max:e}");
}
