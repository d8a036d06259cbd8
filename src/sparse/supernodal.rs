//! The solve `A x = b` with a supernodal Cholesky factor `A = LLᵀ` on the
//! threads, bitwise the same on any number of them.
//!
//! A supernode is a run of columns of `L` with one row pattern: a dense
//! column-major block, its `w × w` lower triangle on the diagonal and its
//! `m` off-diagonal rows below. Supernodes come in a postorder of the
//! elimination tree (children before parents, the descendants of a
//! supernode right before it), so a subtree is a range of supernodes and
//! of columns, and the rows of a supernode are columns of its ancestors.
//!
//! The tree is cut once, when the factor is built: disjoint subtrees of
//! balanced cost, and the *top* (the supernodes above them). Forward,
//! `L y = b`: the subtrees in parallel, each adding its updates of top rows
//! into a buffer of its own; the buffers into `y` in subtree order; then
//! the top supernodes in order. Backward, `Lᵀ x = y`: the top supernodes
//! in reverse order, then the subtrees in parallel (each reads the top's
//! values and writes only its own columns). In a top supernode the
//! off-diagonal block, a product with one vector, is split over the
//! threads by rows (forward) or by columns (backward): every value is
//! still the same sum in the same order. The cut depends on the factor
//! only, never on the thread count.

use rayon::prelude::*;
use std::ops::Range;

/// One supernode: columns `start..start + w`, values at `val` (column-major,
/// leading dimension `w + m`), off-diagonal rows `rows[pat]` (`m` of them).
#[derive(Debug, Clone)]
struct Node {
    start: usize,
    w: usize,
    val: usize,
    pat: Range<usize>,
}

impl Node {
    fn ld(&self) -> usize {
        self.w + self.pat.len()
    }
    /// Values touched by one triangular solve.
    fn cost(&self) -> usize {
        self.w * (self.w + 1) / 2 + self.w * self.pat.len()
    }
}

/// Subtrees are cut until none costs more than this fraction of the whole.
const CUT: usize = 8;
/// Below this many values in `L` the solve is sequential (no cut).
const MIN_PARALLEL: usize = 50_000;
/// Off-diagonal blocks of top supernodes with fewer values than this are
/// done on one thread.
const MIN_SPLIT: usize = 32_768;

/// The supernodal structure of a factor and its schedule on the threads.
#[derive(Debug)]
pub(crate) struct TreeSolve {
    nodes: Vec<Node>,
    rows: Vec<u32>,
    /// `x[i] = b[perm[i]]` into the factor's order, `b[i] = x[inv[i]]` out.
    perm: Vec<u32>,
    inv: Vec<u32>,
    /// The subtrees (supernode ranges, ascending) and their columns.
    subtrees: Vec<Range<usize>>,
    cols: Vec<Range<usize>>,
    /// Supernodes outside the subtrees, ascending; their columns, and the
    /// position of a column among them (`u32::MAX`: in a subtree).
    top: Vec<usize>,
    top_cols: Vec<u32>,
    top_pos: Vec<u32>,
    /// Workspace: the permuted vector, per subtree a buffer over the top
    /// columns and a row buffer; one row buffer for the top.
    x: Vec<f64>,
    bufs: Vec<Vec<f64>>,
    tmp: Vec<Vec<f64>>,
    top_tmp: Vec<f64>,
    xtop: Vec<f64>,
}

/// The pieces of a supernodal factor the solve needs (faer's symbolic
/// structure, copied).
pub(crate) struct Structure<'a> {
    pub begin: &'a [usize],
    pub end: &'a [usize],
    pub val_ptr: &'a [usize],
    pub pattern: Vec<&'a [usize]>,
    pub perm: Option<(&'a [usize], &'a [usize])>,
}

