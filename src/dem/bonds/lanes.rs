//! Bonds two or four at once, in the lanes of SSE2 (two) or AVX2 (four)
//! registers: the update of [`Held::step`] ([`bond_step`](super::bond_step),
//! Potyondy & Cundall 2004, Eqs. 6–9) lane by lane with the same
//! operations in the same order, so the forces are bitwise the scalar
//! ones. One kernel, [`step_lanes`], over the [`Lanes`] of either width.
//! Breakage is left to the scalar step: a lane whose bond is not clearly
//! intact ([`Held::intact`]'s test) keeps its old forces, and the caller
//! steps that bond with [`Held::step`].

use super::{BondForce, BondLaw, Held, HeldForces, ShearStrength};
use crate::dem::contact::Side;
use crate::geom::Vec2;
use std::arch::x86_64::*;

/// Step the bonds four at a time ([`step4`]): the processor has AVX2.
pub(in crate::dem) fn four_available() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
}

/// Allow or forbid the four lanes (tests; the results are the same).
/// The operations of the bond kernel on `N` lanes of f64. Every method
/// is an intrinsic of the register's width: the four-lane ones need AVX
/// (the caller runs in an AVX2 function).
trait Lanes: Copy {
    /// Number of lanes.
    const N: usize;
    /// Lane l is `f(l)`.
    unsafe fn from(f: impl Fn(usize) -> f64) -> Self;
    /// Every lane `x`.
    unsafe fn splat(x: f64) -> Self;
    /// The lanes, in the first `N` entries.
    unsafe fn lanes(self) -> [f64; 4];
    unsafe fn add(self, o: Self) -> Self;
    unsafe fn sub(self, o: Self) -> Self;
    unsafe fn mul(self, o: Self) -> Self;
    unsafe fn div(self, o: Self) -> Self;
    unsafe fn sqrt(self) -> Self;
    unsafe fn xor(self, o: Self) -> Self;
    unsafe fn and(self, o: Self) -> Self;
    /// `!self & o`.
    unsafe fn andnot(self, o: Self) -> Self;
    /// All ones where `self < o`.
    unsafe fn lt(self, o: Self) -> Self;
    /// Bit l set where lane l's sign bit is.
    unsafe fn mask(self) -> i32;
}

/// The [`Lanes`] methods of a register type from its intrinsics.
macro_rules! lanes {
    ($v:ty, $n:expr, $set:ident, $set1:ident, $store:ident, $add:ident, $sub:ident,
     $mul:ident, $div:ident, $sqrt:ident, $xor:ident, $and:ident, $andnot:ident,
     $lt:expr, $mask:ident) => {
        impl Lanes for $v {
            const N: usize = $n;
            #[inline(always)]
            unsafe fn from(f: impl Fn(usize) -> f64) -> Self {
                let a: [f64; $n] = std::array::from_fn(f);
                // SAFETY: the caller's.
                unsafe { $set(a.as_ptr()) }
            }
            #[inline(always)]
            unsafe fn splat(x: f64) -> Self {
                unsafe { $set1(x) }
            }
            #[inline(always)]
            unsafe fn lanes(self) -> [f64; 4] {
                let mut a = [0.0; 4];
                unsafe { $store(a.as_mut_ptr(), self) };
                a
            }
            #[inline(always)]
            unsafe fn add(self, o: Self) -> Self {
                unsafe { $add(self, o) }
            }
            #[inline(always)]
            unsafe fn sub(self, o: Self) -> Self {
                unsafe { $sub(self, o) }
            }
            #[inline(always)]
            unsafe fn mul(self, o: Self) -> Self {
                unsafe { $mul(self, o) }
            }
            #[inline(always)]
            unsafe fn div(self, o: Self) -> Self {
                unsafe { $div(self, o) }
            }
            #[inline(always)]
            unsafe fn sqrt(self) -> Self {
                unsafe { $sqrt(self) }
            }
            #[inline(always)]
            unsafe fn xor(self, o: Self) -> Self {
                unsafe { $xor(self, o) }
            }
            #[inline(always)]
            unsafe fn and(self, o: Self) -> Self {
                unsafe { $and(self, o) }
            }
            #[inline(always)]
            unsafe fn andnot(self, o: Self) -> Self {
                unsafe { $andnot(self, o) }
            }
            #[inline(always)]
            unsafe fn lt(self, o: Self) -> Self {
                unsafe { $lt(self, o) }
            }
            #[inline(always)]
            unsafe fn mask(self) -> i32 {
                unsafe { $mask(self) }
            }
        }
    };
}

