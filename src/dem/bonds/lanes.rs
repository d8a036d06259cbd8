//! Two bonds at once, in the two lanes of SSE2 registers: the update of
//! [`Held::step`] ([`bond_step`](super::bond_step), Potyondy & Cundall
//! 2004, Eqs. 6–9) lane by lane with the same operations in the same
//! order, so the forces are bitwise the scalar ones. Breakage is left to
//! the scalar step: a lane whose bond is not clearly intact
//! ([`Held::intact`]'s test) keeps its old forces, and the caller steps
//! that bond with [`Held::step`].

use super::{BondForce, BondLaw, Held, HeldForces, ShearStrength};
use crate::dem::contact::Side;
use crate::dem::sweep::lanes::{get, set};
use crate::geom::Vec2;
use std::arch::x86_64::*;

/// The bonds `h` between the discs `si[l]` and `sj[l]`, lane l, with
/// forces `f[l]`: what they do to the discs written into `out[l]`, and
/// the new forces into `f[l]` for the bonds that are clearly intact (bit
/// l of the mask returned; a lane whose bond is not keeps its forces, and
/// its `out` is to be replaced by the scalar step's); `None` if a pair's
/// centres coincide (or are not finite), left to the scalar step.
#[inline(always)]
pub(in crate::dem) fn step2(
    h: [&Held; 2],
    f: &mut [HeldForces],
    si: [Side; 2],
    sj: [Side; 2],
    law: &BondLaw,
    dt: f64,
    out: &mut [BondForce],
) -> Option<i32> {
    // SAFETY: SSE2 is enabled (module cfg); no memory is accessed through
    // pointers.
    unsafe {
        let pair = |a: fn(&Side) -> f64| (set(a(&si[0]), a(&si[1])), set(a(&sj[0]), a(&sj[1])));
        let (pix, pjx) = pair(|s| s.pos.x);
        let (piy, pjy) = pair(|s| s.pos.y);
        let (dx, dy) = (_mm_sub_pd(pjx, pix), _mm_sub_pd(pjy, piy));
        let d2 = _mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy));
        let zero = _mm_setzero_pd();
        if _mm_movemask_pd(_mm_cmpgt_pd(d2, zero)) != 3 {
            return None;
        }
        // n = d (1/|d|), t = perp(n) = (−n_y, n_x) (negation flips the sign)
        let dist = _mm_sqrt_pd(d2);
        let inv = _mm_div_pd(_mm_set1_pd(1.0), dist);
        let (nx, ny) = (_mm_mul_pd(dx, inv), _mm_mul_pd(dy, inv));
        let sign = _mm_set1_pd(-0.0);
        let tx = _mm_xor_pd(ny, sign);
        // the lever arms d r_i/(r_i + r_j), d r_j/(r_i + r_j)
        let la = _mm_mul_pd(dist, set(h[0].ci, h[1].ci));
        let lb = _mm_mul_pd(dist, set(h[0].cj, h[1].cj));
        let (vix, vjx) = pair(|s| s.vel.x);
        let (viy, vjy) = pair(|s| s.vel.y);
        let (dvx, dvy) = (_mm_sub_pd(vix, vjx), _mm_sub_pd(viy, vjy));
        let (wi, wj) = pair(|s| s.omega);
        let vn = _mm_add_pd(_mm_mul_pd(dvx, nx), _mm_mul_pd(dvy, ny));
        let vt = _mm_add_pd(
            _mm_add_pd(
                _mm_add_pd(_mm_mul_pd(dvx, tx), _mm_mul_pd(dvy, nx)),
                _mm_mul_pd(wi, la),
            ),
            _mm_mul_pd(wj, lb),
        );
        // k̄_n A v_n Δt, k̄_s A v_t Δt, k̄_n I (ω_i − ω_j) Δt
        let dt = _mm_set1_pd(dt);
        let inc = |k: __m128d, v: __m128d| _mm_mul_pd(_mm_mul_pd(k, v), dt);
        let kn_a = set(h[0].kn_a, h[1].kn_a);
        let ks_a = set(h[0].ks_a, h[1].ks_a);
        let kn_i = set(h[0].kn_i, h[1].kn_i);
        let fn_ = _mm_add_pd(set(f[0].0, f[1].0), inc(kn_a, vn));
        let fs = _mm_sub_pd(set(f[0].1, f[1].1), inc(ks_a, vt));
        let m = _mm_sub_pd(set(f[0].2, f[1].2), inc(kn_i, _mm_sub_pd(wi, wj)));
        // f = n (−F_n) + t F_s; M_i = l_i F_s + M, M_j = l_j F_s − M
        let neg_fn = _mm_xor_pd(fn_, sign);
        let fx = _mm_add_pd(_mm_mul_pd(nx, neg_fn), _mm_mul_pd(tx, fs));
        let fy = _mm_add_pd(_mm_mul_pd(ny, neg_fn), _mm_mul_pd(nx, fs));
        let ma = _mm_add_pd(_mm_mul_pd(la, fs), m);
        let mb = _mm_sub_pd(_mm_mul_pd(lb, fs), m);
        let intact = intact2(h, law, fn_, fs, m);
        // lane l's force (x, y) and new (F_n, F_s), stored whole
        let (f0, f1) = (_mm_unpacklo_pd(fx, fy), _mm_unpackhi_pd(fx, fy));
        let (m0, m1) = (_mm_unpacklo_pd(ma, mb), _mm_unpackhi_pd(ma, mb));
        let (f, out) = (&mut f[..2], &mut out[..2]);
        for (o, (fv, mv)) in out.iter_mut().zip([(f0, m0), (f1, m1)]) {
            let ([x, y], [ma, mb]) = (get(fv), get(mv));
            *o = BondForce {
                f: Vec2::new(x, y),
                ma,
                mb,
            };
        }
        let (s0, s1) = (_mm_unpacklo_pd(fn_, fs), _mm_unpackhi_pd(fn_, fs));
        let m = get(m);
        for (l, sv) in [s0, s1].into_iter().enumerate() {
            if intact & (1 << l) != 0 {
                let [fn_l, fs_l] = get(sv);
                f[l] = (fn_l, fs_l, m[l]);
            }
        }
        Some(intact)
    }
}

