//! Everything written to disk: history CSV, ParaView files, summary JSON,
//! plots and reports. Files are streamed and flushed as the run goes, so a
//! run that is stopped keeps what it computed.

pub mod cracks;
pub mod csv;
pub mod frames;
pub mod plot;
pub mod traction;
pub mod view;
pub mod vtk;
pub mod vtp;
pub mod vtu;

use std::io::Write;
use std::path::Path;

/// Write `value` as pretty JSON to `path` atomically (temp file + rename),
/// so a reader never sees a half-written summary.
pub fn write_json(path: &Path, value: &serde_json::Value) -> std::io::Result<()> {
    let tmp = path.with_extension("json.tmp");
    {
        let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        serde_json::to_writer_pretty(&mut f, value)?;
        f.write_all(b"\n")?;
        f.flush()?;
    }
    std::fs::rename(tmp, path)
}

/// A progress bar on stderr for `len` steps; hidden when stderr is not a
/// terminal (CI, pipes) or when `quiet`.
pub fn progress(len: u64, quiet: bool) -> indicatif::ProgressBar {
    if quiet {
        return indicatif::ProgressBar::hidden();
    }
    let pb = indicatif::ProgressBar::new(len);
    pb.set_style(
        indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} steps ({per_sec}, eta {eta}) {msg}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    pb
}
