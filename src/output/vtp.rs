//! `.vtp` (VTK PolyData) frames of a granular assembly, three datasets:
//! - discs: one vertex per disc at its centre, in scenario order (`id`,
//!   1-based, is the `GlobalIds` array), with `radius`, `diameter`,
//!   `velocity`, `spin`, `force`, `torque`, `coordination`;
//! - contacts of every kind (disc–disc, disc–wall, disc–body): one line
//!   each, from the disc's centre to the other disc's centre or to the
//!   contact point, with the forces on the disc as cell data;
//! - walls: one line each, with the force of the discs on it;
//! - cracks (with parallel bonds): one line per broken bond, across the
//!   bond's width `2R̄` at its centre, perpendicular to the line of
//!   centres, with `mode` (0 tension, 1 shear), `step` (in which it
//!   broke, as in `bond_breaks.csv`), `disc_a`/`disc_b`
//!   (1-based) and the `energy` it released.
//!
//! Vectors have 3 components (z = 0).

use super::vtk::{VtkFile, VtkFormat, vec3};
use crate::dem::Granular;
use crate::dem::bonds::BreakMode;
use crate::geom::Vec2;
use crate::model::contacts::{ContactKind, ContactView};
use std::path::Path;

const POLY: &str = "PolyData";

/// Open a PolyData piece of `npts` points, `nverts` vertices and `nlines`
/// lines.
fn piece(f: &mut VtkFile, npts: usize, nverts: usize, nlines: usize) {
    f.open(
        "Piece",
        &format!(
            "NumberOfPoints=\"{npts}\" NumberOfVerts=\"{nverts}\" NumberOfLines=\"{nlines}\" NumberOfStrips=\"0\" NumberOfPolys=\"0\""
        ),
    );
}

/// The `<Points>` element.
fn points(f: &mut VtkFile, xyz: &[f64]) {
    f.open("Points", "");
    f.array("Points", 3, "", xyz);
    f.close("Points");
}

/// A `<Verts>` or `<Lines>` element of cells of `per` points each, the
/// points of cell `k` being `per·k … per·k + per − 1`.
fn cells(f: &mut VtkFile, tag: &str, n: usize, per: usize) {
    f.open(tag, "");
    let conn: Vec<i32> = (0..(n * per) as i32).collect();
    let offs: Vec<i32> = (1..=n as i32).map(|k| per as i32 * k).collect();
    f.array("connectivity", 1, "", &conn);
    f.array("offsets", 1, "", &offs);
    f.close(tag);
}

/// Closed contacts of every kind per disc (by slot), from `contacts`.
pub fn coordination(g: &Granular, contacts: &[ContactView]) -> Vec<i32> {
    let mut z = vec![0i32; g.particles.len()];
    for c in contacts {
        z[g.slot(c.disc)] += 1;
        if c.kind == ContactKind::DiscDisc {
            z[g.slot(c.other)] += 1;
        }
    }
    z
}

/// Write the discs of `g` at `path` (`contacts`: the present contacts of
/// every kind, for the coordination numbers).
pub fn write_discs(
    g: &Granular,
    contacts: &[ContactView],
    format: VtkFormat,
    path: &Path,
) -> std::io::Result<()> {
    let p = &g.particles;
    let n = p.len();
    // slots in id order
    let order: Vec<usize> = (0..n).map(|id| g.slot(id)).collect();
    let by_id = |v: &[f64]| order.iter().map(|&s| v[s]).collect::<Vec<f64>>();
    let by_id2 = |v: &[Vec2]| vec3(order.iter().map(|&s| v[s]));
    let mut f = VtkFile::new(POLY, format);
    piece(&mut f, n, n, 0);
    points(&mut f, &by_id2(&p.pos));
    f.open(
        "PointData",
        "GlobalIds=\"id\" Scalars=\"radius\" Vectors=\"velocity\"",
    );
    let ids: Vec<i64> = order.iter().map(|&s| p.id[s] as i64 + 1).collect();
    f.array("id", 1, "IdType=\"1\"", &ids);
    let r = by_id(&p.radius);
    f.array("radius", 1, "", &r);
    f.array(
        "diameter",
        1,
        "",
        &r.iter().map(|r| 2.0 * r).collect::<Vec<_>>(),
    );
    f.array("velocity", 3, "", &by_id2(&p.vel));
    f.array(
        "displacement",
        3,
        "",
        &vec3(order.iter().map(|&s| g.displacement(s))),
    );
    f.array("spin", 1, "", &by_id(&p.omega));
    f.array("force", 3, "", &by_id2(&p.force));
    f.array("torque", 1, "", &by_id(&p.torque));
    if !g.clumps.is_empty() {
        let clump: Vec<i64> = order
            .iter()
            .map(|&s| super::csv::clump_number(p.clump[s]))
            .collect();
        f.array("clump", 1, "", &clump);
    }
    let z = coordination(g, contacts);
    f.array(
        "coordination",
        1,
        "",
        &order.iter().map(|&s| z[s]).collect::<Vec<_>>(),
    );
    f.close("PointData");
    cells(&mut f, "Verts", n, 1);
    f.close("Piece");
    f.write(POLY, path)
}

