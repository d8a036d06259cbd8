//! The scenario: one TOML format for EFG-only, DEM-only and coupled runs.
//!
//! A run differs only in which sections are present (`[[body]]`,
//! `[granular]`, `[[wall]]`). Every table denies unknown fields. Semantic
//! checks (`validate`) report a dotted path such as `body.0.elastic.E`,
//! which [`parse`] maps back to the line of the file with `toml_edit`, so
//! that every error reads `file:line: field: what is wrong (what is allowed)`.
//! Every field and its default is documented in `docs/scenario.md`.

pub mod body;
pub mod bonds;
pub mod build;
pub mod builder;
pub mod clumps;
pub mod crack;
pub mod fill;
pub mod generate;
pub mod granular;
pub mod measure;
mod part;
pub use part::PartSkeleton;
pub mod prepare;
pub mod rect;

use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};

/// A whole scenario file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// `[simulation]`: time stepping, gravity, coupling options.
    #[serde(default)]
    pub simulation: Simulation,
    /// Contact materials, referenced by name from discs and walls.
    #[serde(default)]
    pub material: Vec<Material>,
    /// Continuum bodies (EFG or FE).
    #[serde(default)]
    pub body: Vec<body::BodySpec>,
    /// The granular assembly (discs).
    pub granular: Option<granular::GranularSpec>,
    /// Rigid walls (line segments).
    #[serde(default)]
    pub wall: Vec<granular::WallSpec>,
    /// Parallel bonds between the discs.
    pub bonds: Option<bonds::BondsSpec>,
    /// Rigid clumps of discs.
    pub clumps: Option<clumps::ClumpsSpec>,
    /// History outputs, one `history.csv` column each.
    #[serde(default)]
    pub probe: Vec<Probe>,
    /// Stress / fabric measurement regions, several `history.csv` columns
    /// each (after the probes).
    #[serde(default)]
    pub measure: Vec<measure::MeasureSpec>,
    /// `[output]`: history and frame intervals.
    #[serde(default)]
    pub output: Output,
    /// Directory of the scenario file: relative paths inside it resolve here.
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// The file name and text it was parsed from (to locate problems).
    #[serde(skip)]
    pub source: Option<std::sync::Arc<Source>>,
}

/// Where a scenario came from.
#[derive(Debug)]
pub struct Source {
    /// File name as given (for messages).
    pub file: String,
    /// The whole TOML text.
    pub text: String,
}

/// Which kind of run a scenario describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Continuum bodies only.
    Continuum,
    /// Discs (and walls) only.
    Granular,
    /// Both: the coupled EFG–DE problem.
    Coupled,
}

/// The kind of run: from the sections present.
pub fn kind(sc: &Scenario) -> Kind {
    match (sc.body.is_empty(), sc.granular.is_some()) {
        (false, false) => Kind::Continuum,
        (true, _) => Kind::Granular,
        (false, true) => Kind::Coupled,
    }
}

/// `[simulation]`: time stepping and global loads.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Simulation {
    /// `"static"` (one linear solve) or `"dynamic"` (time stepping).
    #[serde(default)]
    pub analysis: Analysis,
    /// Time step; for DEM runs `None` means
    /// [`DT_SAFETY`](build::DT_SAFETY) × the critical step.
    pub dt: Option<f64>,
    /// Number of steps (or give `end_time`).
    pub steps: Option<usize>,
    /// End time; the number of steps is `end_time / dt` (rounded up for
    /// continuum-only runs, to nearest otherwise).
    pub end_time: Option<f64>,
    /// Gravity acceleration vector.
    #[serde(default)]
    pub gravity: [f64; 2],
    /// Worker threads; 0 = all cores. Results do not depend on it.
    #[serde(default)]
    pub threads: usize,
    /// Coupled runs: DEM steps per body (Newmark) step, or `"auto"` (the
    /// default: chosen with the scheme, [`crate::coupling::scheme`]).
    #[serde(default)]
    pub substeps: Substeps,
    /// Coupled runs: the coupled scheme (default `"auto"`).
    #[serde(default)]
    pub coupling: CouplingScheme,
    /// Coupled runs: Newton iterations a contact solve may take before the
    /// run stops (default 30).
    #[serde(default = "newton_cap")]
    pub contact_iterations: usize,
    /// Coupled runs: how a body gives the compliance of the implicit contact
    /// step.
    #[serde(default)]
    pub contact_solve: ContactSolve,
    /// Coupled runs: the geometric stiffness of segment contacts (the
    /// normal turning with the boundary) implicit in the step (default
    /// true; false saves its unknowns, at the risk of energy created at
    /// the corners of finely resolved bodies).
    #[serde(default = "yes")]
    pub geometric_stiffness: bool,
}

