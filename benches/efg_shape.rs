//! Shape functions with derivatives at Gauss points (one thread): points/s.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use efgdem::Vec2;
use efgdem::continuum::quadrature::domain_points;
use efgdem::efg::shape::{ShapeRow, shape_functions};
use efgdem::efg::support::Support;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    // 101 × 101 nodes, d_max = 2: 16 nodes cover a Gauss point
    let xs: Vec<f64> = (0..101).map(|i| i as f64 * 0.01).collect();
    let s = Support::for_grid(&xs, &xs, 2.0);
    let pts: Vec<Vec2> = domain_points(Vec2::ZERO, Vec2::new(1.0, 1.0), [100, 100], 4)
        .iter()
        .map(|q| q.x)
        .collect();
    let mut row = ShapeRow::new();
    shape_functions(&s, pts[5000], &mut row).unwrap();
    assert_eq!(row.len(), 16);
    let mut g = c.benchmark_group("efg_shape");
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.sample_size(20);
    g.bench_function("gauss_points_160k_16_nodes", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &p in &pts {
                shape_functions(&s, p, &mut row).unwrap();
                acc += row.dx[0];
            }
            black_box(acc)
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // no plots: the plotting backend needs system fonts
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
