//! Nothing lost and nothing silently wrong under a fault: damaged
//! checkpoints and model states are refused (every single-bit flip), a run
//! killed at any instant or whose disk fills leaves no file a reader of
//! ours accepts when it is not whole, and its restart is byte-identical to
//! a run that never stopped; an output directory is held by one run at a
//! time; standard output that fails, absurd thread counts, unbounded input
//! files and a process memory limit give a message and an exit code, not a
//! panic or a hang.
//!
//! The long campaigns run with `EFGDEM_KILL_N=200` (instants of SIGKILL,
//! default 12) and `EFGDEM_DISKFULL_N=100` (disk sizes, default 10).
#![cfg(unix)]

#[allow(dead_code)]
mod common;

use common::{bin, run_with, tmpdir};
use efgdem::model::ModelState;
use efgdem::output::csv::History;
use efgdem::run::{RunError, RunOptions};
use std::collections::BTreeMap;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A small settling packing: ~300 discs, 2 400 steps, history every 7
/// steps, frames every 300 (about a second of work).
const PACKING: &str = r#"
[simulation]
steps = 2400
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[granular]
material = "sand"
discs = { generate = "hex", box = [[0.0, 0.0], [0.15, 0.12]], radius = [0.0035, 0.0045], jitter = 0.5, seed = 3 }
damping = { kind = "critical-ratio", zeta = 0.2 }

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.15, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 0.3]

[[wall]]
name = "right"
from = [0.15, 0.0]
to = [0.15, 0.3]

[[probe]]
name = "ke"
quantity = "kinetic"

[output]
every = 7
vtk_every = 300
"#;

fn env_or(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// A deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: u64) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) % n.max(1)
    }
}

