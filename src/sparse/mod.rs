//! Symmetric sparse matrices stored as their lower triangle in CSC form, and
//! their sparse Cholesky factor (faer; AMD or METIS nested-dissection ordering), factored once and
//! solved many times without allocating.
//!
//! Shared by the EFG body and (later) the bilinear FE body: every operator of
//! one body (K̄, M, C) lives on one [`Pattern`], so that the Newmark matrix
//! `α₁M + α₄C + K̄` is a value-wise linear combination.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;
use std::sync::Arc;

mod split_solve;
use split_solve::SplitSolve;

/// Errors of the sparse linear algebra.
#[derive(Debug, thiserror::Error)]
pub enum SparseError {
    /// Cholesky met a non-positive pivot (its column, in the fill-reducing
    /// order): the matrix is singular or indefinite.
    #[error(
        "the matrix is not positive definite (pivot {0}); check the boundary conditions (is the body fixed somewhere?) and the material"
    )]
    NotPositiveDefinite(usize),
    /// Any other failure reported by faer.
    #[error("sparse factorisation failed: {0}")]
    Faer(String),
    /// [`SymCsc::combine`] of matrices on different patterns.
    #[error("matrices on different sparsity patterns cannot be combined")]
    PatternMismatch,
}

/// The sparsity pattern of the lower triangle of a symmetric `n × n` matrix
/// (CSC: column `j` holds rows `row_idx[col_ptr[j]..col_ptr[j+1]]`, sorted,
/// the first one being `j` itself).
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    /// Order of the matrix.
    pub n: usize,
    /// Column starts into `row_idx`, `n + 1` entries.
    pub col_ptr: Vec<usize>,
    /// Row of each stored entry.
    pub row_idx: Vec<usize>,
}

impl Pattern {
    /// Stored entries (lower triangle with the diagonal).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Both triangles by rows, of the stored entries `k` = `(i, j)` that
    /// `keep(k, i, j)` accepts: `(j, k)` in row `i` and, off the diagonal,
    /// its mirror `(i, k)` in row `j`. Returns the row starts (`n + 1`),
    /// each entry's column and its place `k` in the lower-triangle storage;
    /// every row's columns ascending (columns are visited in order).
    fn by_rows(
        &self,
        keep: impl Fn(usize, usize, usize) -> bool,
    ) -> (Vec<usize>, Vec<u32>, Vec<usize>) {
        let n = self.n;
        let entries = || {
            (0..n).flat_map(move |j| {
                (self.col_ptr[j]..self.col_ptr[j + 1]).map(move |k| (k, self.row_idx[k], j))
            })
        };
        let mut start = vec![0usize; n + 1];
        for (k, i, j) in entries() {
            if keep(k, i, j) {
                start[i + 1] += 1;
                if i != j {
                    start[j + 1] += 1;
                }
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let (mut col, mut pos) = (vec![0u32; start[n]], vec![0usize; start[n]]);
        let mut at = start.clone();
        for (k, i, j) in entries() {
            if keep(k, i, j) {
                (col[at[i]], pos[at[i]]) = (j as u32, k);
                at[i] += 1;
                if i != j {
                    (col[at[j]], pos[at[j]]) = (i as u32, k);
                    at[j] += 1;
                }
            }
        }
        (start, col, pos)
    }
    fn faer(&self) -> SymbolicSparseColMatRef<'_, usize> {
        // SAFETY: built sorted and in bounds by the assembler; checked in debug builds.
        debug_assert!(self.check());
        unsafe {
            SymbolicSparseColMatRef::new_unchecked(
                self.n,
                self.n,
                &self.col_ptr,
                None,
                &self.row_idx,
            )
        }
    }
    /// Invariants: monotone `col_ptr`, rows sorted, unique, ≥ the column, < n.
    pub fn check(&self) -> bool {
        if self.col_ptr.len() != self.n + 1 || self.col_ptr[self.n] != self.row_idx.len() {
            return false;
        }
        (0..self.n).all(|j| {
            let r = &self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]];
            r.first() == Some(&j)
                && r.windows(2).all(|w| w[0] < w[1])
                && r.iter().all(|&i| i < self.n)
        })
    }
}

