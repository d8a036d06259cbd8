//! The per-step stability check: a run whose state is no longer physical
//! (non-finite numbers, discs jumping more than their radius in one step)
//! stops with a diagnosis instead of writing NaN or running on.

use super::{Model, System};
use crate::dem::{DT_SAFETY, Granular};
use crate::model::body::BodyRef;

/// Why the state of a model stopped being physical, and what to do.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Instability {
    /// Steps taken when it was detected.
    pub step: usize,
    /// Time then.
    pub time: f64,
    /// What went wrong: `disc 12` (1-based scenario id) or `body `beam``.
    pub culprit: String,
    /// The symptom, e.g. `speed 2.1e3 (0.4 m per step = 9.8 radii)` or
    /// `non-finite displacement`.
    pub symptom: String,
    /// The time step in use.
    pub dt: f64,
    /// A time step that should be stable: the default fraction of the
    /// critical step ([`Granular::critical_step`]) when discs are
    /// involved (at most half the present), else half the present.
    pub suggested_dt: f64,
}

impl std::fmt::Display for Instability {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the run became unstable at step {} (t = {:e}): {}: {}; try dt = {:.3e} (now {:e})",
            self.step, self.time, self.culprit, self.symptom, self.suggested_dt, self.dt
        )
    }
}

/// Largest distance a disc may travel in one step, in radii: beyond it the
/// contact detection skips whole discs and nothing computed is physical.
pub const MAX_RADII_PER_STEP: f64 = 1.0;

/// Check the present state of `model` (one pass over the discs' velocities
/// and, after a body step, the bodies' Newmark vectors: cheap next to a
/// step).
pub fn check(model: &Model) -> Result<(), Instability> {
    let culprit = match &model.system {
        System::Continuum { bodies, .. } => bodies.iter().find_map(|b| body_culprit(b.view())),
        System::Granular(g) => disc_culprit(g),
        System::Coupled(m) => disc_culprit(&m.granular).or_else(|| {
            let bodies = if m.at_body_step() && m.is_settled() {
                m.bodies.len()
            } else {
                0
            };
            (0..bodies).find_map(|i| body_culprit(super::coupled_body(m, i)))
        }),
    };
    let Some((culprit, symptom)) = culprit else {
        return Ok(());
    };
    let dt = model.dt;
    let suggested_dt = match model.granular() {
        Some(g) => {
            let bodies = model.coupled().map_or(&[][..], |m| &m.body_laws[..]);
            (DT_SAFETY * g.critical_step(bodies).dt).min(0.5 * dt)
        }
        None => 0.5 * dt,
    };
    Err(Instability {
        step: model.step,
        time: model.time(),
        culprit,
        symptom,
        dt,
        suggested_dt,
    })
}

/// The worst disc with a non-finite state or moving more than
/// [`MAX_RADII_PER_STEP`] radii per step (non-finite first, then the most
/// radii per step; ties to the lowest slot), and its symptom.
fn disc_culprit(g: &Granular) -> Option<(String, String)> {
    // the step that made this state checked every disc as below
    if g.step_check(MAX_RADII_PER_STEP) == Some(true) {
        return None;
    }
    let p = &g.particles;
    let dt = g.dt;
    // the common case in one pass without square roots (NaN fails every
    // comparison); the diagnosis only on failure
    let max_step = MAX_RADII_PER_STEP * MAX_RADII_PER_STEP / (dt * dt);
    let bad = |k: usize| {
        let (x, v, r) = (p.pos[k], p.vel[k], p.radius[k]);
        !(v.dot(v) <= max_step * r * r && (x.x + x.y + p.omega[k]).is_finite())
    };
    let first = (0..p.len()).find(|&k| bad(k))?;
    // report the worst: a non-finite disc, else the most radii per step
    let k = (first..p.len())
        .filter(|&k| bad(k))
        .max_by(|&a, &b| {
            let key = |k: usize| {
                let s = p.vel[k].dot(p.vel[k]) / (p.radius[k] * p.radius[k]);
                if s.is_finite() && (p.pos[k].x + p.pos[k].y).is_finite() {
                    s
                } else {
                    f64::INFINITY
                }
            };
            key(a).total_cmp(&key(b)).then(b.cmp(&a))
        })
        .unwrap_or(first);
    let (x, v, r) = (p.pos[k], p.vel[k], p.radius[k]);
    let symptom = if !(x.x.is_finite() && x.y.is_finite()) {
        format!("non-finite position ({:e}, {:e})", x.x, x.y)
    } else if !(v.x.is_finite() && v.y.is_finite() && p.omega[k].is_finite()) {
        format!(
            "non-finite velocity ({:e}, {:e}), spin {:e}",
            v.x, v.y, p.omega[k]
        )
    } else {
        let s = v.norm() * dt;
        format!(
            "speed {:.3e}, i.e. {:.3e} per step = {:.3e} radii (more than {MAX_RADII_PER_STEP}: contacts are skipped)",
            v.norm(),
            s,
            s / r
        )
    };
    Some((format!("disc {}", p.id[k] + 1), symptom))
}

