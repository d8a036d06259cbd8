//! Build the model a scenario describes, in one pass after validation:
//! discs (inline, CSV, generated), materials with the named damping, walls
//! with their motion, bodies (EFG or FE), the coupled model, and the
//! probes bound to their targets. Every problem found here is an
//! [`Invalid`] with the path of the field it comes from, so that the
//! scenario reports it as `file:line: field: message`.

use super::body::{
    BODY_QUANTITIES, CONTACT_FORCE_QUANTITIES, Method, POINT_QUANTITIES, is_body_probe,
};
use super::generate::discs_from_csv;
use super::granular::{
    CONTACT_QUANTITIES, DISC_QUANTITIES, DampingSpec, DiscsSpec, GLOBAL_QUANTITIES, Generator,
    GranularSpec, Packing, SlipNormalSpec, WALL_QUANTITIES, slip_normal,
};
use super::{Analysis, ContactSolve, CouplingScheme, Invalid, Scenario};
use crate::continuum::ComplianceMode;
use crate::continuum::Continuum;
use crate::coupling::CoupledModel;
use crate::dem::contact::{ContactLaw, SlipNormal};
use crate::dem::packing::{
    DiscRow, Lattice, grow_in_box, lattice_packing, overlapping_pairs, settle_in_box,
};
use crate::dem::particles::Particles;
use crate::dem::{BodyDamping, DT_WARN, Granular};
use crate::efg::EfgBody;
use crate::efg::boundary::EfgContinuum;
use crate::fem::{FemBody, FemContinuum};
use crate::geom::Vec2;
use crate::model::body::Body;
use crate::model::{Model, Probe, System};

/// Default fraction of the critical step when `simulation.dt` is omitted.
pub const DT_SAFETY: f64 = 0.1;

fn bad(path: &str, message: impl std::fmt::Display) -> Invalid {
    Invalid {
        path: path.to_string(),
        message: message.to_string(),
    }
}

fn spec(sc: &Scenario) -> Result<&GranularSpec, Invalid> {
    sc.granular
        .as_ref()
        .ok_or_else(|| bad("granular", "the scenario has no [granular] section"))
}

/// Contact law of every scenario material with the scenario's dashpots, and
/// the body damping.
pub fn laws(sc: &Scenario, damping: &DampingSpec) -> (Vec<ContactLaw>, BodyDamping) {
    let mut body = BodyDamping::None;
    let mats = sc
        .material
        .iter()
        .map(|m| {
            let mut l = ContactLaw {
                kn: m.kn,
                ks: m.ks,
                mu: m.friction,
                cohesion: m.cohesion,
                slip_normal: match slip_normal(m) {
                    Some(SlipNormalSpec::Elastic) => SlipNormal::Elastic,
                    _ => SlipNormal::Total,
                },
                mu_roll: m.rolling_friction,
                roll_stiffness: m.rolling_stiffness,
                roll_damping: m.rolling_damping,
                ..Default::default()
            };
            match *damping {
                DampingSpec::None => {}
                DampingSpec::ContactViscous {
                    beta,
                    beta_shear,
                    no_tension,
                } => {
                    l.beta_n = beta;
                    l.beta_s = beta_shear;
                    l.no_tension = no_tension;
                }
                DampingSpec::CriticalRatio {
                    zeta,
                    zeta_shear,
                    no_tension,
                } => {
                    l.zeta_n = zeta;
                    l.zeta_s = zeta_shear;
                    l.no_tension = no_tension;
                }
                DampingSpec::Local { alpha } => body = BodyDamping::Local { alpha },
                DampingSpec::Global { c, c_rot } => body = BodyDamping::Mass { c, c_rot },
            }
            l
        })
        .collect();
    (mats, body)
}

fn material_index(sc: &Scenario, name: &str, path: &str) -> Result<u16, Invalid> {
    sc.material
        .iter()
        .position(|m| m.name == name)
        .map(|i| i as u16)
        .ok_or_else(|| bad(path, format!("no [[material]] named `{name}`")))
}

