//! Assembly of the EFG operators (Eqs. 21–32): stiffness K (Eq. 25, B per
//! ERRATA E5), the Gram matrix `∫ΦᵀΦ t dΩ` from which the consistent mass
//! (Eq. 23) and the mass-proportional damping (Eq. 24) follow, and the
//! penalty points of the boundary integral (ERRATA E4), kept apart
//! ([`Penalty`]: `K̄ = K + K^α` on demand, the penalty energy from the gap).
//!
//! Determinism: shape functions are computed per quadrature point (in
//! parallel, each point independently); the matrices are then *gathered*
//! column by column: node I sums, in increasing point order, the
//! contributions of every point its support covers to its own columns
//! `2I, 2I+1` of the lower triangle. Every entry is therefore summed in one
//! fixed order, and the result is bitwise identical for any thread count.

use super::penalty::Penalty;
use super::shape::{CoverageError, ShapeRow, shape_functions};
use super::support::Support;
use crate::geom::Vec2;
use crate::sparse::{Pattern, SymCsc};
use rayon::prelude::*;
use std::sync::Arc;

/// Shape functions precomputed at a list of points (CSR): the nodes covering
/// point `g` are `idx[ptr[g]..ptr[g+1]]` with `[φ, φ,x, φ,y]` in `val`.
#[derive(Debug, Clone, Default)]
pub struct PointShapes {
    /// Row starts, one per point plus the end.
    pub ptr: Vec<usize>,
    /// Covering node of each entry.
    pub idx: Vec<u32>,
    /// `[φ_I, φ_I,x, φ_I,y]` of each entry (Eqs. 13–14 per E3).
    pub val: Vec<[f64; 3]>,
}

impl PointShapes {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.ptr.len().saturating_sub(1)
    }
    /// No points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Fewest nodes covering any point.
    pub fn min_cover(&self) -> usize {
        self.ptr.windows(2).map(|w| w[1] - w[0]).min().unwrap_or(0)
    }
    /// Most nodes covering any point.
    pub fn max_cover(&self) -> usize {
        self.ptr.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0)
    }
}

const CHUNK: usize = 256;

/// Shape functions and derivatives at every point, in parallel. On failure
/// the error names the first failing point (in point order).
pub fn point_shapes(support: &Support, points: &[Vec2]) -> Result<PointShapes, CoverageError> {
    let counts: Vec<usize> = points
        .par_iter()
        .map(|&p| {
            support
                .candidates(p)
                .iter()
                .filter(|&&k| support.covers(k as usize, p))
                .count()
        })
        .collect();
    let mut ptr = Vec::with_capacity(points.len() + 1);
    ptr.push(0usize);
    for c in &counts {
        ptr.push(ptr.last().copied().unwrap_or(0) + c);
    }
    drop(counts);
    let total = ptr[points.len()];
    let mut idx = vec![0u32; total];
    let mut val = vec![[0.0f64; 3]; total];
    // disjoint output slices, one per chunk of points
    let mut jobs = Vec::with_capacity(points.len().div_ceil(CHUNK));
    {
        let (mut ri, mut rv) = (&mut idx[..], &mut val[..]);
        for c0 in (0..points.len()).step_by(CHUNK) {
            let c1 = (c0 + CHUNK).min(points.len());
            let len = ptr[c1] - ptr[c0];
            let (a, b) = std::mem::take(&mut ri).split_at_mut(len);
            let (va, vb) = std::mem::take(&mut rv).split_at_mut(len);
            ri = b;
            rv = vb;
            jobs.push((c0, c1, a, va));
        }
    }
    let results: Vec<Result<(), CoverageError>> = jobs
        .into_par_iter()
        .map(|(c0, c1, oi, ov)| {
            let mut row = ShapeRow::new();
            let base = ptr[c0];
            for g in c0..c1 {
                shape_functions(support, points[g], &mut row)?;
                let s = ptr[g] - base;
                for k in 0..row.len() {
                    oi[s + k] = row.idx[k];
                    ov[s + k] = [row.phi[k], row.dx[k], row.dy[k]];
                }
            }
            Ok(())
        })
        .collect();
    for r in results {
        r?;
    }
    Ok(PointShapes { ptr, idx, val })
}

