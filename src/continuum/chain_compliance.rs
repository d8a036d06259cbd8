//! The compliance among the points of a body's contact chains for one
//! body step: `S_ab = φ_aᵀ A⁻¹ φ_b` (2 × 2 blocks), the displacement of
//! chain point `a` at the end of a Newmark step (`A = α₁M + α₄C + K̄`,
//! Eq. 49 per E8) under a unit point load at chain point `b` (Eq. 46, E7,
//! through the rows `φ_J` of the chain points).
//!
//! The compliant sub-cycled scheme ([`crate::coupling`]) lets the contact
//! boundary respond to the discs' forces through this compliance in every
//! DEM step of a body step. Only the columns of chain points that carry a
//! load are ever needed: each is computed at its first use (two solves),
//! then kept. A column holds the response of every chain point, so the
//! whole boundary can follow the loads. When those of all the chain
//! points would fit in [`FULL_BYTES`], the responses of every DOF
//! (`A⁻¹ φ_b` itself) are kept too: the body step then ends with their
//! sum instead of a solve ([`ChainCompliance::add_response`]).

use super::Row;
use crate::geom::Vec2;
use crate::sparse::{Cholesky, SparseError};
use rayon::prelude::*;

/// Columns computed per parallel task (a fixed block: the result does not
/// depend on the number of threads).
const BLOCK: usize = 8;

/// A new column: the chain points' responses and (within [`FULL_BYTES`])
/// the DOF responses.
type Column = (Vec<f64>, Vec<f64>);

/// Memory for the DOF responses `A⁻¹ φ_b` of every chain point of a body
/// (bytes): a body whose would need more keeps only the chain points'
/// responses.
pub const FULL_BYTES: usize = 128 << 20;

/// The columns of `S` computed so far, chain points numbered chain after
/// chain ([`ChainCompliance::new`]).
#[derive(Debug, Default)]
pub struct ChainCompliance {
    /// Number of chain points.
    n: usize,
    /// Per chain point `b`: empty, or its two columns: the responses
    /// `(u_x, u_y)` of every chain point `a` to a unit `x` load at `b`
    /// (`2a`, `2a + 1`), then to a unit `y` load (`2n + 2a`, `2n + 2a + 1`).
    cols: Vec<Vec<f64>>,
    /// Per chain point `b`: empty, or `A⁻¹ φ_b` at every DOF for a unit
    /// `x` load, then for a unit `y` load (within [`FULL_BYTES`]).
    full: Vec<Vec<f64>>,
}

impl ChainCompliance {
    /// No column yet, for `n` chain points.
    pub fn new(n: usize) -> Self {
        ChainCompliance {
            n,
            cols: vec![Vec::new(); n],
            full: vec![Vec::new(); n],
        }
    }

    /// Compute the columns of the chain points `points` not known yet:
    /// `A⁻¹ φ_b` for both directions by `factor` (no load on `imposed`
    /// DOFs), read at every chain point through `rows` (chain points in
    /// order).
    pub fn ensure(
        &mut self,
        points: &[usize],
        rows: &[&Row],
        imposed: &[bool],
        factor: &Cholesky,
    ) -> Result<(), SparseError> {
        let mut new: Vec<usize> = points
            .iter()
            .copied()
            .filter(|&b| self.cols[b].is_empty())
            .collect();
        if new.is_empty() {
            return Ok(());
        }
        new.sort_unstable();
        new.dedup();
        let dofs = factor.n();
        let n = self.n;
        // decided by the sizes alone, not by the columns made so far: a run
        // restarted from a checkpoint takes the same path
        let keep = 2 * dofs * n * std::mem::size_of::<f64>() <= FULL_BYTES;
        let cols: Vec<Column> = new
            .par_chunks(BLOCK)
            .map(|chunk| -> Result<Vec<Column>, SparseError> {
                let k = 2 * chunk.len();
                let mut rhs = vec![0.0; dofs * k];
                for (c, &b) in chunk.iter().enumerate() {
                    for a in 0..2 {
                        let col = &mut rhs[(2 * c + a) * dofs..(2 * c + a + 1) * dofs];
                        for &(j, phi) in rows[b] {
                            let i = 2 * j as usize + a;
                            if !imposed.get(i).copied().unwrap_or(false) {
                                col[i] += phi;
                            }
                        }
                    }
                }
                factor.solve_columns(&mut rhs, k)?;
                Ok(chunk
                    .iter()
                    .enumerate()
                    .map(|(c, _)| {
                        let mut out = Vec::with_capacity(4 * n);
                        for a in 0..2 {
                            let x = &rhs[(2 * c + a) * dofs..(2 * c + a + 1) * dofs];
                            for row in rows {
                                let u = super::interpolate(row, x);
                                out.extend([u.x, u.y]);
                            }
                        }
                        let both = &rhs[2 * c * dofs..(2 * c + 2) * dofs];
                        (out, if keep { both.to_vec() } else { Vec::new() })
                    })
                    .collect())
            })
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .flatten()
            .collect();
        for (b, (col, full)) in new.into_iter().zip(cols) {
            self.cols[b] = col;
            self.full[b] = full;
        }
        Ok(())
    }

