//! Build the model a scenario describes, in one pass after validation:
//! discs (inline, CSV, generated), materials with the named damping, walls
//! with their motion, bodies (EFG or FE), the coupled model, and the
//! probes bound to their targets. Every problem found here is an
//! [`Invalid`] with the path of the field it comes from, so that the
//! scenario reports it as `file:line: field: message`.

use super::body::{
    BODY_QUANTITIES, CONTACT_FORCE_QUANTITIES, CRACK_QUANTITIES, DRIVE_QUANTITIES, Method,
    POINT_QUANTITIES, is_body_probe,
};
use super::generate::discs_from_csv;
use super::granular::{
    CONTACT_QUANTITIES, DISC_QUANTITIES, DampingSpec, DiscsSpec, DiscsTable, GLOBAL_QUANTITIES,
    Generator, GranularSpec, Packing, SlipNormalSpec, WALL_QUANTITIES, slip_normal,
};
use super::{Analysis, ContactSolve, CouplingScheme, Invalid, Scenario, Substeps};
use crate::continuum::ComplianceMode;
use crate::continuum::Continuum;
use crate::coupling::CoupledModel;
use crate::coupling::scheme::{self, Scheme};
use crate::decomp::{Comm, Cut};
use crate::dem::clumps::{Clumps, NO_CLUMP};
use crate::dem::contact::{ContactLaw, SlipNormal};
use crate::dem::packing::{
    DiscRow, Lattice, grow_in_box, lattice_capacity, lattice_packing, overlapping_pairs,
};
use crate::dem::particles::Particles;
use crate::dem::walls::Wall;
use crate::dem::{BodyDamping, DT_WARN, Granular};
use crate::efg::EfgBody;
use crate::efg::boundary::EfgContinuum;
use crate::fem::{FemBody, FemContinuum};
use crate::geom::Vec2;
use crate::model::body::Body;
use crate::model::{Model, Probe, System};

pub use crate::dem::DT_SAFETY;

pub(super) fn bad(path: &str, message: impl std::fmt::Display) -> Invalid {
    Invalid {
        path: path.to_string(),
        message: message.to_string(),
    }
}

pub(super) fn spec(sc: &Scenario) -> Result<&GranularSpec, Invalid> {
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

/// The contact law a packing's preparation uses (of its `settle_material`,
/// or of the discs' material; without dashpots) and the discs' density.
pub(super) fn settle_law(sc: &Scenario, t: &DiscsTable) -> Result<(ContactLaw, f64), Invalid> {
    let g = spec(sc)?;
    let mi = material_index(sc, &g.material, "granular.material")? as usize;
    let settle = match &t.settle_material {
        Some(m) => material_index(sc, m, "granular.discs.settle_material")? as usize,
        None => mi,
    };
    let (mats, _) = laws(sc, &DampingSpec::None);
    Ok((mats[settle], sc.material[mi].density))
}

pub(super) fn material_index(sc: &Scenario, name: &str, path: &str) -> Result<u16, Invalid> {
    sc.material
        .iter()
        .position(|m| m.name == name)
        .map(|i| i as u16)
        .ok_or_else(|| bad(path, format!("no [[material]] named `{name}`")))
}

/// What [`model_with`] builds the model for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BuildFor<'a> {
    /// A run: the gravity deposit or radius growth of a generated packing
    /// (`method = "deposit"` or `"grow"`) is stepped, or read from its
    /// cache ([`super::prepare::prepare`]).
    Run,
    /// A run whose packing has been prepared: these discs (from
    /// [`super::prepare::prepare`]).
    Prepared(&'a [DiscRow]),
    /// `check`: no time stepping — the discs stay where the generator put
    /// them (a deposit's loose packing; a growth's random centres with the
    /// final radii) — and a static analysis factors and solves its bodies
    /// once, so that a stiffness matrix that cannot be factored is reported
    /// with the body's line.
    Check,
}

/// The preparation of a generated packing that a run starts with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Preparation {
    /// [`Packing::Deposit`] or [`Packing::Grow`].
    pub method: Packing,
    /// Its DEM steps (`settle_steps`).
    pub steps: usize,
    /// Its discs (`count`), when given.
    pub count: Option<usize>,
}

/// Default `settle_steps` of a deposit or a growth.
pub const SETTLE_STEPS: usize = 20_000;

/// The deposit or growth the scenario's discs need before the run, if any.
pub fn preparation(sc: &Scenario) -> Option<Preparation> {
    match &sc.granular.as_ref()?.discs {
        DiscsSpec::Table(t)
            if t.generate == Some(Generator::Random)
                && matches!(t.method, Packing::Deposit | Packing::Grow) =>
        {
            Some(Preparation {
                method: t.method,
                steps: t.settle_steps.unwrap_or(SETTLE_STEPS),
                count: t.count,
            })
        }
        _ => None,
    }
}

impl Preparation {
    /// `a gravity deposit` or `a radius growth`.
    pub fn what(&self) -> &'static str {
        match self.method {
            Packing::Grow => "a radius growth",
            _ => "a gravity deposit",
        }
    }
}

impl std::fmt::Display for Preparation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} DEM steps will be run at the start of `run` (not by `check`)",
            self.what(),
            self.steps
        )
    }
}

/// The discs the scenario describes (generating, preparing or reading
/// them), before any is removed for a body.
pub(super) fn disc_rows(sc: &Scenario, purpose: BuildFor) -> Result<Vec<DiscRow>, Invalid> {
    let g = spec(sc)?;
    let t = match &g.discs {
        DiscsSpec::Inline(rows) => {
            return Ok(rows
                .iter()
                .map(|r| DiscRow {
                    pos: Vec2::new(r[0], r[1]),
                    r: r[2],
                    material: None,
                })
                .collect());
        }
        DiscsSpec::Table(t) => t,
    };
    if let Some(csv) = &t.csv {
        let path = sc.resolve(csv);
        let text = super::read_text(&path, super::MAX_CSV_BYTES).map_err(|e| {
            bad(
                "granular.discs.csv",
                format!("cannot read discs file {}: {e}", path.display()),
            )
        })?;
        return discs_from_csv(&text)
            .map_err(|e| bad("granular.discs.csv", format!("{}: {e}", path.display())));
    }
    let prepared = preparation(sc).is_some();
    match purpose {
        BuildFor::Prepared(rows) if prepared => Ok(rows.to_vec()),
        BuildFor::Run if prepared => match super::prepare::prepare(sc, &mut |_| true) {
            Ok(bed) => Ok(bed.map(|b| b.rows).unwrap_or_default()),
            Err(super::prepare::PrepareError::Invalid(e)) => Err(e),
            Err(super::prepare::PrepareError::Stopped { step, .. }) => Err(bad(
                "granular.discs",
                format!("the preparation stopped after {step} steps"),
            )),
        },
        _ => {
            let rows = loose_rows(sc, t)?;
            if prepared {
                // `check`: the bodies in the region the preparation will fill
                super::fill::check_bodies(sc, &rows)?;
            }
            Ok(rows)
        }
    }
}

