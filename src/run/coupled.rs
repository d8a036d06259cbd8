//! Driver for coupled scenarios (bodies and discs): `efgdem run` / `check`.

use super::session::{Outputs, Session, checkpoint_due, due};
use super::{Run, RunError};
use crate::continuum::Edge;
use crate::coupling::energy::WorkMeter;
use crate::coupling::{CoupledModel, GUARD_STEPS, MAX_CREATED};
use crate::decomp::Comm;
use crate::geom::Vec2;
use crate::model::body::At;
use crate::model::body::BodyRef;
use crate::model::{Model, System, coupled_body as body};
use crate::output::csv::{BOND_COLUMNS, bond_row, write_bond_breaks};
use crate::output::write_json;
use crate::scenario::Scenario;
use on_ranks::OnRanks;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};
use std::sync::Arc;
use std::time::Instant;

mod on_ranks;

/// Watches for discs whose centre enters a body through an edge that is
/// not one of its contact edges: the body does not see such a disc from
/// outside, and its contact chains may see it from inside (forces up to
/// 2 k_n r). Each disc is reported once, as a warning on stderr.
struct EntryWatch {
    bodies: Vec<Watched>,
    polygons: Vec<WatchedPolygon>,
}

/// A polygon body with at least one segment outside its contact edges.
struct WatchedPolygon {
    body: usize,
    /// Per loop (outline, then holes, body on the left), its vertices:
    /// reference position and where to sample their displacement.
    loops: Vec<Vec<(Vec2, At)>>,
    /// Per loop, per segment (vertex k to k + 1): the name of the edge to
    /// report if it is not a contact edge, `None` if it is one.
    open: Vec<Vec<Option<String>>>,
}

/// A body with at least one edge that is not a contact edge.
struct Watched {
    body: usize,
    /// Corners counter-clockwise from the lower left: reference position
    /// and where to sample their displacement.
    corners: [(Vec2, At); 4],
    /// Edge k, from corner k to corner k + 1 ([`Edge::ALL`] order), is not
    /// a contact edge.
    open: [bool; 4],
}

impl EntryWatch {
    fn new(sc: &Scenario, m: &CoupledModel) -> Result<Self, crate::model::body::BodyError> {
        let mut bodies = Vec::new();
        let mut polygons = Vec::new();
        for (i, spec) in sc.body.iter().enumerate() {
            if let Ok(Some(d)) = spec.domain()
                && !spec.default_contact_edges()
            {
                // a segment is open unless a contact edge names it; it is
                // reported under the first named edge holding it
                let contact: Vec<(usize, usize)> = spec
                    .contact_edges
                    .iter()
                    .filter_map(|e| d.edge(e.as_str()))
                    .flat_map(|e| e.segments.iter().copied())
                    .collect();
                let open: Vec<Vec<Option<String>>> = d
                    .loops
                    .iter()
                    .enumerate()
                    .map(|(l, lp)| {
                        (0..lp.len())
                            .map(|s| {
                                (!contact.contains(&(l, s))).then(|| {
                                    d.edges
                                        .iter()
                                        .find(|e| e.segments.contains(&(l, s)))
                                        .map_or_else(
                                            || format!("loop {l}, segment {s}"),
                                            |e| e.name.clone(),
                                        )
                                })
                            })
                            .collect()
                    })
                    .collect();
                if open.iter().flatten().any(Option::is_some) {
                    let b = body(m, i);
                    let loops = d
                        .loops
                        .iter()
                        .map(|lp| {
                            lp.points
                                .iter()
                                .map(|&x| b.bind(x).map(|at| (x, at)))
                                .collect::<Result<Vec<_>, _>>()
                        })
                        .collect::<Result<Vec<_>, _>>()?;
                    polygons.push(WatchedPolygon {
                        body: i,
                        loops,
                        open,
                    });
                }
                continue;
            }
            let sides = spec.contact_sides();
            let open = Edge::ALL.map(|e| !sides.contains(&e));
            if spec.is_polygon() || !open.contains(&true) {
                continue;
            }
            let (o, s) = (
                Vec2::from(spec.rectangle.origin),
                Vec2::from(spec.rectangle.size),
            );
            let corners = [o, o + Vec2::new(s.x, 0.0), o + s, o + Vec2::new(0.0, s.y)];
            let b = body(m, i);
            let corners = [0, 1, 2, 3].map(|k| b.bind(corners[k]).map(|at| (corners[k], at)));
            let [c0, c1, c2, c3] = corners;
            bodies.push(Watched {
                body: i,
                corners: [c0?, c1?, c2?, c3?],
                open,
            });
        }
        Ok(EntryWatch { bodies, polygons })
    }