/// A symmetric matrix: lower-triangle values on a shared [`Pattern`].
#[derive(Debug, Clone)]
pub struct SymCsc {
    /// The shared sparsity pattern.
    pub pattern: Arc<Pattern>,
    /// Value of each stored entry, in pattern order.
    pub values: Vec<f64>,
}

impl SymCsc {
    /// The zero matrix on `pattern`.
    pub fn zeros(pattern: Arc<Pattern>) -> Self {
        let values = vec![0.0; pattern.nnz()];
        SymCsc { pattern, values }
    }
    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.pattern.n
    }
    /// `a·self + b·other` (same pattern).
    pub fn combine(&self, a: f64, other: &SymCsc, b: f64) -> Result<SymCsc, SparseError> {
        if !Arc::ptr_eq(&self.pattern, &other.pattern) && self.pattern != other.pattern {
            return Err(SparseError::PatternMismatch);
        }
        let values = self
            .values
            .iter()
            .zip(&other.values)
            .map(|(x, y)| a * x + b * y)
            .collect();
        Ok(SymCsc {
            pattern: self.pattern.clone(),
            values,
        })
    }
    /// `self · s`.
    pub fn scaled(&self, s: f64) -> SymCsc {
        SymCsc {
            pattern: self.pattern.clone(),
            values: self.values.iter().map(|v| v * s).collect(),
        }
    }
    /// `y += A x` for the full symmetric matrix. Serial, fixed order.
    pub fn mul_add(&self, x: &[f64], y: &mut [f64]) {
        let p = &*self.pattern;
        for j in 0..p.n {
            let (s, e) = (p.col_ptr[j], p.col_ptr[j + 1]);
            let xj = x[j];
            // diagonal first
            let mut acc = self.values[s] * xj;
            for k in s + 1..e {
                let i = p.row_idx[k];
                let a = self.values[k];
                y[i] += a * xj;
                acc += a * x[i];
            }
            y[j] += acc;
        }
    }
    /// `xᵀ A x`.
    pub fn quad_form(&self, x: &[f64]) -> f64 {
        let p = &*self.pattern;
        let mut q = 0.0;
        for j in 0..p.n {
            let (s, e) = (p.col_ptr[j], p.col_ptr[j + 1]);
            let mut off = 0.0;
            for k in s + 1..e {
                off += self.values[k] * x[p.row_idx[k]];
            }
            q += x[j] * (self.values[s] * x[j] + 2.0 * off);
        }
        q
    }
    /// Entry `(i, j)` of the symmetric matrix (zero if not stored).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        let p = &*self.pattern;
        let rows = &p.row_idx[p.col_ptr[c]..p.col_ptr[c + 1]];
        match rows.binary_search(&r) {
            Ok(k) => self.values[p.col_ptr[c] + k],
            Err(_) => 0.0,
        }
    }
    fn faer(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(self.pattern.faer(), &self.values)
    }
}

/// A symmetric matrix by rows, both triangles, its nonzero entries only:
/// products `y += A x` row by row on the threads, each row summed in the
/// order of [`SymCsc::mul_add`] (bitwise its result, on any number of
/// threads).
#[derive(Debug, Clone)]
pub struct SymRows {
    start: Vec<usize>,
    /// Per row, its first entry on or right of the diagonal.
    mid: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
}

/// Rows per task of [`SymRows::mul_add`]'s parallel loop.
const ROWS_PER_TASK: usize = 512;

impl SymRows {
    /// The nonzero entries of `a` (exact zeros of its pattern dropped:
    /// a mass matrix on a stiffness pattern has no `x`–`y` couplings).
    pub fn new(a: &SymCsc) -> Self {
        let p = &*a.pattern;
        let (start, col, pos) = p.by_rows(|k, _, _| a.values[k] != 0.0);
        let val = pos.iter().map(|&k| a.values[k]).collect();
        let mid = (0..p.n)
            .map(|i| start[i] + col[start[i]..start[i + 1]].partition_point(|&c| (c as usize) < i))
            .collect();
        SymRows {
            start,
            mid,
            col,
            val,
        }
    }

