//! A coupled run divided over ranks: each rank steps the discs of its
//! region and every body ([`NearBodies`]); rank 0 gathers the whole model
//! when an output is due (history rows, frames, checkpoints, the end) and
//! writes every file from it, as the run on one rank does, bitwise.

use super::super::checkpoint::{self, Checkpoint};
use super::super::progress::Progress;
use super::super::session::{Ended, Outputs, checkpoint_due, due};
use super::super::{Run, RunError};
use super::Running;
use crate::decomp::near_bodies::NearBodies;
use crate::decomp::{Comm, Decomposed};
use crate::dem::Granular;
use crate::model::{Model, ModelError, stability};
use serde_json::Value;
use std::sync::Arc;
use std::sync::atomic::Ordering;

/// A rank's share of a coupled run.
pub(super) struct OnRanks {
    nb: NearBodies,
    /// Rank 0: the whole assembly, set to the gathered state when an
    /// output is due (the other ranks keep none).
    whole: Granular,
    /// Every rank's record for the summary (made at the end).
    record: Value,
}

impl OnRanks {
    /// Divide the discs of `model` (built or restored the same on every
    /// rank) over the ranks of `comm` (collective).
    pub fn new(model: &mut Model, comm: Arc<dyn Comm>) -> OnRanks {
        let m = model.coupled_mut().expect("a coupled model");
        m.granular.prepare_contacts();
        let d = Decomposed::new(&m.granular, comm.clone());
        let (nb, mut whole) = NearBodies::new(d, m);
        if comm.rank() != 0 {
            whole = whole.with_discs(Default::default());
        }
        OnRanks {
            nb,
            whole,
            record: Value::Null,
        }
    }

    fn root(&self) -> bool {
        self.nb.d.comm().rank() == 0
    }

    /// Exchange the model's discs (near the bodies) and the whole
    /// assembly.
    fn swap(&mut self, model: &mut Model) {
        let m = model.coupled_mut().expect("a coupled model");
        std::mem::swap(&mut m.granular, &mut self.whole);
    }

    /// Gather the whole assembly into rank 0's model (collective); undo
    /// with [`swap`](Self::swap).
    fn gather_in(&mut self, model: &mut Model) {
        if let Some(st) = self.nb.d.gather() {
            (self.whole.restore_state(&st)).expect("the gathered state fits the whole assembly");
            self.swap(model);
        }
    }

    /// The step loop (collective); `output` writes rank 0's outputs of the
    /// present step. Ends with the whole assembly in rank 0's model.
    pub fn drive(
        &mut self,
        run: &Run,
        model: &mut Model,
        r: &mut Running,
        mut out: Option<&mut Outputs>,
        output: &mut impl FnMut(&Model, &mut Running, &mut Outputs) -> Result<(), RunError>,
    ) -> Result<Ended, RunError> {
        let (opts, steps, root) = (run.opts, model.steps, self.root());
        let (every, vtk_every) = (run.sc.output.every, run.sc.output.vtk_every);
        let mut progress = Progress::new(model.step, steps, opts.quiet || !root);
        let mut failed: Option<RunError> = None;
        // rank 0's model holds the whole assembly
        let mut whole_in = false;
        let ended = loop {
            if model.step >= steps {
                break Ended::Completed;
            }
            let signal = opts.stop.as_ref().map_or(0, |s| s.load(Ordering::Relaxed));
            self.nb.flag = signal != 0 || failed.is_some();
            let m = model.coupled_mut().expect("a coupled model");
            self.nb.set_zone(&m.bodies);
            let res = m.step_with(&mut self.nb);
            model.step += 1;
            for n in model.take_notices() {
                if root {
                    progress.warn(&format!("warning: {n}"));
                }
            }
            let (clean, stop) = self.nb.outcome;
            if !clean || res.is_err() {
                // as the one-rank run: an unphysical state first, then the
                // coupling's error (the same on every rank)
                self.gather_in(model);
                whole_in = true;
                if let Some(i) = root.then(|| stability::check(model).err()).flatten() {
                    break Ended::Unstable(Box::new(i));
                }
                match res.map_err(ModelError::from) {
                    Ok(()) => break Ended::Completed,
                    Err(ModelError::Unstable(i)) => break Ended::Unstable(i),
                    Err(e) if e.is_numerical() => break Ended::Failed(Box::new(e)),
                    Err(e) => return Err(e.into()),
                }
            }
            r.meter.after_step(&self.nb.d.part);
            let step = model.step;
            let ck = stop || checkpoint_due(step, opts.checkpoint_every, steps);
            let need = due(step, every, steps) || due(step, vtk_every, steps) || ck;
            if need {
                self.gather_in(model);
            }
            if let Some(out) = out.as_deref_mut() {
                let mut res = output(model, r, out);
                if ck && res.is_ok() {
                    res = out.hist.flush().map_err(RunError::from).and_then(|()| {
                        Checkpoint::new(run.sc, model, &*r, out.hist.bytes(), out.frames.entries())
                            .write(&checkpoint::path(&opts.out_dir))
                            .map_err(RunError::from)
                    });
                }
                if let Err(e) = res {
                    failed.get_or_insert(e);
                }
            }
            if need && root {
                self.swap(model);
            }
            progress.update(step, model.time());
            run.last_step.set(step);
            if stop {
                // a stop that another rank saw: SIGINT, as mpirun forwards it
                break Ended::Interrupted(if signal != 0 { signal } else { 2 });
            }
        };
        progress.finish();
        if !whole_in {
            self.gather_in(model);
        }
        self.record = super::super::ranks::ranks_record(&self.nb.d);
        match failed {
            Some(e) => Err(e),
            None => Ok(ended),
        }
    }

    /// The `ranks` record of the summary, as made at the end of the run.
    pub fn record(&self) -> Value {
        self.record.clone()
    }
}
