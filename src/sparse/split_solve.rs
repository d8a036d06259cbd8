//! The solve `A x = b` with a supernodal Cholesky factor `A = LLᵀ`, split
//! at the top of the elimination tree so that two threads share it.
//!
//! The supernodes of `L` are in postorder: every subtree of the
//! elimination tree is a contiguous range of supernodes and of columns.
//! Below the root chain (the separator of a nested-dissection ordering)
//! the tree divides into independent subtrees ("parts"). The forward
//! solve `L y = b` runs each part on its own (its updates to its own rows
//! in place, those to the chain's rows into a buffer of its own), then adds
//! the buffers to the chain's rows in part order and solves the chain; the
//! backward solve `Lᵀ x = y` solves the chain, then each part, which only
//! reads the chain's rows. The arithmetic is the same on any number of
//! threads, so the result is bitwise independent of it.
//!
//! The supernodes' dense kernels are faer's; the walk over the tree is
//! written here because faer's supernodal solve walks the supernodes one
//! after another: a solve with one right-hand side
//! reads `L` twice with two flops per entry, so it is bound by memory
//! bandwidth, and the independent halves of the tree are the only way a
//! second thread gets its own share of it.

use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place_with_conj, solve_upper_triangular_in_place_with_conj,
};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, Conj, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::ops::Range;

/// One supernode: columns `start..start + size`, its dense block of
/// `size + rows.len()` rows (column-major, at `val` in the values of `L`),
/// whose rows below the diagonal block are `rows`.
#[derive(Debug, Clone)]
struct Node {
    start: usize,
    size: usize,
    rows: Range<usize>,
    val: usize,
}

/// The split of a supernodal factor's elimination tree, and the solve's
/// workspaces.
#[derive(Debug, Clone)]
pub struct SplitSolve {
    nodes: Vec<Node>,
    /// Row indices below the diagonal blocks, all supernodes.
    row_idx: Vec<usize>,
    /// Supernode ranges of the independent subtrees, in column order.
    parts: Vec<Range<usize>>,
    /// First column of the root chain (`n` if there is none).
    sep: usize,
    /// `perm[new] = old` of the fill-reducing ordering.
    perm: Vec<usize>,
    /// The right-hand side in the factor's order.
    x: Vec<f64>,
    /// Per part: its updates to the chain's rows, and a supernode's rows below.
    bufs: Vec<(Vec<f64>, Vec<f64>)>,
    /// A supernode's rows below, for the chain.
    work: Vec<f64>,
}

impl SplitSolve {
    /// The split of `s` (with the ordering `perm`, `perm[new] = old`), or
    /// `None` if its tree does not divide below its root chain.
    pub fn new(s: &SymbolicSupernodalCholesky<usize>, perm: Vec<usize>) -> Option<Self> {
        let (begin, end) = (s.supernode_begin(), s.supernode_end());
        let ns = begin.len();
        let n = s.nrows();
        let nodes: Vec<Node> = (0..ns)
            .map(|k| {
                let at = s.col_ptr_for_row_idx()[k];
                Node {
                    start: begin[k],
                    size: end[k] - begin[k],
                    rows: at..s.col_ptr_for_row_idx()[k + 1],
                    val: s.col_ptr_for_val()[k],
                }
            })
            .collect();
        // supernode of each column, parent = supernode of the first row below
        let mut of_col = vec![0; n];
        for (k, nd) in nodes.iter().enumerate() {
            of_col[nd.start..nd.start + nd.size].fill(k);
        }
        let row_idx = s.row_idx().to_vec();
        let parent: Vec<Option<usize>> = nodes
            .iter()
            .map(|nd| {
                row_idx
                    .get(nd.rows.clone())
                    .and_then(|r| r.first())
                    .map(|&r| of_col[r])
            })
            .collect();
        let mut children = vec![Vec::new(); ns + 1];
        let mut count = vec![1usize; ns];
        for k in 0..ns {
            children[parent[k].unwrap_or(ns)].push(k);
            if let Some(p) = parent[k] {
                count[p] += count[k];
            }
        }
        // down the root chain to the first supernode with several children
        let mut top = ns;
        while children[top].len() == 1 {
            top = children[top][0];
        }
        let parts: Vec<Range<usize>> = children[top]
            .iter()
            .map(|&c| c + 1 - count[c]..c + 1)
            .collect();
        let chain = if top == ns { ns } else { top };
        let tiles = parts.windows(2).all(|w| w[0].end == w[1].start)
            && parts.first().is_some_and(|p| p.start == 0)
            && parts.last().is_some_and(|p| p.end == chain);
        if parts.len() < 2 || !tiles {
            return None;
        }
        let sep = nodes.get(chain).map_or(n, |nd| nd.start);
        let widest = nodes.iter().map(|nd| nd.rows.len()).max().unwrap_or(0);
        let bufs = parts
            .iter()
            .map(|_| (vec![0.0; n - sep], vec![0.0; widest]))
            .collect();
        Some(SplitSolve {
            nodes,
            row_idx,
            parts,
            sep,
            perm,
            x: vec![0.0; n],
            bufs,
            work: vec![0.0; widest],
        })
    }