    /// `y += A x`: per row, the entries left of the diagonal added to `y_i`
    /// one by one, then the sum of the others (as the lower-triangle
    /// product scatters its columns and gathers the diagonal's column).
    pub fn mul_add(&self, x: &[f64], y: &mut [f64]) {
        let row = |i: usize, yi: &mut f64| {
            let (s, m, e) = (self.start[i], self.mid[i], self.start[i + 1]);
            let term = |q: usize| self.val[q] * x[self.col[q] as usize];
            let mut left = *yi;
            for q in s..m {
                left += term(q);
            }
            if m < e {
                let mut right = term(m);
                for q in m + 1..e {
                    right += term(q);
                }
                left += right;
            }
            *yi = left;
        };
        if self.val.len() < 1 << 15 {
            y.iter_mut().enumerate().for_each(|(i, yi)| row(i, yi));
        } else {
            y.par_chunks_mut(ROWS_PER_TASK)
                .enumerate()
                .for_each(|(b, ys)| {
                    for (k, yi) in ys.iter_mut().enumerate() {
                        row(b * ROWS_PER_TASK + k, yi);
                    }
                });
        }
    }
}

/// Some rows of up to three symmetric matrices on one [`Pattern`] (both
/// triangles gathered, their values copied side by side), for the sum of
/// their products `Σ_m (A_m x_m)_i` on those rows only, in one pass.
#[derive(Debug, Clone)]
pub struct RowSelection {
    /// The selected rows, ascending.
    pub rows: Vec<usize>,
    /// Per selected row `start[r]..start[r + 1]`: columns, and the
    /// matrices' values at `[q · m ..][..m]`.
    start: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
    /// Number of matrices.
    m: usize,
}

impl RowSelection {
    /// Select `rows` (ascending, distinct) of the matrices `mats` (1 to 3,
    /// all on the pattern of the first).
    pub fn new(mats: &[&SymCsc], rows: Vec<usize>) -> Self {
        let m = mats.len();
        assert!((1..=3).contains(&m), "one to three matrices");
        let p = &*mats[0].pattern;
        assert!(mats.iter().all(|a| *a.pattern == *p), "one pattern");
        let mut sel = vec![usize::MAX; p.n];
        for (r, &i) in rows.iter().enumerate() {
            sel[i] = r;
        }
        let mut lists: Vec<Vec<(usize, usize)>> = vec![Vec::new(); rows.len()];
        for j in 0..p.n {
            for k in p.col_ptr[j]..p.col_ptr[j + 1] {
                let i = p.row_idx[k];
                if sel[i] != usize::MAX {
                    lists[sel[i]].push((j, k));
                }
                if i != j && sel[j] != usize::MAX {
                    lists[sel[j]].push((i, k));
                }
            }
        }
        let mut start = vec![0];
        let (mut col, mut val) = (Vec::new(), Vec::new());
        for l in lists {
            for (j, k) in l {
                col.push(j as u32);
                val.extend(mats.iter().map(|a| a.values[k]));
            }
            start.push(col.len());
        }
        RowSelection {
            rows,
            start,
            col,
            val,
            m,
        }
    }

    /// `y_i += (A_1 x_1)_i`, then `+= (A_2 x_2)_i`, … on the selected rows
    /// (`xs`: one vector per matrix, in the order given to
    /// [`new`](Self::new)); each product summed from zero in the order of
    /// the row's entries, so the result is bitwise that of the products
    /// taken one after the other.
    pub fn mul_add(&self, xs: &[&[f64]], y: &mut [f64]) {
        assert_eq!(xs.len(), self.m, "one vector per matrix");
        match self.m {
            1 => self.mul_add_m::<1>(xs, y),
            2 => self.mul_add_m::<2>(xs, y),
            _ => self.mul_add_m::<3>(xs, y),
        }
    }

