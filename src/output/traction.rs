//! CSV of an averaged contact traction profile
//! ([`EdgeTraction`](crate::model::traction::EdgeTraction)): one row per
//! bin.

use crate::model::traction::TractionBin;
use std::io::Write;
use std::path::Path;

/// Write `bins` to `path`: `from, to, mid` (coordinate along the edge, m),
/// `depth` (`surface − mid`, m; empty without a surface), `normal`,
/// `shear` (tractions on the body, Pa: compression positive; shear along
/// +x or +y), `contacts` (mean per state). The first line is a comment
/// with `label` (e.g. the body, edge and averaging window).
pub fn write_traction_csv(
    path: &Path,
    label: &str,
    bins: &[TractionBin],
    surface: Option<f64>,
) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(f, "# {label}")?;
    writeln!(f, "from,to,mid,depth,normal,shear,contacts")?;
    for b in bins {
        let depth = surface.map_or(String::new(), |s| format!("{:e}", s - b.mid()));
        writeln!(
            f,
            "{:e},{:e},{:e},{depth},{:e},{:e},{:e}",
            b.from,
            b.to,
            b.mid(),
            b.normal,
            b.shear,
            b.contacts
        )?;
    }
    f.flush()
}
