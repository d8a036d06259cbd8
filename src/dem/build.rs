//! Building a [`Granular`] from a scenario: discs (inline, CSV, generated),
//! materials with the named damping, walls with their motion.

use super::contact::{ContactLaw, SlipNormal};
use super::particles::Particles;
use super::walls::{Wall, WallMotion};
use super::{BodyDamping, DemError, Granular};
use crate::geom::Vec2;
use crate::scenario::Scenario;
use crate::scenario::generate::{DiscRow, Lattice, discs_from_csv, lattice_packing};
use crate::scenario::granular::{
    DampingSpec, DiscsSpec, Generator, GranularSpec, Packing, SlipNormalSpec, slip_normal,
};

/// Default fraction of the critical step when `simulation.dt` is omitted.
pub const DT_SAFETY: f64 = 0.1;
/// `efgdem check` and `run` warn above this fraction of the critical step (E11).
pub const DT_WARN: f64 = 0.2;

fn spec(sc: &Scenario) -> Result<&GranularSpec, DemError> {
    sc.granular
        .as_ref()
        .ok_or_else(|| DemError::Input("the scenario has no [granular] section".into()))
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

fn material_index(sc: &Scenario, name: &str) -> Result<u16, DemError> {
    sc.material
        .iter()
        .position(|m| m.name == name)
        .map(|i| i as u16)
        .ok_or_else(|| DemError::Input(format!("no [[material]] named `{name}`")))
}

/// The discs the scenario describes (generating or reading them).
pub fn disc_rows(sc: &Scenario) -> Result<Vec<DiscRow>, DemError> {
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
                    DemError::Input(format!("cannot read discs file {}: {e}", path.display()))
                })?;
                return discs_from_csv(&text)
                    .map_err(|e| DemError::Input(format!("{}: {e}", path.display())));
            }
            let kind = t
                .generate
                .ok_or_else(|| DemError::Input("granular.discs: nothing to generate".into()))?;
            let [a, b] = t
                .region
                .ok_or_else(|| DemError::Input("granular.discs.box is missing".into()))?;
            let radius = t
                .radius
                .ok_or_else(|| DemError::Input("granular.discs.radius is missing".into()))?
                .range();
            let (lat, gap, jitter) = match kind {
                Generator::Square => (Lattice::Square, 0.0, t.jitter.unwrap_or(0.0)),
                Generator::Hex => (Lattice::Hex, 0.0, t.jitter.unwrap_or(0.0)),
                Generator::Random => (Lattice::Hex, 0.1, t.jitter.unwrap_or(1.0)),
            };
            let (lo, hi) = (Vec2::from(a), Vec2::from(b));
            let steps = t.settle_steps.unwrap_or(20_000);
            if kind == Generator::Random && t.method == Packing::Grow {
                let count = t.count.ok_or_else(|| {
                    DemError::Input("granular.discs: `method = \"grow\"` needs `count`".into())
                })?;
                return grow(sc, lo, hi, radius, count, t.seed, steps);
            }
            let rows = lattice_packing(lat, lo, hi, radius, t.count, gap, jitter, t.seed)
                .map_err(|e| DemError::Input(format!("granular.discs: {e}")))?;
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
) -> Result<Vec<DiscRow>, DemError> {
    let g = spec(sc)?;
    let mi = material_index(sc, &g.material)?;
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
}

/// Radius growth: `count` centres uniform in the box (seeded), final radii
/// uniform in `[r_min, r_max]`; the radii start at the scale that gives a
/// packing fraction of 0.3 and grow linearly to their final size over 70 %
/// of `steps` DEM steps (no gravity, local damping 0.7, normal dashpot
/// ζ = 0.3 with the elastic Coulomb cap, four fixed walls), then the
/// packing relaxes for the rest.
fn grow(
    sc: &Scenario,
    lo: Vec2,
    hi: Vec2,
    (r_min, r_max): (f64, f64),
    count: usize,
    seed: u64,
    steps: usize,
) -> Result<Vec<DiscRow>, DemError> {
    let g = spec(sc)?;
    let mi = material_index(sc, &g.material)?;
    let (mut mats, _) = laws(sc, &DampingSpec::None);
    let mut law = mats[mi as usize];
    law.zeta_n = 0.3;
    // the settling dashpot is a numerical aid: it must not add friction
    law.slip_normal = SlipNormal::Elastic;
    mats = vec![law];
    let mut rng = oorandom::Rand64::new(seed as u128);
    let r_final: Vec<f64> = (0..count)
        .map(|_| r_min + (r_max - r_min) * rng.rand_float())
        .collect();
    let area: f64 = r_final.iter().map(|r| std::f64::consts::PI * r * r).sum();
    let ext = hi - lo;
    let phi = area / (ext.x * ext.y);
    if phi > 0.85 {
        return Err(DemError::Input(format!(
            "granular.discs: {count} discs of radius {r_min}…{r_max} fill {:.0} % of the box; radius growth reaches at most 85 %",
            100.0 * phi
        )));
    }
    let s0 = (0.3 / phi).sqrt().min(1.0);
    let density = sc.material[mi as usize].density;
    let mut p = Particles::default();
    for &r in &r_final {
        let x = lo.x + r_max + (ext.x - 2.0 * r_max).max(0.0) * rng.rand_float();
        let y = lo.y + r_max + (ext.y - 2.0 * r_max).max(0.0) * rng.rand_float();
        // mass of the final disc: the critical step stays that of the end state
        p.push(Vec2::new(x, y), r, density, g.thickness, 0);
    }
    for (r, rf) in p.radius.iter_mut().zip(&r_final) {
        *r = rf * s0;
    }
    let corners = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
    let walls = (0..4)
        .map(|k| Wall::new("box", corners[k], corners[(k + 1) % 4], WallMotion::Fixed))
        .collect();
    let mut gr = Granular::new(p, mats, walls, 1.0);
    gr.dt = 0.15 * gr.critical_dt();
    gr.damping = BodyDamping::Local { alpha: 0.7 };
    gr.set_skin(0.1 * r_max);
    let grow_steps = (0.7 * steps as f64) as usize;
    for n in 0..steps {
        if n <= grow_steps {
            let s = s0 + (1.0 - s0) * (n as f64 / grow_steps.max(1) as f64);
            let p = &mut gr.particles;
            for (r, &id) in p.radius.iter_mut().zip(&p.id) {
                *r = r_final[id as usize] * s;
            }
            // radii grow by ≪ skin/2 in 10 steps: rebuild every 10 steps
            if n % 10 == 0 {
                gr.grid.stale = true;
            }
        }
        gr.step();
    }
    gr.check_finite()?;
    let p = &gr.particles;
    Ok((0..count)
        .map(|id| {
            let k = p.slot[id] as usize;
            DiscRow {
                pos: p.pos[k],
                r: r_final[id],
                material: None,
            }
        })
        .collect())
}

