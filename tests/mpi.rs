//! `mpirun -np N efgdem run` (the `mpi` feature, a system MPI) writes the
//! outputs of the run on one process, byte for byte, for 1 to 3 ranks
//! (oversubscribed on a smaller machine) and 1 or 2 threads per rank:
//! `history.csv`, `discs_final.csv` and the ParaView frames — for 20 000
//! discs settling under a servo lid with rolling resistance, discs that
//! cross the regions' cuts again and again (a shaken column), a collapsing
//! column that makes the regions be cut again, granular checkpoints
//! written on 3 ranks and continued on 2 and the reverse (and one
//! process's on 2), and a coupled footing with the exact and the
//! compliant schemes. Run by `.ci/mpi`:
//! `cargo test --release --features mpi --test mpi`.
#![cfg(feature = "mpi")]

#[allow(dead_code)]
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

/// A history row every 100 steps (the lid's height, the floor's force,
/// kinetic energy, contacts), frames every 500.
const OUTPUTS: &str = r#"
[output]
every = 100
vtk_every = 500

[[probe]]
name = "lid_y"
quantity = "wall_y"
wall = "lid"

[[probe]]
name = "floor_fy"
quantity = "wall_fy"
wall = "floor"

[[probe]]
name = "kinetic"
quantity = "kinetic"

[[probe]]
name = "contacts"
quantity = "contacts"
"#;

fn efgdem(dir: &Path, out: &str, ranks: usize, threads: usize) -> std::process::Output {
    efgdem_with(dir, out, ranks, threads, &[])
}

