//! The linear contact law: normal spring + dashpot, incremental shear spring
//! with a Coulomb–cohesion cap (Eqs. 35–38 corrected per ERRATA E6, E12),
//! the cap on the total normal force `max(0, k_n δ + c_n δ̇)` as Eq. (37)
//! with Eq. (35) (or on `k_n δ`, PFC: [`SlipNormal`]); optional rolling
//! resistance, an elastic–plastic spring–dashpot moment ([`rolling`]).
//!
//! Geometry of a contact between disc i and an entity j (disc or wall):
//! `n` is the unit normal from i towards j, `t = perp(n)` (n rotated +90°),
//! δ the overlap. As in Cundall & Strack (1979), the contact point of each
//! disc is on its surface along n, at the arm `r_i` from its centre (and
//! `r_j` from j; 0 for a wall). The same arms are used for the
//! contact-point velocity (`r_i ω_i + r_j ω_j`) and for the moments
//! (`r_i F_s`, `r_j F_s`), so the pair is work-consistent.

use crate::geom::Vec2;

/// Which normal force caps the shear force (`slip_normal` of a material).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SlipNormal {
    /// `|F_s| ≤ μ max(0, k_n δ + c_n δ̇) + c`: the total normal force of
    /// Eq. (35), clamped at zero as the normal force is — the paper's
    /// Eq. (37), Yade's `ViscElPhys` and LAMMPS `granular` (`damping
    /// velocity`). The default.
    #[default]
    Total,
    /// `|F_s| ≤ μ k_n δ + c`: the elastic part only — PFC's linear
    /// contact model (the dashpot is a separate parallel element).
    Elastic,
}

/// Stiffness, friction, cohesion, dashpot and rolling-resistance
/// coefficients of one material pair (disc–disc) or of a wall or body
/// against a disc material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLaw {
    /// Normal stiffness `k_n`.
    pub kn: f64,
    /// Shear stiffness `k_s`.
    pub ks: f64,
    /// Friction coefficient `tan φ` (the smaller of the two, Eq. 37).
    pub mu: f64,
    /// Cohesion `c` (the smaller of the two, Eq. 37).
    pub cohesion: f64,
    /// Stiffness-proportional normal dashpot: `c_n = β_n k_n` (ERRATA E6).
    pub beta_n: f64,
    /// Stiffness-proportional shear dashpot: `c_s = β_s k_s`.
    pub beta_s: f64,
    /// Normal dashpot as a fraction of critical: `c_n = ζ_n 2√(k_n m_eff)`.
    pub zeta_n: f64,
    /// Shear dashpot as a fraction of critical: `c_s = ζ_s 2√(k_s m_eff)`.
    pub zeta_s: f64,
    /// Clamp the total normal force (spring + dashpot) at zero. When false
    /// (the default, as PFC's "full" dashpot mode and LIGGGHTS), the spring is
    /// never tensile but the dashpot may pull while the discs overlap, which
    /// gives the textbook restitution `exp(−πζ/√(1−ζ²))`.
    pub no_tension: bool,
    /// Normal force in the Coulomb cap (Eq. 37) and in the rolling limit.
    pub slip_normal: SlipNormal,
    /// Rolling friction `μ_r`: limiting rolling moment `μ_r r̄ F_n`
    /// ([`rolling`]); 0 = no rolling resistance.
    pub mu_roll: f64,
    /// Rolling stiffness factor `β_r`: `k_r = β_r k_s r̄²` (default 1,
    /// Iwashita & Oda 1998).
    pub roll_stiffness: f64,
    /// Rolling dashpot as a fraction of critical: `C_r = η_r 2√(I_r k_r)`
    /// (Ai et al. 2011, model C; default 0).
    pub roll_damping: f64,
}

impl Default for ContactLaw {
    fn default() -> Self {
        ContactLaw {
            kn: 0.0,
            ks: 0.0,
            mu: 0.0,
            cohesion: 0.0,
            beta_n: 0.0,
            beta_s: 0.0,
            zeta_n: 0.0,
            zeta_s: 0.0,
            no_tension: false,
            slip_normal: SlipNormal::Total,
            mu_roll: 0.0,
            roll_stiffness: 1.0,
            roll_damping: 0.0,
        }
    }
}