fn yes() -> bool {
    true
}

/// `[simulation] contact_solve`: `"boundary"` (default: the body's
/// boundary Green matrix, computed once at the first contact; no solve per
/// contact) or `"direct"` (two solves per contact and step: the reference,
/// for checking).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ContactSolve {
    /// Through the boundary Green matrix, built once.
    #[default]
    Boundary,
    /// Two solves per contact and step (the reference).
    Direct,
}

fn newton_cap() -> usize {
    crate::coupling::implicit::MAX_NEWTON
}

/// `[simulation] substeps`: a count, or `"auto"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Substeps {
    /// Chosen with the scheme.
    #[default]
    Auto,
    /// This many DEM steps per body step.
    Fixed(usize),
}

impl<'de> Deserialize<'de> for Substeps {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            N(i64),
            S(String),
        }
        match Raw::deserialize(d)? {
            Raw::N(n) if n >= 0 => Ok(Substeps::Fixed(n as usize)),
            Raw::N(n) => Err(serde::de::Error::custom(format!(
                "expected a positive integer or \"auto\", got {n}"
            ))),
            Raw::S(s) if s == "auto" => Ok(Substeps::Auto),
            Raw::S(s) => Err(serde::de::Error::custom(format!(
                "expected a positive integer or \"auto\", got \"{s}\""
            ))),
        }
    }
}

impl Substeps {
    /// The count, if one is given.
    pub fn fixed(&self) -> Option<usize> {
        match self {
            Substeps::Auto => None,
            Substeps::Fixed(n) => Some(*n),
        }
    }
}

/// `[simulation] coupling`: the coupled scheme
/// ([`crate::coupling::scheme`]): `"auto"` (default: the fastest safe one,
/// with `substeps`), `"exact"`, `"predicted"`, `"compliant"`,
/// `"staggered"` (the body takes the contact forces of the previous state
/// as loads — the plain explicit transfer, kept for comparison), or
/// `"implicit"` (the exact step with `substeps = 1`, the predicted scheme
/// with more).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum CouplingScheme {
    /// Chosen with `substeps`.
    #[default]
    Auto,
    /// A body step per DEM step, the contacts implicit in it.
    Exact,
    /// Sub-cycled, the boundary on its predicted path.
    Predicted,
    /// Sub-cycled, the boundary giving way to the contacts through the
    /// body step's compliance in every DEM step.
    Compliant,
    /// The body takes the previous state's contact forces as loads.
    Staggered,
    /// The exact step with one substep, the predicted scheme with more.
    Implicit,
}

impl Default for Simulation {
    fn default() -> Self {
        Simulation {
            analysis: Analysis::Dynamic,
            dt: None,
            steps: None,
            end_time: None,
            gravity: [0.0, 0.0],
            threads: 0,
            substeps: Substeps::Auto,
            coupling: CouplingScheme::Auto,
            contact_iterations: newton_cap(),
            contact_solve: ContactSolve::Boundary,
            geometric_stiffness: true,
        }
    }
}

/// `[simulation] analysis`: `"static"` or `"dynamic"` (default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Analysis {
    /// One linear solve `K̄ U = F` per body (continuum-only runs; granular
    /// and coupled runs are always dynamic and ignore it).
    Static,
    /// Time stepping: Newmark for the bodies, central difference for the
    /// discs.
    #[default]
    Dynamic,
}