/// Settle `rows` in the box `[lo, hi]` (four fixed walls) under `gravity`
/// for `steps` steps at 0.15 × the critical step, with local damping 0.3
/// and a normal dashpot at ζ = 0.3 added to `law` (with the elastic
/// Coulomb cap, so that this settling aid adds no friction). Returns the
/// settled discs in the input order.
#[allow(clippy::too_many_arguments)]
pub fn settle_in_box(
    rows: &[DiscRow],
    lo: Vec2,
    hi: Vec2,
    law: ContactLaw,
    density: f64,
    thickness: f64,
    gravity: Vec2,
    steps: usize,
) -> Result<Vec<DiscRow>, DemError> {
    let mut p = Particles::default();
    for r in rows {
        p.push(r.pos, r.r, density, thickness, 0);
    }
    let corners = [lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
    let walls = (0..4)
        .map(|k| Wall::new("box", corners[k], corners[(k + 1) % 4], WallMotion::Fixed))
        .collect();
    let mut law = law;
    law.zeta_n = 0.3;
    // the settling dashpot is a numerical aid: it must not add friction
    law.slip_normal = SlipNormal::Elastic;
    let mut gr = Granular::new(p, vec![law], walls, 1.0);
    gr.dt = 0.15 * gr.critical_dt();
    gr.gravity = gravity;
    gr.damping = BodyDamping::Local { alpha: 0.3 };
    for _ in 0..steps {
        gr.step();
    }
    gr.check_finite()?;
    let p = &gr.particles;
    Ok((0..p.len())
        .map(|id| {
            let s = p.slot[id] as usize;
            DiscRow {
                pos: p.pos[s],
                r: p.radius[s],
                material: rows[id].material.clone(),
            }
        })
        .collect())
}

/// Build the assembly described by the scenario. `dt` is the scenario's,
/// or [`DT_SAFETY`] × the critical step.
pub fn build(sc: &Scenario) -> Result<Granular, DemError> {
    let g = spec(sc)?;
    let rows = disc_rows(sc)?;
    let default_mat = material_index(sc, &g.material)?;
    let (mats, body) = laws(sc, &g.damping);
    let mut p = Particles::default();
    let v0 = g.velocity.map(Vec2::from).unwrap_or(Vec2::ZERO);
    for (k, r) in rows.iter().enumerate() {
        let mi = match &r.material {
            Some(name) => material_index(sc, name)
                .map_err(|e| DemError::Input(format!("disc {}: {e}", k + 1)))?,
            None => default_mat,
        };
        let m = &sc.material[mi as usize];
        if m.density.is_nan() || m.density <= 0.0 {
            return Err(DemError::Input(format!(
                "disc {}: material `{}` needs a density > 0",
                k + 1,
                m.name
            )));
        }
        p.push(r.pos, r.r, m.density, g.thickness, mi);
        p.vel[k] = v0;
    }
    let mut walls = Vec::new();
    for w in &sc.wall {
        let motion = match (&w.velocity, &w.history) {
            (Some(v), _) => WallMotion::Constant {
                velocity: Vec2::from(*v),
                until_step: w.until_step,
            },
            (None, Some(h)) => {
                WallMotion::Piecewise(h.iter().map(|r| (r[0], Vec2::new(r[1], r[2]))).collect())
            }
            (None, None) => WallMotion::Fixed,
        };
        let mut wall = Wall::new(&w.name, Vec2::from(w.from), Vec2::from(w.to), motion);
        if let Some(m) = &w.material {
            wall.material = Some(material_index(sc, m)?);
        }
        walls.push(wall);
    }
    let mut gr = Granular::new(p, mats, walls, 1.0);
    gr.damping = body;
    gr.gravity = Vec2::from(sc.simulation.gravity);
    gr.dt = sc.simulation.dt.unwrap_or(DT_SAFETY * gr.critical_dt());
    if !gr.dt.is_finite() || gr.dt <= 0.0 {
        return Err(DemError::Input(
            "cannot choose a time step: give simulation.dt (no contact stiffness to derive it from)"
                .into(),
        ));
    }
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

/// A warning when Δt exceeds [`DT_WARN`] × the critical step (ERRATA E11).
pub fn dt_warning(gr: &Granular) -> Option<String> {
    let crit = gr.critical_dt();
    (gr.dt > DT_WARN * crit).then(|| {
        format!(
            "dt = {:e} is {:.3} × the critical step 2√(m_min/k_max) = {crit:e}; above {DT_WARN} × it the central difference may be unstable (ERRATA E11)",
            gr.dt,
            gr.dt / crit
        )
    })
}