/// Every file under `dir` (relative path → bytes), `.tmp` files and the
/// lock file left out (no reader of ours opens them).
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries {
            let p = e.unwrap().path();
            let name = p.strip_prefix(root).unwrap().display().to_string();
            if p.is_dir() {
                walk(root, &p, out);
            } else if !name.ends_with(".tmp") && !name.ends_with(".efgdem.lock") {
                out.insert(name, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// The files a run writes that do not depend on timing.
fn deterministic(f: &BTreeMap<String, Vec<u8>>) -> BTreeMap<String, Vec<u8>> {
    f.iter()
        .filter(|(k, _)| !k.ends_with("summary.json") && !k.ends_with("checkpoint.bin"))
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect()
}

/// What a reader of ours makes of the outputs of a run that stopped
/// anyhow, against those of the whole run: every file it accepts is whole
/// (`history.csv` a prefix of whole rows, every other file identical to
/// the whole run's, or refused when read).
fn assert_no_partial_file_accepted(out: &Path, whole: &BTreeMap<String, Vec<u8>>, what: &str) {
    for (name, bytes) in files(out) {
        let text = String::from_utf8_lossy(&bytes);
        match name.as_str() {
            "history.csv" => {
                if let Ok(h) = History::parse(&text) {
                    assert!(
                        whole["history.csv"].starts_with(&bytes),
                        "{what}: history.csv is not a prefix of the whole run's"
                    );
                    assert!(text.is_empty() || text.ends_with('\n'), "{what}");
                    assert!(h.rows.iter().all(|r| r.len() == h.columns.len()));
                }
            }
            "summary.json" => {
                // written whole or not at all: it parses
                let s: serde_json::Value = serde_json::from_str(&text)
                    .unwrap_or_else(|e| panic!("{what}: summary.json: {e}\n{text}"));
                assert!(s["status"].is_string(), "{what}: {text}");
            }
            "checkpoint.bin" => {} // checked by the restart
            name if name.ends_with(".pvd") => {
                // a complete collection, whose frames exist and are whole
                assert!(
                    text.ends_with("</Collection>\n</VTKFile>\n"),
                    "{what}: {name} is cut:\n{text}"
                );
            }
            _ => {
                let reference = whole
                    .get(&name)
                    .unwrap_or_else(|| panic!("{what}: {name} is not a file of the whole run"));
                if name.ends_with(".csv") {
                    // a disc source must be whole to be read at all
                    let parsed = efgdem::scenario::generate::discs_from_csv(&text);
                    assert_eq!(parsed.is_ok(), &bytes == reference, "{what}: {name}");
                }
                assert!(
                    &bytes == reference,
                    "{what}: {name} differs from the whole run's"
                );
            }
        }
    }
}

fn packing(dir: &Path) -> PathBuf {
    let f = dir.join("packing.toml");
    std::fs::write(&f, PACKING).unwrap();
    f
}

/// If the stopped run in `out` left a checkpoint: restart it, and check
/// its outputs are those of the whole run, byte for byte. Whether it did.
fn restart_matches(file: &Path, out: &Path, whole: &BTreeMap<String, Vec<u8>>, what: &str) -> bool {
    if !out.join("checkpoint.bin").exists() || !out.join("history.csv").exists() {
        return false;
    }
    let o = bin()
        .args(["run", file.to_str().unwrap(), "-q", "--restart"])
        .arg(out.join("checkpoint.bin"))
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        deterministic(&files(out)) == *whole,
        "{what}: outputs differ after the restart"
    );
    true
}

#[test]
fn a_run_killed_at_any_instant_leaves_no_partial_file_and_restarts_bitwise() {
    let root = tmpdir("faults-kill");
    let file = packing(&root);
    let whole_dir = root.join("whole");
    let o = run_with(&file, &whole_dir, &["--checkpoint-every", "250"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let whole = deterministic(&files(&whole_dir));
    // how long a run takes here, to kill it anywhere in it
    let t0 = Instant::now();
    let o = run_with(&file, &root.join("timing"), &[]);
    assert!(o.status.success());
    let span = t0.elapsed().as_micros() as u64 + 1;
    let n = env_or("EFGDEM_KILL_N", 12);
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let (mut restarted, mut none) = (0, 0);
    for k in 0..n {
        let out = root.join(format!("killed{k}"));
        let mut child = bin()
            .args(["run", file.to_str().unwrap(), "-q", "-o"])
            .arg(&out)
            .args(["--checkpoint-every", "250"])
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_micros(rng.below(span)));
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();
        let what = format!("kill {k}");
        assert_no_partial_file_accepted(&out, &whole, &what);
        if restart_matches(&file, &out, &whole, &what) {
            restarted += 1;
        } else {
            none += 1;
        }
        let _ = std::fs::remove_dir_all(&out);
    }
    println!("{n} kills: {restarted} restarted bitwise, {none} before the first checkpoint");
    assert!(restarted > 0 || n < 5, "no kill after a checkpoint");
}

/// `cmd` with its files limited to `bytes` (`RLIMIT_FSIZE`; SIGXFSZ
/// ignored, so a write past it fails with EFBIG like a full disk).
fn file_size_limited(cmd: &mut Command, bytes: u64) -> &mut Command {
    // SAFETY: only async-signal-safe calls between fork and exec
    unsafe {
        cmd.pre_exec(move || {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let r = libc::rlimit {
                rlim_cur: bytes,
                rlim_max: bytes,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &r) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        })
    }
}

#[test]
fn a_full_disk_leaves_whole_files_names_the_file_and_restarts_bitwise() {
    let root = tmpdir("faults-full");
    let file = packing(&root);
    let whole_dir = root.join("whole");
    let o = run_with(&file, &whole_dir, &["--checkpoint-every", "250"]);
    assert!(o.status.success());
    let whole_files = files(&whole_dir);
    let whole = deterministic(&whole_files);
    let largest = whole_files.values().map(Vec::len).max().unwrap() as u64;
    let n = env_or("EFGDEM_DISKFULL_N", 10);
    let mut rng = Rng(0x2545_F491_4F6C_DD1D);
    let mut failed = 0;
    for k in 0..n {
        let limit = 1 + rng.below(largest);
        let out = root.join(format!("full{k}"));
        let o = file_size_limited(
            bin()
                .args(["run", file.to_str().unwrap(), "-q", "-o"])
                .arg(&out)
                .args(["--checkpoint-every", "250"]),
            limit,
        )
        .output()
        .unwrap();
        let what = format!("files limited to {limit} bytes");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{what}: {err}");
        if o.status.success() {
            continue; // every file fit
        }
        failed += 1;
        // exit 1, the file named once with the OS's words once
        assert_eq!(o.status.code(), Some(1), "{what}: {err}");
        assert_eq!(err.matches("File too large").count(), 1, "{what}: {err}");
        assert!(err.contains(out.to_str().unwrap()), "{what}: {err}");
        assert_no_partial_file_accepted(&out, &whole, &what);
        if let Ok(s) = std::fs::read_to_string(out.join("summary.json")) {
            let s: serde_json::Value = serde_json::from_str(&s).unwrap();
            assert_eq!(s["status"], "failed", "{what}");
        }
        restart_matches(&file, &out, &whole, &what);
    }
    println!("{n} file-size limits: {failed} runs failed cleanly");
    assert!(failed > 0 || n < 5);
}

/// The packing run for 300 steps.
fn short_packing() -> String {
    PACKING.replace("steps = 2400", "steps = 300")
}

/// A checkpoint of [`short_packing`] (written to `file`) at step 250 in
/// `dir`, and the run's options.
fn checkpointed(file: &Path, dir: &Path) -> (efgdem::scenario::Scenario, RunOptions) {
    std::fs::write(file, short_packing()).unwrap();
    let sc = efgdem::scenario::load(file).unwrap();
    let opts = RunOptions {
        quiet: true,
        checkpoint_every: 250,
        ..RunOptions::new(dir)
    };
    efgdem::run::run(&sc, &opts).unwrap();
    (sc, opts)
}

#[test]
fn every_single_bit_flip_of_a_checkpoint_is_refused() {
    let root = tmpdir("faults-flip");
    let (sc, opts) = checkpointed(&root.join("packing.toml"), &root.join("out"));
    let good = std::fs::read(opts.out_dir.join("checkpoint.bin")).unwrap();
    let before = std::fs::read(opts.out_dir.join("history.csv")).unwrap();
    let flipped = root.join("flipped.bin");
    let mut rng = Rng(0xDEAD_BEEF_CAFE_F00D);
    let n = env_or("EFGDEM_FLIPS_N", 1000);
    let restart = RunOptions {
        restart: Some(flipped.clone()),
        ..opts.clone()
    };
    for _ in 0..n {
        let bit = rng.below(8 * good.len() as u64);
        let mut bytes = good.clone();
        bytes[(bit / 8) as usize] ^= 1 << (bit % 8);
        std::fs::write(&flipped, &bytes).unwrap();
        match efgdem::run::run(&sc, &restart) {
            Err(e @ RunError::Restart { .. }) => {
                assert_eq!(e.exit_code(), 2);
                let m = e.to_string();
                assert!(
                    m.contains("damaged checkpoint")
                        || m.contains("not an efgdem checkpoint")
                        || m.contains("checkpoint format"),
                    "bit {bit}: {m}"
                );
            }
            other => panic!("bit {bit} of {}: {other:?}", good.len()),
        }
    }
    // refused before anything was written
    assert!(std::fs::read(opts.out_dir.join("history.csv")).unwrap() == before);
    // the intact one continues
    std::fs::write(&flipped, &good).unwrap();
    efgdem::run::run(&sc, &restart).unwrap();
}

#[test]
fn every_single_bit_flip_of_a_model_state_is_refused() {
    let sc = efgdem::scenario::parse(PACKING, "packing.toml").unwrap();
    let mut m = sc.build().unwrap();
    for _ in 0..20 {
        m.step().unwrap();
    }
    let good = m.save_state().to_bytes();
    let mut rng = Rng(12345);
    for _ in 0..1000 {
        let bit = rng.below(8 * good.len() as u64);
        let mut bytes = good.clone();
        bytes[(bit / 8) as usize] ^= 1 << (bit % 8);
        assert!(
            ModelState::from_bytes(&bytes).is_err(),
            "bit {bit} of {} accepted",
            good.len()
        );
    }
    // cut short
    for cut in [1, 4, 5, good.len() / 2, good.len() - 1] {
        assert!(ModelState::from_bytes(&good[..cut]).is_err());
    }
    assert!(ModelState::from_bytes(&good).is_ok());
}

#[test]
fn a_restart_whose_history_does_not_fit_is_refused_once_with_exit_2() {
    let root = tmpdir("faults-history");
    let file = root.join("packing.toml");
    let out = root.join("out");
    checkpointed(&file, &out);
    // history.csv cut below what the checkpoint recorded
    let h = std::fs::read(out.join("history.csv")).unwrap();
    std::fs::write(out.join("history.csv"), &h[..h.len() / 3]).unwrap();
    let o = bin()
        .args(["run", file.to_str().unwrap(), "-q", "--restart"])
        .arg(out.join("checkpoint.bin"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.matches("cannot restart from").count(), 1, "{err}");
    assert!(err.contains("shorter than the"), "{err}");
}

#[test]
fn an_output_directory_is_held_by_one_run_at_a_time() {
    let root = tmpdir("faults-lock");
    let file = root.join("long.toml");
    // endless on any machine: the run is killed below, and must still be
    // running when the second and third runs ask for its directory
    std::fs::write(&file, PACKING.replace("steps = 2400", "steps = 100000000")).unwrap();
    let out = root.join("out");
    let mut first = bin()
        .args(["run", file.to_str().unwrap(), "-q", "-o"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let hist = out.join("history.csv");
    let t0 = Instant::now();
    while std::fs::read_to_string(&hist).map_or(0, |s| s.lines().count()) < 3 {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the run did not start"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let frames_before = std::fs::read_dir(out.join("frames")).unwrap().count();
    for extra in [&[][..], &["--overwrite"][..]] {
        let o = run_with(&file, &out, extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.contains(&format!(
                "is in use by another efgdem run (process {})",
                first.id()
            )),
            "{err}"
        );
    }
    // nothing of the first run's was removed
    assert!(out.join("frames").is_dir());
    assert!(std::fs::read_dir(out.join("frames")).unwrap().count() >= frames_before);
    // killed: its lock is stale, and the directory can be taken over
    first.kill().unwrap();
    first.wait().unwrap();
    assert!(out.join(".efgdem.lock").exists());
    let short = packing(&root);
    let o = run_with(&short, &out, &["--overwrite"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn standard_output_that_fails_is_an_error_not_a_panic() {
    let root = tmpdir("faults-stdout");
    let file = packing(&root);
    // a full device: exit 1 with the OS's message
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = bin().arg("check").arg(&file).stdout(full).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("writing to standard output: No space left on device"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    // a pipe closed by its reader (`| head`): a quiet end
    let mut child = bin()
        .arg("check")
        .arg(&file)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(o.status.code(), Some(0), "{err}");
}

#[test]
fn a_thread_count_beyond_the_machine_is_lowered_with_a_warning() {
    let root = tmpdir("faults-threads");
    let file = root.join("short.toml");
    std::fs::write(&file, PACKING.replace("steps = 2400", "steps = 20")).unwrap();
    let t0 = Instant::now();
    let o = run_with(&file, &root.join("out"), &["--threads", "1000000000000"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(t0.elapsed() < Duration::from_secs(60));
    assert!(
        err.contains("warning: 1000000000000 threads asked for; this machine runs"),
        "{err}"
    );
    let cores = std::thread::available_parallelism().unwrap().get();
    assert_eq!(
        common::summary(&root.join("out"))["threads"],
        serde_json::json!(cores)
    );
}

#[test]
fn devices_and_endless_files_are_not_read_without_bound() {
    let root = tmpdir("faults-zero");
    let t0 = Instant::now();
    let o = bin().args(["check", "/dev/zero"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("/dev/zero: cannot read the scenario: a device, not a file"),
        "{err}"
    );
    // a discs file that never ends
    let file = root.join("zero.toml");
    std::fs::write(
        &file,
        PACKING.replace(
            r#"discs = { generate = "hex", box = [[0.0, 0.0], [0.15, 0.12]], radius = [0.0035, 0.0045], jitter = 0.5, seed = 3 }"#,
            r#"discs = { csv = "/dev/zero" }"#,
        ),
    )
    .unwrap();
    let o = bin().arg("check").arg(&file).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("granular.discs.csv: cannot read discs file /dev/zero: a device, not a file"),
        "{err}"
    );
    // a (sparse) scenario file larger than any scenario: refused unread
    let huge = root.join("huge.toml");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(efgdem::scenario::MAX_SCENARIO_BYTES + 1)
        .unwrap();
    let o = bin().arg("check").arg(&huge).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cannot read the scenario: larger than 256 MiB"),
        "{err}"
    );
    assert!(t0.elapsed() < Duration::from_secs(60));
}

#[test]
fn a_process_memory_limit_is_respected_before_anything_is_allocated() {
    let root = tmpdir("faults-ulimit");
    let file = root.join("big.toml");
    // ~2 million discs: ~0.8 GB estimated, under a 600 MB address space
    std::fs::write(
        &file,
        PACKING.replace(
            r#"box = [[0.0, 0.0], [0.15, 0.12]], radius = [0.0035, 0.0045], jitter = 0.5, seed = 3"#,
            r#"box = [[0.0, 0.0], [10.0, 10.0]], radius = 0.0035, seed = 3"#,
        ),
    )
    .unwrap();
    for cmd in ["check", "run"] {
        let mut c = bin();
        c.arg(cmd).arg(&file).current_dir(&root);
        if cmd == "run" {
            c.args(["-q", "-o"]).arg(root.join("out"));
        }
        // SAFETY: only async-signal-safe calls between fork and exec
        unsafe {
            c.pre_exec(|| {
                let r = libc::rlimit {
                    rlim_cur: 600 << 20,
                    rlim_max: 600 << 20,
                };
                if libc::setrlimit(libc::RLIMIT_AS, &r) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let o = c.output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {err}");
        assert!(
            err.contains("granular.discs: the run would need about")
                && err.contains("process limit (ulimit -v)"),
            "{cmd}: {err}"
        );
    }
}
