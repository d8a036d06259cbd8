//! Python bindings of efgdem: the module `efgdem` (built by maturin from
//! `python/pyproject.toml`).
//!
//! One class, `PyModel` (`efgdem.Model`), wraps [`efgdem::model::Model`]
//! with the scenario's bound probes, a thread pool of its own (stepping runs
//! inside it, as `efgdem run` does) and what frames and nodal sampling need
//! (cached on first use). Errors become `efgdem.ScenarioError` (a
//! `ValueError`, with the scenario's `file:line: field: message`) and
//! `efgdem.ModelError` (a `RuntimeError`).
//!
//! State comes out in two forms (see the module docstring below):
//! id-ordered copies (`disc_positions()` …) and zero-copy read-only live
//! views in slot order (`disc_views()`). The views borrow the disc arrays of
//! the Rust model, with the Python `Model` object as their numpy base. That
//! is sound because those arrays are allocated once, when the assembly is
//! built, and never reallocated (`Particles::permute`
//! reorders them in place); `Inner::check_buffers` asserts it after every
//! step.

use efgdem::dem::Granular;
use efgdem::geom::Vec2;
use efgdem::model::body::{At, BodyRef};
use efgdem::model::{ContactKind, Model, Probe, System};
use efgdem::output::frames::Frames;
use efgdem::output::vtk::VtkFormat;
use efgdem::scenario::{self, Scenario};
use numpy::ndarray::{Array1, Array2, ArrayView1, ArrayView2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyIOError, PyIndexError, PyKeyError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard, TryLockError};
use std::time::{Duration, Instant};

pyo3::create_exception!(
    efgdem,
    ScenarioError,
    PyValueError,
    "The scenario is invalid or cannot be built. The message has one line per problem, `file:line: field: message` (`<dict>: field: message` for Model.from_dict); the attributes `file` and `errors` (a list of (line or None, field, message)) give the parts."
);
pyo3::create_exception!(
    efgdem,
    ModelError,
    PyRuntimeError,
    "A step failed (an unstable granular assembly, a singular body solve, a static model stepped, …), or the model is busy in another thread."
);

/// File name that `from_dict` scenarios carry in messages.
const DICT_FILE: &str = "<dict>";

/// The structured dtype of `Model.contacts()` (packed, 81 bytes a
/// record). `disc` and `other` are the numbers the files use (from 1);
/// `disc_index` and `other_index` the rows of the id-ordered arrays and of
/// `body_names()` (from 0).
const CONTACT_FIELDS: [(&str, &str); 13] = [
    ("kind", "u1"),
    ("disc", "<u4"),
    ("other", "<u4"),
    ("disc_index", "<u4"),
    ("other_index", "<u4"),
    ("x", "<f8"),
    ("y", "<f8"),
    ("nx", "<f8"),
    ("ny", "<f8"),
    ("overlap", "<f8"),
    ("fn_elastic", "<f8"),
    ("fn_total", "<f8"),
    ("fs", "<f8"),
];

/// One record of the contacts array, laid out as [`CONTACT_FIELDS`].
#[repr(C, packed)]
#[derive(Clone, Copy)]
struct ContactRecord {
    kind: u8,
    /// `disc_id`, `other_id` (from 1), `disc_index`, `other_index` (from 0).
    ids: [u32; 4],
    f: [f64; 8],
}

/// `e` as a Python `ScenarioError`. `dict`: the TOML text made from a
/// dict (its lines mean nothing to the user: they are dropped, and a
/// problem found by the TOML parser, which names no field, gets the field
/// its line holds).
fn scenario_error(py: Python<'_>, e: scenario::ScenarioError, dict: Option<&str>) -> PyErr {
    let (file, errors) = match e {
        scenario::ScenarioError::Invalid { file, mut errors } => {
            if let Some(text) = dict {
                for l in &mut errors {
                    if l.field.is_empty()
                        && let Some(f) = l.line.and_then(|n| field_at_line(text, n))
                    {
                        l.field = f;
                    }
                    l.line = None;
                }
            }
            (file, errors)
        }
        e @ scenario::ScenarioError::Io { .. } => {
            let err = ScenarioError::new_err(e.to_string());
            return err;
        }
    };
    let e = scenario::ScenarioError::Invalid {
        file: file.clone(),
        errors: errors.clone(),
    };
    let err = ScenarioError::new_err(e.to_string());
    let value = err.value(py);
    let list: Vec<(Option<usize>, String, String)> = errors
        .into_iter()
        .map(|l| (l.line, l.field, l.message))
        .collect();
    let _ = value.setattr("file", file);
    let _ = value.setattr("errors", list);
    err
}

/// The field (`material[0].kn`, `wall[1]`) that line `line` (1-based) of
/// TOML text written by `toml::to_string` holds: the key of a `key = value`
/// line under its table header, or the header itself.
fn field_at_line(text: &str, line: usize) -> Option<String> {
    // current index of each array of tables, by its plain dotted path
    let mut index: HashMap<String, usize> = HashMap::new();
    // entries of each array of tables, by its path with parents' indices
    let mut count: HashMap<String, usize> = HashMap::new();
    let render = |plain: &str, index: &HashMap<String, usize>| {
        let mut out = String::new();
        let mut so_far = String::new();
        for part in plain.split('.') {
            let part = part.trim().trim_matches('"');
            if !so_far.is_empty() {
                so_far.push('.');
                out.push('.');
            }
            so_far.push_str(part);
            out.push_str(part);
            if let Some(i) = index.get(&so_far) {
                out.push_str(&format!("[{i}]"));
            }
        }
        out
    };
    let mut header = String::new();
    for (k, l) in text.lines().enumerate() {
        let t = l.trim();
        if let Some(name) = t.strip_prefix("[[").and_then(|r| r.strip_suffix("]]")) {
            let name = name.trim();
            let mut parent = index.clone();
            parent.remove(name);
            let key = render(name, &parent);
            let c = count.entry(key).or_insert(0);
            index.insert(name.to_string(), *c);
            *c += 1;
            header = render(name, &index);
        } else if let Some(name) = t.strip_prefix('[').and_then(|r| r.strip_suffix(']')) {
            header = render(name.trim(), &index);
        } else if k + 1 == line
            && let Some((key, _)) = t.split_once('=')
        {
            let key = key.trim().trim_matches('"');
            return Some(if header.is_empty() {
                key.to_string()
            } else {
                format!("{header}.{key}")
            });
        }
        if k + 1 == line {
            return (!header.is_empty()).then_some(header);
        }
    }
    None
}

