//! Driver for continuum-only scenarios (static or dynamic): `efgdem run`
//! and `efgdem check` for files with `[[body]]` sections only.
//!
//! Outputs (in the run directory): `history.csv` (step, time, one column
//! per `[[probe]]`), `summary.json` (final value of every probe under its
//! name, extrema, sizes, timings, Newmark parameters, and for a Timoshenko
//! body the exact tip deflection and the energy-norm error), and ParaView
//! frames `frames/<body>_<step>.vtu` + `<body>.pvd` (dynamic, every
//! `output.vtk_every` steps) or `<body>.vtu` (static).
//!
//! Bodies are EFG or bilinear FE (`method = "fem-q4"`); both are driven
//! the same way through [`Body`].

use super::session::{Ended, Outputs, Session, due};
use super::{Run, RunError};
use crate::geom::Vec2;
use crate::model::body::{Body, BodyError};
use crate::model::{Model, Probe, System};
use crate::output::csv::HistoryWriter;
use crate::output::write_json;
use crate::scenario::{Analysis, Scenario};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::time::Instant;

/// Each probe's `[min, max, last]` recorded value (the driver's running
/// values: checkpointed).
type Extrema = Vec<[f64; 3]>;

fn record(
    probes: &[(String, Probe)],
    ext: &mut Extrema,
    model: &Model,
    hist: &mut HistoryWriter,
) -> std::io::Result<()> {
    let mut row = Vec::with_capacity(probes.len() + 2);
    row.push(model.step as f64);
    row.push(model.time());
    for ((_, p), e) in probes.iter().zip(ext.iter_mut()) {
        let v = model.probe(p);
        *e = [e[0].min(v), e[1].max(v), v];
        row.push(v);
    }
    hist.row(&row)
}

fn body_summary(b: &Body) -> Result<Value, BodyError> {
    // Each method's own quadrature for the error norm: EFG 4 × 4 Gauss on
    // a doubled grid, FE 3 × 3 per element half.
    let (method, info, params, tim, grid) = match b {
        Body::Efg(b) => ("efg", json!(b.info), b.params, &b.timoshenko, b.grid),
        Body::Fem(b) => ("fem-q4", json!(b.info), b.params, &b.timoshenko, b.grid),
    };
    let mut v = json!({
        "name": b.name(),
        "method": method,
        "build": info,
        "newmark": { "gamma": params.gamma, "beta": params.beta, "dt": params.dt },
        "kinetic_energy": b.kinetic_energy(),
        "strain_energy": b.strain_energy(),
    });
    if let Body::Efg(b) = b
        && !b.cracks().is_empty()
    {
        v["cracks"] = crack_summary(b)?;
        v["fracture_energy"] = json!(b.fracture_energy);
    }
    if let Some(t) = tim {
        let tip_at = Vec2::new(t.x0 + t.l, t.yc);
        let cells = [2 * (grid[0] - 1), 2 * (grid[1] - 1)];
        let (tip, err) = match b {
            Body::Efg(b) => (
                b.sample(tip_at)?.u.y,
                b.energy_error(|p| t.stress(p), cells, 4)?,
            ),
            Body::Fem(b) => (
                b.sample(tip_at)?.u.y,
                b.energy_error(|p| t.stress(p), cells, 3)?,
            ),
        };
        v["timoshenko"] = json!({
            "tip_uy": tip,
            "tip_uy_exact": t.tip_deflection(),
            "tip_uy_relative_error": (tip - t.tip_deflection()) / t.tip_deflection(),
            "energy_norm_relative_error": err,
        });
    }
    Ok(v)
}

