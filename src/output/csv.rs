//! `history.csv`: one row per recorded step, streamed to disk, and read
//! back ([`History`]) by post-processing.

use crate::dem::Granular;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::{Duration, Instant};

/// A CSV time-series writer. Rows are buffered and flushed at least once a
/// second and on drop, so an interrupted run loses at most a second of rows.
pub struct HistoryWriter {
    out: BufWriter<File>,
    ncols: usize,
    /// Columns written as integers (`step`).
    integer: Vec<bool>,
    /// The row being formatted: rows reach the buffer whole, so the file
    /// never ends in half a row.
    line: String,
    last_flush: Instant,
    /// Bytes of the file so far (written or buffered).
    bytes: u64,
}

impl HistoryWriter {
    /// Create `path` and write the header line.
    pub fn create(path: &Path, columns: &[&str]) -> std::io::Result<Self> {
        let mut out = BufWriter::new(File::create(path)?);
        let header = format!("{}\n", columns.join(","));
        out.write_all(header.as_bytes())?;
        out.flush()?;
        Ok(Self::with(out, columns, header.len() as u64))
    }

    /// Continue `path` (a restart): keep its first `bytes` bytes (what a
    /// checkpoint recorded with [`bytes`](Self::bytes)), drop the rest, and
    /// append from there. Fails if the file is shorter or its header is
    /// not `columns`.
    pub fn resume(path: &Path, columns: &[&str], bytes: u64) -> std::io::Result<Self> {
        use std::io::{Error, ErrorKind, Read, Seek, SeekFrom};
        let bad =
            |m: String| Error::new(ErrorKind::InvalidData, format!("{}: {m}", path.display()));
        let mut f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)?;
        let header = format!("{}\n", columns.join(","));
        let mut first = vec![0; header.len()];
        if f.read_exact(&mut first).is_err() || first != header.as_bytes() {
            return Err(bad(format!("the header is not `{}`", header.trim_end())));
        }
        let len = f.metadata()?.len();
        if len < bytes {
            return Err(bad(format!(
                "{len} bytes, shorter than the {bytes} the checkpoint recorded"
            )));
        }
        f.set_len(bytes)?;
        f.seek(SeekFrom::End(0))?;
        Ok(Self::with(BufWriter::new(f), columns, bytes))
    }

    fn with(out: BufWriter<File>, columns: &[&str], bytes: u64) -> Self {
        HistoryWriter {
            out,
            ncols: columns.len(),
            integer: columns.iter().map(|c| *c == "step").collect(),
            line: String::new(),
            last_flush: Instant::now(),
            bytes,
        }
    }

    /// Length of the file once flushed (header and every row so far).
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Append one row; `values.len()` must equal the number of columns.
    pub fn row(&mut self, values: &[f64]) -> std::io::Result<()> {
        use std::fmt::Write as _;
        debug_assert_eq!(values.len(), self.ncols, "history row width");
        self.line.clear();
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.line.push(',');
            }
            let _ = if self.integer[i] {
                write!(self.line, "{}", *v as i64)
            } else {
                write!(self.line, "{v:e}")
            };
        }
        self.line.push('\n');
        self.out.write_all(self.line.as_bytes())?;
        self.bytes += self.line.len() as u64;
        if self.last_flush.elapsed() > Duration::from_secs(1) {
            self.flush()?;
        }
        Ok(())
    }

    /// Write the buffered rows to the file now.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.last_flush = Instant::now();
        self.out.flush()
    }
}

impl Drop for HistoryWriter {
    fn drop(&mut self) {
        let _ = self.out.flush();
    }
}

/// Read a CSV written by [`HistoryWriter`] back: header and numeric rows.
pub fn read(path: &Path) -> std::io::Result<(Vec<String>, Vec<Vec<f64>>)> {
    let text = std::fs::read_to_string(path)?;
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|v| v.trim().parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    Ok((header, rows))
}

/// Write the discs as `x,y,r,vx,vy,omega` in scenario order (readable as a
/// `discs = { csv = ... }` source: the extra columns are... not accepted,
/// so only `x,y,r` are written).
pub fn write_discs_csv(gr: &Granular, path: &std::path::Path) -> std::io::Result<()> {
    let p = &gr.particles;
    let mut w = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(w, "x,y,r")?;
    for id in 0..p.len() {
        let k = p.slot[id] as usize;
        writeln!(w, "{:e},{:e},{:e}", p.pos[k].x, p.pos[k].y, p.radius[k])?;
    }
    w.flush()
}