/// Write the contacts at `path`: per contact two points (the disc's
/// centre; the other disc's centre or the contact point on the wall or
/// body) and a line, with cell data `kind` (0 disc–disc, 1 disc–wall,
/// 2 disc–body), `disc` (its number, from 1), `other` (the number of the
/// other disc, wall or body, by `kind`: each counted from 1 in scenario
/// order), `normal_force` and
/// `tangential_force` (vectors, on the disc; elastic normal part `k_n δ`
/// and shear spring), `fn` (`k_n δ`, compression positive), `ft` (|shear
/// force|), `overlap`.
pub fn write_contacts(
    g: &Granular,
    contacts: &[ContactView],
    format: VtkFormat,
    path: &Path,
) -> std::io::Result<()> {
    let p = &g.particles;
    let m = contacts.len();
    let mut f = VtkFile::new(POLY, format);
    piece(&mut f, 2 * m, 0, m);
    let pts = vec3(contacts.iter().flat_map(|c| {
        let end = match c.kind {
            ContactKind::DiscDisc => p.pos[g.slot(c.other)],
            _ => c.point,
        };
        [p.pos[g.slot(c.disc)], end]
    }));
    points(&mut f, &pts);
    f.open("CellData", "Scalars=\"fn\" Vectors=\"normal_force\"");
    let col = |q: fn(&ContactView) -> f64| contacts.iter().map(q).collect::<Vec<f64>>();
    f.array("fn", 1, "", &col(|c| c.normal_elastic));
    f.array("ft", 1, "", &col(|c| c.shear.abs()));
    f.array(
        "normal_force",
        3,
        "",
        &vec3(contacts.iter().map(|c| c.normal * -c.normal_elastic)),
    );
    f.array(
        "tangential_force",
        3,
        "",
        &vec3(contacts.iter().map(|c| c.normal.perp() * c.shear)),
    );
    f.array("overlap", 1, "", &col(|c| c.overlap));
    f.array(
        "kind",
        1,
        "",
        &contacts.iter().map(|c| c.kind as i32).collect::<Vec<_>>(),
    );
    f.array(
        "disc",
        1,
        "",
        &contacts
            .iter()
            .map(|c| c.disc as i32 + 1)
            .collect::<Vec<_>>(),
    );
    f.array(
        "other",
        1,
        "",
        &contacts
            .iter()
            .map(|c| c.other as i32 + 1)
            .collect::<Vec<_>>(),
    );
    f.close("CellData");
    cells(&mut f, "Lines", m, 2);
    f.close("Piece");
    f.write(POLY, path)
}

/// Write the walls of `g` at `path`: one line each (its two end points),
/// with cell data `wall` (its number, from 1 in scenario order), `force` (of
/// the discs on the wall in the last step) and `velocity`.
pub fn write_walls(g: &Granular, format: VtkFormat, path: &Path) -> std::io::Result<()> {
    let w = &g.walls;
    let mut f = VtkFile::new(POLY, format);
    piece(&mut f, 2 * w.len(), 0, w.len());
    points(&mut f, &vec3(w.iter().flat_map(|w| [w.a, w.b])));
    f.open("CellData", "Vectors=\"force\"");
    f.array("wall", 1, "", &(1..=w.len() as i32).collect::<Vec<_>>());
    f.array("force", 3, "", &vec3(w.iter().map(|w| w.force)));
    f.array("velocity", 3, "", &vec3(w.iter().map(|w| w.vel)));
    f.close("CellData");
    cells(&mut f, "Lines", w.len(), 2);
    f.close("Piece");
    f.write(POLY, path)
}

/// Write the cracks of `g` (every bond broken so far) at `path`.
pub fn write_cracks(g: &Granular, format: VtkFormat, path: &Path) -> std::io::Result<()> {
    let c = &g.bonds.list.broken;
    let mut f = VtkFile::new(POLY, format);
    piece(&mut f, 2 * c.len(), 0, c.len());
    let ends = c.iter().flat_map(|b| {
        let half = b.normal.perp() * b.radius;
        [b.pos - half, b.pos + half]
    });
    points(&mut f, &vec3(ends));
    f.open("CellData", "Scalars=\"mode\"");
    let mode: Vec<i32> = c
        .iter()
        .map(|b| (b.mode == BreakMode::Shear) as i32)
        .collect();
    f.array("mode", 1, "", &mode);
    f.array(
        "step",
        1,
        "",
        &c.iter().map(|b| (b.step + 1) as f64).collect::<Vec<_>>(),
    );
    f.array(
        "disc_a",
        1,
        "",
        &c.iter().map(|b| b.a as i32 + 1).collect::<Vec<_>>(),
    );
    f.array(
        "disc_b",
        1,
        "",
        &c.iter().map(|b| b.b as i32 + 1).collect::<Vec<_>>(),
    );
    f.array(
        "energy",
        1,
        "",
        &c.iter().map(|b| b.energy).collect::<Vec<_>>(),
    );
    f.close("CellData");
    cells(&mut f, "Lines", c.len(), 2);
    f.close("Piece");
    f.write(POLY, path)
}
