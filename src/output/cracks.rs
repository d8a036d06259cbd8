//! `.vtp` (VTK PolyData) frames of the cracks of an EFG body: per crack
//! two polylines, its left and its right face (left and right of the
//! direction from its first point to its last), through the face nodes at
//! their reference positions (the faces meet at a tip). Point data:
//! `displacement`, the true displacement of each face node (ParaView's
//! *Warp By Vector* opens the crack); cell data: `crack` (1-based),
//! `face` (0 left, 1 right), `length` (the crack's length).

use super::vtk::{VtkFile, VtkFormat, vec3};
use crate::efg::EfgBody;
use crate::efg::assemble::PointShapes;
use crate::geom::Vec2;
use std::path::Path;

const POLY: &str = "PolyData";

/// The true displacement at node `i` from its nodal shape row.
fn node_displacement(b: &EfgBody, shapes: &PointShapes, i: usize) -> Vec2 {
    let u = &b.state.u;
    (shapes.ptr[i]..shapes.ptr[i + 1]).fold(Vec2::new(0.0, 0.0), |acc, k| {
        let (j, phi) = (shapes.idx[k] as usize, shapes.val[k][0]);
        acc + Vec2::new(u[2 * j], u[2 * j + 1]) * phi
    })
}

/// Write the crack faces of `b` (`shapes`: its nodal shape rows) to `path`.
pub fn write_cracks(
    b: &EfgBody,
    shapes: &PointShapes,
    format: VtkFormat,
    path: &Path,
) -> std::io::Result<()> {
    let mut nodes: Vec<usize> = Vec::new();
    let mut offsets: Vec<i32> = Vec::new();
    let (mut crack, mut face, mut length) = (Vec::new(), Vec::new(), Vec::new());
    for (k, c) in b.cracks().iter().enumerate() {
        for side in 0..2 {
            nodes.extend(c.nodes.iter().map(|pair| pair[side]));
            offsets.push(nodes.len() as i32);
            crack.push(k as i32 + 1);
            face.push(side as i32);
            length.push(c.crack.length());
        }
    }
    let mut f = VtkFile::new(POLY, format);
    f.open(
        "Piece",
        &format!(
            "NumberOfPoints=\"{}\" NumberOfVerts=\"0\" NumberOfLines=\"{}\" NumberOfStrips=\"0\" NumberOfPolys=\"0\"",
            nodes.len(),
            offsets.len()
        ),
    );
    f.open("Points", "");
    f.array("Points", 3, "", &vec3(nodes.iter().map(|&i| b.node(i))));
    f.close("Points");
    f.open("PointData", "Vectors=\"displacement\"");
    let u = vec3(nodes.iter().map(|&i| node_displacement(b, shapes, i)));
    f.array("displacement", 3, "", &u);
    f.close("PointData");
    f.open("CellData", "");
    f.array("crack", 1, "", &crack);
    f.array("face", 1, "", &face);
    f.array("length", 1, "", &length);
    f.close("CellData");
    f.open("Lines", "");
    f.array(
        "connectivity",
        1,
        "",
        &(0..nodes.len() as i32).collect::<Vec<_>>(),
    );
    f.array("offsets", 1, "", &offsets);
    f.close("Lines");
    f.close("Piece");
    f.write(POLY, path)
}
