//! Central-difference time integration of the discs, Eqs. (50)–(54) with
//! the accelerations of Eqs. (56)–(57) corrected per ERRATA E10:
//! `ü = ΣF/m + g`, `θ̈ = ΣM/I` (no Δt factor).

use super::BodyDamping;
use super::particles::{FIX_ROT, FIX_X, FIX_Y, GHOST, Particles};
use crate::geom::Vec2;
use rayon::prelude::*;

/// Discs per parallel task of [`central_difference`].
pub const CHUNK: usize = 2048;

/// Cundall's local damping of one force component: `F − α|F| sign(v)`.
#[inline(always)]
fn local(f: f64, v: f64, alpha: f64) -> f64 {
    if v == 0.0 {
        f
    } else {
        f - alpha * f.abs() * v.signum()
    }
}

/// Advance one disc by one step: `v(t+Δt/2) = v(t−Δt/2) + ü(t) Δt`
/// (Eqs. 53–54), `x(t+Δt) = x(t) + v(t+Δt/2) Δt` (Eqs. 50–51), with the
/// body damping (local, or global mass damping of Eqs. 33–34 discretised
/// as `v⁺ = [v⁻(1 − cΔt/2m) + FΔt/m] / (1 + cΔt/2m)`). Components flagged
/// fixed keep their velocity.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn advance(
    pos: &mut Vec2,
    vel: &mut Vec2,
    theta: &mut f64,
    omega: &mut f64,
    f: Vec2,
    torque: f64,
    inv_m: f64,
    inv_i: f64,
    fix: u8,
    g: Vec2,
    damping: BodyDamping,
    dt: f64,
) {
    let mut fk = f;
    let mut t = torque;
    let mut v = *vel;
    let mut w = *omega;
    match damping {
        BodyDamping::None => {
            v += (fk * inv_m + g) * dt;
            w += t * inv_i * dt;
        }
        BodyDamping::Local { alpha } => {
            if inv_m > 0.0 {
                fk += g * (1.0 / inv_m);
            }
            fk = Vec2::new(local(fk.x, v.x, alpha), local(fk.y, v.y, alpha));
            t = local(t, w, alpha);
            v += fk * (inv_m * dt);
            w += t * inv_i * dt;
        }
        BodyDamping::Mass { c, c_rot } => {
            let a = 0.5 * c * dt * inv_m;
            v = (v * (1.0 - a) + (fk * inv_m + g) * dt) * (1.0 / (1.0 + a));
            let b = 0.5 * c_rot * dt * inv_i;
            w = (w * (1.0 - b) + t * inv_i * dt) / (1.0 + b);
        }
    }
    if fix != 0 {
        if fix & FIX_X != 0 {
            v.x = vel.x;
        }
        if fix & FIX_Y != 0 {
            v.y = vel.y;
        }
        if fix & FIX_ROT != 0 {
            w = *omega;
        }
    }
    *vel = v;
    *omega = w;
    *pos += v * dt;
    *theta += w * dt;
}

/// The per-step check of a disc after its step
/// ([`Granular::step_check`](super::Granular::step_check)): its state is
/// finite and it moves at most `√max_v2 · r` per unit time,
/// `v·v ≤ max_v2 r²` with `max_v2 = (radii_per_step/Δt)²`.
#[inline(always)]
pub fn passes_check(x: Vec2, v: Vec2, omega: f64, r: f64, max_v2: f64) -> bool {
    v.dot(v) <= max_v2 * r * r && (x.x + x.y + omega).is_finite()
}

/// Advance every disc by one step with [`advance`]. Returns the largest
/// displacement from `ref_pos` (for the Verlet criterion); the max is
/// exact, so the result does not depend on the thread count.
pub fn central_difference(
    p: &mut Particles,
    ref_pos: &[Vec2],
    g: Vec2,
    damping: BodyDamping,
    dt: f64,
) -> f64 {
    let has_ref = ref_pos.len() == p.pos.len();
    let max2 = (
        p.pos.par_chunks_mut(CHUNK),
        p.vel.par_chunks_mut(CHUNK),
        p.theta.par_chunks_mut(CHUNK),
        p.omega.par_chunks_mut(CHUNK),
        p.force.par_chunks(CHUNK),
        p.torque.par_chunks(CHUNK),
        p.inv_mass.par_chunks(CHUNK),
        p.inv_inertia.par_chunks(CHUNK),
        p.fixity.par_chunks(CHUNK),
    )
        .into_par_iter()
        .enumerate()
        .map(|(c, (pos, vel, th, om, f, tq, im, ii, fx))| {
            let mut m2 = 0.0f64;
            for k in 0..pos.len() {
                if fx[k] & GHOST != 0 {
                    continue;
                }
                advance(
                    &mut pos[k],
                    &mut vel[k],
                    &mut th[k],
                    &mut om[k],
                    f[k],
                    tq[k],
                    im[k],
                    ii[k],
                    fx[k],
                    g,
                    damping,
                    dt,
                );
                if has_ref {
                    m2 = m2.max((pos[k] - ref_pos[c * CHUNK + k]).norm2());
                }
            }
            m2
        })
        .reduce(|| 0.0, f64::max);
    if has_ref { max2.sqrt() } else { f64::INFINITY }
}
