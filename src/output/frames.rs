//! The ParaView frames of a model, named the same by every run kind and by
//! the Python module (step number, 7 digits):
//!
//! | dataset | series | frames |
//! |---|---|---|
//! | discs | `discs.pvd` | `frames/discs_NNNNNNN.vtp` |
//! | contacts of every kind | `contacts.pvd` | `frames/contacts_NNNNNNN.vtp` |
//! | walls (if any) | `walls.pvd` | `frames/walls_NNNNNNN.vtp` |
//! | broken parallel bonds (with `[bonds]`) | `cracks.pvd` | `frames/cracks_NNNNNNN.vtp` |
//! | each body | `<body>.pvd` | `frames/<body>_NNNNNNN.vtu` |
//! | the cracks of each EFG body with cracks | `<body>_cracks.pvd` | `frames/<body>_cracks_NNNNNNN.vtp` |
//!
//! A static analysis writes `<body>.vtu` (and `<body>_cracks.vtp`). What
//! each file holds: [`vtp`](super::vtp), [`vtu`](super::vtu),
//! [`cracks`](super::cracks); how: [`vtk`](super::vtk).

use super::cracks::write_cracks as write_body_cracks;
use super::vtk::{PvdSeries, VtkFormat};
use super::vtp::{write_contacts, write_cracks, write_discs, write_walls};
use super::vtu::write_body;
use crate::efg::assemble::PointShapes;
use crate::model::Model;
use crate::model::body::{BodyError, BodyRef};
use std::path::{Path, PathBuf};

/// Frame file of dataset `stem` at `step`, relative to the output directory.
pub fn frame_file(stem: &str, step: usize, ext: &str) -> String {
    format!("frames/{stem}_{step:07}.{ext}")
}

/// Does body `i` of `model` have cracks (an EFG body with cracks)?
fn has_cracks(model: &Model, i: usize) -> bool {
    matches!(model.body(i), BodyRef::Efg(b) if !b.cracks().is_empty())
}

/// The cracks of body `i` (`shapes`: its nodal shape rows) to `path`.
fn crack_frame(
    model: &Model,
    i: usize,
    shapes: &Option<PointShapes>,
    format: VtkFormat,
    path: &Path,
) -> std::io::Result<()> {
    match (model.body(i), shapes) {
        (BodyRef::Efg(b), Some(s)) => write_body_cracks(b, s, format, path),
        _ => Ok(()),
    }
}

/// One dataset of the frames.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Dataset {
    Discs,
    Contacts,
    Walls,
    Cracks,
    Body(usize),
    BodyCracks(usize),
}

/// The frame series of one model in one directory.
pub struct Frames {
    dir: PathBuf,
    format: VtkFormat,
    bodies: Vec<String>,
    /// Per body: EFG nodal shape rows (FE needs none) and the body's
    /// generation they belong to (a body rebuilt by crack growth needs new
    /// ones).
    nodal: Vec<(Option<PointShapes>, usize)>,
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
            .map(|i| Ok((model.body(i).frame_data()?, model.body(i).generation())))
            .collect::<Result<_, BodyError>>()?;
        let mut sets = Vec::new();
        if let Some(g) = model.granular() {
            sets.push((Dataset::Discs, "discs".to_string()));
            sets.push((Dataset::Contacts, "contacts".to_string()));
            if !g.walls.is_empty() {
                sets.push((Dataset::Walls, "walls".to_string()));
            }
            if g.bonds.active() {
                sets.push((Dataset::Cracks, "cracks".to_string()));
            }
        }
        for (i, n) in bodies.iter().enumerate() {
            sets.push((Dataset::Body(i), n.clone()));
            if has_cracks(model, i) {
                sets.push((Dataset::BodyCracks(i), format!("{n}_cracks")));
            }
        }
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
        self.refresh(model)?;
        let (step, t) = (model.step, model.time());
        let contacts = match model.granular() {
            Some(_) => model.contacts(),
            None => Vec::new(),
        };
        let mut written = Vec::new();
        for (set, series) in &mut self.series {
            let (stem, ext) = match *set {
                Dataset::Discs => ("discs".to_string(), "vtp"),
                Dataset::Contacts => ("contacts".to_string(), "vtp"),
                Dataset::Walls => ("walls".to_string(), "vtp"),
                Dataset::Body(i) => (self.bodies[i].clone(), "vtu"),
                Dataset::Cracks => ("cracks".to_string(), "vtp"),
                Dataset::BodyCracks(i) => (format!("{}_cracks", self.bodies[i]), "vtp"),
            };
            let f = frame_file(&stem, step, ext);
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
                    write_body(model.body(i), self.nodal[i].0.as_ref(), self.format, &path)?
                }
                Dataset::BodyCracks(i) => {
                    crack_frame(model, i, &self.nodal[i].0, self.format, &path)?
                }
            }
            series.add(t, &f)?;
            written.push(path);
        }
        Ok(written)
    }

    /// A static analysis: `<body>.vtu` per body (and `<body>_cracks.vtp`
    /// for a body with cracks), no series.
    pub fn write_static(&mut self, model: &Model) -> std::io::Result<Vec<PathBuf>> {
        self.refresh(model)?;
        let mut written = Vec::new();
        for (i, name) in self.bodies.iter().enumerate() {
            let f = self.dir.join(format!("{name}.vtu"));
            write_body(model.body(i), self.nodal[i].0.as_ref(), self.format, &f)?;
            written.push(f);
            if has_cracks(model, i) {
                let f = self.dir.join(format!("{name}_cracks.vtp"));
                crack_frame(model, i, &self.nodal[i].0, self.format, &f)?;
                written.push(f);
            }
        }
        Ok(written)
    }

    /// New nodal shape rows for the bodies rebuilt by crack growth since
    /// the last frame.
    fn refresh(&mut self, model: &Model) -> std::io::Result<()> {
        for (i, (shapes, generation)) in self.nodal.iter_mut().enumerate() {
            let b = model.body(i);
            if b.generation() != *generation {
                *shapes = b.frame_data().map_err(std::io::Error::other)?;
                *generation = b.generation();
            }
        }
        Ok(())
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