fn model_error(e: impl std::fmt::Display) -> PyErr {
    ModelError::new_err(e.to_string())
}

/// Deepest nesting of dicts and lists accepted by `Model.from_dict` (the
/// scenario schema needs 5).
const MAX_DEPTH: usize = 32;

/// A `ScenarioError` about the value at `path` of a dict.
fn dict_error(path: &str, what: &str) -> PyErr {
    let at = if path.is_empty() {
        String::new()
    } else {
        format!("{path}: ")
    };
    ScenarioError::new_err(format!("{DICT_FILE}: {at}{what}"))
}

/// `obj` (a dict of the scenario schema) as a TOML value; `path` names
/// where it is, for messages. A dict or list that contains itself, or
/// nesting deeper than [`MAX_DEPTH`], is refused (rather than recursing
/// until the stack overflows).
fn to_toml(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    to_toml_in(obj, path, &mut Vec::new())
}

/// [`to_toml`] inside the containers `open` (their addresses, outermost
/// first).
fn to_toml_in(obj: &Bound<'_, PyAny>, path: &str, open: &mut Vec<usize>) -> PyResult<toml::Value> {
    use toml::Value;
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Boolean(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        return obj
            .extract::<i64>()
            .map(Value::Integer)
            .map_err(|_| dict_error(path, "an integer out of the 64-bit range"));
    }
    if let Ok(f) = obj.cast::<PyFloat>() {
        return Ok(Value::Float(f.value()));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.to_str()?.to_owned()));
    }
    let container = obj.is_instance_of::<PyDict>()
        || obj.is_instance_of::<PyList>()
        || obj.is_instance_of::<PyTuple>();
    if container {
        let at = obj.as_ptr() as usize;
        if open.contains(&at) {
            return Err(dict_error(
                path,
                "contains itself (a dict or list inside its own value): a scenario is a tree",
            ));
        }
        if open.len() >= MAX_DEPTH {
            return Err(dict_error(
                path,
                &format!("nested more than {MAX_DEPTH} levels deep; a scenario needs a few"),
            ));
        }
        open.push(at);
        let v = container_to_toml(obj, path, open);
        open.pop();
        return v;
    }
    // numpy arrays and scalars (and anything else with a `tolist`)
    if obj.hasattr("tolist")? {
        let l = obj.call_method0("tolist")?;
        if !l.is(obj) {
            return to_toml_in(&l, path, open);
        }
    }
    Err(dict_error(
        path,
        &format!(
            "a value of type `{}` has no TOML form (use dicts, lists, str, int, float, bool)",
            obj.get_type().name()?
        ),
    ))
}

/// A dict as a TOML table, a list or tuple as an array ([`to_toml_in`]).
fn container_to_toml(
    obj: &Bound<'_, PyAny>,
    path: &str,
    open: &mut Vec<usize>,
) -> PyResult<toml::Value> {
    use toml::Value;
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, v) in d.iter() {
            let Ok(k) = k.extract::<String>() else {
                return Err(dict_error(
                    path,
                    &format!("keys must be strings (got {})", k.repr()?),
                ));
            };
            if v.is_none() {
                continue; // TOML has no null: an absent key takes the default
            }
            let sub = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            t.insert(k, to_toml_in(&v, &sub, open)?);
        }
        return Ok(Value::Table(t));
    }
    let mut a = Vec::new();
    for (i, v) in obj.try_iter()?.enumerate() {
        a.push(to_toml_in(&v?, &format!("{path}[{i}]"), open)?);
    }
    Ok(Value::Array(a))
}

/// What the model needs besides the Rust model: probes, a pool, caches.
struct Inner {
    model: Model,
    /// The worker threads (started by the process `pool_pid`: a process
    /// forked from it has none of them and starts its own).
    pool: Arc<rayon::ThreadPool>,
    threads: usize,
    pool_pid: u32,
    probes: Vec<(String, Probe)>,
    /// Per body: its nodes bound for sampling (on first use), and the
    /// body's generation they were bound in (a body rebuilt by crack
    /// growth has other nodes).
    node_at: Vec<Option<(usize, Vec<At>)>>,
    /// The ParaView frames written per output directory (named as
    /// `efgdem run` names them).
    frames: HashMap<PathBuf, Frames>,
    /// How the frames store their arrays (the scenario's
    /// `output.vtk_format`).
    vtk_format: VtkFormat,
    /// Disc buffers as built (address, length): views borrow them.
    buffers: Vec<(usize, usize)>,
}

fn granular_buffers(g: Option<&Granular>) -> Vec<(usize, usize)> {
    g.map_or_else(Vec::new, |g| {
        let p = &g.particles;
        vec![
            (p.pos.as_ptr() as usize, p.pos.len()),
            (p.vel.as_ptr() as usize, p.vel.len()),
            (p.omega.as_ptr() as usize, p.omega.len()),
            (p.radius.as_ptr() as usize, p.radius.len()),
            (p.force.as_ptr() as usize, p.force.len()),
            (p.id.as_ptr() as usize, p.id.len()),
            (p.theta.as_ptr() as usize, p.theta.len()),
        ]
    })
}

impl Inner {
    fn new(
        model: Model,
        probes: Vec<(String, Probe)>,
        pool: rayon::ThreadPool,
        vtk_format: VtkFormat,
    ) -> Inner {
        let nb = model.n_bodies();
        let buffers = granular_buffers(model.granular());
        Inner {
            model,
            threads: pool.current_num_threads(),
            pool: Arc::new(pool),
            pool_pid: std::process::id(),
            probes,
            node_at: (0..nb).map(|_| None).collect(),
            frames: HashMap::new(),
            vtk_format,
            buffers,
        }
    }

    /// The views handed out borrow the disc arrays: they must never move.
    fn check_buffers(&self) {
        assert!(
            granular_buffers(self.model.granular()) == self.buffers,
            "efgdem: a disc array was reallocated while numpy views may borrow it"
        );
    }

    /// The model's pool, started again in a process forked from the one
    /// that started it (its threads do not survive `fork`: using them
    /// would wait for ever).
    fn ensure_pool(&mut self) -> PyResult<()> {
        if self.pool_pid != std::process::id() {
            let pool = Arc::new(thread_pool(self.threads)?);
            // the old pool's threads are gone: dropping it could wait on
            // them; it is left as it is
            std::mem::forget(std::mem::replace(&mut self.pool, pool));
            self.pool_pid = std::process::id();
        }
        Ok(())
    }