/// The discs of a generated packing as the generator places them, before
/// any preparation: on their lattice (`loose`, and a deposit's start), or
/// a growth's random centres with the final radii.
pub(super) fn loose_rows(sc: &Scenario, t: &DiscsTable) -> Result<Vec<DiscRow>, Invalid> {
    let l = lattice_of(t)?;
    if t.generate == Some(Generator::Random) && t.method == Packing::Grow {
        let count = t
            .count
            .ok_or_else(|| bad("granular.discs", "`method = \"grow\"` needs `count`"))?;
        // no step: the centres and final radii (the law is not used)
        let (law, density) = settle_law(sc, t)?;
        let thickness = spec(sc)?.thickness;
        return grow_in_box(
            l.lo,
            l.hi,
            l.radius,
            count,
            t.seed,
            0,
            law,
            density,
            thickness,
            &mut |_| true,
        )
        .map_err(|e| bad("granular.discs", e));
    }
    let (lat, gap, jitter) = (l.lattice, l.gap, l.jitter);
    lattice_packing(lat, l.lo, l.hi, l.radius, t.count, gap, jitter, t.seed)
        .map_err(|e| bad("granular.discs", e))
}

/// Where a generator places its discs: lattice, box, radii, and the gap
/// and jitter of its sites.
pub(super) struct LatticeArgs {
    pub(super) lattice: Lattice,
    pub(super) lo: Vec2,
    pub(super) hi: Vec2,
    pub(super) radius: (f64, f64),
    pub(super) gap: f64,
    pub(super) jitter: f64,
}

/// The lattice of the generated packing `t`.
pub(super) fn lattice_of(t: &DiscsTable) -> Result<LatticeArgs, Invalid> {
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
    let (lattice, gap, jitter) = match kind {
        Generator::Square => (Lattice::Square, 0.0, t.jitter.unwrap_or(0.0)),
        Generator::Hex => (Lattice::Hex, 0.0, t.jitter.unwrap_or(0.0)),
        Generator::Random => (Lattice::Hex, 0.1, t.jitter.unwrap_or(1.0)),
    };
    Ok(LatticeArgs {
        lattice,
        lo: Vec2::from(a),
        hi: Vec2::from(b),
        radius,
        gap,
        jitter,
    })
}

/// The discs of `rows` inside `[granular] keep` (all without it), in
/// their order; an error if none is.
fn kept(sc: &Scenario, rows: Vec<DiscRow>) -> Result<Vec<DiscRow>, Invalid> {
    let Some(k) = spec(sc)?.keep else {
        return Ok(rows);
    };
    let n = rows.len();
    let rows: Vec<DiscRow> = rows.into_iter().filter(|d| k.holds(d.pos, d.r)).collect();
    if rows.is_empty() && n > 0 {
        return Err(bad(
            "granular.keep",
            format!("none of the {n} discs lies inside the circle"),
        ));
    }
    Ok(rows)
}

/// The disc–body contact laws of the scenario's bodies: a body's
/// `contact_material`, or else each disc material's own law (as for walls).
pub fn body_laws(sc: &Scenario, mats: &[ContactLaw]) -> Vec<ContactLaw> {
    let named = |b: &super::body::BodySpec| {
        let m = b.contact_material.as_ref()?;
        sc.material.iter().position(|x| &x.name == m)
    };
    let mut out = Vec::new();
    for b in &sc.body {
        match named(b) {
            Some(i) => out.push(mats[i]),
            None => out.extend_from_slice(mats),
        }
    }
    out
}

/// Build the assembly described by the scenario. `dt` is the scenario's,
/// or [`DT_SAFETY`] × the critical step.
pub fn granular(sc: &Scenario) -> Result<Granular, Invalid> {
    granular_with(sc, BuildFor::Run)
}

/// The assembly for `purpose` ([`BuildFor`]).
fn granular_with(sc: &Scenario, purpose: BuildFor) -> Result<Granular, Invalid> {
    let g = spec(sc)?;
    let (rows, groups) = assembly_rows(sc, purpose)?;
    let default_mat = material_index(sc, &g.material, "granular.material")?;
    let v0 = g.velocity.map(Vec2::from).unwrap_or(Vec2::ZERO);
    let mut p = Particles::default();
    reserve(&mut p, rows.len())?;
    for (k, r) in rows.iter().enumerate() {
        let (mi, ..) = disc_of(sc, k, r, default_mat)?;
        p.push(
            r.pos,
            r.r,
            sc.material[mi as usize].density,
            g.thickness,
            mi,
        );
        p.vel[k] = v0;
    }
    drop(rows);
    let mut clumps = Clumps::default();
    for (i, m) in groups.iter().enumerate() {
        // before the assembly is made: its start positions are the clumps'
        clumps.add(&mut p, m).map_err(|e| {
            let at = match sc.clumps.as_ref().is_some_and(|c| c.template.is_some()) {
                true => "clumps.template".to_string(),
                false => format!("clumps.members.{i}"),
            };
            bad(&at, e)
        })?;
    }
    let sum = p.pos.iter().fold(Vec2::ZERO, |s, &x| s + x);
    let walls = super::granular::walls(sc, super::granular::centroid(sum, p.len()))?;
    let mut gr = assembly(sc, p, walls)?;
    gr.clumps = clumps;
    gr.dt = time_step(sc, &gr)?;
    super::granular::check_wall_speeds(sc, &gr)?;
    if let Some(s) = g.skin {
        gr.set_skin(s);
    }
    Ok(gr)
}

/// The assembly of the discs `p` with the scenario's `walls`, contact
/// laws, damping, gravity, thickness and bond law (no time step yet).
pub(super) fn assembly(sc: &Scenario, p: Particles, walls: Vec<Wall>) -> Result<Granular, Invalid> {
    let g = spec(sc)?;
    let (mats, body) = laws(sc, &g.damping);
    let mut gr = Granular::new(p, mats, walls, 1.0);
    gr.damping = body;
    gr.gravity = Vec2::from(sc.simulation.gravity);
    gr.thickness = g.thickness;
    if let Some(b) = &sc.bonds {
        let (law, rule) = super::bonds::law_and_rule(sc, b);
        gr.bonds.law = law;
        gr.bonds.rule = Some(rule);
    }
    Ok(gr)
}

