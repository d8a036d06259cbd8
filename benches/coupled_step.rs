//! The coupled footing of `common/body_setup.rs` (20 000 discs, an EFG
//! footing of 61 × 21 nodes pressed into them): 20 coupled steps with the
//! exact implicit step, with the sub-cycled scheme (`substeps = 20`) and
//! with the scheme the automatic choice takes, each on 1 and 2 threads. `examples/body_threads.rs` measures the same
//! cases interleaved.

#[path = "common/body_setup.rs"]
mod body_setup;

use criterion::{Criterion, criterion_group, criterion_main};

const STEPS: usize = 20;

fn bench(c: &mut Criterion) {
    for (name, substeps) in [("exact", 1), ("substeps_20", 20), ("auto", 0)] {
        let mut g = c.benchmark_group(format!("coupled_footing_{name}"));
        g.sample_size(10);
        let mut m = body_setup::footing(substeps, 1000);
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            g.bench_function(format!("threads_{threads}"), |b| {
                // as `efgdem run` steps between outputs
                b.iter(|| {
                    pool.install(|| {
                        (0..STEPS).for_each(|_| m.step_deferring().expect("step"));
                        m.settle().expect("settle")
                    })
                })
            });
        }
        g.finish();
    }
}

criterion_group! {
    name = benches;
    // no plots: the plotting backend needs system fonts
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
