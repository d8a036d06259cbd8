//! 4-node bilinear quadrilateral (Q4): shape functions, element stiffness
//! with 2 × 2 Gauss quadrature, consistent and lumped mass.
//!
//! Node order is counter-clockwise: (−1,−1), (1,−1), (1,1), (−1,1) in the
//! parent square. Element DOFs are interleaved `(u_x, u_y)` per node, like
//! the global DOFs. The constitutive matrix `D` is the same as the EFG body's
//! (Eqs. 31–32); strain is engineering (ERRATA E5).

/// Parent coordinates of the four nodes.
pub const CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// 2 × 2 Gauss points (weights 1).
const G: f64 = 0.577_350_269_189_625_8; // 1/√3

/// Shape functions `N_a(ξ, η)` and their parent derivatives `∂N_a/∂ξ`, `∂N_a/∂η`.
#[inline]
pub fn shape(xi: f64, eta: f64) -> ([f64; 4], [[f64; 2]; 4]) {
    let mut n = [0.0; 4];
    let mut dn = [[0.0; 2]; 4];
    for (a, c) in CORNERS.iter().enumerate() {
        n[a] = 0.25 * (1.0 + c[0] * xi) * (1.0 + c[1] * eta);
        dn[a] = [
            0.25 * c[0] * (1.0 + c[1] * eta),
            0.25 * c[1] * (1.0 + c[0] * xi),
        ];
    }
    (n, dn)
}

/// Physical derivatives `∂N_a/∂x`, `∂N_a/∂y` and the Jacobian determinant at
/// `(ξ, η)` for an element with corner coordinates `xy`.
#[inline]
pub fn gradients(xy: &[[f64; 2]; 4], xi: f64, eta: f64) -> ([[f64; 2]; 4], f64) {
    let (_, dn) = shape(xi, eta);
    let mut j = [[0.0; 2]; 2]; // j[r][c] = ∂x_c/∂ξ_r
    for a in 0..4 {
        for r in 0..2 {
            for c in 0..2 {
                j[r][c] += dn[a][r] * xy[a][c];
            }
        }
    }
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    let inv = [
        [j[1][1] / det, -j[0][1] / det],
        [-j[1][0] / det, j[0][0] / det],
    ];
    let mut g = [[0.0; 2]; 4];
    for a in 0..4 {
        for c in 0..2 {
            g[a][c] = inv[c][0] * dn[a][0] + inv[c][1] * dn[a][1];
        }
    }
    (g, det)
}

/// Element stiffness `K_e = ∫ Bᵀ D B t dA` by 2 × 2 Gauss (exact for a
/// parallelogram), `B` with engineering shear strain (ERRATA E5).
pub fn stiffness(xy: &[[f64; 2]; 4], d: &[[f64; 3]; 3], thickness: f64) -> [[f64; 8]; 8] {
    let mut k = [[0.0; 8]; 8];
    for &(xi, eta) in &[(-G, -G), (G, -G), (G, G), (-G, G)] {
        let (g, det) = gradients(xy, xi, eta);
        let w = det * thickness;
        for a in 0..4 {
            // D·B_a, B_a = [[g_x,0],[0,g_y],[g_y,g_x]]
            let db = |col: usize| -> [f64; 3] {
                let b = if col == 0 {
                    [g[a][0], 0.0, g[a][1]]
                } else {
                    [0.0, g[a][1], g[a][0]]
                };
                [
                    d[0][0] * b[0] + d[0][1] * b[1] + d[0][2] * b[2],
                    d[1][0] * b[0] + d[1][1] * b[1] + d[1][2] * b[2],
                    d[2][0] * b[0] + d[2][1] * b[1] + d[2][2] * b[2],
                ]
            };
            let dba = [db(0), db(1)];
            for b in 0..4 {
                let bb = [[g[b][0], 0.0, g[b][1]], [0.0, g[b][1], g[b][0]]];
                for r in 0..2 {
                    for c in 0..2 {
                        let v: f64 = (0..3).map(|q| bb[r][q] * dba[c][q]).sum();
                        k[2 * b + r][2 * a + c] += w * v;
                    }
                }
            }
        }
    }
    k
}

/// Consistent mass `M_e = ∫ ρ t Nᵀ N dA` (2 × 2 Gauss, exact for a
/// parallelogram), per direction: `m[a][b]` multiplies both `u_x` and `u_y`.
pub fn consistent_mass(xy: &[[f64; 2]; 4], density: f64, thickness: f64) -> [[f64; 4]; 4] {
    let mut m = [[0.0; 4]; 4];
    for &(xi, eta) in &[(-G, -G), (G, -G), (G, G), (-G, G)] {
        let (n, _) = shape(xi, eta);
        let (_, det) = gradients(xy, xi, eta);
        let w = density * thickness * det;
        for a in 0..4 {
            for b in 0..4 {
                m[a][b] += w * n[a] * n[b];
            }
        }
    }
    m
}

/// Lumped (row-sum) mass per node.
pub fn lumped_mass(xy: &[[f64; 2]; 4], density: f64, thickness: f64) -> [f64; 4] {
    let m = consistent_mass(xy, density, thickness);
    [0, 1, 2, 3].map(|a| m[a].iter().sum())
}

