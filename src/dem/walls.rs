//! Rigid walls: line segments that translate (the plates of Cundall &
//! Strack's nine-disc test, the platens of a biaxial test), recording the
//! total force the discs exert on each wall at every step.
//!
//! A wall's velocity is prescribed ([`WallMotion::Fixed`],
//! [`Constant`](WallMotion::Constant), [`Piecewise`](WallMotion::Piecewise)),
//! or follows from the state: a servo holding a normal stress
//! ([`WallMotion::Servo`]) or a true strain rate of the distance to the
//! opposite wall ([`WallMotion::StrainRate`]); both move the wall along its
//! inward normal. An end of a wall that lies on a servo or strain-rate
//! wall is *joined* to it ([`Wall::joins`]): after every move it is put
//! back on that wall's line, so the wall stretches or shrinks with the box
//! and no gap opens at the corner.
//!
//! A wall may change its motion during a run: [`WallMotion::Phases`] runs
//! one motion after another, each until a step number (e.g. a servo for
//! the isotropic consolidation of a biaxial test, then a strain rate for
//! its shearing). The motion is a function of the step, so a checkpoint
//! needs nothing more than the walls' positions.

use crate::geom::{Vec2, closest_on_segment};

/// Servo control of a wall's normal stress: the standard PFC / Yade
/// loop (Itasca, *PFC manual*, "servo-control" of walls; Yade's
/// `TriaxialStressController`).
///
/// The wall moves along its outward normal at
/// `v = G (F_measured − F_target)`, clamped to `±max_velocity`: too much
/// force moves it out, too little moves it in. `F_measured` is the force of
/// the discs on the wall along its outward normal in the last step and
/// `F_target = σ L t`, with L the wall's present length and t the disc
/// thickness ([`Granular::thickness`](super::Granular::thickness)).
///
/// The automatic gain is PFC's `G = α A/(k_n N_c Δt)` written for a force,
/// `G = α/(K Δt)` with `K = Σ k_n` over the discs touching the wall (= k_n
/// N_c for one material; Yade's `stiffness` of the wall; the wall's largest
/// k_n when no disc touches it, i.e. N_c ≥ 1): in one step the wall moves
/// `Δx = α (F − F_target)/K`, which, with the discs held, removes the
/// fraction α of the force error — α < 1 does not overshoot within a step.
///
/// With contact dashpots the measured force also jumps by `C Δv` when the
/// wall's speed changes (`C = Σ c_n` over the same contacts), and PFC's
/// gain then oscillates from step to step (a box of discs with ζ = 0.2
/// does). Here the dashpots enter the gain:
/// `G = α/(K Δt + 2C)`, PFC's gain when C = 0. For one contact against
/// discs held in place the force error obeys
/// `e_{n+1} = (1 − a − b) e_n + b e_{n−1}` with `a = G K Δt`, `b = G C`,
/// which is stable for `a + 2b < 2`; this gain gives `a + 2b = α`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Servo {
    /// Target normal stress σ (compression positive).
    pub stress: f64,
    /// Gain G (velocity per force); `None`: automatic, `α/(K Δt)`.
    pub gain: Option<f64>,
    /// Relaxation factor α of the automatic gain (PFC's 0.5).
    pub relaxation: f64,
    /// Largest speed of the wall.
    pub max_velocity: f64,
    /// Integral action β (0: none, the plain proportional servo): each
    /// step that the wall is not at `max_velocity`, β × the proportional
    /// velocity `G (F − F_target)` is added to an integral velocity
    /// ([`Wall::integral`]) that the wall keeps and adds to its speed.
    /// It removes the steady lag `F − F_target = v/G` of a wall that must
    /// keep moving (a dilating sample's side walls). Against held discs
    /// (no dashpots, `a = G K Δt`) the force error follows
    /// `e_{n+1} = (2 − a) e_n − (1 − a + βa) e_{n−1}`: it settles for
    /// β < 1.
    pub integral: f64,
}

