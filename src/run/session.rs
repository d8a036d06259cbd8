//! What every time-stepped run shares, whatever it simulates: the output
//! directory, the step loop's end (completed, interrupted by a signal,
//! unstable), progress and checkpoints.

use super::checkpoint::{self, Checkpoint};
use super::progress::Progress;
use super::{Run, RunError, RunOptions};
use crate::model::{Instability, Model, ModelError};
use crate::output::csv::HistoryWriter;
use crate::output::frames::Frames;
use serde::Serialize;
use serde_json::{Value, json};
use std::path::Path;
use std::sync::atomic::Ordering;

/// Files and directories a run writes into its output directory (the
/// `.pvd`/`.vtu` series by suffix): what `--overwrite` clears.
const OWN_FILES: [&str; 4] = [
    "history.csv",
    "summary.json",
    "discs_final.csv",
    "checkpoint.bin",
];

/// The file that marks an output directory as held by a run: locked
/// (`flock`) for as long as the run lasts, with the holder's process id in
/// it. The kernel releases the lock when the process ends, however it
/// ends, so a lock file left by a killed run is stale and simply taken
/// over; the file itself stays (removing it would race with the next run).
pub const LOCK_FILE: &str = ".efgdem.lock";

/// An output directory held by this run (released on drop).
#[derive(Debug)]
pub(super) struct DirLock(#[allow(dead_code)] Option<std::fs::File>);

/// Lock `f` for this process without waiting (`flock`, exclusive):
/// whether it is held now (`false`: another process holds it); `None` on
/// a file system without locks.
#[cfg(unix)]
fn try_flock(f: &std::fs::File) -> std::io::Result<Option<bool>> {
    use std::os::fd::AsRawFd;
    // SAFETY: flock on the descriptor `f` owns for as long as it lives
    if unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } == 0 {
        return Ok(Some(true));
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EWOULDBLOCK) => Ok(Some(false)),
        Some(libc::ENOLCK | libc::EOPNOTSUPP | libc::ENOSYS) => Ok(None),
        _ => Err(e),
    }
}

#[cfg(not(unix))]
fn try_flock(_: &std::fs::File) -> std::io::Result<Option<bool>> {
    Ok(None)
}

