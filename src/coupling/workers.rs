//! The pool's workers kept awake through the serial part of a coupled
//! step.
//!
//! A coupled step alternates a parallel DEM sweep with serial work (the
//! disc–body contacts, the contact solve, the body solves). A rayon worker
//! that finds nothing to do goes to sleep after a few microseconds, and
//! waking it again costs far more than that on a virtual machine or a core
//! in a deep idle state: measured on an 8 000-disc bed, the sweep after
//! 0.5 ms of serial work took 0.23 ms on 2 threads instead of 0.14 ms
//! (the step of a lone bed), i.e. the second thread was mostly lost.
//! [`awake`] runs the serial work while the other workers wait awake —
//! and run any job the serial work spawns — as OpenMP runtimes do between
//! parallel regions. It changes no result: only who waits, and how.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The longest a worker spins for one call: past it, serial work is long
/// enough that a wake-up no longer matters, and a worker that took the
/// spinning job while it still had unfinished work of `f` beneath it on
/// its stack (a rare interleaving of nested joins) is never held longer.
const MAX_SPIN: Duration = Duration::from_millis(5);

/// Run `f` on this thread while the other workers of the current pool
/// spin (running pending jobs, e.g. `f`'s own parallel loops) until it
/// returns. With one thread, just `f()`.
pub fn awake<R>(f: impl FnOnce() -> R) -> R {
    let n = rayon::current_num_threads();
    if n == 1 {
        return f();
    }
    let done = AtomicBool::new(false);
    let me = rayon::current_thread_index();
    rayon::in_place_scope(|s| {
        for _ in 1..n {
            s.spawn(|_| {
                // never on the thread that runs `f` (it would wait for itself)
                if rayon::current_thread_index() == me {
                    return;
                }
                let t = Instant::now();
                while !done.load(Ordering::Acquire) && t.elapsed() < MAX_SPIN {
                    if rayon::yield_now() != Some(rayon::Yield::Executed) {
                        std::thread::yield_now();
                    }
                }
            });
        }
        let r = f();
        done.store(true, Ordering::Release);
        r
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn the_serial_work_and_its_parallel_loops_run_and_return_on_any_pool() {
        for n in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap();
            let s = pool.install(|| {
                awake(|| {
                    (0..100_000u64)
                        .into_par_iter()
                        .map(|i| i * i % 7)
                        .sum::<u64>()
                })
            });
            assert_eq!(s, (0..100_000u64).map(|i| i * i % 7).sum::<u64>());
        }
        // outside any pool (the global one)
        assert_eq!(awake(|| 3), 3);
    }
}
