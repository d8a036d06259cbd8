//! MLS weight functions: the cubic spline of Eq. (5) (corrected per ERRATA
//! E1) on a rectangular, tensor-product support (Eqs. 6–8, ERRATA E2).

/// Cubic spline weight `w(r)` and its derivative `dw/dr`, Eq. (5) corrected
/// per ERRATA E1:
/// `w = 2/3 − 4r² + 4r³` for `r ≤ 1/2`,
/// `w = 4/3 − 4r + 4r² − (4/3)r³` for `1/2 < r ≤ 1`, `0` beyond.
/// C² at `r = 1/2`; `w(1) = w'(1) = 0`. `r ≥ 0`.
#[inline(always)]
pub fn cubic_spline(r: f64) -> (f64, f64) {
    if r <= 0.5 {
        (
            2.0 / 3.0 - 4.0 * r * r + 4.0 * r * r * r,
            -8.0 * r + 12.0 * r * r,
        )
    } else if r <= 1.0 {
        let s = 1.0 - r;
        // 4/3 − 4r + 4r² − (4/3)r³ = (4/3)(1 − r)³
        ((4.0 / 3.0) * s * s * s, -4.0 * s * s)
    } else {
        (0.0, 0.0)
    }
}

/// Tensor-product weight of a node at `(xi, yi)` with support half-widths
/// `(dx, dy)` = `d_max·(c_xI, c_yI)`, evaluated at `(x, y)`: Eq. (6) with
/// `r_x = |x − x_I|/d_mx` (Eq. 7) and `r_y = |y − y_I|/d_my` (Eq. 8 per
/// ERRATA E2). Returns `(w, ∂w/∂x, ∂w/∂y)`, or `None` when the point is
/// outside the open support (weight zero).
#[inline(always)]
pub fn tensor_weight(x: f64, y: f64, xi: f64, yi: f64, dx: f64, dy: f64) -> Option<[f64; 3]> {
    let ddx = x - xi;
    let ddy = y - yi;
    let rx = ddx.abs() / dx;
    let ry = ddy.abs() / dy;
    if rx >= 1.0 || ry >= 1.0 {
        return None;
    }
    let (wx, dwx) = cubic_spline(rx);
    let (wy, dwy) = cubic_spline(ry);
    let dwx = dwx * ddx.signum() / dx;
    let dwy = dwy * ddy.signum() / dy;
    Some([wx * wy, dwx * wy, wx * dwy])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spline_is_c2_and_vanishes_at_one() {
        let (w0, d0) = cubic_spline(0.0);
        assert!((w0 - 2.0 / 3.0).abs() < 1e-15 && d0 == 0.0);
        let (a, da) = cubic_spline(0.5);
        let (b, db) = cubic_spline(0.5 + 1e-12);
        assert!((a - b).abs() < 1e-11 && (da - db).abs() < 1e-10);
        // second derivatives at 1/2: −8 + 24r = 4 and 8(1 − r) = 4
        let (w1, d1) = cubic_spline(1.0);
        assert_eq!((w1, d1), (0.0, 0.0));
        assert_eq!(cubic_spline(1.5), (0.0, 0.0));
        // the second branch equals the printed polynomial with r³ (E1)
        let r: f64 = 0.8;
        let poly = 4.0 / 3.0 - 4.0 * r + 4.0 * r * r - 4.0 / 3.0 * r.powi(3);
        assert!((cubic_spline(r).0 - poly).abs() < 1e-15);
    }

    #[test]
    fn derivative_matches_finite_differences() {
        for &r in &[0.1, 0.3, 0.49, 0.51, 0.7, 0.95] {
            let h = 1e-6;
            let fd = (cubic_spline(r + h).0 - cubic_spline(r - h).0) / (2.0 * h);
            assert!((fd - cubic_spline(r).1).abs() < 1e-8, "r = {r}");
        }
    }
}
