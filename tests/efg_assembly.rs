//! Assembly properties: bitwise independence of the thread count, symmetry
//! and rigid-body modes of K, mass conservation of M, and the coupling
//! helpers (point loads are work-consistent with the sampled velocity, E7).

use efgdem::Vec2;
use efgdem::efg::{EfgBody, ShapeRow};
use efgdem::scenario;

#[allow(dead_code)]
mod common;

const SRC: &str = r#"
[simulation]
analysis = "dynamic"
dt = 0.01
steps = 1
gravity = [0.0, -9.81]
[[body]]
name = "b"
rectangle = { origin = [0.5, -1.0], size = [3.0, 2.0] }
nodes = [16, 11]
elastic = { E = 1000.0, nu = 0.3, density = 2.0, thickness = 0.5 }
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
edge = "top"
traction = [1.0, 0.0]
"#;

fn build(threads: usize) -> EfgBody {
    let sc = scenario::parse(SRC, "t.toml").unwrap();
    common::on_threads(threads, || {
        EfgBody::new(&sc.body[0].params(), sc.simulation.gravity).unwrap()
    })
}

#[test]
fn assembly_is_bitwise_independent_of_thread_count() {
    let a = build(1);
    let b = build(2);
    let c = build(3);
    for o in [&b, &c] {
        assert_eq!(a.ops.k.pattern, o.ops.k.pattern);
        let bits =
            |m: &efgdem::sparse::SymCsc| m.values.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.ops.k), bits(&o.ops.k));
        assert_eq!(bits(&a.ops.kbar()), bits(&o.ops.kbar()));
        assert!(
            a.ops
                .gram
                .values
                .iter()
                .zip(&o.ops.gram.values)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        assert!(
            a.f_permanent
                .iter()
                .zip(&o.f_permanent)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
    }
}

#[test]
fn mass_and_rigid_modes() {
    let b = build(2);
    let n = b.n_dofs();
    // total mass: 1ᵀ M 1 over the x DOFs = ρ t area
    let ones_x: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { 1.0 } else { 0.0 }).collect();
    let m = 2.0 * b.ops.gram.quad_form(&ones_x);
    assert!((m - 2.0 * 0.5 * 6.0).abs() < 1e-10 * m, "{m}");
    // a rigid y-translation costs no energy when only ux is prescribed
    let src = SRC.replace("fixed = true", "ux = 0.0");
    let sc = scenario::parse(&src, "t.toml").unwrap();
    let free = EfgBody::new(&sc.body[0].params(), [0.0, 0.0]).unwrap();
    let ty: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 1 { 1e-3 } else { 0.0 })
        .collect();
    assert!(free.ops.kbar().quad_form(&ty).abs() < 1e-9);
    // symmetric storage: K̄ entries are read symmetric
    let kbar = b.ops.kbar();
    assert_eq!(kbar.get(3, 10), kbar.get(10, 3));
    // body force: Σ F_y = ρ g t A (+ the traction has no y part)
    let fy: f64 = b.f_permanent.iter().skip(1).step_by(2).sum();
    let fx: f64 = b.f_permanent.iter().step_by(2).sum();
    assert!((fy + 2.0 * 9.81 * 0.5 * 6.0).abs() < 1e-9, "{fy}");
    assert!((fx - 1.0 * 0.5 * 3.0).abs() < 1e-9, "{fx}");
}

#[test]
fn point_load_is_work_consistent_with_sampled_velocity() {
    let mut b = build(2);
    b.start_dynamic(0.01).unwrap();
    for _ in 0..3 {
        b.advance().unwrap();
    }
    let x = Vec2::new(3.5, 0.3);
    let f = Vec2::new(0.7, -1.3);
    let mut row = ShapeRow::new();
    b.shape_row(x, &mut row).unwrap();
    b.add_point_load_row(&row, f);
    let v = b.sample_row(&row).v;
    let power_point = v.dot(f);
    let power_nodal: f64 = b.f_point.iter().zip(&b.state.v).map(|(a, c)| a * c).sum();
    assert!((power_point - power_nodal).abs() < 1e-12 * power_point.abs().max(1e-30));
    // resultant preserved (partition of unity)
    let sx: f64 = b.f_point.iter().step_by(2).sum();
    assert!((sx - f.x).abs() < 1e-12);
    // cleared by the next step
    b.advance().unwrap();
    assert!(b.f_point.iter().all(|&v| v == 0.0));
}
