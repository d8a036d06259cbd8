//! Which coupled scheme a model steps with, and how many DEM steps each
//! body step spans: what a scenario names, or the fastest one that is
//! safe (`substeps = "auto"`, `coupling = "auto"`).
//!
//! The schemes ([`crate::coupling`]):
//! * **exact**: a body step per DEM step, the contacts implicit in it;
//!   two body solves and a contact solve per DEM step;
//! * **predicted** (n DEM steps per body step): the boundary on the path
//!   predicted under the last body step's loads, the discs' mean force as
//!   the next load; two body solves per body step and no contact solve.
//!   Its lag feeds the contacts back on themselves with the gain `Γ` of
//!   [`Continuum::collective_gain`](crate::continuum::Continuum::collective_gain):
//!   safe when `Γ` is small;
//! * **compliant** (n DEM steps per body step): the boundary on that path
//!   plus its response, through the body step's compliance, to the change
//!   of the contact forces, solved with the contacts in every DEM step:
//!   stable whatever `Γ`; two body solves per body step and a contact
//!   solve per DEM step over the chain points' compliance. It sees the
//!   body's response to the contacts as quasi-static within a body step,
//!   so the body step must not be long against the contacts' own period.
//!
//! The choice uses two numbers: `Γ(n)` per body for the predicted scheme
//! (one factorization and a few dozen solves per candidate n), and
//! `ω_c h`, the contacts' own angular frequency `ω_c = √(k_n/m)` (the
//! lightest disc on the stiffest body law) times the body step.

use super::{CoupledModel, CouplingError};
use crate::continuum::SolveError;

/// A coupled scheme ([module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// A body step per DEM step, the contacts implicit in it.
    Exact,
    /// Sub-cycled, the boundary on the path predicted under the held loads.
    Predicted,
    /// Sub-cycled, the boundary giving way to the contacts through the
    /// body step's compliance in every DEM step.
    Compliant,
    /// The body takes the previous state's contact forces (comparison
    /// only).
    Staggered,
}

impl Scheme {
    /// The name the scenario uses.
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::Exact => "exact",
            Scheme::Predicted => "predicted",
            Scheme::Compliant => "compliant",
            Scheme::Staggered => "staggered",
        }
    }
}

/// What a scenario asks for; `None`: choose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Request {
    /// The scheme, or choose one.
    pub scheme: Option<Scheme>,
    /// DEM steps per body step, or choose.
    pub substeps: Option<usize>,
}

/// The scheme a model steps with, and why.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Choice {
    /// The scheme.
    pub scheme: Scheme,
    /// DEM steps per body step.
    pub substeps: usize,
    /// `ω_c Δt`: the contacts' own angular frequency times the DEM step.
    pub omega_dt: f64,
    /// The predicted scheme's collective gain per body at each substep
    /// count examined, `(n, [Γ per body])`, largest n first.
    pub gains: Vec<(usize, Vec<f64>)>,
    /// Chosen (`true`) or named by the scenario.
    pub automatic: bool,
    /// Why, in a sentence.
    pub why: String,
}

/// The predicted scheme is safe while every body's collective gain is at
/// most this (measured map: docs/howto/choose-scheme-and-time-step.md).
pub const PREDICTED_MAX_GAIN: f64 = 0.02;

/// The compliant scheme takes body steps up to `ω_c h` = this (measured
/// map: docs/howto/choose-scheme-and-time-step.md).
pub const COMPLIANT_MAX_OMEGA_H: f64 = 3.0;

/// Substep counts the choice examines, largest first.
pub const CANDIDATES: [usize; 6] = [100, 50, 20, 10, 5, 2];

/// A predicted scheme with fewer substeps than this is slower than the
/// compliant one with more (each body step costs two body solves).
const PREDICTED_WORTH: usize = 10;

/// `ω_c = √(k_n/m)` of the lightest disc on the stiffest disc–body law
/// (0 without discs or contact stiffness).
pub fn contact_omega(m: &CoupledModel) -> f64 {
    let kn = m.body_laws.iter().fold(0.0f64, |k, l| k.max(l.kn));
    let mass = m.granular.particles.min_mass();
    if kn > 0.0 && mass.is_finite() && mass > 0.0 {
        (kn / mass).sqrt()
    } else {
        0.0
    }
}

