//! Driver for granular scenarios on several ranks (MPI processes, or the
//! threads of a test): the assembly is divided over the ranks
//! ([`Decomposed`]). A history row is reduced from the ranks' shares of
//! each probe (exact sums, counts, the value of the disc's owner:
//! [`probe::share`]), without moving the discs; rank 0 keeps the whole
//! model, into which the ranks' parts are gathered only for frames,
//! checkpoints and the end (`discs_final.csv`, `summary.json`), and
//! writes every file. The outputs are those of the run on one rank,
//! bitwise.

use super::checkpoint::{self, Checkpoint};
use super::granular::{columns, granular, summary};
use super::progress::Progress;
use super::session::{Ended, Outputs, checkpoint_due, due};
use super::{Run, RunError};
use crate::decomp::{Comm, Decomposed};
use crate::model::probe::{self, Share};
use crate::model::{Model, ModelState, System, SystemState, stability};
use crate::output::csv::write_discs_csv;
use crate::output::write_json;
use serde_json::json;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Why the discs of `g` cannot be divided over ranks, if they cannot.
pub(super) fn discs_refusal(g: &crate::dem::Granular) -> Option<&'static str> {
    if g.bonds.active() {
        Some(
            "bonded discs ([bonds]) do not run on several ranks yet: run this scenario with one process",
        )
    } else if !g.clumps.is_empty() {
        Some(
            "clumps ([clumps]) do not run on several ranks yet: run this scenario with one process",
        )
    } else {
        None
    }
}

/// The exit code rank 0 ended with, known to every rank (collective): on
/// rank 0 `res` itself, on the others `Ok` or [`RunError::OnRank0`].
pub(super) fn agree<T: Default>(comm: &dyn Comm, res: Result<T, RunError>) -> Result<T, RunError> {
    let code = match &res {
        Ok(_) => 0,
        Err(e) => e.exit_code(),
    };
    let all = comm.all_gather(&[code]);
    match (comm.rank(), all[0][0]) {
        (0, _) => res,
        (_, 0) => Ok(T::default()),
        (_, code) => Err(RunError::OnRank0 { code }),
    }
}

/// Every rank's discs, ghosts, traffic and peak memory, with the count,
/// imbalance and recuts: the `ranks` record of rank 0's summary
/// (collective).
pub(super) fn ranks_record(d: &Decomposed) -> serde_json::Value {
    let t = d.comm().traffic();
    let mine = json!({
        "owned": d.owned(),
        "ghosts": d.ghosts(),
        "arrivals": d.arrivals,
        "histories_in": d.histories_in,
        "bytes_sent": t.bytes,
        "messages": t.messages,
        "communication_seconds": t.seconds,
        "step_bytes_sent": d.stepping.bytes,
        "step_messages": d.stepping.messages,
        "peak_memory_bytes": super::memory::peak_resident_bytes(),
        "memory_bytes": super::memory::resident_bytes(),
    });
    let all = d.comm().all_gather(mine.to_string().as_bytes());
    let per_rank: Vec<serde_json::Value> = all
        .iter()
        .map(|b| serde_json::from_slice(b).unwrap_or_default())
        .collect();
    json!({
        "count": d.comm().size(),
        "imbalance": d.imbalance,
        "recuts": d.recuts,
        "per_rank": per_rank,
    })
}

/// Rank 0's whole model set to the gathered state (collective).
fn gather(d: &Decomposed, model: &mut Option<Model>) -> Result<(), RunError> {
    if let (Some(state), Some(model)) = (d.gather(), model.as_mut()) {
        let st = ModelState {
            step: state.step,
            system: SystemState::Granular(Box::new(state)),
        };
        model.restore_state(&st)?;
    }
    Ok(())
}

/// Run a granular scenario divided over the ranks of `comm` (every rank
/// calls it with the same scenario, options and freshly built or restored
/// `model`). Rank 0 writes the outputs and returns the summary; the
/// others return `Null`.
pub(super) fn run(
    run: Run,
    model: Model,
    comm: Arc<dyn Comm>,
) -> Result<serde_json::Value, RunError> {
    let root = comm.rank() == 0;
    let mut whole = model;
    if let System::Granular(g) = &mut whole.system {
        g.prepare_contacts();
    }
    let steps = whole.steps;
    let warnings: Vec<String> = granular(&whole).dt_warning(&[]).into_iter().collect();
    if root && run.opts.warn {
        warnings.iter().for_each(|w| eprintln!("warning: {w}"));
    }
    let mut d = Decomposed::new(granular(&whole), comm.clone());
    let mut model = root.then_some(whole);
    let res = drive(&run, &mut d, &mut model, steps);
    // the end's outputs, timed apart from the steps
    let t0 = Instant::now();
    let res = res.and_then(|r| gather(&d, &mut model).map(|()| r));
    let ranks = ranks_record(&d);
    let res = match (res, model) {
        (Ok((ended, wall_s, start)), Some(model)) => {
            let mut s = summary(&run, &model, warnings, wall_s, model.step - start);
            s["ranks"] = ranks;
            finish(&run, &model, ended, s, t0)
        }
        (Ok(_), None) => Ok(serde_json::Value::Null),
        (Err(e), _) => Err(e),
    };
    agree(&*comm, res)
}

