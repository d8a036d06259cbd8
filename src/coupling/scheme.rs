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
//!   stable whatever `Γ`; two body solves per body step (one for a body
//!   without moving edges) and a contact solve per DEM step over the
//!   chain points' compliance. It sees the body's response to the
//!   contacts as quasi-static within a body step, so the body step must
//!   not be long against the contacts' own period.
//!
//! The choice uses three numbers: `Γ(n)` per body for the predicted scheme
//! (one factorization and a few dozen solves per candidate n); `ω_c h`,
//! the contacts' own angular frequency `ω_c = √(k_n/m)` (the lightest
//! disc on the stiffest body law) times the body step; and `ω_b h`, the
//! bodies' collective-mode frequency ([`Collective::omega`]) times the
//! body step: the compliant scheme resolves both periods.

use super::{CoupledModel, CouplingError};
use crate::continuum::{Collective, SolveError};
use crate::dem::contact::ContactLaw;

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
    /// `ω_b Δt`: the bodies' collective-mode angular frequency
    /// ([`Collective::omega`], the largest over the bodies, at the longest
    /// body step examined) times the DEM step; 0 if not examined.
    pub body_omega_dt: f64,
    /// The predicted scheme's collective gain per body at each substep
    /// count examined, `(n, [Γ per body])`, largest n first.
    pub gains: Vec<(usize, Vec<f64>)>,
    /// Chosen (`true`) or named by the scenario.
    pub automatic: bool,
    /// Why, in a sentence.
    pub why: String,
    /// A scheme the scenario named against the measured map.
    pub warning: Option<String>,
    /// The exact step's body solves against the DEM step, estimated
    /// ([`exact_overhead`]).
    pub exact_overhead: f64,
    /// Contacts the bodies' chains can carry at once: their length over
    /// the mean disc diameter ([`max_contacts`]).
    pub max_contacts: usize,
    /// The last sub-cycled scheme given up during the run for fewer
    /// substeps or the exact step ([`CoupledModel::fall_back`]).
    pub fallback: Option<super::Fallback>,
}

/// Contacts the bodies' contact chains can carry at once: their length
/// over the mean disc diameter.
pub fn max_contacts(m: &CoupledModel) -> usize {
    let p = &m.granular.particles;
    let d = 2.0 * p.radius.iter().sum::<f64>() / p.len().max(1) as f64;
    let length: f64 = (m.bodies.iter())
        .flat_map(|b| b.contact_boundary())
        .flat_map(|c| c.reference.windows(2).map(|s| (s[1] - s[0]).norm()))
        .sum();
    if d > 0.0 {
        (length / d).ceil() as usize
    } else {
        0
    }
}

/// The compliant scheme's contact solve grows with the cube of the
/// contacts in it: the choice uses it only on bodies whose chains carry at
/// most this many ([`max_contacts`]).
pub const COMPLIANT_MAX_CONTACTS: usize = 300;

/// The predicted scheme is safe while every body's collective gain is at
/// most this (measured map: docs/howto/choose-scheme-and-time-step.md,
/// `examples/scheme_map.rs`). Larger gains are not, whatever the body
/// step: gains 0.03–0.1 with `ω_c h` ≤ 0.7 create 1.5–4 % of the work
/// exchanged and grow, and so do the footings of `examples/footing.toml`
/// (Γ = 0.086 at `ω_c h` = 3.1: 8.8 %) and the stiff footing of
/// `examples/soft_footing.toml` (E = 10 GPa, Γ = 0.097 at `ω_c h` = 6.2:
/// 2.6 %).
pub const PREDICTED_MAX_GAIN: f64 = 0.02;

/// Longest body step of the predicted scheme the map covers, in `ω_c h`.
pub const PREDICTED_MAX_OMEGA_H: f64 = 10.0;

/// Is the predicted scheme safe with the collective gain `gain` at a body
/// step of `omega_h` (`ω_c h`)?
pub fn predicted_safe(gain: f64, omega_h: f64) -> bool {
    omega_h <= PREDICTED_MAX_OMEGA_H && gain <= PREDICTED_MAX_GAIN
}

