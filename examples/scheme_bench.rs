//! Cost of a coupled step against the DEM step on the same bed, for a
//! scenario file as written (the coupled scheme it chooses or names), on
//! 1 and 2 threads, measured in one run: blocks of coupled steps and of
//! DEM-only steps (the same bed built without its bodies) alternate, so a
//! busy machine slows both alike; the ratio of each pair of blocks is
//! reported as a median with its min–max (the thread counts take turns
//! block by block, so each samples the same stretch of the run), with the
//! coupled step's timing
//! split and the scheme's energy account.
//!
//!     cargo run --release --example scheme_bench -- SCENARIO [options]
//!
//! Options:
//! - `--start T`: step both models to time T first (default: when the
//!   body has had contacts for 200 steps), untimed;
//! - `--blocks N` (default 5) pairs of blocks per thread count, `--block K`
//!   (default 200) steps each;
//! - `--threads 1,2` (default);
//! - `--substeps auto|N`: override `[simulation] substeps`;
//! - `--replace 'A=>B'`: replace the text A by B in the scenario first
//!   (repeatable; e.g. `--replace 'E = 1.0e8=>E = 1.0e10'`).
//!
//! The ratio includes everything a coupled step does beyond the DEM step:
//! transfer, contact solve, body solves.

use efgdem::model::{Model, System};
use efgdem::scenario;
use std::time::Instant;

struct Args {
    path: String,
    start: Option<f64>,
    blocks: usize,
    block: usize,
    threads: Vec<usize>,
    substeps: Option<String>,
    replace: Vec<(String, String)>,
}