    fn mul_add_m<const M: usize>(&self, xs: &[&[f64]], y: &mut [f64]) {
        let xs: [&[f64]; M] = std::array::from_fn(|m| xs[m]);
        for (r, &i) in self.rows.iter().enumerate() {
            let mut acc = [0.0; M];
            for q in self.start[r]..self.start[r + 1] {
                let (j, v) = (self.col[q] as usize, &self.val[q * M..q * M + M]);
                for m in 0..M {
                    acc[m] += v[m] * xs[m][j];
                }
            }
            for a in acc {
                y[i] += a;
            }
        }
    }
}

/// A nested-dissection ordering of `p`'s graph (METIS `NodeND`):
/// `(perm, perm⁻¹)` with `perm[new] = old`. `None` if METIS fails.
fn nested_dissection(p: &Pattern) -> Option<(Vec<usize>, Vec<usize>)> {
    use metis_sys::idx_t;
    let n = p.n;
    let (start, col, _) = p.by_rows(|_, i, j| i != j);
    let mut xadj: Vec<idx_t> = start.iter().map(|&d| d as idx_t).collect();
    let mut adj: Vec<idx_t> = col.iter().map(|&c| c as idx_t).collect();
    let mut nv = n as idx_t;
    let mut options = [0 as idx_t; metis_sys::METIS_NOPTIONS as usize];
    let (mut perm, mut iperm) = (vec![0 as idx_t; n], vec![0 as idx_t; n]);
    // METIS keeps its random generator in global state (seeded by each
    // call): calls from two threads at once would interleave their draws
    // and give orderings that differ from run to run, so one at a time.
    static METIS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one = METIS.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: the arrays have the sizes METIS_NodeND documents (xadj n + 1,
    // adjncy xadj[n], perm/iperm n, options METIS_NOPTIONS), and live for the call.
    let status = unsafe {
        metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        options[metis_sys::moptions_et_METIS_OPTION_SEED as usize] = 1;
        metis_sys::METIS_NodeND(
            &mut nv,
            xadj.as_mut_ptr(),
            adj.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    (status == metis_sys::rstatus_et_METIS_OK).then(|| {
        (
            perm.iter().map(|&k| k as usize).collect(),
            iperm.iter().map(|&k| k as usize).collect(),
        )
    })
}

/// Unknowns from which [`analyse`] also tries nested dissection: below a
/// few thousand AMD's fill is the smaller one on the bodies measured (a
/// footing of 2 562 unknowns: 467 k entries of `L` against 575 k), and a
/// second analysis is not worth its time.
const ND_MIN: usize = 8_000;

/// Entries of `L` from which the factor is supernodal whatever faer's
/// heuristic (which weighs the factorisation's cost, made once) prefers:
/// the steps' solves read `L` twice each, and the supernodal solve's dense
/// blocks read it faster than the simplicial one's entry-by-entry columns
/// (an EFG footing of 2 576 unknowns, 220 k entries: ≈ 30 % less time per
/// solve).
const SUPERNODAL_MIN: usize = 100_000;

/// Entries of `L` from which the solve is split over the elimination tree
/// (below, a fork/join costs more than the second thread saves).
const SPLIT_MIN: usize = 1_000_000;

/// Symbolic Cholesky of `p` under the fill-reducing ordering that leaves
/// the fewer entries in `L`: AMD, or for large matrices nested dissection
/// if it does better (on a 201 × 201-node EFG plate, 80 802 unknowns:
/// 43.1 M entries against AMD's 59.0 M; each solve reads `L` twice, so the
/// step's time follows the fill). Both orderings are deterministic.
fn analyse(p: &Pattern) -> Result<SymbolicCholesky<usize>, SparseError> {
    let run = |ordering: SymmetricOrdering<'_, usize>, threshold| {
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: threshold,
            ..Default::default()
        };
        factorize_symbolic_cholesky(p.faer(), Side::Lower, ordering, params)
            .map_err(|e| SparseError::Faer(format!("{e:?}")))
    };
    // faer's choice, then supernodal for a large simplicial factor
    let kernel = |ordering: SymmetricOrdering<'_, usize>| {
        let s = run(ordering, SupernodalThreshold::default())?;
        if matches!(s.raw(), SymbolicCholeskyRaw::Simplicial(_)) && s.len_val() >= SUPERNODAL_MIN {
            return run(ordering, SupernodalThreshold::FORCE_SUPERNODAL);
        }
        Ok(s)
    };
    let amd = kernel(SymmetricOrdering::Amd)?;
    let Some((fwd, inv)) = (p.n >= ND_MIN).then(|| nested_dissection(p)).flatten() else {
        return Ok(amd);
    };
    let nd = kernel(SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(
        &fwd, &inv, p.n,
    )))?;
    Ok(if nd.len_val() < amd.len_val() {
        nd
    } else {
        amd
    })
}