impl ContactLaw {
    /// Combine two materials (disc–disc): stiffnesses in series scaled so
    /// that equal materials give back their own value (`2 k_i k_j/(k_i+k_j)`,
    /// also for the rolling stiffness factor), friction, cohesion, rolling
    /// friction and rolling damping the smaller of the two (Eq. 37); the
    /// elastic Coulomb cap if either material asks for it (symmetric, so
    /// that the pair's law does not depend on the slot order).
    pub fn mix(a: &ContactLaw, b: &ContactLaw) -> ContactLaw {
        let h = |x: f64, y: f64| {
            if x + y > 0.0 {
                2.0 * x * y / (x + y)
            } else {
                0.0
            }
        };
        ContactLaw {
            kn: h(a.kn, b.kn),
            ks: h(a.ks, b.ks),
            mu: a.mu.min(b.mu),
            cohesion: a.cohesion.min(b.cohesion),
            slip_normal: if a.slip_normal == SlipNormal::Elastic
                || b.slip_normal == SlipNormal::Elastic
            {
                SlipNormal::Elastic
            } else {
                SlipNormal::Total
            },
            mu_roll: a.mu_roll.min(b.mu_roll),
            roll_stiffness: h(a.roll_stiffness, b.roll_stiffness),
            roll_damping: a.roll_damping.min(b.roll_damping),
            ..*a
        }
    }

    /// Is rolling resistance on (`μ_r > 0`)?
    #[inline(always)]
    pub fn rolling(&self) -> bool {
        self.mu_roll > 0.0
    }

    /// Rolling stiffness `k_r = β_r k_s r̄²` for the rolling radius `r̄`.
    #[inline(always)]
    pub fn roll_kr(&self, rbar: f64) -> f64 {
        self.roll_stiffness * self.ks * rbar * rbar
    }

    /// Normal and shear dashpot coefficients for effective mass `m_eff`.
    #[inline(always)]
    pub fn dashpots(&self, m_eff: f64) -> (f64, f64) {
        self.dashpots_sqrt(m_eff.sqrt())
    }

    /// [`dashpots`](Self::dashpots) from `√m_eff` (cached per contact).
    #[inline(always)]
    pub fn dashpots_sqrt(&self, sqrt_m_eff: f64) -> (f64, f64) {
        let mut cn = self.beta_n * self.kn;
        let mut cs = self.beta_s * self.ks;
        if self.zeta_n != 0.0 {
            cn += self.zeta_n * 2.0 * self.kn.sqrt() * sqrt_m_eff;
        }
        if self.zeta_s != 0.0 {
            cs += self.zeta_s * 2.0 * self.ks.sqrt() * sqrt_m_eff;
        }
        (cn, cs)
    }

    /// Dashpot coefficients as `(c_n0, c_n1, c_s0, c_s1)` with
    /// `c_n = c_n0 + c_n1 √m_eff` and `c_s = c_s0 + c_s1 √m_eff`
    /// (precomputed once per law: no square root per contact).
    pub fn dashpot_terms(&self) -> [f64; 4] {
        [
            self.beta_n * self.kn,
            self.zeta_n * 2.0 * self.kn.sqrt(),
            self.beta_s * self.ks,
            self.zeta_s * 2.0 * self.ks.sqrt(),
        ]
    }

    /// Does the law need the effective mass (critical-ratio dashpots)?
    pub fn needs_mass(&self) -> bool {
        self.zeta_n != 0.0 || self.zeta_s != 0.0
    }
}

/// What one contact contributes: force `f` on i (the force on j is its
/// opposite) and the shear force `fs` along t, from which the moments on i
/// and j about their centres are `r_i fs` and `r_j fs` (ERRATA E12:
/// `r_c × F` with `r_c = r_i n` and `r_c = −r_j n`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactForce {
    /// Force on side i (side j gets the opposite).
    pub f: Vec2,
    /// Shear force along `t = perp(n)` (total, with the shear dashpot).
    pub fs: f64,
}

/// Kinematic state of one side of a contact.
#[derive(Debug, Clone, Copy)]
pub struct Side {
    /// Centre (a disc) or contact point (a wall).
    pub pos: Vec2,
    /// Velocity of that point.
    pub vel: Vec2,
    /// Spin ω, counter-clockwise positive (0 for a wall).
    pub omega: f64,
    /// Lever arm from the centre to the contact point: the disc radius, 0
    /// for a wall.
    pub radius: f64,
}

