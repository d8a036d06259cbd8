//! MLS shape functions with the linear basis `p = [1, x, y]` (Eqs. 1–16),
//! in the shifted-and-scaled form allowed by ERRATA E3, with exact first
//! derivatives.
//!
//! At an evaluation point `x̄` the basis is `p(z) = [1, (z_x − x̄_x)/h_x,
//! (z_y − x̄_y)/h_y]` with `x̄` held fixed while differentiating; MLS is
//! invariant under such affine changes of the basis, so the shape functions
//! are exactly those of `[1, x, y]` but the 3 × 3 moment matrix `A` stays
//! well conditioned whatever the coordinates. Then (Liu & Gu §5.3)
//! `φ_I = γᵀ B_I`, `γ = A⁻¹ p(x̄)`, `B_I = w_I p_I`, and
//! `φ_I,k = γ,kᵀ B_I + γᵀ B_I,k` with `γ,k = A⁻¹ (p,k − A,k γ)`, which is
//! `p,kᵀA⁻¹B + pᵀ(A⁻¹),kB + pᵀA⁻¹B,k` written without forming `A⁻¹,k`.

use super::support::Support;
use crate::geom::Vec2;

/// Why shape functions could not be built at a point.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "the point ({x}, {y}) is covered by {covering} node support(s){}; MLS needs at least 3 non-collinear nodes: increase d_max (support size) or refine the node grid",
    if *covering >= 3 { " that are (nearly) collinear" } else { "" }
)]
pub struct CoverageError {
    /// x of the point.
    pub x: f64,
    /// y of the point.
    pub y: f64,
    /// Number of nodes whose support covers it.
    pub covering: usize,
}

/// Shape functions at one point: the covering nodes `idx` (increasing) and
/// `φ_I`, `φ_I,x`, `φ_I,y`. Reuse one `ShapeRow` across calls: after warm-up
/// no call allocates.
#[derive(Debug, Clone, Default)]
pub struct ShapeRow {
    /// Covering nodes, increasing.
    pub idx: Vec<u32>,
    /// `φ_I(x)` (Eq. 13 per E3); sums to 1.
    pub phi: Vec<f64>,
    /// `φ_I,x(x)` (Eq. 14 per E3); sums to 0.
    pub dx: Vec<f64>,
    /// `φ_I,y(x)`; sums to 0.
    pub dy: Vec<f64>,
    /// Scratch: the shifted, scaled basis `p_I` of each covering node.
    basis: Vec<[f64; 2]>,
}

impl ShapeRow {
    /// An empty row with room for 32 covering nodes.
    pub fn new() -> Self {
        Self::with_capacity(32)
    }
    /// An empty row with room for `n` covering nodes.
    pub fn with_capacity(n: usize) -> Self {
        ShapeRow {
            idx: Vec::with_capacity(n),
            phi: Vec::with_capacity(n),
            dx: Vec::with_capacity(n),
            dy: Vec::with_capacity(n),
            basis: Vec::with_capacity(n),
        }
    }
    /// Number of covering nodes.
    pub fn len(&self) -> usize {
        self.idx.len()
    }
    /// No covering node (not computed yet).
    pub fn is_empty(&self) -> bool {
        self.idx.is_empty()
    }
    /// `Σ φ_I v_I` of a nodal field with `ncomp` interleaved components
    /// (`ncomp = 2` for displacement), component `c`.
    #[inline]
    pub fn interpolate(&self, v: &[f64], ncomp: usize, c: usize) -> f64 {
        self.idx
            .iter()
            .zip(&self.phi)
            .map(|(&i, &p)| p * v[i as usize * ncomp + c])
            .sum()
    }
}

/// Smallest accepted `det(A)/(A₀₀A₁₁A₂₂)` (Hadamard ratio, 1 for an
/// orthogonal basis, 0 for collinear nodes).
const MIN_HADAMARD: f64 = 1e-10;