/// The discs the scenario describes (generating or reading them).
fn disc_rows(sc: &Scenario) -> Result<Vec<DiscRow>, Invalid> {
    let g = spec(sc)?;
    match &g.discs {
        DiscsSpec::Inline(rows) => Ok(rows
            .iter()
            .map(|r| DiscRow {
                pos: Vec2::new(r[0], r[1]),
                r: r[2],
                material: None,
            })
            .collect()),
        DiscsSpec::Table(t) => {
            if let Some(csv) = &t.csv {
                let path = sc.resolve(csv);
                let text = std::fs::read_to_string(&path).map_err(|e| {
                    bad(
                        "granular.discs.csv",
                        format!("cannot read discs file {}: {e}", path.display()),
                    )
                })?;
                return discs_from_csv(&text)
                    .map_err(|e| bad("granular.discs.csv", format!("{}: {e}", path.display())));
            }
            let kind = t
                .generate
                .ok_or_else(|| bad("granular.discs", "nothing to generate"))?;
            let [a, b] = t
                .region
                .ok_or_else(|| bad("granular.discs", "`box` is missing"))?;
            let radius = t
                .radius
                .ok_or_else(|| bad("granular.discs", "`radius` is missing"))?
                .range();
            let (lat, gap, jitter) = match kind {
                Generator::Square => (Lattice::Square, 0.0, t.jitter.unwrap_or(0.0)),
                Generator::Hex => (Lattice::Hex, 0.0, t.jitter.unwrap_or(0.0)),
                Generator::Random => (Lattice::Hex, 0.1, t.jitter.unwrap_or(1.0)),
            };
            let (lo, hi) = (Vec2::from(a), Vec2::from(b));
            let steps = t.settle_steps.unwrap_or(20_000);
            if kind == Generator::Random && t.method == Packing::Grow {
                let count = t
                    .count
                    .ok_or_else(|| bad("granular.discs", "`method = \"grow\"` needs `count`"))?;
                let g = spec(sc)?;
                let mi = material_index(sc, &g.material, "granular.material")? as usize;
                let (mats, _) = laws(sc, &DampingSpec::None);
                let density = sc.material[mi].density;
                return grow_in_box(
                    lo,
                    hi,
                    radius,
                    count,
                    t.seed,
                    steps,
                    mats[mi],
                    density,
                    g.thickness,
                )
                .map_err(|e| bad("granular.discs", e));
            }
            let rows = lattice_packing(lat, lo, hi, radius, t.count, gap, jitter, t.seed)
                .map_err(|e| bad("granular.discs", e))?;
            if kind == Generator::Random && t.method == Packing::Deposit {
                return deposit(sc, rows, lo, hi, steps);
            }
            Ok(rows)
        }
    }
}

/// Gravity deposition: settle a loose packing inside the box under gravity
/// (the scenario's, or −9.81 ŷ if it has none). Returns the settled
/// positions (velocities are dropped).
fn deposit(
    sc: &Scenario,
    rows: Vec<DiscRow>,
    lo: Vec2,
    hi: Vec2,
    steps: usize,
) -> Result<Vec<DiscRow>, Invalid> {
    let g = spec(sc)?;
    let mi = material_index(sc, &g.material, "granular.material")?;
    let (mats, _) = laws(sc, &DampingSpec::None);
    let grav = Vec2::from(sc.simulation.gravity);
    let grav = if grav.norm2() > 0.0 {
        grav
    } else {
        Vec2::new(0.0, -9.81)
    };
    let m = &sc.material[mi as usize];
    settle_in_box(
        &rows,
        lo,
        hi,
        mats[mi as usize],
        m.density,
        g.thickness,
        grav,
        steps,
    )
    .map_err(|e| bad("granular.discs", e))
}

