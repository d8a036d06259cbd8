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
//! Bodies are EFG ([`EfgBody`]) or bilinear FE ([`FemBody`],
//! `method = "fem-q4"`); both are driven the same way through the private `Body` enum.

use super::assemble::PointShapes;
use super::body::EfgBody;
use super::{EfgError, Sample, ShapeRow};
use crate::fem::FemBody;
use crate::fem::body::Located;
use crate::geom::Vec2;
use crate::output::csv::HistoryWriter;
use crate::output::vtk::PvdSeries;
use crate::output::vtu::{Field, write_quad_grid};
use crate::output::{progress, write_json};
use crate::run::RunOptions;
use crate::scenario::body::BODY_QUANTITIES;
use crate::scenario::body::Method;
use crate::scenario::{Analysis, Probe, Scenario};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// A continuum body of either method, driven the same way.
enum Body {
    Efg(Box<EfgBody>),
    Fem(Box<FemBody>),
}

impl Body {
    fn name(&self) -> &str {
        match self {
            Body::Efg(b) => &b.name,
            Body::Fem(b) => &b.name,
        }
    }
    fn time(&self) -> f64 {
        match self {
            Body::Efg(b) => b.time,
            Body::Fem(b) => b.time,
        }
    }
    fn solve_static(&mut self) -> Result<(), EfgError> {
        match self {
            Body::Efg(b) => b.solve_static(),
            Body::Fem(b) => Ok(b.solve_static()?),
        }
    }
    fn start_dynamic(&mut self, dt: f64) -> Result<(), EfgError> {
        match self {
            Body::Efg(b) => b.start_dynamic(dt),
            Body::Fem(b) => Ok(b.start_dynamic(dt)?),
        }
    }
    fn advance(&mut self) -> Result<(), EfgError> {
        match self {
            Body::Efg(b) => b.advance(),
            Body::Fem(b) => Ok(b.advance()?),
        }
    }
    fn kinetic_energy(&self) -> f64 {
        match self {
            Body::Efg(b) => b.kinetic_energy(),
            Body::Fem(b) => b.kinetic_energy(),
        }
    }
    fn strain_energy(&self) -> f64 {
        match self {
            Body::Efg(b) => b.strain_energy(),
            Body::Fem(b) => b.strain_energy(),
        }
    }
    fn view(&self) -> BodyRef<'_> {
        match self {
            Body::Efg(b) => BodyRef::Efg(b),
            Body::Fem(b) => BodyRef::Fem(b),
        }
    }
}

/// A borrowed body of either method: what probes and frames need. Shared
/// with the coupled driver, whose bodies live inside the coupled model.
#[derive(Clone, Copy)]
pub(crate) enum BodyRef<'a> {
    Efg(&'a EfgBody),
    Fem(&'a FemBody),
}

impl BodyRef<'_> {
    pub(crate) fn n_nodes(self) -> usize {
        match self {
            BodyRef::Efg(b) => b.n_nodes(),
            BodyRef::Fem(b) => b.n_nodes(),
        }
    }
    /// Bind a sampling point: a shape row (EFG) or an element (FE).
    pub(crate) fn bind(self, p: Vec2) -> Result<At, EfgError> {
        match self {
            BodyRef::Efg(b) => {
                let mut r = ShapeRow::new();
                b.shape_row(p, &mut r)?;
                Ok(At::Row(r))
            }
            BodyRef::Fem(b) => Ok(At::Element(b.locate(p)?)),
        }
    }
    pub(crate) fn sample_at(self, at: &At) -> Sample {
        match (self, at) {
            (BodyRef::Efg(b), At::Row(r)) => b.sample_row(r),
            (BodyRef::Fem(b), At::Element(l)) => b.sample_located(l),
            _ => unreachable!("a probe is bound by its own body"),
        }
    }
    /// Per-body data for frames: EFG nodal shape rows (FE needs none).
    pub(crate) fn frame_data(self) -> Result<Option<PointShapes>, EfgError> {
        match self {
            BodyRef::Efg(b) => Ok(Some(b.nodal_shapes()?)),
            BodyRef::Fem(_) => Ok(None),
        }
    }
    /// A `.vtu` frame: true nodal displacement, velocity and stress.
    pub(crate) fn write_frame(
        self,
        shapes: Option<&PointShapes>,
        path: &Path,
    ) -> Result<(), EfgError> {
        match (self, shapes) {
            (BodyRef::Efg(b), Some(s)) => write_frame_efg(b, s, path),
            (BodyRef::Fem(b), _) => {
                let (u, v, s) = b.nodal_fields();
                let pts: Vec<[f64; 2]> = (0..b.n_nodes()).map(|i| b.node(i).to_array()).collect();
                write_fields(path, b.grid, &pts, &u, &v, &s)
            }
            _ => unreachable!("EFG frames need nodal shapes"),
        }
    }
}