    /// `u += Σ_b A⁻¹ φ_b f_b` over the `loads` `(b, f_b)`, in their order,
    /// when every one of them has its DOF responses; false (and `u`
    /// untouched) otherwise. The same as a solve of `A Δu = Σ_b φ_b f_b`
    /// to round-off.
    pub fn add_response(&self, loads: &[(usize, Vec2)], u: &mut [f64]) -> bool {
        if loads.iter().any(|&(b, _)| self.full[b].is_empty()) {
            return false;
        }
        let dofs = u.len();
        for &(b, f) in loads {
            let (x, y) = self.full[b].split_at(dofs);
            for ((ui, xi), yi) in u.iter_mut().zip(x).zip(y) {
                *ui += f.x * xi + f.y * yi;
            }
        }
        true
    }

    /// Is the column of chain point `b` known?
    pub fn has(&self, b: usize) -> bool {
        !self.cols[b].is_empty()
    }

    /// The block `S_ab` (row-major: `[xx, xy, yx, yy]`, the `x`/`y`
    /// displacement of `a` under a unit `x`/`y` load at `b`); the column of
    /// `b` must be known.
    #[inline]
    pub fn block(&self, a: usize, b: usize) -> [f64; 4] {
        let c = &self.cols[b];
        let n2 = 2 * self.n;
        [c[2 * a], c[n2 + 2 * a], c[2 * a + 1], c[n2 + 2 * a + 1]]
    }

    /// `Σ_b S_ab f_b` at chain point `a` over the `loads` `(b, f_b)`, added
    /// in their order (the columns must be known).
    pub fn response_at(&self, a: usize, loads: &[(usize, Vec2)]) -> Vec2 {
        let mut r = Vec2::ZERO;
        for &(b, f) in loads {
            let k = self.block(a, b);
            r.x += k[0] * f.x + k[1] * f.y;
            r.y += k[2] * f.x + k[3] * f.y;
        }
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::tests::lap;

    /// The body step's end by the kept responses equals a solve of the
    /// same loads (imposed DOFs unloaded), to round-off.
    #[test]
    fn the_sum_of_kept_responses_is_the_solve_of_the_loads() {
        let dofs = 60;
        let mut factor = Cholesky::factor(&lap(dofs)).unwrap();
        // three chain points on nodes 3–4, 10–11, 20 (DOFs 2j, 2j + 1)
        let rows: Vec<Row> = vec![
            vec![(3, 0.25), (4, 0.75)],
            vec![(10, 0.5), (11, 0.5)],
            vec![(20, 1.0)],
        ];
        let mut imposed = vec![false; dofs];
        imposed[22] = true;
        let refs: Vec<&Row> = rows.iter().collect();
        let mut s = ChainCompliance::new(3);
        s.ensure(&[0, 2], &refs, &imposed, &factor).unwrap();
        let loads = [(2, Vec2::new(-3.0, 2.0)), (0, Vec2::new(1.5, 0.5))];
        let mut u = vec![0.25; dofs];
        assert!(s.add_response(&loads, &mut u));
        let mut f = vec![0.0; dofs];
        for &(b, g) in &loads {
            for &(j, phi) in &rows[b] {
                for (i, c) in [(2 * j as usize, g.x), (2 * j as usize + 1, g.y)] {
                    if !imposed[i] {
                        f[i] += phi * c;
                    }
                }
            }
        }
        factor.solve_in_place(&mut f);
        for (a, b) in u.iter().zip(&f) {
            assert!((a - 0.25 - b).abs() <= 1e-14 * (1.0 + b.abs()), "{a} {b}");
        }
        // a load whose column is unknown: not by the responses
        assert!(!s.add_response(&[(1, Vec2::new(1.0, 0.0))], &mut u));
    }
}