/// Build the assembly described by the scenario. `dt` is the scenario's,
/// or [`DT_SAFETY`] × the critical step.
pub fn granular(sc: &Scenario) -> Result<Granular, Invalid> {
    let g = spec(sc)?;
    let rows = disc_rows(sc)?;
    let default_mat = material_index(sc, &g.material, "granular.material")?;
    let (mats, body) = laws(sc, &g.damping);
    let mut p = Particles::default();
    let v0 = g.velocity.map(Vec2::from).unwrap_or(Vec2::ZERO);
    for (k, r) in rows.iter().enumerate() {
        let mi = match &r.material {
            Some(name) => material_index(sc, name, "granular.discs")
                .map_err(|e| bad("granular.discs", format!("disc {}: {}", k + 1, e.message)))?,
            None => default_mat,
        };
        let m = &sc.material[mi as usize];
        if m.density.is_nan() || m.density <= 0.0 {
            return Err(bad(
                "granular.discs",
                format!("disc {}: material `{}` needs a density > 0", k + 1, m.name),
            ));
        }
        p.push(r.pos, r.r, m.density, g.thickness, mi);
        p.vel[k] = v0;
    }
    let walls = super::granular::walls(sc, &p.pos)?;
    let mut gr = Granular::new(p, mats, walls, 1.0);
    gr.damping = body;
    gr.gravity = Vec2::from(sc.simulation.gravity);
    gr.thickness = g.thickness;
    gr.dt = sc.simulation.dt.unwrap_or(DT_SAFETY * gr.critical_dt());
    if !gr.dt.is_finite() || gr.dt <= 0.0 {
        return Err(bad(
            "simulation.dt",
            "cannot choose a time step: give simulation.dt (no contact stiffness to derive it from)",
        ));
    }
    super::granular::check_wall_speeds(sc, &gr)?;
    if let Some(s) = g.skin {
        gr.set_skin(s);
    }
    Ok(gr)
}

/// Number of steps: `simulation.steps`, or `end_time / dt` rounded.
pub fn steps(sc: &Scenario, dt: f64) -> usize {
    match (sc.simulation.steps, sc.simulation.end_time) {
        (Some(n), _) => n,
        (None, Some(t)) => (t / dt).round() as usize,
        (None, None) => 0,
    }
}

/// Number of steps: `simulation.steps`, or the fewest steps that reach
/// `end_time` (`⌈end_time / dt⌉`, with a relative tolerance of 1e-9 so
/// that `0.3 / 0.1` is 3 steps, not 4).
fn steps_of(sc: &Scenario, dt: f64) -> usize {
    match (sc.simulation.steps, sc.simulation.end_time) {
        (Some(n), _) => n,
        (None, Some(t)) => (t / dt * (1.0 - 1e-9)).ceil() as usize,
        (None, None) => 0,
    }
}

/// The continuum bodies of a continuum-only scenario, started for a
/// dynamic analysis at `dt` (after their initial static state, if any).
fn bodies(sc: &Scenario, dt: Option<f64>) -> Result<Vec<Body>, Invalid> {
    let g = sc.simulation.gravity;
    sc.body
        .iter()
        .enumerate()
        .map(|(i, spec)| {
            let at = format!("body.{i}");
            let p = spec.params();
            let mut b = match spec.method {
                Method::Efg => Body::Efg(Box::new(EfgBody::new(&p, g).map_err(|e| bad(&at, e))?)),
                Method::FemQ4 => Body::Fem(Box::new(FemBody::new(&p, g).map_err(|e| bad(&at, e))?)),
            };
            if let Some(dt) = dt {
                if spec.initial.is_some() {
                    b.solve_static()
                        .map_err(|e| bad(&format!("{at}.initial"), e))?;
                }
                b.start_dynamic(dt).map_err(|e| bad(&at, e))?;
            }
            Ok(b)
        })
        .collect()
}