/// A sampling point bound to a body.
pub(crate) enum At {
    Row(ShapeRow),
    Element(Located),
}

/// A probe resolved to a body and, for point quantities, a bound point.
struct BoundProbe {
    name: String,
    body: usize,
    quantity: String,
    row: Option<At>,
    min: f64,
    max: f64,
    last: f64,
}

fn build_bodies(sc: &Scenario) -> Result<Vec<Body>, EfgError> {
    let g = sc.simulation.gravity;
    sc.body
        .iter()
        .map(|b| match b.method {
            Method::Efg => Ok(Body::Efg(Box::new(EfgBody::new(&b.params(), g)?))),
            Method::FemQ4 => Ok(Body::Fem(Box::new(FemBody::new(&b.params(), g)?))),
        })
        .collect()
}

fn bind_probes(sc: &Scenario, bodies: &[Body]) -> Result<Vec<BoundProbe>, EfgError> {
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
            Some(n) => bodies.iter().position(|b| b.name() == n),
            None => Some(0),
        }
        .ok_or_else(|| EfgError::Invalid(format!("probe `{name}`: no body `{body:?}`")))?;
        let row = match point {
            Some(pt) if !BODY_QUANTITIES.contains(&quantity.as_str()) => {
                Some(bodies[bi].view().bind(Vec2::from(*pt))?)
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

fn probe_value(p: &BoundProbe, b: &Body) -> f64 {
    let energy = |q: &str| match q {
        "kinetic_energy" => b.kinetic_energy(),
        "strain_energy" => b.strain_energy(),
        _ => b.kinetic_energy() + b.strain_energy(),
    };
    let Some(row) = &p.row else {
        return energy(&p.quantity);
    };
    b.view()
        .sample_at(row)
        .field(&p.quantity)
        .unwrap_or_else(|| energy(&p.quantity))
}

fn record(
    probes: &mut [BoundProbe],
    bodies: &[Body],
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
fn write_frame_efg(b: &EfgBody, shapes: &PointShapes, path: &Path) -> Result<(), EfgError> {
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
    write_fields(path, b.grid, &pts, &u, &v, &s)
}

fn write_fields(
    path: &Path,
    grid: [usize; 2],
    pts: &[[f64; 2]],
    u: &[f64],
    v: &[f64],
    s: &[f64],
) -> Result<(), EfgError> {
    write_quad_grid(
        path,
        grid[0],
        grid[1],
        pts,
        &[
            Field {
                name: "displacement",
                ncomp: 2,
                values: u,
            },
            Field {
                name: "velocity",
                ncomp: 2,
                values: v,
            },
            Field {
                name: "stress_xx_yy_xy",
                ncomp: 3,
                values: s,
            },
        ],
    )?;
    Ok(())
}

fn body_summary(b: &Body) -> Result<Value, EfgError> {
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
                let shapes = b.view().frame_data()?;
                b.view()
                    .write_frame(shapes.as_ref(), &dir.join(format!("{}.vtu", b.name())))?;
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
                    series.push(PvdSeries::new(&dir.join(format!("{}.pvd", b.name()))));
                    nodal.push(b.view().frame_data()?);
                }
            }
            let frame =
                |bodies: &[Body], series: &mut [PvdSeries], step: usize| -> Result<(), EfgError> {
                    for (k, b) in bodies.iter().enumerate() {
                        let f = format!("{}_{step:06}.vtu", b.name());
                        b.view().write_frame(nodal[k].as_ref(), &frames.join(&f))?;
                        series[k].add(b.time(), &format!("frames/{f}"))?;
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
                let t = bodies[0].time();
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
            summary["end_time"] = json!(bodies[0].time());
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
                    "  material: E = {}, ν = {}, ρ = {}, t = {}, plane {:?}",
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
