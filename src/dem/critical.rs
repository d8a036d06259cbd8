//! The critical time step of the discs' central difference for the contact
//! laws in use: the largest Δt at which every linear mode of the contacts
//! stays bounded, dashpots included.
//!
//! Basis. Between rebuilds the contacts are linear springs and dashpots:
//! `M ẍ + C ẋ + K x = 0` in the discs' translations and rotations, the
//! dashpots fed with the velocity of the half step before (as
//! [`super::sweep`] does: `v₊ = v + Δt M⁻¹(−K x − C v)`, `x₊ = x + Δt v₊`).
//! The step is stable while the spectral radius of that map is at most 1;
//! for one mode of angular frequency ω and damping ratio ζ this is
//! `ωΔt ≤ 2(√(1 + ζ²) − ζ)`. The modes that limit it:
//!
//! * a pair of the lightest discs: the normal mode (effective mass
//!   `m/2`: `0.707 × 2√(m/k_n)` undamped) and the tangential mode with
//!   both discs turning (`1/m_t = 2/m + 2r²/I`: `0.408 × 2√(m/k_s)` for
//!   `I = mr²/2`), with the rolling spring on their relative rotation;
//! * a disc of the lightest on a wall or a body (rigid): the normal mode
//!   (`2√(m/k_n)`) and the tangential one (`1/m_t = 1/m + r²/I`);
//! * with three discs or more, a hexagonal packing of the lightest discs
//!   (six contacts each, the densest packing of equal discs): every Bloch
//!   mode of the lattice in translation and rotation, the limit the
//!   largest over its Brillouin zone — for `k_s = k_n` undamped the spin
//!   mode, all discs turning the same way, `ω² = 24 k_s/m`:
//!   `0.204 × 2√(m/k)`.
//!
//! Each mode's limit is found by bisection on the spectral radius of the
//! step map (small dense eigenvalue problems), so non-proportional
//! dashpots (normal, shear and rolling of different ratios) are exact,
//! not a modal approximation. A packing of unequal discs is stiffest where
//! the lightest discs sit together; the hexagonal packing of the lightest
//! is taken as the bound.

use super::contact::{ContactLaw, contact_inertia};
use faer::{Mat, c64};

/// A critical time step and the mode that sets it.
#[derive(Debug, Clone, PartialEq)]
pub struct Critical {
    /// The largest stable Δt.
    pub dt: f64,
    /// Which mode limits it, for messages.
    pub mode: String,
    /// The limit of the normal mode that two of the lightest discs meeting
    /// (or one meeting a wall or a body) always have, dashpot included:
    /// above it a run is unstable at its first collision, whatever the
    /// packing (`efgdem check` and `run` refuse it). Between
    /// [`dt`](Self::dt) and this, packings of some shapes stay stable (the
    /// modes above need six equal neighbours, or a stick contact whose
    /// shear spring the friction cap does not clip); a run that goes
    /// unstable there is stopped by the per-step check.
    pub certain: f64,
}

/// Spectral radius up to which the step map counts as stable: the
/// eigenvalues of undamped modes lie on the unit circle, and the
/// rigid-body modes give a defective eigenvalue 1. Past an undamped limit
/// by a fraction ε the radius is `1 + √(8ε)`, past a damped one
/// `1 + O(ε)`: the limits found are within about 1e-6 of the exact ones.
const STABLE_TOL: f64 = 1e-6;

/// Is the central difference with lagged dashpots stable at `dt` for
/// masses `m` (diagonal) and the Hermitian `k`, `c` (n × n, row-major)?
fn stable(m: &[f64], k: &[c64], c: &[c64], dt: f64) -> bool {
    let n = m.len();
    let one = c64::new(1.0, 0.0);
    // in mass-scaled coordinates y = M^½ x and w = Δt M^½ v (every entry
    // of order one: the eigenvalues to round-off), the step
    // w₊ = w − Δt² K̃ y − Δt C̃ w, y₊ = y + w₊ with K̃ = M^-½ K M^-½
    let a = Mat::<c64>::from_fn(2 * n, 2 * n, |i, j| {
        let (bi, ii) = (i / n, i % n);
        let (bj, jj) = (j / n, j % n);
        let s = 1.0 / (m[ii] * m[jj]).sqrt();
        let kk = k[ii * n + jj] * (s * dt * dt);
        let cc = c[ii * n + jj] * (s * dt);
        let id = if ii == jj { one } else { c64::new(0.0, 0.0) };
        match (bi, bj) {
            (0, 0) | (1, 0) => -kk + if bi == 0 { id } else { c64::new(0.0, 0.0) },
            _ => id - cc,
        }
    });
    match a.eigenvalues() {
        Ok(ev) => ev.iter().all(|z| z.norm() <= 1.0 + STABLE_TOL),
        Err(_) => false,
    }
}

