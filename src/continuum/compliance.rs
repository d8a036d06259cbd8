//! The response of a body's Newmark step to point forces on its contact
//! boundary: the compliance `S = Φ A⁻¹ Φᵀ` of the implicit contact step
//! (Eq. 49 with point loads through the rows `φ_J(x_H)`, Eq. 46 / E7).
//!
//! Each step solves `A U₊ = F + Φᵀ g` with the constant
//! `A = α₁M + α₄C + K̄`. The contact forces `g` act only at material points
//! of the contact boundary, and the rows of such points only touch a fixed
//! set `B` of DOFs (the nodes whose support reaches the boundary). So the
//! block `G = (A⁻¹)_BB` is computed once, by `|B|` solves in parallel
//! blocks of right-hand sides, and kept dense ([`BoundaryGreen`]). Then,
//! for any set of `m` contact points ([`PointRows`]):
//!
//! * one 2 × 2 block `S_kl` costs `|row_k| · |row_l|` products of 2 × 2
//!   entries of `G` (no solve);
//! * a product `S x` costs a scatter through the rows, a dense product over
//!   the `n_act` DOFs that the rows touch (`n_act²`), and a gather;
//! * the step's solution takes the forces with one solve, `A⁻¹ Φᵀ g`.
//!
//! The cost of the contact solve then depends on the contacts and the DOFs
//! they touch, not on the size of the body (the body still pays its two
//! solves per step: the free step and the contact forces).

use super::state::StateError;
use crate::geom::Vec2;
use crate::sparse::{Cholesky, SparseError};
use rayon::prelude::*;

/// No position (a DOF outside `B`, or an imposed DOF).
pub const NONE: u32 = u32::MAX;

/// Right-hand sides per start-up solve (a fixed block size: the result does
/// not depend on the number of threads).
const BLOCK: usize = 16;

/// `G = (A⁻¹)_BB`, the inverse of the Newmark matrix restricted to the DOFs
/// `B` that boundary rows touch: dense, column-major `|B| × |B|`.
#[derive(Debug, Default)]
pub struct BoundaryGreen {
    /// The DOFs of `B`, in the order of `G`'s rows and columns.
    dofs: Vec<u32>,
    /// Position in `B` of every DOF of the body ([`NONE`] if not in `B`).
    index: Vec<u32>,
    /// Column-major entries.
    g: Vec<f64>,
    /// DOFs never put in `B` (imposed DOFs take no load and do not move).
    excluded: Vec<bool>,
    /// `√|G_aa|` of every DOF of `B`: entry `G_ab` is significant when
    /// `|G_ab| > ε √|G_aa| √|G_bb|` ([`SIGNIFICANT`]).
    root_diag: Vec<f64>,
    /// Number of significant entries of `G`.
    significant: usize,
    /// End in `dofs` of each batch of [`extend`](Self::extend) so far.
    batch_end: Vec<u32>,
    /// Unique to this `G` and its extent ([`next_id`]): a [`PointRows`]
    /// keeps what it gathered from the same `G` on the same DOFs.
    id: u64,
}

/// A number no `G` had before.
fn next_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

/// Entries of `G` below `ε √(G_aa G_bb)` are left out of the products `S x`.
/// `A⁻¹` of the Newmark matrix `α₁M + K̄` decays exponentially with distance
/// (over about `c √β Δt`, the distance a wave runs in a step), so on a body
/// many such lengths long most of `G` is below the round-off of the solves
/// that computed it (cond(A) · 1e-16); on a small or stiff body nothing is
/// left out.
pub const SIGNIFICANT: f64 = 1e-14;

impl BoundaryGreen {
    /// An empty `G` for a body of `n` DOFs; `excluded[i]` marks DOFs that
    /// never enter `B` (imposed values, see
    /// [`Newmark::set_imposed`](crate::continuum::newmark::Newmark::set_imposed)).
    pub fn new(n: usize, excluded: Vec<bool>) -> Self {
        BoundaryGreen {
            dofs: Vec::new(),
            index: vec![NONE; n],
            g: Vec::new(),
            excluded,
            root_diag: Vec::new(),
            significant: 0,
            batch_end: Vec::new(),
            id: next_id(),
        }
    }

    /// The DOFs of `B` in the batches they were added in (each ascending),
    /// as [`extend_dofs`](Self::extend_dofs) takes them to build the same
    /// `G` again: the same solves, the same order of rows and columns.
    pub fn batches(&self) -> Vec<Vec<u32>> {
        let mut lo = 0;
        self.batch_end
            .iter()
            .map(|&e| {
                let b = self.dofs[lo..e as usize].to_vec();
                lo = e as usize;
                b
            })
            .collect()
    }

