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
use super::granular::{Facts, columns, granular, summary_of};
use super::progress::Progress;
use super::session::{Ended, Outputs, checkpoint_due, due};
use super::{Run, RunError};
use crate::decomp::{Comm, Cut, Decomposed};
use crate::model::probe::{self, Share};
use crate::model::{Model, System, stability};
use crate::output::csv::write_discs_csv_by_ids;
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

/// `f` of the whole model (collective): rank 0's model holds the
/// assembly gathered from the ranks while `f` runs, then its assembly
/// without discs again; `None` on the other ranks.
fn with_whole<T>(
    d: &Decomposed,
    model: &mut Option<Model>,
    f: impl FnOnce(&Model) -> T,
) -> Option<T> {
    let model = model.as_mut();
    let skeleton = model.as_ref().map_or(&d.part, |m| granular(m));
    let mut whole = d.gather_whole(skeleton)?;
    let model = model.expect("rank 0 has the model");
    // the model's assembly and `whole` change places, and back after `f`
    let swap = |model: &mut Model, other: &mut crate::dem::Granular| {
        let System::Granular(g) = &mut model.system else {
            unreachable!("a granular model")
        };
        std::mem::swap(&mut **g, other);
    };
    swap(model, &mut whole);
    model.step = d.part.step;
    let r = f(model);
    swap(model, &mut whole);
    Some(r)
}

/// How a granular run on ranks gets its parts.
pub(super) enum Start {
    /// Each rank takes its share of the whole model it built or restored.
    Whole,
    /// Each rank built its part alone, of these regions.
    Fresh(Cut),
    /// Each rank restored its part alone from a checkpoint.
    Restored(Box<Decomposed>),
}

/// Run a granular scenario divided over the ranks of `comm` (every rank
/// calls it with the same scenario, options and freshly built or restored
/// `model`). Rank 0 writes the outputs and returns the summary; the
/// others return `Null`. No rank keeps the whole assembly: rank 0's
/// model keeps its walls, laws and clock without discs, and holds the
/// whole only while a frame or a checkpoint is written.
pub(super) fn run(
    run: Run,
    mut model: Model,
    comm: Arc<dyn Comm>,
    start: Start,
) -> Result<serde_json::Value, RunError> {
    let root = comm.rank() == 0;
    let steps = model.steps;
    // the whole's contact list is never built: each part builds its own
    // (`Decomposed::prepare`)
    let mut d = match (start, &mut model.system) {
        (Start::Restored(d), _) => *d,
        (Start::Fresh(cut), System::Granular(g)) => Decomposed::from_part(g, cut, comm.clone()),
        _ => Decomposed::new(granular(&model), comm.clone()),
    };
    // the critical step of the discs' constants (the same at the end)
    let (crit, warning) = d.critical_step(&[]);
    let warnings: Vec<String> = warning.into_iter().collect();
    if root && run.opts.warn {
        warnings.iter().for_each(|w| eprintln!("warning: {w}"));
    }
    let mut model = root.then(|| {
        if let System::Granular(g) = &mut model.system {
            // the discs' start positions serve the frames' displacements
            **g = match run.sc.output.vtk_every {
                0 => g.with_discs(Default::default()),
                _ => g.with_same_discs(Default::default()),
            };
        }
        model
    });
    let res = drive_granular(&run, &mut d, &mut model, steps);
    // the end's outputs, timed apart from the steps
    let t0 = Instant::now();
    // rank 0 decides (only it knows an instability or a failed output);
    // every rank takes part in the gathers, or none
    let write = matches!(&res, Ok((e, ..)) if !matches!(e, Ended::Unstable(_)));
    let write = comm.all_gather(&[write as u8])[0][0] != 0;
    let res = res.and_then(|r| {
        if write {
            let path = run.opts.out_dir.join("discs_final.csv");
            let path = root.then_some(path.as_path());
            write_discs_csv_by_ids(path, d.total(), |ids| d.gather_ids(ids))?;
        }
        Ok(r)
    });
    let facts = facts(&mut d, crit);
    let ranks = ranks_record(&d);
    let res = match (res, model, facts) {
        (Ok((ended, wall_s, start)), Some(mut model), Some(facts)) => {
            model.step = d.part.step;
            let took = (warnings, wall_s, d.part.step - start);
            let mut s = summary_of(&run, &d.part, steps, &facts, took);
            s["ranks"] = ranks;
            finish(&model, ended, s, (facts.discs, t0), &run)
        }
        (Ok(_), _, _) => Ok(serde_json::Value::Null),
        (Err(e), _, _) => Err(e),
    };
    agree(&*comm, res)
}

/// Every rank's shares merged on rank 0 (`None` on the others),
/// collective.
fn reduce(d: &Decomposed, shares: &[Share]) -> Option<Vec<Share>> {
    let mut mine = Vec::new();
    shares.iter().for_each(|s| s.pack(&mut mine));
    let bytes: Vec<u8> = mine.iter().flat_map(|x| x.to_le_bytes()).collect();
    let all = d.comm().all_gather(&bytes);
    if d.comm().rank() != 0 {
        return None;
    }
    let mut merged = vec![Share::default(); shares.len()];
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
    Some(merged)
}

