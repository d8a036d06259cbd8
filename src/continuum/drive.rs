//! Drives: prescribed edge components that change in time (manual:
//! scenario format, "Servo drives"). A drive moves one displacement component of an
//! edge's points by `ū_c(x_g, tₙ) = ū_c(x_g, 0) + s_g · d(n)`, `s_g` a
//! per-point scale (1 for a rigid translation, `a + b x + c y` for a
//! linear field scaled in time) and `d(n)` the drive's position after n
//! body steps:
//!
//! - a function of the step: constant velocity (`{ velocity, until_step }`,
//!   `d = v · min(n, N) · Δt`), a displacement table (`d = table(tₙ)`),
//!   a velocity table integrated exactly (`d = ∫₀^tₙ v`, piecewise
//!   quadratic);
//! - a law of the state: a servo holding a target force, or phases (a
//!   constant velocity until a step, then a servo): `d(n+1) = d(n) + vₙ Δt`
//!   with `vₙ` decided from the state at `tₙ` ([`Drive::decide`]); its
//!   position, velocity and integral are running state (saved by
//!   checkpoints, [`DriveState`]).
//!
//! The work of a drive on the body is `Σ ½ (Fₙ + Fₙ₊₁)(d(n+1) − d(n))`,
//! `F` the generalised force `Σ_g s_g w_g,c (ū_c − u_c)` of its penalty
//! springs (EFG) or the support reactions (FE): exact for γ = ½, β = ¼
//! whatever the sequence `d(n)` ([`crate::efg::penalty`]).

use super::conditions::MotionField;
pub use super::state::DriveState;
use super::table::Table;
use serde::Deserialize;

/// Which prescribed values: at the body's present step, or at the end of
/// the step under way (after the drives decided it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    /// At the present step.
    Now,
    /// At the next step.
    Next,
}

/// The target resultant of a servo: a number, or a table in time (load
/// to a pressure, then hold).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged, expecting = "a number or a table [[t, F], …]")]
pub enum Target {
    /// A constant target.
    Value(f64),
    /// A target piecewise linear in time.
    Table(Table),
}

impl Target {
    /// The target at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        match self {
            Target::Value(v) => *v,
            Target::Table(tb) => tb.value(t),
        }
    }
}

/// What a servo measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Measure {
    /// The drive's own penalty reaction (EFG) or support reaction (FE):
    /// the force the driven edge exerts on the body along its component
    /// (a body pressed against a support).
    #[default]
    Edge,
    /// The total force of the discs on the body along the component
    /// (`contact_fx` / `contact_fy`: a footing pushed into grains).
    Contacts,
}

/// `servo = { force, gain, max_velocity, integral, measure }`: move the
/// edge so that the measured force on the body along the component
/// reaches `force` (the resultant on the body's thickness, N, like
/// `contact_fy`; not a stress). With `measure = "edge"` the measured
/// force is the edge's own force on the body (a top edge pressing a
/// block down: negative); with `"contacts"` the discs' force on the body
/// (grains pushing a footing up: positive).
///
/// Each body step the drive's velocity is `v = G (F_target − F) + I`
/// (`"edge"`; `v = G (F − F_target) + I` for `"contacts"`, whose force
/// falls as the edge moves along the component),
/// clamped to `±max_velocity`, and when within the limit the integral
/// velocity `I` grows by `β G (F_target − F)` (clamped too): the DEM servo
/// walls' PI law ([`crate::dem::walls::Servo::speed_integral`]) with the
/// sign of a force on the body. Against a stiffness K held still (`a = G
/// K Δt`) the error obeys `e_{n+1} = (1 − a) eₙ` (β = 0) or
/// `e_{n+1} = (2 − a) eₙ − (1 − a + βa) e_{n−1}`: choose `a` ≲ 0.5, β < 1.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ServoSpec {
    /// Target force on the body along the component (N); required.
    pub force: Option<Target>,
    /// Gain G (m/s per N); required.
    pub gain: Option<f64>,
    /// Largest speed of the edge (m/s); required.
    pub max_velocity: Option<f64>,
    /// Integral action β in [0, 1) (0: proportional servo).
    #[serde(default)]
    pub integral: f64,
    /// What is measured: `"edge"` (default) or `"contacts"`.
    #[serde(default)]
    pub measure: Measure,
}