/// What one quadrature point contributes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PointRole {
    /// Domain point with weight `w·t`: stiffness and Gram matrix.
    Domain(f64),
    /// Boundary point on Γu: penalty weights `α_x·w·t`, `α_y·w·t` (E4),
    /// kept in [`Operators::penalty`].
    Penalty(f64, f64),
}

/// The assembled operators of one body, lower triangles on one pattern.
#[derive(Debug, Clone)]
pub struct Operators {
    /// The elastic stiffness K (Eq. 25 with B per E5), on a pattern that
    /// also holds the couplings of the penalty points.
    pub k: SymCsc,
    /// The penalty points (E4), in point order; their prescribed values are
    /// zero until the body sets them.
    pub penalty: Penalty,
    /// `G = ∫ ΦᵀΦ t dΩ`: consistent mass `M = ρG` (Eq. 23), damping `C = cG` (Eq. 24).
    pub gram: SymCsc,
    /// `∫ φ_I t dΩ` per node (body force per unit density and acceleration, Eq. 27).
    pub phi_integral: Vec<f64>,
}

impl Operators {
    /// `K̄ = K + K^α` (Eq. 25 plus the boundary penalty of E4), bitwise
    /// what one assembly pass over all points would give.
    pub fn kbar(&self) -> SymCsc {
        self.penalty.stiffen(&self.k)
    }
}