/// `[[material]]`: a contact material (discs, walls, body contact edges).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Unique name; discs, walls and bodies refer to the material by it.
    pub name: String,
    /// Mass density of discs made of this material.
    #[serde(default)]
    pub density: f64,
    /// Normal contact stiffness `k_n` (force / length).
    #[serde(default)]
    pub kn: f64,
    /// Shear contact stiffness `k_s`.
    #[serde(default)]
    pub ks: f64,
    /// Friction coefficient `tan φ` (Eq. 37).
    #[serde(default)]
    pub friction: f64,
    /// Cohesion `c` (force) in the Coulomb cap (Eq. 37).
    #[serde(default)]
    pub cohesion: f64,
    /// Normal force in the Coulomb cap and the rolling limit: `"total"`
    /// (spring + dashpot, the paper; default) or `"elastic"` (PFC); read
    /// with [`granular::slip_normal`] (checked by the validation, so that
    /// a bad value is reported with its field).
    #[serde(default = "granular::total")]
    pub slip_normal: String,
    /// Rolling friction `μ_r` (default 0: no rolling resistance).
    #[serde(default)]
    pub rolling_friction: f64,
    /// Rolling stiffness factor `β_r`, `k_r = β_r k_s r̄²` (default 1).
    #[serde(default = "one_f64")]
    pub rolling_stiffness: f64,
    /// Rolling dashpot, fraction of critical `η_r` (default 0).
    #[serde(default)]
    pub rolling_damping: f64,
}

fn one_f64() -> f64 {
    1.0
}

/// `[[probe]]`: one named time series in `history.csv`. Which fields are
/// meaningful depends on `quantity`; each driver checks the probes it knows.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Probe {
    /// Column name in `history.csv`.
    pub name: String,
    /// What to record, e.g. `"uy"` at a body point, `"normal_elastic"` at a contact.
    pub quantity: String,
    /// A point of a body (reference configuration).
    pub point: Option<[f64; 2]>,
    /// Body name (default: the first body).
    pub body: Option<String>,
    /// A contact between two discs, 1-based disc numbers.
    pub contact: Option<[usize; 2]>,
    /// A disc, 1-based.
    pub disc: Option<usize>,
    /// A wall name.
    pub wall: Option<String>,
    /// A crack of the body, 1-based (crack quantities; default 1).
    pub crack: Option<usize>,
    /// The crack's end: 1 its first point, 2 its last (stress intensity
    /// factors; default: the last point if it is a tip, else the first).
    pub tip: Option<usize>,
}

/// `[output]`: what is written and how often.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// A `history.csv` row every this many steps.
    #[serde(default = "one")]
    pub every: usize,
    /// A ParaView frame every this many steps; 0 = none.
    #[serde(default)]
    pub vtk_every: usize,
    /// How the frames' arrays are stored.
    #[serde(default)]
    pub vtk_format: VtkFormat,
}

/// How the arrays of the ParaView frames are stored.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VtkFormat {
    /// Binary, appended raw after the XML, each array zlib-compressed
    /// (VTK's `vtkZLibDataCompressor` blocks).
    #[default]
    Binary,
    /// Binary, appended raw, not compressed (fastest to write, largest).
    BinaryUncompressed,
    /// Text inside the XML (largest and slowest; readable by eye).
    Ascii,
}

fn one() -> usize {
    1
}

impl Default for Output {
    fn default() -> Self {
        Output {
            every: 1,
            vtk_every: 0,
            vtk_format: VtkFormat::default(),
        }
    }
}

/// One semantic problem found by `validate`, before it is located in the file.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    /// Dotted path into the TOML tree, array indices as numbers: `body.0.elastic.E`.
    pub path: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

/// Collects [`Invalid`]s during validation.
#[derive(Debug, Default)]
pub struct Problems(pub Vec<Invalid>);

impl Problems {
    /// Record `message` at the dotted `path`.
    pub fn push(&mut self, path: impl Into<String>, message: impl Into<String>) {
        self.0.push(Invalid {
            path: path.into(),
            message: message.into(),
        });
    }
    /// Record `message` at `path` unless `ok`.
    pub fn check(&mut self, ok: bool, path: impl Into<String>, message: impl Into<String>) {
        if !ok {
            self.push(path, message);
        }
    }
    /// `value` must be finite and > 0.
    pub fn positive(&mut self, value: f64, path: impl Into<String>) {
        self.check(
            value.is_finite() && value > 0.0,
            path,
            format!("must be a finite number > 0 (got {value})"),
        );
    }
    /// `value` must be finite and ≥ 0.
    pub fn non_negative(&mut self, value: f64, path: impl Into<String>) {
        self.check(
            value.is_finite() && value >= 0.0,
            path,
            format!("must be a finite number ≥ 0 (got {value})"),
        );
    }
}