/// The predicted scheme's rule, for messages.
fn predicted_rule() -> String {
    format!("Γ ≤ {PREDICTED_MAX_GAIN} with ω_c h ≤ {PREDICTED_MAX_OMEGA_H}")
}

/// The compliant scheme takes body steps up to `ω_b h` = this, `ω_b` the
/// bodies' collective mode, damped contacts or not (the body rings on its
/// own): the 10 GPa footing of `examples/soft_footing.toml`
/// (ω_b Δt = 0.68) created 2.5 % of the work it exchanged at
/// `ω_b h` = 4.1, 0.84 % at 2.0 and 0.16 % at 1.35.
pub const COMPLIANT_MAX_OMEGA_H: f64 = 2.0;

/// The compliant scheme takes body steps up to `ω_c h` = this when a
/// disc–body contact law has no normal dashpot (or a weaker one than
/// [`COMPLIANT_DAMPED_ZETA`]). Measured (`examples/scheme_map.rs`, the
/// undamped bed, where nothing dissipates the contacts' oscillation, at
/// E = 0.1–10 GPa, with friction 0 and 0.5): at most 0.21 % of the work
/// exchanged created up to `ω_c h` = 1.73, but 0.6 and 1.1 % in two of
/// the frictional cases at 2.01, and a body step near half the contacts'
/// period resonates (16 % at `ω_c h` = 2.98, 4.3 % at 3.47 with
/// friction).
pub const COMPLIANT_UNDAMPED_OMEGA_H: f64 = 1.75;

/// The compliant scheme's longest body step against the contacts' own
/// period, in `ω_c h`, when every disc–body contact law has a normal
/// dashpot of at least [`COMPLIANT_DAMPED_ZETA`] of critical
/// ([`contact_zeta`]): the dashpot damps the resonance of a body step near
/// half the contacts' period. Measured (`examples/scheme_map.rs` with
/// `ζ` = 0.05, 0.1, 0.2, friction 0 and 0.5, E = 0.1–10 GPa): at most
/// 0.51 % of the work exchanged created up to `ω_c h` = 4.02, and the
/// mean reaction within 1.2 % of the exact step's (0.6 % at 5.55).
pub const COMPLIANT_DAMPED_OMEGA_H: f64 = 4.0;

/// The normal dashpot, as a fraction of critical, from which the
/// contacts count as damped ([`COMPLIANT_DAMPED_OMEGA_H`]): the least
/// the measured map examined.
pub const COMPLIANT_DAMPED_ZETA: f64 = 0.05;

/// The choice keeps the exact step for assemblies of fewer discs than
/// this: their DEM step costs little, and the exact step resolves each
/// contact's impulse on the body (a sub-cycled body sees the contacts'
/// forces only as body-step averages or end values, which a single impact
/// shorter than a body step does not survive).
pub const AUTO_MIN_DISCS: usize = 1000;

/// The choice keeps the exact step when its two body solves per DEM step
/// are estimated to cost at most this fraction of the DEM step
/// ([`exact_overhead`]).
pub const EXACT_OVERHEAD: f64 = 0.3;

/// The exact step's body solves per DEM step against the DEM step, from
/// the factors' entries and the discs (two triangular pairs over the factor
/// per body, memory bound, against the discs' sweep: calibrated on the
/// soft footing of docs/performance.md, where the estimate is within 30 %
/// of the measured split).
pub fn exact_overhead(m: &mut CoupledModel) -> f64 {
    let nnz: usize = m.bodies.iter_mut().map(|b| b.factor_nnz()).sum();
    let n = m.granular.particles.len().max(1);
    OVERHEAD_PER_ENTRY * nnz as f64 / n as f64
}

/// Cost of a body's two solves per factor entry against the DEM step per
/// disc ([`exact_overhead`]).
const OVERHEAD_PER_ENTRY: f64 = 0.15;

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