impl ServoSpec {
    /// `(velocity, next integral)` for the measured force `f` against the
    /// target `target`, from the integral `i` (see the type's docs).
    pub fn velocity(&self, f: f64, target: f64, i: f64) -> (f64, f64) {
        let g = self.gain.unwrap_or(0.0);
        let vmax = self.max_velocity.unwrap_or(0.0);
        let p = g * (target - f);
        let v = p + i;
        if v.is_nan() {
            (0.0, i)
        } else if v.abs() < vmax {
            let i1 = if self.integral == 0.0 {
                i
            } else {
                (i + self.integral * p).clamp(-vmax, vmax)
            };
            (v, i1)
        } else {
            (v.clamp(-vmax, vmax), i)
        }
    }
}

/// One phase of a `phases` drive: `velocity` or `servo` (or neither: at
/// rest) until `until_step` (0-based body step at which the next phase
/// begins; `None`: to the end).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DrivePhase {
    /// The step at which the next phase begins; required on all but the
    /// last phase.
    pub until_step: Option<usize>,
    /// A constant velocity (m/s).
    pub velocity: Option<f64>,
    /// A servo.
    pub servo: Option<ServoSpec>,
}

/// How a drive's position follows time or the state.
#[derive(Debug, Clone, PartialEq)]
pub enum DriveLaw {
    /// `d = v · min(n, N) · Δt`.
    Velocity(MotionField),
    /// `d = table(tₙ)`.
    Table(Table),
    /// `d = ∫₀^tₙ table`.
    VelocityTable(Table),
    /// A servo ([`ServoSpec`]).
    Servo(ServoSpec),
    /// Phases ([`DrivePhase`]).
    Phases(Vec<DrivePhase>),
}

impl DriveLaw {
    /// The position after `step` steps of `dt` for a law of time, `None`
    /// for a law of the state.
    pub fn position(&self, step: usize, dt: f64) -> Option<f64> {
        let t = step as f64 * dt;
        match self {
            DriveLaw::Velocity(m) => Some(m.displacement(step, dt)),
            DriveLaw::Table(tb) => Some(tb.value(t)),
            DriveLaw::VelocityTable(tb) => Some(tb.integral(t)),
            DriveLaw::Servo(_) | DriveLaw::Phases(_) => None,
        }
    }

    /// The servo the drive follows at some time, if any.
    pub fn servo(&self) -> Option<&ServoSpec> {
        match self {
            DriveLaw::Servo(s) => Some(s),
            DriveLaw::Phases(ps) => ps.iter().find_map(|p| p.servo.as_ref()),
            _ => None,
        }
    }
}

/// A drive: its law and running state.
#[derive(Debug, Clone, PartialEq)]
pub struct Drive {
    /// The law.
    pub law: DriveLaw,
    /// The running state.
    pub state: DriveState,
}

impl Drive {
    /// A drive at t = 0: a law of time at its position at t = 0 (0 except
    /// for a displacement table that starts elsewhere), a servo at 0.
    pub fn new(law: DriveLaw) -> Self {
        let d = law.position(0, 1.0).unwrap_or(0.0);
        Drive {
            law,
            state: DriveState {
                d,
                d_next: d,
                ..Default::default()
            },
        }
    }

    /// What the drive's servo measures, if it has one.
    pub fn measure(&self) -> Option<Measure> {
        self.law.servo().map(|s| s.measure)
    }

    /// Place a law of time at `step` (positions at `step` and `step + 1`);
    /// a law of the state keeps its state.
    pub fn set_step(&mut self, step: usize, dt: f64) {
        if let (Some(d), Some(d1)) = (self.law.position(step, dt), self.law.position(step + 1, dt))
        {
            self.state.d = d;
            self.state.d_next = d1;
        }
    }