impl TreeSolve {
    /// The schedule of the factor with structure `s`.
    pub(crate) fn new(s: Structure<'_>) -> Self {
        let ns = s.begin.len();
        let n = s.end.last().copied().unwrap_or(0);
        let mut rows = Vec::new();
        let nodes: Vec<Node> = (0..ns)
            .map(|k| {
                let p0 = rows.len();
                rows.extend(s.pattern[k].iter().map(|&r| r as u32));
                Node {
                    start: s.begin[k],
                    w: s.end[k] - s.begin[k],
                    val: s.val_ptr[k],
                    pat: p0..rows.len(),
                }
            })
            .collect();
        let (perm, inv) = match s.perm {
            Some((f, i)) => (
                f.iter().map(|&v| v as u32).collect(),
                i.iter().map(|&v| v as u32).collect(),
            ),
            None => ((0..n as u32).collect(), (0..n as u32).collect()),
        };
        let roots = cut(&nodes, &rows, n);
        let mut subtrees: Vec<Range<usize>> =
            roots.iter().map(|&(r, size)| r + 1 - size..r + 1).collect();
        subtrees.sort_by_key(|r| r.start);
        let mut in_sub = vec![false; ns];
        for r in &subtrees {
            in_sub[r.clone()].iter_mut().for_each(|b| *b = true);
        }
        let cols: Vec<Range<usize>> = subtrees
            .iter()
            .map(|r| nodes[r.start].start..nodes[r.end - 1].start + nodes[r.end - 1].w)
            .collect();
        let top: Vec<usize> = (0..ns).filter(|&k| !in_sub[k]).collect();
        let top_cols: Vec<u32> = top
            .iter()
            .flat_map(|&k| (nodes[k].start..nodes[k].start + nodes[k].w).map(|c| c as u32))
            .collect();
        let mut top_pos = vec![u32::MAX; n];
        for (i, &c) in top_cols.iter().enumerate() {
            top_pos[c as usize] = i as u32;
        }
        let max_m = |r: &Range<usize>| {
            nodes[r.clone()]
                .iter()
                .map(|v| v.pat.len())
                .max()
                .unwrap_or(0)
        };
        TreeSolve {
            bufs: subtrees.iter().map(|_| vec![0.0; top_cols.len()]).collect(),
            tmp: subtrees.iter().map(|r| vec![0.0; max_m(r)]).collect(),
            top_tmp: vec![0.0; top.iter().map(|&k| nodes[k].pat.len()).max().unwrap_or(0)],
            x: vec![0.0; n],
            xtop: vec![0.0; top_cols.len()],
            nodes,
            rows,
            perm,
            inv,
            subtrees,
            cols,
            top,
            top_cols,
            top_pos,
        }
    }

    /// Number of subtrees solved in parallel (0: sequential).
    #[cfg(test)]
    pub(crate) fn parallel_parts(&self) -> usize {
        self.subtrees.len()
    }

    /// The share of the values of `L` a solve reads in its parallel parts
    /// (the subtrees, the large off-diagonal blocks of the top).
    pub(crate) fn parallel_share(&self) -> f64 {
        let total: usize = self.nodes.iter().map(Node::cost).sum();
        let subtrees: usize = self
            .subtrees
            .iter()
            .flat_map(|r| &self.nodes[r.clone()])
            .map(Node::cost)
            .sum();
        let split: usize = self
            .top
            .iter()
            .map(|&k| &self.nodes[k])
            .filter(|v| v.w * v.pat.len() >= MIN_SPLIT)
            .map(|v| v.w * v.pat.len())
            .sum();
        (subtrees + split) as f64 / total.max(1) as f64
    }

    /// Overwrite `b` with `A⁻¹ b`, `values` the factor's values.
    pub(crate) fn solve(&mut self, values: &[f64], b: &mut [f64]) {
        let mut x = std::mem::take(&mut self.x);
        for (xi, &p) in x.iter_mut().zip(&self.perm) {
            *xi = b[p as usize];
        }
        self.forward(values, &mut x);
        self.backward(values, &mut x);
        for (bi, &q) in b.iter_mut().zip(&self.inv) {
            *bi = x[q as usize];
        }
        self.x = x;
    }

