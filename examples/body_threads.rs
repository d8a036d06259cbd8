//! The continuum and coupled cases of `benches/common/body_setup.rs` on 1
//! and 2 threads, interleaved: each round steps the same model on one pool
//! and then on the other (results are bitwise the same on any thread
//! count, so both continue one run), and the ratio of a round's times is
//! the speed-up from 1 to 2 threads. Prints the median (min–max) of the
//! time per step on each pool and of the ratio.
//!
//! ```sh
//! cargo run --release --example body_threads -- plate 201 --steps 5 --reps 3
//! cargo run --release --example body_threads -- footing 1 --steps 200 --reps 3   # exact step
//! cargo run --release --example body_threads -- footing 20 --steps 200 --reps 3  # sub-cycled
//! cargo run --release --example body_threads -- footing auto --steps 200 --reps 3 # the automatic choice
//! ```
//! The footing case also prints the split of its steps (DEM, transfer,
//! contact solve, body) per thread count. It steps as `efgdem run` does
//! between outputs (an exact step's body end done beside the next step's
//! discs, `CoupledModel::step_deferring`); `--settled` completes every
//! step before the next, as `Model::step` does.

#[path = "../benches/common/body_setup.rs"]
mod body_setup;

use std::time::Instant;

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> T {
    args.iter()
        .position(|a| a == name)
        .and_then(|k| args.get(k + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn median_min_max(v: &[f64]) -> (f64, f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    (s[s.len() / 2], s[0], s[s.len() - 1])
}

/// Time `step` (`steps` times per round, `reps` rounds) on pools of 1 and 2
/// threads alternately; per pool the milliseconds per step of each round.
fn interleaved(steps: usize, reps: usize, mut step: impl FnMut(usize) + Send) -> [Vec<f64>; 2] {
    let pools: Vec<_> = [1, 2]
        .iter()
        .map(|&t| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .expect("thread pool")
        })
        .collect();
    let mut ms = [Vec::new(), Vec::new()];
    for _ in 0..reps {
        for (k, p) in pools.iter().enumerate() {
            let t0 = Instant::now();
            p.install(|| (0..steps).for_each(|_| step(k)));
            ms[k].push(1e3 * t0.elapsed().as_secs_f64() / steps as f64);
        }
    }
    ms
}

fn report(ms: &[Vec<f64>; 2]) {
    for (k, t) in ms.iter().enumerate() {
        let (m, lo, hi) = median_min_max(t);
        println!("threads {}: {m:.3} ms/step ({lo:.3}–{hi:.3})", k + 1);
    }
    let ratio: Vec<f64> = ms[0].iter().zip(&ms[1]).map(|(a, b)| a / b).collect();
    let (r, lo, hi) = median_min_max(&ratio);
    println!("1 → 2 threads: {r:.3}× ({lo:.3}–{hi:.3})");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let case = args.get(1).map(String::as_str).unwrap_or("plate");
    let size: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0);
    let steps: usize = arg(&args, "--steps", 5);
    let reps: usize = arg(&args, "--reps", 3);
    match case {
        "plate" => {
            let n = if size == 0 { 201 } else { size };
            let mut b = body_setup::plate(n);
            let nm = b.newmark().expect("dynamic");
            println!(
                "plate {n} × {n}: {} DOFs, nnz(L) = {}",
                b.n_dofs(),
                nm.factor_nnz()
            );
            b.advance().expect("step");
            report(&interleaved(steps, reps, |_| b.advance().expect("step")));
        }
        "footing" => {
            // `footing auto`: the automatic choice
            let auto = args.get(2).is_some_and(|a| a == "auto");
            let mut m = body_setup::footing(
                if auto { 0 } else { size.max(1) },
                arg(&args, "--warm", 1000),
            );
            let substeps = m.substeps;
            if let Some(c) = &m.choice {
                println!("scheme: {} × {} ({})", c.scheme.name(), c.substeps, c.why);
            }
            if let Some(f) = &m.fallback {
                println!("fell back: {f:?}");
            }
            // as `efgdem run` steps between outputs (`--settled`: every
            // step's bodies complete before it returns, as `Model::step`)
            let settled = args.iter().any(|a| a == "--settled");
            let mut split = [efgdem::coupling::StepTiming::default(); 2];
            let ms = interleaved(steps.next_multiple_of(substeps), reps, |k| {
                let before = m.timing;
                if settled {
                    m.step().expect("step");
                } else {
                    m.step_deferring().expect("step");
                }
                let t = &mut split[k];
                t.dem += m.timing.dem - before.dem;
                t.transfer += m.timing.transfer - before.transfer;
                t.contact_solve += m.timing.contact_solve - before.contact_solve;
                t.body += m.timing.body - before.body;
            });
            println!(
                "footing, substeps = {substeps}: {} discs, {} contacts at the end",
                m.granular.particles.len(),
                m.contacts.len()
            );
            report(&ms);
            let per = 1e3 / (reps * steps.next_multiple_of(substeps)) as f64;
            for (k, t) in split.iter().enumerate() {
                println!(
                    "threads {}: DEM {:.3}, transfer {:.3}, contact solve {:.3}, body {:.3} ms/step",
                    k + 1,
                    t.dem * per,
                    t.transfer * per,
                    t.contact_solve * per,
                    t.body * per
                );
            }
        }
        _ => eprintln!(
            "usage: body_threads plate [N] | footing [substeps | auto] [--steps S] [--reps R] [--settled]"
        ),
    }
}
