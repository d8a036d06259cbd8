//! Driver for continuum-only scenarios (static or dynamic): `efgdem run`
//! and `efgdem check` for files with `[[body]]` sections only.
//!
//! Outputs (in the run directory): `history.csv` (step, time, one column
//! per `[[probe]]`), `summary.json` (final value of every probe under its
//! name, extrema, sizes, timings, Newmark parameters, and for a Timoshenko
//! body the exact tip deflection and the energy-norm error), and ParaView
//! frames `frames/<body>_<step>.vtu` + `<body>.pvd` (dynamic, every
//! `output.vtk_every` steps) or `<body>.vtu` (static).

use super::body::EfgBody;
use super::{EfgError, ShapeRow};
use crate::geom::Vec2;
use crate::output::csv::HistoryWriter;
use crate::output::vtk::PvdSeries;
use crate::output::vtu::{Field, write_quad_grid};
use crate::output::{progress, write_json};
use crate::run::RunOptions;
use crate::scenario::body::BODY_QUANTITIES;
use crate::scenario::{Analysis, Probe, Scenario};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// A probe resolved to a body and, for point quantities, a shape row.
struct BoundProbe {
    name: String,
    body: usize,
    quantity: String,
    row: Option<ShapeRow>,
    min: f64,
    max: f64,
    last: f64,
}

fn build_bodies(sc: &Scenario) -> Result<Vec<EfgBody>, EfgError> {
    sc.body
        .iter()
        .map(|b| EfgBody::from_spec(b, sc.simulation.gravity))
        .collect()
}

fn bind_probes(sc: &Scenario, bodies: &[EfgBody]) -> Result<Vec<BoundProbe>, EfgError> {
    let mut out = vec![];
    for p in &sc.probe {
        let Probe {
            name,
            quantity,
            point,
            body,
            ..
        } = p;
        let bi = match body {
            Some(n) => bodies.iter().position(|b| &b.name == n),
            None => Some(0),
        }
        .ok_or_else(|| EfgError::Invalid(format!("probe `{name}`: no body `{body:?}`")))?;
        let row = match point {
            Some(pt) if !BODY_QUANTITIES.contains(&quantity.as_str()) => {
                let mut r = ShapeRow::new();
                bodies[bi].shape_row(Vec2::from(*pt), &mut r)?;
                Some(r)
            }
            _ => None,
        };
        out.push(BoundProbe {
            name: name.clone(),
            body: bi,
            quantity: quantity.clone(),
            row,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            last: f64::NAN,
        });
    }
    Ok(out)
}

fn probe_value(p: &BoundProbe, b: &EfgBody) -> f64 {
    let energy = |q: &str| match q {
        "kinetic_energy" => b.kinetic_energy(),
        "strain_energy" => b.strain_energy(),
        _ => b.kinetic_energy() + b.strain_energy(),
    };
    let Some(row) = &p.row else {
        return energy(&p.quantity);
    };
    let s = b.sample_row(row);
    match p.quantity.as_str() {
        "ux" => s.u.x,
        "uy" => s.u.y,
        "vx" => s.v.x,
        "vy" => s.v.y,
        "exx" => s.strain[0],
        "eyy" => s.strain[1],
        "gxy" => s.strain[2],
        "sxx" => s.stress[0],
        "syy" => s.stress[1],
        "sxy" => s.stress[2],
        q => energy(q),
    }
}

fn record(
    probes: &mut [BoundProbe],
    bodies: &[EfgBody],
    hist: &mut HistoryWriter,
    step: usize,
    t: f64,
) -> std::io::Result<()> {
    let mut row = Vec::with_capacity(probes.len() + 2);
    row.push(step as f64);
    row.push(t);
    for p in probes.iter_mut() {
        let v = probe_value(p, &bodies[p.body]);
        p.min = p.min.min(v);
        p.max = p.max.max(v);
        p.last = v;
        row.push(v);
    }
    hist.row(&row)
}