    /// `x ← L⁻¹ x`.
    fn forward(&mut self, values: &[f64], x: &mut [f64]) {
        let (nodes, rows, top_pos) = (&self.nodes, &self.rows, &self.top_pos);
        let mut tasks = split_by(x, &self.cols);
        tasks
            .par_iter_mut()
            .zip(&mut self.bufs)
            .zip(&mut self.tmp)
            .zip(&self.subtrees)
            .for_each(|(((xs, buf), tmp), range)| {
                buf.fill(0.0);
                let off = xs.0;
                for node in &nodes[range.clone()] {
                    let m = node.pat.len();
                    let l = &values[node.val..node.val + node.ld() * node.w];
                    let xn = &mut xs.1[node.start - off..node.start - off + node.w];
                    fwd_diag(l, node.ld(), node.w, xn);
                    fwd_off(l, node.ld(), node.w, 0, xn, &mut tmp[..m]);
                    for (&r, &t) in rows[node.pat.clone()].iter().zip(&tmp[..m]) {
                        let r = r as usize;
                        match top_pos[r] {
                            u32::MAX => xs.1[r - off] -= t,
                            p => buf[p as usize] -= t,
                        }
                    }
                }
            });
        for (i, &c) in self.top_cols.iter().enumerate() {
            for buf in &self.bufs {
                x[c as usize] += buf[i];
            }
        }
        for &k in &self.top {
            let node = &self.nodes[k];
            let m = node.pat.len();
            let (ld, w) = (node.ld(), node.w);
            let l = &values[node.val..node.val + ld * w];
            let xn = &mut x[node.start..node.start + w];
            fwd_diag(l, ld, w, xn);
            let xn = &*xn;
            let tmp = &mut self.top_tmp[..m];
            let chunk = chunk_len(w, m);
            tmp.par_chunks_mut(chunk)
                .enumerate()
                .for_each(|(i, t)| fwd_off(l, ld, w, i * chunk, xn, t));
            for (&r, &t) in self.rows[node.pat.clone()].iter().zip(&*tmp) {
                x[r as usize] -= t;
            }
        }
    }

    /// `x ← L⁻ᵀ x`.
    fn backward(&mut self, values: &[f64], x: &mut [f64]) {
        for &k in self.top.iter().rev() {
            let node = &self.nodes[k];
            let m = node.pat.len();
            let (ld, w) = (node.ld(), node.w);
            let l = &values[node.val..node.val + ld * w];
            let tmp = &mut self.top_tmp[..m];
            for (t, &r) in tmp.iter_mut().zip(&self.rows[node.pat.clone()]) {
                *t = x[r as usize];
            }
            let tmp = &*tmp;
            let xn = &mut x[node.start..node.start + w];
            let chunk = chunk_len(m, w);
            xn.par_chunks_mut(chunk)
                .enumerate()
                .for_each(|(i, xc)| bwd_off(l, ld, w, i * chunk, tmp, xc));
            bwd_diag(l, ld, w, xn);
        }
        // the top's values, for the subtrees to read
        for (t, &c) in self.xtop.iter_mut().zip(&self.top_cols) {
            *t = x[c as usize];
        }
        let (nodes, rows, top_pos, xtop) = (&self.nodes, &self.rows, &self.top_pos, &self.xtop);
        let mut tasks = split_by(x, &self.cols);
        tasks
            .par_iter_mut()
            .zip(&mut self.tmp)
            .zip(&self.subtrees)
            .for_each(|((xs, tmp), range)| {
                let off = xs.0;
                for node in nodes[range.clone()].iter().rev() {
                    let m = node.pat.len();
                    for (t, &r) in tmp[..m].iter_mut().zip(&rows[node.pat.clone()]) {
                        let r = r as usize;
                        *t = match top_pos[r] {
                            u32::MAX => xs.1[r - off],
                            p => xtop[p as usize],
                        };
                    }
                    let l = &values[node.val..node.val + node.ld() * node.w];
                    let xn = &mut xs.1[node.start - off..node.start - off + node.w];
                    bwd_off(l, node.ld(), node.w, 0, &tmp[..m], xn);
                    bwd_diag(l, node.ld(), node.w, xn);
                }
            });
    }
}

/// Chunk length for splitting `parts` of a block with `other` values each
/// over the threads (the whole block if it is small).
fn chunk_len(other: usize, parts: usize) -> usize {
    let threads = rayon::current_num_threads();
    if threads == 1 || other * parts < MIN_SPLIT {
        parts.max(1)
    } else {
        parts.div_ceil(threads).max(1)
    }
}

/// `x` cut into the disjoint mutable column ranges `cols` (ascending),
/// each with its first column.
fn split_by<'a>(x: &'a mut [f64], cols: &[Range<usize>]) -> Vec<(usize, &'a mut [f64])> {
    let mut out = Vec::with_capacity(cols.len());
    let mut rest = x;
    let mut at = 0;
    for r in cols {
        let (_, tail) = rest.split_at_mut(r.start - at);
        let (mine, tail) = tail.split_at_mut(r.len());
        out.push((r.start, mine));
        rest = tail;
        at = r.end;
    }
    out
}