/// The coupled model: discs, walls and bodies (EFG or FE) with each
/// body's Newmark matrix factored for `dt × substeps`.
fn coupled(sc: &Scenario) -> Result<CoupledModel, Invalid> {
    let granular = granular(sc)?;
    let substeps = sc.simulation.substeps.max(1);
    let body_dt = granular.dt * substeps as f64;
    let mode = match sc.simulation.contact_solve {
        ContactSolve::Boundary => ComplianceMode::Boundary,
        ContactSolve::Direct => ComplianceMode::Direct,
    };
    let mut bodies: Vec<Box<dyn Continuum>> = Vec::new();
    let mut mats = Vec::new();
    for (i, spec) in sc.body.iter().enumerate() {
        let at = format!("body.{i}");
        let (g, edges, refine) = (
            sc.simulation.gravity,
            &spec.contact_edges,
            spec.contact_refine,
        );
        let p = spec.params();
        bodies.push(match spec.method {
            Method::Efg => {
                let mut body = EfgBody::new(&p, g).map_err(|e| bad(&at, e))?;
                body.start_dynamic(body_dt).map_err(|e| bad(&at, e))?;
                let mut c = EfgContinuum::new(body, edges, refine)
                    .map_err(|e| bad(&format!("{at}.contact_edges"), e))?;
                c.mode = mode;
                Box::new(c)
            }
            Method::FemQ4 => {
                let mut body = FemBody::new(&p, g).map_err(|e| bad(&at, e))?;
                body.start_dynamic(body_dt).map_err(|e| bad(&at, e))?;
                let mut c = FemContinuum::new(body, edges, refine)
                    .map_err(|e| bad(&format!("{at}.contact_edges"), e))?;
                c.mode = mode;
                Box::new(c)
            }
        });
        mats.push(match &spec.contact_material {
            Some(m) => Some(material_index(sc, m, &format!("{at}.contact_material"))?),
            None => None,
        });
    }
    let mut m = CoupledModel::new(granular, bodies, &mats, substeps);
    m.staggered |= sc.simulation.coupling == CouplingScheme::Staggered;
    m.geometric_stiffness = sc.simulation.geometric_stiffness;
    Ok(m)
}

/// Build the model (see [`Scenario::build`]); problems carry field paths.
pub fn model(sc: &Scenario) -> Result<Model, Invalid> {
    let dynamic = sc.simulation.analysis == Analysis::Dynamic;
    let model = match super::kind(sc) {
        super::Kind::Continuum => {
            let dt = if dynamic {
                Some(sc.simulation.dt.ok_or_else(|| {
                    bad("simulation.dt", "a dynamic analysis needs `simulation.dt`")
                })?)
            } else {
                None
            };
            let steps = dt.map_or(0, |dt| steps_of(sc, dt));
            Model {
                system: System::Continuum {
                    bodies: bodies(sc, dt)?,
                    dynamic,
                },
                dt: dt.unwrap_or(0.0),
                steps,
                step: 0,
            }
        }
        super::Kind::Granular => {
            let g = granular(sc)?;
            Model {
                dt: g.dt,
                steps: steps_of(sc, g.dt),
                system: System::Granular(Box::new(g)),
                step: 0,
            }
        }
        super::Kind::Coupled => {
            let m = coupled(sc)?;
            Model {
                dt: m.granular.dt,
                steps: steps_of(sc, m.granular.dt),
                system: System::Coupled(Box::new(m)),
                step: 0,
            }
        }
    };
    if let Some(g) = model.granular() {
        start_state(sc, g)?;
    }
    probes(sc, &model)?;
    Ok(model)
}

/// Overlap accepted at the start, relative to the smaller radius.
pub const START_OVERLAP_TOL: f64 = 1e-3;