    /// Report the discs that entered a body through a non-contact edge since
    /// the last call (at output steps: one pass over the discs, like the
    /// energy account's) and are not yet marked in `reported` (by disc id).
    fn check(&self, m: &CoupledModel, names: &[String], reported: &mut [bool]) {
        let p = &m.granular.particles;
        for w in &self.bodies {
            let b = body(m, w.body);
            let at = w.corners.each_ref().map(|(x, at)| (*x, b.sample_at(at)));
            let quad = at.map(|(x, smp)| x + smp.u);
            let v_body = at.iter().fold(Vec2::ZERO, |s, (_, smp)| s + smp.v) * 0.25;
            let lo = quad
                .iter()
                .fold(quad[0], |a, c| Vec2::new(a.x.min(c.x), a.y.min(c.y)));
            let hi = quad
                .iter()
                .fold(quad[0], |a, c| Vec2::new(a.x.max(c.x), a.y.max(c.y)));
            for d in 0..p.len() {
                let x = p.pos[d];
                if x.x <= lo.x || x.x >= hi.x || x.y <= lo.y || x.y >= hi.y {
                    continue;
                }
                let id = p.id[d] as usize;
                if let Some(k) = entered_edge(&quad, x, p.vel[d] - v_body)
                    && w.open[k]
                    && !reported[id]
                {
                    reported[id] = true;
                    eprintln!(
                        "warning: disc {} entered body `{}` through a non-contact edge ({}) at t = {:.6} s (step {}); list the edge in `contact_edges` (default: all four)",
                        id + 1,
                        names[w.body],
                        Edge::ALL[k].name(),
                        m.granular.time,
                        m.granular.step
                    );
                }
            }
        }
        for w in &self.polygons {
            let b = body(m, w.body);
            let mut v_body = Vec2::ZERO;
            let mut count = 0.0;
            let loops: Vec<Vec<Vec2>> = w
                .loops
                .iter()
                .map(|lp| {
                    lp.iter()
                        .map(|(x, at)| {
                            let smp = b.sample_at(at);
                            v_body += smp.v;
                            count += 1.0;
                            *x + smp.u
                        })
                        .collect()
                })
                .collect();
            let v_body = v_body * (1.0 / count);
            let (lo, hi) = loops[0]
                .iter()
                .fold((loops[0][0], loops[0][0]), |(a, c), p| {
                    (
                        Vec2::new(a.x.min(p.x), a.y.min(p.y)),
                        Vec2::new(c.x.max(p.x), c.y.max(p.y)),
                    )
                });
            for d in 0..p.len() {
                let x = p.pos[d];
                if x.x <= lo.x || x.x >= hi.x || x.y <= lo.y || x.y >= hi.y {
                    continue;
                }
                let id = p.id[d] as usize;
                if reported[id] {
                    continue;
                }
                if let Some((l, k)) = entered_segment(&loops, x, p.vel[d] - v_body)
                    && let Some(name) = &w.open[l][k]
                {
                    reported[id] = true;
                    eprintln!(
                        "warning: disc {} entered body `{}` through a non-contact edge ({}) at t = {:.6} s (step {}); list the edge in `contact_edges` (default: every loop)",
                        id + 1,
                        names[w.body],
                        name,
                        m.granular.time,
                        m.granular.step
                    );
                }
            }
        }
    }
}

