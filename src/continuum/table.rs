//! Piecewise-linear tables in time, `[[t₀, v₀], [t₁, v₁], …]`: the value
//! of a load multiplier, a prescribed displacement or a prescribed
//! velocity at time t (manual: scenario format, "Tables in time").
//!
//! Convention: the times are non-decreasing (two equal times make a jump:
//! at the jump the later value holds); before `t₀` the value is `v₀`,
//! after the last time the last value (held constant). The same
//! convention as a wall's `history` ([`crate::dem::walls`]), which is
//! also constant outside its points.

use serde::Deserialize;

/// A piecewise-linear function of time through `[t, v]` points (module
/// docs). Check it with [`Table::problem`] before use.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(transparent)]
pub struct Table {
    /// The points `[t, v]`, t non-decreasing.
    pub points: Vec<[f64; 2]>,
}

impl Table {
    /// A table through `points`.
    pub fn new(points: Vec<[f64; 2]>) -> Self {
        Table { points }
    }

    /// What is wrong with the table, if anything: empty, a non-finite
    /// number, or times that decrease.
    pub fn problem(&self) -> Option<String> {
        if self.points.is_empty() {
            return Some("an empty table: give at least one `[t, value]` point".into());
        }
        if let Some(k) = self
            .points
            .iter()
            .position(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return Some(format!(
                "point {k} ({:?}) is not two finite numbers",
                self.points[k]
            ));
        }
        if let Some(k) = (1..self.points.len()).find(|&k| self.points[k][0] < self.points[k - 1][0])
        {
            return Some(format!(
                "the times must be non-decreasing: point {k} (t = {}) comes after t = {}",
                self.points[k][0],
                self.points[k - 1][0]
            ));
        }
        None
    }

    /// A jump: the first two consecutive points at most `dt` apart in
    /// time (at the same time with `dt` = 0) whose values differ, as
    /// `(t, from, to)`. A prescribed displacement that jumps has an
    /// infinite velocity (or one step's worth of it): no time step can
    /// follow it.
    pub fn jump(&self, dt: f64) -> Option<(f64, f64, f64)> {
        self.points.windows(2).find_map(|w| {
            let ([t0, v0], [t1, v1]) = (w[0], w[1]);
            (t1 - t0 <= dt && v1 != v0).then_some((t0, v0, v1))
        })
    }

    /// The index of the segment `[t_k, t_{k+1})` holding `t`, or `None`
    /// before the first or at/after the last point.
    fn segment(&self, t: f64) -> Option<usize> {
        let p = &self.points;
        // first point with t_k > t
        let k = p.partition_point(|q| q[0] <= t);
        (k > 0 && k < p.len()).then(|| k - 1)
    }

    /// The value at time `t` (module docs).
    pub fn value(&self, t: f64) -> f64 {
        let p = &self.points;
        match self.segment(t) {
            Some(k) => {
                let ([t0, v0], [t1, v1]) = (p[k], p[k + 1]);
                v0 + (v1 - v0) * ((t - t0) / (t1 - t0))
            }
            None if p.first().is_some_and(|q| t < q[0]) => p[0][1],
            None => p.last().map_or(0.0, |q| q[1]),
        }
    }

    /// `∫₀ᵗ value(s) ds` exactly (the table is piecewise linear, so the
    /// integral is piecewise quadratic): a prescribed velocity integrated
    /// into a displacement. Negative `t` integrates backwards.
    pub fn integral(&self, t: f64) -> f64 {
        self.antiderivative(t) - self.antiderivative(0.0)
    }

    /// An antiderivative `A(t)` with `A(t₀) = 0`.
    fn antiderivative(&self, t: f64) -> f64 {
        let p = &self.points;
        let Some(first) = p.first() else {
            return 0.0;
        };
        if t <= first[0] {
            return first[1] * (t - first[0]);
        }
        let mut acc = 0.0;
        for w in p.windows(2) {
            let ([t0, v0], [t1, v1]) = (w[0], w[1]);
            if t < t1 {
                let s = t - t0;
                let slope = (v1 - v0) / (t1 - t0);
                return acc + v0 * s + 0.5 * slope * s * s;
            }
            acc += 0.5 * (v0 + v1) * (t1 - t0);
        }
        let last = p[p.len() - 1];
        acc + last[1] * (t - last[0])
    }

