//! DEM step throughput (docs/performance.md): 10 000 and 100 000 polydisperse
//! discs (r uniform in [0.8, 1.2], ρ = 1, k_n = k_s = 10⁶, friction 0.5,
//! normal dashpot at ζ = 0.2, gravity) in a box,
//! (a) settling from a loose start, (b) a dense settled packing,
//! each on 1 and 2 threads. Throughput is in particle-steps per second.
//!
//! The dense packing is made once by gravity deposition and cached in
//! `target/dem-bench-cache/dense_N.csv`.
//!
//! On 1 thread the same steps are also timed through `Model::step`
//! (`model_step_threads_1`), which adds the per-step stability check.
//!
//! `DEM_BENCH_SIZES=10000` restricts the sizes; `DEM_BENCH_ROLLING=0.1`
//! adds rolling resistance (μ_r = 0.1, rolling dashpot η_r = 0.3) to the
//! measured assembly (the packing is the same).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use efgdem::Vec2;
use efgdem::dem::Granular;
use efgdem::dem::contact::ContactLaw;
use efgdem::dem::packing::{DiscRow, Lattice, lattice_packing, settle_in_box};
use efgdem::dem::particles::Particles;
use efgdem::dem::walls::{Wall, WallMotion};
use efgdem::model::{Model, System};
use efgdem::scenario::generate::discs_from_csv;
use std::path::PathBuf;

const STEPS: usize = 20;

fn law() -> ContactLaw {
    ContactLaw {
        kn: 1.0e6,
        ks: 1.0e6,
        mu: 0.5,
        ..Default::default()
    }
}

/// Box for n discs: a wide bed (width 2.64 · 4√n, about n/(1.5√n) rows),
/// tall enough for the loose packing.
pub fn bounds(n: usize) -> (Vec2, Vec2) {
    let w = 2.64 * 4.0 * (n as f64).sqrt();
    let rows = (n as f64 / (w / 2.64 - 1.0)).ceil() + 2.0;
    (Vec2::ZERO, Vec2::new(w, rows * 2.64 * 0.87 + 3.0))
}

fn loose(n: usize) -> Vec<DiscRow> {
    let (lo, hi) = bounds(n);
    lattice_packing(Lattice::Hex, lo, hi, (0.8, 1.2), Some(n), 0.1, 1.0, 42).expect("fits")
}

fn dense(n: usize) -> Vec<DiscRow> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/dem-bench-cache");
    let path = dir.join(format!("dense_{n}.csv"));
    if let Ok(text) = std::fs::read_to_string(&path)
        && let Ok(rows) = discs_from_csv(&text)
        && rows.len() == n
    {
        return rows;
    }
    eprintln!(
        "settling {n} discs once for the dense packing (cached in {})",
        path.display()
    );
    let (lo, hi) = bounds(n);
    // deposit under 10 g (faster), then relax under g
    let rows = settle_in_box(
        &loose(n),
        lo,
        hi,
        law(),
        1.0,
        1.0,
        Vec2::new(0.0, -98.1),
        6_000,
        &mut |_| true,
    )
    .expect("settles");
    let rows = settle_in_box(
        &rows,
        lo,
        hi,
        law(),
        1.0,
        1.0,
        Vec2::new(0.0, -9.81),
        10_000,
        &mut |_| true,
    )
    .expect("settles");
    std::fs::create_dir_all(&dir).ok();
    let mut s = String::from("x,y,r\n");
    for r in &rows {
        s.push_str(&format!("{:e},{:e},{:e}\n", r.pos.x, r.pos.y, r.r));
    }
    std::fs::write(&path, s).ok();
    rows
}

/// The benchmark assembly: normal dashpot ζ = 0.2, Δt = 0.15 × critical.
pub fn assembly(rows: &[DiscRow], n: usize) -> Granular {
    let (lo, hi) = bounds(n);
    let mut p = Particles::default();
    for r in rows {
        p.push(r.pos, r.r, 1.0, 1.0, 0);
    }
    let c = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
    let walls = (0..4)
        .map(|k| Wall::new("box", c[k], c[(k + 1) % 4], WallMotion::Fixed))
        .collect();
    let mut l = law();
    l.zeta_n = 0.2;
    if let Some(mu_r) = std::env::var("DEM_BENCH_ROLLING")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
    {
        l.mu_roll = mu_r;
        l.roll_damping = 0.3;
    }
    let mut g = Granular::new(p, vec![l], walls, 1.0);
    g.dt = 0.15 * g.critical_dt();
    g.gravity = Vec2::new(0.0, -9.81);
    // as `efgdem run` between frames: disc forces are not kept
    g.store_forces = false;
    g
}

fn sizes() -> Vec<usize> {
    std::env::var("DEM_BENCH_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![10_000, 100_000])
}

fn bench(c: &mut Criterion) {
    for n in sizes() {
        for (case, rows) in [("a_settling", loose(n)), ("b_dense", dense(n))] {
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
                let mut g = assembly(&rows, n);
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
                    g.contacts.pairs.len() as f64 / n as f64,
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
