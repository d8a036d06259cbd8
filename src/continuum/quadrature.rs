//! Background integration: rectangular cells with n × n Gauss points over the
//! body (Fig. 1), and Gauss points along boundary edges.

use crate::geom::Vec2;

/// A quadrature point: position and weight (area or length, Jacobian included).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadPoint {
    /// Position (reference configuration).
    pub x: Vec2,
    /// Weight: area (domain) or length (edge) it stands for, without the
    /// thickness.
    pub w: f64,
}

/// Gauss–Legendre abscissae and weights on [−1, 1], `n ≥ 1` (Newton on
/// Legendre polynomials; exact for polynomials of degree 2n − 1).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let n = n.max(1);
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { z } else { p1 };
            let pnm1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (z * pn - pnm1) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        if n == 1 {
            z = 0.0;
            dp = 1.0;
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        let wi = 2.0 / ((1.0 - z * z) * dp * dp);
        w[i] = wi;
        w[n - 1 - i] = wi;
    }
    if n == 1 {
        w[0] = 2.0;
    }
    (x, w)
}

/// Gauss points of a rectangle `[origin, origin + size]` split into
/// `cells[0] × cells[1]` background cells, `n × n` points per cell. Ordered
/// cell by cell (cells row-major, bottom row first), `n²` points per cell.
pub fn domain_points(origin: Vec2, size: Vec2, cells: [usize; 2], n: usize) -> Vec<QuadPoint> {
    let (gx, gw) = gauss_legendre(n);
    let (hx, hy) = (size.x / cells[0] as f64, size.y / cells[1] as f64);
    let jac = 0.25 * hx * hy;
    let mut out = Vec::with_capacity(cells[0] * cells[1] * n * n);
    for cj in 0..cells[1] {
        for ci in 0..cells[0] {
            let cx = origin.x + (ci as f64 + 0.5) * hx;
            let cy = origin.y + (cj as f64 + 0.5) * hy;
            for b in 0..gx.len() {
                for a in 0..gx.len() {
                    out.push(QuadPoint {
                        x: Vec2::new(cx + 0.5 * hx * gx[a], cy + 0.5 * hy * gx[b]),
                        w: jac * gw[a] * gw[b],
                    });
                }
            }
        }
    }
    out
}

/// Gauss points along the segment `a → b`, split into `segments` equal
/// pieces with `n` points each; weights are lengths.
pub fn edge_points(a: Vec2, b: Vec2, segments: usize, n: usize) -> Vec<QuadPoint> {
    let (gx, gw) = gauss_legendre(n);
    let segments = segments.max(1);
    let d = (b - a) * (1.0 / segments as f64);
    let half = 0.5 * d.norm();
    let mut out = Vec::with_capacity(segments * gx.len());
    for s in 0..segments {
        let c = a + d * (s as f64 + 0.5);
        for (x, w) in gx.iter().zip(&gw) {
            out.push(QuadPoint {
                x: c + d * (0.5 * x),
                w: half * w,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in 1..=8 {
            let (x, w) = gauss_legendre(n);
            for deg in 0..2 * n {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(deg as i32)).sum();
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                assert!(
                    (q - exact).abs() < 1e-13,
                    "n = {n}, degree {deg}: {q} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn cell_and_edge_weights_sum_to_area_and_length() {
        let p = domain_points(Vec2::new(1.0, -2.0), Vec2::new(3.0, 2.0), [3, 4], 4);
        assert_eq!(p.len(), 3 * 4 * 16);
        let area: f64 = p.iter().map(|q| q.w).sum();
        assert!((area - 6.0).abs() < 1e-12);
        let first: f64 = p.iter().map(|q| q.w * q.x.x * q.x.y).sum();
        // ∫∫ x y over [1,4]×[−2,0] = 7.5 · (−2)
        assert!((first + 15.0).abs() < 1e-12);
        let e = edge_points(Vec2::new(0.0, 0.0), Vec2::new(3.0, 4.0), 5, 3);
        let len: f64 = e.iter().map(|q| q.w).sum();
        assert!((len - 5.0).abs() < 1e-12);
    }
}