/// The least damping ratio of the disc–body contact laws' normal
/// dashpots: `ζ_n`, plus `β_n ω / 2` of a stiffness-proportional one at
/// the heaviest disc's `ω = √(k_n/m)` (its least); 0 without laws.
pub fn contact_zeta(m: &CoupledModel) -> f64 {
    let p = &m.granular.particles;
    let heaviest = p.mass.iter().fold(0.0f64, |a, &b| a.max(b));
    let zeta = |l: &ContactLaw| {
        let omega = if heaviest > 0.0 {
            (l.kn / heaviest).sqrt()
        } else {
            0.0
        };
        l.zeta_n + 0.5 * l.beta_n * omega
    };
    let least = (m.body_laws.iter())
        .filter(|l| l.kn > 0.0)
        .map(zeta)
        .fold(f64::INFINITY, f64::min);
    if least.is_finite() { least } else { 0.0 }
}

/// The compliant scheme's bound on `ω_c h`: [`COMPLIANT_DAMPED_OMEGA_H`]
/// when the disc–body contacts are damped ([`contact_zeta`] at least
/// [`COMPLIANT_DAMPED_ZETA`]), else [`COMPLIANT_UNDAMPED_OMEGA_H`].
pub fn compliant_contact_bound(zeta: f64) -> f64 {
    if zeta >= COMPLIANT_DAMPED_ZETA {
        COMPLIANT_DAMPED_OMEGA_H
    } else {
        COMPLIANT_UNDAMPED_OMEGA_H
    }
}

