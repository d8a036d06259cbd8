//! A coupled run divided over ranks: each rank steps the discs of its
//! region and every body ([`NearBodies`]); rank 0 gathers the whole model
//! when an output is due (history rows, frames, checkpoints, the end),
//! writes every file from it, as the run on one rank does, bitwise, and
//! lets it go again.

use super::super::checkpoint::{self, Checkpoint};
use super::super::ranks::{self, Due, RankRun, Stepped};
use super::super::session::{Ended, Outputs};
use super::super::{Run, RunError};
use super::Running;
use crate::decomp::near_bodies::NearBodies;
use crate::decomp::{Comm, Decomposed};
use crate::dem::Granular;
use crate::model::{Model, ModelError, stability};
use serde_json::Value;
use std::sync::Arc;

/// A rank's share of a coupled run.
pub(super) struct OnRanks {
    nb: NearBodies,
    /// The whole assembly without its discs (its walls, laws, clock),
    /// into which rank 0 gathers the discs when an output is due.
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
        let (nb, whole) = NearBodies::new(d, m);
        let whole = whole.with_same_discs(Default::default());
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
    /// with [`release`](Self::release).
    fn gather_in(&mut self, model: &mut Model) {
        if let Some(whole) = self.nb.d.gather_whole(&self.whole) {
            self.whole = whole;
            self.swap(model);
        }
    }

    /// The model's discs near the bodies back in rank 0's model, the whole
    /// assembly let go.
    fn release(&mut self, model: &mut Model) {
        self.swap(model);
        self.whole = self.whole.with_same_discs(Default::default());
    }

    /// The step loop (collective, [`ranks::drive`]); `output` writes rank
    /// 0's outputs of the present step. Ends with the whole assembly in
    /// rank 0's model.
    pub fn drive(
        &mut self,
        run: &Run,
        model: &mut Model,
        r: &mut Running,
        out: Option<&mut Outputs>,
        output: &mut impl FnMut(&Model, &mut Running, &mut Outputs) -> Result<(), RunError>,
    ) -> Result<Ended, RunError> {
        let (steps, root) = (model.steps, self.root());
        let mut x = CoupledRanks {
            rk: self,
            run,
            model,
            r,
            out,
            output,
            whole_in: false,
        };
        let every = run.sc.output.every;
        let ended = ranks::drive(run, &mut x, (steps, every), root, Ok(()));
        let whole_in = x.whole_in;
        if !whole_in {
            self.gather_in(model);
        }
        self.record = ranks::ranks_record(&self.nb.d);
        ended
    }

    /// The `ranks` record of the summary, as made at the end of the run.
    pub fn record(&self) -> Value {
        self.record.clone()
    }
}

/// A coupled run on ranks as [`ranks::drive`] steps it.
struct CoupledRanks<'a, F> {
    rk: &'a mut OnRanks,
    run: &'a Run<'a>,
    model: &'a mut Model,
    r: &'a mut Running,
    /// Rank 0's files.
    out: Option<&'a mut Outputs>,
    /// Rank 0's outputs of the present step.
    output: &'a mut F,
    /// Rank 0's model holds the whole assembly (at an early end).
    whole_in: bool,
}

impl<F> RankRun for CoupledRanks<'_, F>
where
    F: FnMut(&Model, &mut Running, &mut Outputs) -> Result<(), RunError>,
{
    fn clock(&self) -> (usize, f64) {
        (self.model.step, self.model.time())
    }

    fn step(&mut self, flag: bool) -> Result<Stepped, RunError> {
        let nb = &mut self.rk.nb;
        nb.flag = flag;
        let m = self.model.coupled_mut().expect("a coupled model");
        nb.set_zone(&m.bodies);
        let res = m.step_with(nb);
        self.model.step += 1;
        let (clean, stop) = nb.outcome;
        if clean && res.is_ok() {
            return Ok(Stepped::Taken { stop });
        }
        // as the one-rank run: an unphysical state first, then the
        // coupling's error (the same on every rank)
        self.rk.gather_in(self.model);
        self.whole_in = true;
        let root = self.rk.root();
        if let Some(i) = root.then(|| stability::check(self.model).err()).flatten() {
            return Ok(Stepped::Ended(Ended::Unstable(Box::new(i))));
        }
        Ok(Stepped::Ended(match res.map_err(ModelError::from) {
            Ok(()) => Ended::Completed,
            Err(ModelError::Unstable(i)) => Ended::Unstable(i),
            Err(e) if e.is_numerical() => Ended::Failed(Box::new(e)),
            Err(e) => return Err(e.into()),
        }))
    }

    fn notices(&mut self) -> Vec<String> {
        self.model.take_notices()
    }

    fn after_step(&mut self, _: usize, due: Due) -> Result<(), RunError> {
        let (run, model, r) = (self.run, &mut *self.model, &mut *self.r);
        r.meter.after_step(&self.rk.nb.d.part);
        if due.any() {
            self.rk.gather_in(model);
        }
        // every step: the contact events
        let mut res = Ok(());
        if let Some(out) = self.out.as_deref_mut() {
            res = (self.output)(model, r, out);
            if due.checkpoint && res.is_ok() {
                res = out.hist.flush().map_err(RunError::from).and_then(|()| {
                    Checkpoint::new(run.sc, model, &*r, out.hist.bytes(), out.frames.entries())
                        .write(&checkpoint::path(&run.opts.out_dir))
                        .map_err(RunError::from)
                });
            }
        }
        if due.any() && self.rk.root() {
            self.rk.release(model);
        }
        res
    }
}