/// If `x` lies strictly inside the polygon with holes `loops` (outline
/// first; point in polygon by crossing numbers), the segment `(loop, k)`
/// (vertex k to k + 1) it came in through, moving with velocity `v`
/// relative to the polygon: the first segment hit when going back along
/// `−v`; the nearest segment if the ray back hits none (e.g. at rest).
fn entered_segment(loops: &[Vec<Vec2>], x: Vec2, v: Vec2) -> Option<(usize, usize)> {
    use crate::geom::polygon::inside_loop;
    if !inside_loop(&loops[0], x) || loops[1..].iter().any(|h| inside_loop(h, x)) {
        return None;
    }
    let mut nearest: Option<((usize, usize), f64)> = None;
    let mut crossed: Option<((usize, usize), f64)> = None;
    for (l, lp) in loops.iter().enumerate() {
        let n = lp.len();
        for k in 0..n {
            let (a, b) = (lp[k], lp[(k + 1) % n]);
            let dist = (x - crate::geom::closest_on_segment(x, a, b).1).norm();
            if nearest.is_none_or(|(_, d)| dist < d) {
                nearest = Some(((l, k), dist));
            }
            // x − t v = a + s (b − a), t > 0, 0 ≤ s ≤ 1
            let (e, w) = (b - a, x - a);
            let den = v.cross(e);
            if den != 0.0 {
                let t = w.cross(e) / den;
                let s = w.cross(v) / (-den);
                if t > 0.0 && (0.0..=1.0).contains(&s) && crossed.is_none_or(|(_, u)| t < u) {
                    crossed = Some(((l, k), t));
                }
            }
        }
    }
    crossed.or(nearest).map(|(k, _)| k)
}

/// If `x` lies strictly inside the convex quadrilateral `quad`
/// (counter-clockwise), the edge `quad[k] → quad[k + 1]` it came in
/// through, moving with velocity `v` relative to the quadrilateral: the
/// first edge hit when going back along `−v`; the nearest edge if `v` does
/// not point into the quadrilateral through any edge (e.g. at rest).
fn entered_edge(quad: &[Vec2; 4], x: Vec2, v: Vec2) -> Option<usize> {
    let mut nearest: Option<(usize, f64)> = None;
    let mut crossed: Option<(usize, f64)> = None;
    for k in 0..4 {
        let (a, b) = (quad[k], quad[(k + 1) % 4]);
        let n = (b - a).perp() * (1.0 / (b - a).norm()); // inward unit normal
        let h = n.dot(x - a); // distance inside the edge
        if h <= 0.0 {
            return None;
        }
        if nearest.is_none_or(|(_, m)| h < m) {
            nearest = Some((k, h));
        }
        // inward motion through this edge: it was on it h / (v·n) ago
        let vn = v.dot(n);
        if vn > 0.0 && crossed.is_none_or(|(_, s)| h / vn < s) {
            crossed = Some((k, h / vn));
        }
    }
    crossed.or(nearest).map(|(k, _)| k)
}