    /// Decide the position at `step + 1` from the state at `step` (time
    /// `step · dt`), `measured` the force the servo measures (or the
    /// edge's reaction).
    pub fn decide(&mut self, step: usize, dt: f64, measured: f64) {
        let s = &mut self.state;
        // the servo acts on the mean of the last two measurements: it
        // cannot feed the step-to-step (Nyquist) ringing of the stiff
        // penalty springs and of Newmark's prescribed-edge velocities
        // (2v, 0, 2v, … after a change of speed), which γ = ½ never damps
        let previous = if step == 0 { measured } else { s.measured };
        let mean = 0.5 * (measured + previous);
        s.measured = measured;
        if let Some(d1) = self.law.position(step + 1, dt) {
            s.d_next = d1;
            s.velocity = (d1 - s.d) / dt;
            return;
        }
        let t1 = (step + 1) as f64 * dt;
        let servo_velocity = |sv: &ServoSpec, s: &mut DriveState| {
            let target = sv.force.as_ref().map_or(0.0, |f| f.at(t1));
            // the edge's own force on the body grows along the component as
            // the edge moves along it; the discs' force on the body falls
            // (they push back): the law acts on minus the latter
            let (v, i) = match sv.measure {
                Measure::Edge => sv.velocity(mean, target, s.integral),
                Measure::Contacts => sv.velocity(-mean, -target, s.integral),
            };
            s.integral = i;
            v
        };
        let v = match &self.law {
            DriveLaw::Servo(sv) => servo_velocity(sv, s),
            DriveLaw::Phases(ps) => match ps.iter().find(|p| p.until_step.is_none_or(|n| step < n))
            {
                Some(DrivePhase {
                    servo: Some(sv), ..
                }) => servo_velocity(sv, s),
                Some(DrivePhase {
                    velocity: Some(v), ..
                }) => *v,
                _ => 0.0,
            },
            _ => 0.0,
        };
        s.velocity = v;
        s.d_next = s.d + v * dt;
    }

    /// Accept the decided step: `d(n) ← d(n+1)`.
    pub fn advance(&mut self) {
        self.state.d = self.state.d_next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn servo(force: f64, gain: f64, beta: f64) -> ServoSpec {
        ServoSpec {
            force: Some(Target::Value(force)),
            gain: Some(gain),
            max_velocity: Some(1.0),
            integral: beta,
            measure: Measure::Edge,
        }
    }

    #[test]
    fn a_servo_against_a_spring_reaches_its_target() {
        // the edge pushes a spring of stiffness K: F = K d (force on the
        // body along +y when the edge moves up); target −100 N
        let (k, dt) = (1.0e4, 1.0e-3);
        for beta in [0.0, 0.3] {
            let mut d = Drive::new(DriveLaw::Servo(servo(-100.0, 0.5 / (k * dt), beta)));
            for n in 0..200 {
                let f = k * d.state.d;
                d.decide(n, dt, f);
                d.advance();
            }
            assert!(
                (k * d.state.d + 100.0).abs() < 1e-9,
                "{beta}: {}",
                k * d.state.d
            );
        }
        // the velocity is clamped
        let mut d = Drive::new(DriveLaw::Servo(servo(-1e9, 1.0, 0.0)));
        d.decide(0, dt, 0.0);
        assert_eq!(d.state.velocity, -1.0);
    }

    #[test]
    fn phases_push_then_hold() {
        let law = DriveLaw::Phases(vec![
            DrivePhase {
                until_step: Some(10),
                velocity: Some(-0.5),
                servo: None,
            },
            DrivePhase {
                until_step: None,
                velocity: None,
                servo: Some(servo(-100.0, 0.5e-1, 0.0)),
            },
        ]);
        let mut d = Drive::new(law);
        let dt = 1e-2;
        for n in 0..10 {
            d.decide(n, dt, 0.0);
            d.advance();
        }
        assert!((d.state.d + 0.05).abs() < 1e-15);
        // then the servo: a spring of stiffness 1000 N/m below the start
        for n in 10..400 {
            let f = -1000.0 * d.state.d;
            d.decide(n, dt, -f);
            d.advance();
        }
        assert!((1000.0 * d.state.d + 100.0).abs() < 1e-6);
    }

    #[test]
    fn laws_of_time_are_functions_of_the_step() {
        let tb = Table::new(vec![[0.0, -0.1], [0.2, 0.0]]);
        let mut d = Drive::new(DriveLaw::VelocityTable(tb.clone()));
        let dt = 0.01;
        for n in 0..30 {
            d.decide(n, dt, 0.0);
            d.advance();
        }
        assert_eq!(d.state.d, tb.integral(30.0 * dt));
    }
}