/// [`Held::intact`] in two lanes: bit l set when lane l's bond is.
#[inline(always)]
fn intact2(h: [&Held; 2], law: &BondLaw, fn_: __m128d, fs: __m128d, m: __m128d) -> i32 {
    // SAFETY: SSE2 is enabled (module cfg).
    unsafe {
        let tol = _mm_set1_pd(16.0 * f64::EPSILON);
        let abs = |v: __m128d| _mm_andnot_pd(_mm_set1_pd(-0.0), v);
        let inv_a = set(h[0].inv_a, h[1].inv_a);
        let sn = _mm_mul_pd(_mm_xor_pd(fn_, _mm_set1_pd(-0.0)), inv_a);
        let sm = _mm_mul_pd(abs(m), set(h[0].r_over_i, h[1].r_over_i));
        let tau = _mm_mul_pd(abs(fs), inv_a);
        let friction = match law.shear {
            ShearStrength::Fixed(_) => _mm_setzero_pd(),
            ShearStrength::Coulomb { tan_phi, .. } => {
                _mm_mul_pd(_mm_mul_pd(fn_, inv_a), _mm_set1_pd(tan_phi))
            }
        };
        let tau_c = _mm_add_pd(set(h[0].shear, h[1].shear), friction);
        let sigma = _mm_add_pd(_mm_add_pd(sn, sm), _mm_mul_pd(tol, _mm_add_pd(abs(sn), sm)));
        let ok_t = _mm_cmplt_pd(sigma, set(h[0].tensile, h[1].tensile));
        let shear = _mm_add_pd(tau, _mm_mul_pd(tol, _mm_add_pd(tau, abs(friction))));
        let ok_s = _mm_cmplt_pd(shear, _mm_mul_pd(tau_c, _mm_sub_pd(_mm_set1_pd(1.0), tol)));
        _mm_movemask_pd(_mm_and_pd(ok_t, ok_s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::bonds::{section, stresses};

    /// The two lanes give bitwise the scalar step's forces (disc forces,
    /// moments, new bond forces) for every bond they find intact, leave
    /// the others' forces alone, and call no bond intact that the scalar
    /// step breaks: random discs and bonds, fixed and cohesion–friction
    /// strengths, some bonds loaded to breakage.
    #[test]
    fn two_lanes_equal_the_scalar_bond_step_bitwise() {
        let mut rng = oorandom::Rand64::new(5);
        let mut u = |a: f64, b: f64| a + (b - a) * rng.rand_float();
        let (mut same, mut left, mut broke) = (0, 0, 0);
        for case in 0..4000 {
            let law = BondLaw {
                kn: u(1e5, 1e7),
                ks: u(1e5, 1e7),
                shear: if case % 2 == 0 {
                    ShearStrength::Fixed(0.0)
                } else {
                    ShearStrength::Coulomb {
                        cohesion: 0.0,
                        tan_phi: u(0.1, 1.0),
                    }
                },
                ..Default::default()
            };
            let (thickness, dt) = (u(0.5, 2.0), 1e-6);
            let mut side = |c: Vec2| Side {
                pos: c + Vec2::new(u(-0.1, 0.1), u(-0.1, 0.1)),
                vel: Vec2::new(u(-3.0, 3.0), u(-3.0, 3.0)),
                omega: u(-5.0, 5.0),
                radius: u(0.8, 1.2),
            };
            let si = [side(Vec2::ZERO), side(Vec2::new(5.0, 0.0))];
            let sj = [side(Vec2::new(2.0, 0.3)), side(Vec2::new(5.3, 2.0))];
            let mut held = [Held::default(); 2];
            let mut radii_of = [0.0; 2];
            let mut f = [(0.0, 0.0, 0.0); 2];
            for (l, h) in held.iter_mut().enumerate() {
                let radius = u(0.5, 1.0);
                let (a, i) = section(radius, thickness);
                let forces = (u(-100.0, 100.0), u(-100.0, 100.0), u(-50.0, 50.0));
                let (sigma, tau) = stresses(forces.0, forces.1, forces.2, radius, a, i);
                // strengths about the current stresses: some bonds break
                let strengths = (sigma.abs() * u(0.8, 2.0), tau * u(0.8, 2.0));
                let radii = (si[l].radius, sj[l].radius);
                *h = Held::new((0, 0), radius, strengths, radii, &law, thickness);
                radii_of[l] = radius;
                f[l] = forces;
            }
            let mut lanes_f = f;
            let mut out = [BondForce::default(); 2];
            let intact = step2(
                [&held[0], &held[1]],
                &mut lanes_f,
                si,
                sj,
                &law,
                dt,
                &mut out,
            )
            .expect("distinct centres");
            for l in 0..2 {
                let mut fl = f[l];
                let (bf, brk) =
                    held[l].step(l, &mut fl, &si[l], &sj[l], &law, &radii_of, thickness, dt);
                broke += usize::from(brk.is_some());
                let bits = |b: &BondForce| [b.f.x, b.f.y, b.ma, b.mb].map(f64::to_bits);
                let fbits = |f: HeldForces| [f.0, f.1, f.2].map(f64::to_bits);
                if intact & (1 << l) != 0 {
                    assert!(brk.is_none(), "case {case} lane {l}: intact but broke");
                    assert_eq!(bits(&out[l]), bits(&bf), "case {case} lane {l}");
                    assert_eq!(fbits(lanes_f[l]), fbits(fl), "case {case} lane {l}");
                    same += 1;
                } else {
                    assert_eq!(fbits(lanes_f[l]), fbits(f[l]), "case {case} lane {l}");
                    left += 1;
                }
            }
        }
        assert!(
            same > 1000 && left > 500 && broke > 500,
            "{same} {left} {broke}"
        );
    }
}
