//! `efgdem run` stopped by a real signal (issue 12): the run finishes its
//! step, writes complete outputs (whole CSV rows, no temporary files, a
//! valid `.pvd`), `summary.json` with `"status": "interrupted"` and a
//! checkpoint, and exits with 128 + signal; `--restart` continues it to
//! outputs byte-identical to an uninterrupted run. Also: a non-empty output
//! directory is refused (exit 2) unless `--overwrite`.
#![cfg(unix)]

#[allow(dead_code)]
mod common;
use common::{bin, run, run_with, summary, tmpdir};
use std::time::Duration;

/// ~1000 discs settling for 150 000 steps (several seconds even on a fast
/// machine: the signal, sent once the history has rows, must come well
/// before the end).
const PACKING: &str = r#"
[simulation]
steps = 150000
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[granular]
material = "sand"
discs = { generate = "hex", box = [[0.0, 0.0], [0.3, 0.24]], radius = [0.0035, 0.0045], jitter = 0.5, seed = 3 }
damping = { kind = "critical-ratio", zeta = 0.2 }

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.3, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 0.4]

[[wall]]
name = "right"
from = [0.3, 0.0]
to = [0.3, 0.4]

[[probe]]
name = "ke"
quantity = "kinetic"

[output]
every = 7
vtk_every = 3000
"#;

#[test]
fn a_signalled_run_stops_cleanly_and_restarts_bitwise() {
    let root = tmpdir("signals");
    let file = root.join("packing.toml");
    std::fs::write(&file, PACKING).unwrap();
    let whole = root.join("whole");
    run(&file, &whole);
    for (sig, name, code) in [(2, "INT", 130), (15, "TERM", 143)] {
        let out = root.join(format!("stopped-{name}"));
        let child = bin()
            .args([
                "run",
                file.to_str().unwrap(),
                "-q",
                "-o",
                out.to_str().unwrap(),
            ])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // stop it once it is stepping (its history has rows)
        let hist = out.join("history.csv");
        while std::fs::read_to_string(&hist).map_or(0, |s| s.lines().count()) < 3 {
            std::thread::sleep(Duration::from_millis(20));
        }
        std::thread::sleep(Duration::from_millis(200));
        let k = std::process::Command::new("kill")
            .args([format!("-{name}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(k.success());
        let o = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{stderr}");
        assert!(stderr.contains("--restart"), "{stderr}");
        let s = summary(&out);
        assert_eq!(s["status"], "interrupted");
        assert_eq!(s["signal"], sig);
        let last = s["last_step"].as_u64().unwrap();
        assert!(last > 0 && last < 150000, "stopped at {last}");
        // the results so far, on stdout as for a completed run
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(
            stdout.starts_with(&format!("granular run interrupted: {last} steps")),
            "{stdout}"
        );
        // whole rows only, the last one no later than the stop
        let text = std::fs::read_to_string(&hist).unwrap();
        assert!(text.ends_with('\n'));
        let last_row: u64 = text
            .lines()
            .last()
            .unwrap()
            .split(',')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(last_row <= last && last - last_row < 7);
        let pvd = std::fs::read_to_string(out.join("discs.pvd")).unwrap();
        assert!(pvd.trim_end().ends_with("</VTKFile>"));
        let tmp: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .chain(std::fs::read_dir(out.join("frames")).unwrap())
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .filter(|n| n.ends_with(".tmp"))
            .collect();
        assert!(tmp.is_empty(), "{tmp:?}");
        // continue: the same outputs as the uninterrupted run
        let ck = out.join("checkpoint.bin");
        let o = bin()
            .args([
                "run",
                file.to_str().unwrap(),
                "-q",
                "--restart",
                ck.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(summary(&out)["status"], "completed");
        for f in [
            "history.csv",
            "discs_final.csv",
            "discs.pvd",
            "frames/discs_0030000.vtp",
        ] {
            assert!(
                std::fs::read(whole.join(f)).unwrap() == std::fs::read(out.join(f)).unwrap(),
                "{f} differs after SIG{name} and restart"
            );
        }
    }
    // the directory of a finished run is refused, then replaced on request
    let o = run_with(&file, &whole, &[]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--overwrite"));
    std::fs::write(whole.join("notes.txt"), "mine").unwrap();
    let o = run_with(
        &file,
        &whole,
        &["--overwrite", "--checkpoint-every", "5000"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(whole.join("notes.txt").exists() && whole.join("checkpoint.bin").exists());
    std::fs::remove_dir_all(root).unwrap();
}
