//! The 201 × 201-node plate (80 802 DOFs, 4 × 4 Gauss points per cell):
//! shape functions + assembly of K̄ and M, sparse Cholesky of the Newmark
//! matrix, one Newmark step (RHS + solve) on 1 and 2 threads. Small sample sizes:
//! `cargo bench --bench efg_plate` takes about two minutes on 2 cores.

use criterion::{Criterion, criterion_group, criterion_main};
use efgdem::Vec2;
use efgdem::continuum::material::elasticity;
use efgdem::continuum::newmark::{Newmark, NewmarkParams, State};
use efgdem::continuum::quadrature::{domain_points, edge_points};
use efgdem::efg::assemble::{PointRole, assemble, point_shapes};
use efgdem::efg::support::Support;
use efgdem::sparse::Cholesky;
use std::hint::black_box;

const N: usize = 201;

fn bench(c: &mut Criterion) {
    let xs: Vec<f64> = (0..N).map(|i| i as f64 / (N - 1) as f64).collect();
    let s = Support::for_grid(&xs, &xs, 2.0);
    let dom = domain_points(Vec2::ZERO, Vec2::new(1.0, 1.0), [N - 1, N - 1], 4);
    let edge = edge_points(Vec2::ZERO, Vec2::new(0.0, 1.0), N - 1, 4);
    let mut pts: Vec<Vec2> = dom.iter().map(|q| q.x).collect();
    pts.extend(edge.iter().map(|q| q.x));
    let mut roles: Vec<PointRole> = dom.iter().map(|q| PointRole::Domain(q.w)).collect();
    roles.extend(
        edge.iter()
            .map(|q| PointRole::Penalty(2e16 * q.w, 2e16 * q.w)),
    );
    let d = elasticity(2e11, 0.3, true);
    let mut g = c.benchmark_group("efg_plate_201x201");
    g.sample_size(10);
    g.bench_function("shape_functions_and_assembly_K_M", |b| {
        b.iter(|| {
            let sh = point_shapes(&s, &pts).unwrap();
            black_box(assemble(s.len(), &sh, &roles, d))
        })
    });
    let sh = point_shapes(&s, &pts).unwrap();
    let ops = assemble(s.len(), &sh, &roles, d);
    drop(sh);
    let p = NewmarkParams {
        dt: 1e-4,
        gamma: 0.5,
        beta: 0.25,
    };
    let a = p.alphas();
    let m = ops.gram.scaled(7800.0);
    let eff = ops.kbar().combine(1.0, &m, a[0]).unwrap();
    g.bench_function("cholesky_newmark_matrix", |b| {
        b.iter(|| black_box(Cholesky::factor(&eff).unwrap().nnz_l()))
    });
    drop(eff);
    let mut nm = Newmark::new(m, None, ops.kbar(), p).unwrap();
    let n = 2 * s.len();
    let mut st = State::zeros(n);
    let f: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 1 { -1.0 } else { 0.0 })
        .collect();
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        g.bench_function(format!("newmark_step_threads_{threads}"), |b| {
            b.iter(|| pool.install(|| nm.advance(&mut st, black_box(&f))))
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    // no plots: the plotting backend needs system fonts
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