impl Servo {
    /// Outward speed `G (F_measured − F_target)` clamped to
    /// `±max_velocity`, with the automatic gain `α/(K Δt + 2C)` unless a
    /// gain is given (`stiffness` = K, `damping` = C; K = C = 0 gives the
    /// full speed towards the target).
    pub fn speed(&self, measured: f64, target: f64, stiffness: f64, damping: f64, dt: f64) -> f64 {
        let g = self
            .gain
            .unwrap_or(self.relaxation / (stiffness * dt + 2.0 * damping));
        let v = g * (measured - target);
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-self.max_velocity, self.max_velocity)
        }
    }

    /// [`speed`](Self::speed) with the integral action: the outward speed
    /// `G (F − F_target) + I` clamped to `±max_velocity`, and the integral
    /// velocity I of the next step, `I + β G (F − F_target)` (clamped to
    /// `±max_velocity`) when the speed is within the limit, else I
    /// unchanged (no wind-up while the wall runs at its largest speed,
    /// e.g. towards a sample it does not touch yet). With β = 0 it is
    /// `(speed, I)`, bitwise.
    pub fn speed_integral(
        &self,
        measured: f64,
        target: f64,
        stiffness: f64,
        damping: f64,
        dt: f64,
        integral: f64,
    ) -> (f64, f64) {
        if self.integral == 0.0 {
            return (
                self.speed(measured, target, stiffness, damping, dt),
                integral,
            );
        }
        let g = self
            .gain
            .unwrap_or(self.relaxation / (stiffness * dt + 2.0 * damping));
        let p = g * (measured - target);
        let v = p + integral;
        if v.is_nan() {
            (0.0, integral)
        } else if v.abs() < self.max_velocity {
            let i = (integral + self.integral * p).clamp(-self.max_velocity, self.max_velocity);
            (v, i)
        } else {
            (v.clamp(-self.max_velocity, self.max_velocity), integral)
        }
    }
}

/// How a wall moves. Walls translate; they do not rotate.
#[derive(Debug, Clone, PartialEq)]
pub enum WallMotion {
    /// At rest.
    Fixed,
    /// Constant velocity during the first `until_step` steps (all steps if
    /// `None`), then at rest.
    Constant {
        /// Velocity of the wall.
        velocity: Vec2,
        /// Number of steps after which the wall stops; `None`: never.
        until_step: Option<usize>,
    },
    /// Velocity piecewise linear in time through `(t, v)` points sorted by
    /// t, constant beyond the first and last.
    Piecewise(Vec<(f64, Vec2)>),
    /// Servo-controlled normal stress ([`Servo`]).
    Servo(Servo),
    /// A true strain rate of the box: the wall moves along its inward
    /// normal at `share · ε̇ · D`, D the present distance to the parallel
    /// wall `opposite` (which its inward normal points to). Alone
    /// (`share` = 1) it makes `Ḋ = −ε̇ D`, i.e. `D(t) = D₀ e^{−ε̇t}` (ε̇ > 0
    /// compresses); two facing strain-rate walls take `share` = ½ each.
    /// Discretely `D_{n+1} = D_n (1 − ε̇ Δt)`.
    StrainRate {
        /// ε̇ (1/s), compression positive.
        rate: f64,
        /// Index of the opposite wall.
        opposite: usize,
        /// Fraction of the rate this wall makes (1, or ½ when the opposite
        /// wall is a strain-rate wall too).
        share: f64,
    },
    /// One motion after another: phase k moves the wall during the steps
    /// (0-based, counted from the start of the run) from the previous
    /// phase's `until_step` (0 for the first) up to its own `until_step`
    /// (excluded); after the last phase's `until_step` the wall is at
    /// rest. A phase's motion is not itself phased.
    Phases(Vec<WallPhase>),
}

/// One phase of a [`WallMotion::Phases`] wall.
#[derive(Debug, Clone, PartialEq)]
pub struct WallPhase {
    /// The phase moves the wall during the steps before this one (0-based
    /// step index, from the start of the run); `None`: to the end of the
    /// run.
    pub until_step: Option<usize>,
    /// The motion during the phase (a [`Piecewise`](WallMotion::Piecewise)
    /// history keeps the run's time, not the phase's).
    pub motion: WallMotion,
}

/// The motion of a wall whose phases are over.
static AT_REST: WallMotion = WallMotion::Fixed;

