//! The ParaView frames of a model, named the same by every run kind and by
//! the Python module (step number, 7 digits):
//!
//! | dataset | series | frames |
//! |---|---|---|
//! | discs | `discs.pvd` | `frames/discs_NNNNNNN.vtp` |
//! | contacts of every kind | `contacts.pvd` | `frames/contacts_NNNNNNN.vtp` |
//! | walls (if any) | `walls.pvd` | `frames/walls_NNNNNNN.vtp` |
//! | each body | `<body>.pvd` | `frames/<body>_NNNNNNN.vtu` |
//!
//! A static analysis writes `<body>.vtu`. What each file holds:
//! [`vtp`](super::vtp), [`vtu`](super::vtu); how: [`vtk`](super::vtk).

use super::vtk::{PvdSeries, VtkFormat};
use super::vtp::{write_contacts, write_cracks, write_discs, write_walls};
use super::vtu::write_body;
use crate::efg::assemble::PointShapes;
use crate::model::Model;
use crate::model::body::BodyError;
use std::path::{Path, PathBuf};

/// Frame file of dataset `stem` at `step`, relative to the output directory.
pub fn frame_file(stem: &str, step: usize, ext: &str) -> String {
    format!("frames/{stem}_{step:07}.{ext}")
}

/// One dataset of the frames.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Dataset {
    Discs,
    Contacts,
    Walls,
    Cracks,
    Body(usize),
}

/// The frame series of one model in one directory.
pub struct Frames {
    dir: PathBuf,
    format: VtkFormat,
    bodies: Vec<String>,
    /// Per body: EFG nodal shape rows (FE needs none).
    nodal: Vec<Option<PointShapes>>,
    /// The datasets in the order of [`entries`](Self::entries): discs,
    /// contacts and walls (if the model has them), then the bodies.
    series: Vec<(Dataset, PvdSeries)>,
}

impl Frames {
    /// Frames of `model` into `dir`, binary (nothing is written yet; the
    /// bodies' nodal shape rows are computed now).
    pub fn new(model: &Model, dir: &Path) -> Result<Self, BodyError> {
        let bodies: Vec<String> = (0..model.n_bodies())
            .map(|i| model.body(i).name().to_string())
            .collect();
        let nodal = (0..bodies.len())
            .map(|i| model.body(i).frame_data())
            .collect::<Result<_, _>>()?;
        let mut sets = Vec::new();
        if let Some(g) = model.granular() {
            sets.push((Dataset::Discs, "discs"));
            sets.push((Dataset::Contacts, "contacts"));
            if !g.walls.is_empty() {
                sets.push((Dataset::Walls, "walls"));
            }
            if g.bonds.active() {
                sets.push((Dataset::Cracks, "cracks"));
            }
        }
        sets.extend(
            bodies
                .iter()
                .enumerate()
                .map(|(i, n)| (Dataset::Body(i), n.as_str())),
        );
        let series = sets
            .into_iter()
            .map(|(d, n)| (d, PvdSeries::new(&dir.join(format!("{n}.pvd")))))
            .collect();
        Ok(Frames {
            dir: dir.to_path_buf(),
            format: VtkFormat::default(),
            bodies,
            nodal,
            series,
        })
    }

    /// Store the arrays as `format` (the scenario's `output.vtk_format`).
    pub fn with_format(mut self, format: VtkFormat) -> Self {
        self.format = format;
        self
    }

    /// Write the frames of the present step and list them in the series;
    /// returns the files written. Every file is written under a temporary
    /// name and renamed, so a reader never sees half a frame.
    pub fn write(&mut self, model: &Model) -> std::io::Result<Vec<PathBuf>> {
        std::fs::create_dir_all(self.dir.join("frames"))?;
        let (step, t) = (model.step, model.time());
        let contacts = match model.granular() {
            Some(_) => model.contacts(),
            None => Vec::new(),
        };
        let mut written = Vec::new();
        for (set, series) in &mut self.series {
            let (stem, ext) = match *set {
                Dataset::Discs => ("discs", "vtp"),
                Dataset::Contacts => ("contacts", "vtp"),
                Dataset::Walls => ("walls", "vtp"),
                Dataset::Cracks => ("cracks", "vtp"),
                Dataset::Body(i) => (self.bodies[i].as_str(), "vtu"),
            };
            let f = frame_file(stem, step, ext);
            let path = self.dir.join(&f);
            let g = || {
                model
                    .granular()
                    .expect("discs are written with a granular model")
            };
            match *set {
                Dataset::Discs => write_discs(g(), &contacts, self.format, &path)?,
                Dataset::Contacts => write_contacts(g(), &contacts, self.format, &path)?,
                Dataset::Walls => write_walls(g(), self.format, &path)?,
                Dataset::Cracks => write_cracks(g(), self.format, &path)?,
                Dataset::Body(i) => {
                    write_body(model.body(i), self.nodal[i].as_ref(), self.format, &path)?
                }
            }
            series.add(t, &f)?;
            written.push(path);
        }
        Ok(written)
    }

    /// A static analysis: `<body>.vtu` per body, no series.
    pub fn write_static(&self, model: &Model) -> std::io::Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        for (i, name) in self.bodies.iter().enumerate() {
            let f = self.dir.join(format!("{name}.vtu"));
            write_body(model.body(i), self.nodal[i].as_ref(), self.format, &f)?;
            written.push(f);
        }
        Ok(written)
    }

    /// The series' entries `(time, file)` so far (for a checkpoint).
    pub fn entries(&self) -> Vec<Vec<(f64, String)>> {
        self.series
            .iter()
            .map(|(_, s)| s.entries().to_vec())
            .collect()
    }

    /// Continue series with the entries of [`entries`](Self::entries)
    /// (a restart) and write the `.pvd` files as they were then. Entries
    /// of another set of series (a checkpoint of an older layout) are
    /// refused.
    pub fn resume(&mut self, entries: Vec<Vec<(f64, String)>>) -> std::io::Result<()> {
        if entries.len() != self.series.len() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "the checkpoint lists {} frame series, this model writes {}: a checkpoint of another output layout",
                    entries.len(),
                    self.series.len()
                ),
            ));
        }
        self.series
            .iter_mut()
            .zip(entries)
            .try_for_each(|((_, s), e)| s.resume(e))
    }
}
