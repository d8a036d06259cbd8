//! `efgdem view`: a ParaView Python script, `view.py`, written next to a
//! run's results, that shows them ready to look at — discs as true-size
//! filled circles coloured by speed, bodies (deformed) coloured by von
//! Mises stress, contact force chains as tubes whose width grows with the
//! normal force, walls, and the time — with colour ranges over the whole
//! series (or per frame), an optional region to zoom into, body grid lines
//! only where they do not hide the colours, and a warp factor for small
//! deflections ([`ViewOptions`]). `paraview --script=OUT/view.py` opens it;
//! `pvbatch OUT/view.py --screenshot FILE.png` renders an image, and
//! [`render`] does so on a machine without a display too.

use serde::Serialize;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// The script (`src/output/view.py`); `@DIR@` is replaced by the run's
/// directory, used when ParaView runs the script without `__file__`, and
/// `@OPTIONS@` by the [`ViewOptions`] as JSON: its defaults.
const SCRIPT: &str = include_str!("view.py");

/// What the view shows; each is also a command-line option of the script.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewOptions {
    /// The frame shown (default: the last).
    pub time: Option<f64>,
    /// Image size in pixels (screenshots).
    pub size: Option<[u32; 2]>,
    /// `"velocity"` (speed) or `"displacement"` (since t = 0): the discs'
    /// colour.
    pub discs: String,
    /// `"series"`: colour ranges over all frames; `"frame"`: each frame's.
    pub range: String,
    /// The discs' colour range ends at this percentile of their values.
    pub percentile: f64,
    /// Show only this rectangle `[x0, y0, x1, y1]`.
    pub region: Option<[f64; 4]>,
    /// Body grid lines: `"auto"` (where cells are at least 6 pixels),
    /// `"on"`, `"off"`.
    pub edges: String,
    /// Bodies drawn at `X + warp · u`.
    pub warp: f64,
}

impl Default for ViewOptions {
    fn default() -> Self {
        ViewOptions {
            time: None,
            size: None,
            discs: "velocity".into(),
            range: "series".into(),
            percentile: 99.0,
            region: None,
            edges: "auto".into(),
            warp: 1.0,
        }
    }
}

/// The text of `view.py` for the results in `dir`, with `options` as its
/// defaults.
pub fn script(dir: &Path, options: &ViewOptions) -> String {
    let abs = std::path::absolute(dir).unwrap_or_else(|_| dir.to_path_buf());
    let json = serde_json::to_string(options).expect("options serialise");
    SCRIPT
        .replace("@DIR@", &abs.to_string_lossy().replace('"', "\\\""))
        .replace("@OPTIONS@", &json)
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
pub fn write_script(dir: &Path, options: &ViewOptions) -> std::io::Result<PathBuf> {
    let path = dir.join("view.py");
    std::fs::write(&path, script(dir, options))?;
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

/// Is there a display a GUI (or ParaView's renderer) can open: `DISPLAY`
/// or `WAYLAND_DISPLAY` set?
pub fn has_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// A virtual X server for the time of a rendering, stopped when dropped.
struct VirtualDisplay {
    child: Child,
    display: String,
}

impl VirtualDisplay {
    /// Start `Xvfb` on a free display: it picks the number itself
    /// (`-displayfd`, no race with other servers) and does not reset when
    /// its last client leaves (`-noreset`: a reset while ParaView opens
    /// its second connection aborts it, as `xvfb-run` alone often does).
    fn start(xvfb: &Path) -> std::io::Result<VirtualDisplay> {
        let mut child = Command::new(xvfb)
            .args(["-displayfd", "1", "-noreset", "-nolisten", "tcp"])
            .args(["-screen", "0", "3840x2160x24"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()?;
        let mut line = String::new();
        let read = child
            .stdout
            .take()
            .map(|o| BufReader::new(o).read_line(&mut line));
        match (read, line.trim().parse::<u32>()) {
            (Some(Ok(_)), Ok(n)) => Ok(VirtualDisplay {
                child,
                display: format!(":{n}"),
            }),
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                Err(std::io::Error::other("Xvfb did not start"))
            }
        }
    }
}

impl Drop for VirtualDisplay {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Why [`render`] could not make an image.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// `pvbatch` is not on `PATH`.
    #[error(
        "ParaView's batch renderer `pvbatch` is not on PATH (Debian: apt-get install paraview)"
    )]
    NoParaView,
    /// No display and no `Xvfb` to make one.
    #[error(
        "no display (DISPLAY and WAYLAND_DISPLAY are not set) and no `Xvfb` on PATH to start a virtual one (Debian: apt-get install xvfb)"
    )]
    NoDisplay,
    /// Starting a program failed.
    #[error("{0}: {1}")]
    Start(String, std::io::Error),
    /// `pvbatch` failed.
    #[error("pvbatch failed ({status}):\n{stderr}")]
    Failed {
        /// Its exit status.
        status: std::process::ExitStatus,
        /// The end of its stderr.
        stderr: String,
    },
}

/// Render `script` (a `view.py`) to the image `png` with `pvbatch`; without
/// a display, on a virtual X server started for it. Returns the script's
/// `colours: TITLE: LOW to HIGH` lines, the ranges of the colour bars.
pub fn render(script: &Path, png: &Path) -> Result<Vec<String>, RenderError> {
    let pvbatch = on_path("pvbatch").ok_or(RenderError::NoParaView)?;
    let virtual_display = match has_display() {
        true => None,
        false => {
            let xvfb = on_path("Xvfb").ok_or(RenderError::NoDisplay)?;
            Some(VirtualDisplay::start(&xvfb).map_err(|e| RenderError::Start("Xvfb".into(), e))?)
        }
    };
    let mut cmd = Command::new(&pvbatch);
    cmd.arg(script).arg("--screenshot").arg(png);
    if let Some(v) = &virtual_display {
        cmd.env("DISPLAY", &v.display).env_remove("WAYLAND_DISPLAY");
    }
    let out = cmd
        .output()
        .map_err(|e| RenderError::Start(pvbatch.display().to_string(), e))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = err.lines().rev().take(20).collect();
        return Err(RenderError::Failed {
            status: out.status,
            stderr: tail.into_iter().rev().collect::<Vec<_>>().join("\n"),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.starts_with("colours: "))
        .map(str::to_string)
        .collect())
}