/// A problem with its place in the file.
#[derive(Debug, Clone)]
pub struct Located {
    /// 1-based line in the file; `None` when the scenario has no source or
    /// the path is not in it (a default value).
    pub line: Option<usize>,
    /// Field path as the user writes it: `body[0].elastic.E`.
    pub field: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

/// Why a scenario could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("{file}: cannot read the scenario: {source}")]
    Io {
        /// The path as given.
        file: String,
        /// The i/o error.
        source: std::io::Error,
    },
    /// TOML syntax or type errors, or semantic problems, with their lines.
    #[error("{}", format_located(file, errors))]
    Invalid {
        /// File name (or `"scenario"` for one built in code).
        file: String,
        /// Every problem found, in order.
        errors: Vec<Located>,
    },
}

fn format_located(file: &str, errors: &[Located]) -> String {
    let mut s = String::new();
    for (i, e) in errors.iter().enumerate() {
        if i > 0 {
            s.push('\n');
        }
        match e.line {
            Some(l) => s.push_str(&format!("{file}:{l}: ")),
            None => s.push_str(&format!("{file}: ")),
        }
        if !e.field.is_empty() {
            s.push_str(&format!("{}: ", e.field));
        }
        s.push_str(&e.message);
    }
    s
}

impl fmt::Display for Located {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

/// Largest scenario file read ([`load`]): 256 MiB.
pub const MAX_SCENARIO_BYTES: u64 = 256 << 20;

/// Largest discs CSV file read (`discs = { csv = … }`): 1 GiB, some 20
/// million discs.
pub const MAX_CSV_BYTES: u64 = 1 << 30;

/// The bytes of the file `path`, refused if it is a directory or a device
/// (`/dev/zero`) or has more than `max` bytes (a pipe that does not end, a
/// file that is not what it is said to be): nothing is read without bound.
pub fn read_bounded(path: &Path, max: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let f = std::fs::File::open(path)?;
    let kind = f.metadata()?.file_type();
    if kind.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::IsADirectory,
            "a directory, not a file",
        ));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_char_device() || kind.is_block_device() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "a device, not a file",
            ));
        }
    }
    let too_large = || {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "larger than {} MiB, more than such a file can be (is it the right file?)",
                max >> 20
            ),
        )
    };
    // a regular file says its size; anything else (a pipe) is read up to it
    if kind.is_file() && f.metadata()?.len() > max {
        return Err(too_large());
    }
    let mut bytes = Vec::new();
    f.take(max + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > max {
        return Err(too_large());
    }
    Ok(bytes)
}

/// The text of the file `path` ([`read_bounded`]), which must be UTF-8.
pub fn read_text(path: &Path, max: u64) -> std::io::Result<String> {
    String::from_utf8(read_bounded(path, max)?).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
        )
    })
}

/// Read, parse and validate a scenario file.
pub fn load(path: &Path) -> Result<Scenario, ScenarioError> {
    let file = path.display().to_string();
    let src = read_text(path, MAX_SCENARIO_BYTES).map_err(|source| ScenarioError::Io {
        file: file.clone(),
        source,
    })?;
    let mut sc = parse(&src, &file)?;
    sc.base_dir = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    Ok(sc)
}