/// The time step of the assembly whose discs are those of `g` (or those
/// that decide its critical step): the scenario's, or [`DT_SAFETY`] × the
/// critical step; an error if it is not finite and positive.
pub(super) fn time_step(sc: &Scenario, g: &Granular) -> Result<f64, Invalid> {
    let dt = match sc.simulation.dt {
        Some(dt) => dt,
        None => DT_SAFETY * g.critical_step(&body_laws(sc, &g.materials)).dt,
    };
    if !dt.is_finite() || dt <= 0.0 {
        return Err(bad(
            "simulation.dt",
            "cannot choose a time step: give simulation.dt (no contact stiffness to derive it from)",
        ));
    }
    Ok(dt)
}

/// The discs of the assembly as rows (those inside `[granular] keep`,
/// without those a body removes) and its clumps' members.
#[allow(clippy::type_complexity)]
fn assembly_rows(
    sc: &Scenario,
    purpose: BuildFor,
) -> Result<(Vec<DiscRow>, Vec<Vec<usize>>), Invalid> {
    let mut rows = kept(sc, disc_rows(sc, purpose)?)?;
    // `check` does not prepare a packing: its discs are not where the
    // bodies will find them
    let unprepared = purpose == BuildFor::Check && preparation(sc).is_some();
    let gone: std::collections::HashSet<usize> = overlapped(sc, &rows)
        .into_iter()
        .flat_map(|(_, r)| r)
        .collect();
    let removed = !gone.is_empty() && !unprepared;
    if removed {
        rows = (rows.into_iter().enumerate())
            .filter_map(|(k, r)| (!gone.contains(&k)).then_some(r))
            .collect();
    }
    super::clumps::clump_rows(sc, rows, removed)
}

/// `p` with room for `n` discs, or the error that they do not fit.
pub(super) fn reserve(p: &mut Particles, n: usize) -> Result<(), Invalid> {
    p.try_reserve(n).map_err(|e| {
        bad(
            "granular.discs",
            format!(
                "cannot allocate the arrays of {n} discs ({e}): more than this process may use"
            ),
        )
    })
}

/// The material of disc `k` (row `r`; its own or the section's
/// `default_mat`) and its mass and moment of inertia, which must be finite
/// and positive.
pub(super) fn disc_of(
    sc: &Scenario,
    k: usize,
    r: &DiscRow,
    default_mat: u16,
) -> Result<(u16, f64, f64), Invalid> {
    let g = spec(sc)?;
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
    let (mass, inertia) = Particles::mass_of(r.r, m.density, g.thickness);
    if mass.is_finite() && mass > 0.0 && inertia.is_finite() && inertia > 0.0 {
        return Ok((mi, mass, inertia));
    }
    // blame the factor farthest from 1 (in orders of magnitude)
    let disc = match &g.discs {
        DiscsSpec::Inline(_) => format!("granular.discs.{k}"),
        DiscsSpec::Table(_) => "granular.discs".to_string(),
    };
    let density = format!("material.{mi}.density");
    let suspects = [
        (m.density.ln().abs(), density.as_str()),
        ((r.r * r.r).ln().abs(), disc.as_str()),
        (g.thickness.ln().abs(), "granular.thickness"),
    ];
    let (_, at) = suspects.iter().fold(
        (f64::NEG_INFINITY, "granular.thickness"),
        |best, &(v, f)| {
            if v > best.0 { (v, f) } else { best }
        },
    );
    Err(bad(
        at,
        format!(
            "disc {}: its mass ρπr²t = {mass:e} and moment of inertia m r²/2 = {inertia:e} must be finite and > 0 (ρ = {:e}, r = {:e}, t = {:e})",
            k + 1,
            m.density,
            r.r,
            g.thickness
        ),
    ))
}

/// The search grid's skin of discs of largest radius `max_r` when the
/// scenario gives none ([`Granular::new`]'s).
pub(super) fn default_skin(max_r: f64) -> f64 {
    0.1 * max_r.max(f64::MIN_POSITIVE)
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
/// dynamic analysis at `dt` (after their initial static state, if any);
/// for a static analysis with `trial`, solved once (the solution is not
/// kept by the caller: `check` only wants to know that K̄ factors).
fn bodies(sc: &Scenario, dt: Option<f64>, trial: bool) -> Result<Vec<Body>, Invalid> {
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
            } else if trial {
                b.solve_static().map_err(|e| bad(&at, e))?;
            }
            Ok(b)
        })
        .collect()
}