/// Per body, the collective gain of the predicted scheme with body steps
/// of `n` DEM steps (each body factored again for them).
pub fn gains(m: &mut CoupledModel, n: usize) -> Result<Vec<f64>, SolveError> {
    let nm = m.granular.materials.len();
    let r_min = (m.granular.particles.radius.iter()).fold(f64::INFINITY, |a, &r| a.min(r));
    let spacing = 2.0 * r_min;
    let h = m.granular.dt * n as f64;
    let mut out = Vec::new();
    for (b, body) in m.bodies.iter_mut().enumerate() {
        let laws = &m.body_laws[b * nm..(b + 1) * nm];
        let kn = laws.iter().fold(0.0f64, |k, l| k.max(l.kn));
        let ks = laws.iter().fold(0.0f64, |k, l| k.max(l.ks));
        if !(spacing.is_finite() && spacing > 0.0) || kn == 0.0 {
            out.push(0.0);
            continue;
        }
        if m.factored != n {
            body.set_step(h)?;
        }
        out.push(body.collective_gain(kn, ks, spacing)?);
    }
    m.factored = n;
    Ok(out)
}

/// Largest gain of a list (0 for none).
fn worst(g: &[f64]) -> f64 {
    g.iter().fold(0.0f64, |a, &b| a.max(b))
}

