//! Driver for granular-only scenarios (discs and walls): `efgdem run` and
//! `efgdem check`.

use super::session::{Ended, Outputs, Session, due};
use super::{Run, RunError};
use crate::dem::{DT_SAFETY, DT_WARN};
use crate::model::{Model, System};
use crate::output::csv::{BOND_COLUMNS, bond_row, write_bond_breaks, write_discs_csv};
use crate::output::write_json;
use crate::scenario::Scenario;
use serde_json::json;
use std::time::Instant;

/// Run a granular scenario: `history.csv` (columns `step, t` and one per
/// probe, then [`BOND_COLUMNS`] with bonds; a row at step 0, every
/// `output.every` steps and at the last step), `frames/discs_NNNNNNN.vtp` +
/// `discs.pvd` every `output.vtk_every` steps, `discs_final.csv`,
/// `bond_breaks.csv` with bonds, and `summary.json`.
pub(super) fn run(run: Run, mut model: Model) -> Result<serde_json::Value, RunError> {
    let (sc, out) = (run.sc, &run.opts.out_dir);
    let steps = model.steps;
    let mut warnings = Vec::new();
    if let Some(w) = model.granular().and_then(|g| g.dt_warning(&[])) {
        if run.opts.warn {
            eprintln!("warning: {w}");
        }
        warnings.push(w);
    }
    let cols = columns(&run, model.granular().is_some_and(|g| g.bonds.active()));
    let mut outputs = Outputs::open(&run, &model, &cols)?;
    let every = sc.output.every.max(1);
    let vtk_every = sc.output.vtk_every;
    let mut row = vec![0.0; cols.len()];
    let record =
        |model: &Model, row: &mut Vec<f64>, out: &mut Outputs| record(&run, model, row, out);
    if run.restart.is_none() {
        // the contact list of the start state (for probes and the first frame)
        if let System::Granular(g) = &mut model.system {
            g.prepare_contacts();
        }
        record(&model, &mut row, &mut outputs)?;
        if vtk_every > 0 {
            outputs.frames.write(&model)?;
        }
    }
    let start = model.step;
    let mut session = Session::new(&run, &model);
    let t0 = Instant::now();
    let ended = loop {
        // disc forces are only read by the frames
        let next = model.step + 1;
        if let System::Granular(g) = &mut model.system {
            g.store_forces = due(next, vtk_every, steps);
        }
        if let Some(end) = session.step(&mut model, false)? {
            break end;
        }
        let step = model.step;
        if due(step, every, steps) {
            record(&model, &mut row, &mut outputs)?;
        }
        if due(step, vtk_every, steps) {
            outputs.frames.write(&model)?;
        }
        // the model is the whole state of a granular run
        if let Some(end) = session.after_step(&mut model, &mut outputs, &())? {
            break end;
        }
    };
    session.finish();
    outputs.hist.flush()?;
    let wall_s = t0.elapsed().as_secs_f64();
    let gr = granular(&model);
    // a disc source for another run: not the state of a blow-up
    if !matches!(ended, Ended::Unstable(_) | Ended::Failed(_)) {
        write_discs_csv(gr, &out.join("discs_final.csv"))?;
    }
    if model.granular().is_some_and(|g| g.bonds.active()) {
        write_bond_breaks(gr, &out.join("bond_breaks.csv"))?;
    }
    let mut summary = summary(&run, &model, warnings, wall_s, model.step - start);
    run.annotate(&mut summary)?;
    ended.record(&mut summary, &model);
    write_json(&out.join("summary.json"), &summary)?;
    ended.result(summary, &model, out)
}

/// The history columns of a granular run: `step, t`, the probes, and
/// [`BOND_COLUMNS`] with bonds.
pub(super) fn columns<'a>(run: &'a Run, bonded: bool) -> Vec<&'a str> {
    let mut cols = vec!["step", "t"];
    cols.extend(run.probes.iter().map(|p| p.0.as_str()));
    if bonded {
        cols.extend(BOND_COLUMNS);
    }
    cols
}

/// Write the history row of the present state (`row`: one per column).
pub(super) fn record(
    run: &Run,
    model: &Model,
    row: &mut [f64],
    out: &mut Outputs,
) -> std::io::Result<()> {
    row[0] = model.step as f64;
    row[1] = model.time();
    for (k, (_, s)) in run.probes.iter().enumerate() {
        row[2 + k] = model.probe(s);
    }
    let gr = granular(model);
    if gr.bonds.active() {
        let n = row.len() - BOND_COLUMNS.len();
        row[n..].copy_from_slice(&bond_row(gr));
    }
    out.hist.row(row)
}