/// The `history.csv` columns of the parallel bonds: intact bonds, bonds
/// broken in tension and in shear so far, energy stored in the intact
/// bonds and released by the broken ones.
pub const BOND_COLUMNS: [&str; 5] = [
    "bonds",
    "bonds_broken_tension",
    "bonds_broken_shear",
    "E_bond",
    "E_bond_released",
];

/// The values of [`BOND_COLUMNS`] for `gr`.
pub fn bond_row(gr: &Granular) -> [f64; 5] {
    let b = &gr.bonds;
    let (t, s) = b.broken_counts();
    [
        b.list.len() as f64,
        t as f64,
        s as f64,
        b.energy(gr.thickness),
        b.list.released,
    ]
}

/// Write every bond broken so far to `path` (`bond_breaks.csv`): one row
/// per breakage in the order they happened, with the step in which it
/// broke (its stresses reached the strength in the state before; the first
/// `history.csv` row that counts it) and the time at the end of it, the
/// bond's centre and unit normal (from disc a to b; the crack runs across
/// it), its radius, the two discs (1-based), the mode and the energy it
/// released.
pub fn write_bond_breaks(gr: &Granular, path: &Path) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::new(File::create(path)?);
    writeln!(w, "step,t,x,y,nx,ny,radius,disc_a,disc_b,mode,energy")?;
    for b in &gr.bonds.list.broken {
        writeln!(
            w,
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{:e}",
            b.step + 1,
            b.time + gr.dt,
            b.pos.x,
            b.pos.y,
            b.normal.x,
            b.normal.y,
            b.radius,
            b.a + 1,
            b.b + 1,
            b.mode.name(),
            b.energy
        )?;
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let dir = std::env::temp_dir().join(format!("efgdem-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("h.csv");
        {
            let mut w = HistoryWriter::create(&p, &["t", "f"]).unwrap();
            w.row(&[0.0, 1.5]).unwrap();
            w.row(&[0.1, -2.25e-9]).unwrap();
        }
        let (h, rows) = read(&p).unwrap();
        assert_eq!(h, vec!["t", "f"]);
        assert_eq!(rows, vec![vec![0.0, 1.5], vec![0.1, -2.25e-9]]);
        std::fs::remove_dir_all(dir).unwrap();
    }
}

/// A `history.csv`: its column names and rows of numbers.
#[derive(Debug, Clone, Default)]
pub struct History {
    /// Column names, in order (`step`, `t`, probes, measures).
    pub columns: Vec<String>,
    /// The rows.
    pub rows: Vec<Vec<f64>>,
}

impl History {
    /// Parse the text of a `history.csv` (a header line, then numbers).
    pub fn parse(text: &str) -> Result<History, String> {
        let mut lines = text.lines().filter(|l| !l.trim().is_empty());
        let columns: Vec<String> = lines
            .next()
            .ok_or("empty history")?
            .split(',')
            .map(|s| s.trim().to_string())
            .collect();
        let mut rows = Vec::new();
        for (k, l) in lines.enumerate() {
            let row = l
                .split(',')
                .map(|s| s.trim().parse::<f64>())
                .collect::<Result<Vec<f64>, _>>()
                .map_err(|e| format!("history row {}: {e}", k + 1))?;
            if row.len() != columns.len() {
                return Err(format!(
                    "history row {}: {} values for {} columns",
                    k + 1,
                    row.len(),
                    columns.len()
                ));
            }
            rows.push(row);
        }
        Ok(History { columns, rows })
    }

    /// Read and parse a `history.csv` file.
    pub fn read(path: &Path) -> Result<History, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        History::parse(&text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The values of the column `name`, one per row.
    pub fn values(&self, name: &str) -> Result<Vec<f64>, String> {
        let c = self.column(name)?;
        Ok(self.rows.iter().map(|r| r[c]).collect())
    }

    /// Index of the column `name`.
    pub fn column(&self, name: &str) -> Result<usize, String> {
        self.columns
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| format!("history.csv has no column `{name}`"))
    }
}
