//! `.vtu` frames of continuum bodies: the node grid as quads (VTK
//! unstructured grid), in the deformed configuration (points at `X + u`),
//! with point data `displacement`, `velocity` (3 components), `stress` and
//! `strain` (symmetric tensors, 6 components in ParaView's order XX, YY,
//! ZZ, XY, YZ, XZ; tensor strain, ε_xy = γ_xy/2; the out-of-plane
//! components from plane stress or plane strain), `von_mises`,
//! `sigma_xx`, `sigma_yy`, `sigma_zz`, `sigma_xy`.

use super::vtk::{VtkFile, VtkFormat};
use crate::continuum::Plane;
use crate::continuum::material::Material;
use crate::efg::assemble::PointShapes;
use crate::efg::{EfgBody, ShapeRow};
use crate::model::body::BodyRef;
use std::path::Path;

/// The nodal values of one frame of a body.
pub struct NodalFields {
    /// Reference position `X` of each node (grid order, row-major).
    pub reference: Vec<[f64; 2]>,
    /// Displacement `u` at each node.
    pub u: Vec<[f64; 2]>,
    /// Velocity at each node.
    pub v: Vec<[f64; 2]>,
    /// In-plane stress `(σ_xx, σ_yy, σ_xy)` at each node.
    pub stress: Vec<[f64; 3]>,
    /// In-plane engineering strain `(ε_xx, ε_yy, γ_xy)` at each node.
    pub strain: Vec<[f64; 3]>,
}

/// The out-of-plane stress σ_zz and strain ε_zz of an isotropic body.
fn out_of_plane(m: &Material, s: [f64; 3]) -> (f64, f64) {
    match m.plane {
        Plane::Stress => (0.0, -m.nu * (s[0] + s[1]) / m.e),
        Plane::Strain => (m.nu * (s[0] + s[1]), 0.0),
    }
}

/// Von Mises stress of `(σ_xx, σ_yy, σ_xy)` with `σ_zz`.
pub fn von_mises(s: [f64; 3], szz: f64) -> f64 {
    let [xx, yy, xy] = s;
    (0.5 * ((xx - yy).powi(2) + (yy - szz).powi(2) + (szz - xx).powi(2)) + 3.0 * xy * xy).sqrt()
}

const GRID: &str = "UnstructuredGrid";
const TENSOR: &str = "ComponentName0=\"XX\" ComponentName1=\"YY\" ComponentName2=\"ZZ\" ComponentName3=\"XY\" ComponentName4=\"YZ\" ComponentName5=\"XZ\"";

/// Write an `nx × ny` row-major node grid as quads in the deformed
/// configuration, with the point data of the module docs, atomically.
pub fn write_grid(
    path: &Path,
    grid: [usize; 2],
    m: &Material,
    f: &NodalFields,
    format: VtkFormat,
) -> std::io::Result<()> {
    write_cells(path, grid, None, m, f, format)
}

/// [`write_grid`], or with `triangles` (a polygon body's integration
/// triangulation, counter-clockwise node triples) as VTK triangles instead
/// of the grid's quads.
pub fn write_cells(
    path: &Path,
    grid: [usize; 2],
    triangles: Option<&[[usize; 3]]>,
    m: &Material,
    f: &NodalFields,
    format: VtkFormat,
) -> std::io::Result<()> {
    let [nx, ny] = grid;
    let n = f.reference.len();
    let ncells = match triangles {
        Some(t) => t.len(),
        None => nx.saturating_sub(1) * ny.saturating_sub(1),
    };
    let mut w = VtkFile::new(GRID, format);
    w.open(
        "Piece",
        &format!("NumberOfPoints=\"{n}\" NumberOfCells=\"{ncells}\""),
    );
    w.open("Points", "");
    let pts: Vec<f64> = (0..n)
        .flat_map(|i| {
            let (x, u) = (f.reference[i], f.u[i]);
            [x[0] + u[0], x[1] + u[1], 0.0]
        })
        .collect();
    w.array("Points", 3, "", &pts);
    w.close("Points");
    w.open(
        "PointData",
        "Scalars=\"von_mises\" Vectors=\"displacement\" Tensors=\"stress\"",
    );
    let v3 = |v: &[[f64; 2]]| v.iter().flat_map(|a| [a[0], a[1], 0.0]).collect::<Vec<_>>();
    w.array("displacement", 3, "", &v3(&f.u));
    w.array("velocity", 3, "", &v3(&f.v));
    let zz: Vec<(f64, f64)> = f.stress.iter().map(|&s| out_of_plane(m, s)).collect();
    let stress: Vec<f64> = f
        .stress
        .iter()
        .zip(&zz)
        .flat_map(|(s, z)| [s[0], s[1], z.0, s[2], 0.0, 0.0])
        .collect();
    w.array("stress", 6, TENSOR, &stress);
    let strain: Vec<f64> = f
        .strain
        .iter()
        .zip(&zz)
        .flat_map(|(e, z)| [e[0], e[1], z.1, 0.5 * e[2], 0.0, 0.0])
        .collect();
    w.array("strain", 6, TENSOR, &strain);
    let vm: Vec<f64> = f
        .stress
        .iter()
        .zip(&zz)
        .map(|(s, z)| von_mises(*s, z.0))
        .collect();
    w.array("von_mises", 1, "", &vm);
    for (name, k) in [("sigma_xx", 0), ("sigma_yy", 1), ("sigma_xy", 2)] {
        w.array(
            name,
            1,
            "",
            &f.stress.iter().map(|s| s[k]).collect::<Vec<_>>(),
        );
        if k == 1 {
            w.array(
                "sigma_zz",
                1,
                "",
                &zz.iter().map(|z| z.0).collect::<Vec<_>>(),
            );
        }
    }
    w.close("PointData");
    w.open("Cells", "");
    if let Some(t) = triangles {
        let conn: Vec<i32> = t.iter().flat_map(|c| c.map(|i| i as i32)).collect();
        w.array("connectivity", 1, "", &conn);
        let offs: Vec<i32> = (1..=ncells as i32).map(|c| 3 * c).collect();
        w.array("offsets", 1, "", &offs);
        w.array("types", 1, "", &vec![5u8; ncells]);
        w.close("Cells");
        w.close("Piece");
        return w.write(GRID, path);
    }
    let conn: Vec<i32> = (0..ny.saturating_sub(1))
        .flat_map(|j| {
            (0..nx - 1).flat_map(move |i| {
                let a = (j * nx + i) as i32;
                let n = nx as i32;
                [a, a + 1, a + n + 1, a + n]
            })
        })
        .collect();
    w.array("connectivity", 1, "", &conn);
    let offs: Vec<i32> = (1..=ncells as i32).map(|c| 4 * c).collect();
    w.array("offsets", 1, "", &offs);
    w.array("types", 1, "", &vec![9u8; ncells]);
    w.close("Cells");
    w.close("Piece");
    w.write(GRID, path)
}