    /// Add one batch of DOFs of [`batches`](Self::batches) to `B` (as the
    /// [`extend`](Self::extend) that made it did); refused unless they are
    /// ascending, in range, not excluded and not in `B` yet.
    pub fn extend_dofs(&mut self, dofs: &[u32], factor: &Cholesky) -> Result<(), StateError> {
        let n = self.index.len();
        for (k, &i) in dofs.iter().enumerate() {
            let i = i as usize;
            let ok = i < n
                && self.index[i] == NONE
                && !self.excluded.get(i).copied().unwrap_or(false)
                && (k == 0 || dofs[k - 1] < i as u32);
            if !ok {
                return Err(StateError::new(format!(
                    "the saved boundary Green matrix has DOF {i}, which does not fit the body ({n} DOFs)"
                )));
            }
        }
        self.add(dofs.to_vec(), factor)
            .map_err(|e| StateError::new(e.to_string()))
    }

    /// Number of DOFs in `B`.
    pub fn len(&self) -> usize {
        self.dofs.len()
    }

    /// No DOF in `B` yet.
    pub fn is_empty(&self) -> bool {
        self.dofs.is_empty()
    }

    /// Bytes held by the dense block.
    pub fn bytes(&self) -> usize {
        self.g.len() * 8
    }

    /// Position of DOF `i` in `B`, or [`NONE`].
    #[inline]
    pub fn position(&self, i: usize) -> u32 {
        self.index[i]
    }

    /// Entry `G(a, b)` for positions `a`, `b` in `B`.
    #[inline]
    pub fn get(&self, a: u32, b: u32) -> f64 {
        self.g[a as usize + b as usize * self.dofs.len()]
    }

    /// Does `B` hold every DOF of the nodes `nodes` (or are they excluded)?
    pub fn covers(&self, nodes: impl IntoIterator<Item = u32>) -> bool {
        nodes.into_iter().all(|j| {
            (0..2).all(|a| {
                let i = 2 * j as usize + a;
                self.index[i] != NONE || self.excluded.get(i).copied().unwrap_or(false)
            })
        })
    }

    /// Add both DOFs of `nodes` to `B` (those not there yet and not
    /// excluded): one solve `A⁻¹ e_i` per new DOF, in parallel blocks of
    /// right-hand sides; the new rows follow from the symmetry of `A`.
    pub fn extend(
        &mut self,
        nodes: impl IntoIterator<Item = u32>,
        factor: &Cholesky,
    ) -> Result<(), SparseError> {
        let n = self.index.len();
        let mut new: Vec<u32> = Vec::new();
        for j in nodes {
            for a in 0..2 {
                let i = 2 * j as usize + a;
                if i < n && self.index[i] == NONE && !self.excluded.get(i).copied().unwrap_or(false)
                {
                    self.index[i] = 0; // mark; set below
                    new.push(i as u32);
                }
            }
        }
        new.sort_unstable();
        self.add(new, factor)
    }

    /// Add the DOFs `new` (ascending, none in `B` yet) to `B`: one solve
    /// per DOF, in blocks; one batch.
    fn add(&mut self, new: Vec<u32>, factor: &Cholesky) -> Result<(), SparseError> {
        if new.is_empty() {
            return Ok(());
        }
        let n = self.index.len();
        let old = self.dofs.len();
        let total = old + new.len();
        self.dofs.extend_from_slice(&new);
        for (p, &i) in self.dofs.iter().enumerate() {
            self.index[i as usize] = p as u32;
        }
        // the new columns, A⁻¹ e_i restricted to B, in blocks of BLOCK solves
        let dofs = &self.dofs;
        let cols: Vec<Vec<f64>> = new
            .par_chunks(BLOCK)
            .map(|chunk| -> Result<Vec<f64>, SparseError> {
                let k = chunk.len();
                let mut rhs = vec![0.0; n * k];
                for (c, &i) in chunk.iter().enumerate() {
                    rhs[c * n + i as usize] = 1.0;
                }
                factor.solve_columns(&mut rhs, k)?;
                let mut out = Vec::with_capacity(k * total);
                for c in 0..k {
                    let col = &rhs[c * n..(c + 1) * n];
                    out.extend(dofs.iter().map(|&d| col[d as usize]));
                }
                Ok(out)
            })
            .collect::<Result<_, _>>()?;
        let mut g = vec![0.0; total * total];
        for c in 0..old {
            g[c * total..c * total + old].copy_from_slice(&self.g[c * old..(c + 1) * old]);
        }
        for (c, col) in cols.iter().flat_map(|b| b.chunks_exact(total)).enumerate() {
            let c = old + c;
            g[c * total..(c + 1) * total].copy_from_slice(col);
            // symmetry: row c of the old columns
            for r in 0..old {
                g[r * total + c] = col[r];
            }
        }
        self.g = g;
        self.id = next_id();
        self.find_significant();
        self.batch_end.push(total as u32);
        Ok(())
    }

