//! `efgdem study-dt`: the largest stable time step of a coupled scenario
//! (§4.2.3 of the paper: EFG–DE ran at Δt = 0.01525, FE–DE reportedly
//! needed 1.525e-5).
//!
//! A run at Δt covers the scenario's physical time: its step counts
//! (`steps`, walls', wall phases' and edges' `until_step`) are rescaled from the
//! scenario's Δt. It is **bounded** when it completes with a finite state
//! and the stored energy (kinetic + strain + contact) never exceeds
//! [`ENERGY_FACTOR`] times the largest of the external work so far, the
//! initial stored energy and the energy at the scenario's own Δt. The
//! search bisects (in log Δt) between the scenario's Δt and the DEM
//! critical step `2√(m_min/k_max)`, the upper limit of the explicit side.

use crate::continuum::Prescribed;
use crate::coupling::energy::WorkMeter;
use crate::coupling::{CoupledModel, CouplingError};
use crate::run::RunError;
use crate::scenario::Scenario;

/// Unbounded when the stored energy exceeds this factor times the work put in.
pub const ENERGY_FACTOR: f64 = 10.0;

/// One trial run.
#[derive(Debug, Clone)]
pub struct Trial {
    /// The time step tried.
    pub dt: f64,
    /// Completed with a finite state and bounded stored energy.
    pub bounded: bool,
    /// Why it is not bounded (or "ok").
    pub reason: String,
    /// Wall time of the trial (s).
    pub seconds: f64,
}

/// The result of the study.
#[derive(Debug, Clone)]
pub struct DtStudy {
    /// The largest Δt studied: the lightest disc's wall step
    /// `2√(m_min/k_max)`, or the build's limit for a first collision
    /// ([`Critical::certain`](crate::dem::critical::Critical::certain)) if
    /// smaller.
    pub dt_critical: f64,
    /// Largest bounded Δt found (within `rel_tol`), if any.
    pub dt_max: Option<f64>,
    /// Every trial run, in the order run.
    pub trials: Vec<Trial>,
}

/// The scenario with time step `dt` over the same physical time.
pub fn with_dt(sc: &Scenario, dt: f64) -> Scenario {
    let mut s = sc.clone();
    let dt0 = sc.simulation.dt.unwrap_or(dt);
    let scale = |n: usize| ((n as f64) * dt0 / dt).round().max(1.0) as usize;
    s.simulation.dt = Some(dt);
    if let Some(n) = sc.simulation.steps {
        s.simulation.steps = Some(scale(n));
    }
    for w in &mut s.wall {
        w.until_step = w.until_step.map(scale);
        for ph in w.phases.iter_mut().flatten() {
            ph.until_step = ph.until_step.map(scale);
        }
    }
    for b in &mut s.body {
        for bc in &mut b.bc {
            for p in [&mut bc.ux, &mut bc.uy].into_iter().flatten() {
                if let Prescribed::Motion(m) = p {
                    m.until_step = m.until_step.map(scale);
                }
            }
        }
    }
    s.output.every = usize::MAX;
    s
}

/// Run `sc` at `dt` and decide whether it stays bounded. `e_ref` is an
/// energy scale below which growth is not judged (the reference run's).
pub fn trial(sc: &Scenario, dt: f64, e_ref: f64) -> Result<(Trial, f64), RunError> {
    let t0 = std::time::Instant::now();
    let (mut m, steps) = coupled(&with_dt(sc, dt))?;
    let mut meter = WorkMeter::new(&m);
    let e0 = meter.account(&m).stored();
    let (mut w_max, mut e_max) = (0.0f64, e0);
    let mut verdict = Ok(());
    for step in 0..steps {
        if let Err(e) = m.step() {
            verdict = Err(match e {
                CouplingError::Unstable { .. } => format!("non-finite discs at step {step}"),
                other => other.to_string(),
            });
            break;
        }
        meter.after_step(&m.granular);
        let e = meter.account(&m);
        let stored = e.stored();
        w_max = w_max.max(e.w_ext.abs());
        e_max = e_max.max(stored);
        let limit = ENERGY_FACTOR * w_max.max(e0).max(e_ref);
        if !stored.is_finite() || stored > limit {
            verdict = Err(format!(
                "stored energy {stored:.3e} > {ENERGY_FACTOR} × {:.3e} at step {step}",
                limit / ENERGY_FACTOR
            ));
            break;
        }
    }
    let seconds = t0.elapsed().as_secs_f64();
    Ok((
        Trial {
            dt,
            bounded: verdict.is_ok(),
            reason: verdict.err().unwrap_or_else(|| "ok".into()),
            seconds,
        },
        e_max,
    ))
}

/// Bisect for the largest bounded Δt up to the DEM critical step, to a
/// relative tolerance `rel_tol`. `progress` is told about every trial.
pub fn study_dt(
    sc: &Scenario,
    rel_tol: f64,
    mut progress: impl FnMut(&Trial),
) -> Result<DtStudy, RunError> {
    let (m, _) = coupled(sc)?;
    let crit = m.granular.critical_step(&m.body_laws);
    // trials above the collision limit are refused at the build
    let dt_critical = m.granular.critical_dt().min(crit.certain);
    let dt0 = (sc.simulation.dt).unwrap_or(crate::dem::DT_SAFETY * crit.dt);
    // trials rescale step counts from the scenario's Δt: make it explicit
    let mut sc = sc.clone();
    sc.simulation.dt = Some(dt0);
    let sc = &sc;
    let mut trials = Vec::new();
    let mut record = |t: Trial, trials: &mut Vec<Trial>| {
        progress(&t);
        let ok = t.bounded;
        trials.push(t);
        ok
    };
    // the scenario's own Δt sets the energy scale; shrink until bounded
    let mut lo = dt0.min(dt_critical);
    let e_ref = loop {
        let (t, e) = trial(sc, lo, 0.0)?;
        if record(t, &mut trials) {
            break e;
        }
        lo /= 10.0;
        if lo < dt0 * 1e-4 {
            return Ok(DtStudy {
                dt_critical,
                dt_max: None,
                trials,
            });
        }
    };
    let mut hi = dt_critical;
    let (t, _) = trial(sc, hi, e_ref)?;
    if record(t, &mut trials) {
        return Ok(DtStudy {
            dt_critical,
            dt_max: Some(hi),
            trials,
        });
    }
    while hi / lo > 1.0 + rel_tol {
        let mid = (lo * hi).sqrt();
        let (t, _) = trial(sc, mid, e_ref)?;
        if record(t, &mut trials) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(DtStudy {
        dt_critical,
        dt_max: Some(lo),
        trials,
    })
}

/// The coupled model of `sc` and its number of steps.
fn coupled(sc: &Scenario) -> Result<(CoupledModel, usize), RunError> {
    let model = sc.build()?;
    let steps = model.steps;
    match model.system {
        crate::model::System::Coupled(m) => Ok((*m, steps)),
        _ => Err(RunError::Scenario(sc.located(vec![
            crate::scenario::Invalid {
                path: String::new(),
                message: "study-dt needs a coupled scenario ([[body]] and [granular])".into(),
            },
        ]))),
    }
}