/// One contact evaluation, Eqs. (35)–(38) per ERRATA E6/E12.
///
/// * normal: `F_n = k_n δ + c_n δ̇`, the spring part only while δ > 0 (never
///   tensile), `δ̇ = (v_i − v_j)·n` at the contact;
/// * shear: `F_s ← F_s − k_s v_t Δt` with the contact-point relative
///   tangential velocity `v_t = (v_i − v_j)·t + ω_i l_i + ω_j l_j`, capped at
///   `|F_s| ≤ F_n tan φ + c` (Eq. 37) with `F_n = max(0, k_n δ + c_n δ̇)`
///   ([`SlipNormal::Total`], the default: Eqs. 35 and 37 as printed) or
///   `F_n = k_n δ` ([`SlipNormal::Elastic`], PFC); the shear dashpot
///   `−c_s v_t` acts only while the contact sticks;
/// * moments `r_c × F` about each centre (E12): `r_i F_s` and `r_j F_s`
///   (returned as `fs`; the caller multiplies by the radius).
///
/// `fs` is the contact's shear history (force along `t`); it is reset to
/// zero when the entities do not overlap. `n` is the unit normal from i to
/// j, δ > 0 the overlap, `(cn, cs)` the dashpot coefficients
/// ([`ContactLaw::dashpots`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn evaluate(
    law: &ContactLaw,
    n: Vec2,
    delta: f64,
    i: &Side,
    j: &Side,
    (cn, cs): (f64, f64),
    fs: &mut f64,
    dt: f64,
) -> ContactForce {
    evaluate_capped(law, n, delta, i, j, (cn, cs), fs, dt).0
}

/// [`evaluate`], also returning the normal force of the Coulomb cap
/// (`max(0, k_n δ + c_n δ̇)` or `k_n δ`, per [`ContactLaw::slip_normal`]),
/// which also limits the rolling moment ([`rolling`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn evaluate_capped(
    law: &ContactLaw,
    n: Vec2,
    delta: f64,
    i: &Side,
    j: &Side,
    (cn, cs): (f64, f64),
    fs: &mut f64,
    dt: f64,
) -> (ContactForce, f64) {
    let t = n.perp();
    let dv = i.vel - j.vel;
    let vn = dv.dot(n);
    let vt = dv.dot(t) + i.omega * i.radius + j.omega * j.radius;
    let fn_el = law.kn * delta;
    let mut fn_tot = fn_el + cn * vn;
    if law.no_tension && fn_tot < 0.0 {
        fn_tot = 0.0;
    }
    let trial = *fs - law.ks * vt * dt;
    let fn_cap = match law.slip_normal {
        SlipNormal::Elastic => fn_el,
        // clamped at zero as the normal force (a pulling dashpot gives no
        // friction); written as a select so that it compiles to maxsd
        SlipNormal::Total => {
            if fn_tot > 0.0 {
                fn_tot
            } else {
                0.0
            }
        }
    };
    let cap = law.mu * fn_cap + law.cohesion;
    // Coulomb cap, branch-free (min/max): sliding when the cap bites, and
    // then the shear dashpot is off
    // (written as selects so that they compile to minsd/maxsd)
    let capped = if trial > cap { cap } else { trial };
    let capped = if capped < -cap { -cap } else { capped };
    let damp = if capped == trial { cs * vt } else { 0.0 };
    *fs = capped;
    let fs_tot = capped - damp;
    (
        ContactForce {
            f: n * (-fn_tot) + t * fs_tot,
            fs: fs_tot,
        },
        fn_cap,
    )
}

/// Rolling resistance of one contact: the elastic–plastic spring–dashpot
/// model (Ai, Chen, Rotter & Ooi 2011, "type C"; the spring of Iwashita &
/// Oda 1998), in 2D.
///
/// Sign convention: `omega_rel = ω_i − ω_j` (counter-clockwise positive;
/// `ω_j = 0` for a wall or a body), the relative rolling rotation of i
/// against j over the step is `Δθ_r = ω_rel Δt`, and `mr` is the contact's
/// rolling-spring history, *the moment on i* (j gets `−mr`):
///
/// * spring `M_k ← M_k − k_r Δθ_r`, `k_r = β_r k_s r̄²`;
/// * plastic limit `|M_k| ≤ μ_r r̄ F_n` (F_n as in the Coulomb cap:
///   [`ContactLaw::slip_normal`]);
/// * dashpot `M_d = −C_r ω_rel` only while the spring is below the limit
///   (Ai et al.'s f = 0), `C_r` = `c_r` ([`rolling_dashpot`]).
///
/// Returns the moment on i, `M_k + M_d`. The pair is energy-consistent:
/// the moments do work `M_i ω_i + M_j ω_j = M ω_rel`, i.e. the spring
/// stores `M_k²/(2k_r)` and the limit dissipates `μ_r r̄ F_n |Δθ_plastic|`.
/// Written as selects (min/max) like the shear cap.
#[inline(always)]
pub fn rolling(
    law: &ContactLaw,
    rbar: f64,
    fn_cap: f64,
    omega_rel: f64,
    c_r: f64,
    mr: &mut f64,
    dt: f64,
) -> f64 {
    let kr = law.roll_kr(rbar);
    let limit = law.mu_roll * rbar * fn_cap;
    let trial = *mr - kr * omega_rel * dt;
    let capped = if trial > limit { limit } else { trial };
    let capped = if capped < -limit { -limit } else { capped };
    let damp = if capped == trial {
        c_r * omega_rel
    } else {
        0.0
    };
    *mr = capped;
    capped - damp
}