/// Parse and validate scenario text; `file` names it in error messages.
pub fn parse(src: &str, file: &str) -> Result<Scenario, ScenarioError> {
    // strict tables: a struct given as an array is refused, not read
    // field by field in order
    let sc: Result<Scenario, toml::de::Error> =
        toml::Deserializer::parse(src).and_then(crate::strict::deserialize);
    let sc: Scenario = sc.map_err(|e| ScenarioError::Invalid {
        file: file.to_string(),
        errors: vec![Located {
            line: e.span().map(|s| line_of(src, s.start)),
            field: e
                .span()
                .and_then(|s| field_at(src, s.start))
                .map_or_else(String::new, |p| display_path(&p)),
            message: e.message().trim().to_string(),
        }],
    })?;
    let mut sc = sc;
    // a polygon body's rectangle is its outline's bounding box
    for b in &mut sc.body {
        if let Some(o) = &b.outline
            && !o.is_empty()
            && b.rectangle.size == [0.0, 0.0]
        {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in o {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            b.rectangle = body::Rectangle {
                origin: lo,
                size: [hi[0] - lo[0], hi[1] - lo[1]],
            };
        }
    }
    sc.source = Some(std::sync::Arc::new(Source {
        file: file.to_string(),
        text: src.to_string(),
    }));
    let problems = sc.validate();
    if problems.is_empty() {
        return Ok(sc);
    }
    Err(sc.located(problems))
}

impl Scenario {
    /// Build the model: discs, walls, bodies, the coupling, with every
    /// body's operators assembled and factored, ready to
    /// [`step`](crate::model::Model::step). Probes are bound too, so a
    /// probe naming a missing disc, wall, body or point is reported here.
    /// Problems are located in the scenario's file when it has one.
    pub fn build(&self) -> Result<crate::model::Model, ScenarioError> {
        let problems = self.validate();
        if !problems.is_empty() {
            return Err(self.located(problems));
        }
        build::model(self).map_err(|p| self.located(vec![p]))
    }

    /// [`build`](Self::build) without any time stepping, for `efgdem
    /// check` ([`build::BuildFor::Check`]): a `deposit` or `grow` packing is
    /// not prepared (its discs stay where the generator put them;
    /// [`build::preparation`] says what `run` will do), a static analysis
    /// solves its bodies once; everything else is built and checked as for
    /// a run, the memory estimate included.
    pub fn build_unprepared(&self) -> Result<crate::model::Model, ScenarioError> {
        let problems = self.validate();
        if !problems.is_empty() {
            return Err(self.located(problems));
        }
        build::model_with(self, build::BuildFor::Check).map_err(|p| self.located(vec![p]))
    }

    /// [`build`](Self::build) with the discs of its packing's preparation
    /// given: `bed`, from [`prepare::prepare`] (which `build` runs itself).
    pub fn build_prepared(
        &self,
        bed: &[crate::dem::packing::DiscRow],
    ) -> Result<crate::model::Model, ScenarioError> {
        let problems = self.validate();
        if !problems.is_empty() {
            return Err(self.located(problems));
        }
        build::model_with(self, build::BuildFor::Prepared(bed)).map_err(|p| self.located(vec![p]))
    }

    /// A rank's part of the model of a granular scenario (no bodies,
    /// bonds or clumps; `None` otherwise) and the regions of the ranks of
    /// `comm` (collective): only the discs the cut keeps for this rank of
    /// the whole assembly are made ([`build::part`]); `bed` the discs of
    /// its packing's preparation, if it has one.
    pub fn build_part(
        &self,
        bed: Option<&[crate::dem::packing::DiscRow]>,
        comm: &dyn crate::decomp::Comm,
    ) -> Result<Option<(crate::model::Model, crate::decomp::Cut)>, ScenarioError> {
        let problems = self.validate();
        if !problems.is_empty() {
            return Err(self.located(problems));
        }
        let purpose = bed.map_or(build::BuildFor::Run, build::BuildFor::Prepared);
        build::part(self, purpose, comm).map_err(|p| self.located(vec![p]))
    }

    /// What a rank restarting a granular scenario from a checkpoint
    /// builds before it knows its discs ([`PartSkeleton`]: the model
    /// without discs; then the discs it holds, by id); `None` for what
    /// is not a plain granular scenario (bodies, bonds, clumps). `bed` as
    /// for [`build_part`](Self::build_part).
    pub fn part_skeleton<'a>(
        &'a self,
        bed: Option<&'a [crate::dem::packing::DiscRow]>,
    ) -> Result<Option<PartSkeleton<'a>>, ScenarioError> {
        let problems = self.validate();
        if !problems.is_empty() {
            return Err(self.located(problems));
        }
        let purpose = bed.map_or(build::BuildFor::Run, build::BuildFor::Prepared);
        build::part_skeleton(self, purpose).map_err(|p| self.located(vec![p]))
    }

    /// The `[[probe]]`s bound to their targets in `model` (built from this
    /// scenario), in file order.
    pub fn probes(
        &self,
        model: &crate::model::Model,
    ) -> Result<Vec<(String, crate::model::Probe)>, ScenarioError> {
        build::probes(self, model).map_err(|p| self.located(vec![p]))
    }

    /// `problems` as a [`ScenarioError`] with the lines of the source file
    /// (if the scenario has one).
    pub fn located(&self, problems: Vec<Invalid>) -> ScenarioError {
        let src = self.source.as_deref();
        let doc = src.and_then(|s| toml_edit::Document::parse(s.text.clone()).ok());
        let errors = problems
            .into_iter()
            .map(|p| Located {
                line: doc
                    .as_ref()
                    .zip(src)
                    .and_then(|(d, s)| locate(d, &p.path).map(|off| line_of(&s.text, off))),
                field: display_path(&p.path),
                message: p.message,
            })
            .collect();
        ScenarioError::Invalid {
            file: src.map_or_else(|| "scenario".to_string(), |s| s.file.clone()),
            errors,
        }
    }

    /// All semantic problems of the scenario (empty = valid).
    pub fn validate(&self) -> Vec<Invalid> {
        let mut p = Problems::default();
        let sim = &self.simulation;
        if let Some(dt) = sim.dt {
            p.positive(dt, "simulation.dt");
        }
        if let Some(t) = sim.end_time {
            p.positive(t, "simulation.end_time");
        }
        if sim.steps.is_some() && sim.end_time.is_some() {
            p.push(
                "simulation.end_time",
                "give either `steps` or `end_time`, not both",
            );
        }
        p.check(
            sim.gravity.iter().all(|g| g.is_finite()),
            "simulation.gravity",
            "must be two finite numbers [gx, gy]",
        );
        p.check(self.output.every >= 1, "output.every", "must be ≥ 1");
        if let Some(n) = sim.substeps.fixed() {
            p.check(
                (1..=100_000).contains(&n),
                "simulation.substeps",
                format!("must be \"auto\" or between 1 and 100000 (got {n})"),
            );
        }
        p.check(
            (1..=1000).contains(&sim.contact_iterations),
            "simulation.contact_iterations",
            format!(
                "must be between 1 and 1000 (got {})",
                sim.contact_iterations
            ),
        );
        let mut names = std::collections::HashSet::new();
        for (i, m) in self.material.iter().enumerate() {
            let at = |f: &str| format!("material.{i}.{f}");
            p.check(
                names.insert(m.name.as_str()),
                at("name"),
                format!("material `{}` is defined twice", m.name),
            );
            p.non_negative(m.density, at("density"));
            p.non_negative(m.kn, at("kn"));
            p.non_negative(m.ks, at("ks"));
            p.non_negative(m.friction, at("friction"));
            p.non_negative(m.cohesion, at("cohesion"));
            granular::validate_contact_fields(m, &at, &mut p);
        }
        let dynamic = sim.analysis == Analysis::Dynamic || self.granular.is_some();
        p.check(
            !dynamic || sim.steps.is_some() || sim.end_time.is_some(),
            "simulation",
            "give `steps` or `end_time`: how long to run",
        );
        let mut probe_names = std::collections::HashSet::new();
        for (i, pr) in self.probe.iter().enumerate() {
            p.check(
                probe_names.insert(pr.name.as_str()),
                format!("probe.{i}.name"),
                format!(
                    "probe `{}` is defined twice (one history column each)",
                    pr.name
                ),
            );
        }
        p.check(
            !self.body.is_empty() || self.granular.is_some(),
            "",
            "the scenario has neither a [[body]] nor a [granular] section: nothing to run",
        );
        body::validate(self, &mut p);
        granular::validate(self, &mut p);
        bonds::validate(self, &mut p);
        clumps::validate(self, &mut p);
        measure::validate(self, &mut p);
        p.0
    }

    /// The material named `name`.
    pub fn material(&self, name: &str) -> Option<&Material> {
        self.material.iter().find(|m| m.name == name)
    }

    /// Resolve a path given in the scenario relative to its directory.
    pub fn resolve(&self, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.base_dir.join(p)
        }
    }
}

