//! The efgdem side of the DEM benchmarks: the packings of
//! `benches/common/dem_setup.rs`, stepped on rayon pools of given sizes.
//!
//! ```sh
//! # M particle-steps/s on 1 and 2 threads, interleaved reps on one assembly
//! cargo run --release --example dem_peer -- bench 100000 --threads 1,2 --steps 200 --reps 7
//! # write the start packing (x,y,r) and the state after `--steps` steps (JSON)
//! cargo run --release --example dem_peer -- physics 10000 --steps 2000 --packing p.csv
//! ```
//! `--tile k` puts the dense packing k times side by side (1 000 000 dense
//! discs: `bench 100000 --tile 10`, without settling them). `--beta-n β` replaces the critical-ratio normal dashpot by a constant
//! one, `c_n = β k_n` (the law of the peer benchmark); `--loose` starts
//! from the loose lattice instead of the dense packing.
//!
//! `bench` steps one assembly alternately on each pool (results are bitwise
//! the same on any thread count, so every pool continues the same run) and
//! prints, per thread count, the median, min and max of M particle-steps/s,
//! and the paired ratio to the first thread count, then that ratio once
//! more on a line of its own (`scaling 1 → 2 threads at N discs: r×`,
//! the scaling row of docs/performance.md). `physics` runs from the
//! dense packing at rest and prints the contacts per disc, the kinetic
//! energy and the force on each wall as JSON (contacts per disc: disc–disc
//! contacts counted at both discs, `2 N_c/N`; wall contacts apart) (`bench/peers/` compares them
//! with LAMMPS).

#[path = "../benches/common/dem_setup.rs"]
mod dem_setup;

use std::time::Instant;

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool")
}

fn median_min_max(v: &[f64]) -> (f64, f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    (s[s.len() / 2], s[0], s[s.len() - 1])
}

fn main() {
    // as `efgdem` does
    efgdem::run::memory::keep_large_allocations_mapped();
    let args: Vec<String> = std::env::args().collect();
    let mode = args.get(1).map(String::as_str).unwrap_or("bench");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10_000);
    let steps: usize = arg(&args, "--steps", 200);
    // `--tile k`: the dense packing of n discs k times side by side
    let tile: usize = arg(&args, "--tile", 1);
    let mut g = if args.iter().any(|a| a == "--loose") {
        dem_setup::assembly(&dem_setup::loose(n), n)
    } else if tile > 1 {
        let (rows, lo, hi) = dem_setup::dense_tiled(n, tile);
        dem_setup::assembly_in(&rows, lo, hi)
    } else {
        dem_setup::assembly(&dem_setup::dense(n), n)
    };
    let n = g.particles.len();
    // the peer benchmark's law: a constant normal dashpot c_n = β_n k_n
    // (LAMMPS `granular` with `damping velocity` has the same)
    let beta_n: f64 = arg(&args, "--beta-n", 0.0);
    // `--kn`: another normal stiffness (the peer script's self-test of its check)
    let kn: f64 = arg(&args, "--kn", 0.0);
    if kn > 0.0 {
        g.materials[0].kn = kn;
        g.update_laws();
    }
    if beta_n > 0.0 {
        g.materials[0].zeta_n = 0.0;
        g.materials[0].beta_n = beta_n;
        g.update_laws();
    }
    match mode {
        "bench" => {
            let threads: Vec<usize> = arg(&args, "--threads", "1,2".to_string())
                .split(',')
                .filter_map(|s| s.parse().ok())
                .collect();
            let reps: usize = arg(&args, "--reps", 5);
            let warm: usize = arg(&args, "--warm", 500);
            let pools: Vec<_> = threads.iter().map(|&t| pool(t)).collect();
            let built = efgdem::run::memory::peak_resident_bytes();
            // from here on the peak of the stepping alone (Linux: writing
            // 5 to clear_refs resets the high-water mark)
            std::fs::write("/proc/self/clear_refs", "5").ok();
            pools[0].install(|| (0..warm).for_each(|_| g.step()));
            let mut rate = vec![Vec::new(); threads.len()];
            let mut ratio = vec![Vec::new(); threads.len()];
            let rebuilds = g.grid.rebuilds;
            for _ in 0..reps {
                let mut t = Vec::new();
                for p in &pools {
                    let t0 = Instant::now();
                    p.install(|| (0..steps).for_each(|_| g.step()));
                    t.push(t0.elapsed().as_secs_f64());
                }
                for k in 0..threads.len() {
                    rate[k].push((n * steps) as f64 / t[k] / 1e6);
                    ratio[k].push(t[0] / t[k]);
                }
            }
            println!(
                "n = {n}, {steps} steps × {reps} reps, {} rebuilds, {:.0} heap bytes/disc",
                g.grid.rebuilds - rebuilds,
                g.heap_bytes() as f64 / n as f64
            );
            if let (Some(b), Some(s)) = (built, efgdem::run::memory::peak_resident_bytes()) {
                println!(
                    "peak resident memory: {:.0} bytes/disc building, {:.0} stepping",
                    b as f64 / n as f64,
                    s as f64 / n as f64
                );
            }
            for (k, t) in threads.iter().enumerate() {
                let (m, lo, hi) = median_min_max(&rate[k]);
                let (r, rlo, rhi) = median_min_max(&ratio[k]);
                println!(
                    "threads {t}: {m:.2} M p-steps/s ({lo:.2}–{hi:.2}); ÷ threads {}: {r:.3} ({rlo:.3}–{rhi:.3})",
                    threads[0]
                );
            }
            // the scaling target of the performance page, on one line
            for (k, t) in threads.iter().enumerate().skip(1) {
                let (r, rlo, rhi) = median_min_max(&ratio[k]);
                println!(
                    "scaling {} → {t} threads at {n} discs: {r:.2}× (median of {reps} paired reps, {rlo:.2}–{rhi:.2})",
                    threads[0]
                );
            }
        }
        "physics" => {
            if let Some(path) = args
                .iter()
                .position(|a| a == "--packing")
                .and_then(|k| args.get(k + 1))
            {
                let p = &g.particles;
                let mut s = String::from("x,y,r\n");
                for id in 0..n {
                    let k = p.slot[id] as usize;
                    s.push_str(&format!(
                        "{:e},{:e},{:e}\n",
                        p.pos[k].x, p.pos[k].y, p.radius[k]
                    ));
                }
                std::fs::write(path, s).expect("write the packing");
            }
            let threads: usize = arg(&args, "--threads", 1);
            let t0 = Instant::now();
            pool(threads).install(|| (0..steps).for_each(|_| g.step()));
            let secs = t0.elapsed().as_secs_f64();
            let (dd, dw) = g.touching();
            let e = g.energies();
            let walls: Vec<[f64; 2]> = g.walls.iter().map(|w| [w.force.x, w.force.y]).collect();
            let (lo, hi) = (g.walls[0].a, g.walls[2].a);
            println!(
                "{}",
                serde_json::json!({
                    "discs": n, "steps": steps, "threads": threads, "dt": g.dt,
                    "box": [lo.x, lo.y, hi.x, hi.y],
                    "contacts_per_disc": (2 * dd) as f64 / n as f64,
                    "wall_contacts": dw,
                    "kinetic": e.kinetic, "rotational": e.rotational,
                    "wall_force": walls, "seconds": secs,
                })
            );
        }
        _ => eprintln!("usage: dem_peer bench|physics N [--threads 1,2] [--steps S] [--reps R]"),
    }
}
