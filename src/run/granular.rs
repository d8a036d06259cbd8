//! Driver for granular-only scenarios (discs and walls): `efgdem run` and
//! `efgdem check`.

use super::build::{self, DT_WARN};
use super::{DemError, Granular};
use crate::output::csv::HistoryWriter;
use crate::output::vtk::PvdSeries;
use crate::output::vtp::{DiscFrame, write_discs};
use crate::output::{progress, write_json};
use crate::run::RunOptions;
use crate::scenario::{Probe, Scenario};
use serde_json::json;
use std::io::Write;
use std::time::Instant;

/// A probe resolved against the built assembly (disc numbers are 0-based
/// scenario ids; slots are looked up at every sample since discs are
/// renumbered in memory).
#[derive(Debug, Clone)]
enum Sample {
    Normal { a: usize, b: usize, total: bool },
    Wall { w: usize, q: &'static str },
    Disc { id: usize, q: &'static str },
    Global(&'static str),
}

fn resolve(sc: &Scenario, gr: &Granular) -> Result<Vec<(String, Sample)>, DemError> {
    let n = gr.particles.len();
    let disc = |k: usize, pr: &Probe| {
        if k >= 1 && k <= n {
            Ok(k - 1)
        } else {
            Err(DemError::Input(format!(
                "probe `{}`: disc {k} does not exist (the assembly has {n} discs, numbered from 1)",
                pr.name
            )))
        }
    };
    let stat = |q: &str, list: &[&'static str]| list.iter().copied().find(|x| *x == q);
    use crate::scenario::granular::*;
    sc.probe
        .iter()
        .map(|pr| {
            let q = pr.quantity.as_str();
            let s = if let Some(&[a, b]) = pr
                .contact
                .as_ref()
                .filter(|_| CONTACT_QUANTITIES.contains(&q))
            {
                Sample::Normal {
                    a: disc(a, pr)?,
                    b: disc(b, pr)?,
                    total: q == "normal_total",
                }
            } else if let Some(qq) = stat(q, WALL_QUANTITIES) {
                let name = pr.wall.as_deref().unwrap_or("");
                let w = gr
                    .walls
                    .iter()
                    .position(|w| w.name == name)
                    .ok_or_else(|| {
                        DemError::Input(format!("probe `{}`: no wall named `{name}`", pr.name))
                    })?;
                Sample::Wall { w, q: qq }
            } else if let Some(qq) = stat(q, DISC_QUANTITIES) {
                Sample::Disc {
                    id: disc(pr.disc.unwrap_or(0), pr)?,
                    q: qq,
                }
            } else if let Some(qq) = stat(q, GLOBAL_QUANTITIES) {
                Sample::Global(qq)
            } else {
                return Err(DemError::Input(format!(
                    "probe `{}`: quantity `{q}` is not known to a granular run",
                    pr.name
                )));
            };
            Ok((pr.name.clone(), s))
        })
        .collect()
}

/// A wall probe quantity ([`WALL_QUANTITIES`](crate::scenario::granular::WALL_QUANTITIES)).
pub(crate) fn wall_quantity(w: &super::walls::Wall, q: &str) -> f64 {
    match q {
        "wall_fx" => w.force.x,
        "wall_fy" => w.force.y,
        "wall_x" => w.a.x,
        _ => w.a.y,
    }
}

/// A disc probe quantity of scenario disc `id` (0-based)
/// ([`DISC_QUANTITIES`](crate::scenario::granular::DISC_QUANTITIES)).
pub(crate) fn disc_quantity(gr: &Granular, id: usize, q: &str) -> f64 {
    let k = gr.slot(id);
    let p = &gr.particles;
    match q {
        "x" => p.pos[k].x,
        "y" => p.pos[k].y,
        "vx" => p.vel[k].x,
        "vy" => p.vel[k].y,
        "theta" => p.theta[k],
        _ => p.omega[k],
    }
}

fn sample(gr: &Granular, s: &Sample) -> f64 {
    match *s {
        Sample::Normal { a, b, total } => {
            let (el, tot) = gr.normal_force(gr.slot(a), gr.slot(b));
            if total { tot } else { el }
        }
        Sample::Wall { w, q } => wall_quantity(&gr.walls[w], q),
        Sample::Disc { id, q } => disc_quantity(gr, id, q),
        Sample::Global(q) => global_quantity(gr, q),
    }
}

/// An assembly-wide probe quantity
/// ([`GLOBAL_QUANTITIES`](crate::scenario::granular::GLOBAL_QUANTITIES)).
pub(crate) fn global_quantity(gr: &Granular, q: &str) -> f64 {
    if q == "contacts" {
        let (a, b) = gr.touching();
        return (a + b) as f64;
    }
    let e = gr.energies();
    match q {
        "kinetic" => e.kinetic,
        "rotational" => e.rotational,
        "spring" => e.spring,
        "gravity_energy" => e.gravity,
        _ => e.total(),
    }
}

/// Write a ParaView frame of the present state.
pub fn write_frame(gr: &Granular, path: &std::path::Path) -> std::io::Result<()> {
    let p = &gr.particles;
    let contacts: Vec<(u32, u32, f64)> = gr
        .contacts
        .pairs
        .iter()
        .filter_map(|q| {
            let (el, _) = gr.normal_force(q.i as usize, q.j as usize);
            (el > 0.0).then_some((q.i, q.j, el))
        })
        .collect();
    let walls: Vec<_> = gr.walls.iter().map(|w| (w.a, w.b)).collect();
    write_discs(
        path,
        &DiscFrame {
            pos: &p.pos,
            radius: &p.radius,
            vel: &p.vel,
            omega: &p.omega,
            force: &p.force,
            id: &p.id,
            contacts: &contacts,
            walls: &walls,
        },
    )
}

/// Write the discs as `x,y,r,vx,vy,omega` in scenario order (readable as a
/// `discs = { csv = ... }` source: the extra columns are... not accepted,
/// so only `x,y,r` are written).
pub fn write_discs_csv(gr: &Granular, path: &std::path::Path) -> std::io::Result<()> {
    let p = &gr.particles;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "x,y,r")?;
    for id in 0..p.len() {
        let k = p.slot[id] as usize;
        writeln!(w, "{:e},{:e},{:e}", p.pos[k].x, p.pos[k].y, p.radius[k])?;
    }
    w.flush()
}

/// Run a granular scenario: `history.csv` (columns `cycle, t` and one per
/// probe, a row every `output.every` steps after the step),
/// `frames/discs_NNNNNN.vtp` + `discs.pvd` every `output.vtk_every` steps,
/// `discs_final.csv` and `summary.json`.
pub fn run(sc: &Scenario, opts: &RunOptions) -> Result<serde_json::Value, DemError> {
    let t_build = Instant::now();
    let mut gr = build::build(sc)?;
    let build_s = t_build.elapsed().as_secs_f64();
    let steps = build::steps(sc, gr.dt);
    let mut warnings = Vec::new();
    if let Some(w) = build::dt_warning(&gr) {
        eprintln!("warning: {w}");
        warnings.push(w);
    }
    let probes = resolve(sc, &gr)?;
    let out = &opts.out_dir;
    std::fs::create_dir_all(out)?;
    let mut cols = vec!["cycle", "t"];
    cols.extend(probes.iter().map(|p| p.0.as_str()));
    let mut hist = HistoryWriter::create(&out.join("history.csv"), &cols)?;
    let every = sc.output.every.max(1);
    let vtk_every = sc.output.vtk_every;
    let mut pvd = None;
    if vtk_every > 0 {
        std::fs::create_dir_all(out.join("frames"))?;
        let mut s = PvdSeries::new(&out.join("discs.pvd"));
        let f = "frames/discs_000000.vtp";
        gr.prepare_contacts();
        write_frame(&gr, &out.join(f))?;
        s.add(0.0, f)?;
        pvd = Some(s);
    }
    let pb = progress(steps as u64, opts.quiet);
    let mut row = vec![0.0; cols.len()];
    let t0 = Instant::now();
    let mut last_pb = 0usize;
    for cycle in 1..=steps {
        // disc forces are only read by the frames
        gr.store_forces = vtk_every > 0 && cycle % vtk_every == 0;
        gr.step();
        if cycle % 256 == 0 {
            gr.check_finite()?;
        }
        if cycle % every == 0 {
            row[0] = cycle as f64;
            row[1] = gr.time;
            for (k, (_, s)) in probes.iter().enumerate() {
                row[2 + k] = sample(&gr, s);
            }
            hist.row(&row)?;
        }
        if let Some(s) = pvd.as_mut()
            && cycle % vtk_every == 0
        {
            let f = format!("frames/discs_{cycle:06}.vtp");
            write_frame(&gr, &out.join(&f))?;
            s.add(gr.time, &f)?;
        }
        if cycle - last_pb >= 1000 || cycle == steps {
            pb.inc((cycle - last_pb) as u64);
            last_pb = cycle;
        }
    }
    pb.finish_and_clear();
    hist.flush()?;
    let wall_s = t0.elapsed().as_secs_f64();
    gr.check_finite()?;
    write_discs_csv(&gr, &out.join("discs_final.csv"))?;
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
pub fn check(sc: &Scenario) -> Result<String, DemError> {
    let gr = build::build(sc)?;
    resolve(sc, &gr)?;
    let p = &gr.particles;
    let n = p.len();
    let (rmin, rmax) = p
        .radius
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
    let crit = gr.critical_dt();
    let steps = build::steps(sc, gr.dt);
    let mut s = format!(
        "granular: {n} discs (radius {rmin:e} … {rmax:e}), {} walls, {} materials\n\
         time step: dt = {:e}, critical 2√(m_min/k_max) = {crit:e} (dt/critical = {:.4}; warn above {DT_WARN})\n\
         steps: {steps} (end time {:e})\n\
         damping: {:?}, body damping {:?}",
        gr.walls.len(),
        gr.materials.len(),
        gr.dt,
        gr.dt / crit,
        steps as f64 * gr.dt,
        sc.granular.as_ref().map(|g| g.damping),
        gr.damping,
    );
    if let Some(w) = build::dt_warning(&gr) {
        s.push_str(&format!("\nwarning: {w}"));
    }
    Ok(s)
}
