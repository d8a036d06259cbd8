//! Rigid walls: line segments with a prescribed velocity history (the
//! plates of Cundall & Strack's nine-disc test), recording the total force
//! the discs exert on each wall at every step.

use crate::geom::{Vec2, closest_on_segment};

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
}

impl WallMotion {
    /// Velocity during step `step` (0-based), which runs from `t` to `t + dt`.
    /// The piecewise history is sampled at the middle of the step, which
    /// makes the displacement exact for a linear history (central difference).
    pub fn velocity(&self, step: usize, t: f64, dt: f64) -> Vec2 {
        match self {
            WallMotion::Fixed => Vec2::ZERO,
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
    /// Prescribed velocity history.
    pub motion: WallMotion,
    /// Velocity during the current step (set by the integrator).
    pub vel: Vec2,
    /// Total force exerted by the discs on the wall in the last step.
    pub force: Vec2,
    /// Index of the wall's own material in the assembly's material table;
    /// `None` = use the disc's material.
    pub material: Option<u16>,
}

impl Wall {
    /// A wall from `a` to `b` with `motion`, at rest, with the discs'
    /// material.
    pub fn new(name: &str, a: Vec2, b: Vec2, motion: WallMotion) -> Self {
        Wall {
            name: name.to_string(),
            a,
            b,
            motion,
            vel: Vec2::ZERO,
            force: Vec2::ZERO,
            material: None,
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
}