/// MLS shape functions and their first derivatives at `p` (Eqs. 12–16 per
/// ERRATA E3), written into `row`. Error if fewer than 3 non-collinear nodes
/// cover `p`.
#[inline]
pub fn shape_functions(
    support: &Support,
    p: Vec2,
    row: &mut ShapeRow,
) -> Result<(), CoverageError> {
    row.idx.clear();
    row.phi.clear();
    row.dx.clear();
    row.dy.clear();
    row.basis.clear();
    let cand = support.candidates(p);
    let Some(&c0) = cand.first() else {
        return Err(CoverageError {
            x: p.x,
            y: p.y,
            covering: 0,
        });
    };
    // basis scale: the support half-widths of one candidate (any fixed
    // positive scale gives the same φ; this one keeps A well conditioned)
    let inv = &support.inv_half;
    let (ihx, ihy) = (inv[c0 as usize][0], inv[c0 as usize][1]);
    // one pass: weights (Eqs. 5–8), shifted-scaled basis, moment matrix
    // A = Σ w p pᵀ and its derivatives (symmetric: 6 entries each)
    let mut a = [0.0f64; 6];
    let mut ax = [0.0f64; 6];
    let mut ay = [0.0f64; 6];
    for &k in cand {
        let n = &support.node[k as usize];
        let iv = inv[k as usize];
        let ddx = p.x - n[0];
        let ddy = p.y - n[1];
        let rx = ddx.abs() * iv[0];
        let ry = ddy.abs() * iv[1];
        if rx >= 1.0 || ry >= 1.0 {
            continue;
        }
        let (w, w_x, w_y) = if support.hidden(k as usize, p) {
            // diffraction: the offset scaled by f = (s₁ + s₂)/s₀
            let Some((f, [fx, fy])) = support.diffraction(k as usize, p) else {
                continue;
            };
            let (ex, ey) = (ddx * f, ddy * f);
            let rx = ex.abs() * iv[0];
            let ry = ey.abs() * iv[1];
            if rx >= 1.0 || ry >= 1.0 {
                continue;
            }
            let (wx, dwx) = super::weight::cubic_spline(rx);
            let (wy, dwy) = super::weight::cubic_spline(ry);
            let (sx, sy) = (ex.signum() * iv[0], ey.signum() * iv[1]);
            let (rx_x, rx_y) = (sx * (f + ddx * fx), sx * ddx * fy);
            let (ry_x, ry_y) = (sy * ddy * fx, sy * (f + ddy * fy));
            (
                wx * wy,
                dwx * rx_x * wy + wx * dwy * ry_x,
                dwx * rx_y * wy + wx * dwy * ry_y,
            )
        } else {
            let (wx, dwx) = super::weight::cubic_spline(rx);
            let (wy, dwy) = super::weight::cubic_spline(ry);
            let dwx = dwx * ddx.signum() * iv[0];
            let dwy = dwy * ddy.signum() * iv[1];
            (wx * wy, dwx * wy, wx * dwy)
        };
        let px = -ddx * ihx;
        let py = -ddy * ihy;
        let q = [1.0, px, py, px * px, px * py, py * py];
        for t in 0..6 {
            a[t] += w * q[t];
            ax[t] += w_x * q[t];
            ay[t] += w_y * q[t];
        }
        row.idx.push(k);
        row.phi.push(w);
        row.dx.push(w_x);
        row.dy.push(w_y);
        row.basis.push([px, py]);
    }
    let m = row.idx.len();
    let err = || CoverageError {
        x: p.x,
        y: p.y,
        covering: m,
    };
    if m < 3 {
        return Err(err());
    }
    // a = [a00, a01, a02, a11, a12, a22]
    let [a00, a01, a02, a11, a12, a22] = a;
    let c00 = a11 * a22 - a12 * a12;
    let c01 = a02 * a12 - a01 * a22;
    let c02 = a01 * a12 - a02 * a11;
    let det = a00 * c00 + a01 * c01 + a02 * c02;
    let diag = a00 * a11 * a22;
    if !det.is_finite() || det <= MIN_HADAMARD * diag {
        return Err(err());
    }
    let id = 1.0 / det;
    let c11 = a00 * a22 - a02 * a02;
    let c12 = a01 * a02 - a00 * a12;
    let c22 = a00 * a11 - a01 * a01;
    // A⁻¹ (symmetric)
    let inv = [c00 * id, c01 * id, c02 * id, c11 * id, c12 * id, c22 * id];
    let mulsym = |s: &[f64; 6], v: [f64; 3]| {
        [
            s[0] * v[0] + s[1] * v[1] + s[2] * v[2],
            s[1] * v[0] + s[3] * v[1] + s[4] * v[2],
            s[2] * v[0] + s[4] * v[1] + s[5] * v[2],
        ]
    };
    // γ = A⁻¹ e₀ (p(x̄) = e₀)
    let g = [inv[0], inv[1], inv[2]];
    // γ,x = A⁻¹ (p,x − A,x γ), p,x = [0, 1/h_x, 0]
    let axg = mulsym(&ax, g);
    let gx = mulsym(&inv, [-axg[0], ihx - axg[1], -axg[2]]);
    let ayg = mulsym(&ay, g);
    let gy = mulsym(&inv, [-ayg[0], -ayg[1], ihy - ayg[2]]);
    for k in 0..m {
        let [px, py] = row.basis[k];
        let (w, wx, wy) = (row.phi[k], row.dx[k], row.dy[k]);
        let gp = g[0] + g[1] * px + g[2] * py;
        let gxp = gx[0] + gx[1] * px + gx[2] * py;
        let gyp = gy[0] + gy[1] * px + gy[2] * py;
        row.phi[k] = w * gp;
        row.dx[k] = w * gxp + wx * gp;
        row.dy[k] = w * gyp + wy * gp;
    }
    Ok(())
}