    /// Largest `|value|` over the table.
    pub fn max_abs(&self) -> f64 {
        self.points.iter().map(|p| p[1].abs()).fold(0.0, f64::max)
    }

    /// The last time of the table.
    pub fn end(&self) -> f64 {
        self.points.last().map_or(0.0, |p| p[0])
    }
}

/// A load that changes in time: a nodal load vector (sparse, `(DOF,
/// value)`) times `table(t)` — a traction or point load with a `table`.
#[derive(Debug, Clone, PartialEq)]
pub struct TimedLoad {
    /// The multiplier.
    pub table: Table,
    /// The load at multiplier 1, `(DOF, value)`.
    pub dofs: Vec<(usize, f64)>,
}

impl TimedLoad {
    /// A timed load from a dense vector (its non-zero entries).
    pub fn from_dense(table: Table, f: &[f64]) -> Self {
        let dofs = f
            .iter()
            .enumerate()
            .filter(|(_, v)| **v != 0.0)
            .map(|(i, v)| (i, *v))
            .collect();
        TimedLoad { table, dofs }
    }
    /// `f += table(t) · F`.
    pub fn add_to(&self, f: &mut [f64], t: f64) {
        let s = self.table.value(t);
        for &(i, v) in &self.dofs {
            f[i] += s * v;
        }
    }
    /// `F · u` at multiplier 1.
    pub fn dot(&self, u: &[f64]) -> f64 {
        self.dofs.iter().map(|&(i, v)| v * u[i]).sum()
    }
    /// `Σ_k ½ (s_k(t₀) + s_k(t₁)) F_k · u`: with `u` the states after and
    /// before a step from `t₀` to `t₁`, the difference of two calls is the
    /// trapezoidal work of the loads over the step (exact for Newmark
    /// γ = ½, β = ¼, whose energy balance is `Δ(T + V) = ½ (Fₙ + Fₙ₊₁) ·
    /// ΔU`).
    pub fn half_sum(loads: &[TimedLoad], u: &[f64], t0: f64, t1: f64) -> f64 {
        loads
            .iter()
            .map(|l| 0.5 * (l.table.value(t0) + l.table.value(t1)) * l.dot(u))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_hold_outside_and_interpolate_inside() {
        let t = Table::new(vec![[0.1, 1.0], [0.3, 3.0], [0.3, -1.0], [0.5, 0.0]]);
        assert_eq!(t.problem(), None);
        assert_eq!(t.value(-1.0), 1.0);
        assert_eq!(t.value(0.1), 1.0);
        assert!((t.value(0.2) - 2.0).abs() < 1e-15);
        // at a jump the later value holds
        assert_eq!(t.value(0.3), -1.0);
        assert!((t.value(0.4) + 0.5).abs() < 1e-15);
        assert_eq!(t.value(0.5), 0.0);
        assert_eq!(t.value(9.0), 0.0);
    }

    #[test]
    fn the_integral_is_exact() {
        let t = Table::new(vec![[0.0, -0.1], [0.2, 0.0], [0.4, 0.2]]);
        // ∫₀^0.2 = −0.01; ∫_0.2^0.4 = 0.02; then 0.2 per second
        assert!((t.integral(0.2) + 0.01).abs() < 1e-16);
        assert!((t.integral(0.4) - 0.01).abs() < 1e-16);
        assert!((t.integral(1.4) - 0.21).abs() < 1e-15);
        // inside a segment: −0.1 s + ½ (0.5) s²
        let s: f64 = 0.1;
        assert!((t.integral(s) - (-0.1 * s + 0.25 * s * s)).abs() < 1e-17);
        // before the first point the first value holds
        let late = Table::new(vec![[1.0, 2.0], [2.0, 2.0]]);
        assert!((late.integral(0.5) - 1.0).abs() < 1e-15);
        assert!((late.integral(3.0) - 6.0).abs() < 1e-15);
    }

    #[test]
    fn bad_tables_are_named() {
        assert!(Table::new(vec![]).problem().unwrap().contains("empty"));
        let nan = Table::new(vec![[0.0, f64::NAN]]);
        assert!(nan.problem().unwrap().contains("finite"));
        let unsorted = Table::new(vec![[0.0, 0.0], [0.2, 1.0], [0.1, 2.0]]);
        assert!(unsorted.problem().unwrap().contains("non-decreasing"));
    }
}
