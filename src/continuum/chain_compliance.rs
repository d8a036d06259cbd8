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
//! whole boundary can follow the loads.

use super::Row;
use crate::geom::Vec2;
use crate::sparse::{Cholesky, SparseError};
use rayon::prelude::*;

/// Columns computed per parallel task (a fixed block: the result does not
/// depend on the number of threads).
const BLOCK: usize = 8;

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
}

impl ChainCompliance {
    /// No column yet, for `n` chain points.
    pub fn new(n: usize) -> Self {
        ChainCompliance {
            n,
            cols: vec![Vec::new(); n],
        }
    }

    /// Number of columns computed (for the memory report).
    pub fn computed(&self) -> usize {
        self.cols.iter().filter(|c| !c.is_empty()).count()
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
        let cols: Vec<Vec<f64>> = new
            .par_chunks(BLOCK)
            .map(|chunk| -> Result<Vec<Vec<f64>>, SparseError> {
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
                        out
                    })
                    .collect())
            })
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .flatten()
            .collect();
        for (b, col) in new.into_iter().zip(cols) {
            self.cols[b] = col;
        }
        Ok(())
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