/// The largest stable Δt of a linear system ([`stable`]), bisected from
/// the bracket `[lo, hi]` (grown until `hi` is unstable), to `rel`.
fn bisect(m: &[f64], k: &[c64], c: &[c64], mut lo: f64, mut hi: f64, rel: f64) -> f64 {
    for _ in 0..60 {
        if !stable(m, k, c, hi) {
            break;
        }
        (lo, hi) = (hi, 2.0 * hi);
    }
    while hi - lo > rel * hi {
        let mid = 0.5 * (lo + hi);
        if stable(m, k, c, mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// `Σ w gᵢ gⱼ` added to an n × n row-major matrix for the constraint `g`.
fn add_outer(a: &mut [c64], g: &[f64], w: f64) {
    let n = g.len();
    for i in 0..n {
        for j in 0..n {
            a[i * n + j] += c64::new(w * g[i] * g[j], 0.0);
        }
    }
}

/// One side of a contact: a disc of mass `m` and radius `r` (`I = mr²/2`).
#[derive(Debug, Clone, Copy)]
pub struct Disc {
    /// Mass.
    pub m: f64,
    /// Radius.
    pub r: f64,
}

impl Disc {
    fn inertia(&self) -> f64 {
        0.5 * self.m * self.r * self.r
    }
}

/// Δt of one normal mode: `(2/ω)(√(1 + ζ²) − ζ)`.
fn single(k: f64, c: f64, m: f64) -> f64 {
    if k <= 0.0 {
        return f64::INFINITY;
    }
    let w = (k / m).sqrt();
    let z = c / (2.0 * (k * m).sqrt());
    2.0 / w * ((1.0 + z * z).sqrt() - z)
}

/// Upper end of a bracket: the undamped step of the stiffest spring on
/// the disc's mass alone.
fn bracket(law: &ContactLaw, d: Disc) -> f64 {
    2.0 * (d.m / law.kn.max(law.ks)).sqrt()
}

/// Two discs `d` touching with `law`: the normal mode and the tangential–
/// rotational one (with the rolling spring), the smaller Δt and its name.
pub fn pair(law: &ContactLaw, d: Disc) -> Critical {
    let meff = 0.5 * d.m;
    let (cn, cs) = law.dashpots(meff);
    let normal = single(law.kn, cn, meff);
    // DOFs (u_t,i, θ_i, u_t,j, θ_j): slip s = u_ti − u_tj + r θ_i + r θ_j,
    // relative rotation θ_i − θ_j
    let (m, i) = (d.m, d.inertia());
    let masses = [m, i, m, i];
    let zero = c64::new(0.0, 0.0);
    let (mut k, mut c) = (vec![zero; 16], vec![zero; 16]);
    let g = [1.0, d.r, -1.0, d.r];
    add_outer(&mut k, &g, law.ks);
    add_outer(&mut c, &g, cs);
    if law.rolling() {
        let kr = law.roll_kr(0.5 * d.r);
        let a = contact_inertia(1.0 / m, 1.0 / i, d.r);
        let cr = super::contact::rolling_dashpot(law, kr, a, a);
        let h = [0.0, 1.0, 0.0, -1.0];
        add_outer(&mut k, &h, kr);
        add_outer(&mut c, &h, cr);
    }
    let hi = bracket(law, d);
    let shear = if law.ks > 0.0 || law.rolling() {
        bisect(&masses, &k, &c, 0.0, hi, 1e-6)
    } else {
        f64::INFINITY
    };
    if normal <= shear {
        Critical {
            dt: normal,
            mode: "the normal mode of a pair of the lightest discs".into(),
            certain: f64::INFINITY,
        }
    } else {
        Critical {
            dt: shear,
            mode: "the shear–rotation mode of a pair of the lightest discs".into(),
            certain: f64::INFINITY,
        }
    }
}

/// A disc `d` on a wall or a body (rigid) with `law`.
pub fn on_wall(law: &ContactLaw, d: Disc) -> Critical {
    let (cn, cs) = law.dashpots(d.m);
    let normal = single(law.kn, cn, d.m);
    let (m, i) = (d.m, d.inertia());
    let zero = c64::new(0.0, 0.0);
    let (mut k, mut c) = (vec![zero; 4], vec![zero; 4]);
    add_outer(&mut k, &[1.0, d.r], law.ks);
    add_outer(&mut c, &[1.0, d.r], cs);
    if law.rolling() {
        let kr = law.roll_kr(d.r);
        let a = contact_inertia(1.0 / m, 1.0 / i, d.r);
        let cr = super::contact::rolling_dashpot(law, kr, a, (0.0, 1.0));
        add_outer(&mut k, &[0.0, 1.0], kr);
        add_outer(&mut c, &[0.0, 1.0], cr);
    }
    let shear = if law.ks > 0.0 || law.rolling() {
        bisect(&[m, i], &k, &c, 0.0, bracket(law, d), 1e-6)
    } else {
        f64::INFINITY
    };
    if normal <= shear {
        Critical {
            dt: normal,
            mode: "the normal mode of the lightest disc on a wall or body".into(),
            certain: f64::INFINITY,
        }
    } else {
        Critical {
            dt: shear,
            mode: "the shear–rotation mode of the lightest disc on a wall or body".into(),
            certain: f64::INFINITY,
        }
    }
}

/// Bloch wave-vectors sampled per reciprocal lattice vector (a multiple of
/// 6: the zone's centre, edge midpoints M and corners K are on the grid).
const ZONE: usize = 12;

/// A hexagonal packing of discs `d` in contact with `law`: the stiffest
/// Bloch mode over the Brillouin zone (every wave-vector of a
/// `ZONE × ZONE` grid roughly, the worst ones to 1e-6).
pub fn hexagonal(law: &ContactLaw, d: Disc) -> Critical {
    let (cn, cs) = law.dashpots(0.5 * d.m);
    let (kr, cr) = if law.rolling() {
        let kr = law.roll_kr(0.5 * d.r);
        let a = contact_inertia(1.0 / d.m, 1.0 / d.inertia(), d.r);
        (kr, super::contact::rolling_dashpot(law, kr, a, a))
    } else {
        (0.0, 0.0)
    };
    let masses = [d.m, d.m, d.inertia()];
    let hi = bracket(law, d);
    let mut worst: Vec<(f64, [f64; 2])> = Vec::new();
    for a in 0..ZONE {
        for b in 0..ZONE {
            let q = [a as f64 / ZONE as f64, b as f64 / ZONE as f64];
            let (k, c) = bloch(law, d, q, (kr, cr), (cn, cs));
            worst.push((bisect(&masses, &k, &c, 0.0, hi, 1e-3), q));
        }
    }
    worst.sort_by(|x, y| x.0.total_cmp(&y.0));
    let dt = worst
        .iter()
        .take(4)
        .map(|&(_, q)| {
            let (k, c) = bloch(law, d, q, (kr, cr), (cn, cs));
            bisect(&masses, &k, &c, 0.0, hi, 1e-6)
        })
        .fold(f64::INFINITY, f64::min);
    Critical {
        dt,
        mode: "a hexagonal packing of the lightest discs (six contacts each)".into(),
        certain: f64::INFINITY,
    }
}

/// Stiffness and dashpot matrices (Hermitian, 3 × 3 in `(u_x, u_y, θ)`)
/// of the hexagonal lattice's Bloch wave with reduced wave-vector `q` (in
/// units of the reciprocal vectors).
fn bloch(
    law: &ContactLaw,
    d: Disc,
    q: [f64; 2],
    (kr, cr): (f64, f64),
    (cn, cs): (f64, f64),
) -> (Vec<c64>, Vec<c64>) {
    let zero = c64::new(0.0, 0.0);
    let (mut k, mut c) = (vec![zero; 9], vec![zero; 9]);
    for nb in 0..6 {
        let a = nb as f64 * std::f64::consts::PI / 3.0;
        let n = [a.cos(), a.sin()];
        let t = [-n[1], n[0]];
        // the neighbour at δ = 2r n; lattice vectors a1 = 2r(1, 0),
        // a2 = 2r(½, √3/2): δ = i a1 + j a2, phase 2π(q₁ i + q₂ j)
        let (i, j) = match nb {
            0 => (1.0, 0.0),
            1 => (0.0, 1.0),
            2 => (-1.0, 1.0),
            3 => (-1.0, 0.0),
            4 => (0.0, -1.0),
            _ => (1.0, -1.0),
        };
        let phase = 2.0 * std::f64::consts::PI * (q[0] * i + q[1] * j);
        let e = c64::new(phase.cos(), phase.sin());
        // relative coordinates (normal, slip, relative rotation) of the
        // contact in the disc's (U, Θ): B = G_i + G_j e^{iφ}
        let gi = [[-n[0], -n[1], 0.0], [t[0], t[1], d.r], [0.0, 0.0, 1.0]];
        let gj = [[n[0], n[1], 0.0], [-t[0], -t[1], d.r], [0.0, 0.0, -1.0]];
        let stiff = [law.kn, law.ks, kr];
        let damp = [cn, cs, cr];
        for row in 0..3 {
            let b: [c64; 3] = std::array::from_fn(|x| e * gj[row][x] + gi[row][x]);
            for x in 0..3 {
                for y in 0..3 {
                    // ½ Bᴴ w B
                    let v = b[x].conj() * b[y];
                    k[x * 3 + y] += v * (0.5 * stiff[row]);
                    c[x * 3 + y] += v * (0.5 * damp[row]);
                }
            }
        }
    }
    (k, c)
}

/// The critical step of discs whose lightest is `d` (`n` of them), with
/// the disc–disc laws `pairs` and the disc–wall and disc–body laws
/// `walls` in use: the smallest of the modes of the [module docs](self)
/// (the hexagonal packing only with three discs or more; a lone disc is
/// taken on a wall of its own law).
pub fn estimate(d: Disc, n: usize, pairs: &[ContactLaw], walls: &[ContactLaw]) -> Critical {
    let mut best = Critical {
        dt: f64::INFINITY,
        mode: "no contact stiffness".into(),
        certain: f64::INFINITY,
    };
    let mut keep = |c: Critical| {
        if c.dt < best.dt {
            best = c;
        }
    };
    let stiff = |l: &&ContactLaw| l.kn > 0.0 || l.ks > 0.0;
    for law in pairs.iter().filter(stiff) {
        if n >= 2 {
            keep(pair(law, d));
        }
        if n >= 3 {
            keep(hexagonal(law, d));
        }
    }
    // a lone disc can only meet something rigid: its own law on a wall
    let lone = if n < 2 { pairs } else { &[] };
    for law in walls.iter().chain(lone).filter(stiff) {
        keep(on_wall(law, d));
    }
    // the normal modes of a first collision
    let pair_normal = |law: &ContactLaw| single(law.kn, law.dashpots(0.5 * d.m).0, 0.5 * d.m);
    let wall_normal = |law: &ContactLaw| single(law.kn, law.dashpots(d.m).0, d.m);
    let pairs = pairs.iter().filter(|_| n >= 2).map(pair_normal);
    let walls = walls.iter().chain(lone).map(wall_normal);
    best.certain = pairs.chain(walls).fold(f64::INFINITY, f64::min);
    best.certain = best.certain.max(best.dt);
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law(kn: f64, ks: f64) -> ContactLaw {
        ContactLaw {
            kn,
            ks,
            ..Default::default()
        }
    }

    /// The undamped limits in closed form: a pair's normal mode
    /// `2√(m/2k)`, its shear–rotation mode `2/√(6k/m)`, a disc on a wall
    /// `2√(m/k)` and `2/√(3k/m)`, the hexagonal packing's spin mode
    /// `2/√(24k/m)`; a dashpot at ζ of critical on the pair's normal mode
    /// `(2/ω)(√(1 + ζ²) − ζ)`.
    #[test]
    fn closed_forms() {
        let d = Disc { m: 0.2, r: 0.005 };
        let k = 1e7;
        let t = |x: f64| 2.0 / (x * k / d.m).sqrt();
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-5;
        let p = pair(&law(k, 0.0), d);
        assert!(close(p.dt, t(2.0)), "{p:?}");
        let p = pair(&law(0.1 * k, k), d);
        assert!(close(p.dt, t(6.0)), "{p:?}");
        assert!(p.mode.contains("shear"));
        assert!(close(on_wall(&law(k, 0.0), d).dt, t(1.0)));
        assert!(close(on_wall(&law(0.1 * k, k), d).dt, t(3.0)));
        let h = hexagonal(&law(k, k), d);
        assert!(close(h.dt, t(24.0)), "{h:?}");
        let damped = ContactLaw {
            zeta_n: 0.3,
            ..law(k, 0.0)
        };
        let w = (2.0 * k / d.m).sqrt();
        let want = 2.0 / w * ((1.0f64 + 0.09).sqrt() - 0.3);
        assert!(close(pair(&damped, d).dt, want));
    }
}