/// The coupled model: discs, walls and bodies (EFG or FE), the coupled
/// scheme and its substeps chosen ([`scheme::choose`]), each body's
/// Newmark matrix factored for `dt × substeps`.
fn coupled(sc: &Scenario, purpose: BuildFor) -> Result<CoupledModel, Invalid> {
    // the scheme is chosen with the discs as generated (the preparation
    // moves them, it does not change their masses or radii): a scenario
    // `run` would refuse is refused before any preparation, as `check` does
    let granular = granular_with(sc, BuildFor::Check)?;
    let substeps = sc.simulation.substeps.fixed().unwrap_or(1).max(1);
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
            &spec.contact_sides(),
            spec.contact_refine,
        );
        let p = spec.params();
        bodies.push(match spec.method {
            Method::Efg => {
                let mut body = EfgBody::new(&p, g).map_err(|e| bad(&at, e))?;
                if spec.initial.is_some() {
                    body.solve_static()
                        .map_err(|e| bad(&format!("{at}.initial"), e))?;
                }
                body.start_dynamic(body_dt).map_err(|e| bad(&at, e))?;
                let named =
                    (!spec.default_contact_edges()).then_some(spec.contact_edges.as_slice());
                let mut c = EfgContinuum::named(body, named, edges, refine)
                    .map_err(|e| bad(&format!("{at}.contact_edges"), e))?;
                c.mode = mode;
                Box::new(c)
            }
            Method::FemQ4 => {
                let mut body = FemBody::new(&p, g).map_err(|e| bad(&at, e))?;
                if spec.initial.is_some() {
                    body.solve_static()
                        .map_err(|e| bad(&format!("{at}.initial"), e))?;
                }
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
    m.geometric_stiffness = sc.simulation.geometric_stiffness;
    m.set_contact_iterations(sc.simulation.contact_iterations);
    let request = scheme::Request {
        scheme: match sc.simulation.coupling {
            // a drive's `until_step` counts body steps: the automatic
            // choice must not sub-cycle it (that would move its phases)
            // a body whose cracks grow is rebuilt between two exact steps
            CouplingScheme::Auto if step_counted_drive(sc) || grows(sc) => Some(Scheme::Exact),
            CouplingScheme::Auto => None,
            CouplingScheme::Exact => Some(Scheme::Exact),
            CouplingScheme::Predicted => Some(Scheme::Predicted),
            CouplingScheme::Compliant => Some(Scheme::Compliant),
            CouplingScheme::Staggered => Some(Scheme::Staggered),
            CouplingScheme::Implicit => Some(match sc.simulation.substeps.fixed() {
                None | Some(1) => Scheme::Exact,
                Some(_) => Scheme::Predicted,
            }),
        },
        substeps: sc.simulation.substeps.fixed(),
    };
    if grows(sc) && request.scheme != Some(Scheme::Exact) {
        return Err(bad(
            "simulation.coupling",
            "crack growth (`[body.fracture]`) in a coupled run takes the exact step: leave `coupling` out or set `coupling = \"exact\"`",
        ));
    }
    let choice = scheme::choose(&mut m, request)
        .map_err(|e| bad("body.0", e))?
        .map_err(|why| {
            let at = match sc.simulation.substeps {
                Substeps::Fixed(_) => "simulation.substeps",
                Substeps::Auto => "simulation.coupling",
            };
            bad(at, why)
        })?;
    scheme::apply(&mut m, &choice).map_err(|e| bad("simulation.coupling", e))?;
    // the discs of the run: prepared (here or by the caller), with those a
    // body placed after the preparation overlaps removed
    if purpose != BuildFor::Check && preparation(sc).is_some() {
        m.granular = granular_with(sc, purpose)?;
    }
    Ok(m)
}

/// Whether a body has a prescribed motion whose phases or end are counted
/// in body steps (`until_step`): a sub-cycled scheme would take them
/// `substeps` times later, so the automatic choice keeps the exact step.
/// Does a body's crack grow (`[body.fracture]`)?
fn grows(sc: &Scenario) -> bool {
    sc.body.iter().any(|b| b.fracture.is_some())
}

fn step_counted_drive(sc: &Scenario) -> bool {
    use crate::continuum::conditions::Prescribed;
    let counted = |p: &Option<Prescribed>| match p {
        Some(Prescribed::Motion(m)) => m.until_step.is_some(),
        Some(Prescribed::Phases(ph)) => ph.phases.iter().any(|q| q.until_step.is_some()),
        _ => false,
    };
    sc.body
        .iter()
        .flat_map(|b| &b.bc)
        .any(|c| counted(&c.ux) || counted(&c.uy))
}

/// Build the model (see [`Scenario::build`]); problems carry field paths.
pub fn model(sc: &Scenario) -> Result<Model, Invalid> {
    model_with(sc, BuildFor::Run)
}

/// [`model`] for a run or for `check` (see [`BuildFor`]).
/// First of all, a run whose estimated memory
/// ([`memory_estimate`]) exceeds the machine's is refused, before anything
/// is allocated.
pub fn model_with(sc: &Scenario, purpose: BuildFor) -> Result<Model, Invalid> {
    check_memory(sc)?;
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
                    bodies: bodies(sc, dt, purpose == BuildFor::Check)?,
                    dynamic,
                },
                dt: dt.unwrap_or(0.0),
                steps,
                step: 0,
            }
        }
        super::Kind::Granular => {
            let g = granular_with(sc, purpose)?;
            Model {
                dt: g.dt,
                steps: steps_of(sc, g.dt),
                system: System::Granular(Box::new(g)),
                step: 0,
            }
        }
        super::Kind::Coupled => {
            let m = coupled(sc, purpose)?;
            Model {
                dt: m.granular.dt,
                steps: steps_of(sc, m.granular.dt),
                system: System::Coupled(Box::new(m)),
                step: 0,
            }
        }
    };
    if let Some((path, message)) = super::body::absurd_motion(sc, model.steps, model.dt) {
        return Err(bad(&path, message));
    }
    if let Some(g) = model.granular() {
        start_state(sc, g, purpose)?;
    }
    probes(sc, &model)?;
    Ok(model)
}

/// A rank's part of a granular scenario's model, with the regions of the
/// ranks of `comm` (collective): the discs the cut keeps for this rank of
/// the whole assembly (their ids those of the whole), with the whole's
/// walls, laws and time step and every check of the start state the whole
/// would pass or fail (`scenario::part`). The whole assembly is never made.
/// `None` for what is not a plain granular scenario (bodies, bonds,
/// clumps).
pub fn part(
    sc: &Scenario,
    purpose: BuildFor,
    comm: &dyn Comm,
) -> Result<Option<(Model, Cut)>, Invalid> {
    if !in_parts(sc) {
        return Ok(None);
    }
    check_memory(sc)?;
    let (g, cut) = super::part::granular(sc, purpose, comm)?;
    Ok(Some((part_model(sc, g)?, cut)))
}

/// Whether `sc` is a plain granular scenario (no bodies, bonds or
/// clumps), whose assembly is built in parts.
pub fn in_parts(sc: &Scenario) -> bool {
    super::kind(sc) == super::Kind::Granular && sc.bonds.is_none() && sc.clumps.is_none()
}

/// The model of a rank's part `g` (or of its assembly without discs),
/// with the checks of the whole's model that need no discs.
pub(super) fn part_model(sc: &Scenario, g: Granular) -> Result<Model, Invalid> {
    let model = Model {
        dt: g.dt,
        steps: steps_of(sc, g.dt),
        system: System::Granular(Box::new(g)),
        step: 0,
    };
    if let Some((path, message)) = super::body::absurd_motion(sc, model.steps, model.dt) {
        return Err(bad(&path, message));
    }
    probes(sc, &model)?;
    Ok(model)
}

/// [`super::part::PartSkeleton`] of `sc`: `None` for what is not a plain
/// granular scenario.
pub fn part_skeleton<'a>(
    sc: &'a Scenario,
    purpose: BuildFor<'a>,
) -> Result<Option<super::part::PartSkeleton<'a>>, Invalid> {
    if !in_parts(sc) {
        return Ok(None);
    }
    check_memory(sc)?;
    super::part::part_skeleton(sc, purpose).map(Some)
}

/// Bytes per disc assumed by [`memory_estimate`]: the disc arrays (≈ 125
/// B), the contact list of a dense packing (≈ 2.5 pairs per disc, ≈ 30 B
/// each), the search grid, and the transient copies of the build (a
/// `summary.json` reports ≈ 160–250 B per disc in the run itself).
pub const DISC_BYTES: f64 = 400.0;

/// The memory a run of a scenario needs, estimated from the scenario
/// alone (nothing is generated or allocated): what `check` prints and what
/// `check` and `run` compare with the machine's memory.
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryEstimate {
    /// Number of discs: inline rows, data lines of the CSV file, `count`,
    /// or as many as the generator's box holds (a float: a huge box holds
    /// more than a `usize` counts).
    pub discs: f64,
    /// Bytes of the discs, `discs ×` [`DISC_BYTES`].
    pub disc_bytes: f64,
    /// Contact pairs beyond [`PAIRS_PER_DISC`] per disc (discs given by
    /// their positions that overlap: a stack pressed into itself).
    pub extra_pairs: f64,
    /// Their bytes, `extra_pairs ×` [`PAIR_BYTES`].
    pub pair_bytes: f64,
    /// Bytes of each body (name, bytes): its sparse operators and their
    /// Cholesky factor, the EFG shape functions at the Gauss points and, in
    /// coupled runs with `contact_solve = "boundary"`, the dense boundary
    /// Green matrix.
    pub bodies: Vec<(String, f64)>,
}