lanes!(
    __m128d,
    2,
    _mm_loadu_pd,
    _mm_set1_pd,
    _mm_storeu_pd,
    _mm_add_pd,
    _mm_sub_pd,
    _mm_mul_pd,
    _mm_div_pd,
    _mm_sqrt_pd,
    _mm_xor_pd,
    _mm_and_pd,
    _mm_andnot_pd,
    _mm_cmplt_pd,
    _mm_movemask_pd
);
lanes!(
    __m256d,
    4,
    _mm256_loadu_pd,
    _mm256_set1_pd,
    _mm256_storeu_pd,
    _mm256_add_pd,
    _mm256_sub_pd,
    _mm256_mul_pd,
    _mm256_div_pd,
    _mm256_sqrt_pd,
    _mm256_xor_pd,
    _mm256_and_pd,
    _mm256_andnot_pd,
    _mm256_cmp_pd::<_CMP_LT_OS>,
    _mm256_movemask_pd
);

/// The bonds `h` between the discs `si[l]` and `sj[l]`, lane l, with
/// forces `f[l]` (the bonds' law and the discs' thickness): what they do
/// to the discs written into `out[l]`, and the new forces into `f[l]`
/// for the bonds that are clearly intact (bit l of the mask returned; a
/// lane whose bond is not keeps its forces, and its `out` is to be
/// replaced by the scalar step's); `None` if a pair's centres coincide
/// (or are not finite), left to the scalar step.
#[inline(always)]
pub(in crate::dem) fn step2(
    h: [&Held; 2],
    f: &mut [HeldForces],
    si: [Side; 2],
    sj: [Side; 2],
    law: (&BondLaw, f64),
    dt: f64,
    out: &mut [BondForce],
) -> Option<i32> {
    // SAFETY: SSE2 is enabled (module cfg).
    unsafe { step_lanes::<__m128d>(&h, f, &si, &sj, law, dt, out) }
}

/// [`step2`] four bonds at once.
///
/// # Safety
/// The processor has AVX2, and the caller runs with it enabled (an AVX2
/// function, into which this one is inlined).
#[inline(always)]
pub(in crate::dem) unsafe fn step4(
    h: [&Held; 4],
    f: &mut [HeldForces],
    si: [Side; 4],
    sj: [Side; 4],
    law: (&BondLaw, f64),
    dt: f64,
    out: &mut [BondForce],
) -> Option<i32> {
    // SAFETY: as the caller promises.
    unsafe { step_lanes::<__m256d>(&h, f, &si, &sj, law, dt, out) }
}