/// 1-based line number of byte offset `off`.
pub fn line_of(src: &str, off: usize) -> usize {
    src.as_bytes()[..off.min(src.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// `body.0.elastic.E` → `body[0].elastic.E`.
pub fn display_path(path: &str) -> String {
    let mut s = String::new();
    for seg in path.split('.').filter(|s| !s.is_empty()) {
        if seg.chars().all(|c| c.is_ascii_digit()) {
            s.push_str(&format!("[{seg}]"));
        } else {
            if !s.is_empty() {
                s.push('.');
            }
            s.push_str(seg);
        }
    }
    s
}

/// The dotted path (`body.0.rectangle`) of the innermost value of the TOML
/// text `src` that holds byte offset `off`, if a value does (the field a
/// type error is about).
fn field_at(src: &str, off: usize) -> Option<String> {
    use toml_edit::{Item, TableLike, Value};
    fn value(v: &Value, path: String, off: usize) -> Option<String> {
        let span = v.span()?;
        if !span.contains(&off) {
            return None;
        }
        let inner = match v {
            Value::Array(a) => a
                .iter()
                .enumerate()
                .find_map(|(i, x)| value(x, format!("{path}.{i}"), off)),
            Value::InlineTable(t) => table(t, &path, off),
            _ => None,
        };
        inner.or(Some(path))
    }
    fn table(t: &dyn TableLike, prefix: &str, off: usize) -> Option<String> {
        t.iter().find_map(|(k, item)| {
            let path = if prefix.is_empty() {
                k.to_string()
            } else {
                format!("{prefix}.{k}")
            };
            match item {
                Item::Value(v) => value(v, path, off),
                Item::Table(t) => table(t, &path, off),
                Item::ArrayOfTables(a) => a
                    .iter()
                    .enumerate()
                    .find_map(|(i, t)| table(t, &format!("{path}.{i}"), off)),
                Item::None => None,
            }
        })
    }
    let doc = toml_edit::Document::parse(src.to_string()).ok()?;
    table(doc.as_table(), "", off)
}

/// Byte offset of the deepest part of `path` present in the document: the
/// key of the field if it is there, else the nearest enclosing entry.
fn locate(doc: &toml_edit::Document<String>, path: &str) -> Option<usize> {
    use toml_edit::{Item, TableLike, Value};
    enum Node<'a> {
        Table(&'a dyn TableLike),
        Item(&'a Item),
        Value(&'a Value),
    }
    let mut node = Node::Table(doc.as_table());
    let mut best = None;
    for seg in path.split('.').filter(|s| !s.is_empty()) {
        let next = if let Ok(i) = seg.parse::<usize>() {
            match node {
                Node::Item(Item::ArrayOfTables(a)) => a.get(i).map(|t| {
                    let first = t.iter().next().and_then(|(k, _)| t.key(k)?.span());
                    (first.map(|s| s.start), Node::Table(t as &dyn TableLike))
                }),
                Node::Item(Item::Value(Value::Array(a))) | Node::Value(Value::Array(a)) => a
                    .get(i)
                    .map(|v| (v.span().map(|s| s.start), Node::Value(v))),
                _ => None,
            }
        } else {
            let table: Option<&dyn TableLike> = match node {
                Node::Table(t) => Some(t),
                Node::Item(it) => it.as_table_like(),
                Node::Value(v) => v.as_inline_table().map(|t| t as &dyn TableLike),
            };
            table
                .and_then(|t| t.get_key_value(seg))
                .map(|(k, v)| (k.span().map(|s| s.start), Node::Item(v)))
        };
        match next {
            Some((off, n)) => {
                best = off.or(best);
                node = n;
            }
            None => break,
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_path_brackets_indices() {
        assert_eq!(display_path("body.0.elastic.E"), "body[0].elastic.E");
        assert_eq!(display_path("simulation.dt"), "simulation.dt");
    }

    #[test]
    fn locate_finds_nested_keys_in_arrays_of_tables() {
        let src = "[simulation]\ndt = 1.0\n\n[[body]]\nname = \"a\"\n[[body]]\nname = \"b\"\nelastic = { E = -1.0, nu = 0.3 }\n";
        let doc = toml_edit::Document::parse(src.to_string()).unwrap();
        let line = |p: &str| locate(&doc, p).map(|o| line_of(src, o));
        assert_eq!(line("simulation.dt"), Some(2));
        assert_eq!(line("body.1.elastic.E"), Some(8));
        assert_eq!(line("body.1.name"), Some(7));
        // missing field: falls back to the nearest enclosing entry
        assert_eq!(line("body.1.nodes"), Some(7));
    }

    #[test]
    fn a_type_error_names_its_field() {
        let src = "[[body]]\nname = \"a\"\nrectangle = [[0.1, 0.1], [0.3, 0.2]]\nelastic = { E = \"x\" }\n";
        let off = |s: &str| src.find(s).unwrap();
        assert_eq!(
            field_at(src, off("[[0.1")).as_deref(),
            Some("body.0.rectangle")
        );
        assert_eq!(
            field_at(src, off("0.3")).as_deref(),
            Some("body.0.rectangle.1.0")
        );
        assert_eq!(
            field_at(src, off("\"x\"")).as_deref(),
            Some("body.0.elastic.E")
        );
        assert_eq!(field_at(src, 0), None);
    }

    #[test]
    fn line_of_counts_newlines() {
        assert_eq!(line_of("a\nb\nc", 0), 1);
        assert_eq!(line_of("a\nb\nc", 2), 2);
        assert_eq!(line_of("a\nb\nc", 4), 3);
    }
}
