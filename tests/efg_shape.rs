//! Validation 1: MLS shape functions (consistency and derivatives).
#![allow(clippy::needless_range_loop)]

use efgdem::Vec2;
use efgdem::efg::shape::{ShapeRow, shape_functions};
use efgdem::efg::support::Support;

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn dense(s: &Support, p: Vec2, row: &mut ShapeRow) -> Vec<[f64; 3]> {
    shape_functions(s, p, row).unwrap();
    let mut v = vec![[0.0; 3]; s.len()];
    for k in 0..row.len() {
        v[row.idx[k] as usize] = [row.phi[k], row.dx[k], row.dy[k]];
    }
    v
}

fn check_grid(xs: &[f64], ys: &[f64], d_max: f64, seed: u64) -> (f64, f64, f64) {
    let s = Support::for_grid(xs, ys, d_max);
    let (x0, x1) = (xs[0], *xs.last().unwrap());
    let (y0, y1) = (ys[0], *ys.last().unwrap());
    let scale = (x1 - x0).max(y1 - y0);
    let mut rng = Lcg(seed);
    let mut row = ShapeRow::new();
    let (mut e0, mut e1, mut efd) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..500 {
        let p = Vec2::new(x0 + rng.next() * (x1 - x0), y0 + rng.next() * (y1 - y0));
        let v = dense(&s, p, &mut row);
        let (mut sum, mut sx, mut sy) = (0.0, 0.0, 0.0);
        let (mut dsum, mut dxx, mut dxy, mut dyx, mut dyy, mut dysum) =
            (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for (i, f) in v.iter().enumerate() {
            let n = s.node[i];
            sum += f[0];
            sx += f[0] * n[0];
            sy += f[0] * n[1];
            dsum += f[1];
            dysum += f[2];
            dxx += f[1] * n[0];
            dxy += f[1] * n[1];
            dyx += f[2] * n[0];
            dyy += f[2] * n[1];
        }
        e0 = e0
            .max((sum - 1.0).abs())
            .max((sx - p.x).abs() / scale)
            .max((sy - p.y).abs() / scale);
        e1 = e1
            .max(dsum.abs() * scale)
            .max(dysum.abs() * scale)
            .max((dxx - 1.0).abs())
            .max(dxy.abs())
            .max(dyx.abs())
            .max((dyy - 1.0).abs());
        // central finite differences
        let h = 2e-6 * scale;
        let vxp = dense(&s, Vec2::new(p.x + h, p.y), &mut row);
        let vxm = dense(&s, Vec2::new(p.x - h, p.y), &mut row);
        let vyp = dense(&s, Vec2::new(p.x, p.y + h), &mut row);
        let vym = dense(&s, Vec2::new(p.x, p.y - h), &mut row);
        let dmax = v
            .iter()
            .map(|f| f[1].abs().max(f[2].abs()))
            .fold(0.0, f64::max);
        for i in 0..v.len() {
            let fx = (vxp[i][0] - vxm[i][0]) / (2.0 * h);
            let fy = (vyp[i][0] - vym[i][0]) / (2.0 * h);
            efd = efd
                .max((fx - v[i][1]).abs() / dmax)
                .max((fy - v[i][2]).abs() / dmax);
        }
    }
    (e0, e1, efd)
}

#[test]
fn shape_functions_reproduce_linear_fields_and_match_finite_differences() {
    // uniform grid, shifted far from the origin (conditioning of the scaled basis)
    let xs: Vec<f64> = (0..13).map(|i| 1000.0 + 0.25 * i as f64).collect();
    let ys: Vec<f64> = (0..7).map(|j| -500.0 + 0.2 * j as f64).collect();
    let (e0, e1, efd) = check_grid(&xs, &ys, 2.0, 1);
    println!("uniform: consistency {e0:.2e}, derivative consistency {e1:.2e}, FD {efd:.2e}");
    assert!(e0 < 1e-12, "Σφ = 1, Σφx = x: {e0:e}");
    assert!(e1 < 1e-10, "Σφ,x = 0, Σφ,x x = 1: {e1:e}");
    assert!(efd < 1e-6, "finite differences: {efd:e}");
    // graded grid, other d_max
    let xs: Vec<f64> = (0..15).map(|i| (i as f64 / 14.0).powf(1.3) * 3.0).collect();
    let ys: Vec<f64> = (0..9).map(|j| (j as f64 / 8.0).powi(2) * 2.0).collect();
    let (e0, e1, efd) = check_grid(&xs, &ys, 2.5, 7);
    println!("graded: consistency {e0:.2e}, derivative consistency {e1:.2e}, FD {efd:.2e}");
    assert!(
        e0 < 1e-12 && e1 < 1e-10 && efd < 1e-6,
        "{e0:e} {e1:e} {efd:e}"
    );
}

#[test]
fn too_small_support_is_an_error_naming_the_point() {
    let xs: Vec<f64> = (0..5).map(|i| i as f64).collect();
    let s = Support::for_grid(&xs, &xs, 1.0);
    let mut row = ShapeRow::new();
    let e = shape_functions(&s, Vec2::new(2.0, 2.0), &mut row).unwrap_err();
    assert_eq!(e.covering, 1);
    let msg = e.to_string();
    assert!(msg.contains("(2, 2)") && msg.contains("d_max"), "{msg}");
    // collinear: nodes on one line
    let s = Support::new((0..5).map(|i| [i as f64, 0.0, 2.0, 2.0]).collect());
    let e = shape_functions(&s, Vec2::new(1.5, 0.5), &mut row).unwrap_err();
    assert!(e.covering >= 3, "{e}");
    assert!(e.to_string().contains("collinear"));
}

/// Regression (issue 12): a 42 × 8 node grid on a 40 × 6 rectangle has
/// nodes at the very edge of other nodes' supports, where `|Δx| < d_m` and
/// `|Δx|/d_m < 1` disagree by one rounding; the nodal shape rows (frames)
/// overran their buffer. `covers` and the shape functions now agree at
/// every node.
#[test]
fn nodes_on_the_edge_of_a_support_are_counted_as_the_shape_functions_see_them() {
    use efgdem::continuum::{BodyParams, Edge, EdgeCondition, Elastic, Rectangle};
    let mut p = BodyParams::new(
        "footing",
        Rectangle {
            origin: [0.0, 0.0],
            size: [40.0, 6.0],
        },
        [42, 8],
        Elastic::new(1e9, 0.2).density(2400.0),
    );
    p.bc.push(EdgeCondition::fixed(Edge::Bottom));
    let b = efgdem::efg::EfgBody::new(&p, [0.0, 0.0]).expect("builds");
    let shapes = b.nodal_shapes().expect("nodal shape rows");
    let mut row = efgdem::efg::ShapeRow::new();
    let mut covering = Vec::new();
    for i in 0..b.n_nodes() {
        b.support.covering(b.node(i), &mut covering);
        efgdem::efg::shape::shape_functions(&b.support, b.node(i), &mut row).unwrap();
        assert_eq!(covering.len(), row.len(), "node {i}");
        assert_eq!(shapes.ptr[i + 1] - shapes.ptr[i], row.len(), "node {i}");
    }
}