/// The cracks of an EFG body: polyline, length, growth increments, and at
/// each tip `K_I`, `K_II`, `K_eq` and the kink angle of the maximum
/// hoop-stress criterion (degrees).
fn crack_summary(b: &crate::efg::EfgBody) -> Result<Value, BodyError> {
    let states = b.tip_states()?;
    let cracks = b
        .cracks()
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let tips: Vec<Value> = states
                .iter()
                .filter(|s| s.tip.crack == k)
                .map(|s| {
                    json!({
                        "tip": s.tip.end + 1,
                        "at": b.tip_frame(s.tip).0.to_array(),
                        "k1": s.k[0],
                        "k2": s.k[1],
                        "k_eq": s.k_eq,
                        "kink_degrees": s.theta.to_degrees(),
                    })
                })
                .collect();
            json!({
                "points": c.crack.points.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
                "length": c.crack.length(),
                "increments": b.increments[k],
                "tips": tips,
            })
        })
        .collect();
    Ok(Value::Array(cracks))
}

/// Run a continuum-only scenario.
pub(super) fn run(run: Run, mut model: Model) -> Result<Value, RunError> {
    let t_start = Instant::now();
    let (sc, dir) = (run.sc, &run.opts.out_dir);
    let probes = &run.probes;
    let mut ext: Extrema = match &run.restart {
        Some(ck) => ck.driver()?,
        None => vec![[f64::INFINITY, f64::NEG_INFINITY, f64::NAN]; probes.len()],
    };
    let mut cols: Vec<&str> = vec!["step", "t"];
    cols.extend(probes.iter().map(|p| p.0.as_str()));
    let mut out = Outputs::open(&run, &model, &cols)?;
    let mut summary = json!({});
    let t_solve = Instant::now();
    let ended = match sc.simulation.analysis {
        Analysis::Static => {
            model.solve_static()?;
            record(probes, &mut ext, &model, &mut out.hist)?;
            out.frames.write_static(&model)?;
            summary["analysis"] = json!("static");
            Ended::Completed
        }
        Analysis::Dynamic => {
            let (steps, dt) = (model.steps, model.dt);
            let vtk_every = sc.output.vtk_every;
            if run.restart.is_none() {
                record(probes, &mut ext, &model, &mut out.hist)?;
                if vtk_every > 0 {
                    out.frames.write(&model)?;
                }
            }
            let mut session = Session::new(&run, &model);
            let ended = loop {
                if let Some(end) = session.step(&mut model, false)? {
                    break end;
                }
                let step = model.step;
                if due(step, sc.output.every, steps) {
                    record(probes, &mut ext, &model, &mut out.hist)?;
                }
                if due(step, vtk_every, steps) {
                    out.frames.write(&model)?;
                }
                if let Some(end) = session.after_step(&mut model, &mut out, &ext)? {
                    break end;
                }
            };
            session.finish();
            summary["analysis"] = json!("dynamic");
            summary["steps"] = json!(steps);
            summary["dt"] = json!(dt);
            summary["end_time"] = json!(model.time());
            ended
        }
    };
    out.hist.flush()?;
    let solve_seconds = t_solve.elapsed().as_secs_f64();
    let mut extrema = serde_json::Map::new();
    for ((name, probe), [min, max, last]) in probes.iter().zip(&ext) {
        summary[name.as_str()] = json!(last);
        let mut e = json!({ "min": min, "max": max, "final": last });
        if let Some(s) = probe.sign() {
            e["sign"] = json!(s);
        }
        extrema.insert(name.clone(), e);
    }
    summary["probes"] = Value::Object(extrema);
    let System::Continuum { bodies, .. } = &model.system else {
        unreachable!("a continuum model")
    };
    summary["bodies"] = Value::Array(bodies.iter().map(body_summary).collect::<Result<_, _>>()?);
    summary["timing"] = json!({
        "build_seconds": run.build_s,
        "solve_seconds": solve_seconds,
        "total_seconds": run.build_s + t_start.elapsed().as_secs_f64(),
        "threads": rayon::current_num_threads(),
    });
    ended.record(&mut summary, &model);
    write_json(&dir.join("summary.json"), &summary)?;
    ended.result(summary, &model, dir)
}