/// Nodal values: true displacement, velocity and stress at every node.
pub(crate) fn write_frame(
    b: &EfgBody,
    shapes: &super::assemble::PointShapes,
    path: &Path,
) -> Result<(), EfgError> {
    let n = b.n_nodes();
    let (mut u, mut v, mut s) = (vec![0.0; 2 * n], vec![0.0; 2 * n], vec![0.0; 3 * n]);
    let mut row = ShapeRow::new();
    for i in 0..n {
        row.idx.clear();
        row.phi.clear();
        row.dx.clear();
        row.dy.clear();
        for k in shapes.ptr[i]..shapes.ptr[i + 1] {
            row.idx.push(shapes.idx[k]);
            row.phi.push(shapes.val[k][0]);
            row.dx.push(shapes.val[k][1]);
            row.dy.push(shapes.val[k][2]);
        }
        let smp = b.sample_row(&row);
        u[2 * i] = smp.u.x;
        u[2 * i + 1] = smp.u.y;
        v[2 * i] = smp.v.x;
        v[2 * i + 1] = smp.v.y;
        s[3 * i..3 * i + 3].copy_from_slice(&smp.stress);
    }
    let pts: Vec<[f64; 2]> = (0..n).map(|i| b.node(i).to_array()).collect();
    write_quad_grid(
        path,
        b.grid[0],
        b.grid[1],
        &pts,
        &[
            Field {
                name: "displacement",
                ncomp: 2,
                values: &u,
            },
            Field {
                name: "velocity",
                ncomp: 2,
                values: &v,
            },
            Field {
                name: "stress_xx_yy_xy",
                ncomp: 3,
                values: &s,
            },
        ],
    )?;
    Ok(())
}

fn body_summary(b: &EfgBody) -> Result<Value, EfgError> {
    let mut v = json!({
        "name": b.name,
        "build": b.info,
        "newmark": { "gamma": b.params.gamma, "beta": b.params.beta, "dt": b.params.dt },
        "kinetic_energy": b.kinetic_energy(),
        "strain_energy": b.strain_energy(),
    });
    if let Some(t) = &b.timoshenko {
        let tip = b.sample(Vec2::new(t.x0 + t.l, t.yc))?.u.y;
        let [nx, ny] = b.grid;
        let err = b.energy_error(|p| t.stress(p), [2 * (nx - 1), 2 * (ny - 1)], 4)?;
        v["timoshenko"] = json!({
            "tip_uy": tip,
            "tip_uy_exact": t.tip_deflection(),
            "tip_uy_relative_error": (tip - t.tip_deflection()) / t.tip_deflection(),
            "energy_norm_relative_error": err,
        });
    }
    Ok(v)
}