/// Sparse Cholesky `A = LLᵀ` (AMD or nested-dissection ordering, whichever
/// leaves the smaller factor; faer's supernodal
/// or simplicial kernel as it sees fit, supernodal from
/// 100 000 entries, `SUPERNODAL_MIN`). The solve workspace is allocated
/// once, so [`Cholesky::solve_in_place`] does not allocate.
pub struct Cholesky {
    symbolic: Arc<SymbolicCholesky<usize>>,
    /// The pattern the analysis was made for.
    pattern: Arc<Pattern>,
    values: Vec<f64>,
    solve_mem: MemBuffer,
    par: Par,
    /// The solve split over the elimination tree, for large supernodal
    /// factors whose tree divides (else faer's solve).
    split: Option<SplitSolve>,
}

impl std::fmt::Debug for Cholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Cholesky(n = {}, nnz(L) = {})",
            self.symbolic.nrows(),
            self.values.len()
        )
    }
}

/// Parallelism for a factor with `nnz_l` entries: threads only pay off on
/// large factors (on small ones the fork/join costs more than the solve).
fn par(nnz_l: usize) -> Par {
    let n = rayon::current_num_threads();
    if n > 1 && nnz_l > 200_000 {
        Par::rayon(n)
    } else {
        Par::Seq
    }
}