/// What a granular run's summary says of its discs at the end: computed
/// from the whole assembly ([`Facts::of`]), or reduced over the ranks of
/// a divided one.
pub(super) struct Facts {
    /// Discs.
    pub discs: usize,
    /// Touching disc–disc and disc–wall pairs.
    pub touching: (usize, usize),
    /// Listed pairs.
    pub listed: usize,
    /// Heap bytes of the assembly (of every rank).
    pub heap_bytes: usize,
    /// Energies.
    pub energies: crate::dem::Energies,
    /// The critical time step.
    pub crit: crate::dem::critical::Critical,
}

impl Facts {
    /// The facts of an undivided assembly.
    pub fn of(gr: &crate::dem::Granular) -> Facts {
        Facts {
            discs: gr.particles.len(),
            touching: gr.touching(),
            listed: gr.contacts.len(),
            heap_bytes: gr.heap_bytes(),
            energies: gr.energies(),
            crit: gr.critical_step(&[]),
        }
    }
}

/// `summary.json` of a granular run that took `steps` steps in `wall_s`
/// seconds (its end is recorded by [`Ended::record`]).
pub(super) fn summary(
    run: &Run,
    model: &Model,
    warnings: Vec<String>,
    wall_s: f64,
    steps: usize,
) -> serde_json::Value {
    let gr = granular(model);
    let facts = Facts::of(gr);
    summary_of(run, gr, model.steps, &facts, (warnings, wall_s, steps))
}

/// [`summary`] from the [`Facts`] of the discs and `gr` for the walls,
/// the clock and the contact search (a part of a divided assembly, its
/// walls' totals those of the whole), of a run of `total_steps`.
pub(super) fn summary_of(
    run: &Run,
    gr: &crate::dem::Granular,
    total_steps: usize,
    f: &Facts,
    (warnings, wall_s, steps): (Vec<String>, f64, usize),
) -> serde_json::Value {
    let (n, crit, (dd, dw)) = (f.discs, &f.crit, f.touching);
    let mut summary = json!({
        "kind": "granular",
        "discs": n,
        "walls": gr.walls.len(),
        "steps": total_steps,
        "dt": gr.dt,
        "critical_dt": crit.dt,
        "critical_mode": crit.mode,
        "dt_over_critical": gr.dt / crit.dt,
        "time": gr.time,
        "threads": rayon::current_num_threads(),
        "build_seconds": run.build_s,
        "run_seconds": wall_s,
        "particle_steps_per_second": if wall_s > 0.0 { (n * steps) as f64 / wall_s } else { 0.0 },
        "neighbour_rebuilds": gr.grid.rebuilds,
        "contacts": { "disc_disc": dd, "disc_wall": dw, "listed_pairs": f.listed },
        "bytes_per_disc": f.heap_bytes as f64 / n.max(1) as f64,
        "energies": f.energies,
        "wall_forces": gr.walls.iter().map(|w| json!({"name": w.name, "force": [w.force.x, w.force.y], "position_from": [w.a.x, w.a.y]})).collect::<Vec<_>>(),
        "warnings": warnings,
    });
    if !gr.clumps.is_empty() {
        summary["clumps"] =
            json!({"count": gr.clumps.len(), "member_discs": gr.clumps.members.len()});
    }
    if gr.bonds.active() {
        let (t, s) = gr.bonds.broken_counts();
        let l = &gr.bonds.list;
        summary["bonds"] = json!({"made": l.made, "intact": l.len(), "broken_tension": t, "broken_shear": s, "released_energy": l.released});
    }
    summary
}

/// What `efgdem check` prints for a granular scenario.
pub(super) fn check(sc: &Scenario, model: &Model) -> String {
    let gr = granular(model);
    let p = &gr.particles;
    let n = p.len();
    let (rmin, rmax) = p
        .radius
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
    let crit = gr.critical_step(&[]);
    let steps = model.steps;
    let mut s = format!(
        "granular: {n} discs (radius {rmin:e} … {rmax:e}), {} walls, {} materials\n\
         {}\n\
         steps: {steps} (end time {:e})\n\
         damping: {}",
        gr.walls.len(),
        gr.materials.len(),
        time_step_line(gr.dt, &crit),
        steps as f64 * gr.dt,
        sc.granular.as_ref().map(|g| g.damping).unwrap_or_default(),
    );
    if let Some(w) = gr.dt_warning(&[]) {
        s.push_str(&format!("\nwarning: {w}"));
    }
    s
}

/// What `efgdem check` says of the time step: Δt against the critical
/// step of the contacts in use, the mode that sets it, and its basis.
pub(super) fn time_step_line(dt: f64, crit: &crate::dem::critical::Critical) -> String {
    format!(
        "time step: dt = {dt:e} is {:.3} × the critical step {:.4e} of the contacts in use, set by {} (linear modes of the central difference, dashpots included; the default dt is {DT_SAFETY} ×, warn above {DT_WARN} ×; refused above {:.4e}, the limit of two of the lightest discs meeting)",
        dt / crit.dt,
        crit.dt,
        crit.mode,
        crit.certain
    )
}

pub(super) fn granular(model: &Model) -> &crate::dem::Granular {
    model.granular().expect("a granular model")
}