/// The summary's [`Facts`] of the whole assembly, reduced over the ranks
/// (collective; on rank 0). Leaves the part ready for the summary
/// ([`Decomposed::ready_outputs`]: the walls' totals of the whole).
fn facts(d: &mut Decomposed, crit: crate::dem::critical::Critical) -> Option<Facts> {
    d.ready_outputs();
    let g = &d.part;
    let p = &g.particles;
    let (dd, dw) = g.touching();
    let listed = g.contacts.pairs().filter(|&(i, _)| !p.is_ghost(i)).count();
    let share = Share {
        sums: g.energy_sums(&p.vel, &p.omega).into_iter().collect(),
        counts: vec![dd as u64, dw as u64, listed as u64, g.heap_bytes() as u64],
        value: None,
    };
    let s = reduce(d, &[share])?.remove(0);
    let c = |k: usize| s.counts[k] as usize;
    Some(Facts {
        discs: d.total(),
        touching: (c(0), c(1)),
        listed: c(2),
        heap_bytes: c(3),
        // bonded assemblies are not divided
        energies: crate::dem::Energies::from_sums(&s.sums, 0.0),
        crit,
    })
}

/// The history row of the present state (collective), on rank 0: each
/// probe's [shares](probe::share) of every rank merged and finished
/// (bitwise the value of the undivided assembly: exact sums, counts, the
/// owner's value). Whether this is rank 0.
fn reduced_row(run: &Run, d: &mut Decomposed, row: &mut [f64]) -> bool {
    row[0] = d.part.step as f64;
    row[1] = d.part.time;
    if run.probes.is_empty() {
        return d.comm().rank() == 0;
    }
    d.ready_outputs();
    let shares: Vec<Share> = (run.probes.iter())
        .map(|(_, p)| probe::share(p, &d.part).expect("granular probes only"))
        .collect();
    let Some(merged) = reduce(d, &shares) else {
        return false;
    };
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

/// What a step taken on ranks came to ([`RankRun::step`]).
pub(super) enum Stepped {
    /// The step was taken; `stop`: a rank saw the stop flag.
    Taken {
        /// A rank saw the stop flag.
        stop: bool,
    },
    /// The run ends here (an unphysical state, a failed step): the step
    /// is not recorded.
    Ended(Ended),
}

/// The outputs due after a step: a history row, a frame, a checkpoint.
#[derive(Clone, Copy)]
pub(super) struct Due {
    /// A history row.
    pub row: bool,
    /// A frame.
    pub frame: bool,
    /// A checkpoint (periodic, or the stop's).
    pub checkpoint: bool,
}

impl Due {
    /// Any output.
    pub fn any(self) -> bool {
        self.row || self.frame || self.checkpoint
    }
}

/// A run divided over ranks as [`drive`] steps it: the granular run
/// ([`GranularRanks`]) or the coupled one
/// (`coupled::on_ranks::CoupledRanks`). Every method is collective.
pub(super) trait RankRun {
    /// The step count and the time now.
    fn clock(&self) -> (usize, f64);
    /// One step; `flag` (a stop request, a failed output) is or-ed over
    /// the ranks.
    fn step(&mut self, flag: bool) -> Result<Stepped, RunError>;
    /// Warnings of the last step, for rank 0 to print.
    fn notices(&mut self) -> Vec<String> {
        Vec::new()
    }
    /// The outputs after `step` (rank 0 writes them).
    fn after_step(&mut self, step: usize, due: Due) -> Result<(), RunError>;
}

/// The step loop of a run on ranks (collective) up to `steps`, history
/// rows every `every` steps: signals, checkpoints, progress; rank 0's
/// failures (an output that cannot be written, `first` that of the
/// outputs before the loop) stop every rank at the next step.
pub(super) fn drive(
    run: &Run,
    x: &mut impl RankRun,
    (steps, every): (usize, usize),
    root: bool,
    first: Result<(), RunError>,
) -> Result<Ended, RunError> {
    let opts = run.opts;
    let vtk_every = run.sc.output.vtk_every;
    let mut progress = Progress::new(x.clock().0, steps, opts.quiet || !root);
    let mut failed = first.err();
    let ended = loop {
        let step = x.clock().0;
        if step >= steps {
            break Ended::Completed;
        }
        let signal = opts.stop.as_ref().map_or(0, |s| s.load(Ordering::Relaxed));
        let stepped = x.step(signal != 0 || failed.is_some())?;
        for n in x.notices().iter().filter(|_| root) {
            progress.warn(&format!("warning: {n}"));
        }
        let stop = match stepped {
            Stepped::Ended(e) => break e,
            Stepped::Taken { stop } => stop,
        };
        let step = step + 1;
        let d = Due {
            row: due(step, every, steps),
            frame: due(step, vtk_every, steps),
            checkpoint: stop || checkpoint_due(step, opts.checkpoint_every, steps),
        };
        if let Err(e) = x.after_step(step, d) {
            failed.get_or_insert(e);
        }
        progress.update(step, x.clock().1);
        run.last_step.set(step);
        if stop {
            // a stop that another rank saw: SIGINT, as mpirun forwards it
            break Ended::Interrupted(if signal != 0 { signal } else { 2 });
        }
    };
    progress.finish();
    match failed {
        Some(e) => Err(e),
        None => Ok(ended),
    }
}

/// A granular run on ranks as [`drive`] steps it.
struct GranularRanks<'a> {
    run: &'a Run<'a>,
    d: &'a mut Decomposed,
    /// Rank 0's model (without discs between outputs).
    model: &'a mut Option<Model>,
    /// Rank 0's files.
    outputs: Option<Outputs>,
    row: Vec<f64>,
    steps: usize,
}

