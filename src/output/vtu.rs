//! `.vtu` frames of continuum bodies: the node grid as a structured quad
//! mesh (VTK unstructured grid of quads) with point data.

use super::vtk::{data_array_f64, data_array_i64};
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