impl Cholesky {
    /// Symbolic analysis (the ordering with the smaller factor) + numeric
    /// factorisation of `a`.
    pub fn factor(a: &SymCsc) -> Result<Self, SparseError> {
        let symbolic = Arc::new(analyse(&a.pattern)?);
        let split = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) if symbolic.len_val() >= SPLIT_MIN => {
                let perm = symbolic
                    .perm()
                    .map_or_else(|| (0..a.n()).collect(), |p| p.arrays().0.to_vec());
                SplitSolve::new(s, perm)
            }
            _ => None,
        };
        Self::numeric(a, symbolic, a.pattern.clone(), split)
    }

    /// The factor of `a`, a matrix on the pattern this factor was analysed
    /// for (e.g. the mass matrix beside the Newmark matrix), reusing the
    /// analysis: the same ordering as [`factor`](Self::factor) would choose,
    /// without its cost. Another pattern gets its own analysis.
    pub fn factor_like(&self, a: &SymCsc) -> Result<Self, SparseError> {
        if !Arc::ptr_eq(&a.pattern, &self.pattern) && a.pattern != self.pattern {
            return Self::factor(a);
        }
        Self::numeric(
            a,
            self.symbolic.clone(),
            self.pattern.clone(),
            self.split.clone(),
        )
    }

    fn numeric(
        a: &SymCsc,
        symbolic: Arc<SymbolicCholesky<usize>>,
        pattern: Arc<Pattern>,
        split: Option<SplitSolve>,
    ) -> Result<Self, SparseError> {
        let solve_mem = MemBuffer::try_new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq))
            .map_err(|e| SparseError::Faer(format!("{e:?}")))?;
        let mut c = Cholesky {
            par: par(symbolic.len_val()),
            values: vec![0.0; symbolic.len_val()],
            symbolic,
            pattern,
            split,
            solve_mem,
        };
        c.refactor(a)?;
        Ok(c)
    }

    /// Numeric factorisation of a matrix with the analysed pattern.
    pub fn refactor(&mut self, a: &SymCsc) -> Result<(), SparseError> {
        let mut mem = MemBuffer::try_new(
            self.symbolic
                .factorize_numeric_llt_scratch::<f64>(self.par, Default::default()),
        )
        .map_err(|e| SparseError::Faer(format!("{e:?}")))?;
        self.symbolic
            .factorize_numeric_llt(
                &mut self.values,
                a.faer(),
                Side::Lower,
                LltRegularization::default(),
                self.par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    SparseError::NotPositiveDefinite(index)
                }
            })?;
        Ok(())
    }

    /// Number of stored entries of `L`.
    pub fn nnz_l(&self) -> usize {
        self.values.len()
    }

    /// Overwrite `rhs` with `A⁻¹ rhs`. Does not allocate.
    ///
    /// Sequential: a solve with one right-hand side reads `L` twice and
    /// does two flops per entry, so it is bound by memory bandwidth, and
    /// splitting its supernodes over threads only adds their
    /// synchronisation: a second thread must never make a step slower.
    /// The factorisation uses the threads.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        if let Some(split) = &mut self.split {
            split.solve(&self.values, rhs, rayon::current_num_threads() > 1);
            return;
        }
        self.faer_solve(rhs);
    }

    /// faer's sequential supernodal (or simplicial) solve.
    fn faer_solve(&mut self, rhs: &mut [f64]) {
        let n = rhs.len();
        let llt = LltRef::new(&self.symbolic, &self.values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_mem),
        );
    }

    /// Order of the factored matrix.
    pub fn n(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Overwrite the `k` columns of `rhs` (column-major, `n × k`) with
    /// `A⁻¹ rhs`, sequentially, with a workspace of its own: callable from
    /// several threads at once (the start-up solves of
    /// [`BoundaryGreen`](crate::continuum::compliance::BoundaryGreen)).
    pub fn solve_columns(&self, rhs: &mut [f64], k: usize) -> Result<(), SparseError> {
        let n = self.symbolic.nrows();
        debug_assert_eq!(rhs.len(), n * k);
        let mut mem = MemBuffer::try_new(self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq))
            .map_err(|e| SparseError::Faer(format!("{e:?}")))?;
        let llt = LltRef::new(&self.symbolic, &self.values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, n, k),
            Par::Seq,
            MemStack::new(&mut mem),
        );
        Ok(())
    }
}

