//! The ParaView frames of a model, named the same by every run kind and by
//! the Python module: `frames/discs_NNNNNNN.vtp` and
//! `frames/<body>_NNNNNNN.vtu` (step number, 7 digits), listed in
//! `discs.pvd` and `<body>.pvd`; a static analysis writes `<body>.vtu`.

use super::vtk::PvdSeries;
use super::vtp::write_granular;
use super::vtu::write_body;
use crate::efg::assemble::PointShapes;
use crate::model::Model;
use crate::model::body::BodyError;
use std::path::{Path, PathBuf};

/// Frame file of dataset `stem` at `step`, relative to the output directory.
pub fn frame_file(stem: &str, step: usize, ext: &str) -> String {
    format!("frames/{stem}_{step:07}.{ext}")
}

/// The frame series of one model in one directory.
pub struct Frames {
    dir: PathBuf,
    bodies: Vec<String>,
    /// Per body: EFG nodal shape rows (FE needs none).
    nodal: Vec<Option<PointShapes>>,
    /// `discs.pvd` first if the model has discs, then one per body.
    series: Vec<PvdSeries>,
}

impl Frames {
    /// Frames of `model` into `dir` (nothing is written yet; the bodies'
    /// nodal shape rows are computed now).
    pub fn new(model: &Model, dir: &Path) -> Result<Self, BodyError> {
        let bodies: Vec<String> = (0..model.n_bodies())
            .map(|i| model.body(i).name().to_string())
            .collect();
        let nodal = (0..bodies.len())
            .map(|i| model.body(i).frame_data())
            .collect::<Result<_, _>>()?;
        let mut series = Vec::new();
        if model.granular().is_some() {
            series.push(PvdSeries::new(&dir.join("discs.pvd")));
        }
        series.extend(
            bodies
                .iter()
                .map(|n| PvdSeries::new(&dir.join(format!("{n}.pvd")))),
        );
        Ok(Frames {
            dir: dir.to_path_buf(),
            bodies,
            nodal,
            series,
        })
    }

    /// Write the frames of the present step and list them in the series;
    /// returns the files written. Every file is written under a temporary
    /// name and renamed, so a reader never sees half a frame.
    pub fn write(&mut self, model: &Model) -> std::io::Result<Vec<PathBuf>> {
        std::fs::create_dir_all(self.dir.join("frames"))?;
        let (step, t) = (model.step, model.time());
        let mut written = Vec::new();
        let mut series = self.series.iter_mut();
        if let Some(g) = model.granular() {
            let f = frame_file("discs", step, "vtp");
            write_granular(g, &self.dir.join(&f))?;
            series.next().expect("a disc series").add(t, &f)?;
            written.push(self.dir.join(f));
        }
        for (i, (name, s)) in self.bodies.iter().zip(series).enumerate() {
            let f = frame_file(name, step, "vtu");
            write_body(model.body(i), self.nodal[i].as_ref(), &self.dir.join(&f))?;
            s.add(t, &f)?;
            written.push(self.dir.join(f));
        }
        Ok(written)
    }

    /// A static analysis: `<body>.vtu` per body, no series.
    pub fn write_static(&self, model: &Model) -> std::io::Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        for (i, name) in self.bodies.iter().enumerate() {
            let f = self.dir.join(format!("{name}.vtu"));
            write_body(model.body(i), self.nodal[i].as_ref(), &f)?;
            written.push(f);
        }
        Ok(written)
    }

    /// The series' entries `(time, file)` so far (for a checkpoint).
    pub fn entries(&self) -> Vec<Vec<(f64, String)>> {
        self.series.iter().map(|s| s.entries().to_vec()).collect()
    }

    /// Continue series with the entries of [`entries`](Self::entries)
    /// (a restart) and rewrite the `.pvd` files.
    pub fn resume(&mut self, entries: Vec<Vec<(f64, String)>>) -> std::io::Result<()> {
        self.series
            .iter_mut()
            .zip(entries)
            .try_for_each(|(s, e)| s.resume(e))
    }
}