    /// The diagonal's roots and the count of significant entries
    /// ([`SIGNIFICANT`]).
    fn find_significant(&mut self) {
        let nb = self.dofs.len();
        self.root_diag = (0..nb).map(|a| self.g[a * nb + a].abs().sqrt()).collect();
        self.significant = (0..nb)
            .map(|b| {
                let col = &self.g[b * nb..(b + 1) * nb];
                (0..nb).filter(|&a| self.is_significant(col, a, b)).count()
            })
            .sum();
    }

    /// Is `G_ab` (`col` = column `b`) significant ([`SIGNIFICANT`])?
    fn is_significant(&self, col: &[f64], a: usize, b: usize) -> bool {
        col[a].abs() > SIGNIFICANT * self.root_diag[b] * self.root_diag[a]
    }

    /// Fraction of `G`'s entries that the products use.
    pub fn significant_fraction(&self) -> f64 {
        self.significant as f64 / (self.dofs.len() as f64).powi(2).max(1.0)
    }
}

/// The linear functionals of one step's contact unknowns, mapped onto the
/// DOFs of `B` they touch (`act`, local numbering), so that blocks and
/// products of `S = Φ G Φᵀ` need no solve. They come in pairs, one pair per
/// unknown: a contact point's `x` and `y` rows `[(2J, φ_J(x_H))]`,
/// `[(2J + 1, φ_J(x_H))]` (E7), or the two functionals of a contact's
/// geometric stiffness ([`crate::continuum::ChainStiffness`]).
#[derive(Debug, Default)]
pub struct PointRows {
    /// Per functional, its entries `start[c]..start[c + 1]`.
    start: Vec<u32>,
    /// Per entry: local position (in `act`) of the DOF ([`NONE`]: imposed)
    /// and the coefficient.
    entries: Vec<(u32, f64)>,
    /// Positions in `B` of the touched DOFs, ascending.
    act: Vec<u32>,
    /// Scratch of the products: nodal forces and displacements on `act`.
    q: Vec<f64>,
    z: Vec<f64>,
    /// The significant entries of `G` on the touched DOFs, upper triangle
    /// (`G` is symmetric): per column in local numbering its rows up to the
    /// diagonal (CSC), gathered at the first product of a step.
    ga_start: Vec<u32>,
    ga_row: Vec<u32>,
    ga_val: Vec<f64>,
    /// Columns of the products' second part ([`SYM_PARTS`]): from here on
    /// (`usize::MAX`: one part), and its output.
    ga_split: usize,
    z2: Vec<f64>,
    /// The `G` ([`BoundaryGreen::id`]) and touched DOFs the gathered
    /// entries are of: a step on the same DOFs keeps them.
    ga_of: (u64, Vec<u32>),
    /// Local position of every DOF of `B` ([`NONE`] if not touched), set
    /// by [`PointRows::set`].
    map: Vec<u32>,
    /// `S` itself (2m × 2m, row-major) when forming it is cheaper than the
    /// products over `G` (`formed`) or the contact solve asked for it
    /// ([`PointRows::dense`]); empty otherwise.
    s: Vec<f64>,
    /// Form `S` at its first use in the step ([`PointRows::set`]'s choice;
    /// timed with the contact solve, not with the body's step).
    formed: bool,
    /// Scratch of [`form`](Self::form): `G` on the touched DOFs, and `S`
    /// by columns.
    ga: Vec<f64>,
    s_cols: Vec<f64>,
}

/// Products `S x` a contact solve typically needs (for the choice of
/// [`PointRows::set`]).
const PRODUCTS: f64 = 8.0;

/// Entries of `G`'s upper triangle from which the products `S x` run in two
/// parts (on two threads when there are two).
const SYM_PARTS: usize = 1 << 15;