/// Choose the scheme for `req` (see the [module docs](self)); the bodies
/// are left factored for whatever body step was examined last
/// ([`apply`] sets the chosen one). A scheme named with a substep count
/// that is not safe is refused: [`Err`] with the reason.
pub fn choose(m: &mut CoupledModel, req: Request) -> Result<Result<Choice, String>, SolveError> {
    let dt = m.granular.dt;
    let omega_dt = contact_omega(m) * dt;
    let compliant_n = || {
        let n = if omega_dt > 0.0 {
            (COMPLIANT_MAX_OMEGA_H / omega_dt).floor()
        } else {
            CANDIDATES[0] as f64
        };
        (n.min(CANDIDATES[0] as f64) as usize).max(1)
    };
    let mut examined: Vec<(usize, Vec<f64>)> = Vec::new();
    let choice = |scheme, substeps, examined: Vec<_>, automatic, why: String| Choice {
        scheme,
        substeps,
        omega_dt,
        gains: examined,
        automatic,
        why,
    };
    let gain_text = |n: usize, g: &[f64]| {
        format!(
            "collective gain Γ = {:.3} at {n} substeps (ω_c h = {:.2})",
            worst(g),
            omega_dt * n as f64
        )
    };
    let no_bodies = m.bodies.is_empty() || omega_dt == 0.0;
    let _ = &no_bodies;
    match (req.scheme, req.substeps) {
        (Some(Scheme::Staggered), n) => Ok(Ok(choice(
            Scheme::Staggered,
            n.unwrap_or(1),
            examined,
            false,
            "named by the scenario (coupling = \"staggered\")".into(),
        ))),
        (Some(Scheme::Exact), None | Some(1)) | (None, Some(1)) => Ok(Ok(choice(
            Scheme::Exact,
            1,
            examined,
            false,
            "named by the scenario".into(),
        ))),
        (Some(Scheme::Exact), Some(n)) => Ok(Err(format!(
            "the exact step takes one DEM step per body step (got substeps = {n}); use substeps = 1 or \"auto\", or another coupling"
        ))),
        (Some(Scheme::Compliant), n) => {
            let n = n.unwrap_or_else(compliant_n);
            let why = match req.substeps {
                Some(_) => "named by the scenario".to_string(),
                None => format!(
                    "named by the scenario; {n} substeps: the largest with ω_c h ≤ {COMPLIANT_MAX_OMEGA_H} (ω_c Δt = {omega_dt:.3})"
                ),
            };
            Ok(Ok(choice(Scheme::Compliant, n, examined, false, why)))
        }
        (Some(Scheme::Predicted), Some(n)) | (None, Some(n)) => {
            let g = gains(m, n)?;
            let safe = worst(&g) <= PREDICTED_MAX_GAIN || no_bodies;
            let text = gain_text(n, &g);
            examined.push((n, g));
            if safe {
                let why = format!("{text} ≤ {PREDICTED_MAX_GAIN}");
                let auto = req.scheme.is_none();
                Ok(Ok(choice(Scheme::Predicted, n, examined, auto, why)))
            } else if req.scheme.is_none() {
                let why = format!(
                    "the predicted scheme's {text} is above {PREDICTED_MAX_GAIN}: the boundary gives way to the contacts in every DEM step instead"
                );
                Ok(Ok(choice(Scheme::Compliant, n, examined, true, why)))
            } else {
                Ok(Err(format!(
                    "the predicted scheme is not safe for this body: {text}, above {PREDICTED_MAX_GAIN} (its lag can drive the contacts); use coupling = \"compliant\", fewer substeps, or substeps = 1"
                )))
            }
        }
        (scheme @ (None | Some(Scheme::Predicted)), None) => {
            if no_bodies {
                let why = "exact: no disc–body contact stiffness to sub-cycle against".into();
                return Ok(Ok(choice(Scheme::Exact, 1, examined, true, why)));
            }
            // the predicted scheme at the largest safe n
            let mut predicted = None;
            for n in CANDIDATES {
                let g = gains(m, n)?;
                let ok = worst(&g) <= PREDICTED_MAX_GAIN;
                examined.push((n, g));
                if ok {
                    predicted = Some(n);
                    break;
                }
            }
            let last = examined.last().map(|(n, g)| gain_text(*n, g));
            if scheme == Some(Scheme::Predicted) {
                return Ok(match predicted {
                    Some(n) => {
                        let why = format!(
                            "{}: the largest substep count examined with Γ ≤ {PREDICTED_MAX_GAIN}",
                            last.unwrap_or_default()
                        );
                        Ok(choice(Scheme::Predicted, n, examined, true, why))
                    }
                    None => Err(format!(
                        "no substep count is safe for the predicted scheme: {} is above {PREDICTED_MAX_GAIN}; use coupling = \"compliant\" or \"exact\"",
                        last.unwrap_or_default()
                    )),
                });
            }
            let nc = compliant_n();
            Ok(Ok(match predicted {
                Some(n) if n >= nc.min(PREDICTED_WORTH) || nc < 2 => {
                    let why = format!(
                        "predicted, {n} substeps: {} ≤ {PREDICTED_MAX_GAIN}",
                        last.unwrap_or_default()
                    );
                    choice(Scheme::Predicted, n, examined, true, why)
                }
                _ if nc >= 2 => {
                    let why = format!(
                        "compliant, {nc} substeps: the predicted scheme is not safe at a useful step ({}); {nc} is the largest with ω_c h ≤ {COMPLIANT_MAX_OMEGA_H} (ω_c Δt = {omega_dt:.3})",
                        last.unwrap_or_default()
                    );
                    choice(Scheme::Compliant, nc, examined, true, why)
                }
                _ => {
                    let why = format!(
                        "exact: the contacts' own period is resolved by few DEM steps (ω_c Δt = {omega_dt:.3}: a body step of 2 would reach ω_c h = {:.2} > {COMPLIANT_MAX_OMEGA_H}) and the predicted scheme is not safe ({})",
                        2.0 * omega_dt,
                        last.unwrap_or_default()
                    );
                    choice(Scheme::Exact, 1, examined, true, why)
                }
            }))
        }
    }
}

/// Make `m` step with `c`: its substeps, each body factored for the body
/// step, the scheme's switches.
pub fn apply(m: &mut CoupledModel, c: &Choice) -> Result<(), CouplingError> {
    m.substeps = c.substeps.max(1);
    let h = m.granular.dt * m.substeps as f64;
    if m.factored != m.substeps {
        for b in &mut m.bodies {
            b.set_step(h)?;
        }
        m.factored = m.substeps;
    }
    m.staggered = c.scheme == Scheme::Staggered;
    if c.scheme == Scheme::Compliant {
        m.set_compliant()?;
    }
    m.choice = Some(c.clone());
    Ok(())
}