impl WallMotion {
    /// Velocity during step `step` (0-based), which runs from `t` to `t + dt`,
    /// of a prescribed motion (zero for a servo or strain-rate wall, whose
    /// velocity follows from the state: [`Granular`](super::Granular)
    /// computes it). The piecewise history is sampled at the middle of the
    /// step, which makes the displacement exact for a linear history
    /// (central difference).
    pub fn velocity(&self, step: usize, t: f64, dt: f64) -> Vec2 {
        match self {
            WallMotion::Phases(_) => self.at(step).velocity(step, t, dt),
            WallMotion::Fixed | WallMotion::Servo(_) | WallMotion::StrainRate { .. } => Vec2::ZERO,
            WallMotion::Constant {
                velocity,
                until_step,
            } => match until_step {
                Some(n) if step >= *n => Vec2::ZERO,
                _ => *velocity,
            },
            WallMotion::Piecewise(pts) => {
                let tm = t + 0.5 * dt;
                match pts.iter().position(|p| p.0 > tm) {
                    None => pts.last().map(|p| p.1).unwrap_or(Vec2::ZERO),
                    Some(0) => pts[0].1,
                    Some(k) => {
                        let (t0, v0) = pts[k - 1];
                        let (t1, v1) = pts[k];
                        let s = if t1 > t0 { (tm - t0) / (t1 - t0) } else { 1.0 };
                        v0 + (v1 - v0) * s
                    }
                }
            }
        }
    }

    /// The motion during step `step` (0-based): the phase that holds then
    /// ([`WallMotion::Phases`]; at rest after the last), or `self`.
    pub fn at(&self, step: usize) -> &WallMotion {
        match self {
            WallMotion::Phases(phases) => phases
                .iter()
                .find(|p| p.until_step.is_none_or(|n| step < n))
                .map_or(&AT_REST, |p| p.motion.at(step)),
            m => m,
        }
    }

    /// Does the wall move along its normal by a law of the state (servo or
    /// strain rate), in some phase? The ends of other walls lying on it
    /// are joined to it.
    pub fn follows_state(&self) -> bool {
        match self {
            WallMotion::Servo(_) | WallMotion::StrainRate { .. } => true,
            WallMotion::Phases(phases) => phases.iter().any(|p| p.motion.follows_state()),
            _ => false,
        }
    }
}

/// A rigid wall segment from `a` to `b`, two-sided.
#[derive(Debug, Clone)]
pub struct Wall {
    /// Name (scenario `[[wall]]` name, used in outputs).
    pub name: String,
    /// First end, current position.
    pub a: Vec2,
    /// Second end, current position.
    pub b: Vec2,
    /// How the wall moves.
    pub motion: WallMotion,
    /// Velocity during the current step (set by the integrator).
    pub vel: Vec2,
    /// Total force exerted by the discs on the wall in the last step.
    pub force: Vec2,
    /// Index of the wall's own material in the assembly's material table;
    /// `None` = use the disc's material.
    pub material: Option<u16>,
    /// Unit direction from `a` to `b` at the start (walls do not rotate).
    pub dir: Vec2,
    /// Unit normal towards the discs (the scenario: towards their centroid,
    /// or the opposite wall of a strain-rate wall; [`Wall::new`]: the left
    /// normal `perp(dir)`). Servo and strain-rate walls move along it;
    /// [`normal_stress`](Self::normal_stress) is the force along `−inward`.
    pub inward: Vec2,
    /// The wall whose line end `a` (`joins[0]`) and end `b` (`joins[1]`)
    /// follow, if any: after each move the end is put on that wall's line.
    pub joins: [Option<u32>; 2],
    /// Discs touching the wall in the last step (per-step scratch; servo
    /// and strain-rate walls only).
    pub contacts: u32,
    /// `Σ k_n` of those contacts (per-step scratch; the servo's K).
    pub stiffness: f64,
    /// `Σ c_n` of their normal dashpots (per-step scratch; the servo's C).
    pub damping: f64,
    /// The integral velocity of a servo with integral action
    /// ([`Servo::integral`]), outward positive; 0 otherwise (evolving
    /// state: saved in checkpoints).
    pub integral: f64,
}

impl Wall {
    /// A wall from `a` to `b` with `motion`, at rest, with the discs'
    /// material, inward normal `perp(b − a)` and no joined ends.
    pub fn new(name: &str, a: Vec2, b: Vec2, motion: WallMotion) -> Self {
        let d = b - a;
        let l = d.norm();
        let dir = if l > 0.0 {
            d * (1.0 / l)
        } else {
            Vec2::new(1.0, 0.0)
        };
        Wall {
            name: name.to_string(),
            a,
            b,
            motion,
            vel: Vec2::ZERO,
            force: Vec2::ZERO,
            material: None,
            dir,
            inward: dir.perp(),
            joins: [None, None],
            contacts: 0,
            stiffness: 0.0,
            damping: 0.0,
            integral: 0.0,
        }
    }

