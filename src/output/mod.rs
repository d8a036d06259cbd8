//! Everything written to disk: history CSV, ParaView files, summary JSON,
//! plots and reports. Files are streamed and flushed as the run goes, so a
//! run that is stopped keeps what it computed.

pub mod csv;
pub mod frames;
pub mod plot;
pub mod traction;
pub mod view;
pub mod vtk;
pub mod vtp;
pub mod vtu;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// `e` with the path of the file it concerns in its message, once:
/// `out/history.csv: No space left on device (os error 28)`.
pub fn io_at(path: &Path, e: std::io::Error) -> std::io::Error {
    std::io::Error::new(e.kind(), format!("{}: {e}", path.display()))
}

/// The temporary name `path` is written under before it is renamed:
/// `summary.json` → `summary.json.tmp` (what `--overwrite` clears).
pub fn temporary(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Write the file `path` whole or not at all: `write` fills a temporary
/// file next to it, which is flushed (and with `sync`, synced to the disk)
/// and renamed over `path`. A reader sees the old file or the new one,
/// never a part; on an error (a full disk) the temporary file is removed
/// and `path` is as it was. Errors name the file.
pub fn write_atomic(
    path: &Path,
    sync: bool,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = temporary(path);
    let result = (|| {
        let mut w = BufWriter::with_capacity(1 << 16, File::create(&tmp)?);
        write(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        if sync {
            f.sync_all()?;
        }
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(|e| io_at(path, e))
}

/// Write `value` as pretty JSON to `path` atomically ([`write_atomic`]),
/// so a reader never sees a half-written summary.
pub fn write_json(path: &Path, value: &serde_json::Value) -> std::io::Result<()> {
    write_atomic(path, true, |f| {
        serde_json::to_writer_pretty(&mut *f, value)?;
        f.write_all(b"\n")
    })
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