/// [`step2`] on `V::N` lanes (`h`, `si`, `sj` of that length).
#[inline(always)]
unsafe fn step_lanes<V: Lanes>(
    h: &[&Held],
    f: &mut [HeldForces],
    si: &[Side],
    sj: &[Side],
    (law, thickness): (&BondLaw, f64),
    dt: f64,
    out: &mut [BondForce],
) -> Option<i32> {
    // SAFETY: the lanes' instructions are enabled (callers).
    unsafe {
        let pair = |a: fn(&Side) -> f64| (V::from(|l| a(&si[l])), V::from(|l| a(&sj[l])));
        let (pix, pjx) = pair(|s| s.pos.x);
        let (piy, pjy) = pair(|s| s.pos.y);
        let (dx, dy) = (pjx.sub(pix), pjy.sub(piy));
        let d2 = dx.mul(dx).add(dy.mul(dy));
        let zero = V::splat(0.0);
        if zero.lt(d2).mask() != (1 << V::N) - 1 {
            return None;
        }
        // n = d (1/|d|), t = perp(n) = (−n_y, n_x) (negation flips the sign)
        let dist = d2.sqrt();
        let inv = V::splat(1.0).div(dist);
        let (nx, ny) = (dx.mul(inv), dy.mul(inv));
        let sign = V::splat(-0.0);
        let tx = ny.xor(sign);
        let c = consts_lanes::<V>(h, si, sj, law, thickness);
        // the lever arms d r_i/(r_i + r_j), d r_j/(r_i + r_j)
        let la = dist.mul(c.ci);
        let lb = dist.mul(c.cj);
        let (vix, vjx) = pair(|s| s.vel.x);
        let (viy, vjy) = pair(|s| s.vel.y);
        let (dvx, dvy) = (vix.sub(vjx), viy.sub(vjy));
        let (wi, wj) = pair(|s| s.omega);
        let vn = dvx.mul(nx).add(dvy.mul(ny));
        let vt = dvx.mul(tx).add(dvy.mul(nx)).add(wi.mul(la)).add(wj.mul(lb));
        // k̄_n A v_n Δt, k̄_s A v_t Δt, k̄_n I (ω_i − ω_j) Δt
        let dt = V::splat(dt);
        let inc = |k: V, v: V| k.mul(v).mul(dt);
        let old = |a: fn(&HeldForces) -> f64| V::from(|l| a(&f[l]));
        let fn_ = old(|f| f.0).add(inc(c.kn_a, vn));
        let fs = old(|f| f.1).sub(inc(c.ks_a, vt));
        let m = old(|f| f.2).sub(inc(c.kn_i, wi.sub(wj)));
        // f = n (−F_n) + t F_s; M_i = l_i F_s + M, M_j = l_j F_s − M
        let neg_fn = fn_.xor(sign);
        let fx = nx.mul(neg_fn).add(tx.mul(fs));
        let fy = ny.mul(neg_fn).add(nx.mul(fs));
        let ma = la.mul(fs).add(m);
        let mb = lb.mul(fs).sub(m);
        let intact = intact_lanes(h, &c, law, fn_, fs, m);
        let [fx, fy, ma, mb] = [fx, fy, ma, mb].map(|v| v.lanes());
        for (l, o) in out[..V::N].iter_mut().enumerate() {
            *o = BondForce {
                f: Vec2::new(fx[l], fy[l]),
                ma: ma[l],
                mb: mb[l],
            };
        }
        let [fn_, fs, m] = [fn_, fs, m].map(|v| v.lanes());
        for (l, f) in f[..V::N].iter_mut().enumerate() {
            if intact & (1 << l) != 0 {
                *f = (fn_[l], fs[l], m[l]);
            }
        }
        Some(intact)
    }
}

/// [`Consts`](super::Consts) in the lanes.
struct ConstsLanes<V> {
    ci: V,
    cj: V,
    kn_a: V,
    ks_a: V,
    kn_i: V,
    inv_a: V,
    r_over_i: V,
}

/// The constants of the bonds `h` between `si[l]` and `sj[l]`, with the
/// operations of [`Consts::new`](super::Consts::new) and
/// [`section`](super::section) in their order.
#[inline(always)]
unsafe fn consts_lanes<V: Lanes>(
    h: &[&Held],
    si: &[Side],
    sj: &[Side],
    law: &BondLaw,
    thickness: f64,
) -> ConstsLanes<V> {
    // SAFETY: the lanes' instructions are enabled (callers).
    unsafe {
        let r = V::from(|l| h[l].r);
        let (ri, rj) = (V::from(|l| si[l].radius), V::from(|l| sj[l].radius));
        let t = V::splat(thickness);
        // A = 2 R̄ t, I = (2/3) R̄³ t
        let a = V::splat(2.0).mul(r).mul(t);
        let inertia = V::splat(2.0 / 3.0).mul(r).mul(r).mul(r).mul(t);
        let rs = ri.add(rj);
        let (kn, ks) = (V::splat(law.kn), V::splat(law.ks));
        ConstsLanes {
            ci: ri.div(rs),
            cj: rj.div(rs),
            kn_a: kn.mul(a),
            ks_a: ks.mul(a),
            kn_i: kn.mul(inertia),
            inv_a: V::splat(1.0).div(a),
            r_over_i: r.div(inertia),
        }
    }
}

