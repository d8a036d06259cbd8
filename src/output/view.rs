//! `efgdem view`: a ParaView Python script, `view.py`, written next to a
//! run's results, that shows them ready to look at — discs as true-size
//! filled circles coloured by speed, bodies (deformed) coloured by von
//! Mises stress, contact force chains as tubes whose width grows with the
//! normal force, walls, and the time. `paraview --script=OUT/view.py`
//! opens it; `pvbatch OUT/view.py --screenshot FILE.png` renders an image.

use std::path::{Path, PathBuf};

/// The script (`src/output/view.py`); `@DIR@` is replaced by the run's
/// directory, used when ParaView runs the script without `__file__`.
const SCRIPT: &str = include_str!("view.py");

/// The text of `view.py` for the results in `dir`.
pub fn script(dir: &Path) -> String {
    let abs = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    SCRIPT.replace("@DIR@", &abs.to_string_lossy().replace('"', "\\\""))
}

/// Does `dir` hold frames this script shows (`*.pvd` or `*.vtu`)?
pub fn has_frames(dir: &Path) -> std::io::Result<bool> {
    Ok(std::fs::read_dir(dir)?.filter_map(Result::ok).any(|e| {
        let n = e.file_name();
        let n = n.to_string_lossy();
        n.ends_with(".pvd") || n.ends_with(".vtu")
    }))
}

/// Write `dir/view.py`; returns its path.
pub fn write_script(dir: &Path) -> std::io::Result<PathBuf> {
    let path = dir.join("view.py");
    std::fs::write(&path, script(dir))?;
    Ok(path)
}

/// The first `program` on `PATH`, if any.
pub fn on_path(program: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|p| {
        std::env::split_paths(&p)
            .map(|d| d.join(program))
            .find(|f| f.is_file())
    })
}