    /// Up to `n` steps inside the model's pool, for at most about
    /// [`SLICE`] (then the caller checks for Ctrl-C); the number taken.
    /// Granular runs store the disc forces of the step that ends the call's
    /// `left` steps only (as `efgdem run` stores them only at frame steps;
    /// they are never read by the physics).
    fn steps_for(&mut self, n: usize, left: usize) -> Result<usize, efgdem::model::ModelError> {
        let Inner { model, pool, .. } = self;
        let t0 = Instant::now();
        // the bodies are read only after the call: their ends may wait for
        // the next step (`Model::step_deferring`), settled before returning
        let done = pool.install(|| {
            let mut k = 0;
            let r = (|| {
                while k < n && (k == 0 || t0.elapsed() < SLICE) {
                    set_store_forces(model, k + 1 == left);
                    model.step_deferring()?;
                    k += 1;
                }
                Ok(())
            })();
            r.and(model.settle()).map(|()| k)
        })?;
        self.check_buffers();
        Ok(done)
    }

    /// Steps until `t` (within half a step, as `Model::run_until`) for at
    /// most about [`SLICE`]; the number taken.
    fn run_for(&mut self, t: f64) -> Result<usize, efgdem::model::ModelError> {
        let Inner { model, pool, .. } = self;
        let t0 = Instant::now();
        let n = pool.install(|| {
            let mut n = 0;
            let r = (|| {
                while model.time() + 0.5 * model.dt < t && (n == 0 || t0.elapsed() < SLICE) {
                    // the last steps store the disc forces (2.5 dt: rounding of t)
                    set_store_forces(model, model.time() + 2.5 * model.dt >= t);
                    model.step_deferring()?;
                    n += 1;
                }
                Ok(())
            })();
            set_store_forces(model, true);
            r.and(model.settle()).map(|()| n)
        })?;
        self.check_buffers();
        Ok(n)
    }

    fn body_index(&self, body: &Bound<'_, PyAny>) -> PyResult<usize> {
        let n = self.model.n_bodies();
        if let Ok(i) = body.extract::<isize>() {
            let k = if i < 0 { i + n as isize } else { i };
            if k < 0 || k as usize >= n {
                return Err(PyIndexError::new_err(format!(
                    "body index {i} out of range: the model has {n} bodies"
                )));
            }
            return Ok(k as usize);
        }
        let name: String = body.extract()?;
        (0..n)
            .find(|&i| self.model.body(i).name() == name)
            .ok_or_else(|| {
                PyKeyError::new_err(format!(
                    "no body named `{name}` (bodies: {:?})",
                    self.body_names()
                ))
            })
    }

    fn body_names(&self) -> Vec<String> {
        (0..self.model.n_bodies())
            .map(|i| self.model.body(i).name().to_string())
            .collect()
    }

    /// Nodes of body `i` bound for sampling (cached).
    fn nodes_bound(&mut self, i: usize) -> PyResult<&[At]> {
        let generation = self.model.body(i).generation();
        if self.node_at[i]
            .as_ref()
            .is_none_or(|(g, _)| *g != generation)
        {
            let b = self.model.body(i);
            let at = (0..b.n_nodes())
                .map(|k| b.bind(node(b, k)))
                .collect::<Result<Vec<_>, _>>()
                .map_err(model_error)?;
            self.node_at[i] = Some((generation, at));
        }
        Ok(&self.node_at[i].as_ref().expect("bound above").1)
    }
}

fn set_store_forces(model: &mut Model, store: bool) {
    if let System::Granular(g) = &mut model.system {
        g.store_forces = store;
    }
}

/// Reference position of node `k` of a body.
fn node(b: BodyRef<'_>, k: usize) -> Vec2 {
    match b {
        BodyRef::Efg(b) => b.node(k),
        BodyRef::Fem(b) => b.node(k),
    }
}

fn vec2_array<'py>(
    py: Python<'py>,
    v: impl ExactSizeIterator<Item = Vec2>,
) -> Bound<'py, PyArray2<f64>> {
    let n = v.len();
    let flat: Vec<f64> = v.flat_map(|p| [p.x, p.y]).collect();
    Array2::from_shape_vec((n, 2), flat)
        .expect("n × 2 values")
        .into_pyarray(py)
}

/// Make a numpy array read-only.
fn read_only<'py, T>(a: Bound<'py, T>) -> PyResult<Bound<'py, T>> {
    let kw = PyDict::new(a.py());
    kw.set_item("write", false)?;
    a.as_any().call_method("setflags", (), Some(&kw))?;
    Ok(a)
}

/// A model built from a scenario: discs, walls, continuum bodies, or both
/// coupled. Build one with `Model.from_scenario(path)` or
/// `Model.from_dict(d)`; advance it with `step(n)` / `run(until)`; read the
/// state with the `disc_*`, `contacts`, `body_*`, `sample` and `probe`
/// methods; write ParaView frames with `write_frame(dir)`.
///
/// Disc state comes in two forms:
///
/// * `disc_positions()`, `disc_velocities()`, `disc_radii()`,
///   `disc_spins()`, `disc_forces()`: **copies in id order** — row `i`
///   (an *index*, from 0) is disc number `i + 1` (its *id*: the number the
///   scenario's probes, `history.csv`, `discs_final.csv` and the frames'
///   `GlobalIds` use). A copy is a snapshot: it stays as it is when the
///   model steps, so `p1 - p0` is a displacement.
/// * `disc_views()`: **zero-copy, read-only views** of the Rust arrays, in
///   *slot* order (the DEM renumbers its slots in space-filling order from
///   time to time; `views["index"][k]` is the index of the disc in slot
///   `k`, `disc_ids()[k]` its id).
///   They are **live**: they show the state after the latest step, including
///   the renumbering, and keep the model alive. Do not read them from another
///   thread while `step()` runs (it releases the GIL).
///
/// `disc_forces()` is the resultant force of the last step (contacts and
/// external forces; gravity not included).
#[pyclass(name = "Model", module = "efgdem")]
struct PyModel {
    inner: Mutex<Inner>,
}

/// Longest time a call steps with the GIL released before it checks for
/// signals (Ctrl-C raises `KeyboardInterrupt` between two steps).
const SLICE: Duration = Duration::from_millis(50);

/// The model's warnings since they were last taken, as `RuntimeWarning`s
/// (e.g. an automatically chosen sub-cycled scheme given up for the exact
/// step).
fn warn_notices(py: Python<'_>, model: &mut Model) -> PyResult<()> {
    for note in model.take_notices() {
        let warning = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
        PyErr::warn(py, &warning, &std::ffi::CString::new(note)?, 1)?;
    }
    Ok(())
}