/// The history row of the present state (collective), on rank 0: each
/// probe's [shares](probe::share) of every rank merged in rank order and
/// finished (bitwise the value of the undivided assembly: exact sums,
/// counts, the owner's value).
fn reduced_row(run: &Run, d: &mut Decomposed, row: &mut [f64]) -> bool {
    row[0] = d.part.step as f64;
    row[1] = d.part.time;
    if run.probes.is_empty() {
        return d.comm().rank() == 0;
    }
    d.ready_outputs();
    let mut mine = Vec::new();
    for (_, p) in &run.probes {
        probe::share(p, &d.part)
            .expect("granular probes only")
            .pack(&mut mine);
    }
    let bytes: Vec<u8> = mine.iter().flat_map(|x| x.to_le_bytes()).collect();
    let all = d.comm().all_gather(&bytes);
    if d.comm().rank() != 0 {
        return false;
    }
    let mut merged = vec![Share::default(); run.probes.len()];
    for b in &all {
        let v: Vec<f64> = b
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        let mut rest = &v[..];
        for m in &mut merged {
            m.merge(&Share::unpack(&mut rest));
        }
    }
    for (k, ((_, p), m)) in run.probes.iter().zip(&merged).enumerate() {
        row[2 + k] = probe::finish(p, m, &d.part);
    }
    true
}

/// Rank 0's frames and checkpoints due now, from its gathered model.
fn write(
    run: &Run,
    model: &Model,
    out: &mut Outputs,
    (frame, ck): (bool, bool),
) -> Result<(), RunError> {
    if frame {
        out.frames.write(model)?;
    }
    if ck {
        out.hist.flush()?;
        Checkpoint::new(run.sc, model, &(), out.hist.bytes(), out.frames.entries())
            .write(&checkpoint::path(&run.opts.out_dir))?;
    }
    Ok(())
}

/// The step loop (collective): how it ended, its wall-clock seconds and
/// its first step. Rank 0's failures (an output that cannot be written)
/// stop every rank at the next step.
fn drive(
    run: &Run,
    d: &mut Decomposed,
    model: &mut Option<Model>,
    steps: usize,
) -> Result<(Ended, f64, usize), RunError> {
    let (sc, opts) = (run.sc, run.opts);
    // bonded scenarios do not run on several ranks
    let cols = columns(run, false);
    let mut row = vec![0.0; cols.len()];
    let opened = model
        .as_ref()
        .map(|m| Outputs::open(run, m, &cols))
        .transpose();
    let mut outputs = agree(d.comm(), opened)?;
    let (every, vtk_every) = (sc.output.every.max(1), sc.output.vtk_every);
    let mut failed: Option<RunError> = None;
    // the row reduced, the whole gathered for frames and checkpoints
    // (collective), then rank 0 writes; its failure is kept
    let mut output = |d: &mut Decomposed,
                      model: &mut Option<Model>,
                      (rec, frame, ck): (bool, bool, bool),
                      failed: &mut Option<_>| {
        let root = rec && reduced_row(run, d, &mut row);
        let mut r = Ok(());
        if root && let Some(out) = outputs.as_mut() {
            r = out.hist.row(&row).map_err(RunError::from);
        }
        if frame || ck {
            r = r
                .and(gather(d, model))
                .and_then(|()| match (model.as_ref(), outputs.as_mut()) {
                    (Some(m), Some(out)) => write(run, m, out, (frame, ck)),
                    _ => Ok(()),
                });
        }
        if let Err(e) = r {
            failed.get_or_insert(e);
        }
    };
    if run.restart.is_none() {
        // the start state, as the one-rank run records it
        d.prepare();
        output(d, model, (true, vtk_every > 0, false), &mut failed);
    }
    let start = d.part.step;
    let mut progress = Progress::new(start, steps, opts.quiet || model.is_none());
    let t0 = Instant::now();
    let ended = loop {
        let step = d.part.step;
        if step >= steps {
            break Ended::Completed;
        }
        d.part.store_forces = due(step + 1, vtk_every, steps);
        let signal = opts.stop.as_ref().map_or(0, |s| s.load(Ordering::Relaxed));
        let (clean, stop) = d.step(signal != 0 || failed.is_some());
        let step = step + 1;
        if !clean {
            if let Err(e) = gather(d, model) {
                failed.get_or_insert(e);
            }
            // rank 0 diagnoses; the others learn the end from it
            let unstable = model.as_ref().and_then(|m| stability::check(m).err());
            break unstable.map_or(Ended::Completed, |i| Ended::Unstable(Box::new(i)));
        }
        let ck = stop || checkpoint_due(step, opts.checkpoint_every, steps);
        let due = (due(step, every, steps), due(step, vtk_every, steps), ck);
        if due.0 || due.1 || due.2 {
            output(d, model, due, &mut failed);
        }
        progress.update(step, d.part.time);
        run.last_step.set(step);
        if stop {
            // a stop that another rank saw: SIGINT, as mpirun forwards it
            break Ended::Interrupted(if signal != 0 { signal } else { 2 });
        }
    };
    progress.finish();
    let wall_s = t0.elapsed().as_secs_f64();
    if let Some(e) = failed {
        return Err(e);
    }
    if let Some(out) = outputs.as_mut() {
        out.hist.flush()?;
    }
    Ok((ended, wall_s, start))
}

/// Rank 0's end of the run: `discs_final.csv` and `summary.json`
/// (`output_seconds`: from `t0`, the start of the end's gather, to the
/// summary).
fn finish(
    run: &Run,
    model: &Model,
    ended: Ended,
    mut s: serde_json::Value,
    t0: Instant,
) -> Result<serde_json::Value, RunError> {
    let out = &run.opts.out_dir;
    if !matches!(ended, Ended::Unstable(_)) {
        write_discs_csv(granular(model), &out.join("discs_final.csv"))?;
    }
    ended.record(&mut s, model);
    s["output_seconds"] = json!(t0.elapsed().as_secs_f64());
    write_json(&out.join("summary.json"), &s)?;
    ended.result(s, model, out)
}