/// Run a continuum-only scenario.
pub fn run(sc: &Scenario, opts: &RunOptions) -> Result<Value, EfgError> {
    let t_start = Instant::now();
    let dir = &opts.out_dir;
    std::fs::create_dir_all(dir)?;
    let mut bodies = build_bodies(sc)?;
    let t_build = t_start.elapsed().as_secs_f64();
    let mut probes = bind_probes(sc, &bodies)?;
    let mut cols: Vec<&str> = vec!["step", "time"];
    cols.extend(probes.iter().map(|p| p.name.as_str()));
    let mut hist = HistoryWriter::create(&dir.join("history.csv"), &cols)?;
    let mut summary = json!({});
    let analysis = sc.simulation.analysis;
    let t_solve = Instant::now();
    match analysis {
        Analysis::Static => {
            for b in bodies.iter_mut() {
                b.solve_static()?;
            }
            record(&mut probes, &bodies, &mut hist, 0, 0.0)?;
            for b in &bodies {
                let shapes = b.nodal_shapes()?;
                write_frame(b, &shapes, &dir.join(format!("{}.vtu", b.name)))?;
            }
            summary["analysis"] = json!("static");
        }
        Analysis::Dynamic => {
            let dt = sc.simulation.dt.ok_or_else(|| {
                EfgError::Invalid("a dynamic analysis needs `simulation.dt`".into())
            })?;
            let steps = match (sc.simulation.steps, sc.simulation.end_time) {
                (Some(n), _) => n,
                (None, Some(t)) => (t / dt).ceil() as usize,
                (None, None) => {
                    return Err(EfgError::Invalid(
                        "a dynamic analysis needs `simulation.steps` or `simulation.end_time`"
                            .into(),
                    ));
                }
            };
            for (b, spec) in bodies.iter_mut().zip(&sc.body) {
                if spec.initial.is_some() {
                    b.solve_static()?;
                }
                b.start_dynamic(dt)?;
            }
            let vtk_every = sc.output.vtk_every;
            let frames = dir.join("frames");
            let mut series = Vec::new();
            let mut nodal = Vec::new();
            if vtk_every > 0 {
                std::fs::create_dir_all(&frames)?;
                for b in &bodies {
                    series.push(PvdSeries::new(&dir.join(format!("{}.pvd", b.name))));
                    nodal.push(b.nodal_shapes()?);
                }
            }
            let frame = |bodies: &[EfgBody],
                         series: &mut [PvdSeries],
                         step: usize|
             -> Result<(), EfgError> {
                for (k, b) in bodies.iter().enumerate() {
                    let f = format!("{}_{step:06}.vtu", b.name);
                    write_frame(b, &nodal[k], &frames.join(&f))?;
                    series[k].add(b.time, &format!("frames/{f}"))?;
                }
                Ok(())
            };
            record(&mut probes, &bodies, &mut hist, 0, 0.0)?;
            if vtk_every > 0 {
                frame(&bodies, &mut series, 0)?;
            }
            let pb = progress(steps as u64, opts.quiet);
            for step in 1..=steps {
                for b in bodies.iter_mut() {
                    b.advance()?;
                }
                let t = bodies[0].time;
                if step % sc.output.every == 0 || step == steps {
                    record(&mut probes, &bodies, &mut hist, step, t)?;
                }
                if vtk_every > 0 && (step % vtk_every == 0 || step == steps) {
                    frame(&bodies, &mut series, step)?;
                }
                pb.inc(1);
            }
            pb.finish_and_clear();
            summary["analysis"] = json!("dynamic");
            summary["steps"] = json!(steps);
            summary["dt"] = json!(dt);
            summary["end_time"] = json!(bodies[0].time);
        }
    }
    hist.flush()?;
    let solve_seconds = t_solve.elapsed().as_secs_f64();
    let mut extrema = serde_json::Map::new();
    for p in &probes {
        summary[p.name.as_str()] = json!(p.last);
        extrema.insert(
            p.name.clone(),
            json!({ "min": p.min, "max": p.max, "final": p.last }),
        );
    }
    summary["probes"] = Value::Object(extrema);
    summary["bodies"] = Value::Array(bodies.iter().map(body_summary).collect::<Result<_, _>>()?);
    summary["timing"] = json!({
        "build_seconds": t_build,
        "solve_seconds": solve_seconds,
        "total_seconds": t_start.elapsed().as_secs_f64(),
        "threads": rayon::current_num_threads(),
    });
    write_json(&dir.join("summary.json"), &summary)?;
    Ok(summary)
}

/// Validate further (build every body: coverage of every quadrature point,
/// probe points) and describe the problem, without solving.
pub fn check(sc: &Scenario) -> Result<String, EfgError> {
    let bodies = build_bodies(sc)?;
    bind_probes(sc, &bodies)?;
    let mut s = String::new();
    for (b, spec) in bodies.iter().zip(&sc.body) {
        let i = &b.info;
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
        let _ = writeln!(
            s,
            "  support coverage: {}–{} nodes per Gauss point (≥ 3 needed); K̄ lower triangle: {} entries",
            i.min_cover, i.max_cover, i.nnz
        );
        let _ = writeln!(
            s,
            "  material: E = {}, ν = {}, ρ = {}, t = {}, plane {:?}; penalty α = {:e}",
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
        "analysis: {:?}{}; {} probe(s)",
        sc.simulation.analysis,
        match (
            sc.simulation.analysis,
            sc.simulation.dt,
            sc.simulation.steps
        ) {
            (Analysis::Dynamic, Some(dt), Some(n)) => format!(", dt = {dt}, {n} steps"),
            (Analysis::Dynamic, Some(dt), None) =>
                format!(", dt = {dt}, end_time = {:?}", sc.simulation.end_time),
            _ => String::new(),
        },
        sc.probe.len()
    );
    Ok(s)
}