/// A `.vtu` frame of a body (`shapes`: the EFG body's nodal shape rows,
/// from [`BodyRef::frame_data`]).
pub fn write_body(
    body: BodyRef,
    shapes: Option<&PointShapes>,
    format: VtkFormat,
    path: &Path,
) -> std::io::Result<()> {
    match (body, shapes) {
        (BodyRef::Efg(b), Some(s)) => write_cells(
            path,
            b.grid,
            b.mesh.as_ref().map(|m| m.triangles.as_slice()),
            &b.material,
            &efg_fields(b, s),
            format,
        ),
        (BodyRef::Fem(b), _) => {
            let (u, v, s) = b.nodal_fields();
            let n = b.n_nodes();
            let pair = |a: &[f64]| (0..n).map(|i| [a[2 * i], a[2 * i + 1]]).collect();
            let stress: Vec<[f64; 3]> = (0..n)
                .map(|i| [s[3 * i], s[3 * i + 1], s[3 * i + 2]])
                .collect();
            // the nodal stress is an average of the elements' (linear in
            // their strains): the same average of the strains is D⁻¹ σ
            let [d11, d12, d22, d33] = b.material.d;
            let det = d11 * d22 - d12 * d12;
            let strain = stress
                .iter()
                .map(|s| {
                    [
                        (d22 * s[0] - d12 * s[1]) / det,
                        (d11 * s[1] - d12 * s[0]) / det,
                        s[2] / d33,
                    ]
                })
                .collect();
            let f = NodalFields {
                reference: (0..n).map(|i| b.node(i).to_array()).collect(),
                u: pair(&u),
                v: pair(&v),
                stress,
                strain,
            };
            write_grid(path, b.grid, &b.material, &f, format)
        }
        _ => unreachable!("EFG frames need nodal shapes"),
    }
}

/// The true displacement, velocity, strain and stress at every node.
fn efg_fields(b: &EfgBody, shapes: &PointShapes) -> NodalFields {
    let points = b.frame_points();
    let n = points.len();
    let mut f = NodalFields {
        reference: Vec::with_capacity(n),
        u: Vec::with_capacity(n),
        v: Vec::with_capacity(n),
        stress: Vec::with_capacity(n),
        strain: Vec::with_capacity(n),
    };
    let mut row = ShapeRow::new();
    for (i, p) in points.iter().enumerate() {
        row.idx.clear();
        row.phi.clear();
        row.dx.clear();
        row.dy.clear();
        for k in shapes.ptr[i]..shapes.ptr[i + 1] {
            row.idx.push(shapes.idx[k]);
            row.phi.push(shapes.val[k][0]);
            row.dx.push(shapes.val[k][1]);
            row.dy.push(shapes.val[k][2]);
        }
        let smp = b.sample_row(&row);
        f.reference.push(p.to_array());
        f.u.push(smp.u.to_array());
        f.v.push(smp.v.to_array());
        f.stress.push(smp.stress);
        f.strain.push(smp.strain);
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn von_mises_of_uniaxial_and_pure_shear() {
        assert!((von_mises([3.0, 0.0, 0.0], 0.0) - 3.0).abs() < 1e-12);
        assert!((von_mises([0.0, 0.0, 2.0], 0.0) - 2.0 * 3f64.sqrt()).abs() < 1e-12);
        // hydrostatic: none
        assert!(von_mises([5.0, 5.0, 0.0], 5.0).abs() < 1e-12);
    }
}
