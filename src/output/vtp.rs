//! ParaView `.vtp` (VTK PolyData) frames of a granular assembly: discs as
//! vertices with point data (radius, velocity, spin, force), contacts as
//! lines between the centres with their normal force as cell data, walls
//! as lines.

use super::vtk::{data_array_f64, data_array_i64};
use crate::dem::Granular;
use crate::geom::Vec2;
use std::io::Write;
use std::path::Path;

/// What one frame shows.
pub struct DiscFrame<'a> {
    /// Disc centres (by slot).
    pub pos: &'a [Vec2],
    /// Disc radii.
    pub radius: &'a [f64],
    /// Disc velocities (at the half step, see
    /// [`Particles::vel`](crate::dem::particles::Particles::vel)).
    pub vel: &'a [Vec2],
    /// Spins ω, counter-clockwise positive.
    pub omega: &'a [f64],
    /// Resultant contact (and external) force of the last step, without
    /// gravity.
    pub force: &'a [Vec2],
    /// Scenario id (0-based) of each disc; written 1-based to the file.
    pub id: &'a [u32],
    /// Touching disc pairs (indices into `pos`) and their normal force.
    pub contacts: &'a [(u32, u32, f64)],
    /// Wall segments.
    pub walls: &'a [(Vec2, Vec2)],
}

/// Write `frame` to `path` (ASCII XML PolyData).
pub fn write_discs<'a>(path: &Path, frame: &DiscFrame<'a>) -> std::io::Result<()> {
    let n = frame.pos.len();
    let nw = frame.walls.len();
    let npts = n + 2 * nw;
    let nlines = frame.contacts.len() + nw;
    let tmp = path.with_extension("vtp.tmp");
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        writeln!(w, "<?xml version=\"1.0\"?>")?;
        writeln!(
            w,
            "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n<PolyData>"
        )?;
        writeln!(
            w,
            "<Piece NumberOfPoints=\"{npts}\" NumberOfVerts=\"{n}\" NumberOfLines=\"{nlines}\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
        )?;
        writeln!(w, "<Points>")?;
        let pts = frame
            .pos
            .iter()
            .copied()
            .chain(frame.walls.iter().flat_map(|&(a, b)| [a, b]));
        data_array_f64(&mut w, "Points", 3, pts.flat_map(|p| [p.x, p.y, 0.0]))?;
        writeln!(w, "</Points>")?;
        writeln!(w, "<PointData Scalars=\"radius\" Vectors=\"velocity\">")?;
        let pad = |v: &'a [f64]| v.iter().copied().chain(std::iter::repeat_n(0.0, 2 * nw));
        data_array_f64(&mut w, "radius", 1, pad(frame.radius))?;
        let vec3 = |v: &'a [Vec2]| {
            v.iter()
                .flat_map(|p| [p.x, p.y, 0.0])
                .chain(std::iter::repeat_n(0.0, 6 * nw))
        };
        data_array_f64(&mut w, "velocity", 3, vec3(frame.vel))?;
        data_array_f64(&mut w, "spin", 1, pad(frame.omega))?;
        data_array_f64(&mut w, "force", 3, vec3(frame.force))?;
        data_array_i64(
            &mut w,
            "disc",
            "Int64",
            frame
                .id
                .iter()
                .map(|&i| i as i64 + 1)
                .chain(std::iter::repeat_n(0, 2 * nw)),
        )?;
        writeln!(w, "</PointData>")?;
        // cell data: verts first, then lines (contacts, then walls)
        writeln!(w, "<CellData Scalars=\"normal_force\">")?;
        data_array_f64(
            &mut w,
            "normal_force",
            1,
            std::iter::repeat_n(0.0, n)
                .chain(frame.contacts.iter().map(|c| c.2))
                .chain(std::iter::repeat_n(0.0, nw)),
        )?;
        data_array_i64(
            &mut w,
            "kind",
            "Int32",
            std::iter::repeat_n(0, n)
                .chain(std::iter::repeat_n(1, frame.contacts.len()))
                .chain(std::iter::repeat_n(2, nw)),
        )?;
        writeln!(w, "</CellData>")?;
        writeln!(w, "<Verts>")?;
        data_array_i64(&mut w, "connectivity", "Int64", 0..n as i64)?;
        data_array_i64(&mut w, "offsets", "Int64", 1..=n as i64)?;
        writeln!(w, "</Verts>")?;
        writeln!(w, "<Lines>")?;
        let conn = frame
            .contacts
            .iter()
            .flat_map(|c| [c.0 as i64, c.1 as i64])
            .chain((0..2 * nw as i64).map(|k| n as i64 + k));
        data_array_i64(&mut w, "connectivity", "Int64", conn)?;
        data_array_i64(
            &mut w,
            "offsets",
            "Int64",
            (1..=nlines as i64).map(|k| 2 * k),
        )?;
        writeln!(w, "</Lines>")?;
        writeln!(w, "</Piece>\n</PolyData>\n</VTKFile>")?;
        w.flush()?;
    }
    std::fs::rename(tmp, path)
}

/// Write a ParaView frame of the present state.
pub fn write_granular(gr: &Granular, path: &std::path::Path) -> std::io::Result<()> {
    let p = &gr.particles;
    let contacts: Vec<(u32, u32, f64)> = gr
        .contacts
        .pairs
        .iter()
        .filter_map(|q| {
            let (el, _) = gr.normal_force(q.i as usize, q.j as usize);
            (el > 0.0).then_some((q.i, q.j, el))
        })
        .collect();
    let walls: Vec<_> = gr.walls.iter().map(|w| (w.a, w.b)).collect();
    write_discs(
        path,
        &DiscFrame {
            pos: &p.pos,
            radius: &p.radius,
            vel: &p.vel,
            omega: &p.omega,
            force: &p.force,
            id: &p.id,
            contacts: &contacts,
            walls: &walls,
        },
    )
}