/// A pool of `n` worker threads (0: one per core; never more than the
/// machine runs at once, with a `RuntimeWarning` when fewer than asked).
fn thread_pool(n: usize) -> PyResult<rayon::ThreadPool> {
    let (n, note) = efgdem::run::worker_threads(n);
    if let Some(note) = note {
        Python::attach(|py| {
            let warning = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
            PyErr::warn(py, &warning, &std::ffi::CString::new(note)?, 1)
        })?;
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(model_error)
}

fn build(py: Python<'_>, sc: Scenario, threads: Option<usize>, dict: bool) -> PyResult<PyModel> {
    let pool = thread_pool(threads.unwrap_or(sc.simulation.threads))?;
    let built = py.detach(|| {
        pool.install(|| {
            let model = sc.build()?;
            let probes = sc.probes(&model)?;
            Ok::<_, scenario::ScenarioError>((model, probes))
        })
    });
    let text = dict
        .then(|| sc.source.as_ref().map(|s| s.text.as_str()))
        .flatten();
    let (model, probes) = built.map_err(|e| scenario_error(py, e, text))?;
    Ok(PyModel {
        inner: Mutex::new(Inner::new(model, probes, pool, sc.output.vtk_format)),
    })
}

impl PyModel {
    /// The state, unless another thread is stepping the model.
    fn lock(&self) -> PyResult<MutexGuard<'_, Inner>> {
        match self.inner.try_lock() {
            Ok(g) => Ok(g),
            Err(TryLockError::WouldBlock) => Err(ModelError::new_err(
                "the model is busy: another thread is stepping it",
            )),
            Err(TryLockError::Poisoned(_)) => Err(ModelError::new_err(
                "the model is unusable: a step panicked",
            )),
        }
    }
}

/// Disc arrays in id order: `f(slot)` for each id.
fn by_id<T>(g: Option<&Granular>, f: impl Fn(&Granular, usize) -> T) -> Vec<T> {
    g.map_or_else(Vec::new, |g| {
        g.particles.slot.iter().map(|&s| f(g, s as usize)).collect()
    })
}

#[pymethods]
impl PyModel {
    /// Build the model a scenario file describes. `threads`: worker threads
    /// (default: the scenario's `simulation.threads`; 0 = one per core;
    /// results do not depend on it). Raises `ScenarioError`
    /// (`file:line: field: message`).
    #[staticmethod]
    #[pyo3(signature = (path, threads = None))]
    fn from_scenario(py: Python<'_>, path: PathBuf, threads: Option<usize>) -> PyResult<Self> {
        let sc = scenario::load(&path).map_err(|e| scenario_error(py, e, None))?;
        build(py, sc, threads, false)
    }

    /// Build a model from a dict of the scenario schema (the same tables
    /// and fields as the TOML file, e.g. `{"simulation": {...},
    /// "material": [{...}], "granular": {...}, "wall": [...]}`; `None`
    /// values are left out). Relative paths in it resolve against
    /// `base_dir` (default: the working directory). Raises `ScenarioError`
    /// (`<dict>: field: message`), also for a dict or list that contains
    /// itself or is nested more than 32 levels deep. `threads` above the
    /// machine's count are lowered to it (a `RuntimeWarning`).
    #[staticmethod]
    #[pyo3(signature = (scenario, base_dir = None, threads = None))]
    fn from_dict(
        py: Python<'_>,
        scenario: &Bound<'_, PyDict>,
        base_dir: Option<PathBuf>,
        threads: Option<usize>,
    ) -> PyResult<Self> {
        let text = toml_text(scenario)?;
        let mut sc =
            scenario::parse(&text, DICT_FILE).map_err(|e| scenario_error(py, e, Some(&text)))?;
        sc.base_dir = base_dir.unwrap_or_else(|| PathBuf::from("."));
        build(py, sc, threads, true)
    }

    /// Advance `n` time steps (the GIL is released while stepping).
    /// Raises `ModelError` if a step fails; Ctrl-C raises
    /// `KeyboardInterrupt` within a fraction of a second, the model left
    /// after a whole step.
    #[pyo3(signature = (n = 1))]
    fn step(&self, py: Python<'_>, n: usize) -> PyResult<()> {
        let mut g = self.lock()?;
        let inner: &mut Inner = &mut g;
        inner.ensure_pool()?;
        let mut left = n;
        while left > 0 {
            let done = py.detach(|| inner.steps_for(left, left));
            warn_notices(py, &mut inner.model)?;
            left -= done.map_err(model_error)?;
            py.check_signals()?;
        }
        Ok(())
    }

    /// Step until the time reaches `until` (within half a step); returns the
    /// number of steps taken (the GIL is released while stepping). `until`
    /// must be finite (`ValueError`); Ctrl-C raises `KeyboardInterrupt`
    /// within a fraction of a second, the model left after a whole step.
    fn run(&self, py: Python<'_>, until: f64) -> PyResult<usize> {
        if !until.is_finite() {
            return Err(PyValueError::new_err(format!(
                "run(until={until}): the end time must be a finite number"
            )));
        }
        let mut g = self.lock()?;
        let inner: &mut Inner = &mut g;
        inner.ensure_pool()?;
        let mut n = 0;
        loop {
            let k = py.detach(|| inner.run_for(until));
            warn_notices(py, &mut inner.model)?;
            let k = k.map_err(model_error)?;
            if k == 0 {
                return Ok(n);
            }
            n += k;
            py.check_signals()?;
        }
    }

