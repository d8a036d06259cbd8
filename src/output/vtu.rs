//! `.vtu` frames of continuum bodies: the node grid as a structured quad
//! mesh (VTK unstructured grid of quads) with point data.

use super::vtk::{data_array_f64, data_array_i64};
use crate::efg::assemble::PointShapes;
use crate::efg::{EfgBody, ShapeRow};
use crate::model::body::BodyRef;
use std::io::Write;
use std::path::Path;

/// One point-data field: name, number of components, values (interleaved).
pub struct Field<'a> {
    pub name: &'a str,
    pub ncomp: usize,
    pub values: &'a [f64],
}

/// Write an `nx × ny` row-major grid of points (`[x, y]`) as quads, with
/// point data, atomically (temp file + rename).
pub fn write_quad_grid(
    path: &Path,
    nx: usize,
    ny: usize,
    points: &[[f64; 2]],
    fields: &[Field<'_>],
) -> std::io::Result<()> {
    let ncells = (nx.saturating_sub(1)) * (ny.saturating_sub(1));
    let tmp = path.with_extension("vtu.tmp");
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        writeln!(
            w,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{ncells}\">",
            points.len()
        )?;
        writeln!(w, "<PointData>")?;
        for f in fields {
            data_array_f64(&mut w, f.name, f.ncomp, f.values.iter().copied())?;
        }
        writeln!(w, "</PointData>\n<Points>")?;
        data_array_f64(
            &mut w,
            "Points",
            3,
            points.iter().flat_map(|p| [p[0], p[1], 0.0]),
        )?;
        writeln!(w, "</Points>\n<Cells>")?;
        let conn = (0..ny.saturating_sub(1)).flat_map(|j| {
            (0..nx - 1).flat_map(move |i| {
                let a = (j * nx + i) as i64;
                let n = nx as i64;
                [a, a + 1, a + n + 1, a + n]
            })
        });
        data_array_i64(&mut w, "connectivity", "Int64", conn)?;
        data_array_i64(
            &mut w,
            "offsets",
            "Int64",
            (1..=ncells as i64).map(|c| 4 * c),
        )?;
        data_array_i64(&mut w, "types", "UInt8", (0..ncells).map(|_| 9))?;
        writeln!(w, "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>")?;
        w.flush()?;
    }
    std::fs::rename(tmp, path)
}

/// A `.vtu` frame of a body: true nodal displacement, velocity and stress
/// (`shapes`: the EFG body's nodal shape rows, from
/// [`BodyRef::frame_data`]).
pub fn write_body(body: BodyRef, shapes: Option<&PointShapes>, path: &Path) -> std::io::Result<()> {
    match (body, shapes) {
        (BodyRef::Efg(b), Some(s)) => write_frame_efg(b, s, path),
        (BodyRef::Fem(b), _) => {
            let (u, v, s) = b.nodal_fields();
            let pts: Vec<[f64; 2]> = (0..b.n_nodes()).map(|i| b.node(i).to_array()).collect();
            write_fields(path, b.grid, &pts, &u, &v, &s)
        }
        _ => unreachable!("EFG frames need nodal shapes"),
    }
}

/// Nodal values: true displacement, velocity and stress at every node.
fn write_frame_efg(b: &EfgBody, shapes: &PointShapes, path: &Path) -> std::io::Result<()> {
    let n = b.n_nodes();
    let (mut u, mut v, mut s) = (vec![0.0; 2 * n], vec![0.0; 2 * n], vec![0.0; 3 * n]);
    let mut row = ShapeRow::new();
    for i in 0..n {
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
        u[2 * i] = smp.u.x;
        u[2 * i + 1] = smp.u.y;
        v[2 * i] = smp.v.x;
        v[2 * i + 1] = smp.v.y;
        s[3 * i..3 * i + 3].copy_from_slice(&smp.stress);
    }
    let pts: Vec<[f64; 2]> = (0..n).map(|i| b.node(i).to_array()).collect();
    write_fields(path, b.grid, &pts, &u, &v, &s)
}

fn write_fields(
    path: &Path,
    grid: [usize; 2],
    pts: &[[f64; 2]],
    u: &[f64],
    v: &[f64],
    s: &[f64],
) -> std::io::Result<()> {
    write_quad_grid(
        path,
        grid[0],
        grid[1],
        pts,
        &[
            Field {
                name: "displacement",
                ncomp: 2,
                values: u,
            },
            Field {
                name: "velocity",
                ncomp: 2,
                values: v,
            },
            Field {
                name: "stress_xx_yy_xy",
                ncomp: 3,
                values: s,
            },
        ],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_a_readable_grid() {
        let dir = std::env::temp_dir().join(format!("efgdem-vtu-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("g.vtu");
        let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        let u = [0.0; 8];
        write_quad_grid(
            &p,
            2,
            2,
            &pts,
            &[Field {
                name: "u",
                ncomp: 2,
                values: &u,
            }],
        )
        .unwrap();
        let s = std::fs::read_to_string(&p).unwrap();
        assert!(s.contains("NumberOfCells=\"1\"") && s.contains("0 1 3 2"));
        std::fs::remove_dir_all(dir).unwrap();
    }
}
