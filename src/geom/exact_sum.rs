//! Exact sums of `f64`: the value is the correctly rounded sum of every
//! term, whatever their order or grouping. An assembly divided over ranks
//! sums its parts separately and merges them: with an exact sum the
//! result is bitwise that of the undivided assembly.
//!
//! Shewchuk's adaptive expansion (Shewchuk 1997, "Adaptive precision
//! floating-point arithmetic and fast robust geometric predicates"; the
//! algorithm of Python's `math.fsum`): the running sum is a short list of
//! non-overlapping partials, increasing in magnitude, whose exact sum is
//! the exact sum of the terms; each term is added by error-free
//! transformations (two-sum). The final rounding is round-half-even of
//! that exact value.

/// An exact sum of `f64` terms ([module docs](self)).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExactSum {
    /// Non-overlapping partials, increasing in magnitude, all finite.
    partials: Vec<f64>,
    /// The sum of the non-finite terms (and of an overflow): NaN, ±∞ or 0.
    special: f64,
}

impl ExactSum {
    /// Add the term `x` (exactly).
    pub fn add(&mut self, mut x: f64) {
        if !x.is_finite() {
            self.special += x;
            return;
        }
        let mut i = 0;
        for k in 0..self.partials.len() {
            let mut y = self.partials[k];
            if x.abs() < y.abs() {
                std::mem::swap(&mut x, &mut y);
            }
            let hi = x + y;
            if !hi.is_finite() {
                // an overflow: the sum is ±∞ in any order
                self.special += hi;
                self.partials.truncate(i);
                return;
            }
            let lo = y - (hi - x);
            if lo != 0.0 {
                self.partials[i] = lo;
                i += 1;
            }
            x = hi;
        }
        self.partials.truncate(i);
        self.partials.push(x);
    }

    /// Add every term of `other` (exactly).
    pub fn merge(&mut self, other: &ExactSum) {
        self.special += other.special;
        for &x in &other.partials {
            self.add(x);
        }
    }

    /// The exact sum, rounded to the nearest `f64` (ties to even); NaN or
    /// ±∞ if a term was.
    pub fn value(&self) -> f64 {
        if self.special != 0.0 || self.special.is_nan() {
            return self.special;
        }
        let p = &self.partials;
        let Some(mut n) = p.len().checked_sub(1) else {
            return 0.0;
        };
        let mut hi = p[n];
        let mut lo = 0.0;
        while n > 0 {
            let x = hi;
            n -= 1;
            let y = p[n];
            hi = x + y;
            lo = y - (hi - x);
            if lo != 0.0 {
                break;
            }
        }
        // half-way cases: the partials below decide the direction
        if n > 0 && (lo < 0.0 && p[n - 1] < 0.0 || lo > 0.0 && p[n - 1] > 0.0) {
            let y = lo * 2.0;
            let x = hi + y;
            if y == x - hi {
                hi = x;
            }
        }
        hi
    }

    /// The state as `f64`s, for another process ([`from_parts`](Self::from_parts)).
    pub fn parts(&self) -> Vec<f64> {
        let mut v = Vec::with_capacity(self.partials.len() + 1);
        v.push(self.special);
        v.extend_from_slice(&self.partials);
        v
    }

    /// The sum whose [`parts`](Self::parts) these are.
    pub fn from_parts(v: &[f64]) -> ExactSum {
        ExactSum {
            special: v.first().copied().unwrap_or(0.0),
            partials: v.get(1..).unwrap_or_default().to_vec(),
        }
    }
}

impl FromIterator<f64> for ExactSum {
    fn from_iter<I: IntoIterator<Item = f64>>(it: I) -> Self {
        let mut s = ExactSum::default();
        it.into_iter().for_each(|x| s.add(x));
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Terms k·2^e with small integers k: their sum is exact in i128
    /// fixed point (the reference).
    fn dyadic(seed: u64, n: usize) -> (Vec<f64>, f64) {
        let mut s = seed;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        let mut exact: i128 = 0;
        let terms: Vec<f64> = (0..n)
            .map(|_| {
                let k = (next() % 2_000_001) as i64 - 1_000_000;
                let e = (next() % 40) as i32; // 2^(e - 60) with e < 40
                exact += (k as i128) << e;
                k as f64 * 2f64.powi(e - 60)
            })
            .collect();
        // exact < 2^61: a correctly rounded conversion
        (terms, exact as f64 * 2f64.powi(-60))
    }

    #[test]
    fn the_sum_is_exact_and_independent_of_order_and_grouping() {
        for seed in 1..20 {
            let (mut terms, want) = dyadic(seed, 1000);
            let s: ExactSum = terms.iter().copied().collect();
            assert_eq!(s.value(), want);
            terms.reverse();
            let (a, b) = terms.split_at(337);
            let mut sa: ExactSum = a.iter().copied().collect();
            sa.merge(&ExactSum::from_parts(
                &b.iter().copied().collect::<ExactSum>().parts(),
            ));
            assert_eq!(sa.value().to_bits(), want.to_bits());
        }
    }

    #[test]
    fn cancellation_and_ties_round_correctly() {
        let v = |t: &[f64]| t.iter().copied().collect::<ExactSum>().value();
        assert_eq!(v(&[1e100, 1.0, -1e100]), 1.0);
        assert_eq!(v(&[]), 0.0);
        // 1 + 2^-53 is half-way between 1 and its successor: to even (1);
        // a further tiny term decides it upwards
        let (u, tiny) = (2f64.powi(-53), 2f64.powi(-80));
        assert_eq!(v(&[1.0, u]), 1.0);
        assert_eq!(v(&[1.0, u, tiny]), 1.0 + 2.0 * u);
        assert_eq!(v(&[tiny, u, 1.0]), 1.0 + 2.0 * u);
        // a naive sum gets 0.1 + 0.2 - 0.3 wrong; the exact value of these
        // doubles is 2^-55 + 2^-56 + ... = 2.7755575615628914e-17
        assert_eq!(v(&[0.1, 0.2, -0.3]), 2.7755575615628914e-17);
        assert!(v(&[1.0, f64::NAN]).is_nan());
        assert_eq!(v(&[f64::MAX, f64::MAX, 1.0]), f64::INFINITY);
    }
}