/// Hold `dir` for this run: refused with [`RunError::Busy`] while another
/// run (of this or another process) holds it.
fn lock_dir(dir: &Path) -> Result<DirLock, RunError> {
    use std::io::{Read, Seek, Write};
    let path = dir.join(LOCK_FILE);
    let io = |error| RunError::OutDir {
        path: dir.to_path_buf(),
        error,
    };
    let mut f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(|e| io(crate::output::io_at(&path, e)))?;
    // a process forked by this one keeps the lock until it executes its
    // program (a moment): ask again for a second before calling it busy
    let lock = || try_flock(&f).map_err(|e| io(crate::output::io_at(&path, e)));
    let mut held = lock()?;
    for _ in 0..20 {
        if held != Some(false) {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
        held = lock()?;
    }
    match held {
        Some(true) => {}
        Some(false) => {
            let mut text = String::new();
            let _ = f.read_to_string(&mut text);
            return Err(RunError::Busy {
                path: dir.to_path_buf(),
                holder: text.trim().parse().ok(),
            });
        }
        // a file system without locks: run unguarded, as before
        None => return Ok(DirLock(None)),
    }
    f.set_len(0)
        .and_then(|_| f.rewind())
        .and_then(|_| writeln!(f, "{}", std::process::id()))
        .map_err(|e| io(crate::output::io_at(&path, e)))?;
    Ok(DirLock(Some(f)))
}

/// Make the output directory ready and hold it for this run ([`LOCK_FILE`]):
/// created if missing; a non-empty one is refused unless `overwrite`, which
/// removes the files a run writes there (and nothing else). A restart
/// continues the outputs already there. A directory another run holds is
/// refused, whatever the options.
pub(super) fn prepare_out_dir(opts: &RunOptions) -> Result<DirLock, RunError> {
    let dir = &opts.out_dir;
    let io = |error| RunError::OutDir {
        path: dir.clone(),
        error,
    };
    if opts.restart.is_some() {
        if !dir.join("history.csv").is_file() {
            return Err(RunError::Restart {
                path: opts.restart.clone().unwrap_or_default(),
                message: format!(
                    "{} has no history.csv to continue: restart into the directory of the stopped run (-o)",
                    dir.display()
                ),
            });
        }
        return lock_dir(dir);
    }
    std::fs::create_dir_all(dir).map_err(io)?;
    let lock = lock_dir(dir)?;
    let entries: Vec<_> = std::fs::read_dir(dir)
        .map_err(io)?
        .collect::<Result<Vec<_>, _>>()
        .map_err(io)?
        .into_iter()
        .filter(|e| e.file_name() != LOCK_FILE)
        .collect();
    if entries.is_empty() {
        return Ok(lock);
    }
    if !opts.overwrite {
        return Err(RunError::NotEmpty(dir.clone()));
    }
    for e in entries {
        let name = e.file_name().to_string_lossy().into_owned();
        let path = e.path();
        let own = OWN_FILES.contains(&name.as_str())
            || [".pvd", ".vtu", ".tmp"].iter().any(|s| name.ends_with(s));
        if name == "frames" && path.is_dir() {
            std::fs::remove_dir_all(&path).map_err(io)?;
        } else if own && path.is_file() {
            std::fs::remove_file(&path).map_err(io)?;
        }
    }
    Ok(lock)
}

/// Is an output with period `every` (0: never) due at `step` of `steps`?
/// Every `every` steps and at the last step.
pub(super) fn due(step: usize, every: usize, steps: usize) -> bool {
    every > 0 && (step.is_multiple_of(every) || step == steps)
}

/// Is a periodic checkpoint (`checkpoint_every`, 0: none) due after
/// `step` of `steps`? Not at the last step (the run is then complete).
pub(super) fn checkpoint_due(step: usize, every: usize, steps: usize) -> bool {
    every > 0 && step.is_multiple_of(every) && step < steps
}

/// How a run's step loop ended.
#[derive(Debug)]
pub(super) enum Ended {
    /// Every step was taken.
    Completed,
    /// A stop was requested (the signal number) after the last step taken.
    Interrupted(usize),
    /// The state stopped being physical; the last step is not recorded.
    Unstable(Box<Instability>),
    /// Another numerical failure of a step ([`ModelError::is_numerical`]:
    /// a sub-cycled body that creates energy, a contact solve that does
    /// not converge); the failed step is not recorded.
    Failed(Box<ModelError>),
}

impl Ended {
    /// Record the end in the run's summary: `status`, `last_step` and the
    /// signal or instability.
    pub fn record(&self, summary: &mut Value, model: &Model) {
        summary["last_step"] = json!(model.step);
        // measured, not estimated: the process's peak resident memory
        let peak = super::memory::peak_resident_bytes();
        summary["peak_memory_bytes"] = json!(peak);
        summary["memory_bytes"] = json!(super::memory::resident_bytes());
        if let (Some(peak), Some(g)) = (peak, model.granular()) {
            let n = g.particles.len().max(1);
            summary["peak_bytes_per_disc"] = json!(peak as f64 / n as f64);
        }
        summary["status"] = json!(match self {
            Ended::Completed => "completed",
            Ended::Interrupted(_) => "interrupted",
            Ended::Unstable(_) | Ended::Failed(_) => "unstable",
        });
        match self {
            Ended::Completed => {}
            Ended::Interrupted(sig) => {
                summary["signal"] = json!(sig);
                summary["checkpoint"] = json!(checkpoint::FILE);
            }
            Ended::Unstable(i) => summary["instability"] = json!(i),
            Ended::Failed(e) => summary["failure"] = json!(e.to_string()),
        }
    }

    /// The run's result once its outputs are complete.
    pub fn result(self, summary: Value, model: &Model, out_dir: &Path) -> Result<Value, RunError> {
        match self {
            Ended::Completed => Ok(summary),
            Ended::Interrupted(signal) => Err(RunError::Interrupted {
                signal,
                step: model.step,
                checkpoint: checkpoint::path(out_dir),
            }),
            Ended::Unstable(i) => Err(RunError::Model(ModelError::Unstable(i))),
            Ended::Failed(e) => Err(RunError::Model(*e)),
        }
    }
}

/// The files a time-stepped run streams: `history.csv` and the frames.
pub(super) struct Outputs {
    /// `history.csv`.
    pub hist: HistoryWriter,
    /// The ParaView frames and their series.
    pub frames: Frames,
}

impl Outputs {
    /// Fresh outputs with history `columns`, or, on a restart, the
    /// checkpointed ones continued (rows and frames written after the
    /// checkpoint are dropped: they are written again, identically).
    pub fn open(run: &Run, model: &Model, columns: &[&str]) -> Result<Self, RunError> {
        let dir = &run.opts.out_dir;
        let path = dir.join("history.csv");
        let mut frames = Frames::new(model, dir)?.with_format(run.sc.output.vtk_format);
        let hist = match &run.restart {
            Some(ck) => {
                // the outputs do not fit the checkpoint: a refused restart
                let refused = |e: std::io::Error| RunError::Restart {
                    path: run.opts.restart.clone().unwrap_or_default(),
                    message: e.to_string(),
                };
                frames.resume(ck.series.clone()).map_err(refused)?;
                HistoryWriter::resume(&path, columns, ck.history_bytes).map_err(refused)?
            }
            None => HistoryWriter::create(&path, columns)?,
        };
        Ok(Outputs { hist, frames })
    }
}

/// The step loop's companion: takes steps, shows progress, writes
/// checkpoints, watches for a stop request.
pub(super) struct Session<'a> {
    run: &'a Run<'a>,
    progress: Progress,
}

