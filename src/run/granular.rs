//! Driver for granular-only scenarios (discs and walls): `efgdem run` and
//! `efgdem check`.

use super::{RunError, RunOptions};
use crate::dem::DT_WARN;
use crate::model::{Model, Probe, System};
use crate::output::csv::{HistoryWriter, write_discs_csv};
use crate::output::vtk::PvdSeries;
use crate::output::vtp::write_granular;
use crate::output::{progress, write_json};
use crate::scenario::Scenario;
use serde_json::json;
use std::time::Instant;

/// Run a granular scenario: `history.csv` (columns `step, t` and one per
/// probe; a row at step 0, every `output.every` steps and at the last step),
/// `frames/discs_NNNNNN.vtp` + `discs.pvd` every `output.vtk_every` steps,
/// `discs_final.csv` and `summary.json`.
pub(super) fn run(
    sc: &Scenario,
    mut model: Model,
    probes: Vec<(String, Probe)>,
    build_s: f64,
    opts: &RunOptions,
) -> Result<serde_json::Value, RunError> {
    let steps = model.steps;
    let mut warnings = Vec::new();
    if let Some(w) = model.granular().and_then(|g| g.dt_warning()) {
        eprintln!("warning: {w}");
        warnings.push(w);
    }
    let out = &opts.out_dir;
    let mut cols = vec!["step", "t"];
    cols.extend(probes.iter().map(|p| p.0.as_str()));
    let mut hist = HistoryWriter::create(&out.join("history.csv"), &cols)?;
    let every = sc.output.every.max(1);
    let vtk_every = sc.output.vtk_every;
    // the contact list of the start state (for probes and the first frame)
    if let System::Granular(g) = &mut model.system {
        g.prepare_contacts();
    }
    let mut row = vec![0.0; cols.len()];
    let mut record = |model: &Model, row: &mut Vec<f64>, step: usize| {
        row[0] = step as f64;
        row[1] = model.time();
        for (k, (_, s)) in probes.iter().enumerate() {
            row[2 + k] = model.probe(s);
        }
        hist.row(row)
    };
    record(&model, &mut row, 0)?;
    let mut pvd = None;
    if vtk_every > 0 {
        std::fs::create_dir_all(out.join("frames"))?;
        let mut s = PvdSeries::new(&out.join("discs.pvd"));
        let f = "frames/discs_000000.vtp";
        write_granular(granular(&model), &out.join(f))?;
        s.add(0.0, f)?;
        pvd = Some(s);
    }
    let pb = progress(steps as u64, opts.quiet);
    let t0 = Instant::now();
    let mut last_pb = 0usize;
    for cycle in 1..=steps {
        // disc forces are only read by the frames
        if let System::Granular(g) = &mut model.system {
            g.store_forces = vtk_every > 0 && (cycle % vtk_every == 0 || cycle == steps);
        }
        model.step()?;
        if cycle % every == 0 || cycle == steps {
            record(&model, &mut row, cycle)?;
        }
        if let Some(s) = pvd.as_mut()
            && (cycle % vtk_every == 0 || cycle == steps)
        {
            let f = format!("frames/discs_{cycle:06}.vtp");
            write_granular(granular(&model), &out.join(&f))?;
            s.add(model.time(), &f)?;
        }
        if cycle - last_pb >= 1000 || cycle == steps {
            pb.inc((cycle - last_pb) as u64);
            last_pb = cycle;
        }
    }
    pb.finish_and_clear();
    hist.flush()?;
    let wall_s = t0.elapsed().as_secs_f64();
    let gr = granular(&model);
    gr.check_finite()?;
    write_discs_csv(gr, &out.join("discs_final.csv"))?;
    let n = gr.particles.len();
    let (dd, dw) = gr.touching();
    let e = gr.energies();
    let summary = json!({
        "kind": "granular",
        "discs": n,
        "walls": gr.walls.len(),
        "steps": steps,
        "dt": gr.dt,
        "critical_dt": gr.critical_dt(),
        "dt_over_critical": gr.dt / gr.critical_dt(),
        "time": gr.time,
        "threads": rayon::current_num_threads(),
        "build_seconds": build_s,
        "run_seconds": wall_s,
        "particle_steps_per_second": if wall_s > 0.0 { (n * steps) as f64 / wall_s } else { 0.0 },
        "neighbour_rebuilds": gr.grid.rebuilds,
        "contacts": { "disc_disc": dd, "disc_wall": dw, "listed_pairs": gr.contacts.pairs.len() },
        "bytes_per_disc": gr.heap_bytes() as f64 / n.max(1) as f64,
        "energies": e,
        "wall_forces": gr.walls.iter().map(|w| json!({"name": w.name, "force": [w.force.x, w.force.y], "position_from": [w.a.x, w.a.y]})).collect::<Vec<_>>(),
        "warnings": warnings,
    });
    write_json(&out.join("summary.json"), &summary)?;
    Ok(summary)
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
    let crit = gr.critical_dt();
    let steps = model.steps;
    let mut s = format!(
        "granular: {n} discs (radius {rmin:e} … {rmax:e}), {} walls, {} materials\n\
         time step: dt = {:e}, critical 2√(m_min/k_max) = {crit:e} (dt/critical = {:.4}; warn above {DT_WARN})\n\
         steps: {steps} (end time {:e})\n\
         damping: {}",
        gr.walls.len(),
        gr.materials.len(),
        gr.dt,
        gr.dt / crit,
        steps as f64 * gr.dt,
        sc.granular.as_ref().map(|g| g.damping).unwrap_or_default(),
    );
    if let Some(w) = gr.dt_warning() {
        s.push_str(&format!("\nwarning: {w}"));
    }
    s
}

fn granular(model: &Model) -> &crate::dem::Granular {
    model.granular().expect("a granular model")
}