/// `1/(I + m r²)` of one side of a contact (the inverse of its moment of
/// inertia about the contact point) as a fraction `n/d` with
/// `n = I⁻¹ m⁻¹`, `d = m⁻¹ + r² I⁻¹`, from the inverse mass and inertia;
/// `(0, 1)` for a wall or a fixed disc. No division here: see
/// [`rolling_dashpot`].
#[inline(always)]
pub fn contact_inertia(inv_m: f64, inv_i: f64, r: f64) -> (f64, f64) {
    let d = inv_m + r * r * inv_i;
    if d > 0.0 {
        (inv_i * inv_m, d)
    } else {
        (0.0, 1.0)
    }
}

/// Rolling dashpot `C_r = η_r 2√(I_r k_r)` with
/// `I_r = [1/(I_i + m_i r_i²) + 1/(I_j + m_j r_j²)]⁻¹ = d_i d_j/(n_i d_j + n_j d_i)`
/// (Ai et al. 2011; `(n, d)` from [`contact_inertia`]: one division and
/// one square root); 0 when neither side can turn.
#[inline(always)]
pub fn rolling_dashpot(
    law: &ContactLaw,
    kr: f64,
    (ni, di): (f64, f64),
    (nj, dj): (f64, f64),
) -> f64 {
    let s = ni * dj + nj * di;
    if law.roll_damping == 0.0 || s <= 0.0 {
        return 0.0;
    }
    law.roll_damping * 2.0 * (kr * (di * dj) / s).sqrt()
}

/// Energy `M_r²/(2k_r)` stored in a rolling spring with history `mr`.
#[inline]
pub fn rolling_energy(law: &ContactLaw, rbar: f64, mr: f64) -> f64 {
    let kr = law.roll_kr(rbar);
    if kr > 0.0 { 0.5 * mr * mr / kr } else { 0.0 }
}

/// Rolling radius `r̄ = r_i r_j/(r_i + r_j)` of two discs (a wall or a
/// body: `r̄ = r_i`).
#[inline(always)]
pub fn rolling_radius(ri: f64, rj: f64) -> f64 {
    ri * rj / (ri + rj)
}

/// Normal force of a contact from the present state (for probes): elastic
/// `k_n δ` and total `k_n δ + c_n δ̇` (clamped at 0 with `no_tension`).
pub fn normal_force(law: &ContactLaw, delta: f64, vn: f64, m_eff: f64) -> (f64, f64) {
    if delta <= 0.0 {
        return (0.0, 0.0);
    }
    let (cn, _) = law.dashpots(m_eff);
    let el = law.kn * delta;
    let mut tot = el + cn * vn;
    if law.no_tension && tot < 0.0 {
        tot = 0.0;
    }
    (el, tot)
}

/// Effective mass `m_i m_j/(m_i + m_j)` from inverse masses (a wall or a
/// fixed disc has inverse mass 0).
#[inline(always)]
pub fn effective_mass(inv_mi: f64, inv_mj: f64) -> f64 {
    let s = inv_mi + inv_mj;
    if s > 0.0 { 1.0 / s } else { 0.0 }
}

/// Unit normal and distance from `a` to `b`, with a fixed fallback
/// direction for coincident centres (no NaN).
#[inline(always)]
pub fn normal_between(a: Vec2, b: Vec2) -> (Vec2, f64) {
    let d = b - a;
    let dist = d.norm();
    if dist > 0.0 {
        (d * (1.0 / dist), dist)
    } else {
        (Vec2::new(1.0, 0.0), 0.0)
    }
}