/// Solve `a x = b` in place (`b ← x`), Gaussian elimination with partial
/// pivoting; `a` is n × n row-major and is destroyed.
pub fn gauss_solve(a: &mut [f64], b: &mut [f64], n: usize) {
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))
            .unwrap_or(col);
        if a[piv * n + col] == 0.0 {
            continue;
        }
        if piv != col {
            for k in 0..n {
                a.swap(piv * n + k, col * n + k);
            }
            b.swap(piv, col);
        }
        let d = a[col * n + col];
        for i in col + 1..n {
            let f = a[i * n + col] / d;
            if f != 0.0 {
                for k in col..n {
                    a[i * n + k] -= f * a[col * n + k];
                }
                b[i] -= f * b[col];
            }
        }
    }
    for col in (0..n).rev() {
        let mut x = b[col];
        for k in col + 1..n {
            x -= a[col * n + k] * b[k];
        }
        let d = a[col * n + col];
        b[col] = if d != 0.0 { x / d } else { 0.0 };
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// 1D Laplacian + identity on n points, lower triangle.
    pub(crate) fn lap(n: usize) -> SymCsc {
        let mut col_ptr = vec![0];
        let mut row_idx = vec![];
        let mut values = vec![];
        for j in 0..n {
            row_idx.push(j);
            values.push(3.0);
            if j + 1 < n {
                row_idx.push(j + 1);
                values.push(-1.0);
            }
            col_ptr.push(row_idx.len());
        }
        SymCsc {
            pattern: Arc::new(Pattern {
                n,
                col_ptr,
                row_idx,
            }),
            values,
        }
    }

    /// The row-wise product of the nonzeros is bitwise the lower-triangle
    /// one, on 1 and 2 threads (a matrix large enough for the threads).
    #[test]
    fn sym_rows_product_is_bitwise_the_lower_triangle_one() {
        for (nx, ny) in [(9, 8), (60, 40)] {
            let mut a = grid(nx, ny, 2);
            // zeros off the diagonal, as a mass matrix on a stiffness pattern
            let p = a.pattern.clone();
            for j in 0..p.n {
                for k in p.col_ptr[j] + 1..p.col_ptr[j + 1] {
                    if (p.row_idx[k] + j).is_multiple_of(3) {
                        a.values[k] = 0.0;
                    }
                }
            }
            let x: Vec<f64> = (0..a.n()).map(|i| (i as f64 * 0.7).sin()).collect();
            let y0: Vec<f64> = (0..a.n()).map(|i| (i as f64 * 0.3).cos()).collect();
            let mut y1 = y0.clone();
            a.mul_add(&x, &mut y1);
            let rows = SymRows::new(&a);
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let mut y2 = y0.clone();
                pool.install(|| rows.mul_add(&x, &mut y2));
                assert!(y1.iter().zip(&y2).all(|(p, q)| p.to_bits() == q.to_bits()));
            }
        }
    }

    /// Products on selected rows equal those rows of the full product.
    #[test]
    fn row_selection_matches_the_full_product() {
        let a = lap(9);
        let x: Vec<f64> = (0..9).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut full = vec![0.0; 9];
        a.mul_add(&x, &mut full);
        let sel = RowSelection::new(&[&a], vec![0, 4, 8]);
        let mut part = vec![0.0; 9];
        sel.mul_add(&[&x], &mut part);
        for i in [0, 4, 8] {
            assert!((part[i] - full[i]).abs() < 1e-15);
        }
        assert_eq!(part[3], 0.0);
        // three matrices in one pass: bitwise the three products in turn
        let b = a.scaled(-0.3);
        let x2: Vec<f64> = x.iter().map(|v| v * 1.7 + 0.1).collect();
        let x3: Vec<f64> = x.iter().map(|v| v * v - 0.4).collect();
        let three = RowSelection::new(&[&a, &b, &a], vec![0, 4, 8]);
        let mut turn = vec![0.5; 9];
        for (m, xm) in [(&a, &x), (&b, &x2), (&a, &x3)] {
            RowSelection::new(&[m], vec![0, 4, 8]).mul_add(&[xm], &mut turn);
        }
        let mut fused = vec![0.5; 9];
        three.mul_add(&[&x, &x2, &x3], &mut fused);
        assert_eq!(turn, fused);
    }

    /// The solve split over the elimination tree equals faer's sequential
    /// solve to round-off (different summation order only), leaves a
    /// residual at round-off, and is bitwise the same on 1 and 2 threads.
    #[test]
    fn split_solve_is_the_solve_on_any_thread_count() {
        let a = grid(100, 90, 2);
        let mut c = Cholesky::factor(&a).unwrap();
        let SymbolicCholeskyRaw::Supernodal(s) = c.symbolic.raw() else {
            panic!("a supernodal factor expected");
        };
        let perm = c.symbolic.perm().map(|p| p.arrays().0.to_vec()).unwrap();
        let mut split = SplitSolve::new(s, perm).expect("the tree divides");
        let b: Vec<f64> = (0..a.n()).map(|i| (i as f64 * 0.37).sin() + 0.2).collect();
        let mut want = b.clone();
        c.faer_solve(&mut want);
        let scale = want.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mut got = Vec::new();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut x = b.clone();
            pool.install(|| split.solve(&c.values, &mut x, threads > 1));
            got.push(x);
        }
        assert!(
            got[0]
                .iter()
                .zip(&got[1])
                .all(|(p, q)| p.to_bits() == q.to_bits())
        );
        let err = got[0]
            .iter()
            .zip(&want)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        assert!(err < 1e-13 * scale, "split vs faer: {err:e} of {scale:e}");
        let mut r: Vec<f64> = b.iter().map(|v| -v).collect();
        a.mul_add(&got[0], &mut r);
        let res = r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(
            res < 1e-12 * b.iter().fold(0.0f64, |m, x| m.max(x.abs())),
            "residual {res:e}"
        );
    }

    /// A factor that reuses another's analysis (same pattern) is bitwise
    /// the factor analysed afresh: the ordering depends on the pattern only
    /// (also while other tests factor at the same time: METIS's global
    /// random state is used by one call at a time).
    #[test]
    fn a_factor_like_another_is_the_factor() {
        let a = grid(100, 90, 2);
        let b = a.combine(0.5, &a.scaled(3.0), 1.0).unwrap();
        let b_rhs: Vec<f64> = (0..a.n()).map(|i| (i as f64 * 0.11).cos()).collect();
        let (mut x, mut y) = (b_rhs.clone(), b_rhs.clone());
        Cholesky::factor(&b).unwrap().solve_in_place(&mut x);
        Cholesky::factor(&a)
            .unwrap()
            .factor_like(&b)
            .unwrap()
            .solve_in_place(&mut y);
        assert!(x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits()));
    }

    #[test]
    fn cholesky_solves_and_matvec_is_symmetric() {
        let a = lap(50);
        assert!(a.pattern.check());
        let x: Vec<f64> = (0..50).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut b = vec![0.0; 50];
        a.mul_add(&x, &mut b);
        assert!(
            (a.quad_form(&x) - x.iter().zip(&b).map(|(p, q)| p * q).sum::<f64>()).abs() < 1e-12
        );
        let mut ch = Cholesky::factor(&a).unwrap();
        ch.solve_in_place(&mut b);
        for (p, q) in x.iter().zip(&b) {
            assert!((p - q).abs() < 1e-12);
        }
        assert_eq!(a.get(3, 4), -1.0);
        assert_eq!(a.get(4, 3), -1.0);
        assert_eq!(a.get(3, 5), 0.0);
    }

    /// A node grid `nx × ny` coupled to every node within `reach` cells
    /// (an EFG-like pattern), diagonally dominant.
    pub(crate) fn grid(nx: usize, ny: usize, reach: i64) -> SymCsc {
        let n = nx * ny;
        let (mut col_ptr, mut row_idx, mut values) = (vec![0], vec![], vec![]);
        for j in 0..n {
            let (xj, yj) = ((j % nx) as i64, (j / nx) as i64);
            let mut off = vec![];
            for i in j + 1..n {
                let (xi, yi) = ((i % nx) as i64, (i / nx) as i64);
                if (xi - xj).abs() <= reach && (yi - yj).abs() <= reach {
                    off.push(i);
                }
            }
            row_idx.push(j);
            values.push(4.0 * reach as f64 * (reach as f64 + 1.0) + 1.0);
            for i in off {
                row_idx.push(i);
                values.push(-0.5 - 0.1 * ((i * 7 + j * 3) % 5) as f64 / 5.0);
            }
            col_ptr.push(row_idx.len());
        }
        SymCsc {
            pattern: Arc::new(Pattern {
                n,
                col_ptr,
                row_idx,
            }),
            values,
        }
    }

    #[test]
    fn indefinite_matrix_is_an_error() {
        let a = lap(5).scaled(-1.0);
        assert!(matches!(
            Cholesky::factor(&a),
            Err(SparseError::NotPositiveDefinite(_))
        ));
    }
}