impl MemoryEstimate {
    /// Bytes of the whole run.
    pub fn total(&self) -> f64 {
        self.disc_bytes + self.pair_bytes + self.bodies.iter().map(|b| b.1).sum::<f64>()
    }
}

/// `b` bytes as `12.3 MiB`.
pub fn human_bytes(b: f64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = b;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if v >= 1e4 {
        format!("{b:.1e} B")
    } else if u == 0 {
        format!("{v:.0} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// A count that may be astronomically large: an integer up to 1e15.
fn count_text(n: f64) -> String {
    if n < 1e15 {
        format!("{n:.0}")
    } else {
        format!("{n:.1e}")
    }
}

impl std::fmt::Display for MemoryEstimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "about {}", human_bytes(self.total()))?;
        let mut parts = Vec::new();
        if self.discs > 0.0 {
            parts.push(format!(
                "{} discs × ~{DISC_BYTES} B = {}",
                count_text(self.discs),
                human_bytes(self.disc_bytes)
            ));
        }
        if self.extra_pairs > 0.0 {
            parts.push(format!(
                "{} more contact pairs (overlapping discs) × ~{PAIR_BYTES} B = {}",
                count_text(self.extra_pairs.round()),
                human_bytes(self.pair_bytes)
            ));
        }
        for (name, b) in &self.bodies {
            parts.push(format!("body `{name}` {}", human_bytes(*b)));
        }
        if !parts.is_empty() {
            write!(f, " ({})", parts.join("; "))?;
        }
        Ok(())
    }
}

/// Contact pairs per disc that [`DISC_BYTES`] allows for (a dense
/// packing of discs that do not overlap).
pub const PAIRS_PER_DISC: f64 = 2.5;

/// Bytes per listed contact pair beyond [`PAIRS_PER_DISC`]: the pair
/// with its shear and rolling history, its slot in the neighbour list and
/// the transient copies of a rebuild (measured on overlapping packings).
pub const PAIR_BYTES: f64 = 100.0;

/// Listed contact pairs (gap below the Verlet skin, `skin` or 0.1 × the
/// largest radius) per disc of the discs `rows` (`[x, y, r]`), counted
/// around up to 2 000 of them spread over the list: a packing given by
/// its positions may overlap, with many contacts per disc.
fn pairs_per_disc(rows: &[[f64; 3]], skin: Option<f64>) -> f64 {
    let n = rows.len();
    if n < 2 {
        return 0.0;
    }
    let r_max = rows.iter().map(|r| r[2]).fold(0.0, f64::max);
    let skin = skin.unwrap_or(0.1 * r_max);
    let cell = 2.0 * r_max + skin;
    if !(cell.is_finite() && cell > 0.0) {
        return 0.0;
    }
    let key = |r: &[f64; 3]| ((r[0] / cell).floor() as i64, (r[1] / cell).floor() as i64);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<u32>> =
        std::collections::HashMap::new();
    for (k, r) in rows.iter().enumerate() {
        grid.entry(key(r)).or_default().push(k as u32);
    }
    let samples = n.min(2000);
    let mut found = 0usize;
    for s in 0..samples {
        let i = s * n / samples;
        let a = &rows[i];
        let (cx, cy) = key(a);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for &j in grid
                    .get(&(cx + dx, cy + dy))
                    .map_or(&[][..], |v| v.as_slice())
                {
                    let b = &rows[j as usize];
                    let reach = a[2] + b[2] + skin;
                    if j as usize != i && (a[0] - b[0]).hypot(a[1] - b[1]) < reach {
                        found += 1;
                    }
                }
            }
        }
    }
    0.5 * found as f64 / samples as f64
}

/// Number of discs the scenario describes, without generating them, and
/// the contact pairs per disc of discs given by their positions (inline
/// or in a CSV file; `None` for generated ones, which do not overlap).
fn disc_count(sc: &Scenario) -> (f64, Option<f64>) {
    let Some(g) = &sc.granular else {
        return (0.0, None);
    };
    match &g.discs {
        DiscsSpec::Inline(rows) => (rows.len() as f64, Some(pairs_per_disc(rows, g.skin))),
        DiscsSpec::Table(t) => {
            if let Some(csv) = &t.csv {
                // the build reports a file it cannot read
                let Ok(text) = super::read_text(&sc.resolve(csv), super::MAX_CSV_BYTES) else {
                    return (0.0, None);
                };
                return match super::generate::discs_from_csv(&text) {
                    Ok(d) => {
                        let rows: Vec<[f64; 3]> =
                            d.iter().map(|d| [d.pos.x, d.pos.y, d.r]).collect();
                        (rows.len() as f64, Some(pairs_per_disc(&rows, g.skin)))
                    }
                    Err(_) => (0.0, None),
                };
            }
            if let Some(c) = t.count {
                return (c as f64, None);
            }
            let (Some(kind), Some([a, b]), Some(r)) = (t.generate, t.region, t.radius) else {
                return (0.0, None);
            };
            let (lat, gap) = match kind {
                Generator::Square => (Lattice::Square, 0.0),
                Generator::Hex => (Lattice::Hex, 0.0),
                Generator::Random => (Lattice::Hex, 0.1),
            };
            (
                lattice_capacity(lat, Vec2::from(a), Vec2::from(b), r.range().1, gap),
                None,
            )
        }
    }
}