impl PointRows {
    /// Map the functionals `rows[c] = [(DOF, coefficient)]` (pairs) onto
    /// `green` (which must cover their DOFs, [`BoundaryGreen::covers`]).
    pub fn set(&mut self, rows: &[Vec<(usize, f64)>], green: &BoundaryGreen) {
        self.start.clear();
        self.entries.clear();
        self.start.push(0);
        // mark the touched DOFs of B, number them in B's order
        self.map.clear();
        self.map.resize(green.len(), NONE);
        for row in rows {
            for &(i, c) in row {
                let b = green.position(i);
                self.entries.push((b, c));
                if b != NONE {
                    self.map[b as usize] = 0;
                }
            }
            self.start.push(self.entries.len() as u32);
        }
        self.act.clear();
        for (b, l) in self.map.iter_mut().enumerate() {
            if *l != NONE {
                *l = self.act.len() as u32;
                self.act.push(b as u32);
            }
        }
        for e in &mut self.entries {
            if e.0 != NONE {
                e.0 = self.map[e.0 as usize];
            }
        }
        let act = &self.act;
        self.q.resize(act.len(), 0.0);
        self.z.resize(act.len(), 0.0);
        if (green.id, act) != (self.ga_of.0, &self.ga_of.1) {
            self.ga_start.clear();
        }
        // S by columns costs a gather of n_act² and 2m·r·(n_act + 2m)
        // multiply-adds, then 4m² a product; the products over G cost a
        // gather of its upper triangle and a read of it each
        let (m2, na) = (rows.len() as f64, self.act.len() as f64);
        let r = self.entries.len() as f64 / m2.max(1.0);
        let form = na * na + m2 * r * (na + m2) + PRODUCTS * m2 * m2;
        let over_g = (PRODUCTS + 1.0) * 0.5 * na * na * green.significant_fraction();
        self.s.clear();
        self.formed = form < over_g;
    }

    /// `S = Φ (G Φᵀ)` column by column: `G` on the touched DOFs gathered
    /// once (contiguous columns), then for each functional the combination
    /// of its columns, then the functionals of that. Both in parallel over
    /// columns once there is enough work (each column summed in the same
    /// order whatever the thread count).
    fn form(&mut self, green: &BoundaryGreen) {
        let (m2, na, nb) = (self.start.len() - 1, self.act.len(), green.len());
        let parallel = m2 * na >= 1 << 14;
        let mut ga = std::mem::take(&mut self.ga);
        let mut sc = std::mem::take(&mut self.s_cols);
        ga.resize(na * na, 0.0);
        sc.resize(m2 * m2, 0.0);
        let act = &self.act;
        let gather = |(gc, &b): (&mut [f64], &u32)| {
            let col = &green.g[b as usize * nb..(b as usize + 1) * nb];
            for (v, &i) in gc.iter_mut().zip(act) {
                *v = col[i as usize];
            }
        };
        if parallel {
            ga.par_chunks_mut(na.max(1)).zip(act).for_each(gather);
        } else {
            ga.chunks_mut(na.max(1)).zip(act).for_each(gather);
        }
        // column c of S (column-major in `sc`), with the scratch `t` (na)
        let this = &*self;
        let column = |t: &mut Vec<f64>, (c, sc): (usize, &mut [f64])| {
            t.clear();
            t.resize(na, 0.0);
            for &(l, coef) in this.row(c) {
                if l == NONE {
                    continue;
                }
                let col = &ga[l as usize * na..(l as usize + 1) * na];
                for (tv, g) in t.iter_mut().zip(col) {
                    *tv += coef * g;
                }
            }
            for (r, s) in sc.iter_mut().enumerate() {
                let mut u = 0.0;
                for &(l, coef) in this.row(r) {
                    if l != NONE {
                        u += coef * t[l as usize];
                    }
                }
                *s = u;
            }
        };
        if parallel {
            sc.par_chunks_mut(m2)
                .enumerate()
                .with_min_len(8)
                .for_each_init(Vec::new, column);
        } else {
            let mut t = Vec::new();
            sc.chunks_mut(m2.max(1))
                .enumerate()
                .for_each(|x| column(&mut t, x));
        }
        self.s.resize(m2 * m2, 0.0);
        for (c, col) in sc.chunks_exact(m2.max(1)).enumerate() {
            for (r, v) in col.iter().enumerate() {
                self.s[r * m2 + c] = *v;
            }
        }
        self.ga = ga;
        self.s_cols = sc;
    }

    /// Number of unknowns (functional pairs).
    pub fn len(&self) -> usize {
        self.start.len().saturating_sub(1) / 2
    }

