//! `history.csv`: one row per recorded step, streamed to disk.

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
    last_flush: Instant,
}

impl HistoryWriter {
    /// Create `path` and write the header line.
    pub fn create(path: &Path, columns: &[&str]) -> std::io::Result<Self> {
        let mut out = BufWriter::new(File::create(path)?);
        writeln!(out, "{}", columns.join(","))?;
        out.flush()?;
        Ok(HistoryWriter {
            out,
            ncols: columns.len(),
            last_flush: Instant::now(),
        })
    }

    /// Append one row; `values.len()` must equal the number of columns.
    pub fn row(&mut self, values: &[f64]) -> std::io::Result<()> {
        debug_assert_eq!(values.len(), self.ncols, "history row width");
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.out.write_all(b",")?;
            }
            write!(self.out, "{v:e}")?;
        }
        self.out.write_all(b"\n")?;
        if self.last_flush.elapsed() > Duration::from_secs(1) {
            self.flush()?;
        }
        Ok(())
    }

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