/// Estimated bytes of one body (see [`MemoryEstimate::bodies`]), from
/// measurements of `efgdem check` on EFG and FE bodies of 5 000 to
/// 40 000 nodes (within ≈ 20 % for `d_max` 1.5–3, `gauss` 2–8).
fn body_bytes(sc: &Scenario, b: &super::body::BodySpec) -> f64 {
    // a polygon body: the grid of its bounding box, and its vertices
    let (grid, vertices) = match (b.domain().ok().flatten(), b.spacing) {
        (Some(d), Some(h)) if h > 0.0 => {
            let (lo, hi) = d.bounds();
            let vertices: usize = d.loops.iter().map(|l| l.len()).sum();
            (
                [(hi.x - lo.x) / h + 1.0, (hi.y - lo.y) / h + 1.0],
                vertices as f64,
            )
        }
        _ => (b.nodes.map(|n| n as f64), 0.0),
    };
    let [nx, ny] = grid;
    let nodes = nx * ny;
    let (mut bytes, band) = match b.method {
        Method::Efg => {
            let d = b.d_max.clamp(1.0, 10.0);
            // node pairs whose supports meet: (4 d − 1)² per node, 2 × 2
            // DOFs each, lower triangle; ≈ 60 B per entry with the factor
            let nnz = nodes * 2.0 * (4.0 * d - 1.0).powi(2);
            let cells = b
                .cells
                .map_or((nx - 1.0) * (ny - 1.0), |c| c[0] as f64 * c[1] as f64);
            let points = cells * (b.gauss as f64).powi(2);
            // shape functions and gradients of (2 d)² nodes per point
            let shapes = points * (2.0 * d).powi(2) * 40.0;
            // per polygon vertex: the Gauss point of its sliver and of its
            // boundary piece, its segment in the R-tree and the
            // visibility lists
            let per_vertex = 2.0 * (2.0 * d).powi(2) * 40.0 + 256.0;
            (60.0 * nnz + shapes + vertices * per_vertex, d.ceil())
        }
        // K, M, the Newmark matrix and the factor: ≈ 3.5 kB per node
        Method::FemQ4 => (3500.0 * nodes, 1.0),
    };
    if sc.granular.is_some() && sc.simulation.contact_solve == ContactSolve::Boundary {
        // the dense boundary Green matrix (8 B per entry + its index of
        // significant entries) over the DOFs of the nodes whose support
        // reaches a contact edge
        let edge_nodes: f64 = b
            .contact_sides()
            .iter()
            .map(|e| match e {
                super::body::Edge::Left | super::body::Edge::Right => ny,
                _ => nx,
            })
            .sum();
        let dofs = 2.0 * band * edge_nodes;
        bytes += 12.0 * dofs * dofs;
    }
    bytes
}

/// The memory a run of `sc` needs (see [`MemoryEstimate`]).
pub fn memory_estimate(sc: &Scenario) -> MemoryEstimate {
    let (discs, pairs) = disc_count(sc);
    let extra_pairs = discs * (pairs.unwrap_or(0.0) - PAIRS_PER_DISC).max(0.0);
    MemoryEstimate {
        discs,
        disc_bytes: discs * DISC_BYTES,
        extra_pairs,
        pair_bytes: extra_pairs * PAIR_BYTES,
        bodies: sc
            .body
            .iter()
            .map(|b| (b.name.clone(), body_bytes(sc, b)))
            .collect(),
    }
}

/// The machine's memory in bytes (`MemTotal` of `/proc/meminfo`); `None`
/// where that is not available (the memory check is then skipped).
pub fn machine_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

/// The memory this process may still use, in bytes, and what bounds it:
/// the machine's (`MemTotal`) or, if lower, the process's address-space
/// limit (`ulimit -v`, `RLIMIT_AS`) less what the process already maps
/// (its code, libraries, thread stacks). `None` where neither is known
/// (the memory check is then skipped).
pub fn memory_limit() -> Option<(f64, String)> {
    let machine = machine_memory().map(|m| (m, format!("machine: {}", human_bytes(m))));
    let process = address_space_limit().map(|(limit, used)| {
        (
            (limit - used).max(0.0),
            format!(
                "process limit (ulimit -v): {} left of {}",
                human_bytes((limit - used).max(0.0)),
                human_bytes(limit)
            ),
        )
    });
    match (machine, process) {
        (Some(m), Some(p)) => Some(if p.0 < m.0 { p } else { m }),
        (m, p) => m.or(p),
    }
}

/// `RLIMIT_AS` (bytes) and the address space already mapped (`VmSize` of
/// `/proc/self/status`, 0 if unknown); `None` without a limit.
#[cfg(unix)]
fn address_space_limit() -> Option<(f64, f64)> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } != 0 || r.rlim_cur == libc::RLIM_INFINITY
    {
        return None;
    }
    let used = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|t| {
            let l = t.lines().find(|l| l.starts_with("VmSize:"))?;
            l.split_whitespace().nth(1)?.parse::<f64>().ok()
        })
        .map_or(0.0, |kib| kib * 1024.0);
    Some((r.rlim_cur as f64, used))
}

#[cfg(not(unix))]
fn address_space_limit() -> Option<(f64, f64)> {
    None
}

/// Refuse a run that would not fit in the memory it may use
/// ([`memory_limit`]: the machine's, or the process's limit), naming the
/// largest consumer: the discs (`granular.discs`, or its `count`) or a
/// body (`body.i.nodes`, `body.i.spacing` or `body.i.holes`).
pub(super) fn check_memory(sc: &Scenario) -> Result<(), Invalid> {
    let Some((limit, what)) = memory_limit() else {
        return Ok(());
    };
    let est = memory_estimate(sc);
    if est.total() <= limit {
        return Ok(());
    }
    let biggest_body = est
        .bodies
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.1.total_cmp(&b.1.1));
    let path = match biggest_body {
        Some((i, (_, b))) if *b > est.disc_bytes + est.pair_bytes => match &sc.body[i] {
            body if body.is_polygon() => format!("body.{i}.spacing"),
            _ => format!("body.{i}.nodes"),
        },
        _ => match &sc.granular.as_ref().map(|g| &g.discs) {
            Some(DiscsSpec::Table(t)) if t.count.is_some() => "granular.discs.count".into(),
            _ => "granular.discs".into(),
        },
    };
    Err(bad(
        &path,
        format!(
            "the run would need {est} of memory, more than it may use ({what}{}); use fewer discs or nodes",
            if what.starts_with("machine") {
                " MemTotal"
            } else {
                ""
            }
        ),
    ))
}

/// Overlap accepted at the start, relative to the smaller radius.
pub const START_OVERLAP_TOL: f64 = 1e-3;

