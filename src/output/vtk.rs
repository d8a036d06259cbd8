//! ParaView output shared by bodies (`.vtu`) and discs (`.vtp`): the `.pvd`
//! time series and XML data-array writing.

use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A `.pvd` collection, rewritten after every frame so that it is always a
/// complete, readable file even if the run stops.
pub struct PvdSeries {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdSeries {
    /// An empty collection to be written at `path`.
    pub fn new(path: &Path) -> Self {
        PvdSeries {
            path: path.to_path_buf(),
            entries: Vec::new(),
        }
    }

    /// Register a frame file (path relative to the `.pvd`) at time `t`.
    pub fn add(&mut self, t: f64, file: &str) -> std::io::Result<()> {
        self.entries.push((t, file.to_string()));
        self.write()
    }

    /// The frames registered so far: `(time, file)`.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// Replace the entries (a restart continues the series it checkpointed)
    /// and rewrite the file.
    pub fn resume(&mut self, entries: Vec<(f64, String)>) -> std::io::Result<()> {
        self.entries = entries;
        self.write()
    }

    /// Write the collection (temporary file + rename: always complete).
    fn write(&self) -> std::io::Result<()> {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
        );
        for (t, f) in &self.entries {
            let _ = writeln!(s, "<DataSet timestep=\"{t:e}\" part=\"0\" file=\"{f}\"/>");
        }
        s.push_str("</Collection>\n</VTKFile>\n");
        let tmp = self.path.with_extension("pvd.tmp");
        std::fs::write(&tmp, s)?;
        std::fs::rename(tmp, &self.path)
    }
}

/// Write an ASCII `<DataArray>` of `f64` with `ncomp` components.
pub fn data_array_f64(
    w: &mut impl Write,
    name: &str,
    ncomp: usize,
    values: impl IntoIterator<Item = f64>,
) -> std::io::Result<()> {
    writeln!(
        w,
        "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{ncomp}\" format=\"ascii\">"
    )?;
    for (i, v) in values.into_iter().enumerate() {
        if i > 0 {
            w.write_all(if i % ncomp.max(1) == 0 { b"\n" } else { b" " })?;
        }
        write!(w, "{v:e}")?;
    }
    writeln!(w, "\n</DataArray>")
}

/// Write an ASCII `<DataArray>` of integers (connectivity, offsets, types).
pub fn data_array_i64(
    w: &mut impl Write,
    name: &str,
    ty: &str,
    values: impl IntoIterator<Item = i64>,
) -> std::io::Result<()> {
    writeln!(
        w,
        "<DataArray type=\"{ty}\" Name=\"{name}\" format=\"ascii\">"
    )?;
    for (i, v) in values.into_iter().enumerate() {
        if i > 0 {
            w.write_all(b" ")?;
        }
        write!(w, "{v}")?;
    }
    writeln!(w, "\n</DataArray>")
}
