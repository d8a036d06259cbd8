//! Cost per step of parallel bonds and of clumps against plain discs
//! (docs/performance.md): the dense settled packing of the DEM benchmark
//! (`benches/common/dem_setup.rs`, N discs under gravity in a box) stepped
//! three ways — as it is, bonded (every pair closer than 5 % of the
//! smaller radius, strong bonds that do not break) and with its discs
//! joined two by two into clumps (each disc with a touching neighbour not
//! yet in a clump) — in interleaved rounds of 50 steps, so that the
//! machine's load falls on all three alike. Prints the median over the
//! rounds of each variant's time per step over the plain one's, in
//! wall-clock time and in CPU time (the time the process ran: on a
//! shared machine the steadier of the two).
//!
//!     cargo run --release --example bond_cost -- [N (10000)] [rounds (12)]
//!
//! The first run settles the packing once (cached in target/).

#[path = "../benches/common/dem_setup.rs"]
mod dem_setup;

use efgdem::dem::Granular;
use efgdem::dem::bonds::{BondLaw, BondRule, ShearStrength};
use std::time::Instant;

const STEPS: usize = 50;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let n = args.first().copied().unwrap_or(10_000);
    let rounds = args.get(1).copied().unwrap_or(12);
    let rows = dem_setup::dense(n);
    let (lo, hi) = dem_setup::bounds(n);
    let plain = dem_setup::assembly_in(&rows, lo, hi);
    let mut bonded = plain.clone();
    bonded.bonds.law = BondLaw {
        kn: 1e6,
        ks: 1e6,
        tensile: f64::INFINITY,
        shear: ShearStrength::Fixed(f64::INFINITY),
        ..Default::default()
    };
    bonded.bonds.rule = Some(BondRule {
        gap: 0.05,
        ..Default::default()
    });
    bonded.dt = plain.dt.min(0.15 * bonded.critical_dt());
    let mut clumped = plain.clone();
    pair_up(&mut clumped);
    clumped.dt = plain.dt.min(0.15 * clumped.critical_dt());
    let mut runs = [("plain", plain), ("bonded", bonded), ("clumps", clumped)];
    // settle each into its own state (bonds made, lists built)
    for (_, g) in &mut runs {
        for _ in 0..200 {
            g.step();
        }
    }
    println!(
        "{n} discs: {} bonds, {} clumps ({} discs in clumps), {} threads",
        runs[1].1.bonds.list().len(),
        runs[2].1.clumps.len(),
        runs[2].1.clumps.members.len(),
        rayon::current_num_threads()
    );
    let mut ratios = vec![vec![]; runs.len()];
    let mut cpu_ratios = vec![vec![]; runs.len()];
    let mut plain_us = vec![];
    for _ in 0..rounds {
        let times: Vec<(f64, f64)> = runs
            .iter_mut()
            .map(|(_, g)| {
                let (t, c) = (Instant::now(), cpu_ns());
                for _ in 0..STEPS {
                    g.step();
                }
                let wall = t.elapsed().as_secs_f64() / STEPS as f64;
                (wall, (cpu_ns() - c) as f64)
            })
            .collect();
        plain_us.push(times[0].0 * 1e6);
        for (k, t) in times.iter().enumerate() {
            ratios[k].push(t.0 / times[0].0);
            cpu_ratios[k].push(t.1 / times[0].1);
        }
    }
    plain_us.sort_by(f64::total_cmp);
    println!(
        "plain step: {:.0} µs (median; range {:.0}–{:.0})",
        plain_us[plain_us.len() / 2],
        plain_us[0],
        plain_us[plain_us.len() - 1]
    );
    for (((name, g), r), c) in runs.iter().zip(&mut ratios).zip(&mut cpu_ratios) {
        r.sort_by(f64::total_cmp);
        c.sort_by(f64::total_cmp);
        println!(
            "{name:>7}: {:.2} × plain per step (median of {rounds} rounds; range {:.2}–{:.2}); \
             CPU time {:.2} × ({:.2}–{:.2}); {} rebuilds",
            r[r.len() / 2],
            r[0],
            r[r.len() - 1],
            c[c.len() / 2],
            c[0],
            c[c.len() - 1],
            g.grid.rebuilds
        );
    }
}

/// CPU time of the process's threads so far, in ns (Linux:
/// `/proc/self/task/*/schedstat`; 0 elsewhere): the time it ran, which a
/// machine shared with other jobs does not stretch as it stretches the
/// wall-clock time.
fn cpu_ns() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    tasks
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

/// Join each disc with a touching neighbour not yet in a clump (in list
/// order): clumps of two, as many discs as before.
fn pair_up(g: &mut Granular) {
    g.step(); // the contact list
    let p = &g.particles;
    let mut taken = vec![false; p.len()];
    let mut pairs = vec![];
    for (i, j) in g.contacts.pairs() {
        let r = p.radius[i] + p.radius[j];
        if !taken[i] && !taken[j] && (p.pos[j] - p.pos[i]).norm2() < r * r {
            taken[i] = true;
            taken[j] = true;
            pairs.push([p.id[i] as usize, p.id[j] as usize]);
        }
    }
    for m in pairs {
        g.add_clump(&m).expect("two discs of one density");
    }
}
