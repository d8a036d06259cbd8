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

/// Make the output directory ready: created if missing; a non-empty one is
/// refused unless `overwrite`, which removes the files a run writes there
/// (and nothing else). A restart continues the outputs already there.
pub(super) fn prepare_out_dir(opts: &RunOptions) -> Result<(), RunError> {
    let dir = &opts.out_dir;
    let io = |source| RunError::OutDir {
        path: dir.clone(),
        source,
    };
    if opts.restart.is_some() {
        return match dir.join("history.csv").is_file() {
            true => Ok(()),
            false => Err(io(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no history.csv to continue: restart into the directory of the stopped run (-o)",
            ))),
        };
    }
    std::fs::create_dir_all(dir).map_err(io)?;
    let entries: Vec<_> = std::fs::read_dir(dir)
        .map_err(io)?
        .collect::<Result<_, _>>()
        .map_err(io)?;
    if entries.is_empty() {
        return Ok(());
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
    Ok(())
}

/// Is an output with period `every` (0: never) due at `step` of `steps`?
/// Every `every` steps and at the last step.
pub(super) fn due(step: usize, every: usize, steps: usize) -> bool {
    every > 0 && (step.is_multiple_of(every) || step == steps)
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
                frames.resume(ck.series.clone())?;
                HistoryWriter::resume(&path, columns, ck.history_bytes)?
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
    /// or the step made the state unphysical).
    pub fn step(&mut self, model: &mut Model) -> Result<Option<Ended>, RunError> {
        if model.step >= model.steps {
            return Ok(Some(Ended::Completed));
        }
        match model.step() {
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
        model: &Model,
        out: &mut Outputs,
        driver: &impl Serialize,
    ) -> Result<Option<Ended>, RunError> {
        self.progress.update(model.step, model.time());
        let opts = self.run.opts;
        let signal = opts.stop.as_ref().map_or(0, |s| s.load(Ordering::Relaxed));
        let every = opts.checkpoint_every;
        if signal != 0
            || (every > 0 && model.step.is_multiple_of(every) && model.step < model.steps)
        {
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
        prepare_out_dir(&opts).unwrap();
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
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
        prepare_out_dir(&opts).unwrap();
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(left, vec!["notes.txt"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