/// Impossible start states: discs overlapping each other, a wall or a body
/// (reference configuration) by more than [`START_OVERLAP_TOL`] of the
/// smaller radius (unless `allow_overlap`; a packing efgdem settled is
/// checked against the bodies only, by `run`, once settled), and a time
/// step above the DEM critical step.
fn start_state(sc: &Scenario, g: &Granular, purpose: BuildFor) -> Result<(), Invalid> {
    start_limits(sc, g)?;
    let Some(settled) = overlap_checks(sc, purpose)? else {
        return Ok(());
    };
    let p = &g.particles;
    let tol = START_OVERLAP_TOL;
    // a packing efgdem settled carries its weight on small overlaps with
    // its neighbours and its box (walls on the box edges); the bodies were
    // not there when it settled
    let pairs = match settled {
        true => Vec::new(),
        false => overlapping_pairs(&p.pos, &p.radius, tol),
    };
    // the discs of a clump overlap by design
    let pairs: Vec<_> = pairs
        .into_iter()
        .filter(|&(a, b, _)| p.clump[a] == NO_CLUMP || p.clump[a] != p.clump[b])
        .map(|(a, b, d)| (p.id[a] as usize, p.id[b] as usize, d))
        .collect();
    if !pairs.is_empty() {
        return Err(pairs_refusal(pairs.len(), &pairs[..pairs.len().min(5)]));
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
    for (wi, w) in g.walls.iter().enumerate().filter(|_| !settled) {
        let found = hits(&|x, r| wall_overlap(w, x, r));
        if !found.is_empty() {
            return Err(wall_refusal(wi, &w.name, found.len(), &found));
        }
    }
    for (bi, b) in sc.body.iter().enumerate() {
        let found = hits(&body_overlap(b));
        if !found.is_empty() {
            let message = format!(
                "{} disc(s) overlap body `{}` at the start: {}; set `overlapping_discs = \"remove\"` on the body to remove them, or move the body or the discs",
                found.len(),
                b.name,
                listed(found.len(), &found)
            );
            return Err(bad(&format!("body.{bi}"), message));
        }
    }
    Ok(())
}

/// How to mend discs that overlap at the start.
const OVERLAP_HINT: &str =
    "move them apart, or set `allow_overlap = true` in [granular] for a pre-stressed packing";

/// How much a disc at `x` of radius `r` overlaps wall `w` (> 0: they do).
pub(super) fn wall_overlap(w: &Wall, x: Vec2, r: f64) -> f64 {
    r - (w.closest(x) - x).norm()
}

/// The first (up to five) of `total` discs `(id, overlap)` that overlap
/// something, as a message lists them.
fn listed(total: usize, first: &[(usize, f64)]) -> String {
    let mut s: Vec<String> = first
        .iter()
        .take(5)
        .map(|(id, d)| format!("disc {} (overlap {d:.3e})", id + 1))
        .collect();
    if total > 5 {
        s.push(format!("and {} more", total - 5));
    }
    s.join(", ")
}

/// The refusal of `total` pairs of discs overlapping at the start, the
/// first (up to five) of them `(id, id, overlap)` in `first`.
pub(super) fn pairs_refusal(total: usize, first: &[(usize, usize, f64)]) -> Invalid {
    let tol = START_OVERLAP_TOL;
    let shown: Vec<String> = first
        .iter()
        .take(5)
        .map(|&(a, b, d)| format!("discs {} and {} (overlap {d:.3e})", a + 1, b + 1))
        .collect();
    bad(
        "granular.discs",
        format!(
            "{total} pair(s) of discs overlap at the start by more than {tol} of the smaller radius: {}{}; {OVERLAP_HINT}",
            shown.join(", "),
            if total > 5 { ", …" } else { "" }
        ),
    )
}

/// The refusal of `total` discs crossing wall `wi` (named `name`) at the
/// start, the first of them `(id, overlap)` in `first`.
pub(super) fn wall_refusal(wi: usize, name: &str, total: usize, first: &[(usize, f64)]) -> Invalid {
    bad(
        &format!("wall.{wi}"),
        format!(
            "{total} disc(s) cross wall `{name}` at the start: {}; {OVERLAP_HINT}",
            listed(total, first)
        ),
    )
}

/// Which overlaps of the start state are checked: `None` none (the
/// scenario allows them, or `check` does not settle its packing, whose
/// discs are not where the run will start them), else whether the
/// packing was settled by efgdem (its discs are then checked against the
/// bodies only).
pub(super) fn overlap_checks(sc: &Scenario, purpose: BuildFor) -> Result<Option<bool>, Invalid> {
    let spec = spec(sc)?;
    let settled = matches!(&spec.discs, DiscsSpec::Table(t)
        if t.generate.is_some() && matches!(t.method, Packing::Deposit | Packing::Grow));
    Ok(
        match spec.allow_overlap || (settled && purpose == BuildFor::Check) {
            true => None,
            false => Some(settled),
        },
    )
}

/// The start state's limits on the time step: the critical step of the
/// discs of `g` (or of those that decide it), a fall or an initial or
/// wall velocity that crosses its smallest disc in one step.
pub(super) fn start_limits(sc: &Scenario, g: &Granular) -> Result<(), Invalid> {
    let (mats, _) = laws(sc, &spec(sc)?.damping);
    let crit = g.critical_step(&body_laws(sc, &mats));
    if g.dt > crit.certain {
        return Err(bad(
            "simulation.dt",
            format!(
                "dt = {:e} is above {:e}, the stability limit of the normal mode of two of the lightest discs meeting (or one meeting a wall): the central difference is unstable at the first collision; the critical step of the contacts in use is {:e} (that of {}): use at most {:e} ({DT_WARN} × it; the default is {DT_SAFETY} ×)",
                g.dt,
                crit.certain,
                crit.dt,
                crit.mode,
                DT_WARN * crit.dt
            ),
        ));
    }
    // a disc must not fall through a contact in one step: |g| Δt² < r_min
    let fall = g.gravity.x.hypot(g.gravity.y) * g.dt * g.dt;
    let r_min = g
        .particles
        .radius
        .iter()
        .fold(f64::INFINITY, |a, &r| a.min(r));
    if fall.is_nan() || fall >= r_min {
        return Err(bad(
            "simulation.gravity",
            format!(
                "|g| Δt² = {fall:.3e}: a disc would fall by more than the smallest radius ({r_min:e}) in a single step of dt = {:e}, through any contact",
                g.dt
            ),
        ));
    }
    // nor a disc or wall cross a disc in its first step: |v| Δt < r_min
    let step = |v: Vec2| v.x.hypot(v.y) * g.dt;
    let through = |path: String, what: &str, d: f64| {
        Err(bad(
            &path,
            format!(
                "{what} moves {d:.3e} in one step of dt = {:e}, more than the smallest disc radius ({r_min:e}): it would pass through discs without touching them",
                g.dt
            ),
        ))
    };
    let v0 = spec(sc)?.velocity.map_or(0.0, |v| step(Vec2::from(v)));
    if v0.is_nan() || v0 >= r_min {
        return through(
            "granular.velocity".into(),
            "a disc at the initial velocity",
            v0,
        );
    }
    for (wi, w) in sc.wall.iter().enumerate() {
        // the wall's own motion, then each phase's
        let own = std::iter::once((String::new(), w.velocity, w.history.as_ref()));
        let phases = w
            .phases
            .iter()
            .flatten()
            .enumerate()
            .map(|(k, p)| (format!("phases.{k}."), p.velocity, p.history.as_ref()));
        for (at, velocity, history) in own.chain(phases) {
            let fastest = velocity
                .iter()
                .map(|&v| step(Vec2::from(v)))
                .chain(
                    history
                        .into_iter()
                        .flatten()
                        .map(|r| step(Vec2::new(r[1], r[2]))),
                )
                .fold(0.0, f64::max);
            if fastest.is_nan() || fastest >= r_min {
                let f = if velocity.is_some() {
                    "velocity"
                } else {
                    "history"
                };
                return through(
                    format!("wall.{wi}.{at}{f}"),
                    &format!("wall `{}`", w.name),
                    fastest,
                );
            }
        }
    }
    Ok(())
}

/// How much a disc at `x` of radius `r` overlaps body `b` in its reference
/// configuration: `r` ± the distance from `x` to the boundary (> 0: they
/// overlap).
pub fn body_overlap(b: &super::body::BodySpec) -> impl Fn(Vec2, f64) -> f64 {
    let lo = Vec2::from(b.rectangle.origin);
    let hi = lo + Vec2::from(b.rectangle.size);
    let domain = b.domain().ok().flatten();
    move |x, r| {
        if let Some(d) = &domain {
            // polygon: overlap = r ± distance to the boundary
            let dist = d.boundary_distance(x);
            return if d.contains(x) { r + dist } else { r - dist };
        }
        let c = Vec2::new(x.x.clamp(lo.x, hi.x), x.y.clamp(lo.y, hi.y));
        if c == x {
            // centre inside: overlap = r + distance to the nearest edge
            r + (x.x - lo.x).min(hi.x - x.x).min(x.y - lo.y).min(hi.y - x.y)
        } else {
            r - (c - x).norm()
        }
    }
}

/// The discs of `rows` that each body with `overlapping_discs = "remove"`
/// overlaps by more than [`START_OVERLAP_TOL`] of their radius (what the
/// start-state check would refuse): `(body index, row indices)`, a disc
/// counted for the first such body only.
pub fn overlapped(sc: &Scenario, rows: &[DiscRow]) -> Vec<(usize, Vec<usize>)> {
    let mut taken = vec![false; rows.len()];
    let mut out = Vec::new();
    for (bi, b) in sc.body.iter().enumerate() {
        if b.overlapping_discs != super::body::OverlappingDiscs::Remove {
            continue;
        }
        let overlap = body_overlap(b);
        let hit: Vec<usize> = (0..rows.len())
            .filter(|&k| {
                !taken[k] && overlap(rows[k].pos, rows[k].r) > START_OVERLAP_TOL * rows[k].r
            })
            .collect();
        for &k in &hit {
            taken[k] = true;
        }
        out.push((bi, hit));
    }
    out
}

/// How many discs each body with `overlapping_discs = "remove"` removes
/// from the discs the scenario describes (`purpose`: see [`BuildFor`]; for
/// `check` a prepared packing's discs are those before the preparation,
/// so the count is known only for other disc sources).
pub fn removed_discs(sc: &Scenario, purpose: BuildFor) -> Result<Vec<(String, usize)>, Invalid> {
    let removes =
        |b: &super::body::BodySpec| b.overlapping_discs == super::body::OverlappingDiscs::Remove;
    if sc.granular.is_none() || !sc.body.iter().any(removes) {
        return Ok(Vec::new());
    }
    let rows = kept(sc, disc_rows(sc, purpose)?)?;
    Ok(overlapped(sc, &rows)
        .into_iter()
        .map(|(bi, r)| (sc.body[bi].name.clone(), r.len()))
        .collect())
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
            let drive = |body: usize| {
                let c = usize::from(!q.ends_with('x'));
                model
                    .body(body)
                    .drives()
                    .iter()
                    .position(|d| d.0 == c)
                    .map(|index| Probe::Drive {
                        body,
                        index,
                        quantity: q.clone(),
                    })
                    .ok_or_else(|| bad(&at("quantity"), format!("body {body} has no drive on that component")))
            };
            let probe = match &model.system {
                _ if CRACK_QUANTITIES.contains(&q.as_str()) => crack_probe(model, body_index()?, pr)
                    .map_err(|m| bad(&at("tip"), m))?,
                System::Continuum { .. } if DRIVE_QUANTITIES.contains(&q.as_str()) => {
                    drive(body_index()?)?
                }
                System::Continuum { .. } => {
                    let body = body_index()?;
                    match pr.point {
                        Some(p) if !BODY_QUANTITIES.contains(&q.as_str()) => Probe::BodyPoint {
                            body,
                            at: bind(body, p)?,
                            point: Vec2::from(p),
                            generation: model.body(body).generation(),
                            field: q,
                        },
                        _ => Probe::BodyEnergy { body, quantity: q },
                    }
                }
                System::Granular(g) => granular_probe(g, pr, k, false)?,
                System::Coupled(m) => {
                    if is_body_probe(pr, false) {
                        let body = body_index()?;
                        if DRIVE_QUANTITIES.contains(&q.as_str()) {
                            drive(body)?
                        } else if CONTACT_FORCE_QUANTITIES.contains(&q.as_str()) {
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
                                point: Vec2::from(p),
                                generation: model.body(body).generation(),
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

/// A crack probe ([`Probe::Crack`]) of body `body`: crack `pr.crack`
/// (1-based, default 1), end `pr.tip` (1 first point, 2 last; default the
/// last point if it is a tip, else the first), which must be a tip for the
/// stress intensity factors.
fn crack_probe(model: &Model, body: usize, pr: &super::Probe) -> Result<Probe, String> {
    let crate::model::body::BodyRef::Efg(b) = model.body(body) else {
        return Err("crack quantities belong to EFG bodies".into());
    };
    let crack = pr.crack.unwrap_or(1).saturating_sub(1);
    let Some(c) = b.cracks().get(crack) else {
        return Err(format!("body `{}` has no crack {}", b.name, crack + 1));
    };
    let is_tip = |e: usize| c.ends[e] == crate::geom::crack::End::Tip;
    let end = match pr.tip {
        Some(t) => t.saturating_sub(1).min(1),
        None if is_tip(1) => 1,
        None => 0,
    };
    let needs_tip = matches!(pr.quantity.as_str(), "k1" | "k2" | "k_eq");
    if needs_tip && !is_tip(end) {
        return Err(format!(
            "end {} of crack {} is a mouth on the boundary, not a tip",
            end + 1,
            crack + 1
        ));
    }
    Ok(Probe::Crack {
        body,
        crack,
        end,
        quantity: pr.quantity.clone(),
    })
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
    // the ids of the whole assembly (a part holds some of them)
    let n = g.particles.slot.len().max(g.particles.len());
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
            let p = &g.particles;
            Probe::Disc {
                id,
                quantity: q.to_string(),
                // a part of the assembly may not hold the disc
                x0: match p.slot.get(id).map(|&s| s as usize) {
                    Some(s) if s < p.len() => p.pos[s],
                    // a part may hold neither the disc nor the whole's
                    // start positions (`x0` serves `ux`, `uy`: coupled
                    // runs only, which are not built in parts)
                    _ => g.start_of(id).unwrap_or(Vec2::ZERO),
                },
            }
        } else {
            return Err(bad(
                &format!("probe.{k}.quantity"),
                format!("`{q}` is not known to a granular run"),
            ));
        },
    )
}