/// Assemble `K`, `G`, `∫φ t` and the penalty points from precomputed point
/// shapes. `roles[g]` says how point `g` contributes; `d` is the
/// elasticity matrix.
pub fn assemble(
    n_nodes: usize,
    shapes: &PointShapes,
    roles: &[PointRole],
    d: [f64; 4],
) -> Operators {
    let npts = shapes.len();
    assert_eq!(roles.len(), npts);
    // node → (point, local index) in increasing point order (counting sort)
    let mut nptr = vec![0usize; n_nodes + 1];
    for &i in &shapes.idx {
        nptr[i as usize + 1] += 1;
    }
    for i in 0..n_nodes {
        nptr[i + 1] += nptr[i];
    }
    let mut fill = nptr.clone();
    let mut list = vec![(0u32, 0u32); shapes.idx.len()];
    for g in 0..npts {
        for k in shapes.ptr[g]..shapes.ptr[g + 1] {
            let i = shapes.idx[k] as usize;
            list[fill[i]] = (g as u32, (k - shapes.ptr[g]) as u32);
            fill[i] += 1;
        }
    }
    drop(fill);
    // node-level pattern: J ≥ I sharing a point with I, sorted
    let node_pat: Vec<Vec<u32>> = (0..n_nodes)
        .into_par_iter()
        .map_init(
            || vec![false; n_nodes],
            |mark, i| {
                // the node itself always (an uncovered node gives a zero
                // pivot, reported by the factorisation)
                let mut js = Vec::with_capacity(32);
                js.push(i as u32);
                mark[i] = true;
                for &(g, a) in &list[nptr[i]..nptr[i + 1]] {
                    let s = shapes.ptr[g as usize];
                    let e = shapes.ptr[g as usize + 1];
                    for &j in &shapes.idx[s + a as usize..e] {
                        if !mark[j as usize] {
                            mark[j as usize] = true;
                            js.push(j);
                        }
                    }
                }
                for &j in &js {
                    mark[j as usize] = false;
                }
                js.sort_unstable();
                js
            },
        )
        .collect();
    // DOF-level lower-triangle pattern
    let ndof = 2 * n_nodes;
    let mut col_ptr = Vec::with_capacity(ndof + 1);
    col_ptr.push(0usize);
    for p in &node_pat {
        let m = p.len();
        let c0 = *col_ptr.last().unwrap_or(&0);
        col_ptr.push(c0 + 2 * m);
        col_ptr.push(c0 + 4 * m - 1);
    }
    let nnz = col_ptr[ndof];
    let mut row_idx = vec![0usize; nnz];
    let mut kvals = vec![0.0f64; nnz];
    let mut gvals = vec![0.0f64; nnz];
    // per-node disjoint slices of rows / values
    {
        let mut jobs = Vec::with_capacity(n_nodes);
        let (mut r, mut kv, mut gv) = (&mut row_idx[..], &mut kvals[..], &mut gvals[..]);
        for i in 0..n_nodes {
            let len = col_ptr[2 * i + 2] - col_ptr[2 * i];
            let (a, b) = std::mem::take(&mut r).split_at_mut(len);
            let (ka, kb) = std::mem::take(&mut kv).split_at_mut(len);
            let (ga, gb) = std::mem::take(&mut gv).split_at_mut(len);
            r = b;
            kv = kb;
            gv = gb;
            jobs.push((i, a, ka, ga));
        }
        let [d11, d12, d22, d33] = d;
        jobs.into_par_iter().for_each_init(
            || vec![u32::MAX; n_nodes],
            |slot, (i, rows, kv, gv)| {
                let pat = &node_pat[i];
                let l0 = 2 * pat.len();
                for (k, &j) in pat.iter().enumerate() {
                    slot[j as usize] = k as u32;
                    rows[2 * k] = 2 * j as usize;
                    rows[2 * k + 1] = 2 * j as usize + 1;
                    if k == 0 {
                        rows[l0] = 2 * j as usize + 1;
                    } else {
                        rows[l0 + 2 * k - 1] = 2 * j as usize;
                        rows[l0 + 2 * k] = 2 * j as usize + 1;
                    }
                }
                let (k0, k1) = kv.split_at_mut(l0);
                let (g0, g1) = gv.split_at_mut(l0);
                for &(g, a) in &list[nptr[i]..nptr[i + 1]] {
                    let g = g as usize;
                    let s = shapes.ptr[g] + a as usize;
                    let e = shapes.ptr[g + 1];
                    let vi = shapes.val[s];
                    // penalty points: pattern only (K^α: Operators::kbar)
                    if let PointRole::Domain(w) = roles[g] {
                        let (fx, fy, fm) = (w * vi[1], w * vi[2], w * vi[0]);
                        let (ax, ay) = (d11 * fx, d22 * fy);
                        let (bx, by) = (d12 * fx, d12 * fy);
                        let (cx, cy) = (d33 * fx, d33 * fy);
                        for t in s..e {
                            let j = shapes.idx[t] as usize;
                            let k = slot[j] as usize;
                            let vj = shapes.val[t];
                            let kxx = vj[1] * ax + vj[2] * cy;
                            let kyx = vj[2] * bx + vj[1] * cy;
                            let kxy = vj[1] * by + vj[2] * cx;
                            let kyy = vj[2] * ay + vj[1] * cx;
                            let m = vj[0] * fm;
                            k0[2 * k] += kxx;
                            k0[2 * k + 1] += kyx;
                            g0[2 * k] += m;
                            if k == 0 {
                                k1[0] += kyy;
                                g1[0] += m;
                            } else {
                                k1[2 * k - 1] += kxy;
                                k1[2 * k] += kyy;
                                g1[2 * k] += m;
                            }
                        }
                    }
                }
                for &j in pat {
                    slot[j as usize] = u32::MAX;
                }
            },
        );
    }
    drop(list);
    // ∫ φ_I t dΩ, fixed (point) order
    let mut phi_integral = vec![0.0; n_nodes];
    for (g, role) in roles.iter().enumerate() {
        if let PointRole::Domain(w) = *role {
            for t in shapes.ptr[g]..shapes.ptr[g + 1] {
                phi_integral[shapes.idx[t] as usize] += w * shapes.val[t][0];
            }
        }
    }
    let mut penalty = Penalty::new();
    for (g, role) in roles.iter().enumerate() {
        if let PointRole::Penalty(px, py) = *role {
            let r = shapes.ptr[g]..shapes.ptr[g + 1];
            let phi = shapes.val[r.clone()].iter().map(|v| v[0]);
            penalty.push(shapes.idx[r].iter().copied().zip(phi), [px, py]);
        }
    }
    let pattern = Arc::new(Pattern {
        n: ndof,
        col_ptr,
        row_idx,
    });
    Operators {
        k: SymCsc {
            pattern: pattern.clone(),
            values: kvals,
        },
        gram: SymCsc {
            pattern,
            values: gvals,
        },
        phi_integral,
        penalty,
    }
}