/// Impossible start states: discs overlapping each other, a wall or a body
/// (reference configuration) by more than [`START_OVERLAP_TOL`] of the
/// smaller radius (unless `allow_overlap` or a packing efgdem settled), and
/// a time step above the DEM critical step.
fn start_state(sc: &Scenario, g: &Granular) -> Result<(), Invalid> {
    let crit = g.critical_dt();
    if g.dt > crit {
        return Err(bad(
            "simulation.dt",
            format!(
                "dt = {:e} is {:.2} × the DEM critical step 2√(m_min/k_max) = {crit:e}: the central difference is unstable; use at most {:e} ({DT_WARN} × critical)",
                g.dt,
                g.dt / crit,
                DT_WARN * crit
            ),
        ));
    }
    let spec = spec(sc)?;
    let settled = matches!(&spec.discs, DiscsSpec::Table(t)
        if t.generate.is_some() && matches!(t.method, Packing::Deposit | Packing::Grow));
    if spec.allow_overlap || settled {
        return Ok(());
    }
    let p = &g.particles;
    let tol = START_OVERLAP_TOL;
    let list = |v: &[(usize, f64)]| {
        let mut s: Vec<String> = v
            .iter()
            .take(5)
            .map(|(id, d)| format!("disc {} (overlap {d:.3e})", id + 1))
            .collect();
        if v.len() > 5 {
            s.push(format!("and {} more", v.len() - 5));
        }
        s.join(", ")
    };
    let hint =
        "move them apart, or set `allow_overlap = true` in [granular] for a pre-stressed packing";
    let pairs = overlapping_pairs(&p.pos, &p.radius, tol);
    if !pairs.is_empty() {
        let shown: Vec<String> = pairs
            .iter()
            .take(5)
            .map(|&(a, b, d)| {
                format!(
                    "discs {} and {} (overlap {d:.3e})",
                    p.id[a] + 1,
                    p.id[b] + 1
                )
            })
            .collect();
        return Err(bad(
            "granular.discs",
            format!(
                "{} pair(s) of discs overlap at the start by more than {tol} of the smaller radius: {}{}; {hint}",
                pairs.len(),
                shown.join(", "),
                if pairs.len() > 5 { ", …" } else { "" }
            ),
        ));
    }
    // discs whose overlap `overlap(centre, r)` with one wall or body is
    // above the tolerance: (disc id, overlap)
    let hits = |overlap: &dyn Fn(Vec2, f64) -> f64| -> Vec<(usize, f64)> {
        (0..p.len())
            .filter_map(|k| {
                let d = overlap(p.pos[k], p.radius[k]);
                (d > tol * p.radius[k]).then_some((p.id[k] as usize, d))
            })
            .collect()
    };
    let refuse = |path: String, what: String, hits: Vec<(usize, f64)>| {
        let message = format!(
            "{} disc(s) {what} at the start: {}; {hint}",
            hits.len(),
            list(&hits)
        );
        Err(bad(&path, message))
    };
    for (wi, w) in g.walls.iter().enumerate() {
        let found = hits(&|x, r| r - (w.closest(x) - x).norm());
        if !found.is_empty() {
            return refuse(
                format!("wall.{wi}"),
                format!("cross wall `{}`", w.name),
                found,
            );
        }
    }
    for (bi, b) in sc.body.iter().enumerate() {
        let lo = Vec2::from(b.rectangle.origin);
        let hi = lo + Vec2::from(b.rectangle.size);
        let found = hits(&|x, r| {
            let c = Vec2::new(x.x.clamp(lo.x, hi.x), x.y.clamp(lo.y, hi.y));
            if c == x {
                // centre inside: overlap = r + distance to the nearest edge
                r + (x.x - lo.x).min(hi.x - x.x).min(x.y - lo.y).min(hi.y - x.y)
            } else {
                r - (c - x).norm()
            }
        });
        if !found.is_empty() {
            return refuse(
                format!("body.{bi}"),
                format!("overlap body `{}`", b.name),
                found,
            );
        }
    }
    Ok(())
}

