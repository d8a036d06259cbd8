//! DEM step throughput (docs/performance.md): 10 000 and 100 000 polydisperse
//! discs (`common/dem_setup.rs`: r uniform in [0.8, 1.2], ρ = 1,
//! k_n = k_s = 10⁶, friction 0.5, normal dashpot at ζ = 0.2, gravity) in a
//! box, (a) settling from a loose start, (b) a dense settled packing, each
//! on 1 and 2 threads. Throughput is in particle-steps per second.
//!
//! On 1 thread the same steps are also timed through `Model::step`
//! (`model_step_threads_1`), which adds the per-step stability check.
//!
//! 1 000 000 discs: the dense 100 000-disc packing ten times side by side
//! (group `dem_b_dense_1000000`, dense case only).
//!
//! `DEM_BENCH_SIZES=10000` restricts the sizes; `DEM_BENCH_ROLLING=0.1`
//! adds rolling resistance (μ_r = 0.1, rolling dashpot η_r = 0.3) to the
//! measured assembly (the packing is the same).

#[path = "common/dem_setup.rs"]
mod dem_setup;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dem_setup::{assembly_in, bounds, dense, dense_tiled, loose};
use efgdem::model::{Model, System};

const STEPS: usize = 20;

fn sizes() -> Vec<usize> {
    std::env::var("DEM_BENCH_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![10_000, 100_000, 1_000_000])
}

fn bench(c: &mut Criterion) {
    for n in sizes() {
        let (lo, hi) = bounds(n);
        let cases = if n == 1_000_000 {
            let (rows, lo, hi) = dense_tiled(100_000, 10);
            vec![("b_dense", rows, lo, hi)]
        } else {
            vec![
                ("a_settling", loose(n), lo, hi),
                ("b_dense", dense(n), lo, hi),
            ]
        };
        for (case, rows, lo, hi) in cases {
            let mut group = c.benchmark_group(format!("dem_{case}_{n}"));
            group.sample_size(10);
            group.warm_up_time(std::time::Duration::from_secs(1));
            group.measurement_time(std::time::Duration::from_secs(4));
            group.throughput(Throughput::Elements((n * STEPS) as u64));
            for threads in [1usize, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut g = assembly_in(&rows, lo, hi);
                // (a) falls freely from the loose packing for 2000 steps (until
                // the bed is compacting from the floor up) and keeps settling
                // while measured; (b) first lets the reloaded packing
                // re-equilibrate (shear histories are not cached)
                pool.install(|| {
                    let warm = if case == "b_dense" { 500 } else { 2000 };
                    for _ in 0..warm {
                        g.step();
                    }
                });
                let (dd, dw) = g.touching();
                eprintln!(
                    "{case} n={n} threads={threads}: {:.2} contacts/disc, {:.1} listed pairs/disc, {:.0} bytes/disc",
                    2.0 * dd as f64 / n as f64 + dw as f64 / n as f64,
                    g.contacts.len() as f64 / n as f64,
                    g.heap_bytes() as f64 / n as f64
                );
                group.bench_function(format!("threads_{threads}"), |b| {
                    b.iter(|| {
                        pool.install(|| {
                            for _ in 0..STEPS {
                                g.step();
                            }
                        })
                    })
                });
                eprintln!(
                    "  rebuilds so far: {} over {} steps",
                    g.grid.rebuilds, g.step
                );
                if threads == 1 {
                    // the same steps through the library's `Model::step`,
                    // which adds the per-step stability check
                    let mut m = Model {
                        dt: g.dt,
                        steps: usize::MAX,
                        step: 0,
                        system: System::Granular(Box::new(g)),
                    };
                    group.bench_function("model_step_threads_1", |b| {
                        b.iter(|| {
                            pool.install(|| {
                                for _ in 0..STEPS {
                                    m.step().expect("stable");
                                }
                            })
                        })
                    });
                }
            }
            group.finish();
        }
    }
}

criterion_group! {
    name = benches;
    // no plots: they need system fonts the CI machine may not have
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
