//! `mpirun -np N efgdem run` (the `mpi` feature, a system MPI) writes the
//! outputs of the run on one process, byte for byte, for 1 to 3 ranks
//! (oversubscribed on a smaller machine) and 1 or 2 threads per rank:
//! `history.csv`, `discs_final.csv` and the ParaView frames. Run by
//! `.ci/mpi`: `cargo test --release --features mpi --test mpi`.
#![cfg(feature = "mpi")]

#[allow(dead_code)]
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

/// 3000 discs falling into a box under a servo lid, rolling resistance,
/// frames every 500 steps.
const SCENARIO: &str = r#"
[simulation]
steps = 2000
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5
rolling_friction = 0.1

[granular]
material = "sand"
discs = { generate = "random", box = [[0.0, 0.0], [0.3, 0.5]], count = 3000, radius = [0.002, 0.003], seed = 9 }
damping = { kind = "critical-ratio", zeta = 0.2 }

[[wall]]
name = "floor"
from = [-0.01, 0.0]
to = [0.31, 0.0]

[[wall]]
name = "left"
from = [0.0, -0.01]
to = [0.0, 0.6]

[[wall]]
name = "right"
from = [0.3, -0.01]
to = [0.3, 0.6]

[[wall]]
name = "lid"
from = [-0.01, 0.5]
to = [0.31, 0.5]
servo = { stress = 2.0e3, max_velocity = 0.5 }

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

#[test]
fn mpirun_writes_the_outputs_of_one_process() {
    let dir = std::env::temp_dir().join(format!("efgdem-mpi-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("s.toml"), SCENARIO).unwrap();
    efgdem(&dir, "one", 0, 1);
    let want = files(&dir.join("one"));
    assert!(want.iter().any(|(p, _)| p.ends_with("discs_final.csv")));
    assert!(want.len() >= 4, "{want:?}");
    for (ranks, threads) in [(1, 1), (2, 1), (3, 1), (2, 2)] {
        let out = format!("r{ranks}t{threads}");
        efgdem(&dir, &out, ranks, threads);
        let got = files(&dir.join(&out));
        let names = |v: &[(PathBuf, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
        assert_eq!(names(&got), names(&want), "{ranks} ranks: files");
        for ((p, a), (_, b)) in got.iter().zip(&want) {
            assert!(
                a == b,
                "{ranks} ranks × {threads} threads: {} differs",
                p.display()
            );
        }
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join(&out).join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(s["status"], "completed");
        if ranks > 1 {
            assert_eq!(s["ranks"]["count"], ranks);
            let per: &Vec<serde_json::Value> = s["ranks"]["per_rank"].as_array().unwrap();
            let owned: u64 = per.iter().map(|r| r["owned"].as_u64().unwrap()).sum();
            assert_eq!(owned, 3000);
        }
    }
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
    let dir = std::env::temp_dir().join(format!("efgdem-mpi-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("s.toml"), sc).unwrap();
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
        let dir = std::env::temp_dir().join(format!("efgdem-mpi-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("s.toml"), footing(coupling)).unwrap();
        efgdem(&dir, "one", 0, 1);
        let want = files(&dir.join("one"));
        assert!(want.len() >= 4, "{want:?}");
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("one/summary.json")).unwrap()).unwrap();
        assert_eq!(s["coupling"], name);
        assert!(s["peak_contact_force"].as_f64().unwrap() > 100.0, "{s}");
        for ranks in [2, 3] {
            let out = format!("r{ranks}");
            efgdem(&dir, &out, ranks, 1);
            same_files(&dir.join(&out), &want, &format!("{name} on {ranks} ranks"));
        }
        // written on 3 ranks at step 1000, continued on 2
        efgdem_with(&dir, "ck", 3, 1, &["--checkpoint-every", "1000"]);
        let ck = dir.join("ck").join("checkpoint.bin");
        efgdem_with(&dir, "ck", 2, 1, &["--restart", ck.to_str().unwrap()]);
        same_files(
            &dir.join("ck"),
            &want,
            &format!("{name}: 3 ranks, restarted on 2"),
        );
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
