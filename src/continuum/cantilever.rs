//! Deflection of a cantilever under a distributed load given bin by bin
//! (piecewise constant): Euler–Bernoulli bending plus Timoshenko's shear
//! deflection. Used to check a wall's computed deflection under the earth
//! pressure measured on it (`geotech::retaining`).
//!
//! The beam runs along `s ∈ [0, L]` from the clamp (`s = 0`). A lateral
//! load `q(s)` (force per length, in the direction of the deflection) and
//! a distributed moment `m(s)` (per length, positive in the sense that
//! bends the beam the same way as a positive `q` above the point) give the
//! bending moment `M(s) = ∫_s^L [q(ξ)(ξ − s) + m(ξ)] dξ` and the shear
//! force `V(s) = ∫_s^L q(ξ) dξ`; the free end deflects by
//! `w(L) = ∫_0^L (L − s) M(s)/EI ds + ∫_0^L V(s)/(κGA) ds`
//! (Timoshenko & Gere, *Mechanics of Materials*, the unit-load method).

/// One bin of the load: `q` and `m` constant on `[from, to]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadBin {
    /// Start of the bin (distance from the clamp).
    pub from: f64,
    /// End of the bin.
    pub to: f64,
    /// Lateral load per length.
    pub q: f64,
    /// Distributed moment per length.
    pub m: f64,
}

/// The free end's deflection of a cantilever of length `length` under
/// `bins` (outside `[0, L]` ignored), bending stiffness `ei` and shear
/// stiffness `kga` (`f64::INFINITY`: Euler–Bernoulli): `(bending, shear)`.
/// Integrated exactly for piecewise-constant loads (M is piecewise
/// quadratic; Simpson's rule on each piece of a fine subdivision that
/// contains every bin edge).
pub fn tip_deflection(length: f64, bins: &[LoadBin], ei: f64, kga: f64) -> (f64, f64) {
    // break points: bin edges inside [0, L]
    let mut pts: Vec<f64> = vec![0.0, length];
    for b in bins {
        for s in [b.from, b.to] {
            if s > 0.0 && s < length {
                pts.push(s);
            }
        }
    }
    pts.sort_by(f64::total_cmp);
    pts.dedup();
    let moment = |s: f64| -> (f64, f64) {
        let (mut m, mut v) = (0.0, 0.0);
        for b in bins {
            let (a, c) = (b.from.max(s).max(0.0), b.to.min(length));
            if c <= a {
                continue;
            }
            // ∫_a^c q (ξ − s) dξ + m (c − a)
            m += b.q * 0.5 * ((c - s).powi(2) - (a - s).powi(2)) + b.m * (c - a);
            v += b.q * (c - a);
        }
        (m, v)
    };
    let (mut bend, mut shear) = (0.0, 0.0);
    for w in pts.windows(2) {
        let (a, c) = (w[0], w[1]);
        let mid = 0.5 * (a + c);
        let (ma, va) = moment(a);
        let (mm, vm) = moment(mid);
        let (mc, vc) = moment(c);
        // (L − s) M(s) is cubic on the piece, V linear: Simpson is exact
        let h = (c - a) / 6.0;
        bend += h * ((length - a) * ma + 4.0 * (length - mid) * mm + (length - c) * mc);
        shear += h * (va + 4.0 * vm + vc);
    }
    (bend / ei, if kga.is_finite() { shear / kga } else { 0.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_and_triangular_loads_match_the_formulas() {
        let (l, ei, kga) = (2.0, 3.0e4, 5.0e5);
        // uniform q in 7 bins: qL⁴/(8EI), qL²/(2κGA)
        let q = 10.0;
        let bins: Vec<LoadBin> = (0..7)
            .map(|k| LoadBin {
                from: k as f64 * l / 7.0,
                to: (k + 1) as f64 * l / 7.0,
                q,
                m: 0.0,
            })
            .collect();
        let (b, s) = tip_deflection(l, &bins, ei, kga);
        assert!((b / (q * l.powi(4) / (8.0 * ei)) - 1.0).abs() < 1e-12);
        assert!((s / (q * l * l / (2.0 * kga)) - 1.0).abs() < 1e-12);
        // a point load P at the tip as a thin bin: PL³/(3EI)
        let p = 5.0;
        let e = 1e-7;
        let (b, _) = tip_deflection(
            l,
            &[LoadBin {
                from: l - e,
                to: l,
                q: p / e,
                m: 0.0,
            }],
            ei,
            f64::INFINITY,
        );
        assert!((b / (p * l.powi(3) / (3.0 * ei)) - 1.0).abs() < 1e-6);
        // a uniform moment m: M(s) = m (L − s), w = m L³/(3EI)
        let (b, s) = tip_deflection(
            l,
            &[LoadBin {
                from: 0.0,
                to: l,
                q: 0.0,
                m: 2.0,
            }],
            ei,
            kga,
        );
        assert!((b / (2.0 * l.powi(3) / (3.0 * ei)) - 1.0).abs() < 1e-12 && s == 0.0);
        // triangular q = q0 (1 − s/L) (earth pressure, max at the clamp) in
        // many bins: q0 L⁴/(30 EI) to O(1/n²)
        let n = 400;
        let bins: Vec<LoadBin> = (0..n)
            .map(|k| {
                let (a, c) = (k as f64 * l / n as f64, (k + 1) as f64 * l / n as f64);
                LoadBin {
                    from: a,
                    to: c,
                    q: q * (1.0 - 0.5 * (a + c) / l),
                    m: 0.0,
                }
            })
            .collect();
        let (b, _) = tip_deflection(l, &bins, ei, f64::INFINITY);
        assert!((b / (q * l.powi(4) / (30.0 * ei)) - 1.0).abs() < 1e-5);
    }
}
