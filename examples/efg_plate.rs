//! Timing and memory of the large EFG case: a square plate of N × N nodes
//! (default 201 × 201 = 80 802 DOFs, 4 × 4 Gauss points per cell), clamped
//! on the left, loaded on the right. Prints the time of each phase.
//!
//!     cargo run --release --example efg_plate -- 201 10
//!     /usr/bin/time -v target/release/examples/efg_plate 201 10   # peak memory

use efgdem::Vec2;
use efgdem::efg::EfgBody;
use efgdem::scenario;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(201);
    let steps: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let src = format!(
        r#"
[simulation]
analysis = "dynamic"
dt = 1e-4
steps = {steps}
[[body]]
name = "plate"
rectangle = {{ origin = [0.0, 0.0], size = [1.0, 1.0] }}
nodes = [{n}, {n}]
gauss = 4
elastic = {{ E = 2.0e11, nu = 0.3, density = 7800.0, plane = "strain" }}
damping = 10.0
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
edge = "right"
traction = [0.0, -1.0e6]
"#
    );
    let sc = scenario::parse(&src, "plate.toml").expect("valid scenario");
    println!("threads: {}", rayon::current_num_threads());
    let t = Instant::now();
    let mut b = EfgBody::new(&sc.body[0].params(), sc.simulation.gravity).expect("build");
    println!(
        "build: {:.3} s (shape functions {:.3} s, assembly K̄ + M {:.3} s); {} DOFs, {} Gauss points, nnz(lower K̄) = {}",
        t.elapsed().as_secs_f64(),
        b.info.shape_seconds,
        b.info.assembly_seconds,
        b.n_dofs(),
        b.info.domain_points + b.info.boundary_points,
        b.info.nnz
    );
    let t = Instant::now();
    b.start_dynamic(1e-4).expect("factor");
    println!(
        "Newmark setup (factor M for Ü₀, then α₁M + α₄C + K̄): {:.3} s; nnz(L) = {}",
        t.elapsed().as_secs_f64(),
        b.newmark().map_or(0, |nm| nm.factor_nnz())
    );
    let t = Instant::now();
    for _ in 0..steps {
        b.advance().expect("step");
    }
    println!(
        "{steps} Newmark steps: {:.2} ms per step",
        1e3 * t.elapsed().as_secs_f64() / steps as f64
    );
    println!(
        "tip u_y = {:e}",
        b.sample(Vec2::new(1.0, 0.5)).expect("sample").u.y
    );
}