/// Per body, the collective gain of the predicted scheme with body steps
/// of `n` DEM steps (each body factored again for them), and the body's
/// frequency in that push ([`Collective`]).
pub fn gains(m: &mut CoupledModel, n: usize) -> Result<Vec<Collective>, SolveError> {
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
            out.push(Collective::default());
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

/// The gains of `gains`, and the largest body frequency.
fn split(c: Vec<Collective>) -> (Vec<f64>, f64) {
    let omega = c.iter().fold(0.0f64, |a, b| a.max(b.omega));
    (c.into_iter().map(|c| c.gain).collect(), omega)
}

/// Choose the scheme for `req` (see the [module docs](self)); the bodies
/// are left factored for whatever body step was examined last
/// ([`apply`] sets the chosen one). A scheme named with a substep count
/// that is not safe is refused: [`Err`] with the reason.
pub fn choose(m: &mut CoupledModel, req: Request) -> Result<Result<Choice, String>, SolveError> {
    let r = choose_for(m, req)?;
    let (overhead, contacts) = (exact_overhead(m), max_contacts(m));
    Ok(r.map(|mut c| {
        (c.exact_overhead, c.max_contacts) = (overhead, contacts);
        c
    }))
}

fn choose_for(m: &mut CoupledModel, req: Request) -> Result<Result<Choice, String>, SolveError> {
    let dt = m.granular.dt;
    let omega_dt = contact_omega(m) * dt;
    let overhead = exact_overhead(m);
    let contacts = max_contacts(m);
    // the compliant scheme's longest body step: the contacts' and the
    // bodies' own periods resolved (`body_dt`: ω_b Δt), the contacts'
    // bound on ω_c h by their dashpots
    let zeta = contact_zeta(m);
    let contact_h = compliant_contact_bound(zeta);
    let within = |bound: f64, w: f64| {
        if w > 0.0 {
            (bound / w).floor()
        } else {
            CANDIDATES[0] as f64
        }
    };
    let by_contacts = within(contact_h, omega_dt);
    let by_body = |body_dt: f64| within(COMPLIANT_MAX_OMEGA_H, body_dt);
    let body_bounds = |body_dt: f64| by_body(body_dt) < by_contacts;
    let compliant_n = |body_dt: f64| {
        let n = by_contacts.min(by_body(body_dt));
        (n.min(CANDIDATES[0] as f64) as usize).max(1)
    };
    let damped = if zeta >= COMPLIANT_DAMPED_ZETA {
        format!("the disc–body contacts damped at ζ = {zeta:.3} ≥ {COMPLIANT_DAMPED_ZETA}")
    } else {
        format!("the disc–body contacts' ζ = {zeta:.3} < {COMPLIANT_DAMPED_ZETA}: undamped")
    };
    let compliant_why = |n: usize, body_dt: f64| {
        if body_bounds(body_dt) {
            format!(
                "{n} is the largest with ω_b h ≤ {COMPLIANT_MAX_OMEGA_H}, ω_b the bodies' collective-mode frequency (ω_b Δt = {body_dt:.3}; the contacts' ω_c Δt = {omega_dt:.3})"
            )
        } else {
            format!(
                "{n} is the largest with ω_c h ≤ {contact_h} (ω_c Δt = {omega_dt:.3}, {damped}; the bodies' ω_b Δt = {body_dt:.3})"
            )
        }
    };
    let mut body_dt = 0.0;
    let mut examined: Vec<(usize, Vec<f64>)> = Vec::new();
    let choice =
        |scheme, substeps, examined: Vec<_>, body_omega_dt, automatic, why: String| Choice {
            scheme,
            substeps,
            omega_dt,
            body_omega_dt,
            gains: examined,
            automatic,
            why,
            warning: None,
            fallback: None,
            exact_overhead: 0.0,
            max_contacts: 0,
        };
    let gain_text = |n: usize, g: &[f64]| {
        format!(
            "collective gain Γ = {:.3} at {n} substeps (ω_c h = {:.2})",
            worst(g),
            omega_dt * n as f64
        )
    };
    let no_bodies = m.bodies.is_empty() || omega_dt == 0.0;
    match (req.scheme, req.substeps) {
        (Some(Scheme::Staggered), n) => Ok(Ok(choice(
            Scheme::Staggered,
            n.unwrap_or(1),
            examined,
            0.0,
            false,
            "named by the scenario (coupling = \"staggered\")".into(),
        ))),
        (Some(Scheme::Exact), None | Some(1)) | (None, Some(1)) => Ok(Ok(choice(
            Scheme::Exact,
            1,
            examined,
            0.0,
            false,
            "named by the scenario".into(),
        ))),
        (Some(Scheme::Exact), Some(n)) => Ok(Err(format!(
            "the exact step takes one DEM step per body step (got substeps = {n}); use substeps = 1 or \"auto\", or another coupling"
        ))),
        (Some(Scheme::Compliant), n) => {
            let (n, why) = match n {
                Some(n) => (n, "named by the scenario".to_string()),
                None => {
                    // the bodies' frequency at the longest body step the
                    // automatic choice would examine
                    let long = (CANDIDATES.into_iter())
                        .find(|&k| omega_dt * k as f64 <= PREDICTED_MAX_OMEGA_H)
                        .unwrap_or(2);
                    let (g, omega) = split(gains(m, long)?);
                    body_dt = omega * dt;
                    examined.push((long, g));
                    let n = compliant_n(body_dt);
                    let why = format!("named by the scenario; {}", compliant_why(n, body_dt));
                    (n, why)
                }
            };
            Ok(Ok(choice(
                Scheme::Compliant,
                n,
                examined,
                body_dt,
                false,
                why,
            )))
        }
        (Some(Scheme::Predicted), Some(n)) | (None, Some(n)) => {
            let (g, omega) = split(gains(m, n)?);
            body_dt = omega * dt;
            let safe = predicted_safe(worst(&g), omega_dt * n as f64) || no_bodies;
            let text = gain_text(n, &g);
            examined.push((n, g));
            if safe {
                let why = format!("{text}: safe ({})", predicted_rule());
                let auto = req.scheme.is_none();
                Ok(Ok(choice(
                    Scheme::Predicted,
                    n,
                    examined,
                    body_dt,
                    auto,
                    why,
                )))
            } else if req.scheme.is_none() {
                let why = format!(
                    "the predicted scheme's {text} is not safe (it needs {}): the boundary gives way to the contacts in every DEM step instead",
                    predicted_rule()
                );
                Ok(Ok(choice(
                    Scheme::Compliant,
                    n,
                    examined,
                    body_dt,
                    true,
                    why,
                )))
            } else {
                // forced: the user's choice, with a warning; the run-time
                // guard stops it if its scheme creates energy
                let mut c = choice(
                    Scheme::Predicted,
                    n,
                    examined,
                    body_dt,
                    false,
                    "named by the scenario".into(),
                );
                c.warning = Some(format!(
                    "the predicted scheme is not safe for this body by the measured map: {text}; it needs {} (its lag can drive the contacts' own oscillation); a run stops once a body's scheme creates more than {} % of the work it exchanges for {} body steps in a row; coupling = \"compliant\" is stable",
                    predicted_rule(),
                    100.0 * super::MAX_CREATED,
                    super::GUARD_STEPS
                ));
                Ok(Ok(c))
            }
        }
        (scheme @ (None | Some(Scheme::Predicted)), None) => {
            if no_bodies {
                let why = "exact: no disc–body contact stiffness to sub-cycle against".into();
                return Ok(Ok(choice(Scheme::Exact, 1, examined, 0.0, true, why)));
            }
            let discs = m.granular.particles.len();
            if scheme.is_none() && (discs < AUTO_MIN_DISCS || overhead <= EXACT_OVERHEAD) {
                let why = if discs < AUTO_MIN_DISCS {
                    format!(
                        "exact: {discs} discs (fewer than {AUTO_MIN_DISCS}: the DEM step costs little, and the exact step resolves each contact's impulse on the body)"
                    )
                } else {
                    format!(
                        "exact: its body solves are estimated at {overhead:.2} × the DEM step of {discs} discs (at most {EXACT_OVERHEAD}: sub-cycling would gain little)"
                    )
                };
                return Ok(Ok(choice(Scheme::Exact, 1, examined, 0.0, true, why)));
            }
            // the predicted scheme at the largest safe n
            let mut predicted = None;
            for n in CANDIDATES {
                if omega_dt * n as f64 > PREDICTED_MAX_OMEGA_H {
                    continue;
                }
                let (g, omega) = split(gains(m, n)?);
                if examined.is_empty() {
                    // the longest body step examined: the most nearly
                    // static response, the bodies' lowest ω_b
                    body_dt = omega * dt;
                }
                let ok = predicted_safe(worst(&g), omega_dt * n as f64);
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
                            "{}: the largest substep count examined that is safe ({})",
                            last.unwrap_or_default(),
                            predicted_rule()
                        );
                        Ok(choice(Scheme::Predicted, n, examined, body_dt, true, why))
                    }
                    None => Err(format!(
                        "no substep count is safe for the predicted scheme ({}; it needs {}); use coupling = \"compliant\" or \"exact\"",
                        last.unwrap_or_default(),
                        predicted_rule()
                    )),
                });
            }
            let nc = compliant_n(body_dt);
            Ok(Ok(match predicted {
                Some(n) if n >= nc.min(PREDICTED_WORTH) || nc < 2 => {
                    let why = format!(
                        "predicted, {n} substeps: {}, safe ({})",
                        last.unwrap_or_default(),
                        predicted_rule()
                    );
                    choice(Scheme::Predicted, n, examined, body_dt, true, why)
                }
                _ if nc >= 2 && contacts <= COMPLIANT_MAX_CONTACTS => {
                    let why = format!(
                        "compliant, {nc} substeps: the predicted scheme is not safe at a useful step ({}); {}",
                        last.unwrap_or_default(),
                        compliant_why(nc, body_dt)
                    );
                    choice(Scheme::Compliant, nc, examined, body_dt, true, why)
                }
                _ if nc < 2 => {
                    let (what, fastest, bound) = if body_bounds(body_dt) {
                        (
                            "the bodies' collective mode",
                            body_dt,
                            COMPLIANT_MAX_OMEGA_H,
                        )
                    } else {
                        ("the contacts' own period", omega_dt, contact_h)
                    };
                    let why = format!(
                        "exact: {what} is resolved by few DEM steps (ω Δt = {fastest:.3}: a body step of 2 would reach ω h = {:.2} > {bound}) and the predicted scheme is not safe ({})",
                        2.0 * fastest,
                        last.unwrap_or_default()
                    );
                    choice(Scheme::Exact, 1, examined, body_dt, true, why)
                }
                _ => {
                    let why = format!(
                        "exact: the predicted scheme is not safe ({}), and the bodies' chains can carry {contacts} contacts at once, more than the compliant scheme's {COMPLIANT_MAX_CONTACTS} (its contact solve grows with their cube)",
                        last.unwrap_or_default()
                    );
                    choice(Scheme::Exact, 1, examined, body_dt, true, why)
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