impl<'a> Session<'a> {
    /// A session for `model` from its present step to `model.steps`.
    pub fn new(run: &'a Run<'a>, model: &Model) -> Self {
        Session {
            run,
            progress: Progress::new(model.step, model.steps, run.opts.quiet),
        }
    }

    /// Take the next step; `Some` if the run ends instead (all steps done,
    /// or the step made the state unphysical). `defer`: nothing reads the
    /// bodies after this step, so an exact coupled step may leave their ends
    /// to the next step ([`Model::step_deferring`]); a step that ends the
    /// run never does.
    pub fn step(&mut self, model: &mut Model, defer: bool) -> Result<Option<Ended>, RunError> {
        if model.step >= model.steps {
            return Ok(Some(Ended::Completed));
        }
        let r = if defer && model.step + 1 < model.steps {
            model.step_deferring()
        } else {
            model.step()
        };
        let r = if r.is_err() { r.and(model.settle()) } else { r };
        self.run.last_step.set(model.step);
        for n in model.take_notices() {
            self.progress.warn(&format!("warning: {n}"));
        }
        match r {
            Ok(()) => Ok(None),
            Err(ModelError::Unstable(i)) => Ok(Some(Ended::Unstable(i))),
            Err(e) if e.is_numerical() => Ok(Some(Ended::Failed(Box::new(e)))),
            Err(e) => Err(e.into()),
        }
    }

    /// After a step and its outputs: progress, a checkpoint when due
    /// (`driver`: the driver's running values); `Some` if a stop was
    /// requested — a checkpoint is then written, and the run ends with its
    /// outputs complete.
    pub fn after_step(
        &mut self,
        model: &mut Model,
        out: &mut Outputs,
        driver: &impl Serialize,
    ) -> Result<Option<Ended>, RunError> {
        self.progress.update(model.step, model.time());
        let opts = self.run.opts;
        let signal = opts.stop.as_ref().map_or(0, |s| s.load(Ordering::Relaxed));
        if signal != 0 || checkpoint_due(model.step, opts.checkpoint_every, model.steps) {
            // a step left pending (the signal came after it) ends first
            if let Err(e) = model.settle() {
                return Ok(Some(Ended::Failed(Box::new(e))));
            }
            out.hist.flush()?;
            Checkpoint::new(
                self.run.sc,
                model,
                driver,
                out.hist.bytes(),
                out.frames.entries(),
            )
            .write(&checkpoint::path(&opts.out_dir))?;
        }
        Ok((signal != 0).then_some(Ended::Interrupted(signal)))
    }

    /// Clear the progress display.
    pub fn finish(&self) {
        self.progress.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overwrite_clears_only_the_runs_own_files() {
        let dir = std::env::temp_dir().join(format!("efgdem-outdir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut opts = RunOptions::new(&dir);
        drop(prepare_out_dir(&opts).unwrap());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::create_dir_all(dir.join("frames")).unwrap();
        for f in [
            "history.csv",
            "summary.json",
            "beam.pvd",
            "x.json.tmp",
            "frames/discs_0000000.vtp",
            "notes.txt",
        ] {
            std::fs::write(dir.join(f), "x").unwrap();
        }
        assert!(matches!(prepare_out_dir(&opts), Err(RunError::NotEmpty(_))));
        opts.overwrite = true;
        let held = prepare_out_dir(&opts).unwrap();
        // held: refused to another run, with or without --overwrite
        match prepare_out_dir(&opts) {
            Err(RunError::Busy { holder, .. }) => assert_eq!(holder, Some(std::process::id())),
            other => panic!("{other:?}"),
        }
        drop(held);
        let mut left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        assert_eq!(left, vec![LOCK_FILE, "notes.txt"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