    /// No unknowns.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn row(&self, c: usize) -> &[(u32, f64)] {
        &self.entries[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// The block `S_kk`, its off-diagonal entry once (`S` is symmetric;
    /// [`BoundaryGreen`] is, up to round-off), each inner sum down one
    /// column of `G`.
    fn diagonal_block(&self, green: &BoundaryGreen, k: usize) -> [f64; 4] {
        let nb = green.len();
        let quad = |r: &[(u32, f64)], c: &[(u32, f64)]| {
            let mut v = 0.0;
            for &(a, ca) in r {
                if a == NONE {
                    continue;
                }
                let col = &green.g[self.act[a as usize] as usize * nb..];
                let mut t = 0.0;
                for &(b, cb) in c {
                    if b != NONE {
                        t += cb * col[self.act[b as usize] as usize];
                    }
                }
                v += ca * t;
            }
            v
        };
        let (rx, ry) = (self.row(2 * k), self.row(2 * k + 1));
        let xy = quad(rx, ry);
        [quad(rx, rx), xy, xy, quad(ry, ry)]
    }

    /// The diagonal blocks `S_kk` of every unknown (the preconditioner of
    /// the contact solve), in parallel: `3 |row|²` entries of `G` each,
    /// 4·10⁷ a step for 5 000 contacts with their geometric stiffness.
    pub fn diagonal(&mut self, green: &BoundaryGreen, out: &mut Vec<[f64; 4]>) {
        if self.formed && self.s.is_empty() {
            self.form(green);
        }
        let m = self.len();
        out.clear();
        if self.s.is_empty() {
            (0..m)
                .into_par_iter()
                .with_min_len(64)
                .map(|k| self.diagonal_block(green, k))
                .collect_into_vec(out);
        } else {
            out.extend((0..m).map(|k| dense_block(&self.s, k, k)));
        }
    }

    /// The whole `S` (2m × 2m, row-major), formed column by column
    /// (`form`: `O(n_act² + m r n_act + m² r)` for `m`
    /// functionals of `r` entries on `n_act` DOFs, against `O(m² r²)`
    /// entry by entry) and kept for the blocks and products of the step.
    pub fn dense(&mut self, green: &BoundaryGreen, s: &mut Vec<f64>) {
        if self.s.is_empty() {
            self.form(green);
        }
        s.clear();
        s.extend_from_slice(&self.s);
    }

    /// Gather the significant entries of `G` between the touched DOFs, the
    /// upper triangle by columns; the columns are cut in two parts of about
    /// equal entries once there are [`SYM_PARTS`] of them.
    fn gather(&mut self, green: &BoundaryGreen) {
        self.ga_start.clear();
        self.ga_row.clear();
        self.ga_val.clear();
        self.ga_start.push(0);
        let nb = green.len();
        for (lb, &b) in self.act.iter().enumerate() {
            let col = &green.g[b as usize * nb..(b as usize + 1) * nb];
            for (l, &a) in self.act[..=lb].iter().enumerate() {
                if green.is_significant(col, a as usize, b as usize) {
                    self.ga_row.push(l as u32);
                    self.ga_val.push(col[a as usize]);
                }
            }
            self.ga_start.push(self.ga_row.len() as u32);
        }
        self.ga_of.0 = green.id;
        self.ga_of.1.clone_from(&self.act);
        let half = self.ga_val.len() as u32 / 2;
        self.ga_split = if self.ga_val.len() >= SYM_PARTS {
            self.ga_start.partition_point(|&e| e < half)
        } else {
            usize::MAX
        };
    }

    /// `y = S x` for generalised forces `x[k]` on the unknowns:
    /// `Φ G (Φᵀ x)` over the touched DOFs. The first product of a step
    /// gathers the significant entries of `G`'s upper triangle on the
    /// touched DOFs (once); each product then reads them once, in a fixed
    /// order and a fixed cut in parts (bitwise independent of the thread
    /// count).
    pub fn mul(&mut self, green: &BoundaryGreen, x: &[Vec2], y: &mut [Vec2]) {
        if self.formed && self.s.is_empty() {
            self.form(green);
        }
        if !self.s.is_empty() {
            dense_mul(&self.s, x, y);
            return;
        }
        let na = self.act.len();
        if self.ga_start.is_empty() {
            self.gather(green);
        }
        self.q.iter_mut().for_each(|v| *v = 0.0);
        for (k, xk) in x.iter().enumerate() {
            for (c, xa) in [(2 * k, xk.x), (2 * k + 1, xk.y)] {
                let (s, e) = (self.start[c] as usize, self.start[c + 1] as usize);
                for &(l, coef) in &self.entries[s..e] {
                    if l != NONE {
                        self.q[l as usize] += coef * xa;
                    }
                }
            }
        }
        let (st, rows, val, q) = (&self.ga_start, &self.ga_row, &self.ga_val, &self.q);
        let part =
            |cols: std::ops::Range<usize>, z: &mut [f64]| sym_columns(st, rows, val, q, cols, z);
        if self.ga_split < na {
            // two parts on any number of threads, added in order
            self.z2.resize(na, 0.0);
            let (z, z2, split) = (&mut self.z, &mut self.z2, self.ga_split);
            rayon::join(|| part(0..split, z), || part(split..na, z2));
            for (a, b) in z.iter_mut().zip(z2.iter()) {
                *a += *b;
            }
        } else {
            part(0..na, &mut self.z);
        }
        let dotz = |c: usize| -> f64 {
            let mut u = 0.0;
            for &(l, coef) in self.row(c) {
                if l != NONE {
                    u += coef * self.z[l as usize];
                }
            }
            u
        };
        for (k, yk) in y.iter_mut().enumerate() {
            *yk = Vec2::new(dotz(2 * k), dotz(2 * k + 1));
        }
    }
}

/// The compliance of one implicit step at its contact points, as the body
/// hands it to the contact solve: dense (computed by `2m` solves, the
/// reference) or through the boundary Green matrix.
pub enum Compliance<'a> {
    /// `S` itself, 2m × 2m row-major.
    Dense(&'a [f64]),
    /// `S = Φ G Φᵀ`.
    Boundary(&'a BoundaryGreen, &'a mut PointRows),
}

impl Compliance<'_> {
    /// The diagonal blocks `S_kk` of every unknown.
    pub fn diagonal(&mut self, out: &mut Vec<[f64; 4]>) {
        match self {
            Compliance::Dense(s) => {
                let m = (s.len() as f64).sqrt().round() as usize / 2;
                out.clear();
                out.extend((0..m).map(|k| dense_block(s, k, k)));
            }
            Compliance::Boundary(g, rows) => rows.diagonal(g, out),
        }
    }