/// Validate further (build every body: coverage of every quadrature point,
/// probe points) and describe the problem, without solving.
pub(super) fn check(sc: &Scenario, model: &Model) -> String {
    let System::Continuum { bodies, .. } = &model.system else {
        unreachable!("a continuum model")
    };
    let mut s = String::new();
    for (b, spec) in bodies.iter().zip(&sc.body) {
        let b = match b {
            Body::Efg(b) => b,
            Body::Fem(b) => {
                let i = &b.info;
                let _ = writeln!(
                    s,
                    "body `{}` (FE, bilinear Q4): {} × {} = {} nodes, {} DOFs ({} prescribed, eliminated); {} elements, 2×2 Gauss; {} mass; K lower triangle: {} entries",
                    b.name,
                    b.grid[0],
                    b.grid[1],
                    i.nodes,
                    i.dofs,
                    i.constrained_dofs,
                    i.elements,
                    i.mass,
                    i.nnz
                );
                let _ = writeln!(
                    s,
                    "  material: E = {}, ν = {}, ρ = {}, t = {}, plane {}",
                    b.material.e,
                    b.material.nu,
                    b.material.density,
                    b.material.thickness,
                    b.material.plane
                );
                if sc.simulation.analysis == Analysis::Dynamic {
                    let _ = writeln!(s, "  Newmark γ = {}, β = {}", b.params.gamma, b.params.beta);
                }
                continue;
            }
        };
        let i = &b.info;
        if let Some(m) = &b.mesh {
            let _ = writeln!(
                s,
                "body `{}` (EFG, polygon with {} hole(s), spacing {}): {} nodes, {} DOFs; {} triangles, {} domain + {} boundary Gauss points; d_max = {}",
                b.name,
                m.domain.loops.len() - 1,
                m.spacing,
                i.nodes,
                i.dofs,
                m.triangles.len(),
                i.domain_points,
                i.boundary_points,
                b.d_max
            );
        } else {
            let _ = writeln!(
                s,
                "body `{}` (EFG): {} × {} = {} nodes, {} DOFs; {} domain + {} boundary Gauss points ({}×{} per cell); d_max = {}",
                b.name,
                b.grid[0],
                b.grid[1],
                i.nodes,
                i.dofs,
                i.domain_points,
                i.boundary_points,
                spec.gauss,
                spec.gauss,
                b.d_max
            );
        }
        let _ = writeln!(
            s,
            "  support coverage: {}–{} nodes per Gauss point (≥ 3 needed); K̄ lower triangle: {} entries",
            i.min_cover, i.max_cover, i.nnz
        );
        let _ = writeln!(
            s,
            "  material: E = {}, ν = {}, ρ = {}, t = {}, plane {}; penalty α = {:e}",
            b.material.e,
            b.material.nu,
            b.material.density,
            b.material.thickness,
            b.material.plane,
            spec.penalty.unwrap_or(1e5 * b.material.e)
        );
        if sc.simulation.analysis == Analysis::Dynamic {
            let _ = writeln!(
                s,
                "  Newmark γ = {}, β = {}{}",
                b.params.gamma,
                b.params.beta,
                if b.params.gamma == 0.5 && b.params.beta == 0.25 {
                    " (average acceleration, energy-conserving)"
                } else if b.params.gamma > 0.5 {
                    " (numerically dissipative)"
                } else {
                    ""
                }
            );
        }
    }
    let _ = writeln!(
        s,
        "analysis: {}{}; {} probe(s)",
        match sc.simulation.analysis {
            Analysis::Static => "static",
            Analysis::Dynamic => "dynamic",
        },
        match (
            sc.simulation.analysis,
            sc.simulation.dt,
            sc.simulation.end_time
        ) {
            (Analysis::Dynamic, Some(dt), None) => format!(", dt = {dt}, {} steps", model.steps),
            (Analysis::Dynamic, Some(dt), Some(t)) =>
                format!(", dt = {dt}, end_time = {t} ({} steps)", model.steps),
            _ => String::new(),
        },
        sc.probe.len()
    );
    s
}