/// The subtrees to run in parallel, `(root, number of supernodes)`: start
/// from the roots and replace the costliest subtree by its children until
/// none costs more than `1/CUT` of the whole (or it has no children).
/// Empty (all sequential) if the tree is not postordered or the factor
/// small.
fn cut(nodes: &[Node], rows: &[u32], n: usize) -> Vec<(usize, usize)> {
    let ns = nodes.len();
    let mut owner = vec![0usize; n];
    for (k, v) in nodes.iter().enumerate() {
        owner[v.start..v.start + v.w]
            .iter_mut()
            .for_each(|o| *o = k);
    }
    let parent: Vec<usize> = nodes
        .iter()
        .map(|v| {
            rows.get(v.pat.start)
                .filter(|_| !v.pat.is_empty())
                .map_or(usize::MAX, |&r| owner[r as usize])
        })
        .collect();
    let mut cost: Vec<usize> = nodes.iter().map(Node::cost).collect();
    let mut size = vec![1usize; ns];
    let mut children = vec![Vec::new(); ns];
    for k in 0..ns {
        let p = parent[k];
        if p != usize::MAX {
            if p <= k {
                return Vec::new();
            }
            cost[p] += cost[k];
            size[p] += size[k];
            children[p].push(k);
        }
    }
    // postorder: the descendants of k are the `size[k] − 1` supernodes before it
    for k in 0..ns {
        let mut first = k;
        for &c in &children[k] {
            first = first.min(c + 1 - size[c]);
        }
        if first + size[k] != k + 1 {
            return Vec::new();
        }
    }
    let total: usize = nodes.iter().map(Node::cost).sum();
    if total < MIN_PARALLEL {
        return Vec::new();
    }
    let mut cand: Vec<usize> = (0..ns).filter(|&k| parent[k] == usize::MAX).collect();
    while let Some((i, &k)) = cand
        .iter()
        .enumerate()
        .max_by_key(|&(i, &k)| (cost[k], usize::MAX - i))
    {
        if cost[k] * CUT <= total || children[k].is_empty() {
            break;
        }
        cand.swap_remove(i);
        cand.extend(&children[k]);
    }
    if cand.len() < 2 {
        return Vec::new();
    }
    cand.into_iter().map(|k| (k, size[k])).collect()
}

/// Forward solve with the diagonal block: `x ← L_d⁻¹ x` (column by column).
fn fwd_diag(l: &[f64], ld: usize, w: usize, x: &mut [f64]) {
    for c in 0..w {
        let col = &l[c * ld..c * ld + w];
        let xc = x[c] / col[c];
        x[c] = xc;
        for (xr, a) in x[c + 1..].iter_mut().zip(&col[c + 1..]) {
            *xr -= a * xc;
        }
    }
}

/// `t = L_o[r0.., :] x` for the off-diagonal rows `r0..r0 + t.len()`
/// (each value summed over the columns in order).
fn fwd_off(l: &[f64], ld: usize, w: usize, r0: usize, x: &[f64], t: &mut [f64]) {
    t.fill(0.0);
    for (c, &xc) in x.iter().enumerate().take(w) {
        let col = &l[c * ld + w + r0..c * ld + w + r0 + t.len()];
        for (tr, a) in t.iter_mut().zip(col) {
            *tr += a * xc;
        }
    }
}

/// `x[k] −= L_o[:, c0 + k] · t` for the columns `c0..c0 + x.len()`.
fn bwd_off(l: &[f64], ld: usize, w: usize, c0: usize, t: &[f64], x: &mut [f64]) {
    for (k, xk) in x.iter_mut().enumerate() {
        let c = c0 + k;
        *xk -= dot(&l[c * ld + w..c * ld + w + t.len()], t);
    }
}

/// Backward solve with the diagonal block: `x ← L_d⁻ᵀ x`.
fn bwd_diag(l: &[f64], ld: usize, w: usize, x: &mut [f64]) {
    for c in (0..w).rev() {
        let col = &l[c * ld..c * ld + w];
        let s = dot(&col[c + 1..], &x[c + 1..w]);
        x[c] = (x[c] - s) / col[c];
    }
}

/// `a · b` in four interleaved partial sums (a fixed order the compiler
/// can vectorise).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for i in 0..4 {
            s[i] += x[i] * y[i];
        }
    }
    let mut r = (s[0] + s[1]) + (s[2] + s[3]);
    for (x, y) in ra.iter().zip(rb) {
        r += x * y;
    }
    r
}
