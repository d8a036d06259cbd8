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

/// Dunavant's 7-point rule on a triangle (degree 5, Dunavant 1985): the
/// centroid and two orbits `(α, α, 1 − 2α)` with `α = (6 ∓ √15)/21` and
/// weights `(155 ∓ √15)/1200` (fractions of the area). Each triangle
/// `[a, b, c]` is first split into `sub²` similar sub-triangles (`sub ≥ 1`).
/// Points are appended triangle by triangle.
pub fn triangle_points(tris: &[[Vec2; 3]], sub: usize, out: &mut Vec<QuadPoint>) {
    let r15 = 15f64.sqrt();
    let (a1, a2) = ((6.0 - r15) / 21.0, (6.0 + r15) / 21.0);
    let (w1, w2) = ((155.0 - r15) / 1200.0, (155.0 + r15) / 1200.0);
    let mut rule: Vec<([f64; 3], f64)> = vec![([1.0 / 3.0; 3], 9.0 / 40.0)];
    for (a, w) in [(a1, w1), (a2, w2)] {
        let b = 1.0 - 2.0 * a;
        rule.push(([a, a, b], w));
        rule.push(([a, b, a], w));
        rule.push(([b, a, a], w));
    }
    let sub = sub.max(1);
    let inv = 1.0 / sub as f64;
    for &[a, b, c] in tris {
        let (e1, e2) = ((b - a) * inv, (c - a) * inv);
        let area = 0.5 * e1.cross(e2).abs();
        // sub-triangles: (i, j) upward and (i, j) downward
        for j in 0..sub {
            for i in 0..sub - j {
                let o = a + e1 * i as f64 + e2 * j as f64;
                let mut tri = vec![[o, o + e1, o + e2]];
                if i + j + 1 < sub {
                    tri.push([o + e1, o + e1 + e2, o + e2]);
                }
                for [p, q, r] in tri {
                    for (l, w) in &rule {
                        out.push(QuadPoint {
                            x: p * l[0] + q * l[1] + r * l[2],
                            w: w * area,
                        });
                    }
                }
            }
        }
    }
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

    #[test]
    fn triangle_rule_is_exact_to_degree_five() {
        let t = [[
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(0.0, 1.0),
        ]];
        for sub in [1, 3] {
            let mut q = Vec::new();
            triangle_points(&t, sub, &mut q);
            assert_eq!(q.len(), 7 * sub * sub);
            // ∫ x^i y^j over the triangle (0,0),(2,0),(0,1): 2^(i+1) i! j! / (i+j+2)!
            let fact = |n: u32| (1..=n).map(f64::from).product::<f64>();
            for i in 0..=5u32 {
                for j in 0..=5 - i {
                    let num: f64 = q
                        .iter()
                        .map(|p| p.w * p.x.x.powi(i as i32) * p.x.y.powi(j as i32))
                        .sum();
                    let exact = 2f64.powi(i as i32 + 1) * fact(i) * fact(j) / fact(i + j + 2);
                    assert!(
                        (num - exact).abs() < 1e-13 * exact.max(1.0),
                        "x^{i} y^{j}: {num} vs {exact}"
                    );
                }
            }
        }
    }
}
