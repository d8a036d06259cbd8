//! A granular assembly divided over 2, 3 and 4 ranks (threads of this
//! process talking through `decomp::Threads`, the same code paths as MPI)
//! steps bitwise as the undivided one: the state gathered on rank 0 equals
//! the whole's saved state, byte for byte, at every check — discs, the
//! pair list and its shear and rolling histories, walls (a servo among
//! them), the Verlet bookkeeping.

#[allow(dead_code)]
mod common;

use efgdem::decomp::{Comm, Decomposed, Threads};
use efgdem::dem::Granular;
use efgdem::dem::particles::GHOST;
use efgdem::dem::state::GranularState;
use efgdem::scenario;
use std::sync::Arc;

fn build(src: &str) -> Granular {
    scenario::parse(src, "t.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
        .into_granular()
        .expect("granular")
}

/// `n` discs falling into a box 0.2 m × 0.3 m whose lid is a servo wall;
/// rolling resistance (`common::settling`).
fn settling(n: usize) -> String {
    common::settling(n, 1, 0.2, 0.3)
}

fn bytes(s: &GranularState) -> Vec<u8> {
    postcard::to_stdvec(s).unwrap()
}

/// The fields in which two states differ (for the failure message).
fn differ(a: &[u8], b: &[u8]) -> String {
    let a: GranularState = postcard::from_bytes(a).unwrap();
    let b: GranularState = postcard::from_bytes(b).unwrap();
    let mut out = Vec::new();
    macro_rules! field {
        ($($f:ident),*) => {$(
            let (x, y) = (postcard::to_stdvec(&a.$f).unwrap(), postcard::to_stdvec(&b.$f).unwrap());
            if x != y {
                out.push(stringify!($f));
            }
        )*};
    }
    field!(
        step, time, max_disp, id, pos, vel, theta, omega, force, torque, walls, pairs, shear,
        rolling, roll, wall_pairs, ref_pos, wall_ref, rebuilds, stale
    );
    if let Some(k) =
        (0..a.pos.len().min(b.pos.len())).find(|&k| a.pos[k] != b.pos[k] || a.vel[k] != b.vel[k])
    {
        out.push("first disc:");
        println!(
            "slot {k}: id {} vs {}, pos {:?} vs {:?}",
            a.id[k], b.id[k], a.pos[k], b.pos[k]
        );
    }
    if a.pairs.len() != b.pairs.len() {
        println!("pairs {} vs {}", a.pairs.len(), b.pairs.len());
    }
    out.join(", ")
}

/// What the ranks of [`compare`] saw.
struct Seen {
    /// Largest imbalance after any step.
    worst: f64,
    /// Times the regions were cut again.
    recuts: usize,
    /// For each disc id, how many times it changed rank.
    moves: Vec<u32>,
    /// Discs that arrived at a new owner, over all ranks.
    arrivals: usize,
    /// Non-zero contact histories that arrived with them.
    histories_in: usize,
}

/// Step the whole and `ranks` parts `steps` steps, comparing every
/// `every` steps.
fn compare(whole: &Granular, ranks: usize, steps: usize, every: usize) -> Seen {
    let mut single = whole.clone();
    single.prepare_contacts();
    let mut want = Vec::new();
    for s in 1..=steps {
        single.step();
        if s % every == 0 {
            want.push(bytes(&single.save_state()));
        }
    }
    let comms = Threads::group(ranks);
    type Rank = (Vec<Vec<u8>>, f64, Vec<Vec<u32>>, [usize; 3]);
    let got: Vec<Rank> = std::thread::scope(|sc| {
        let hs: Vec<_> = comms
            .into_iter()
            .map(|c| {
                let whole = whole.clone();
                sc.spawn(move || {
                    let comm: Arc<dyn Comm> = Arc::new(c);
                    let mut d = Decomposed::new(&whole, comm);
                    drop(whole);
                    d.prepare();
                    let mut out = Vec::new();
                    let mut worst = 0.0f64;
                    // the ids this rank owns after each rebuild
                    let mut owned = vec![owned_ids(&d)];
                    let mut rebuilds = d.part.grid.rebuilds;
                    for s in 1..=steps {
                        d.step(false);
                        worst = worst.max(d.imbalance);
                        if d.part.grid.rebuilds != rebuilds {
                            rebuilds = d.part.grid.rebuilds;
                            owned.push(owned_ids(&d));
                        }
                        // gather is collective: every rank calls it
                        if s % every == 0
                            && let Some(st) = d.gather()
                        {
                            out.push(bytes(&st));
                        }
                    }
                    (out, worst, owned, [d.recuts, d.arrivals, d.histories_in])
                })
            })
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let (dd, dw) = single.touching();
    println!(
        "{} discs, {} rebuilds, {dd} disc–disc and {dw} disc–wall contacts",
        single.particles.len(),
        single.grid.rebuilds,
    );
    let root = &got[0].0;
    assert_eq!(root.len(), want.len());
    for (k, (a, b)) in root.iter().zip(&want).enumerate() {
        assert!(
            a == b,
            "{ranks} ranks: state after {} steps differs from the whole: {}",
            (k + 1) * every,
            differ(a, b)
        );
    }
    // each disc's owner after each rebuild, and how often it changed
    let n = whole.particles.len();
    let mut moves = vec![0u32; n];
    let mut last = vec![usize::MAX; n];
    for k in 0..got[0].2.len() {
        let mut now = vec![usize::MAX; n];
        for (r, g) in got.iter().enumerate() {
            for &id in &g.2[k] {
                assert_eq!(now[id as usize], usize::MAX, "disc {id} owned twice");
                now[id as usize] = r;
            }
        }
        assert!(
            now.iter().all(|&r| r != usize::MAX),
            "a disc owned by no rank"
        );
        for ((m, a), b) in moves.iter_mut().zip(&now).zip(&last) {
            *m += (k > 0 && a != b) as u32;
        }
        last = now;
    }
    Seen {
        worst: got.iter().map(|g| g.1).fold(0.0, f64::max),
        recuts: got[0].3[0],
        moves,
        arrivals: got.iter().map(|g| g.3[1]).sum(),
        histories_in: got.iter().map(|g| g.3[2]).sum(),
    }
}

/// The ids of the discs `d` owns (ghosts aside).
fn owned_ids(d: &Decomposed) -> Vec<u32> {
    let p = &d.part.particles;
    (0..p.len())
        .filter(|&s| p.fixity[s] & GHOST == 0)
        .map(|s| p.id[s])
        .collect()
}

/// 1500 discs fall 0.3 m and settle under a servo lid (4000 steps: about
/// 2400 disc–disc contacts, discs crossing the region boundaries while
/// they fall, histories migrating with them); 1–4 ranks.
#[test]
fn parts_step_bitwise_as_the_whole() {
    let whole = build(&settling(1500));
    for ranks in [1, 2, 3, 4] {
        let worst = compare(&whole, ranks, 4000, 500).worst;
        println!("{ranks} ranks: worst imbalance {worst:.3}");
        // recut whenever the counts drift past the threshold (0.1)
        assert!(worst <= 0.1, "{ranks} ranks: imbalance {worst}");
    }
}

/// A dense column shaken vertically at 25 Hz (`common::shaken_column`):
/// it leaps and lands every period, discs near the horizontal cuts change
/// rank again and again with their contact histories, and the state stays
/// bitwise that of the whole on 2 and 3 ranks.
#[test]
fn discs_crossing_regions_again_and_again_stay_bitwise() {
    let whole = build(&common::shaken_column(1));
    for ranks in [2, 3] {
        let seen = compare(&whole, ranks, 8000, 2000);
        let moved = |k: u32| seen.moves.iter().filter(|&&m| m >= k).count();
        println!(
            "{ranks} ranks: {} arrivals, {} histories in, {} recuts; discs that changed rank \
             at least 1, 4, 8 times: {}, {}, {}; most {}",
            seen.arrivals,
            seen.histories_in,
            seen.recuts,
            moved(1),
            moved(4),
            moved(8),
            seen.moves.iter().max().unwrap()
        );
        let total: u32 = seen.moves.iter().sum();
        assert_eq!(seen.arrivals, total as usize);
        assert!(
            moved(4) >= 30,
            "{ranks} ranks: {} discs changed rank ≥ 4 times",
            moved(4)
        );
        assert!(
            seen.histories_in >= seen.arrivals,
            "{ranks} ranks: {} histories",
            seen.histories_in
        );
    }
}

/// A column released against the left wall (`common::collapsing_column`)
/// runs out to the right: regions cut for the column lose their balance,
/// are cut again, and the imbalance after every step stays within the
/// threshold (0.1), bitwise as the whole.
#[test]
fn a_collapsing_column_is_rebalanced() {
    let whole = build(&common::collapsing_column(1));
    for ranks in [2, 3, 4] {
        let seen = compare(&whole, ranks, 8000, 2000);
        println!(
            "{ranks} ranks: {} recuts, worst imbalance {:.3}, {} arrivals",
            seen.recuts, seen.worst, seen.arrivals
        );
        assert!(seen.recuts >= 2, "{ranks} ranks: {} recuts", seen.recuts);
        assert!(seen.worst <= 0.1, "{ranks} ranks: imbalance {}", seen.worst);
    }
}

/// Fewer discs than ranks: some ranks own nothing and still take part.
#[test]
fn ranks_without_discs_take_part() {
    let whole = build(&settling(3));
    compare(&whole, 4, 200, 50);
}

/// `efgdem run` of a granular scenario on 3 ranks (threads) writes the
/// files of the run on one rank, byte for byte: history (wall forces of
/// the servo lid, energies, a disc's position), final discs.
#[test]
fn run_on_ranks_writes_the_outputs_of_one_rank_and_restarts_on_others() {
    let probes = r#"
[output]
every = 250
[[probe]]
name = "lid_fy"
wall = "lid"
quantity = "wall_fy"
[[probe]]
name = "ek"
quantity = "kinetic"
[[probe]]
name = "spring"
quantity = "spring"
[[probe]]
name = "contacts"
quantity = "contacts"
[[probe]]
name = "y7"
disc = 7
quantity = "y"
[[probe]]
name = "er"
quantity = "rotational"
[[probe]]
name = "eg"
quantity = "gravity_energy"
[[probe]]
name = "et"
quantity = "total_energy"
[[probe]]
name = "f12"
contact = [1, 2]
quantity = "normal_total"
[[measure]]
name = "mid"
rectangle = [[0.05, 0.0], [0.15, 0.15]]
"#;
    let src = settling(600).replace("steps = 1\n", "steps = 4000\n") + probes;
    let sc = scenario::parse(&src, "t.toml").unwrap_or_else(|e| panic!("{e}"));
    let dir = std::env::temp_dir().join(format!("efgdem-decomp-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut opts = efgdem::run::RunOptions::new(dir.join("one"));
    opts.quiet = true;
    efgdem::run::run(&sc, &opts).unwrap();
    let read = |d: &str, f: &str| std::fs::read(dir.join(d).join(f)).unwrap();
    let hist = String::from_utf8(read("one", "history.csv")).unwrap();
    println!("{}", hist.lines().last().unwrap());
    // the region's columns measure a settled bed (not a vacuous match):
    // stress, porosity, coordination and fabric from its contacts
    let head: Vec<&str> = hist.lines().next().unwrap().split(',').collect();
    let last: Vec<f64> = (hist.lines().last().unwrap().split(','))
        .map(|x| x.parse().unwrap())
        .collect();
    let col = |name: &str| last[head.iter().position(|h| *h == name).unwrap()];
    assert!(col("mid_syy_cpos") > 0.0 && col("mid_coordination") > 2.0);
    assert!((col("mid_fxx") + col("mid_fyy") - 1.0).abs() < 1e-12);
    assert!(col("mid_porosity") > 0.1 && col("mid_porosity") < 0.9);
    let on = |ranks: usize, opts: &efgdem::run::RunOptions| {
        std::thread::scope(|s| {
            for c in Threads::group(ranks) {
                let sc = &sc;
                s.spawn(move || efgdem::run::run_on(sc, opts, Arc::new(c)).unwrap());
            }
        })
    };
    for ranks in [2, 3] {
        let name = format!("ranks{ranks}");
        let opts = efgdem::run::RunOptions {
            out_dir: dir.join(&name),
            ..opts.clone()
        };
        on(ranks, &opts);
        for f in ["history.csv", "discs_final.csv"] {
            assert!(
                read("one", f) == read(&name, f),
                "{ranks} ranks: {f} differs"
            );
        }
        let s: serde_json::Value = serde_json::from_slice(&read(&name, "summary.json")).unwrap();
        assert_eq!(s["ranks"]["count"], ranks);
        assert_eq!(s["status"], "completed");
        // the summary's account of the discs, reduced over the ranks: that
        // of one process, bitwise
        let one: serde_json::Value = serde_json::from_slice(&read("one", "summary.json")).unwrap();
        for k in [
            "discs",
            "energies",
            "contacts",
            "wall_forces",
            "critical_dt",
            "time",
        ] {
            assert_eq!(s[k], one[k], "{ranks} ranks: summary {k}");
        }
    }
    // a checkpoint written on 3 ranks continues on 2 (and on 1) as if
    // the run had never stopped
    let opts3 = efgdem::run::RunOptions {
        out_dir: dir.join("ck"),
        checkpoint_every: 2000,
        ..opts.clone()
    };
    on(3, &opts3);
    let ck = dir.join("ck").join("checkpoint.bin");
    let saved = std::fs::read(&ck).unwrap();
    for ranks in [2, 1] {
        std::fs::write(&ck, &saved).unwrap();
        let restart = efgdem::run::RunOptions {
            restart: Some(ck.clone()),
            checkpoint_every: 0,
            ..opts3.clone()
        };
        on(ranks, &restart);
        for f in ["history.csv", "discs_final.csv"] {
            assert!(
                read("one", f) == read("ck", f),
                "restart on {ranks}: {f} differs"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `settling(discs)` run for `steps` in one process, uninterrupted into
/// `one/` and with a checkpoint half way into `ck/` (rows every `every`
/// steps), in a fresh directory named after `tag`: the scenario, the
/// directory and the checkpointing run's options.
fn checkpointed(
    discs: usize,
    steps: usize,
    every: usize,
    tag: &str,
) -> (
    scenario::Scenario,
    std::path::PathBuf,
    efgdem::run::RunOptions,
) {
    let src = settling(discs).replace("steps = 1\n", &format!("steps = {steps}\n"))
        + &format!("[output]\nevery = {every}\n");
    let sc = scenario::parse(&src, "t.toml").unwrap_or_else(|e| panic!("{e}"));
    let dir = std::env::temp_dir().join(format!("efgdem-decomp-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut opts = efgdem::run::RunOptions::new(dir.join("one"));
    opts.quiet = true;
    efgdem::run::run(&sc, &opts).unwrap();
    let ck_opts = efgdem::run::RunOptions {
        out_dir: dir.join("ck"),
        checkpoint_every: steps / 2,
        ..opts
    };
    efgdem::run::run(&sc, &ck_opts).unwrap();
    (sc, dir, ck_opts)
}

/// A checkpoint written by one process continues on 3 ranks (each reads
/// only its part of it) as the uninterrupted run; a damaged one (a bit
/// flipped in the discs' arrays or in the header, cut short, extended) is
/// refused by every rank with rank 0's message, none waiting for another.
#[test]
fn a_checkpoint_is_read_in_parts_and_a_damaged_one_refused_by_every_rank() {
    let (sc, dir, ck_opts) = checkpointed(600, 600, 50, "ck");
    let ck = dir.join("ck").join("checkpoint.bin");
    let good = std::fs::read(&ck).unwrap();
    let history = std::fs::read(dir.join("ck/history.csv")).unwrap();
    let restart = efgdem::run::RunOptions {
        restart: Some(ck.clone()),
        checkpoint_every: 0,
        ..ck_opts.clone()
    };
    let on = |ranks: usize| -> Vec<Result<serde_json::Value, efgdem::run::RunError>> {
        std::thread::scope(|s| {
            let runs: Vec<_> = (Threads::group(ranks).into_iter())
                .map(|c| {
                    let (sc, restart) = (&sc, &restart);
                    s.spawn(move || efgdem::run::run_on(sc, restart, Arc::new(c)))
                })
                .collect();
            runs.into_iter().map(|r| r.join().unwrap()).collect()
        })
    };
    let n = good.len();
    let flip = |at: usize| {
        let mut b = good.clone();
        b[at] ^= 0x10;
        b
    };
    let damaged = [
        ("a bit of the arrays", flip(n - 100)),
        ("a bit of the header", flip(30)),
        ("cut short", good[..n - 1000].to_vec()),
        ("extended", [&good[..], &[0u8; 8]].concat()),
    ];
    for (what, bytes) in &damaged {
        std::fs::write(&ck, bytes).unwrap();
        let got = on(3);
        let first = got[0].as_ref().unwrap_err().to_string();
        println!("{what}: {first}");
        assert!(first.contains("damaged checkpoint"), "{what}: {first}");
        for (rank, r) in got.iter().enumerate() {
            match r {
                Err(e @ efgdem::run::RunError::Restart { .. }) => {
                    assert_eq!(e.to_string(), first, "{what}: rank {rank}")
                }
                other => panic!("{what}: rank {rank}: {other:?}"),
            }
        }
        // refused before anything was written
        assert!(std::fs::read(dir.join("ck/history.csv")).unwrap() == history);
    }
    std::fs::write(&ck, &good).unwrap();
    on(3).into_iter().for_each(|r| drop(r.unwrap()));
    let read = |d: &str, f: &str| std::fs::read(dir.join(d).join(f)).unwrap();
    for f in ["history.csv", "discs_final.csv"] {
        assert!(read("one", f) == read("ck", f), "restart on 3: {f} differs");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two discs checkpointed by one process continue on 3 ranks (one rank
/// holds none) as the uninterrupted run.
#[test]
fn a_restart_on_more_ranks_than_discs() {
    let (sc, dir, ck_opts) = checkpointed(2, 300, 10, "few");
    let restart = efgdem::run::RunOptions {
        restart: Some(dir.join("ck/checkpoint.bin")),
        checkpoint_every: 0,
        ..ck_opts.clone()
    };
    std::thread::scope(|s| {
        for c in Threads::group(3) {
            let (sc, restart) = (&sc, &restart);
            s.spawn(move || efgdem::run::run_on(sc, restart, Arc::new(c)).unwrap());
        }
    });
    let read = |d: &str, f: &str| std::fs::read(dir.join(d).join(f)).unwrap();
    for f in ["history.csv", "discs_final.csv"] {
        assert!(read("one", f) == read("ck", f), "{f} differs");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A build without the `mpi` feature started as one of several MPI ranks
/// (as mpirun sets its environment) refuses to run and says how to build
/// with MPI, instead of N copies each running the whole scenario.
#[cfg(not(feature = "mpi"))]
#[test]
fn a_build_without_mpi_refuses_mpirun() {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .args(["run", "no-such.toml", "-q"])
        .env("OMPI_COMM_WORLD_SIZE", "2")
        .env("OMPI_COMM_WORLD_RANK", "0")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--features mpi"), "{err}");
}

/// A bonded scenario on several ranks is refused before any step (exit
/// code 2, a message that says to run it in one process) on every rank,
/// instead of a run whose bonds would be lost at the division.
#[test]
fn bonded_discs_are_refused_on_ranks() {
    refused_on_ranks(include_str!("common/bonded_block.toml"), "bonds");
}

/// Clumps are not decomposed either: refused the same way.
#[test]
fn clumps_are_refused_on_ranks() {
    refused_on_ranks(include_str!("common/clump_pile.toml"), "clumps");
}

/// `src` run on 2 thread ranks: every rank refuses it with exit code 2,
/// saying to run it with one process, before writing anything.
fn refused_on_ranks(src: &str, what: &str) {
    let sc = scenario::parse(src, "b.toml").unwrap_or_else(|e| panic!("{e}"));
    let dir = std::env::temp_dir().join(format!("efgdem-decomp-{what}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut opts = efgdem::run::RunOptions::new(dir.clone());
    opts.quiet = true;
    let errs: Vec<_> = std::thread::scope(|s| {
        let runs: Vec<_> = Threads::group(2)
            .into_iter()
            .map(|c| {
                let (sc, opts) = (&sc, &opts);
                s.spawn(move || efgdem::run::run_on(sc, opts, Arc::new(c)).unwrap_err())
            })
            .collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    for e in errs {
        assert_eq!(e.exit_code(), 2, "{e}");
        assert!(e.to_string().contains("one process"), "{e}");
        assert!(e.to_string().contains(&format!("[{what}]")), "{e}");
    }
    assert!(!dir.join("history.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Run `sc` on one process into `dir/one`, then on each of `ranks` thread
/// ranks into `dir/ranksN`, and compare `history.csv` and
/// `discs_final.csv` byte for byte.
fn same_on_ranks(sc: &scenario::Scenario, dir: &std::path::Path, ranks: &[usize]) {
    let _ = std::fs::remove_dir_all(dir);
    let mut opts = efgdem::run::RunOptions::new(dir.join("one"));
    opts.quiet = true;
    efgdem::run::run(sc, &opts).unwrap_or_else(|e| panic!("{e}"));
    let read = |d: &str, f: &str| std::fs::read(dir.join(d).join(f)).unwrap();
    for &n in ranks {
        let name = format!("ranks{n}");
        let opts = efgdem::run::RunOptions {
            out_dir: dir.join(&name),
            ..opts.clone()
        };
        std::thread::scope(|s| {
            for c in Threads::group(n) {
                let opts = &opts;
                s.spawn(move || efgdem::run::run_on(sc, opts, Arc::new(c)).unwrap());
            }
        });
        for f in ["history.csv", "discs_final.csv"] {
            assert!(read("one", f) == read(&name, f), "{n} ranks: {f} differs");
        }
    }
}

/// Walls whose motion changes (`phases`: proportional servos to
/// consolidate, then a strain rate on the platens and integral servos on
/// the sides, a small biaxial test) around a packing grown by the
/// preparation, a `[[measure]]` region and wall probes: the files of one
/// process on 2 and 3 ranks. Then the settled discs as a CSV disc source
/// (its radii and ids as written) under a servo lid: the same.
#[test]
fn phased_walls_and_disc_sources_on_ranks() {
    let servo = "servo = { stress = 1.0e5, max_velocity = 0.1, relaxation = 1.0 }";
    let pi = "servo = { stress = 1.0e5, max_velocity = 0.1, relaxation = 1.0, integral = 0.1 }";
    let wall = |name: &str, from: [f64; 2], to: [f64; 2], phases: &str| {
        format!(
            "[[wall]]\nname = \"{name}\"\nfrom = {from:?}\nto = {to:?}\nphases = [{phases}]\n\n"
        )
    };
    let axial = format!("{{ until_step = 1500, {servo} }}, {{ strain_rate = 2.0 }}");
    let lateral = format!("{{ until_step = 1500, {servo} }}, {{ {pi} }}");
    let src = format!(
        r#"[simulation]
dt = 1.4e-6
steps = 3000

[output]
every = 100

[[material]]
name = "grain"
density = 2650.0
kn = 1.0e8
ks = 5.0e7
friction = 0.5
rolling_friction = 0.1

[granular]
material = "grain"
discs = {{ generate = "random", method = "grow", box = [[0.0, 0.0], [0.024, 0.048]], radius = [0.0005, 0.001], count = 400, seed = 3, settle_steps = 3000 }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}

{}{}{}{}[[measure]]
name = "all"
rectangle = [[-0.01, -0.01], [0.034, 0.058]]
quantities = ["sxx_cpos", "syy_cpos", "porosity"]

[[probe]]
name = "sl"
wall = "left"
quantity = "wall_stress"

[[probe]]
name = "yt"
wall = "top"
quantity = "wall_y"
"#,
        wall("bottom", [0.0, 0.0], [0.024, 0.0], &axial),
        wall("top", [0.0, 0.048], [0.024, 0.048], &axial),
        wall("left", [0.0, 0.0], [0.0, 0.048], &lateral),
        wall("right", [0.024, 0.0], [0.024, 0.048], &lateral),
    );
    let dir = std::env::temp_dir().join(format!("efgdem-decomp-phases-{}", std::process::id()));
    let sc = scenario::parse(&src, "phases.toml").unwrap_or_else(|e| panic!("{e}"));
    same_on_ranks(&sc, &dir.join("phases"), &[2, 3]);
    // the sheared sample as a CSV disc source
    let csv = dir.join("bed.csv");
    std::fs::copy(dir.join("phases/one/discs_final.csv"), &csv).unwrap();
    let src = format!(
        r#"[simulation]
steps = 1500
gravity = [0.0, -9.81]

[output]
every = 100

[[material]]
name = "grain"
density = 2650.0
kn = 1.0e8
ks = 5.0e7
friction = 0.5
rolling_friction = 0.1

[granular]
material = "grain"
discs = {{ csv = {:?} }}
damping = {{ kind = "critical-ratio", zeta = 0.2 }}

[[wall]]
name = "floor"
from = [-0.01, -0.002]
to = [0.04, -0.002]

[[wall]]
name = "lid"
from = [-0.01, 0.06]
to = [0.04, 0.06]
servo = {{ stress = 5.0e4, max_velocity = 0.1 }}

[[probe]]
name = "lid_fy"
wall = "lid"
quantity = "wall_fy"
"#,
        csv.display().to_string()
    );
    let sc = scenario::parse(&src, "csv.toml").unwrap_or_else(|e| panic!("{e}"));
    same_on_ranks(&sc, &dir.join("csv"), &[2, 3]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The footing of `examples/hex_footing.toml` with friction and rolling
/// resistance ([`common::hex_footing`]), coupled by `coupling`.
fn coupled_model(coupling: &str) -> efgdem::model::Model {
    scenario::parse(&common::hex_footing(1, coupling), "t.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"))
}

/// A coupled model stepped on `ranks` thread-ranks (discs divided, the
/// discs near the bodies copied to every rank) equals the whole model
/// stepped alone, byte for byte: the saved model state (discs, pairs and
/// histories, walls, the body, the disc–body contacts) every `every`
/// steps, and the disc–body contacts the same on every rank.
fn coupled_bitwise(coupling: &str, ranks: usize, steps: usize, every: usize) {
    use efgdem::decomp::near_bodies::NearBodies;
    let mut single = coupled_model(coupling);
    let mut want = Vec::new();
    for s in 1..=steps {
        single.coupled_mut().unwrap().step().unwrap();
        single.step += 1;
        if s % every == 0 {
            want.push(postcard::to_stdvec(&single.save_state()).unwrap());
        }
    }
    let touching = single.coupled().unwrap().contacts.len();
    assert!(touching >= 5, "the footing touches {touching} discs");
    let comms = Threads::group(ranks);
    let got: Vec<(Vec<Vec<u8>>, Vec<u8>)> = std::thread::scope(|sc| {
        let hs: Vec<_> = comms
            .into_iter()
            .map(|c| {
                // each rank its own worker pool, as each MPI process has:
                // a collective inside the exact step's join must not wait
                // for a rank whose closure queues behind it in a shared pool
                let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build();
                sc.spawn(move || {
                    pool.unwrap().install(|| {
                        let comm: Arc<dyn Comm> = Arc::new(c);
                        let mut model = coupled_model(coupling);
                        let m = model.coupled_mut().unwrap();
                        let d = Decomposed::new(&m.granular, comm);
                        let (mut nb, mut whole) = NearBodies::new(d, m);
                        let mut out = Vec::new();
                        for s in 1..=steps {
                            let m = model.coupled_mut().unwrap();
                            nb.set_zone(&m.bodies);
                            m.step_with(&mut nb).unwrap();
                            model.step += 1;
                            assert!(nb.outcome.0);
                            if s % every == 0
                                && let Some(st) = nb.d.gather()
                            {
                                whole.restore_state(&st).unwrap();
                                let m = model.coupled_mut().unwrap();
                                std::mem::swap(&mut m.granular, &mut whole);
                                out.push(postcard::to_stdvec(&model.save_state()).unwrap());
                                let m = model.coupled_mut().unwrap();
                                std::mem::swap(&mut m.granular, &mut whole);
                            }
                        }
                        let contacts = postcard::to_stdvec(&model.coupled().unwrap().contacts);
                        (out, contacts.unwrap())
                    })
                })
            })
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let (root, _) = &got[0];
    assert_eq!(root.len(), want.len());
    for (k, (a, b)) in root.iter().zip(&want).enumerate() {
        assert!(
            a == b,
            "{coupling:?}, {ranks} ranks: the model after {} steps differs from the whole",
            (k + 1) * every
        );
    }
    for (r, (_, c)) in got.iter().enumerate() {
        assert_eq!(c, &got[0].1, "rank {r}'s disc–body contacts differ");
    }
}

/// The exact (implicit) scheme: 1600 steps, the footing pushing into the
/// bed from step 1000 on; 1–3 ranks.
#[test]
fn coupled_exact_scheme_on_ranks_is_bitwise_the_whole() {
    for ranks in 1..=3 {
        coupled_bitwise("", ranks, 1600, 400);
    }
}

/// The compliant sub-cycled scheme (10 DEM steps per body step): 1–3 ranks.
#[test]
fn coupled_compliant_scheme_on_ranks_is_bitwise_the_whole() {
    for ranks in 1..=3 {
        coupled_bitwise("substeps = 10\ncoupling = \"compliant\"", ranks, 1600, 400);
    }
}

/// A rank's part built alone (`Scenario::build_part`: only the discs the
/// cut keeps are made, the whole never listed as rows) is bitwise the
/// share `Decomposed::new` takes of the whole built on every rank: the
/// same discs with the same ids, keys, constants and ghost flags, the
/// same time step, the whole's critical step; and on several ranks it
/// holds fewer discs than the whole. On 1–4 ranks, for a generated
/// packing, the same inside a `keep` circle, and discs given as rows.
#[test]
fn a_part_built_alone_is_the_share_of_the_whole() {
    let generated = settling(1200);
    let circle = generated.replace(
        "material = \"sand\"\n",
        "material = \"sand\"\nkeep = { centre = [0.1, 0.15], radius = 0.12 }\n",
    );
    assert_ne!(circle, generated);
    let whole = build(&generated);
    let rows: Vec<String> = (whole.particles.pos.iter().zip(&whole.particles.radius))
        .map(|(q, r)| format!("[{:?}, {:?}, {r:?}]", q.x, q.y))
        .collect();
    let start = generated.find("discs = {").unwrap();
    let end = start + generated[start..].find('\n').unwrap();
    let inline = format!(
        "{}discs = [{}]{}",
        &generated[..start],
        rows.join(", "),
        &generated[end..]
    );
    for src in [generated, circle, inline] {
        for ranks in 1..=4 {
            part_alone_is_the_share(&src, ranks);
        }
    }
}

/// A bad start state is refused on 2–4 thread ranks, each rank building
/// its part alone, with the message of one process (`file:line: field:
/// message`): overlapping pairs in several regions (more than the five
/// listed), a disc crossing a wall, a wall through a generated packing, a
/// wall too fast for the smallest disc, a time step above the critical
/// step.
#[test]
fn a_bad_start_is_refused_on_ranks_as_in_one_process() {
    let generated = settling(1200);
    let whole = build(&generated);
    let p = &whole.particles;
    // discs 2, 152, 302, … moved onto their neighbour, disc 900
    // onto the floor
    let rows = |crossing: bool| -> Vec<String> {
        (0..p.len())
            .map(|k| {
                let mut q = p.pos[k];
                if k % 150 == 1 {
                    q = p.pos[k - 1] + efgdem::geom::Vec2::new(0.001, 0.0);
                }
                if crossing && k == 899 {
                    q.y = 0.001;
                }
                format!("[{:?}, {:?}, {:?}]", q.x, q.y, p.radius[k])
            })
            .collect()
    };
    let start = generated.find("discs = {").unwrap();
    let end = start + generated[start..].find('\n').unwrap();
    let inline = |rows: Vec<String>| {
        format!(
            "{}discs = [{}]{}",
            &generated[..start],
            rows.join(", "),
            &generated[end..]
        )
    };
    let wall = "[[wall]]\nname = \"cutter\"\nfrom = [0.1, -0.05]\nto = [0.1, 0.35]\n";
    let through = generated.replacen("[[wall]]", &format!("{wall}\n[[wall]]"), 1);
    let fast = generated.replace("[simulation]\n", "[simulation]\ndt = 1.0e-3\n");
    let cases = [
        (
            inline(rows(false)),
            "granular.discs",
            "pair(s) of discs overlap",
        ),
        (
            inline(rows(true)),
            "granular.discs",
            "pair(s) of discs overlap",
        ),
        (through, "wall[0]", "cross wall `cutter`"),
        (fast.clone(), "wall[3].servo.max_velocity", "would move"),
        (
            fast.replace("max_velocity = 0.5", "max_velocity = 0.001"),
            "simulation.dt",
            "is above",
        ),
    ];
    for (k, (src, field, what)) in cases.iter().enumerate() {
        let sc = scenario::parse(src, "t.toml").unwrap();
        let dir = std::env::temp_dir().join(format!("efgdem-bad-{k}-{}", std::process::id()));
        let mut opts = efgdem::run::RunOptions::new(dir.clone());
        opts.quiet = true;
        let one = sc.build().err().map(|e| e.to_string());
        let one = one.unwrap_or_else(|| panic!("case {k} builds"));
        assert!(
            one.contains(&format!("{field}: ")) && one.contains(what),
            "{one}"
        );
        for ranks in 2..=4 {
            let errs: Vec<String> = std::thread::scope(|s| {
                let runs: Vec<_> = Threads::group(ranks)
                    .into_iter()
                    .map(|c| {
                        let (sc, opts) = (&sc, &opts);
                        s.spawn(move || {
                            let e = efgdem::run::run_on(sc, opts, Arc::new(c)).unwrap_err();
                            assert_eq!(e.exit_code(), 2, "{e}");
                            e.to_string()
                        })
                    })
                    .collect();
                runs.into_iter().map(|r| r.join().unwrap()).collect()
            });
            for e in errs {
                assert!(
                    e.contains(&one),
                    "case {k}, {ranks} ranks: {e}\nvs one process: {one}"
                );
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// [`a_part_built_alone_is_the_share_of_the_whole`] for scenario `src` on
/// `ranks` ranks.
fn part_alone_is_the_share(src: &str, ranks: usize) {
    let sc = scenario::parse(src, "t.toml").unwrap();
    let whole = build(src);
    let crit = whole.critical_step(&[]);
    {
        std::thread::scope(|s| {
            for c in Threads::group(ranks) {
                let (sc, whole, crit) = (&sc, &whole, &crit);
                s.spawn(move || {
                    let comm: Arc<dyn Comm> = Arc::new(c);
                    let share = Decomposed::new(whole, comm.clone());
                    let (model, cut) = sc
                        .build_part(None, &*comm)
                        .unwrap()
                        .expect("a granular scenario is built in parts");
                    let mut g = model.into_granular().unwrap();
                    assert_eq!(g.dt.to_bits(), whole.dt.to_bits());
                    let alone = Decomposed::from_part(&mut g, cut, comm);
                    let (a, b) = (&share.part.particles, &alone.part.particles);
                    assert!(ranks == 1 || b.len() < whole.particles.len());
                    assert_eq!(share.keys(), alone.keys());
                    assert_eq!(a.id, b.id);
                    assert_eq!(a.slot, b.slot);
                    assert_eq!(a.fixity, b.fixity);
                    assert_eq!(a.material, b.material);
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    let xy = |v: &[efgdem::geom::Vec2]| {
                        v.iter()
                            .flat_map(|q| [q.x.to_bits(), q.y.to_bits()])
                            .collect::<Vec<_>>()
                    };
                    assert_eq!(xy(&a.pos), xy(&b.pos));
                    assert_eq!(xy(&a.vel), xy(&b.vel));
                    for (x, y) in [
                        (&a.radius, &b.radius),
                        (&a.mass, &b.mass),
                        (&a.inertia, &b.inertia),
                        (&a.inv_mass, &b.inv_mass),
                        (&a.inv_inertia, &b.inv_inertia),
                    ] {
                        assert_eq!(bits(x), bits(y));
                    }
                    assert_eq!(
                        share.part.grid.skin.to_bits(),
                        alone.part.grid.skin.to_bits()
                    );
                    let (got, _) = alone.critical_step(&[]);
                    assert_eq!(got.dt.to_bits(), crit.dt.to_bits());
                    assert_eq!(got.certain.to_bits(), crit.certain.to_bits());
                    assert_eq!(got.mode, crit.mode);
                });
            }
        });
    }
}