impl GranularRanks<'_> {
    /// The outputs `due` now: the row reduced, the whole gathered for
    /// frames and checkpoints, then rank 0 writes.
    fn output(&mut self, due: Due) -> Result<(), RunError> {
        let root = due.row && reduced_row(self.run, self.d, &mut self.row);
        let mut r = Ok(());
        if root && let Some(out) = self.outputs.as_mut() {
            r = out.hist.row(&self.row).map_err(RunError::from);
        }
        if due.frame || due.checkpoint {
            let (run, out) = (self.run, self.outputs.as_mut());
            let fc = (due.frame, due.checkpoint);
            let w = with_whole(self.d, self.model, |m| out.map(|o| write(run, m, o, fc)));
            r = r.and(w.flatten().unwrap_or(Ok(())));
        }
        r
    }
}

impl RankRun for GranularRanks<'_> {
    fn clock(&self) -> (usize, f64) {
        (self.d.part.step, self.d.part.time)
    }

    fn step(&mut self, flag: bool) -> Result<Stepped, RunError> {
        let vtk_every = self.run.sc.output.vtk_every;
        // disc forces are only read by the frames
        self.d.part.store_forces = due(self.d.part.step + 1, vtk_every, self.steps);
        let (clean, stop) = self.d.step(flag);
        if clean {
            return Ok(Stepped::Taken { stop });
        }
        // rank 0 diagnoses; the others learn the end from it
        let unstable = with_whole(self.d, self.model, |m| stability::check(m).err()).flatten();
        Ok(Stepped::Ended(unstable.map_or(Ended::Completed, |i| {
            Ended::Unstable(Box::new(i))
        })))
    }

    fn after_step(&mut self, _: usize, due: Due) -> Result<(), RunError> {
        if due.any() { self.output(due) } else { Ok(()) }
    }
}

/// The granular step loop (collective): how it ended, its wall-clock
/// seconds and its first step.
fn drive_granular(
    run: &Run,
    d: &mut Decomposed,
    model: &mut Option<Model>,
    steps: usize,
) -> Result<(Ended, f64, usize), RunError> {
    // bonded scenarios do not run on several ranks
    let cols = columns(run, false);
    let opened = model
        .as_ref()
        .map(|m| Outputs::open(run, m, &cols))
        .transpose();
    let outputs = agree(d.comm(), opened)?;
    let root = model.is_some();
    let mut x = GranularRanks {
        run,
        d,
        model,
        outputs,
        row: vec![0.0; cols.len()],
        steps,
    };
    let mut first = Ok(());
    if run.restart.is_none() {
        // the start state, as the one-rank run records it
        x.d.prepare();
        let start = Due {
            row: true,
            frame: run.sc.output.vtk_every > 0,
            checkpoint: false,
        };
        first = x.output(start);
    }
    let start = x.d.part.step;
    let t0 = Instant::now();
    let every = run.sc.output.every.max(1);
    let ended = drive(run, &mut x, (steps, every), root, first)?;
    let wall_s = t0.elapsed().as_secs_f64();
    if let Some(out) = x.outputs.as_mut() {
        out.hist.flush()?;
    }
    Ok((ended, wall_s, start))
}

/// Rank 0's end of the run: `summary.json` with what one process writes
/// (the probes' extremes, the preparation; `output_seconds`: from `t0`,
/// the start of the end's outputs, to the summary; the peak memory per
/// disc of the whole assembly's `discs`).
fn finish(
    model: &Model,
    ended: Ended,
    mut s: serde_json::Value,
    (discs, t0): (usize, Instant),
    run: &Run,
) -> Result<serde_json::Value, RunError> {
    let out = &run.opts.out_dir;
    run.annotate(&mut s)?;
    ended.record(&mut s, model);
    if let Some(peak) = s["peak_memory_bytes"].as_f64() {
        s["peak_bytes_per_disc"] = json!(peak / discs.max(1) as f64);
    }
    s["output_seconds"] = json!(t0.elapsed().as_secs_f64());
    write_json(&out.join("summary.json"), &s)?;
    ended.result(s, model, out)
}