/// Bind every `[[probe]]` to its target in `model`, in scenario order.
pub fn probes(sc: &Scenario, model: &Model) -> Result<Vec<(String, Probe)>, Invalid> {
    let mut out: Vec<(String, Probe)> = sc
        .probe
        .iter()
        .enumerate()
        .map(|(k, pr)| {
            let at = |f: &str| format!("probe.{k}.{f}");
            let q = pr.quantity.clone();
            let body_index = || match &pr.body {
                Some(n) => (0..model.n_bodies())
                    .find(|&i| body_name(model, i) == n)
                    .ok_or_else(|| bad(&at("body"), format!("no body named `{n}`"))),
                None => Ok(0),
            };
            let bind = |body: usize, p: [f64; 2]| {
                model
                    .body(body)
                    .bind(Vec2::from(p))
                    .map_err(|e| bad(&at("point"), e))
            };
            let probe = match &model.system {
                System::Continuum { .. } => {
                    let body = body_index()?;
                    match pr.point {
                        Some(p) if !BODY_QUANTITIES.contains(&q.as_str()) => Probe::BodyPoint {
                            body,
                            at: bind(body, p)?,
                            field: q,
                        },
                        _ => Probe::BodyEnergy { body, quantity: q },
                    }
                }
                System::Granular(g) => granular_probe(g, pr, k, false)?,
                System::Coupled(m) => {
                    if is_body_probe(pr, false) {
                        let body = body_index()?;
                        if CONTACT_FORCE_QUANTITIES.contains(&q.as_str()) {
                            Probe::BodyForce {
                                body,
                                y: q == "contact_fy",
                            }
                        } else if !POINT_QUANTITIES.contains(&q.as_str()) {
                            return Err(bad(
                                &at("quantity"),
                                format!(
                                    "`{q}` is not recorded in coupled runs; body probes take a `point` and one of {}",
                                    POINT_QUANTITIES.join(", ")
                                ),
                            ));
                        } else {
                            let p = pr.point.ok_or_else(|| {
                                bad(
                                    &at("quantity"),
                                    "body-wide quantities are not recorded in coupled runs; use the energy columns",
                                )
                            })?;
                            Probe::BodyPoint {
                                body,
                                at: bind(body, p)?,
                                field: q,
                            }
                        }
                    } else {
                        granular_probe(&m.granular, pr, k, true)?
                    }
                }
            };
            Ok((pr.name.clone(), probe))
        })
        .collect::<Result<_, _>>()?;
    // then the `[[measure]]` columns
    out.extend(super::measure::probes(sc, model)?);
    Ok(out)
}

fn body_name(model: &Model, i: usize) -> &str {
    match &model.system {
        System::Continuum { bodies, .. } => bodies[i].name(),
        System::Coupled(m) => m.bodies[i].name(),
        System::Granular(_) => "",
    }
}

/// A probe of the granular assembly (`coupled`: disc displacements `ux`,
/// `uy` are known too).
fn granular_probe(
    g: &Granular,
    pr: &super::Probe,
    k: usize,
    coupled: bool,
) -> Result<Probe, Invalid> {
    let n = g.particles.len();
    let disc = |d: usize, field: &str| {
        (d >= 1 && d <= n).then(|| d - 1).ok_or_else(|| {
            bad(
                &format!("probe.{k}.{field}"),
                format!("disc {d} does not exist (the assembly has {n} discs, numbered from 1)"),
            )
        })
    };
    let q = pr.quantity.as_str();
    let has = |list: &[&str]| list.contains(&q);
    Ok(
        if let Some(&[a, b]) = pr.contact.as_ref().filter(|_| has(CONTACT_QUANTITIES)) {
            Probe::Contact {
                a: disc(a, "contact")?,
                b: disc(b, "contact")?,
                total: q == "normal_total",
            }
        } else if has(WALL_QUANTITIES) {
            let name = pr.wall.as_deref().unwrap_or("");
            let wall = g.walls.iter().position(|w| w.name == name).ok_or_else(|| {
                bad(
                    &format!("probe.{k}.wall"),
                    format!("no wall named `{name}`"),
                )
            })?;
            Probe::Wall {
                wall,
                quantity: q.to_string(),
            }
        } else if has(GLOBAL_QUANTITIES) {
            Probe::Global {
                quantity: q.to_string(),
            }
        } else if has(DISC_QUANTITIES) || (coupled && (q == "ux" || q == "uy")) {
            let id = disc(pr.disc.unwrap_or(0), "disc")?;
            Probe::Disc {
                id,
                quantity: q.to_string(),
                x0: g.particles.pos[g.slot(id)],
            }
        } else {
            return Err(bad(
                &format!("probe.{k}.quantity"),
                format!("`{q}` is not known to a granular run"),
            ));
        },
    )
}