fn args() -> Args {
    let mut a = Args {
        path: String::new(),
        start: None,
        blocks: 5,
        block: 200,
        threads: vec![1, 2],
        substeps: None,
        replace: Vec::new(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(s) = it.next() {
        let mut val = || it.next().expect("option value");
        match s.as_str() {
            "--start" => a.start = Some(val().parse().expect("--start T")),
            "--blocks" => a.blocks = val().parse().expect("--blocks N"),
            "--block" => a.block = val().parse().expect("--block K"),
            "--threads" => {
                a.threads = val()
                    .split(',')
                    .map(|t| t.parse().expect("--threads 1,2"))
                    .collect()
            }
            "--substeps" => a.substeps = Some(val()),
            "--replace" => {
                let v = val();
                let (x, y) = v.split_once("=>").expect("--replace 'A=>B'");
                a.replace.push((x.to_string(), y.to_string()));
            }
            _ => a.path = s,
        }
    }
    assert!(!a.path.is_empty(), "usage: scheme_bench SCENARIO [options]");
    a
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Total vertical force of the discs on the bodies.
fn reaction(m: &Model) -> f64 {
    m.coupled()
        .map_or(0.0, |c| c.contacts.iter().map(|q| -q.force.y).sum())
}

fn main() {
    let a = args();
    let mut src = std::fs::read_to_string(&a.path).expect("scenario file");
    for (x, y) in &a.replace {
        assert!(src.contains(x.as_str()), "`{x}` is not in the scenario");
        src = src.replace(x.as_str(), y);
    }
    if let Some(n) = &a.substeps {
        let v = if n == "auto" {
            "\"auto\"".to_string()
        } else {
            n.clone()
        };
        src = src.replacen(
            "[simulation]\n",
            &format!("[simulation]\nsubsteps = {v}\n"),
            1,
        );
    }
    let sc = scenario::parse(&src, &a.path).unwrap_or_else(|e| panic!("{e}"));
    let mut bed = sc.clone();
    bed.body.clear();
    bed.probe.clear();
    bed.measure.clear();
    let max_threads = a.threads.iter().copied().max().unwrap_or(1);
    let pools: Vec<_> = a
        .threads
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("thread pool")
        })
        .collect();
    let big = rayon::ThreadPoolBuilder::new()
        .num_threads(max_threads)
        .build()
        .expect("thread pool");
    let (mut cm, mut dm) = big.install(|| {
        let t = Instant::now();
        let cm = sc.build().unwrap_or_else(|e| panic!("{e}"));
        let dm = bed.build().unwrap_or_else(|e| panic!("{e}"));
        eprintln!("built both models in {:.1} s", t.elapsed().as_secs_f64());
        (cm, dm)
    });
    let System::Coupled(c) = &cm.system else {
        panic!("not a coupled scenario")
    };
    eprintln!(
        "scheme: {} DEM steps per body step{}",
        c.substeps,
        if c.path_scheme() { " (sub-cycled)" } else { "" }
    );
    // untimed: to the start time, or until contacts have lasted 200 steps
    let t0 = Instant::now();
    let mut touching = 0usize;
    big.install(|| {
        loop {
            let done = match a.start {
                Some(t) => cm.time() + 0.5 * cm.dt >= t,
                None => touching >= 200,
            };
            if done {
                break;
            }
            cm.step().unwrap_or_else(|e| panic!("{e}"));
            dm.step().unwrap_or_else(|e| panic!("{e}"));
            let c = cm.coupled().expect("coupled");
            touching = if c.contacts.is_empty() {
                0
            } else {
                touching + 1
            };
        }
    });
    eprintln!(
        "at t = {:.4} s after {:.1} s untimed",
        cm.time(),
        t0.elapsed().as_secs_f64()
    );
    println!(
        "| threads | DEM-only ms/step | coupled ms/step | ratio median (min–max) | split DEM / transfer / contact solve / body (ms/step) | contacts | mean reaction (N) | E_created / W_exchanged |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let sub = cm.coupled().map_or(1, |c| c.substeps);
    let k = a.block.next_multiple_of(sub);
    let rebuilds = |m: &Model| m.granular().map_or(0, |g| g.grid.rebuilds);
    let mut per: Vec<PerThreads> = a.threads.iter().map(|_| PerThreads::default()).collect();
    // thread counts interleaved block by block: each samples the same
    // stretch of the run
    for _ in 0..a.blocks {
        for (pool, s) in pools.iter().zip(&mut per) {
            let c = cm.coupled().expect("coupled");
            let (before, p0) = (c.timing, c.compliance_products);
            let (rc0, rd0) = (rebuilds(&cm), rebuilds(&dm));
            pool.install(|| {
                let t = Instant::now();
                // as `efgdem run` steps between outputs
                for _ in 0..k {
                    cm.step_deferring().unwrap_or_else(|e| panic!("{e}"));
                    s.contacts += cm.coupled().expect("coupled").contacts.len();
                    s.react += reaction(&cm);
                    let it = cm.coupled().expect("coupled").newton_iterations.min(9);
                    s.newton[it] += 1;
                }
                cm.settle().unwrap_or_else(|e| panic!("{e}"));
                let tc = t.elapsed().as_secs_f64() * 1e3 / k as f64;
                let t = Instant::now();
                for _ in 0..k {
                    dm.step().unwrap_or_else(|e| panic!("{e}"));
                }
                let td = t.elapsed().as_secs_f64() * 1e3 / k as f64;
                s.ratios.push(tc / td);
                s.cms.push(tc);
                s.dms.push(td);
            });
            let c = cm.coupled().expect("coupled");
            let t = &c.timing;
            for (acc, x) in s.split.iter_mut().zip([
                t.dem - before.dem,
                t.transfer - before.transfer,
                t.contact_solve - before.contact_solve,
                t.body - before.body,
            ]) {
                *acc += x;
            }
            s.products += c.compliance_products - p0;
            s.rebuilds.0 += rebuilds(&cm) - rc0;
            s.rebuilds.1 += rebuilds(&dm) - rd0;
        }
    }
    let (created, exchanged) = cm.coupled().expect("coupled").subcycling_energy();
    let n = (k * a.blocks) as f64;
    for (s, nt) in per.iter_mut().zip(&a.threads) {
        let (lo, hi) =
            (s.ratios.iter()).fold((f64::MAX, f64::MIN), |(l, h), &r| (l.min(r), h.max(r)));
        eprintln!(
            "  {nt} threads: products S x per step {:.1}; Newton iterations per step (0..9+) {:?}; neighbour rebuilds coupled {} / DEM-only {}",
            s.products as f64 / n,
            s.newton,
            s.rebuilds.0,
            s.rebuilds.1
        );
        let ms = |x: f64| x * 1e3 / n;
        println!(
            "| {nt} | {:.3} | {:.3} | {:.2} ({lo:.2}–{hi:.2}) | {:.3} / {:.3} / {:.3} / {:.3} | {:.0} | {:.1} | {} |",
            median(&mut s.dms),
            median(&mut s.cms),
            median(&mut s.ratios),
            ms(s.split[0]),
            ms(s.split[1]),
            ms(s.split[2]),
            ms(s.split[3]),
            s.contacts as f64 / n,
            s.react / n,
            if exchanged > 0.0 {
                format!("{:.3e} / {:.3e}", created, exchanged)
            } else {
                "—".to_string()
            }
        );
    }
}

/// One thread count's measurements.
#[derive(Default)]
struct PerThreads {
    ratios: Vec<f64>,
    cms: Vec<f64>,
    dms: Vec<f64>,
    /// DEM / transfer / contact solve / body seconds
    split: [f64; 4],
    products: usize,
    rebuilds: (usize, usize),
    contacts: usize,
    react: f64,
    /// DEM steps by the contact solve's Newton iterations (9: 9 or more)
    newton: [usize; 10],
}
