//! `history.csv`: one row per recorded step, streamed to disk, and read
//! back ([`History`]) by post-processing.

use super::io_at;
use crate::dem::Granular;
use crate::geom::Vec2;
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A CSV time-series writer. Rows are buffered and written at least once a
/// second and on drop, so an interrupted run loses at most a second of
/// rows. The file holds whole rows only: rows reach the buffer whole, and a
/// write that fails (a full disk) is undone by cutting the file back to its
/// last whole row before the error (which names the file) is returned.
pub struct HistoryWriter {
    file: File,
    path: PathBuf,
    ncols: usize,
    /// Columns written as integers (`step`).
    integer: Vec<bool>,
    /// Whole rows not yet written to the file.
    buf: Vec<u8>,
    last_flush: Instant,
    /// Bytes of the file known to be written (whole rows).
    written: u64,
}

/// Rows buffered before they are written, whatever the time.
const BUFFER: usize = 1 << 16;

impl HistoryWriter {
    /// Create `path` and write the header line.
    pub fn create(path: &Path, columns: &[&str]) -> std::io::Result<Self> {
        let file = File::create(path).map_err(|e| io_at(path, e))?;
        let mut w = Self::with(file, path, columns, 0);
        w.buf
            .extend_from_slice(format!("{}\n", columns.join(",")).as_bytes());
        w.flush()?;
        Ok(w)
    }

    /// Continue `path` (a restart): keep its first `bytes` bytes (what a
    /// checkpoint recorded with [`bytes`](Self::bytes)), drop the rest, and
    /// append from there. Fails (`InvalidData`, the message naming the file)
    /// if the file is shorter or its header is not `columns`.
    pub fn resume(path: &Path, columns: &[&str], bytes: u64) -> std::io::Result<Self> {
        use std::io::{Error, ErrorKind, Read};
        let bad =
            |m: String| Error::new(ErrorKind::InvalidData, format!("{}: {m}", path.display()));
        let mut f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(|e| io_at(path, e))?;
        let header = format!("{}\n", columns.join(","));
        let mut first = vec![0; header.len()];
        if f.read_exact(&mut first).is_err() || first != header.as_bytes() {
            return Err(bad(format!("the header is not `{}`", header.trim_end())));
        }
        let len = f.metadata().map_err(|e| io_at(path, e))?.len();
        if len < bytes {
            return Err(bad(format!(
                "{len} bytes, shorter than the {bytes} the checkpoint recorded"
            )));
        }
        f.set_len(bytes)
            .and_then(|_| f.seek(SeekFrom::End(0)))
            .map_err(|e| io_at(path, e))?;
        Ok(Self::with(f, path, columns, bytes))
    }

    fn with(file: File, path: &Path, columns: &[&str], written: u64) -> Self {
        HistoryWriter {
            file,
            path: path.to_path_buf(),
            ncols: columns.len(),
            integer: columns.iter().map(|c| *c == "step").collect(),
            buf: Vec::with_capacity(BUFFER),
            last_flush: Instant::now(),
            written,
        }
    }

    /// Length of the file once flushed (header and every row so far).
    pub fn bytes(&self) -> u64 {
        self.written + self.buf.len() as u64
    }

    /// Append one row; `values.len()` must equal the number of columns.
    pub fn row(&mut self, values: &[f64]) -> std::io::Result<()> {
        use std::io::Write as _;
        debug_assert_eq!(values.len(), self.ncols, "history row width");
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.buf.push(b',');
            }
            // writing into a Vec cannot fail
            let _ = if self.integer[i] {
                write!(self.buf, "{}", *v as i64)
            } else {
                write!(self.buf, "{v:e}")
            };
        }
        self.buf.push(b'\n');
        if self.buf.len() >= BUFFER || self.last_flush.elapsed() > Duration::from_secs(1) {
            self.flush()?;
        }
        Ok(())
    }

    /// Write the buffered rows to the file now. On failure the file is cut
    /// back to the rows written before, and the rows are dropped.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.last_flush = Instant::now();
        if self.buf.is_empty() {
            return Ok(());
        }
        match self.file.write_all(&self.buf) {
            Ok(()) => {
                self.written += self.buf.len() as u64;
                self.buf.clear();
                Ok(())
            }
            Err(e) => {
                self.buf.clear();
                // cutting back frees space: it works on a full disk too
                let _ = self
                    .file
                    .set_len(self.written)
                    .and_then(|_| self.file.seek(SeekFrom::Start(self.written)));
                Err(io_at(&self.path, e))
            }
        }
    }
}

impl Drop for HistoryWriter {
    fn drop(&mut self) {
        let _ = self.flush();
    }
}

/// Read a CSV written by [`HistoryWriter`] back: header and numeric rows.
/// A row with another number of fields than the header, or a field that is
/// not a number, is refused (`InvalidData`, with the file and line).
pub fn read(path: &Path) -> std::io::Result<(Vec<String>, Vec<Vec<f64>>)> {
    let text = std::fs::read_to_string(path).map_err(|e| io_at(path, e))?;
    let h = History::parse(&text).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("{}: {e}", path.display()),
        )
    })?;
    Ok((h.columns, h.rows))
}

/// The smallest, largest and last value of a `history.csv` column, with
/// the times of the first two.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Extrema {
    /// Smallest value.
    pub min: f64,
    /// Its time (the first row that has it).
    pub t_min: f64,
    /// Largest value.
    pub max: f64,
    /// Its time.
    pub t_max: f64,
    /// Value of the last row.
    #[serde(rename = "final")]
    pub last: f64,
}