    /// The whole `S`, row-major.
    pub fn dense(&mut self, out: &mut Vec<f64>) {
        match self {
            Compliance::Dense(s) => {
                out.clear();
                out.extend_from_slice(s);
            }
            Compliance::Boundary(g, rows) => rows.dense(g, out),
        }
    }

    /// `y = S x`.
    pub fn mul(&mut self, x: &[Vec2], y: &mut [Vec2]) {
        match self {
            Compliance::Dense(s) => dense_mul(s, x, y),
            Compliance::Boundary(g, rows) => rows.mul(g, x, y),
        }
    }
}

/// `z = G_c q`, `G_c` the columns `cols` of a symmetric `G` and their
/// transposes, from its upper triangle (CSC, each column's rows ascending
/// up to the diagonal): every stored entry read once, for its column and
/// for its row.
fn sym_columns(
    start: &[u32],
    rows: &[u32],
    vals: &[f64],
    q: &[f64],
    cols: std::ops::Range<usize>,
    z: &mut [f64],
) {
    z.iter_mut().for_each(|v| *v = 0.0);
    for b in cols {
        let (s, e) = (start[b] as usize, start[b + 1] as usize);
        let qb = q[b];
        let mut dot = 0.0;
        for (&a, &g) in rows[s..e].iter().zip(&vals[s..e]) {
            let a = a as usize;
            z[a] += g * qb;
            if a != b {
                dot += g * q[a];
            }
        }
        z[b] += dot;
    }
}

/// The 2 × 2 block `S_kl` (row-major) of a dense row-major `S` (2m × 2m).
fn dense_block(s: &[f64], k: usize, l: usize) -> [f64; 4] {
    let m2 = (s.len() as f64).sqrt().round() as usize;
    let at = |r: usize, c: usize| s[r * m2 + c];
    [
        at(2 * k, 2 * l),
        at(2 * k, 2 * l + 1),
        at(2 * k + 1, 2 * l),
        at(2 * k + 1, 2 * l + 1),
    ]
}

/// `y = S x` for a dense row-major `S` (2m × 2m); rows with four partial
/// sums (vectorisable, fixed order).
fn dense_mul(s: &[f64], x: &[Vec2], y: &mut [Vec2]) {
    dense_mul_rows(s, x, 0..x.len(), y);
}