    /// The model's whole evolving state as bytes (discs, walls, contact
    /// histories, bodies' U, U̇, Ü, coupling state; see
    /// `efgdem::model::state`): restoring it into a model built from the
    /// same scenario continues bitwise as if never stopped.
    fn save_state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = self.lock()?.model.save_state().to_bytes();
        Ok(PyBytes::new(py, &bytes))
    }

    /// Restore bytes of `save_state` (of a model built from the same
    /// scenario). Raises `ModelError` if they do not fit this model or are
    /// damaged (the bytes carry a checksum: any altered bit is refused);
    /// the model is then left as it was. Live numpy views stay valid.
    fn restore_state(&self, state: &[u8]) -> PyResult<()> {
        let mut g = self.lock()?;
        let s = efgdem::model::ModelState::from_bytes(state).map_err(model_error)?;
        g.model.restore_state(&s).map_err(model_error)?;
        g.check_buffers();
        Ok(())
    }

    /// Solve a static continuum model (`analysis = "static"`). Raises
    /// `ModelError` for a model with discs (it has no static solve).
    fn solve_static(&self, py: Python<'_>) -> PyResult<()> {
        let mut g = self.lock()?;
        let inner: &mut Inner = &mut g;
        inner.ensure_pool()?;
        py.detach(|| {
            let Inner { model, pool, .. } = inner;
            pool.install(|| model.solve_static())
        })
        .map_err(model_error)
    }

    /// Present time.
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(self.lock()?.model.time())
    }

    /// Steps taken so far.
    #[getter]
    fn step_count(&self) -> PyResult<usize> {
        Ok(self.lock()?.model.step)
    }

    /// The time step (the DEM step in granular and coupled models).
    #[getter]
    fn dt(&self) -> PyResult<f64> {
        Ok(self.lock()?.model.dt)
    }

    /// Steps the scenario asks for (`steps`, or `end_time / dt`).
    #[getter]
    fn steps(&self) -> PyResult<usize> {
        Ok(self.lock()?.model.steps)
    }

    /// End time the scenario asks for: `steps × dt`.
    #[getter]
    fn end_time(&self) -> PyResult<f64> {
        let g = self.lock()?;
        Ok(g.model.steps as f64 * g.model.dt)
    }

    /// `"granular"`, `"continuum"` or `"coupled"`.
    #[getter]
    fn kind(&self) -> PyResult<&'static str> {
        Ok(match self.lock()?.model.system {
            System::Continuum { .. } => "continuum",
            System::Granular(_) => "granular",
            System::Coupled(_) => "coupled",
        })
    }

    /// Number of discs (0 without a granular assembly).
    #[getter]
    fn n_discs(&self) -> PyResult<usize> {
        Ok(self
            .lock()?
            .model
            .granular()
            .map_or(0, |g| g.particles.len()))
    }

    /// Disc centres, shape (n, 2), id order (a copy).
    fn disc_positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let g = self.lock()?;
        let v = by_id(g.model.granular(), |g, s| g.particles.pos[s]);
        Ok(vec2_array(py, v.into_iter()))
    }

    /// Disc velocities (at the half step, Eq. 53), shape (n, 2), id order.
    fn disc_velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let g = self.lock()?;
        let v = by_id(g.model.granular(), |g, s| g.particles.vel[s]);
        Ok(vec2_array(py, v.into_iter()))
    }

    /// Resultant force of the last step on each disc (contacts + external,
    /// gravity not included), shape (n, 2), id order.
    fn disc_forces<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let g = self.lock()?;
        let v = by_id(g.model.granular(), |g, s| g.particles.force[s]);
        Ok(vec2_array(py, v.into_iter()))
    }

    /// Disc radii, shape (n,), id order.
    fn disc_radii<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let g = self.lock()?;
        Ok(by_id(g.model.granular(), |g, s| g.particles.radius[s]).into_pyarray(py))
    }

    /// Disc spins ω (counter-clockwise positive, at the half step), shape
    /// (n,), id order.
    fn disc_spins<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let g = self.lock()?;
        Ok(by_id(g.model.granular(), |g, s| g.particles.omega[s]).into_pyarray(py))
    }

    /// Disc rotations θ, shape (n,), id order.
    fn disc_rotations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let g = self.lock()?;
        Ok(by_id(g.model.granular(), |g, s| g.particles.theta[s]).into_pyarray(py))
    }

    /// The number of the disc in each slot, as the files give it (from 1:
    /// probes' `disc`, `history.csv`, `discs_final.csv`'s `id`, the frames'
    /// `id`/`GlobalIds`), shape (n,), uint32 — the order of `disc_views()`
    /// (a copy). `disc_ids() - 1` is `disc_indices()`.
    fn disc_ids<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<u32>>> {
        let g = self.lock()?;
        let ids = g.model.granular().map_or_else(Vec::new, |g| {
            g.particles.id.iter().map(|&i| i + 1).collect()
        });
        Ok(ids.into_pyarray(py))
    }

    /// The row of the disc in each slot in the id-ordered arrays
    /// (`disc_positions()` …; from 0), shape (n,), uint32 — the order of
    /// `disc_views()` (a copy; the same as `disc_views()["index"]`).
    fn disc_indices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<u32>>> {
        let g = self.lock()?;
        let ids = g
            .model
            .granular()
            .map_or_else(Vec::new, |g| g.particles.id.clone());
        Ok(ids.into_pyarray(py))
    }

    /// Zero-copy, read-only, live views of the disc arrays in slot order:
    /// a dict with `pos` (n, 2), `vel` (n, 2), `force` (n, 2), `radius`,
    /// `omega`, `theta` (n,) float64 and `index` (n,) uint32, the row of
    /// each slot's disc in the id-ordered arrays (from 0; its number in the
    /// files is `index + 1`). They reflect the state after the latest step
    /// (slots are renumbered from time to time: always index them together
    /// with `index`); copy one (`a.copy()`) to keep a snapshot. They keep
    /// the model alive.
    fn disc_views<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyDict>> {
        let py = slf.py();
        let out = PyDict::new(py);
        let this = slf.borrow();
        let g = this.lock()?;
        let Some(gr) = g.model.granular() else {
            return Ok(out);
        };
        let p = &gr.particles;
        let n = p.len();
        let base = slf.clone().into_any();
        // SAFETY: the arrays live inside the model, which `base` (the Python
        // object owning it) keeps alive as long as any view; they are never
        // reallocated after the build (permuted in place; `check_buffers`
        // asserts it after every step), and `Vec2` is `repr(C)`: two f64.
        unsafe {
            let vec2 = |v: &[Vec2]| -> PyResult<Bound<'py, PyAny>> {
                let a = ArrayView2::from_shape_ptr((n, 2), v.as_ptr() as *const f64);
                Ok(read_only(PyArray2::borrow_from_array(&a, base.clone()))?.into_any())
            };
            let f64s = |v: &[f64]| -> PyResult<Bound<'py, PyAny>> {
                let a = ArrayView1::from_shape_ptr(n, v.as_ptr());
                Ok(read_only(PyArray1::borrow_from_array(&a, base.clone()))?.into_any())
            };
            out.set_item("pos", vec2(&p.pos)?)?;
            out.set_item("vel", vec2(&p.vel)?)?;
            out.set_item("force", vec2(&p.force)?)?;
            out.set_item("radius", f64s(&p.radius)?)?;
            out.set_item("omega", f64s(&p.omega)?)?;
            out.set_item("theta", f64s(&p.theta)?)?;
            let a = ArrayView1::from_shape_ptr(n, p.id.as_ptr());
            out.set_item(
                "index",
                read_only(PyArray1::<u32>::borrow_from_array(&a, base.clone()))?,
            )?;
        }
        Ok(out)
    }

    /// The clump of each disc, shape (n,), id order: its number from 1 (the
    /// frames' and `discs_final.csv`'s `clump`), 0 for a disc in no clump.
    fn disc_clumps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let g = self.lock()?;
        let v = by_id(g.model.granular(), |g, s| {
            efgdem::output::csv::clump_number(g.particles.clump[s])
        });
        Ok(v.into_pyarray(py))
    }

    /// The clumps as a dict of numpy arrays (copies), one entry per clump
    /// in clump order (clump k is number k + 1): `x`, `y` (centre of mass),
    /// `vx`, `vy` (velocity at the half step), `theta` (rotation since it
    /// was made), `omega` (spin), `mass`, `inertia` (of the union of its
    /// discs, about the centre), `fx`, `fy`, `torque` (resultant of the
    /// last step, gravity not included), and the members: `first` (u4,
    /// n_clumps + 1 offsets) and `members` (u4, disc numbers from 1; clump
    /// k's are `members[first[k]:first[k + 1]]`), `members_index` (the
    /// same from 0). Empty arrays without clumps.
    fn clumps<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let g = self.lock()?;
        let out = PyDict::new(py);
        let empty = Default::default();
        let c = g.model.granular().map_or(&empty, |gr| &gr.clumps);
        let xy = |v: &[Vec2], y: bool| -> Vec<f64> {
            v.iter().map(|p| if y { p.y } else { p.x }).collect()
        };
        let (pos, vel, force) = (c.by_id(&c.pos), c.by_id(&c.vel), c.by_id(&c.force));
        for (k, v) in [
            ("x", xy(&pos, false)),
            ("y", xy(&pos, true)),
            ("vx", xy(&vel, false)),
            ("vy", xy(&vel, true)),
            ("theta", c.by_id(&c.theta)),
            ("omega", c.by_id(&c.omega)),
            ("mass", c.by_id(&c.mass)),
            ("inertia", c.by_id(&c.inertia)),
            ("fx", xy(&force, false)),
            ("fy", xy(&force, true)),
            ("torque", c.by_id(&c.torque)),
        ] {
            out.set_item(k, v.into_pyarray(py))?;
        }
        let (first, members_index) = c.members_by_id();
        out.set_item("first", first.into_pyarray(py))?;
        let members: Vec<u32> = members_index.iter().map(|k| k + 1).collect();
        out.set_item("members", members.into_pyarray(py))?;
        out.set_item("members_index", members_index.into_pyarray(py))?;
        Ok(out)
    }

    /// The intact parallel bonds as a dict of numpy arrays (copies), one
    /// entry per bond, sorted by `(a, b)`: `a`, `b` (u4, the discs'
    /// numbers, from 1, as in the files; a < b), `a_index`, `b_index` (the
    /// same from 0: rows of the disc arrays),
    /// `radius` (R̄), `fn` (normal force, compression positive), `fs`
    /// (shear force along (−ny, nx), n from a to b), `moment` (on a),
    /// `tensile` and `shear` (the bond's strengths: σ_c, and τ_c or the
    /// cohesion c). Empty arrays without bonds.
    fn bonds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let g = self.lock()?;
        let out = PyDict::new(py);
        let l = g
            .model
            .granular()
            .map(|gr| gr.bonds.list())
            .unwrap_or_default();
        let number = |v: &[u32]| v.iter().map(|k| k + 1).collect::<Vec<u32>>();
        out.set_item("a", number(&l.a).into_pyarray(py))?;
        out.set_item("b", number(&l.b).into_pyarray(py))?;
        out.set_item("a_index", l.a.clone().into_pyarray(py))?;
        out.set_item("b_index", l.b.clone().into_pyarray(py))?;
        for (k, v) in [
            ("radius", &l.radius),
            ("fn", &l.fn_),
            ("fs", &l.fs),
            ("moment", &l.moment),
            ("tensile", &l.tensile),
            ("shear", &l.shear),
        ] {
            out.set_item(k, v.clone().into_pyarray(py))?;
        }
        Ok(out)
    }

    /// Every bond broken so far, in the order they broke, as a dict of
    /// numpy arrays (copies; the rows of `bond_breaks.csv`): `step` (in
    /// which it broke), `t` (at its end), `x`,
    /// `y` (the bond's centre), `nx`, `ny` (unit normal from a to b; the
    /// crack runs across it), `radius`, `a`, `b` (u4, the discs' numbers
    /// from 1, the file's `disc_a`, `disc_b`), `a_index`, `b_index` (the
    /// same from 0), `mode` (u1: 0
    /// tension, 1 shear) and `energy` (released).
    fn bond_breaks<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let g = self.lock()?;
        let out = PyDict::new(py);
        let (broken, dt) = g
            .model
            .granular()
            .map_or((&[][..], 0.0), |gr| (gr.bonds.broken(), gr.dt));
        let col = |f: &dyn Fn(&efgdem::dem::bonds::BrokenBond) -> f64| {
            broken.iter().map(f).collect::<Vec<f64>>()
        };
        let step: Vec<u64> = broken.iter().map(|b| b.step as u64 + 1).collect();
        out.set_item("step", step.into_pyarray(py))?;
        out.set_item("t", col(&|b| b.time + dt).into_pyarray(py))?;
        out.set_item("x", col(&|b| b.pos.x).into_pyarray(py))?;
        out.set_item("y", col(&|b| b.pos.y).into_pyarray(py))?;
        out.set_item("nx", col(&|b| b.normal.x).into_pyarray(py))?;
        out.set_item("ny", col(&|b| b.normal.y).into_pyarray(py))?;
        out.set_item("radius", col(&|b| b.radius).into_pyarray(py))?;
        let ids = |f: fn(&efgdem::dem::bonds::BrokenBond) -> u32| {
            broken.iter().map(f).collect::<Vec<u32>>()
        };
        out.set_item("a", ids(|b| b.a + 1).into_pyarray(py))?;
        out.set_item("b", ids(|b| b.b + 1).into_pyarray(py))?;
        out.set_item("a_index", ids(|b| b.a).into_pyarray(py))?;
        out.set_item("b_index", ids(|b| b.b).into_pyarray(py))?;
        let mode: Vec<u8> = broken
            .iter()
            .map(|b| (b.mode == efgdem::dem::bonds::BreakMode::Shear) as u8)
            .collect();
        out.set_item("mode", mode.into_pyarray(py))?;
        out.set_item("energy", col(&|b| b.energy).into_pyarray(py))?;
        Ok(out)
    }

    /// Every closed contact (disc–disc, disc–wall, then disc–body) as a
    /// numpy structured array with fields `kind` (u1: 0 disc–disc, 1
    /// disc–wall, 2 disc–body), `disc` (u4, the disc's number, from 1, as
    /// in the files), `other` (u4: the number of the other disc, wall or
    /// body, by `kind`, from 1, as in the frames' `other`), `disc_index`,
    /// `other_index` (u4: the same from 0 — rows of the id-ordered disc
    /// arrays, of the walls, of `body_names()`), `x`, `y` (contact point),
    /// `nx`, `ny` (unit normal from the disc to the other side), `overlap`,
    /// `fn_elastic` (k_n δ), `fn_total` (with the dashpot) and `fs` (shear
    /// spring force along (−ny, nx)). A copy.
    fn contacts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let recs: Vec<ContactRecord> = {
            let g = self.lock()?;
            g.model
                .contacts()
                .iter()
                .map(|c| ContactRecord {
                    kind: match c.kind {
                        ContactKind::DiscDisc => 0,
                        ContactKind::DiscWall => 1,
                        ContactKind::DiscBody => 2,
                    },
                    ids: [
                        c.disc as u32 + 1,
                        c.other as u32 + 1,
                        c.disc as u32,
                        c.other as u32,
                    ],
                    f: [
                        c.point.x,
                        c.point.y,
                        c.normal.x,
                        c.normal.y,
                        c.overlap,
                        c.normal_elastic,
                        c.normal_total,
                        c.shear,
                    ],
                })
                .collect()
        };
        let np = py.import("numpy")?;
        let dtype = np.call_method1("dtype", (PyList::new(py, CONTACT_FIELDS)?,))?;
        let arr = np.call_method1("zeros", (recs.len(), &dtype))?;
        let a = arr.cast::<PyUntypedArray>()?;
        let bytes = std::mem::size_of_val(recs.as_slice());
        assert_eq!(
            a.len() * std::mem::size_of::<ContactRecord>(),
            bytes,
            "contact record layout"
        );
        assert_eq!(
            dtype.getattr("itemsize")?.extract::<usize>()?,
            std::mem::size_of::<ContactRecord>()
        );
        if bytes > 0 {
            // SAFETY: a fresh C-contiguous array of `recs.len()` records of
            // the same packed layout (sizes checked above).
            unsafe {
                std::ptr::copy_nonoverlapping(
                    recs.as_ptr() as *const u8,
                    (*a.as_array_ptr()).fields.data as *mut u8,
                    bytes,
                );
            }
        }
        Ok(arr)
    }

    /// Names of the continuum bodies, in scenario order.
    fn body_names(&self) -> PyResult<Vec<String>> {
        Ok(self.lock()?.body_names())
    }

    /// Nodal fields of a body (given by name or index): a dict of `x`
    /// (reference node positions, (n, 2)), `u` (displacement), `v`
    /// (velocity) (n, 2), `strain` (ε_xx, ε_yy, γ_xy) and `stress`
    /// (σ_xx, σ_yy, σ_xy) (n, 3) — the true fields sampled at the nodes
    /// (EFG nodal unknowns are not displacements).
    fn body_fields<'py>(
        &self,
        py: Python<'py>,
        body: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mut g = self.lock()?;
        let i = g.body_index(body)?;
        g.nodes_bound(i)?;
        let b = g.model.body(i);
        let at = &g.node_at[i].as_ref().expect("bound").1;
        let n = at.len();
        let (mut u, mut v) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let (mut e, mut s) = (Vec::with_capacity(3 * n), Vec::with_capacity(3 * n));
        for a in at {
            let smp = b.sample_at(a);
            u.push(smp.u);
            v.push(smp.v);
            e.extend(smp.strain);
            s.extend(smp.stress);
        }
        let d = PyDict::new(py);
        d.set_item("x", vec2_array(py, (0..n).map(|k| node(b, k))))?;
        d.set_item("u", vec2_array(py, u.into_iter()))?;
        d.set_item("v", vec2_array(py, v.into_iter()))?;
        let m3 = |x: Vec<f64>| {
            Array2::from_shape_vec((n, 3), x)
                .expect("n × 3")
                .into_pyarray(py)
        };
        d.set_item("strain", m3(e))?;
        d.set_item("stress", m3(s))?;
        Ok(d)
    }

    /// Reference node positions and nodal displacement of a body (by name
    /// or index): `(x, u)`, two (n, 2) arrays.
    fn body_displacement<'py>(
        &self,
        py: Python<'py>,
        body: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let d = self.body_fields(py, body)?;
        Ok((d.get_item("x")?.expect("x"), d.get_item("u")?.expect("u")))
    }

    /// The true fields of a body (by name or index) at reference point(s)
    /// (x, y): a dict of `u`, `v` (shape (2,), or (m, 2) for arrays of m
    /// points), `strain` and `stress` ((3,) or (m, 3)). Raises `ModelError`
    /// for a point outside the body.
    fn sample<'py>(
        &self,
        py: Python<'py>,
        body: &Bound<'py, PyAny>,
        x: &Bound<'py, PyAny>,
        y: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let g = self.lock()?;
        let i = g.body_index(body)?;
        let scalar = x.extract::<f64>().is_ok() && y.extract::<f64>().is_ok();
        let (xs, ys): (Vec<f64>, Vec<f64>) = if scalar {
            (vec![x.extract()?], vec![y.extract()?])
        } else {
            let np = py.import("numpy")?;
            let f = |a: &Bound<'py, PyAny>| -> PyResult<Vec<f64>> {
                np.call_method1("ravel", (np.call_method1("asarray", (a, "f8"))?,))?
                    .call_method0("tolist")?
                    .extract()
            };
            (f(x)?, f(y)?)
        };
        if xs.len() != ys.len() {
            return Err(PyValueError::new_err(format!(
                "x and y have {} and {} values",
                xs.len(),
                ys.len()
            )));
        }
        let b = g.model.body(i);
        let mut u = Vec::with_capacity(xs.len());
        let mut v = Vec::with_capacity(xs.len());
        let (mut e, mut s) = (Vec::new(), Vec::new());
        for (&px, &py_) in xs.iter().zip(&ys) {
            let at = b.bind(Vec2::new(px, py_)).map_err(model_error)?;
            let smp = b.sample_at(&at);
            u.push(smp.u);
            v.push(smp.v);
            e.extend(smp.strain);
            s.extend(smp.stress);
        }
        let d = PyDict::new(py);
        let m = xs.len();
        if scalar {
            d.set_item("u", Array1::from(vec![u[0].x, u[0].y]).into_pyarray(py))?;
            d.set_item("v", Array1::from(vec![v[0].x, v[0].y]).into_pyarray(py))?;
            d.set_item("strain", Array1::from(e).into_pyarray(py))?;
            d.set_item("stress", Array1::from(s).into_pyarray(py))?;
        } else {
            d.set_item("u", vec2_array(py, u.into_iter()))?;
            d.set_item("v", vec2_array(py, v.into_iter()))?;
            let m3 = |x: Vec<f64>| {
                Array2::from_shape_vec((m, 3), x)
                    .expect("m × 3")
                    .into_pyarray(py)
            };
            d.set_item("strain", m3(e))?;
            d.set_item("stress", m3(s))?;
        }
        Ok(d)
    }

    /// Names of the scenario's `[[probe]]`s, in file order.
    fn probe_names(&self) -> PyResult<Vec<String>> {
        Ok(self.lock()?.probes.iter().map(|p| p.0.clone()).collect())
    }

    /// The present value of the scenario's `[[probe]]` named `name` (the
    /// value `history.csv` records).
    fn probe(&self, name: &str) -> PyResult<f64> {
        let g = self.lock()?;
        let p = g.probes.iter().find(|p| p.0 == name).ok_or_else(|| {
            PyKeyError::new_err(format!(
                "no probe named `{name}` (probes: {:?})",
                g.probes.iter().map(|p| &p.0).collect::<Vec<_>>()
            ))
        })?;
        Ok(g.model.probe(&p.1))
    }

    /// Write a ParaView frame of the present state into `dir`, the files
    /// `efgdem run` writes (binary): `frames/discs_<step>.vtp`,
    /// `frames/contacts_<step>.vtp`, `frames/walls_<step>.vtp` (if there
    /// are walls) and `frames/<body>_<step>.vtu`, with the series
    /// `discs.pvd`, `contacts.pvd`, `walls.pvd` and `<body>.pvd` in `dir`
    /// updated (a static model: `<body>.vtu` in `dir`). Returns the paths
    /// written.
    fn write_frame(&self, py: Python<'_>, dir: PathBuf) -> PyResult<Vec<PathBuf>> {
        let mut g = self.lock()?;
        let inner: &mut Inner = &mut g;
        inner.ensure_pool()?;
        // inside the model's pool: the frames compress in parallel
        py.detach(|| {
            let pool = Arc::clone(&inner.pool);
            pool.install(|| write_frame(inner, &dir))
        })
        .map_err(|e| match e {
            FrameError::Io(e) => PyIOError::new_err(format!("{}: {e}", dir.display())),
            FrameError::Model(e) => model_error(e),
        })
    }

    fn __repr__(&self) -> PyResult<String> {
        let g = self.lock()?;
        let m = &g.model;
        let kind = match m.system {
            System::Continuum { .. } => "continuum",
            System::Granular(_) => "granular",
            System::Coupled(_) => "coupled",
        };
        Ok(format!(
            "<efgdem.Model {kind}: {} discs, {} bodies, step {} of {}, t = {:e}>",
            m.granular().map_or(0, |g| g.particles.len()),
            m.n_bodies(),
            m.step,
            m.steps,
            m.time()
        ))
    }
}

