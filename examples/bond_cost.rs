//! Cost per step of parallel bonds and of clumps against plain discs
//! (docs/performance.md): the dense settled packing of the DEM benchmark
//! (`benches/common/dem_setup.rs`, N discs under gravity in a box) stepped
//! four ways — as it is, bonded (every pair closer than 5 % of the
//! smaller radius, strong bonds that do not break) and with its discs
//! joined two by two into clumps (each disc with a touching neighbour not
//! yet in a clump), the same clumps made in a random order ("shuffled":
//! the clumps of a scenario need not be listed in the order of their
//! discs in space) — in interleaved rounds of 50 steps, so that the
//! machine's load falls on all alike. Prints the median over the
//! rounds of each variant's time per step over the plain one's, in
//! wall-clock time and in CPU time (the time the process ran: on a
//! shared machine the steadier of the two), over all steps and over the
//! steps that did not rebuild the contact list (the plain packing, which
//! creeps under gravity, rebuilds it about every 60 steps, the bonded one
//! almost never: a round of 50 steps holds one rebuild or none, which
//! made the ratio over all steps jump from round to round; without the
//! rebuilds it is the cost of a step itself).
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
    pair_up(&mut clumped, false);
    clumped.dt = plain.dt.min(0.15 * clumped.critical_dt());
    let mut shuffled = plain.clone();
    pair_up(&mut shuffled, true);
    shuffled.dt = clumped.dt;
    let mut runs = [
        ("plain", plain),
        ("bonded", bonded),
        ("clumps", clumped),
        ("shuffled", shuffled),
    ];
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
    // per variant and round: (wall, CPU) per step over all steps, and
    // over the steps that did not rebuild the contact list
    let mut all = vec![vec![]; runs.len()];
    let mut steady = vec![vec![]; runs.len()];
    for _ in 0..rounds {
        for (k, (_, g)) in runs.iter_mut().enumerate() {
            let (mut sum, mut calm, mut n_calm) = ((0.0, 0.0), (0.0, 0.0), 0.0);
            for _ in 0..STEPS {
                let (t, c, r) = (Instant::now(), cpu_ns(), g.grid.rebuilds);
                g.step();
                let (w, c) = (t.elapsed().as_secs_f64(), (cpu_ns() - c) as f64);
                sum = (sum.0 + w, sum.1 + c);
                if g.grid.rebuilds == r {
                    calm = (calm.0 + w, calm.1 + c);
                    n_calm += 1.0;
                }
            }
            all[k].push((sum.0 / STEPS as f64, sum.1 / STEPS as f64));
            steady[k].push((calm.0 / n_calm, calm.1 / n_calm));
        }
    }
    let mut plain_us: Vec<f64> = all[0].iter().map(|t| t.0 * 1e6).collect();
    plain_us.sort_by(f64::total_cmp);
    println!(
        "plain step: {:.0} µs (median; range {:.0}–{:.0})",
        plain_us[plain_us.len() / 2],
        plain_us[0],
        plain_us[plain_us.len() - 1]
    );
    // median and range over the rounds of a variant's time over plain's
    let ratio = |t: &[Vec<(f64, f64)>], k: usize, cpu: bool| {
        let pick = |x: &(f64, f64)| if cpu { x.1 } else { x.0 };
        let mut r: Vec<f64> = t[k]
            .iter()
            .zip(&t[0])
            .map(|(a, b)| pick(a) / pick(b))
            .collect();
        r.sort_by(f64::total_cmp);
        format!("{:.2} ({:.2}–{:.2})", r[r.len() / 2], r[0], r[r.len() - 1])
    };
    for (k, (name, g)) in runs.iter().enumerate().skip(1) {
        println!(
            "{name:>8}: × plain per step, median of {rounds} rounds (range): \
             all steps: wall {}, CPU {}; without list rebuilds: wall {}, CPU {} \
             ({} rebuilds; plain {})",
            ratio(&all, k, false),
            ratio(&all, k, true),
            ratio(&steady, k, false),
            ratio(&steady, k, true),
            g.grid.rebuilds,
            runs[0].1.grid.rebuilds,
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
/// order): clumps of two, as many discs as before; made in list order, or
/// in a random (seeded) order with `shuffle`.
fn pair_up(g: &mut Granular, shuffle: bool) {
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
    if shuffle {
        let mut rng = oorandom::Rand64::new(7);
        for k in (1..pairs.len()).rev() {
            pairs.swap(k, rng.rand_range(0..k as u64 + 1) as usize);
        }
    }
    for m in pairs {
        g.add_clump(&m).expect("two discs of one density");
    }
}