/// `y = S x` for a dense row-major `S` at the unknowns `rows` only (each
/// `y_k` the same as the whole product's: rows with four partial sums,
/// vectorisable, fixed order); the other entries of `y` are left as they
/// are.
pub fn dense_mul_rows(
    s: &[f64],
    x: &[Vec2],
    rows: impl IntoIterator<Item = usize>,
    y: &mut [Vec2],
) {
    let m2 = 2 * x.len();
    let xs = crate::geom::flat(x);
    let dot = |row: &[f64]| {
        let mut acc = [0.0; 4];
        let (ca, cb) = (row.chunks_exact(4), xs.chunks_exact(4));
        let (ra, rb) = (ca.remainder(), cb.remainder());
        for (a, b) in ca.zip(cb) {
            for i in 0..4 {
                acc[i] += a[i] * b[i];
            }
        }
        let mut t = (acc[0] + acc[1]) + (acc[2] + acc[3]);
        for (a, b) in ra.iter().zip(rb) {
            t += a * b;
        }
        t
    };
    for k in rows {
        y[k] = Vec2::new(
            dot(&s[2 * k * m2..(2 * k + 1) * m2]),
            dot(&s[(2 * k + 1) * m2..(2 * k + 2) * m2]),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::tests::lap;

    /// A `G` extended in several batches is built again bitwise from its
    /// batches (checkpoint/restart); bad batches are refused.
    #[test]
    fn boundary_green_replays_its_batches_bitwise() {
        let n = 80;
        let f = Cholesky::factor(&lap(n)).unwrap();
        let mut excluded = vec![false; n];
        excluded[13] = true;
        let mut g = BoundaryGreen::new(n, excluded.clone());
        g.extend([20, 3, 4], &f).unwrap();
        g.extend([2, 3, 6, 30], &f).unwrap();
        g.extend([3], &f).unwrap(); // nothing new: no batch
        let batches = g.batches();
        assert_eq!(batches.len(), 2);
        assert_eq!(batches[0], [6, 7, 8, 9, 40, 41]);
        assert_eq!(batches[1], [4, 5, 12, 60, 61]);
        let mut h = BoundaryGreen::new(n, excluded.clone());
        for b in &batches {
            h.extend_dofs(b, &f).unwrap();
        }
        assert_eq!(h.dofs, g.dofs);
        assert_eq!(
            h.g.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            g.g.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(h.significant, g.significant);
        assert_eq!(h.batches(), batches);
        for bad in [vec![13], vec![5, 4], vec![80], vec![6]] {
            let mut k = BoundaryGreen::new(n, excluded.clone());
            k.extend_dofs(&[6, 7], &f).unwrap();
            assert!(k.extend_dofs(&bad, &f).is_err(), "{bad:?}");
        }
    }

    /// `G`, its extension, blocks, `S` and products against a dense
    /// inverse of the same matrix.
    #[test]
    fn boundary_green_and_point_compliance_match_the_dense_inverse() {
        let n = 80;
        let a = lap(n);
        let mut f = Cholesky::factor(&a).unwrap();
        let inv: Vec<Vec<f64>> = (0..n)
            .map(|j| {
                let mut e = vec![0.0; n];
                e[j] = 1.0;
                f.solve_in_place(&mut e);
                e
            })
            .collect();
        let mut excluded = vec![false; n];
        excluded[13] = true; // node 6, y: an imposed DOF
        let mut g = BoundaryGreen::new(n, excluded);
        g.extend([0, 1, 2, 3, 20, 21], &f).unwrap();
        let rows: Vec<Vec<(u32, f64)>> = vec![
            vec![(1, 0.3), (2, 0.7)],
            vec![(2, 0.5), (6, 0.25), (20, 0.25)],
            vec![(21, 1.0)],
        ];
        assert!(!g.covers(rows[1].iter().map(|e| e.0)));
        g.extend(rows.iter().flatten().map(|e| e.0), &f).unwrap();
        assert!(rows.iter().all(|r| g.covers(r.iter().map(|e| e.0))));
        assert_eq!(g.position(13), NONE);
        for i in [0, 3, 12, 40, 43] {
            for j in [0, 3, 12, 40, 43] {
                let (pi, pj) = (g.position(i), g.position(j));
                assert!((g.get(pi, pj) - inv[j][i]).abs() < 1e-15, "{i} {j}");
            }
        }
        // S = Φ A⁻¹ Φᵀ with no load on (and no response at) the imposed DOF
        let dof = |j: u32, c: usize| 2 * j as usize + c;
        let mut want = vec![0.0; 36];
        for (k, rk) in rows.iter().enumerate() {
            for (l, rl) in rows.iter().enumerate() {
                for a in 0..2 {
                    for b in 0..2 {
                        let mut v = 0.0;
                        for &(i, pi) in rk {
                            for &(j, pj) in rl {
                                let (di, dj) = (dof(i, a), dof(j, b));
                                if di != 13 && dj != 13 {
                                    v += pi * pj * inv[dj][di];
                                }
                            }
                        }
                        want[(2 * k + a) * 6 + 2 * l + b] = v;
                    }
                }
            }
        }
        let scalar: Vec<Vec<(usize, f64)>> = rows
            .iter()
            .flat_map(|r| [0, 1].map(|a| r.iter().map(|&(j, p)| (2 * j as usize + a, p)).collect()))
            .collect();
        let mut pr = PointRows::default();
        pr.set(&scalar, &g);
        // the diagonal blocks (preconditioner), over G and over a formed S
        let diagonal_matches = |pr: &mut PointRows| {
            let mut d = Vec::new();
            pr.diagonal(&g, &mut d);
            assert_eq!(d.len(), 3);
            for (k, dk) in d.iter().enumerate() {
                for (e, (a, b)) in [(0, 0), (0, 1), (1, 0), (1, 1)].into_iter().enumerate() {
                    let w = want[(2 * k + a) * 6 + 2 * k + b];
                    assert!((dk[e] - w).abs() < 1e-15, "block {k} entry {e}");
                }
            }
        };
        pr.formed = false; // over G, whatever `set` chose for this size
        diagonal_matches(&mut pr);
        assert!(pr.s.is_empty());
        let mut s = Vec::new();
        pr.dense(&g, &mut s);
        assert!(!pr.s.is_empty());
        diagonal_matches(&mut pr);
        for (x, y) in s.iter().zip(&want) {
            assert!((x - y).abs() < 1e-15);
        }
        // products, over G and over a formed S
        let x = [
            Vec2::new(1.0, -2.0),
            Vec2::new(0.5, 3.0),
            Vec2::new(-1.0, 0.25),
        ];
        let mut y = [Vec2::ZERO; 3];
        for formed in [false, true] {
            pr.s.clear();
            pr.formed = formed;
            pr.mul(&g, &x, &mut y);
            assert_eq!(pr.s.is_empty(), !formed);
            for k in 0..3 {
                for a in 0..2 {
                    let v: f64 = (0..6)
                        .map(|c| {
                            want[(2 * k + a) * 6 + c]
                                * if c % 2 == 0 { x[c / 2].x } else { x[c / 2].y }
                        })
                        .sum();
                    let got = if a == 0 { y[k].x } else { y[k].y };
                    assert!((got - v).abs() < 1e-14, "{formed} {k} {a}");
                }
            }
        }
    }

    /// Products over a large `G` (its upper triangle cut in two parts)
    /// against solves with the factor, bitwise the same on 1 and 2 threads.
    #[test]
    fn products_over_a_large_green_matrix_match_solves_on_any_threads() {
        let n = 2400;
        let a = lap(n);
        let mut f = Cholesky::factor(&a).unwrap();
        let mut g = BoundaryGreen::new(n, vec![false; n]);
        g.extend(0..n as u32 / 2, &f).unwrap();
        // 300 points, each row over four nodes with weights summing to 1
        let m = 300;
        let rows: Vec<Vec<(usize, f64)>> = (0..2 * m)
            .map(|c| {
                let (k, axis) = (c / 2, c % 2);
                let w = [0.1, 0.4, 0.3, 0.2];
                (0..4).map(|j| (2 * (4 * k + j) + axis, w[j])).collect()
            })
            .collect();
        let x: Vec<Vec2> = (0..m)
            .map(|k| Vec2::new((k as f64 * 0.37).sin(), (k as f64 * 0.11).cos()))
            .collect();
        // reference: y = Φ A⁻¹ Φᵀ x by a solve
        let mut load = vec![0.0; n];
        for (c, row) in rows.iter().enumerate() {
            let xc = if c % 2 == 0 { x[c / 2].x } else { x[c / 2].y };
            for &(i, w) in row {
                load[i] += w * xc;
            }
        }
        f.solve_in_place(&mut load);
        let want: Vec<f64> = (rows.iter())
            .map(|row| row.iter().map(|&(i, w)| w * load[i]).sum())
            .collect();
        let product = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut pr = PointRows::default();
            pr.set(&rows, &g);
            pr.formed = false;
            let mut y = vec![Vec2::ZERO; m];
            pool.install(|| pr.mul(&g, &x, &mut y));
            assert!(pr.ga_split < pr.act.len(), "two parts");
            // the next step on the same DOFs keeps the gathered entries
            pr.set(&rows, &g);
            assert!(!pr.ga_start.is_empty());
            let mut again = vec![Vec2::ZERO; m];
            pool.install(|| pr.mul(&g, &x, &mut again));
            assert_eq!(y, again);
            y
        };
        let y1 = product(1);
        let scale = want.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for (k, v) in y1.iter().enumerate() {
            assert!((v.x - want[2 * k]).abs() < 1e-12 * scale, "{k} x");
            assert!((v.y - want[2 * k + 1]).abs() < 1e-12 * scale, "{k} y");
        }
        assert_eq!(y1, product(2));
    }
}