enum FrameError {
    Io(std::io::Error),
    Model(efgdem::model::body::BodyError),
}

impl From<std::io::Error> for FrameError {
    fn from(e: std::io::Error) -> Self {
        FrameError::Io(e)
    }
}

fn write_frame(inner: &mut Inner, dir: &Path) -> Result<Vec<PathBuf>, FrameError> {
    if let System::Granular(g) = &mut inner.model.system
        && g.step == 0
    {
        // as `efgdem run` does before its first frame: list the contacts
        g.prepare_contacts();
    }
    let model = &inner.model;
    if !inner.frames.contains_key(dir) {
        let f = Frames::new(model, dir)
            .map_err(FrameError::Model)?
            .with_format(inner.vtk_format);
        inner.frames.insert(dir.to_path_buf(), f);
    }
    let frames = inner.frames.get_mut(dir).expect("inserted");
    std::fs::create_dir_all(dir)?;
    let written = if matches!(model.system, System::Continuum { dynamic: false, .. }) {
        frames.write_static(model)?
    } else {
        frames.write(model)?
    };
    inner.check_buffers();
    Ok(written)
}

/// The TOML text of a scenario dict.
fn toml_text(d: &Bound<'_, PyDict>) -> PyResult<String> {
    let v = to_toml(d.as_any(), "")?;
    toml::to_string(&v).map_err(|e| ScenarioError::new_err(format!("{DICT_FILE}: {e}")))
}