/// [`efgdem`] with more arguments for `efgdem run`.
fn efgdem_with(
    dir: &Path,
    out: &str,
    ranks: usize,
    threads: usize,
    more: &[&str],
) -> std::process::Output {
    let bin = env!("CARGO_BIN_EXE_efgdem");
    let mut args: Vec<String> = Vec::new();
    let mut cmd = if ranks == 0 {
        Command::new(bin)
    } else {
        let mut c = Command::new("mpirun");
        c.args([
            "-np",
            &ranks.to_string(),
            "--oversubscribe",
            "--bind-to",
            "none",
        ]);
        // CI runs as root
        c.env("OMPI_ALLOW_RUN_AS_ROOT", "1");
        c.env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
        args.push(bin.to_string());
        c
    };
    args.extend(
        [
            "run",
            "s.toml",
            "-q",
            "-o",
            out,
            "--threads",
            &threads.to_string(),
        ]
        .map(String::from),
    );
    args.extend(more.iter().map(|a| a.to_string()));
    let o = cmd.args(&args).current_dir(dir).output().expect("mpirun");
    assert!(
        o.status.success(),
        "{ranks} ranks: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Every file under `dir` (relative path, bytes), `summary.json` (timings
/// and the ranks' records differ) and the directory lock (a process id)
/// aside.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if !["summary.json", ".efgdem.lock"]
                .map(std::ffi::OsStr::new)
                .contains(&p.file_name().unwrap())
            {
                out.push((
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

/// A fresh directory for the runs of test `tag`, with the scenario `sc`
/// as `s.toml`.
fn workdir(tag: &str, sc: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("efgdem-mpi-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("s.toml"), sc).unwrap();
    dir
}

/// `s.toml` in `dir` run by one process (`one`), then under mpirun as
/// each (ranks, threads) of `on`: every output file byte for byte that
/// of one process. Returns the files of one process and the summaries of
/// the runs on ranks.
fn as_one_process(
    dir: &Path,
    on: &[(usize, usize)],
) -> (Vec<(PathBuf, Vec<u8>)>, Vec<serde_json::Value>) {
    efgdem(dir, "one", 0, 1);
    let want = files(&dir.join("one"));
    let read = |out: &str| -> serde_json::Value {
        serde_json::from_slice(&std::fs::read(dir.join(out).join("summary.json")).unwrap()).unwrap()
    };
    let one = read("one");
    // granular runs: every disc is owned by one rank
    let discs = dir.join("one/discs_final.csv");
    let n = discs.exists().then(|| common::csv(&discs).1.len() as u64);
    let summaries = on
        .iter()
        .map(|&(ranks, threads)| {
            let out = format!("r{ranks}t{threads}");
            efgdem(dir, &out, ranks, threads);
            same_files(
                &dir.join(&out),
                &want,
                &format!("{ranks} ranks × {threads} threads"),
            );
            let s = read(&out);
            assert_eq!(s["status"], "completed");
            // the summary's physics as one process's: the probes' extremes,
            // the preparation (its cache read or written aside)
            assert_eq!(s["probes"], one["probes"], "{ranks} ranks: probes");
            for key in ["method", "steps", "discs"] {
                let p = &s["preparation"][key];
                assert_eq!(p, &one["preparation"][key], "{ranks} ranks: {key}");
            }
            if ranks > 1 {
                assert_eq!(s["ranks"]["count"], ranks);
                let per = s["ranks"]["per_rank"].as_array().unwrap();
                let owned: u64 = per.iter().map(|r| r["owned"].as_u64().unwrap()).sum();
                if let Some(n) = n {
                    assert_eq!(owned, n, "{ranks} ranks: discs owned");
                }
            }
            s
        })
        .collect();
    (want, summaries)
}

/// A checkpoint of `s.toml` in `dir` written at step `at` on `from`
/// ranks, continued on `to` ranks: the files of the uninterrupted run
/// `want`.
fn restarted(dir: &Path, want: &[(PathBuf, Vec<u8>)], at: usize, from: usize, to: usize) {
    let out = format!("ck{from}to{to}");
    efgdem_with(dir, &out, from, 1, &["--checkpoint-every", &at.to_string()]);
    let ck = dir.join(&out).join("checkpoint.bin");
    efgdem_with(dir, &out, to, 1, &["--restart", ck.to_str().unwrap()]);
    same_files(
        &dir.join(&out),
        want,
        &format!("checkpoint on {from} ranks, restarted on {to}"),
    );
}

/// 20 000 discs falling into a box 1.2 m × 0.7 m under a servo lid, with
/// rolling resistance (`common::settling`), `steps` steps, [`OUTPUTS`]:
/// the files of one process on 1, 2 and 3 ranks and on 2 ranks × 2
/// threads; a checkpoint at half way written on 3 ranks continues on 2,
/// and one written on 2 on 3, and one of one process on 2, as the
/// uninterrupted run. Returns the
/// history of one process.
fn settling_20000(tag: &str, steps: usize) -> common::Csv {
    let dir = workdir(tag, &(common::settling(20_000, steps, 1.2, 0.7) + OUTPUTS));
    let (want, _) = as_one_process(&dir, &[(1, 1), (2, 1), (3, 1), (2, 2)]);
    assert!(want.iter().any(|(p, _)| p.ends_with("discs_final.csv")));
    assert!(want.len() >= 4, "{want:?}");
    restarted(&dir, &want, steps / 2, 3, 2);
    restarted(&dir, &want, steps / 2, 2, 3);
    // one process (0: without mpirun) to 2 ranks, each reading its part
    restarted(&dir, &want, steps / 2, 0, 2);
    let hist = common::csv(&dir.join("one/history.csv"));
    let _ = std::fs::remove_dir_all(&dir);
    hist
}

#[test]
fn mpirun_writes_the_outputs_of_one_process() {
    settling_20000("settle", 2000);
}

/// [`mpirun_writes_the_outputs_of_one_process`] until the bed is at rest
/// under the lid (20 000 steps, 1 s).
#[test]
#[ignore]
fn mpirun_settles_20000_discs_as_one_process() {
    let hist = settling_20000("settle-full", 20_000);
    // at rest: the kinetic energy fell from its peak (600 J as the bed
    // lands) to 3·10⁻⁶ of it (0.0018 J), the lid held at 0.403 m
    let ek = common::column(&hist, "kinetic");
    let peak = ek.iter().copied().fold(0.0, f64::max);
    assert!(*ek.last().unwrap() < 1e-4 * peak, "{ek:?}");
    let lid = common::column(&hist, "lid_y");
    assert!(
        (lid[lid.len() - 1] - lid[lid.len() - 21]).abs() < 1e-4,
        "{lid:?}"
    );
}

/// A dense column shaken at 25 Hz (`common::shaken_column`): discs
/// change rank twice a period with their histories; 2 and 3 ranks write
/// the files of one process, and the discs did migrate with histories.
#[test]
fn mpirun_of_discs_crossing_regions_again_and_again() {
    let dir = workdir("shaken", &common::shaken_column(8000));
    let (_, sums) = as_one_process(&dir, &[(2, 1), (3, 1)]);
    for s in &sums {
        let per = s["ranks"]["per_rank"].as_array().unwrap();
        let sum = |k: &str| per.iter().map(|r| r[k].as_u64().unwrap()).sum::<u64>();
        println!(
            "{} arrivals, {} histories",
            sum("arrivals"),
            sum("histories_in")
        );
        assert!(sum("arrivals") >= 300, "{s}");
        assert!(sum("histories_in") >= sum("arrivals"), "{s}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A column collapsing to the right (`common::collapsing_column`) on 3
/// ranks: the regions are cut again as it runs out and the imbalance at
/// the end is within the threshold (0.1); the files of one process.
#[test]
fn mpirun_rebalances_a_collapsing_column() {
    let dir = workdir("collapse", &common::collapsing_column(5000));
    let (_, sums) = as_one_process(&dir, &[(3, 1)]);
    let r = &sums[0]["ranks"];
    println!("{r}");
    assert!(r["recuts"].as_u64().unwrap() >= 2, "{r}");
    assert!(r["imbalance"].as_f64().unwrap() <= 0.1, "{r}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Fewer discs than ranks: two discs on 3 ranks (one rank owns none)
/// run as in one process.
#[test]
fn mpirun_with_fewer_discs_than_ranks() {
    let dir = workdir("few", &(common::settling(2, 300, 0.2, 0.3) + OUTPUTS));
    as_one_process(&dir, &[(3, 1)]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A continuum scenario on several ranks is refused with exit code 2.
#[test]
fn mpirun_of_a_continuum_scenario_is_refused() {
    let sc = r#"
[simulation]
dt = 1.0e-3
steps = 10

[[body]]
name = "block"
rectangle = { origin = [0.0, 0.0], size = [1.0, 1.0] }
nodes = [4, 4]
elastic = { E = 1.0e7, nu = 0.3, density = 1000.0 }

[[body.bc]]
edge = "bottom"
fixed = true
"#;
    let err = refused_on_two_ranks("c", sc);
    assert!(err.contains("does not run on several ranks"), "{err}");
}

/// `efgdem run` of the scenario `sc` under `mpirun -np 2`: it must be
/// refused with exit code 2; its standard error.
fn refused_on_two_ranks(tag: &str, sc: &str) -> String {
    let dir = workdir(tag, sc);
    let o = Command::new("mpirun")
        .args(["-np", "2", "--oversubscribe"])
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .arg(env!("CARGO_BIN_EXE_efgdem"))
        .args(["run", "s.toml", "-q", "-o", "out"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
    err.into_owned()
}

fn same_files(got: &Path, want: &[(PathBuf, Vec<u8>)], what: &str) {
    let got: Vec<_> = files(got)
        .into_iter()
        .filter(|(p, _)| !p.ends_with("checkpoint.bin"))
        .collect();
    let names = |v: &[(PathBuf, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&got), names(want), "{what}: files");
    for ((p, a), (_, b)) in got.iter().zip(want) {
        assert!(a == b, "{what}: {} differs", p.display());
    }
}

/// The footing of `examples/hex_footing.toml` (friction and rolling
/// resistance in the bed; [`common::hex_footing`]) with the coupled scheme
/// `coupling`, 1500 steps (it touches the bed from step 1000 on), a history
/// row every 50 steps and frames every 500.
fn footing(coupling: &str) -> String {
    common::hex_footing(
        1500,
        &format!("{coupling}\n\n[output]\nevery = 50\nvtk_every = 500"),
    )
}

/// Coupled runs (the exact and the compliant sub-cycled schemes) under
/// mpirun write the files of one process, byte for byte, on 2 and 3 ranks;
/// a checkpoint written on 3 ranks continues on 2 as the uninterrupted
/// run.
#[test]
fn mpirun_of_coupled_scenarios_writes_the_outputs_of_one_process() {
    for (name, coupling) in [
        ("exact", ""),
        ("compliant", "substeps = 10\ncoupling = \"compliant\""),
    ] {
        let dir = workdir(name, &footing(coupling));
        let (want, _) = as_one_process(&dir, &[(2, 1), (3, 1)]);
        assert!(want.len() >= 4, "{want:?}");
        let s = common::summary(&dir.join("one"));
        assert_eq!(s["coupling"], name);
        assert!(s["peak_contact_force"].as_f64().unwrap() > 100.0, "{s}");
        // written on 3 ranks at step 1000, continued on 2
        restarted(&dir, &want, 1000, 3, 2);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The predicted sub-cycled scheme on several ranks is refused (exit code
/// 2) and says what runs.
#[test]
fn mpirun_of_the_predicted_scheme_is_refused() {
    let err = refused_on_two_ranks("p", &footing("substeps = 4\ncoupling = \"predicted\""));
    assert!(
        err.contains("predicted coupled scheme does not run on several ranks"),
        "{err}"
    );
    assert!(err.contains("compliant"), "{err}");
}