/// [`Extrema`] of the columns `names` of the history at `path` (read row
/// by row; `t` is the column `t`), `None` for a column it does not have
/// or without rows.
pub fn extrema(path: &Path, names: &[&str]) -> std::io::Result<Vec<Option<Extrema>>> {
    use std::io::BufRead;
    let file = File::open(path).map_err(|e| io_at(path, e))?;
    let mut lines = std::io::BufReader::new(file).lines();
    let header: Vec<String> = match lines.next() {
        Some(h) => h?.split(',').map(str::to_string).collect(),
        None => return Ok(vec![None; names.len()]),
    };
    let col = |n: &str| header.iter().position(|h| h == n);
    let (cols, t): (Vec<Option<usize>>, _) = (names.iter().map(|n| col(n)).collect(), col("t"));
    let mut out: Vec<Option<Extrema>> = vec![None; names.len()];
    for line in lines {
        let line = line?;
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.trim().parse().unwrap_or(f64::NAN))
            .collect();
        let time = t.and_then(|t| v.get(t).copied()).unwrap_or(f64::NAN);
        for (e, c) in out.iter_mut().zip(&cols) {
            let Some(&x) = c.and_then(|c| v.get(c)) else {
                continue;
            };
            let e = e.get_or_insert(Extrema {
                min: x,
                t_min: time,
                max: x,
                t_max: time,
                last: x,
            });
            if x < e.min {
                (e.min, e.t_min) = (x, time);
            }
            if x > e.max {
                (e.max, e.t_max) = (x, time);
            }
            e.last = x;
        }
    }
    Ok(out)
}

/// Write the discs as `x,y,r,id` in scenario order, `id` the disc's number
/// (from 1, as probes and the frames' `GlobalIds` give it), with a fifth
/// column `clump` (the disc's clump from 1, 0 for none) when there are
/// clumps: a
/// `discs = { csv = ... }` source (its header names the columns), written
/// atomically: a reader never sees part of it.
pub fn write_discs_csv(gr: &Granular, path: &Path) -> std::io::Result<()> {
    let p = &gr.particles;
    let clumps = !gr.clumps.is_empty();
    super::write_atomic(path, true, |w| {
        writeln!(w, "x,y,r,id{}", if clumps { ",clump" } else { "" })?;
        for id in 0..p.len() {
            let k = p.slot[id] as usize;
            disc_row(w, p.pos[k], p.radius[k], id)?;
            if clumps {
                write!(w, ",{}", clump_number(p.clump[k]))?;
            }
            writeln!(w)?;
        }
        Ok(())
    })
}

/// The columns `x,y,r,id` of disc `id` (0-based) in `discs_final.csv`.
fn disc_row(w: &mut impl Write, x: Vec2, r: f64, id: usize) -> std::io::Result<()> {
    write!(w, "{:e},{:e},{r:e},{}", x.x, x.y, id + 1)
}

/// `discs_final.csv` of `n` discs without clumps, as [`write_discs_csv`]
/// writes it, from `chunk(ids)`: the positions and radii of a range of
/// ids at a time (`None`: not this process's to write; a decomposed
/// assembly gathers them from the ranks). `chunk` is called for every
/// range even when writing fails, so that every rank takes part in the
/// same gathers.
pub fn write_discs_csv_by_ids(
    path: Option<&Path>,
    n: usize,
    mut chunk: impl FnMut(std::ops::Range<usize>) -> Option<Vec<(Vec2, f64)>>,
) -> std::io::Result<()> {
    const IDS: usize = 1 << 16;
    let mut ranges = (0..n).step_by(IDS).map(|lo| lo..(lo + IDS).min(n));
    let res = match path {
        Some(path) => super::write_atomic(path, true, |w| {
            writeln!(w, "x,y,r,id")?;
            let mut res = Ok(());
            for ids in ranges.by_ref() {
                let got = chunk(ids.clone()).unwrap_or_default();
                for (k, (x, r)) in got.into_iter().enumerate() {
                    if res.is_ok() {
                        res = disc_row(w, x, r, ids.start + k).and_then(|()| writeln!(w));
                    }
                }
            }
            res
        }),
        None => Ok(()),
    };
    // the gathers the writer did not reach
    ranges.for_each(|ids| drop(chunk(ids)));
    res
}

/// A disc's clump as written: its number from 1, 0 for no clump.
pub fn clump_number(c: u32) -> i64 {
    if c == crate::dem::clumps::NO_CLUMP {
        0
    } else {
        i64::from(c) + 1
    }
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
    super::write_atomic(path, true, |w| {
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
        Ok(())
    })
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
        let e = extrema(&p, &["f", "g"]).unwrap();
        assert_eq!(e[1], None);
        let e = e[0].unwrap();
        assert_eq!(
            (e.min, e.t_min, e.max, e.t_max, e.last),
            (-2.25e-9, 0.1, 1.5, 0.0, -2.25e-9)
        );
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
    /// Refused: a row of another width than the header, a field that is
    /// not a number, a text that does not end with a line end (a file cut
    /// short: its last number may be cut too).
    pub fn parse(text: &str) -> Result<History, String> {
        if !text.is_empty() && !text.ends_with('\n') {
            return Err(format!(
                "line {}: the last row has no line end: the file was cut short",
                text.lines().count()
            ));
        }
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