    /// Closest point of the wall to `p`.
    #[inline]
    pub fn closest(&self, p: Vec2) -> Vec2 {
        closest_on_segment(p, self.a, self.b).1
    }

    /// Translate by `d`.
    pub fn translate(&mut self, d: Vec2) {
        self.a += d;
        self.b += d;
    }

    /// Present length `|b − a|`.
    pub fn length(&self) -> f64 {
        (self.b - self.a).norm()
    }

    /// Normal force of the discs on the wall, along its outward normal
    /// `−inward` (compression positive).
    pub fn normal_force(&self) -> f64 {
        -self.force.dot(self.inward)
    }

    /// Normal stress on the wall, `normal_force / (L t)` (L its present
    /// length, t the disc thickness), compression positive.
    pub fn normal_stress(&self, thickness: f64) -> f64 {
        self.normal_force() / (self.length() * thickness)
    }

    /// Is one of its ends joined to another wall?
    pub fn is_joined(&self) -> bool {
        self.joins[0].is_some() || self.joins[1].is_some()
    }

    /// Where the line of this wall (through `a`, along `dir`) meets the
    /// line of `other` (through `other.a`, normal `perp(other.dir)`); `None`
    /// when they are parallel.
    pub fn meet(&self, other: &Wall) -> Option<Vec2> {
        let n = other.dir.perp();
        let den = self.dir.dot(n);
        if den == 0.0 {
            return None;
        }
        Some(self.a + self.dir * ((other.a - self.a).dot(n) / den))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn servo_speed_sign_gain_and_clamp() {
        let s = Servo {
            stress: 1.0,
            gain: None,
            relaxation: 0.5,
            max_velocity: 10.0,
            integral: 0.0,
        };
        // too much force: outward, α (F − F_t)/(K Δt)
        assert_eq!(
            s.speed(3.0, 1.0, 100.0, 0.0, 0.01),
            0.5 * 2.0 / (100.0 * 0.01)
        );
        // too little: inward
        assert_eq!(s.speed(0.0, 1.0, 100.0, 0.0, 0.01), -0.5);
        // dashpots: α (F − F_t)/(K Δt + 2C)
        assert_eq!(s.speed(3.0, 1.0, 100.0, 1.5, 0.01), 0.5 * 2.0 / 4.0);
        // clamped
        assert_eq!(s.speed(1e9, 1.0, 100.0, 0.0, 0.01), 10.0);
        assert_eq!(s.speed(0.0, 1.0, 0.0, 0.0, 0.01), -10.0);
        assert_eq!(s.speed(1.0, 1.0, 0.0, 0.0, 0.01), 0.0);
        let g = Servo {
            gain: Some(2.0),
            ..s
        };
        assert_eq!(g.speed(1.5, 1.0, 100.0, 7.0, 0.01), 1.0);
    }

    #[test]
    fn servo_integral_action() {
        let p = Servo {
            stress: 1.0,
            gain: Some(0.5),
            relaxation: 0.5,
            max_velocity: 10.0,
            integral: 0.0,
        };
        // β = 0: the proportional speed, the integral left as it is
        assert_eq!(
            p.speed_integral(3.0, 1.0, 7.0, 1.0, 0.1, 0.25),
            (p.speed(3.0, 1.0, 7.0, 1.0, 0.1), 0.25)
        );
        let pi = Servo { integral: 0.1, ..p };
        // G e + I, and I grows by β G e
        assert_eq!(
            pi.speed_integral(3.0, 1.0, 7.0, 1.0, 0.1, 0.25),
            (1.25, 0.35)
        );
        // at the largest speed: clamped, no wind-up
        assert_eq!(
            pi.speed_integral(100.0, 1.0, 7.0, 1.0, 0.1, 0.25),
            (10.0, 0.25)
        );
        assert_eq!(
            pi.speed_integral(-100.0, 1.0, 7.0, 1.0, 0.1, 0.25),
            (-10.0, 0.25)
        );
        // a steady error builds the integral until it carries the speed
        let (mut i, mut v) = (0.0, 0.0);
        for _ in 0..200 {
            (v, i) = pi.speed_integral(1.0 + 1e-3, 1.0, 7.0, 1.0, 0.1, i);
        }
        assert!((i - 200.0 * 0.1 * 0.5e-3).abs() < 1e-12 && v > i);
    }

    /// The servo against held discs (its contacts a spring K and a
    /// dashpot C on the wall's speed) settles on its target
    /// with the automatic gain, with and without integral action, for
    /// `2C/(K Δt)` up to 50, α ≤ 1 and β up to 0.99 (docs/scenario.md,
    /// "Integral action"): the force error falls below 1e-6 of its start.
    #[test]
    fn servo_settles_against_springs_and_dashpots() {
        let (k, dt, target) = (1.0e6, 1.0e-5, 1.0);
        for alpha in [0.1, 0.5, 1.0] {
            for beta in [0.0, 0.1, 0.5, 0.99] {
                for ratio in [0.0, 1.0, 10.0, 50.0] {
                    let c = 0.5 * ratio * k * dt;
                    let s = Servo {
                        stress: 1.0,
                        gain: None,
                        relaxation: alpha,
                        max_velocity: f64::MAX,
                        integral: beta,
                    };
                    // overlap, the wall's outward speed, the integral
                    let (mut d, mut u, mut i, mut e) = (0.0, 0.0, 0.0, 0.0);
                    for _ in 0..40_000 {
                        d -= u * dt;
                        let f = k * d - c * u;
                        e = f - target;
                        (u, i) = s.speed_integral(f, target, k, c, dt, i);
                    }
                    assert!(
                        e.abs() < 1e-6 * target,
                        "α {alpha}, β {beta}, 2C/(KΔt) {ratio}: {e}"
                    );
                }
            }
        }
    }

    #[test]
    fn phases_follow_the_step() {
        let servo = WallMotion::Servo(Servo {
            stress: 1.0,
            gain: None,
            relaxation: 0.5,
            max_velocity: 1.0,
            integral: 0.0,
        });
        let v = Vec2::new(0.0, -2.0);
        let m = WallMotion::Phases(vec![
            WallPhase {
                until_step: Some(3),
                motion: servo.clone(),
            },
            WallPhase {
                until_step: Some(5),
                motion: WallMotion::Constant {
                    velocity: v,
                    until_step: None,
                },
            },
        ]);
        assert!(m.follows_state());
        assert_eq!(m.at(0), &servo);
        assert_eq!(m.at(2), &servo);
        assert_eq!(m.velocity(2, 0.0, 0.1), Vec2::ZERO);
        assert_eq!(m.velocity(3, 0.0, 0.1), v);
        assert_eq!(m.velocity(4, 0.0, 0.1), v);
        assert_eq!(m.at(5), &WallMotion::Fixed);
        assert_eq!(m.velocity(5, 0.0, 0.1), Vec2::ZERO);
        let rest_then_move = WallMotion::Phases(vec![
            WallPhase {
                until_step: Some(1),
                motion: WallMotion::Fixed,
            },
            WallPhase {
                until_step: None,
                motion: WallMotion::Piecewise(vec![(0.0, v), (1.0, v * 2.0)]),
            },
        ]);
        assert!(!rest_then_move.follows_state());
        assert_eq!(rest_then_move.velocity(0, 0.0, 0.1), Vec2::ZERO);
        // the history keeps the run's time
        assert_eq!(rest_then_move.velocity(1000, 0.45, 0.1), v * 1.5);
    }

    #[test]
    fn lines_meet() {
        let floor = Wall::new(
            "f",
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            WallMotion::Fixed,
        );
        let mut side = Wall::new(
            "s",
            Vec2::new(2.0, -1.0),
            Vec2::new(2.0, 3.0),
            WallMotion::Fixed,
        );
        assert_eq!(floor.meet(&side), Some(Vec2::new(2.0, 0.0)));
        assert_eq!(side.meet(&floor), Some(Vec2::new(2.0, 0.0)));
        side.translate(Vec2::new(0.5, 7.0));
        assert_eq!(floor.meet(&side), Some(Vec2::new(2.5, 0.0)));
        let top = Wall::new(
            "t",
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            WallMotion::Fixed,
        );
        assert_eq!(floor.meet(&top), None);
    }
}