/// [`Held::intact`] in the lanes: bit l set when lane l's bond is.
#[inline(always)]
unsafe fn intact_lanes<V: Lanes>(
    h: &[&Held],
    c: &ConstsLanes<V>,
    law: &BondLaw,
    fn_: V,
    fs: V,
    m: V,
) -> i32 {
    // SAFETY: the lanes' instructions are enabled (callers).
    unsafe {
        let held = |a: fn(&Held) -> f32| V::from(|l| a(h[l]) as f64);
        let tol = V::splat(16.0 * f64::EPSILON);
        let neg = V::splat(-0.0);
        let abs = |v: V| neg.andnot(v);
        let sn = fn_.xor(neg).mul(c.inv_a);
        let sm = abs(m).mul(c.r_over_i);
        let tau = abs(fs).mul(c.inv_a);
        let friction = match law.shear {
            ShearStrength::Fixed(_) => V::splat(0.0),
            ShearStrength::Coulomb { tan_phi, .. } => fn_.mul(c.inv_a).mul(V::splat(tan_phi)),
        };
        let tau_c = held(|h| h.shear).add(friction);
        let sigma = sn.add(sm).add(tol.mul(abs(sn).add(sm)));
        let ok_t = sigma.lt(held(|h| h.tensile));
        let shear = tau.add(tol.mul(tau.add(abs(friction))));
        let ok_s = shear.lt(tau_c.mul(V::splat(1.0).sub(tol)));
        ok_t.and(ok_s).mask()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::bonds::{section, stresses};

    /// Random discs and bonds, `N` per case, stepped by `kernel` and by
    /// the scalar step: the lanes give bitwise the scalar step's forces
    /// (disc forces, moments, new bond forces) for every bond they find
    /// intact, leave the others' forces alone, and call no bond intact
    /// that the scalar step breaks. Fixed and cohesion–friction strengths,
    /// some bonds loaded to breakage.
    fn lanes_equal_the_scalar_step<const N: usize>(
        kernel: impl Fn(
            [&Held; N],
            &mut [HeldForces],
            [Side; N],
            [Side; N],
            (&BondLaw, f64),
            f64,
            &mut [BondForce],
        ) -> Option<i32>,
    ) {
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
            let si: [Side; N] = std::array::from_fn(|l| side(Vec2::new(5.0 * l as f64, 0.0)));
            let sj: [Side; N] =
                std::array::from_fn(|l| side(Vec2::new(5.0 * l as f64 + 2.0, 0.3 + l as f64)));
            let mut held = [Held::default(); N];
            let mut exact = [(0.0, 0.0); N];
            let mut f = [(0.0, 0.0, 0.0); N];
            for (l, h) in held.iter_mut().enumerate() {
                let radius = u(0.5, 1.0);
                let (a, i) = section(radius, thickness);
                let forces = (u(-100.0, 100.0), u(-100.0, 100.0), u(-50.0, 50.0));
                let (sigma, tau) = stresses(forces.0, forces.1, forces.2, radius, a, i);
                // strengths about the current stresses: some bonds break
                exact[l] = (sigma.abs() * u(0.8, 2.0), tau * u(0.8, 2.0));
                *h = Held::new((0, 0), radius, exact[l]);
                f[l] = forces;
            }
            let mut lanes_f = f;
            let mut out = [BondForce::default(); N];
            let hs = std::array::from_fn(|l| &held[l]);
            let intact = kernel(hs, &mut lanes_f, si, sj, (&law, thickness), dt, &mut out)
                .expect("distinct centres");
            for l in 0..N {
                let mut fl = f[l];
                let (bf, brk) =
                    held[l].step(l, &mut fl, &si[l], &sj[l], &law, &exact, thickness, dt);
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
            same > 500 * N && left > 250 * N && broke > 250 * N,
            "{same} {left} {broke}"
        );
    }

    #[test]
    fn two_lanes_equal_the_scalar_bond_step_bitwise() {
        lanes_equal_the_scalar_step::<2>(step2);
    }

    /// The four lanes of AVX2 (skipped on a processor without).
    #[test]
    fn four_lanes_equal_the_scalar_bond_step_bitwise() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2: the four-lane bond kernel is not tested here");
            return;
        }
        /// [`step4`] in an AVX2 function.
        #[target_feature(enable = "avx2")]
        fn avx2(
            h: [&Held; 4],
            f: &mut [HeldForces],
            si: [Side; 4],
            sj: [Side; 4],
            law: (&BondLaw, f64),
            dt: f64,
            out: &mut [BondForce],
        ) -> Option<i32> {
            // SAFETY: this function runs with AVX2 (checked above).
            unsafe { step4(h, f, si, sj, law, dt, out) }
        }
        // SAFETY: the processor has AVX2 (checked above).
        lanes_equal_the_scalar_step::<4>(|h, f, si, sj, law, dt, out| unsafe {
            avx2(h, f, si, sj, law, dt, out)
        });
    }
}