/// A body whose displacement, velocity or acceleration is not finite.
fn body_culprit(b: BodyRef) -> Option<(String, String)> {
    let s = b.state();
    let bad = |x: &[f64]| x.iter().position(|v| !v.is_finite());
    let (what, i) = [
        ("displacement", &s.u),
        ("velocity", &s.v),
        ("acceleration", &s.a),
    ]
    .into_iter()
    .find_map(|(w, x)| bad(x).map(|i| (w, i)))?;
    Some((
        format!("body `{}`", b.name()),
        format!(
            "non-finite {what} at node {} ({} component)",
            i / 2 + 1,
            ["x", "y"][i % 2]
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec2;

    /// Discs of radius 0.01 and 0.02 (scenario ids 1, 2), k_n = 1e6,
    /// density 1000, dt = 1e-5.
    fn two_discs() -> Model {
        let mut p = crate::dem::particles::Particles::default();
        p.push(Vec2::new(0.0, 0.0), 0.01, 1000.0, 1.0, 0);
        p.push(Vec2::new(1.0, 0.0), 0.02, 1000.0, 1.0, 0);
        let law = crate::dem::contact::ContactLaw {
            kn: 1e6,
            ks: 1e6,
            ..Default::default()
        };
        let mut g = Granular::new(p, vec![law], Vec::new(), 1e-5);
        g.dt = 1e-5;
        Model {
            system: System::Granular(Box::new(g)),
            dt: 1e-5,
            steps: 10,
            step: 0,
        }
    }

    #[test]
    fn a_disc_faster_than_a_radius_per_step_is_caught_with_its_id() {
        let mut m = two_discs();
        assert_eq!(check(&m), Ok(()));
        let System::Granular(g) = &mut m.system else {
            unreachable!()
        };
        let k = g.slot(1);
        // 0.02 m radius, dt 1e-5: 2000 m/s is exactly one radius per step
        g.particles.vel[k] = Vec2::new(1999.0, 0.0);
        assert_eq!(check(&m), Ok(()));
        let System::Granular(g) = &mut m.system else {
            unreachable!()
        };
        g.particles.vel[k] = Vec2::new(0.0, -2100.0);
        let e = check(&m).unwrap_err();
        assert_eq!(e.culprit, "disc 2");
        assert!(e.symptom.contains("= 1.050e0 radii"), "{}", e.symptom);
        // critical step 2√(m/k) of the lighter disc, times 0.2
        let crit = 2.0 * (1000.0 * std::f64::consts::PI * 1e-4 / 1e6f64).sqrt();
        assert!((e.suggested_dt - (0.2 * crit).min(0.5e-5)).abs() < 1e-12 * crit);
        // two too fast: the one with more radii per step is reported
        let System::Granular(g) = &mut m.system else {
            unreachable!()
        };
        let k0 = g.slot(0);
        g.particles.vel[k0] = Vec2::new(1500.0, 0.0); // 1.5 radii
        let e = check(&m).unwrap_err();
        assert_eq!(e.culprit, "disc 1");
        assert!(e.symptom.contains("= 1.500e0 radii"), "{}", e.symptom);
    }

    #[test]
    fn a_non_finite_disc_is_caught() {
        let mut m = two_discs();
        let System::Granular(g) = &mut m.system else {
            unreachable!()
        };
        let k = g.slot(0);
        g.particles.pos[k].y = f64::NAN;
        let e = check(&m).unwrap_err();
        assert_eq!(e.culprit, "disc 1");
        assert!(
            e.symptom.starts_with("non-finite position"),
            "{}",
            e.symptom
        );
    }
}