/// Parent coordinates `(ξ, η)` of a physical point `p` inside an
/// axis-aligned rectangular element with corners `xy` (the grid elements).
#[inline]
pub fn parent_of_rect(xy: &[[f64; 2]; 4], p: [f64; 2]) -> (f64, f64) {
    let (x0, y0, x1, y1) = (xy[0][0], xy[0][1], xy[2][0], xy[2][1]);
    (
        2.0 * (p[0] - x0) / (x1 - x0) - 1.0,
        2.0 * (p[1] - y0) / (y1 - y0) - 1.0,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane_stress(e: f64, nu: f64) -> [[f64; 3]; 3] {
        let c = e / (1.0 - nu * nu);
        [
            [c, c * nu, 0.0],
            [c * nu, c, 0.0],
            [0.0, 0.0, c * (1.0 - nu) / 2.0],
        ]
    }

    fn skewed() -> [[f64; 2]; 4] {
        [[0.0, 0.0], [2.0, 0.1], [2.3, 1.4], [0.2, 1.1]]
    }

    fn kmul(k: &[[f64; 8]; 8], u: &[f64; 8]) -> [f64; 8] {
        let mut f = [0.0; 8];
        for r in 0..8 {
            f[r] = (0..8).map(|c| k[r][c] * u[c]).sum();
        }
        f
    }

    #[test]
    fn partition_of_unity_and_linear_completeness() {
        for &(xi, eta) in &[(0.3, -0.7), (-1.0, 1.0), (0.0, 0.0)] {
            let (n, dn) = shape(xi, eta);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            let sx: f64 = dn.iter().map(|d| d[0]).sum();
            assert!(sx.abs() < 1e-15);
        }
        let xy = skewed();
        let (g, _) = gradients(&xy, 0.2, 0.4);
        let dxdx: f64 = (0..4).map(|a| g[a][0] * xy[a][0]).sum();
        let dxdy: f64 = (0..4).map(|a| g[a][1] * xy[a][0]).sum();
        assert!((dxdx - 1.0).abs() < 1e-13 && dxdy.abs() < 1e-13);
    }

    #[test]
    fn rigid_body_modes_are_force_free_and_k_is_symmetric() {
        let k = stiffness(&skewed(), &plane_stress(1e3, 0.3), 0.5);
        for r in 0..8 {
            for c in 0..8 {
                assert!((k[r][c] - k[c][r]).abs() < 1e-10 * k[0][0]);
            }
        }
        let xy = skewed();
        let modes: [[f64; 8]; 3] = [
            [1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0],
            // rotation: u = (-y, x)
            [
                -xy[0][1], xy[0][0], -xy[1][1], xy[1][0], -xy[2][1], xy[2][0], -xy[3][1], xy[3][0],
            ],
        ];
        for m in &modes {
            let f = kmul(&k, m);
            assert!(f.iter().all(|v| v.abs() < 1e-10 * k[0][0]), "{f:?}");
        }
    }

    #[test]
    fn uniform_strain_energy_is_exact() {
        // u = (a x, 0): ε_xx = a, energy = ½ a² D00 · area · t.
        let xy = skewed();
        let d = plane_stress(200.0, 0.25);
        let t = 0.3;
        let k = stiffness(&xy, &d, t);
        let a = 1e-3;
        let u: [f64; 8] = [0, 1, 2, 3]
            .map(|i| [a * xy[i][0], 0.0])
            .concat()
            .try_into()
            .unwrap();
        let f = kmul(&k, &u);
        let energy: f64 = 0.5 * (0..8).map(|i| u[i] * f[i]).sum::<f64>();
        // shoelace area
        let area: f64 = 0.5
            * (0..4)
                .map(|i| {
                    let j = (i + 1) % 4;
                    xy[i][0] * xy[j][1] - xy[j][0] * xy[i][1]
                })
                .sum::<f64>();
        let exact = 0.5 * a * a * d[0][0] * area * t;
        assert!(
            (energy - exact).abs() < 1e-12 * exact,
            "{energy} vs {exact}"
        );
    }

    #[test]
    fn mass_adds_up_to_the_element_mass() {
        let xy = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
        let m = consistent_mass(&xy, 3.0, 0.5);
        let total: f64 = m.iter().flatten().sum();
        assert!((total - 3.0).abs() < 1e-13);
        // rectangle: consistent mass = ρtA/36 · [[4,2,1,2],...]
        assert!((m[0][0] - 3.0 * 4.0 / 36.0).abs() < 1e-13);
        assert!((m[0][2] - 3.0 / 36.0).abs() < 1e-13);
        let l = lumped_mass(&xy, 3.0, 0.5);
        assert!(l.iter().all(|v| (v - 0.75).abs() < 1e-13));
        let (xi, eta) = parent_of_rect(&xy, [1.5, 0.25]);
        assert!((xi - 0.5).abs() < 1e-15 && (eta + 0.5).abs() < 1e-15);
    }
}