/// The TOML text `Model.from_dict` parses for `scenario` (for inspection,
/// or to save a dict-built scenario as a file).
#[pyfunction]
fn scenario_toml(scenario: &Bound<'_, PyDict>) -> PyResult<String> {
    toml_text(scenario)
}

/// efgdem: element-free Galerkin continua coupled with a 2D DEM of discs.
///
/// `Model.from_scenario(path)` / `Model.from_dict(d)` build a model from
/// the TOML scenario schema (docs/scenario.md); `step(n)`, `run(until)`
/// advance it with the GIL released; disc state comes as numpy copies in id
/// order (`disc_positions()` …) or zero-copy live views in slot order
/// (`disc_views()`); `contacts()` is a structured array; `write_frame(dir)`
/// writes the ParaView files `efgdem run` writes.
#[pymodule]
#[pyo3(name = "efgdem")]
fn efgdem_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    efgdem::run::memory::keep_large_allocations_mapped();
    let py = m.py();
    m.add_class::<PyModel>()?;
    m.add("ScenarioError", py.get_type::<ScenarioError>())?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add_function(wrap_pyfunction!(scenario_toml, m)?)?;
    m.add("CONTACT_DISC_DISC", 0u8)?;
    m.add("CONTACT_DISC_WALL", 1u8)?;
    m.add("CONTACT_DISC_BODY", 2u8)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