/// Reference points of each body's contact chains where the chain turns
/// (the rectangle's corners) or ends.
fn chain_corners(m: &CoupledModel) -> Vec<Vec<Vec<Vec2>>> {
    m.bodies
        .iter()
        .map(|b| {
            b.contact_boundary()
                .iter()
                .map(|c| {
                    let p = &c.reference;
                    (0..p.len())
                        .filter(|&i| {
                            i == 0
                                || i + 1 == p.len()
                                || (p[i] - p[i - 1]).cross(p[i + 1] - p[i]).abs()
                                    > 1e-12 * (p[i] - p[i - 1]).norm() * (p[i + 1] - p[i]).norm()
                        })
                        .map(|i| p[i])
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// What the run watches for in the contact force, for the summary
/// (§4.1.2 and §4.1.4 of the paper: single-disc events).
#[derive(Default, Serialize, Deserialize)]
struct Events {
    /// Largest total elastic contact force and when.
    peak: (f64, f64),
    first_contact: Option<f64>,
    /// After the peak, when the force no longer carries the disc's weight.
    below_weight: Option<f64>,
    lost_contact: Option<f64>,
    /// When a contact point reached a corner or end of a contact chain.
    fall_off: Option<f64>,
}

impl Events {
    /// Look at the contacts of the present state; returns the total
    /// elastic contact force.
    /// `weight`: the disc's weight in a single-disc run, `None` otherwise.
    fn observe(
        &mut self,
        m: &CoupledModel,
        corners: &[Vec<Vec<Vec2>>],
        weight: Option<f64>,
    ) -> f64 {
        let t = m.granular.time;
        let fn_sum: f64 = m.contacts.iter().map(|c| c.fn_elastic).sum();
        if fn_sum > self.peak.0 {
            self.peak = (fn_sum, t);
            self.below_weight = None;
        } else if let Some(w) = weight
            && self.below_weight.is_none()
            && self.peak.0 > w
            && fn_sum < w
        {
            self.below_weight = Some(t);
        }
        // §4.1.2: the disc falls off when its centre's projection leaves the
        // edge, i.e. its contact point reaches a corner (or end) of the
        // contact boundary — from there on it is a particle–point contact
        // (Fig. 5b)
        if weight.is_some()
            && self.fall_off.is_none()
            && m.contacts.iter().any(|c| {
                corners[c.body as usize][c.chain as usize]
                    .iter()
                    .any(|k| (*k - c.material).norm() <= 1e-9 * k.norm().max(1e-300))
            })
        {
            self.fall_off = Some(t);
        }
        if !m.contacts.is_empty() && self.first_contact.is_none() {
            self.first_contact = Some(t);
        }
        if m.contacts.is_empty() && self.first_contact.is_some() && self.lost_contact.is_none() {
            self.lost_contact = Some(t);
        }
        fn_sum
    }
}

/// The driver's running values (checkpointed with the model).
#[derive(Serialize, Deserialize)]
struct Running {
    events: Events,
    meter: WorkMeter,
    /// By disc id: reported as having entered a body.
    reported: Vec<bool>,
}

/// The disc's weight in a single-disc run.
fn single_weight(g: &crate::dem::Granular) -> Option<f64> {
    (g.particles.len() == 1).then(|| g.particles.mass[0] * g.gravity.norm())
}

/// Run a coupled scenario on the ranks of `comm` (one: the whole model
/// here; several: the discs divided over them, see [`OnRanks`]). Rank 0
/// writes the outputs and returns the summary, the others `Null`.
pub(super) fn run(run: Run, mut model: Model, comm: Arc<dyn Comm>) -> Result<Value, RunError> {
    let (sc, probes) = (run.sc, &run.probes);
    let root = comm.rank() == 0;
    let body_names = super::body_names(&model);
    let steps = model.steps;
    let m = coupled(&model);
    let body_dt = m.granular.dt * m.substeps as f64;
    if comm.size() > 1 {
        on_ranks_refusal(m)?;
    }
    if root && run.opts.warn {
        start_warnings(m)
            .iter()
            .for_each(|w| eprintln!("warning: {w}"));
    }
    let mut cols: Vec<&str> = vec!["step", "t"];
    cols.extend(probes.iter().map(|p| p.0.as_str()));
    cols.extend([
        "contact_fn",
        "E_kin_dem",
        "E_kin_body",
        "E_strain",
        "E_penalty",
        "E_contact",
        "W_ext",
        "E_diss",
    ]);
    let growing = sc.body.iter().any(|b| b.fracture.is_some());
    if growing {
        cols.push("E_fracture");
    }
    let bonded = coupled(&model).granular.bonds.active();
    if bonded {
        cols.extend(BOND_COLUMNS);
    }
    let opened = root.then(|| Outputs::open(&run, &model, &cols)).transpose();
    let mut out = super::ranks::agree(&*comm, opened)?;
    let mut r = match &run.restart {
        Some(ck) => ck.driver()?,
        None => Running {
            events: Events::default(),
            meter: WorkMeter::new(m),
            reported: vec![false; m.granular.particles.len()],
        },
    };
    let watch = EntryWatch::new(sc, m)?;
    let vtk_every = sc.output.vtk_every;
    let mut row = Vec::with_capacity(cols.len());
    let corners = chain_corners(m);
    // a decomposed model's granular is the discs near the bodies
    let fixed_weight = single_weight(&m.granular);
    let ranks_weight = comm.size() > 1;
    // the outputs of the present step (rank 0)
    let mut output = |model: &Model, r: &mut Running, out: &mut Outputs| -> Result<(), RunError> {
        let (step, m) = (model.step, coupled(model));
        let weight = if ranks_weight {
            fixed_weight
        } else {
            single_weight(&m.granular)
        };
        let fn_sum = r.events.observe(m, &corners, weight);
        if due(step, sc.output.every, steps) {
            watch.check(m, &body_names, &mut r.reported);
            let e = r.meter.account(m);
            row.clear();
            row.push(step as f64);
            row.push(m.granular.time);
            row.extend(probes.iter().map(|(_, p)| model.probe(p)));
            row.extend([
                fn_sum, e.kin_dem, e.kin_body, e.strain, e.penalty, e.contact, e.w_ext, e.diss,
            ]);
            if growing {
                row.push(e.fracture);
            }
            if bonded {
                row.extend(bond_row(&m.granular));
            }
            out.hist.row(&row)?;
        }
        if due(step, vtk_every, steps) {
            out.frames.write(model)?;
        }
        Ok(())
    };
    if run.restart.is_none()
        && let Some(out) = out.as_mut()
    {
        output(&model, &mut r, out)?;
    }
    let mut ranks = ranks_weight.then(|| OnRanks::new(&mut model, comm.clone()));
    let t_loop = Instant::now();
    let ended = match ranks.as_mut() {
        None => {
            let out = out.as_mut().expect("one rank writes");
            let mut session = Session::new(&run, &model);
            let ended = loop {
                // nothing reads the bodies after a step without outputs
                let next = model.step + 1;
                let defer = !(due(next, sc.output.every, steps)
                    || due(next, vtk_every, steps)
                    || checkpoint_due(next, run.opts.checkpoint_every, steps));
                if let Some(end) = session.step(&mut model, defer)? {
                    break end;
                }
                r.meter.after_step(&coupled(&model).granular);
                output(&model, &mut r, out)?;
                if let Some(end) = session.after_step(&mut model, out, &r)? {
                    break end;
                }
            };
            session.finish();
            ended
        }
        Some(rk) => match rk.drive(&run, &mut model, &mut r, out.as_mut(), &mut output) {
            Ok(ended) => ended,
            Err(e) => return super::ranks::agree(&*comm, Err(e)),
        },
    };
    let t_total = t_loop.elapsed().as_secs_f64();
    let res = match out.as_mut() {
        Some(out) => finish(
            &run,
            &model,
            ended,
            out,
            &r,
            ranks.as_ref(),
            (t_total, body_dt),
        ),
        None => Ok(Value::Null),
    };
    super::ranks::agree(&*comm, res)
}

/// Rank 0's end of the run: `bond_breaks.csv`, `summary.json`.
fn finish(
    run: &Run,
    model: &Model,
    ended: super::session::Ended,
    out: &mut Outputs,
    r: &Running,
    ranks: Option<&OnRanks>,
    (t_total, body_dt): (f64, f64),
) -> Result<Value, RunError> {
    let dir = &run.opts.out_dir;
    let steps = model.steps;
    let body_names = super::body_names(model);
    let bonded = coupled(model).granular.bonds.active();
    out.hist.flush()?;
    let m = coupled(model);
    if bonded {
        write_bond_breaks(&m.granular, &dir.join("bond_breaks.csv"))?;
    }
    let e = r.meter.account(m);
    let events = &r.events;
    let crit = m.granular.critical_step(&m.body_laws);
    let mut summary = json!({
        "kind": "coupled",
        "steps": steps,
        "dt": m.granular.dt,
        "body_dt": body_dt,
        "substeps": m.substeps,
        "coupling": m.scheme().name(),
        "scheme": m.choice,
        "warnings": start_warnings(m),
        "dem_critical_dt": crit.dt,
        "dem_critical_mode": crit.mode,
        "discs": m.granular.particles.len(),
        "bodies": body_names,
        "peak_contact_force": events.peak.0,
        "peak_contact_time": events.peak.1,
        "first_contact_time": events.first_contact,
        "fall_off_time": events.fall_off,
        "force_below_weight_time": events.below_weight,
        "contact_lost_time": events.lost_contact,
        "discs_entered_through_non_contact_edges": r.reported.iter().filter(|&&x| x).count(),
        "energy": {
            "E_kin_dem": e.kin_dem, "E_kin_body": e.kin_body, "E_strain": e.strain,
            "E_penalty": e.penalty, "E_contact": e.contact, "W_ext": e.w_ext, "E_diss": e.diss,
            "E_fracture": e.fracture,
        },
        "timing": {
            "build_seconds": run.build_s,
            "loop_seconds": t_total,
            "seconds_per_step": if model.step > 0 { t_total / model.step as f64 } else { 0.0 },
            "split_seconds": {
                "dem": m.timing.dem,
                "transfer": m.timing.transfer,
                "contact_solve": m.timing.contact_solve,
                "body_solve": m.timing.body,
            },
        },
    });
    if m.path_scheme() || m.fallback.is_some() {
        summary["subcycling"] = subcycling(m);
    }
    if let Some(rk) = ranks {
        summary["ranks"] = rk.record();
    }
    run.annotate(&mut summary)?;
    ended.record(&mut summary, model);
    write_json(&dir.join("summary.json"), &summary)?;
    ended.result(summary, model, dir)
}

/// What a coupled run warns of as it starts: the time step against the
/// critical step, the coupled scheme's choice.
fn start_warnings(m: &CoupledModel) -> Vec<String> {
    let dt = m.granular.dt_warning(&m.body_laws);
    let choice = m.choice.as_ref().and_then(|c| c.warning.clone());
    dt.into_iter().chain(choice).collect()
}

/// Why a coupled model cannot run on several ranks, if it cannot.
fn on_ranks_refusal(m: &CoupledModel) -> Result<(), RunError> {
    use crate::coupling::scheme::Scheme;
    let why = if matches!(m.scheme(), Scheme::Predicted | Scheme::Staggered) {
        format!(
            "the {} coupled scheme does not run on several ranks: name `coupling = \"exact\"` or `coupling = \"compliant\"` in [simulation], or run this scenario with one process",
            m.scheme().name()
        )
    } else if let Some(why) = super::ranks::discs_refusal(&m.granular) {
        why.into()
    } else {
        return Ok(());
    };
    Err(RunError::Ranks(why))
}

fn coupled(model: &Model) -> &CoupledModel {
    model.coupled().expect("a coupled model")
}

/// Per body, the sub-cycled scheme's energy account for `summary.json`:
/// what it created, the work exchanged, and what the balance is (with
/// γ = ½ the body's energy balance, else the interface's alone).
fn subcycling(m: &CoupledModel) -> Value {
    let bodies: Vec<Value> = (m.bodies.iter().enumerate())
        .map(|(i, b)| {
            let (created, exchanged) = b.path_energy();
            let gamma = body(m, i).newmark().map_or(0.5, |nm| nm.params.gamma);
            json!({
                "body": b.name(),
                "E_created": created,
                "W_exchanged": exchanged,
                "balance": if gamma == 0.5 { "energy" } else { "interface" },
            })
        })
        .collect();
    json!({ "bodies": bodies, "limit": MAX_CREATED, "guard_steps": GUARD_STEPS })
}

/// What `efgdem check` says of the coupled scheme: the choice and why,
/// and the predicted scheme's gains examined.
fn scheme_lines(m: &CoupledModel) -> String {
    let Some(c) = &m.choice else {
        return String::new();
    };
    let mut s = format!(
        "coupled scheme: {} with {} DEM step(s) per body step ({}): {}
",
        c.scheme.name(),
        c.substeps,
        if c.automatic { "chosen" } else { "as named" },
        c.why
    );
    s += &format!(
        "  the exact step's body solves are estimated at {:.2} × the DEM step; the bodies' chains can carry {} contacts at once\n",
        c.exact_overhead, c.max_contacts
    );
    if c.body_omega_dt > 0.0 {
        s += &format!(
            "  the bodies' collective mode: ω_b Δt = {:.3} (the contacts' ω_c Δt = {:.3})\n",
            c.body_omega_dt, c.omega_dt
        );
    }
    for (n, g) in &c.gains {
        let per: Vec<String> = (m.bodies.iter().zip(g))
            .map(|(b, g)| format!("`{}` {g:.4}", b.name()))
            .collect();
        s += &format!(
            "  predicted scheme at {n} substeps (ω_c h = {:.2}): collective gain {}
",
            c.omega_dt * *n as f64,
            per.join(", ")
        );
    }
    if m.path_scheme() {
        s += &format!(
            "  {} if a body's scheme creates more than {} % of the work it exchanges with the discs for {GUARD_STEPS} body steps in a row\n",
            if c.automatic {
                "the run goes on with at most half the substeps (then the exact step)"
            } else {
                "a run stops"
            },
            100.0 * MAX_CREATED
        );
    }
    if let Some(w) = &c.warning {
        s += &format!("warning: {w}\n");
    }
    s
}

/// What `efgdem check` prints for a coupled scenario.
pub(super) fn check(full: &Model) -> String {
    let System::Coupled(model) = &full.system else {
        unreachable!("a coupled model")
    };
    let g = &model.granular;
    let mut s = format!(
        "coupled run: {} discs, {} walls, {} bodies; {} steps of dt = {:e} (bodies: dt = {:e}, {} DEM steps each)\n{}\n",
        g.particles.len(),
        g.walls.len(),
        model.bodies.len(),
        full.steps,
        g.dt,
        model.granular.dt * model.substeps as f64,
        model.substeps,
        super::granular::time_step_line(g.dt, &g.critical_step(&model.body_laws)),
    );
    s += &scheme_lines(model);
    for (i, c) in model.bodies.iter().enumerate() {
        let n = body(model, i).n_nodes();
        s += &format!(
            "body `{}` ({}): {} nodes, {} DOFs, {} contact chain(s) with {} segments\n",
            c.name(),
            match body(model, i) {
                BodyRef::Efg(_) => "EFG",
                BodyRef::Fem(_) => "FE Q4",
            },
            n,
            2 * n,
            c.contact_boundary().len(),
            c.contact_boundary()
                .iter()
                .map(|ch| ch.segments())
                .sum::<usize>()
        );
    }
    if let Some(w) = g.dt_warning(&model.body_laws) {
        s += &format!("warning: {w}\n");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disc_inside_is_attributed_to_the_edge_it_came_through() {
        // a slightly sheared rectangle [0, 2] × [0, 1], counter-clockwise
        let q = [
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.1, 1.0),
            Vec2::new(0.1, 1.0),
        ];
        let rest = Vec2::ZERO;
        // at rest: the nearest edge
        assert_eq!(entered_edge(&q, Vec2::new(1.0, 0.01), rest), Some(0)); // bottom
        assert_eq!(entered_edge(&q, Vec2::new(2.02, 0.5), rest), Some(1)); // right
        assert_eq!(entered_edge(&q, Vec2::new(1.0, 0.98), rest), Some(2)); // top
        assert_eq!(entered_edge(&q, Vec2::new(0.1, 0.5), rest), Some(3)); // left
        // outside (left of the sheared edge) or on the boundary: none
        assert_eq!(entered_edge(&q, Vec2::new(0.02, 0.5), rest), None);
        assert_eq!(entered_edge(&q, Vec2::new(1.0, 1.0), rest), None);
        assert_eq!(entered_edge(&q, Vec2::new(1.0, -0.1), rest), None);
        // moving: the edge behind it, even if another one is nearer
        let x = Vec2::new(1.2, 0.9);
        assert_eq!(entered_edge(&q, x, Vec2::new(1.0, 0.0)), Some(3)); // from the left
        assert_eq!(entered_edge(&q, x, Vec2::new(-1.0, 0.0)), Some(1)); // from the right
        assert_eq!(entered_edge(&q, x, Vec2::new(0.0, 1.0)), Some(0)); // from below
        assert_eq!(entered_edge(&q, x, Vec2::new(1.0, 1.0)), Some(0)); // corner: bottom first
        assert_eq!(entered_edge(&q, x, Vec2::new(0.1, -1.0)), Some(2)); // from above
    }

    #[test]
    fn entered_segment_of_a_polygon_with_a_hole() {
        // an L-shape (outline counter-clockwise) with a square hole stored
        // clockwise (body on the left of every segment)
        let v = |p: &[[f64; 2]]| p.iter().map(|&a| Vec2::from(a)).collect::<Vec<_>>();
        let loops = vec![
            v(&[
                [0.0, 0.0],
                [4.0, 0.0],
                [4.0, 2.0],
                [2.0, 2.0],
                [2.0, 4.0],
                [0.0, 4.0],
            ]),
            v(&[[0.5, 0.5], [0.5, 1.5], [1.5, 1.5], [1.5, 0.5]]),
        ];
        let rest = Vec2::ZERO;
        // outside: beyond the re-entrant corner, inside the hole, beyond x = 4
        assert_eq!(entered_segment(&loops, Vec2::new(3.0, 3.0), rest), None);
        assert_eq!(entered_segment(&loops, Vec2::new(1.0, 1.0), rest), None);
        assert_eq!(entered_segment(&loops, Vec2::new(4.5, 1.0), rest), None);
        // at rest: the nearest segment
        assert_eq!(
            entered_segment(&loops, Vec2::new(2.9, 1.95), rest),
            Some((0, 2))
        );
        assert_eq!(
            entered_segment(&loops, Vec2::new(1.6, 1.0), rest),
            Some((1, 2))
        );
        // moving: the segment crossed going back along −v
        let x = Vec2::new(1.7, 1.0);
        assert_eq!(
            entered_segment(&loops, x, Vec2::new(1.0, 0.0)),
            Some((1, 2))
        ); // out of the hole
        assert_eq!(
            entered_segment(&loops, x, Vec2::new(-1.0, 0.0)),
            Some((0, 1))
        ); // from x = 4
        assert_eq!(
            entered_segment(&loops, x, Vec2::new(0.0, 1.0)),
            Some((0, 0))
        ); // from below
        // from above through the re-entrant step y = 2 (segment 2)
        let y = Vec2::new(3.0, 1.9);
        assert_eq!(
            entered_segment(&loops, y, Vec2::new(0.0, -1.0)),
            Some((0, 2))
        );
    }
}