    /// Overwrite `rhs` with `A⁻¹ rhs`, `l` the values of `L`; the parts on
    /// the current rayon pool if `par`.
    pub fn solve(&mut self, l: &[f64], rhs: &mut [f64], par: bool) {
        for (x, &old) in self.x.iter_mut().zip(&self.perm) {
            *x = rhs[old];
        }
        let (nodes, row_idx, sep) = (&self.nodes, &self.row_idx, self.sep);
        let (below, chain) = self.x.split_at_mut(sep);
        let mut jobs = Vec::with_capacity(self.parts.len());
        let mut rest = below;
        for (range, (buf, work)) in self.parts.iter().zip(&mut self.bufs) {
            let cols =
                nodes[range.end - 1].start + nodes[range.end - 1].size - nodes[range.start].start;
            let (mine, after) = rest.split_at_mut(cols);
            rest = after;
            jobs.push((range.clone(), mine, buf, work));
        }
        let forward = |(range, mine, buf, work): &mut (
            Range<usize>,
            &mut [f64],
            &mut Vec<f64>,
            &mut Vec<f64>,
        )| {
            buf.fill(0.0);
            let base = nodes[range.start].start;
            for nd in &nodes[range.clone()] {
                let w = forward_node(nd, l, &mut mine[nd.start - base..], work);
                for (&r, &d) in row_idx[nd.rows.clone()].iter().zip(w) {
                    if r < sep {
                        mine[r - base] -= d;
                    } else {
                        buf[r - sep] += d;
                    }
                }
            }
        };
        run(&mut jobs, par, forward);
        for (_, _, buf, _) in &jobs {
            for (x, b) in chain.iter_mut().zip(buf.iter()) {
                *x -= b;
            }
        }
        let top = self.parts.last().map_or(0, |p| p.end);
        for nd in &nodes[top..] {
            let w = forward_node(nd, l, &mut chain[nd.start - sep..], &mut self.work);
            for (&r, &d) in row_idx[nd.rows.clone()].iter().zip(w) {
                chain[r - sep] -= d;
            }
        }
        for nd in nodes[top..].iter().rev() {
            backward_node(nd, l, row_idx, chain, |r| r - sep, None, &mut self.work);
        }
        let chain = &*chain;
        let backward = |(range, mine, _, work): &mut (
            Range<usize>,
            &mut [f64],
            &mut Vec<f64>,
            &mut Vec<f64>,
        )| {
            let base = nodes[range.start].start;
            for nd in nodes[range.clone()].iter().rev() {
                backward_node(
                    nd,
                    l,
                    row_idx,
                    &mut mine[..],
                    |r| r - base,
                    Some((sep, chain)),
                    work,
                );
            }
        };
        run(&mut jobs, par, backward);
        for (x, &old) in self.x.iter().zip(&self.perm) {
            rhs[old] = *x;
        }
    }
}

/// `f` on every job, on the pool's threads if `par`.
fn run<J: Send>(jobs: &mut [J], par: bool, f: impl Fn(&mut J) + Sync + Send) {
    if par {
        jobs.par_iter_mut().for_each(f);
    } else {
        jobs.iter_mut().for_each(f);
    }
}

/// The dense block of supernode `nd` in `l`: `(diagonal block, rows below)`.
fn block<'l>(nd: &Node, l: &'l [f64]) -> (MatRef<'l, f64>, MatRef<'l, f64>) {
    let nr = nd.size + nd.rows.len();
    MatRef::from_column_major_slice(&l[nd.val..nd.val + nr * nd.size], nr, nd.size)
        .split_at_row(nd.size)
}

/// Forward solve of one supernode (as faer's): its entries of `x` (`x[0]`
/// = its first column) solved with the diagonal block in place, and
/// `work[..rows]` = `L_bot x_top`, the updates to subtract from its rows
/// below.
fn forward_node<'w>(nd: &Node, l: &[f64], x: &mut [f64], work: &'w mut [f64]) -> &'w [f64] {
    let (top, bot) = block(nd, l);
    let mut xt = MatMut::from_column_major_slice_mut(&mut x[..nd.size], nd.size, 1);
    solve_lower_triangular_in_place_with_conj(top, Conj::No, xt.as_mut(), Par::Seq);
    let m = nd.rows.len();
    let tmp = MatMut::from_column_major_slice_mut(&mut work[..m], m, 1);
    matmul_with_conj(
        tmp,
        Accum::Replace,
        bot,
        Conj::No,
        xt.as_ref(),
        Conj::No,
        1.0,
        Par::Seq,
    );
    &work[..m]
}

/// Backward solve of one supernode (as faer's), in place in `x` (`x[0]` =
/// the whole slice's first column, `at(row)` a row's place in it): its
/// rows below are read from `x` if they are before `split.0`, else from
/// `split.1` at `row − split.0`.
fn backward_node(
    nd: &Node,
    l: &[f64],
    row_idx: &[usize],
    x: &mut [f64],
    at: impl Fn(usize) -> usize,
    split: Option<(usize, &[f64])>,
    work: &mut [f64],
) {
    let m = nd.rows.len();
    for (wi, &r) in work[..m].iter_mut().zip(&row_idx[nd.rows.clone()]) {
        *wi = match split {
            Some((sep, chain)) if r >= sep => chain[r - sep],
            _ => x[at(r)],
        };
    }
    let (top, bot) = block(nd, l);
    let first = at(nd.start);
    let mut xt = MatMut::from_column_major_slice_mut(&mut x[first..first + nd.size], nd.size, 1);
    let tmp = MatRef::from_column_major_slice(&work[..m], m, 1);
    matmul_with_conj(
        xt.as_mut(),
        Accum::Add,
        bot.transpose(),
        Conj::No,
        tmp,
        Conj::No,
        -1.0,
        Par::Seq,
    );
    solve_upper_triangular_in_place_with_conj(top.transpose(), Conj::No, xt, Par::Seq);
}
