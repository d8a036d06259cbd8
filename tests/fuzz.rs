//! Property (mutation) test of issue 12, "runs that can be trusted": the
//! repository's scenario files, mutated thousands of times, must never make
//! `check` or a short `run` panic. Every mutant is either accepted or
//! refused with a located scenario error (`file:line: field: message`,
//! exit code 2 on the command line); a short run may also fail with a
//! model error (an instability), never with a panic.
//!
//! The mutants are deterministic (a seeded xorshift generator): numbers
//! replaced by 0, −x, ±1e300, ±1e-300, nan, ±inf, huge integers, ×1e6;
//! keys, sections and array elements deleted; array-of-tables elements and
//! sections duplicated; types swapped (string ↔ number ↔ array ↔ table);
//! inline tables written as arrays of their values; bodies made polygons
//! of 3 to 100 001 vertices or given circle holes of up to 2⁶³ − 1
//! segments; paths such as `/dev/zero`; enum strings exchanged; unknown
//! keys added; the text truncated, lines deleted, duplicated or swapped. `EFGDEM_FUZZ_N` (mutants, default
//! 2 400) and `EFGDEM_FUZZ_SEED` run a longer or different campaign.
//!
//! The minimal reproducers of what the campaign found are kept below as
//! named regression tests.

use efgdem::run::{RunError, RunOptions};
use efgdem::scenario::{self, Scenario, ScenarioError};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use toml_edit::{Array, ArrayOfTables, DocumentMut, InlineTable, Item, Table, Value};

// ---------------------------------------------------------------------------
// A small deterministic generator.

struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    /// xorshift64*.
    fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn chance(&mut self, p: f64) -> bool {
        ((self.next() >> 11) as f64 / (1u64 << 53) as f64) < p
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

// ---------------------------------------------------------------------------
// The seed scenarios.

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A few scenarios of the tests, to cover what the examples do not
/// (FE bodies with lumped mass, global damping, wall histories, rolling
/// resistance, staggered coupling, static initial states).
const INLINE: &[(&str, &str)] = &[
    (
        "inline_walls",
        r#"[simulation]
dt = 1.0e-4
steps = 20
gravity = [0.0, -9.81]
[[material]]
name = "m"
density = 1000.0
kn = 1.0e6
ks = 1.0e6
friction = 0.5
rolling_friction = 0.1
slip_normal = "elastic"
[[material]]
name = "steel"
density = 7800.0
kn = 1.0e7
ks = 1.0e7
[granular]
material = "m"
discs = { generate = "hex", box = [[0.0, 0.0], [1.0, 0.5]], radius = [0.04, 0.05], count = 40, jitter = 0.5 }
damping = { kind = "global", c = 0.1, c_rot = 0.01 }
skin = 0.01
velocity = [0.1, 0.0]
[[wall]]
name = "floor"
from = [-1.0, 0.0]
to = [2.0, 0.0]
material = "steel"
history = [[0.0, 0.0, 0.0], [0.001, 0.0, 0.1]]
[[wall]]
name = "lid"
from = [-1.0, 1.0]
to = [2.0, 1.0]
velocity = [0.0, -0.1]
until_step = 10
[[probe]]
name = "fy"
wall = "lid"
quantity = "wall_fy"
[[probe]]
name = "n12"
contact = [1, 2]
quantity = "normal_total"
[[probe]]
name = "x3"
disc = 3
quantity = "omega"
[output]
every = 2
vtk_every = 5
"#,
    ),
    (
        "inline_fem_coupled",
        r#"[simulation]
dt = 1.0e-4
end_time = 0.002
gravity = [0.0, -9.81]
substeps = 2
coupling = "staggered"
contact_solve = "direct"
geometric_stiffness = false
[[material]]
name = "m"
density = 1000.0
kn = 1.0e6
ks = 1.0e6
friction = 0.3
cohesion = 1.0
[granular]
material = "m"
discs = [[0.5, 0.25, 0.05], [0.7, 0.25, 0.05]]
damping = { kind = "contact-viscous", beta = 0.001, beta_shear = 0.0005, no_tension = true }
[[body]]
name = "plate"
method = "fem-q4"
mass = "lumped"
rectangle = { origin = [0.0, 0.0], size = [1.0, 0.2] }
nodes = [11, 3]
elastic = { E = 1.0e8, nu = 0.3, density = 2000.0, thickness = 0.1, plane = "strain" }
damping = 0.5
contact_refine = 2
contact_material = "m"
initial = { static_under = ["gravity", "push"] }
[[body.bc]]
edge = "bottom"
fixed = true
[[body.bc]]
name = "push"
edge = "top"
traction = [0.0, -10.0]
[[body.bc]]
edge = "right"
ux = { velocity = 0.01, until_step = 5 }
[[probe]]
name = "fy"
body = "plate"
quantity = "contact_fy"
[[probe]]
name = "sxx"
body = "plate"
point = [0.5, 0.1]
quantity = "sxx"
[[probe]]
name = "d1"
disc = 1
quantity = "uy"
"#,
    ),
    (
        "inline_dynamic_efg",
        r#"[simulation]
dt = 1.0e-3
steps = 10
[[body]]
name = "beam"
rectangle = { origin = [0.0, -0.5], size = [8.0, 1.0] }
nodes = [17, 5]
cells = [16, 4]
gauss = 3
d_max = 2.5
penalty = 1.0e12
elastic = { E = 1.0e7, nu = 0.25, density = 1.0 }
newmark = { gamma = 0.6, beta = 0.3025 }
initial = { static_under = ["tip"] }
[[body.bc]]
edge = "left"
timoshenko = { P = -100.0 }
[[body.bc]]
name = "tip"
edge = "right"
parabolic_shear = -100.0
[[probe]]
name = "tip"
point = [8.0, 0.0]
quantity = "uy"
[[probe]]
name = "ke"
quantity = "kinetic_energy"
"#,
    ),
];

/// (name, directory for relative paths, text) of every seed scenario, with
/// generated disc counts cut to a few hundred (the mutants multiply them).
fn seeds() -> Vec<(String, PathBuf, String)> {
    let mut out = Vec::new();
    for dir in ["examples", "docs/tutorial"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root().join(dir))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        for f in files {
            let text = std::fs::read_to_string(&f).unwrap();
            out.push((
                f.file_name().unwrap().to_string_lossy().into_owned(),
                f.parent().unwrap().to_path_buf(),
                small_counts(&text),
            ));
        }
    }
    for (name, text) in INLINE {
        out.push((name.to_string(), root(), text.to_string()));
    }
    out
}

/// `count = N` with N > 300 becomes `count = 300`.
fn small_counts(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(k) = rest.find("count = ") {
        let (head, tail) = rest.split_at(k + "count = ".len());
        out.push_str(head);
        let digits = tail.chars().take_while(char::is_ascii_digit).count();
        let n: usize = tail[..digits].parse().unwrap_or(0);
        out.push_str(&if n > 300 {
            "300".to_string()
        } else {
            tail[..digits].to_string()
        });
        rest = &tail[digits..];
    }
    out.push_str(rest);
    out
}

// ---------------------------------------------------------------------------
// Structural mutations through toml_edit.

#[derive(Debug, Clone)]
enum Seg {
    K(String),
    I(usize),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Int,
    Float,
    Str,
    Bool,
    Array,
    Inline,
    Table,
    TableElem,
    Aot,
}

/// Every node of the document below the root: its path and kind.
fn nodes(doc: &DocumentMut) -> Vec<(Vec<Seg>, Kind, Option<Value>)> {
    fn value(path: Vec<Seg>, v: &Value, out: &mut Vec<(Vec<Seg>, Kind, Option<Value>)>) {
        let kind = match v {
            Value::Integer(_) => Kind::Int,
            Value::Float(_) => Kind::Float,
            Value::String(_) => Kind::Str,
            Value::Boolean(_) => Kind::Bool,
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    let mut p = path.clone();
                    p.push(Seg::I(i));
                    value(p, x, out);
                }
                Kind::Array
            }
            Value::InlineTable(t) => {
                for (k, x) in t.iter() {
                    let mut p = path.clone();
                    p.push(Seg::K(k.to_string()));
                    value(p, x, out);
                }
                Kind::Inline
            }
            Value::Datetime(_) => Kind::Str,
        };
        out.push((path, kind, Some(v.clone())));
    }
    fn table(path: Vec<Seg>, t: &Table, out: &mut Vec<(Vec<Seg>, Kind, Option<Value>)>) {
        for (k, it) in t.iter() {
            let mut p = path.clone();
            p.push(Seg::K(k.to_string()));
            match it {
                Item::Value(v) => value(p, v, out),
                Item::Table(t) => {
                    table(p.clone(), t, out);
                    out.push((p, Kind::Table, None));
                }
                Item::ArrayOfTables(a) => {
                    for (i, t) in a.iter().enumerate() {
                        let mut q = p.clone();
                        q.push(Seg::I(i));
                        table(q.clone(), t, out);
                        out.push((q, Kind::TableElem, None));
                    }
                    out.push((p, Kind::Aot, None));
                }
                Item::None => {}
            }
        }
    }
    let mut out = Vec::new();
    table(Vec::new(), doc.as_table(), &mut out);
    out
}

enum Parent<'a> {
    Table(&'a mut Table),
    Inline(&'a mut InlineTable),
    Array(&'a mut Array),
    Aot(&'a mut ArrayOfTables),
}

fn of_value(v: &mut Value) -> Option<Parent<'_>> {
    match v {
        Value::Array(a) => Some(Parent::Array(a)),
        Value::InlineTable(t) => Some(Parent::Inline(t)),
        _ => None,
    }
}

/// The container at `path`.
fn container<'a>(doc: &'a mut DocumentMut, path: &[Seg]) -> Option<Parent<'a>> {
    let mut p = Parent::Table(doc.as_table_mut());
    for seg in path {
        p = match (p, seg) {
            (Parent::Table(t), Seg::K(k)) => match t.get_mut(k)? {
                Item::Table(t) => Parent::Table(t),
                Item::ArrayOfTables(a) => Parent::Aot(a),
                Item::Value(v) => of_value(v)?,
                Item::None => return None,
            },
            (Parent::Inline(t), Seg::K(k)) => of_value(t.get_mut(k)?)?,
            (Parent::Array(a), Seg::I(i)) => of_value(a.get_mut(*i)?)?,
            (Parent::Aot(a), Seg::I(i)) => Parent::Table(a.get_mut(*i)?),
            _ => return None,
        };
    }
    Some(p)
}

/// Replace the value at `path` (false if it cannot hold a value).
fn set(doc: &mut DocumentMut, path: &[Seg], v: Value) -> bool {
    let (last, parent) = path.split_last().unwrap();
    match (container(doc, parent), last) {
        (Some(Parent::Table(t)), Seg::K(k)) => {
            t.insert(k, Item::Value(v));
        }
        (Some(Parent::Inline(t)), Seg::K(k)) => {
            t.insert(k.as_str(), v);
        }
        (Some(Parent::Array(a)), Seg::I(i)) => {
            a.replace(*i, v);
        }
        _ => return false,
    }
    true
}

/// Remove the node at `path`.
fn remove(doc: &mut DocumentMut, path: &[Seg]) -> bool {
    let (last, parent) = path.split_last().unwrap();
    match (container(doc, parent), last) {
        (Some(Parent::Table(t)), Seg::K(k)) => t.remove(k).is_some(),
        (Some(Parent::Inline(t)), Seg::K(k)) => t.remove(k).is_some(),
        (Some(Parent::Array(a)), Seg::I(i)) if *i < a.len() => {
            a.remove(*i);
            true
        }
        (Some(Parent::Aot(a)), Seg::I(i)) if *i < a.len() => {
            a.remove(*i);
            true
        }
        _ => false,
    }
}

/// Append a copy of the element at `path` to its array (of tables).
fn duplicate(doc: &mut DocumentMut, path: &[Seg]) -> bool {
    let (last, parent) = path.split_last().unwrap();
    match (container(doc, parent), last) {
        (Some(Parent::Array(a)), Seg::I(i)) => {
            let Some(v) = a.get(*i).cloned() else {
                return false;
            };
            a.push(v);
            true
        }
        (Some(Parent::Aot(a)), Seg::I(i)) => {
            let Some(t) = a.get(*i).cloned() else {
                return false;
            };
            a.push(t);
            true
        }
        _ => false,
    }
}

/// Strings a scenario uses as enum values and names.
const WORDS: &[&str] = &[
    "static",
    "dynamic",
    "efg",
    "fem-q4",
    "lumped",
    "consistent",
    "stress",
    "strain",
    "left",
    "right",
    "top",
    "bottom",
    "square",
    "hex",
    "random",
    "loose",
    "deposit",
    "grow",
    "none",
    "contact-viscous",
    "critical-ratio",
    "local",
    "global",
    "total",
    "elastic",
    "implicit",
    "staggered",
    "boundary",
    "direct",
    "ux",
    "uy",
    "vx",
    "sxx",
    "x",
    "omega",
    "contacts",
    "kinetic",
    "kinetic_energy",
    "total_energy",
    "wall_fy",
    "wall_x",
    "contact_fy",
    "normal_elastic",
    "gravity",
    "sand",
    "disc",
    "grain",
    "floor",
    "beam",
    "footing",
    "tip",
    "",
    "zzz",
    "nan",
    "NaN",
    "inf",
    "-1e300",
    "1e999",
    "discs.csv",
    "/nonexistent/x.csv",
    "../README.md",
    "/dev/zero",
];

/// Field names, some valid somewhere, some nowhere.
const KEYS: &[&str] = &[
    "count",
    "settle_steps",
    "steps",
    "end_time",
    "dt",
    "velocity",
    "until_step",
    "history",
    "allow_overlap",
    "skin",
    "penalty",
    "cells",
    "jitter",
    "method",
    "material",
    "seed",
    "radius",
    "box",
    "point",
    "disc",
    "wall",
    "body",
    "contact",
    "segments",
    "holes",
    "outline",
    "csv",
    "bogus",
];

fn weird_number(rng: &mut Rng, old: Option<f64>) -> Value {
    let x = old.unwrap_or(1.0);
    if rng.chance(0.35) {
        // near the old value or small: edge cases of the logic rather
        // than of the arithmetic (grids of 2 nodes, 1 Gauss point, d_max
        // near 1, disc 0, a radius as large as the box)
        let is_int = x.fract() == 0.0 && x.abs() < 1e15;
        let v = match rng.below(9) {
            0 => x + 1.0,
            1 => x - 1.0,
            2 => x * 2.0,
            3 => x / 2.0,
            4 => 1.0,
            5 => 2.0,
            6 => 3.0,
            7 => x * 1.000_000_1,
            _ => x * 0.999_999_9,
        };
        return if is_int && v.fract() == 0.0 {
            Value::from(v as i64)
        } else {
            Value::from(v)
        };
    }
    match rng.below(17) {
        0 => Value::from(0i64),
        1 => Value::from(0.0),
        2 => Value::from(-x),
        3 => Value::from(1e300),
        4 => Value::from(-1e300),
        5 => Value::from(1e-300),
        6 => Value::from(f64::NAN),
        7 => Value::from(f64::INFINITY),
        8 => Value::from(f64::NEG_INFINITY),
        9 => Value::from(i64::MAX),
        10 => Value::from(i64::MIN),
        11 => Value::from(x * 1e6),
        12 => Value::from(-1i64),
        13 => Value::from(4_294_967_297i64),
        14 => Value::from(x * 1e-6),
        15 => Value::from(-1e-300),
        _ => Value::from((x * 1e6).round().clamp(-9e18, 9e18) as i64),
    }
}

fn some_value(rng: &mut Rng) -> Value {
    match rng.below(8) {
        0 => Value::from(*rng.pick(WORDS)),
        1 => weird_number(rng, None),
        2 => Value::from(true),
        3 => Value::Array(Array::new()),
        4 => {
            let mut a = Array::new();
            a.push(1.0);
            a.push(weird_number(rng, None));
            Value::Array(a)
        }
        5 => {
            let mut a = Array::new();
            let mut row = Array::new();
            row.push(0.0);
            row.push(0.0);
            row.push(1e-3);
            a.push(row);
            Value::Array(a)
        }
        6 => Value::InlineTable(InlineTable::new()),
        _ => {
            let mut t = InlineTable::new();
            t.insert(*rng.pick(KEYS), weird_number(rng, None));
            Value::InlineTable(t)
        }
    }
}

/// One structural mutation of `doc`; false if it did not apply.
fn mutate_doc(doc: &mut DocumentMut, rng: &mut Rng) -> bool {
    let all = nodes(doc);
    if all.is_empty() {
        return false;
    }
    let (path, kind, old) = rng.pick(&all).clone();
    let num = match &old {
        Some(Value::Integer(i)) => Some(*i.value() as f64),
        Some(Value::Float(f)) => Some(*f.value()),
        _ => None,
    };
    match rng.below(12) {
        // a table written as an array of its values (strict tables)
        10 => {
            let inline: Vec<_> = all.iter().filter(|n| n.1 == Kind::Inline).collect();
            let Some((p, _, Some(Value::InlineTable(t)))) =
                inline.get(rng.below(inline.len())).map(|n| (*n).clone())
            else {
                return false;
            };
            let mut a = Array::new();
            for (_, v) in t.iter() {
                a.push(v.clone());
            }
            set(doc, &p, Value::Array(a))
        }
        // polygon sizes: a body made a polygon of many vertices, or given a
        // circle hole of an absurd number of segments
        11 => {
            let bodies: Vec<_> = all
                .iter()
                .filter(|n| {
                    n.1 == Kind::TableElem && matches!(n.0.first(), Some(Seg::K(k)) if k == "body")
                })
                .collect();
            if bodies.is_empty() {
                return false;
            }
            let p = rng.pick(&bodies).0.clone();
            let n = *rng.pick(&[3i64, 1000, 4096, 100_001, 4_294_967_297, i64::MAX]);
            let Some(Parent::Table(t)) = container(doc, &p) else {
                return false;
            };
            if rng.chance(0.5) {
                let mut hole = InlineTable::new();
                let mut c = Array::new();
                c.push(0.5);
                c.push(0.0);
                hole.insert("center", Value::Array(c));
                hole.insert("radius", Value::from(0.1));
                hole.insert("segments", Value::from(n));
                let mut holes = Array::new();
                holes.push(Value::InlineTable(hole));
                t.insert("holes", Item::Value(Value::Array(holes)));
            } else {
                // an n-gon (at most 100 001 vertices written out)
                let m = n.clamp(3, 100_001) as usize;
                let mut o = Array::new();
                for k in 0..m {
                    let a = std::f64::consts::TAU * k as f64 / m as f64;
                    let mut v = Array::new();
                    v.push(0.5 + 0.5 * a.cos());
                    v.push(0.5 * a.sin());
                    o.push(Value::Array(v));
                }
                t.insert("outline", Item::Value(Value::Array(o)));
                t.insert("spacing", Item::Value(Value::from(0.1)));
                for k in ["rectangle", "nodes", "cells"] {
                    t.remove(k);
                }
            }
            true
        }
        // numbers: the main target
        0..=3 => {
            let nums: Vec<_> = all
                .iter()
                .filter(|n| matches!(n.1, Kind::Int | Kind::Float))
                .collect();
            if nums.is_empty() {
                return false;
            }
            let (p, _, v) = (*rng.pick(&nums)).clone();
            let x = match v {
                Some(Value::Integer(i)) => *i.value() as f64,
                Some(Value::Float(f)) => *f.value(),
                _ => 1.0,
            };
            set(doc, &p, weird_number(rng, Some(x)))
        }
        // strings: another enum value or name
        4 => {
            let strs: Vec<_> = all.iter().filter(|n| n.1 == Kind::Str).collect();
            if strs.is_empty() {
                return false;
            }
            let p = rng.pick(&strs).0.clone();
            set(doc, &p, Value::from(*rng.pick(WORDS)))
        }
        // delete a key, an element or a whole section
        5 | 6 => remove(doc, &path),
        // duplicate an element of an array (of tables)
        7 => match kind {
            Kind::TableElem => duplicate(doc, &path),
            _ => {
                let elems: Vec<_> = all
                    .iter()
                    .filter(|n| matches!(n.0.last(), Some(Seg::I(_))))
                    .collect();
                if elems.is_empty() {
                    return false;
                }
                let p = rng.pick(&elems).0.clone();
                duplicate(doc, &p)
            }
        },
        // swap the type of a value
        8 => {
            let v = match (kind, num) {
                (_, Some(x)) => match rng.below(3) {
                    0 => Value::from(format!("{x}")),
                    1 => {
                        let mut a = Array::new();
                        a.push(x);
                        Value::Array(a)
                    }
                    _ => Value::from(x != 0.0),
                },
                (Kind::Str, _) => match rng.below(2) {
                    0 => Value::from(1.5),
                    _ => {
                        let mut a = Array::new();
                        a.push(old.as_ref().and_then(|v| v.as_str()).unwrap_or("x"));
                        Value::Array(a)
                    }
                },
                (Kind::Array | Kind::Inline, _) => match rng.below(3) {
                    0 => Value::from(1.0),
                    1 => Value::from("1.0"),
                    _ => Value::Array(Array::new()),
                },
                (Kind::Bool, _) => Value::from("true"),
                _ => some_value(rng),
            };
            if matches!(kind, Kind::Table | Kind::TableElem | Kind::Aot) {
                // a section replaced by a plain value
                let (last, parent) = path.split_last().unwrap();
                return match (container(doc, parent), last) {
                    (Some(Parent::Table(t)), Seg::K(k)) => {
                        t.insert(k, Item::Value(v));
                        true
                    }
                    _ => false,
                };
            }
            set(doc, &path, v)
        }
        // add a key (known somewhere, or unknown) to a table
        _ => {
            let tables: Vec<_> = all
                .iter()
                .filter(|n| matches!(n.1, Kind::Table | Kind::TableElem | Kind::Inline))
                .collect();
            let p = if tables.is_empty() || rng.chance(0.1) {
                Vec::new()
            } else {
                rng.pick(&tables).0.clone()
            };
            let mut full = p;
            full.push(Seg::K(rng.pick(KEYS).to_string()));
            let v = some_value(rng);
            set(doc, &full, v)
        }
    }
}

/// One textual mutation of `text`.
fn mutate_text(text: &str, rng: &mut Rng) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let n = lines.len().max(1);
    match rng.below(7) {
        // truncate at a character boundary
        0 => {
            let mut k = rng.below(text.len() + 1);
            while !text.is_char_boundary(k) {
                k -= 1;
            }
            text[..k].to_string()
        }
        // delete a line
        1 => {
            let k = rng.below(n);
            lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, l)| format!("{l}\n"))
                .collect()
        }
        // duplicate a line
        2 => {
            let k = rng.below(n);
            lines
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    if i == k {
                        format!("{l}\n{l}\n")
                    } else {
                        format!("{l}\n")
                    }
                })
                .collect()
        }
        // swap two lines
        3 => {
            let mut v: Vec<&str> = lines.clone();
            if !v.is_empty() {
                let (a, b) = (rng.below(n), rng.below(n));
                let last = v.len() - 1;
                v.swap(a.min(last), b.min(last));
            }
            v.iter().map(|l| format!("{l}\n")).collect()
        }
        // duplicate a whole section (header to the next header)
        4 => {
            let heads: Vec<usize> = lines
                .iter()
                .enumerate()
                .filter(|(_, l)| l.trim_start().starts_with('['))
                .map(|(i, _)| i)
                .collect();
            if heads.is_empty() {
                return text.to_string();
            }
            let h = *rng.pick(&heads);
            let end = heads
                .iter()
                .copied()
                .find(|&e| e > h)
                .unwrap_or(lines.len());
            let mut s = text.to_string();
            if !s.ends_with('\n') {
                s.push('\n');
            }
            for l in &lines[h..end] {
                s.push_str(l);
                s.push('\n');
            }
            s
        }
        // a number token replaced by a weird literal
        5 => {
            let starts: Vec<usize> = text
                .char_indices()
                .filter(|&(i, c)| {
                    c.is_ascii_digit()
                        && (i == 0 || !text.as_bytes()[i - 1].is_ascii_alphanumeric())
                        && (i == 0 || text.as_bytes()[i - 1] != b'.')
                })
                .map(|(i, _)| i)
                .collect();
            if starts.is_empty() {
                return text.to_string();
            }
            let s = *rng.pick(&starts);
            let len = text[s..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || "._+-".contains(c)))
                .unwrap_or(text.len() - s);
            let lit = *rng.pick(&[
                "1e999",
                "-0.0",
                "0x10",
                "1_000",
                "nan",
                "+inf",
                "18446744073709551616",
                "9999999999999999999",
                "1e-400",
                "00",
                "1.",
                ".5",
                "\"1.0\"",
                "[]",
                "{}",
            ]);
            format!("{}{lit}{}", &text[..s], &text[s + len..])
        }
        // a garbage line
        _ => {
            let k = rng.below(n + 1);
            let garbage = *rng.pick(&[
                "[[",
                "x =",
                "[simulation]",
                "= 1",
                "[[body]]",
                "\"",
                "[granular]\nmaterial = 1",
            ]);
            let mut v: Vec<&str> = lines.clone();
            v.insert(k.min(v.len()), garbage);
            v.iter().map(|l| format!("{l}\n")).collect()
        }
    }
}

/// A mutant of `text`: one to three mutations, structural or textual.
fn mutant(text: &str, rng: &mut Rng) -> String {
    let k = match rng.below(10) {
        0..=5 => 1,
        6..=8 => 2,
        _ => 3,
    };
    let mut s = text.to_string();
    for _ in 0..k {
        if rng.chance(0.8)
            && let Ok(mut doc) = s.parse::<DocumentMut>()
        {
            for _ in 0..4 {
                if mutate_doc(&mut doc, rng) {
                    break;
                }
            }
            s = doc.to_string();
            continue;
        }
        s = mutate_text(&s, rng);
    }
    s
}

// ---------------------------------------------------------------------------
// Running mutants.

/// Where and why the last panic happened (set by the hook).
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

fn install_panic_recorder() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let msg = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_default();
            let at = info
                .location()
                .map(|l| format!("{}:{}", l.file(), l.line()))
                .unwrap_or_default();
            *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{at}: {msg}"));
            default(info);
        }));
    });
}

/// What became of one mutant.
#[derive(Debug)]
enum Outcome {
    /// Refused by the parser or the validation (`parse`).
    ParseRefused,
    /// Refused by `check` with a located scenario error.
    CheckRefused,
    /// Refused by `check` with an error that is not a scenario error.
    CheckOther(String),
    /// `check` accepted it.
    Accepted,
    /// Its estimated memory is too large to build here (below the
    /// machine's memory, so `check` would build it): not checked.
    TooLarge,
    /// A panic: where and why.
    Panic(String),
}

/// A scenario error must read `file…: message` with every message set.
fn assert_located(e: &ScenarioError, file: &str, text: &str) {
    let shown = e.to_string();
    assert!(shown.starts_with(file), "{shown}\n--- mutant:\n{text}");
    if let ScenarioError::Invalid { errors, .. } = e {
        assert!(!errors.is_empty(), "no errors listed\n{text}");
        for l in errors {
            assert!(!l.message.trim().is_empty(), "{shown}\n--- mutant:\n{text}");
        }
    }
}

/// Bytes above which an accepted mutant is not built by this test.
const BUILD_BUDGET: f64 = 64e6;

fn check_one(name: &str, dir: &Path, text: &str) -> (Outcome, Option<Scenario>) {
    *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = None;
    let r = catch_unwind(AssertUnwindSafe(|| {
        let mut sc = match scenario::parse(text, name) {
            Ok(sc) => sc,
            Err(e) => {
                assert_located(&e, name, text);
                return (Outcome::ParseRefused, None);
            }
        };
        sc.base_dir = dir.to_path_buf();
        let est = scenario::build::memory_estimate(&sc).total();
        let machine = scenario::build::machine_memory().unwrap_or(f64::INFINITY);
        if est > BUILD_BUDGET && est <= machine {
            return (Outcome::TooLarge, None);
        }
        match efgdem::run::check(&sc) {
            Ok(_) => (Outcome::Accepted, Some(sc)),
            Err(RunError::Scenario(e)) => {
                assert_located(&e, name, text);
                (Outcome::CheckRefused, None)
            }
            Err(e) => (Outcome::CheckOther(e.to_string()), None),
        }
    }));
    r.unwrap_or_else(|_| {
        let why = LAST_PANIC
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
            .unwrap_or_default();
        (Outcome::Panic(why), None)
    })
}

/// What became of a short run.
enum RunOutcome {
    /// Finished, every history value finite.
    Clean,
    /// Too large for this test (estimated memory above the budget).
    Skipped,
    /// Failed with a scenario error (what `check` should have found).
    Refused(String),
    /// Failed with a model or i/o error (an instability, a solve).
    Failed(String),
    /// Finished with exit 0 but a non-finite value in `history.csv`.
    NonFinite(String),
    /// A panic: where and why.
    Panic(String),
}

/// A short run of an accepted mutant: `steps` steps, a preparation of at
/// most 200 steps, frames every 2 steps if any.
fn short_run(mut sc: Scenario, out: &Path, steps: usize) -> RunOutcome {
    sc.simulation.steps = Some(steps);
    sc.simulation.end_time = None;
    if sc.output.vtk_every > 0 {
        sc.output.vtk_every = 2;
    }
    if let Some(g) = sc.granular.as_mut()
        && let scenario::granular::DiscsSpec::Table(t) = &mut g.discs
    {
        t.settle_steps = Some(t.settle_steps.unwrap_or(200).min(200));
    }
    if scenario::build::memory_estimate(&sc).total() > BUILD_BUDGET {
        return RunOutcome::Skipped;
    }
    let _ = std::fs::remove_dir_all(out);
    *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = None;
    let opts = RunOptions {
        quiet: true,
        ..RunOptions::new(out)
    };
    let r = catch_unwind(AssertUnwindSafe(|| efgdem::run::run(&sc, &opts)));
    match r {
        Err(_) => RunOutcome::Panic(
            LAST_PANIC
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take()
                .unwrap_or_default(),
        ),
        Ok(Err(RunError::Scenario(e))) => RunOutcome::Refused(e.to_string()),
        Ok(Err(e)) => {
            let msg = e.to_string();
            assert!(!msg.trim().is_empty(), "an error without a message");
            RunOutcome::Failed(msg)
        }
        Ok(Ok(_)) => {
            let h = std::fs::read_to_string(out.join("history.csv")).unwrap_or_default();
            let bad = h.lines().skip(1).find(|l| {
                l.split(',')
                    .any(|f| f.trim().parse::<f64>().is_ok_and(|v| !v.is_finite()))
            });
            bad.map_or(RunOutcome::Clean, |l| RunOutcome::NonFinite(l.to_string()))
        }
    }
}

fn env_or(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[test]
fn thousands_of_mutated_scenarios_never_panic() {
    install_panic_recorder();
    let n = env_or("EFGDEM_FUZZ_N", 2400) as usize;
    let runs_wanted = env_or("EFGDEM_FUZZ_RUNS", 50) as usize;
    let mut rng = Rng::new(env_or("EFGDEM_FUZZ_SEED", 12));
    let seeds = seeds();
    let out_root = std::env::temp_dir().join(format!("efgdem-fuzz-{}", std::process::id()));
    let t0 = std::time::Instant::now();
    let (mut parse_refused, mut check_refused, mut accepted, mut too_large) = (0, 0, 0, 0);
    let mut other: Vec<(String, String, String)> = Vec::new();
    let mut panics: Vec<(String, String, String)> = Vec::new();
    let (mut runs, mut run_nonfinite) = (0, Vec::new());
    let (mut runs_clean, mut runs_skipped) = (0, 0);
    let mut runs_failed: Vec<(String, String)> = Vec::new();
    let mut runs_refused: Vec<(String, String)> = Vec::new();
    let mut slowest = (0.0, String::new());
    for k in 0..n {
        let (name, dir, text) = &seeds[k % seeds.len()];
        let m = mutant(text, &mut rng);
        let file = format!("mutant{k}-{name}");
        let t = std::time::Instant::now();
        let (outcome, sc) = check_one(&file, dir, &m);
        let secs = t.elapsed().as_secs_f64();
        if secs > slowest.0 {
            slowest = (secs, file.clone());
        }
        match outcome {
            Outcome::ParseRefused => parse_refused += 1,
            Outcome::CheckRefused => check_refused += 1,
            Outcome::TooLarge => too_large += 1,
            Outcome::CheckOther(e) => other.push((file.clone(), e, m.clone())),
            Outcome::Panic(why) => panics.push((file.clone(), why, m.clone())),
            Outcome::Accepted => accepted += 1,
        }
        if let Some(sc) = sc
            && runs < runs_wanted
            && rng.chance(0.25)
        {
            runs += 1;
            let steps = 2 + rng.below(9);
            match short_run(sc, &out_root.join(&file), steps) {
                RunOutcome::Clean => runs_clean += 1,
                RunOutcome::Skipped => runs_skipped += 1,
                RunOutcome::Failed(e) => runs_failed.push((file.clone(), e)),
                RunOutcome::Refused(e) => runs_refused.push((file.clone(), e)),
                RunOutcome::NonFinite(row) => run_nonfinite.push((file.clone(), row, m.clone())),
                RunOutcome::Panic(why) => panics.push((format!("{file} (run)"), why, m.clone())),
            }
            let _ = std::fs::remove_dir_all(out_root.join(&file));
        }
    }
    let _ = std::fs::remove_dir_all(&out_root);
    let refused = parse_refused + check_refused;
    println!(
        "{n} mutants of {} scenarios in {:.1} s: {refused} refused with located errors \
         ({parse_refused} by parse/validation, {check_refused} by check), {accepted} accepted, \
         {too_large} too large to build here, {} other errors, {} panics; \
         {runs} short runs ({runs_clean} clean, {} failed with a model error, {} refused \
         what check accepted, {} wrote non-finite history rows with exit 0, {runs_skipped} too \
         large); slowest check {:.2} s ({})",
        seeds.len(),
        t0.elapsed().as_secs_f64(),
        other.len(),
        panics.len(),
        runs_failed.len(),
        runs_refused.len(),
        run_nonfinite.len(),
        slowest.0,
        slowest.1,
    );
    for (f, e, m) in other.iter().take(5) {
        println!("--- {f}: not a scenario error: {e}\n{m}");
    }
    for (f, e) in runs_failed.iter().take(5) {
        println!("--- {f}: run failed (a proper error): {e}");
    }
    for (f, e) in runs_refused.iter().take(5) {
        println!("--- {f}: run refused what check accepted: {e}");
    }
    for (f, row, m) in run_nonfinite.iter().take(5) {
        println!("--- {f}: exit 0 with a non-finite history row: {row}\n{m}");
    }
    for (f, why, m) in panics.iter().take(10) {
        println!("--- {f}: PANIC {why}\n{m}");
    }
    assert!(
        n < 2000 || refused >= n / 4,
        "too few mutants refused: the mutator is broken"
    );
    assert!(panics.is_empty(), "{} panics (see above)", panics.len());
    // the per-step stability check stops a run whose state turns
    // non-finite (exit 3): no run may succeed with NaN or inf in its history
    assert!(
        run_nonfinite.is_empty(),
        "{} runs exited 0 with non-finite history rows (see above)",
        run_nonfinite.len()
    );
    assert!(
        other.is_empty(),
        "{} check errors that are not scenario errors",
        other.len()
    );
}

// ---------------------------------------------------------------------------
// Regression tests: the minimal reproducers of what the fuzzing (and the
// hand-made bad inputs of issue 12) found.

/// The message of the located scenario error `check` (through the
/// library, as `efgdem check` does) gives for `text`; panics if it is
/// accepted or fails otherwise.
fn refused(name: &str, text: &str) -> String {
    let e = match scenario::parse(text, name) {
        Err(e) => e,
        Ok(sc) => match efgdem::run::check(&sc) {
            Err(RunError::Scenario(e)) => e,
            Err(e) => panic!("{name}: not a scenario error: {e}"),
            Ok(report) => panic!("{name}: accepted:\n{report}"),
        },
    };
    assert_located(&e, name, text);
    e.to_string()
}

/// The Timoshenko cantilever of `examples/timoshenko.toml`, static, with
/// `size` and the right edge's condition `right`.
fn cantilever(size: &str, right: &str) -> String {
    format!(
        r#"[simulation]
analysis = "static"
[[body]]
name = "beam"
rectangle = {{ origin = [0.0, -6.0], size = [{size}] }}
nodes = [33, 9]
elastic = {{ E = 3.0e7, nu = 0.3 }}
[[body.bc]]
edge = "left"
fixed = true
[[body.bc]]
edge = "right"
{right}
[[probe]]
name = "tip_uy"
point = [0.0, 0.0]
quantity = "uy"
"#
    )
}

/// A 48 × 1e11 rectangle (issue 12: an index panic in the EFG assembly,
/// then a silent run with a 6·10⁷ relative energy error): the node
/// spacings differ by 8·10⁹; refused at the size.
#[test]
fn regression_a_48_by_1e11_rectangle_is_refused_at_its_size() {
    let e = refused(
        "huge.toml",
        &cantilever("48.0, 1e11", "parabolic_shear = -1000.0"),
    );
    assert!(e.starts_with("huge.toml:5: body[0].rectangle.size: the node spacing is 1.500e0 along x and 1.250e10 along y"), "{e}");
    // the same 1e11 along x: K̄ could not be factored at run time (exit 1)
    let e = refused(
        "long.toml",
        &cantilever("1e11, 12.0", "parabolic_shear = -1000.0"),
    );
    assert!(e.contains("long.toml:5: body[0].rectangle.size:"), "{e}");
    // sizes beyond 1e30 overflow products of lengths (an FE body of
    // 48 × 1e300 wrote NaN with exit 0)
    let e = refused(
        "fem.toml",
        &cantilever("48.0, 1e300", "parabolic_shear = -1000.0")
            .replace("[[body]]\n", "[[body]]\nmethod = \"fem-q4\"\n"),
    );
    assert!(
        e.contains("fem.toml:6: body[0].rectangle: coordinates and sizes must be at most 1e30"),
        "{e}"
    );
}

/// `uy = -1e300` prescribed: `efgdem run` wrote NaN to `history.csv` and
/// exited 0. Refused (exit 2, file:line: field) before anything is written.
#[test]
fn regression_a_prescribed_uy_of_minus_1e300_is_refused_and_writes_no_nan() {
    let text = cantilever("48.0, 12.0", "uy = -1e300");
    let e = refused("uy.toml", &text);
    assert!(
        e.starts_with("uy.toml:13: body[0].bc[1].uy: a prescribed displacement of 1e300 is more than 1e6 × the body's size"),
        "{e}"
    );
    // through the command line: exit 2 and no history
    let dir = std::env::temp_dir().join(format!("efgdem-fuzz-uy-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("uy.toml");
    std::fs::write(&f, &text).unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .args([
            "run",
            f.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("uy.toml:13: body[0].bc[1].uy:"), "{err}");
    assert!(!out.join("history.csv").exists());
    // the same field as a linear field, and a motion that runs away
    let e = refused(
        "lin.toml",
        &cantilever("48.0, 12.0", "uy = { linear = [0.0, 1e300, 0.0] }"),
    );
    assert!(
        e.contains("lin.toml:13: body[0].bc[1].uy: a prescribed displacement of"),
        "{e}"
    );
    let dynamic = cantilever("48.0, 12.0", "uy = { velocity = -1e300 }")
        .replace("analysis = \"static\"", "dt = 1e-3\nsteps = 3")
        .replace("nu = 0.3 }", "nu = 0.3, density = 1.0 }");
    let e = refused("motion.toml", &dynamic);
    assert!(
        e.contains("motion.toml:14: body[0].bc[1].uy: the edge would move by 3"),
        "{e}"
    );
    // a small or ordinary displacement is fine
    for ok in ["uy = 1e-300", "uy = -0.1"] {
        let sc = scenario::parse(&cantilever("48.0, 12.0", ok), "ok.toml").unwrap();
        efgdem::run::check(&sc).unwrap();
    }
}

/// Loads of 1e300 (as a stress, more than 10⁶ × E) gave ±1e296
/// displacements; a body's thickness of 1e300 wrote NaN energies.
#[test]
fn regression_absurd_loads_and_thickness_of_a_body_are_refused() {
    let e = refused(
        "t.toml",
        &cantilever("48.0, 12.0", "traction = [0.0, -1e300]"),
    );
    assert!(
        e.contains(
            "t.toml:13: body[0].bc[1].traction: a load of 1e300 (as a stress) is more than 1e6 × E"
        ),
        "{e}"
    );
    let e = refused(
        "p.toml",
        &cantilever("48.0, 12.0", "parabolic_shear = -1e300"),
    );
    assert!(
        e.contains("p.toml:13: body[0].bc[1].parabolic_shear:"),
        "{e}"
    );
    let e = refused(
        "th.toml",
        &cantilever("48.0, 12.0", "parabolic_shear = -1000.0")
            .replace("nu = 0.3 }", "nu = 0.3, thickness = 1e300 }"),
    );
    assert!(
        e.contains("th.toml:7: body[0].elastic.thickness: a length: at most 1e30"),
        "{e}"
    );
}

/// A penalty of 1e300 passes the validation, but K̄ cannot be factored: a
/// static run failed with exit 1 and no line; `check` now solves a static
/// analysis once and reports it at the body.
#[test]
fn regression_a_static_body_that_cannot_be_factored_is_located_by_check() {
    let text = cantilever("48.0, 12.0", "parabolic_shear = -1000.0")
        .replace("nu = 0.3 }", "nu = 0.3 }\npenalty = 1e300");
    let e = refused("pen.toml", &text);
    assert!(
        e.contains("pen.toml:4: body[0]: ") && e.contains("not positive definite"),
        "{e}"
    );
}

/// A coupled scenario (the paper's disc on a beam) with `gravity`,
/// `[granular] thickness` or a disc velocity of 1e300: NaN or inf in
/// `history.csv` with exit 0.
#[test]
fn regression_absurd_gravity_thickness_and_velocities_of_discs_are_refused() {
    let base = r#"[simulation]
dt = 1.0e-4
steps = 5
gravity = [0.0, -9.81]
[[material]]
name = "disc"
density = 1000.0
kn = 1.0e6
ks = 1.0e6
[granular]
material = "disc"
discs = [[0.5, 0.3, 0.05]]
[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [1.0, 0.0]
"#;
    let e = refused("g.toml", &base.replace("[0.0, -9.81]", "[1e300, -9.81]"));
    assert!(e.contains("g.toml:4: simulation.gravity: |g| Δt² = 1.000e292: a disc would fall by more than the smallest radius"), "{e}");
    let e = refused(
        "t.toml",
        &base.replace(
            "material = \"disc\"\n",
            "material = \"disc\"\nthickness = 1e308\n",
        ),
    );
    assert!(
        e.contains("t.toml:12: granular.thickness: disc 1: its mass ρπr²t = inf"),
        "{e}"
    );
    let e = refused(
        "v.toml",
        &base.replace("0.05]]\n", "0.05]]\nvelocity = [0.0, -1e300]\n"),
    );
    assert!(e.contains("v.toml:13: granular.velocity: a disc at the initial velocity moves 1.000e296 in one step"), "{e}");
    let e = refused("w.toml", &format!("{base}velocity = [0.0, 1e300]\n"));
    assert!(
        e.contains("w.toml:17: wall[0].velocity: wall `floor` moves 1.000e296 in one step"),
        "{e}"
    );
    let e = refused(
        "h.toml",
        &format!("{base}history = [[0.0, 0.0, 0.0], [1.0, 1e300, 0.0]]\n"),
    );
    assert!(
        e.contains("h.toml:17: wall[0].history: wall `floor` moves"),
        "{e}"
    );
    // ordinary values pass
    let sc = scenario::parse(base, "ok.toml").unwrap();
    efgdem::run::check(&sc).unwrap();
}

// ---------------------------------------------------------------------------
// Regression tests of issue 26 ("nothing lost and nothing silently wrong"):
// each reproducer below was accepted, crashed or hung before.

/// A static EFG plate with a hole `hole` (the TOML of one hole) and
/// outline `outline`, fixed along its base.
fn plate(outline: &str, hole: &str) -> String {
    format!(
        r#"[simulation]
analysis = "static"
[[body]]
name = "plate"
outline = {outline}
holes = [{hole}]
spacing = 0.1
elastic = {{ E = 1.0e7, nu = 0.3 }}
[body.edges]
base = {{ loop = 0, segments = [0, 0] }}
[[body.bc]]
edge = "base"
fixed = true
"#
    )
}

const SQUARE_4X2: &str = "[[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]]";

/// A circle hole of 2⁶³ − 1 segments panicked (capacity overflow), 2³² + 1
/// aborted, 10⁵–10⁶ hung: refused at the count before anything is
/// allocated, with its line and field.
#[test]
fn regression_absurd_hole_segments_are_refused_at_the_count() {
    for n in ["9223372036854775807", "4294967297", "1000000", "100001"] {
        let t0 = std::time::Instant::now();
        let text = plate(
            SQUARE_4X2,
            &format!("{{ center = [2.0, 1.0], radius = 0.5, segments = {n} }}"),
        );
        let e = refused("hole.toml", &text);
        assert!(
            e.starts_with(&format!(
                "hole.toml:6: body[0].holes[0].segments: {n} vertices/segments: a polygon body has at most 100000 vertices"
            )),
            "{e}"
        );
        assert!(t0.elapsed().as_secs_f64() < 5.0, "{n}");
    }
    // an outline of more
    let text = plate(&ellipse_outline(100_001), "").replace("holes = []\n", "");
    let e = refused("outline.toml", &text);
    assert!(
        e.contains(
            "outline.toml:5: body[0].outline: 100001 vertices: a polygon body has at most 100000"
        ),
        "{e}"
    );
    // 100 000 vertices that cross: the simplicity test (was O(N²), over a
    // minute) finds the crossing at once
    let mut pts: Vec<&str> = Vec::new();
    let outline = ellipse_outline(100_000);
    pts.extend(outline[1..outline.len() - 1].split(", ["));
    pts.swap(500, 501);
    let crossing = format!("[{}]", pts.join(", ["));
    let t0 = std::time::Instant::now();
    let e = refused(
        "cross.toml",
        &plate(&crossing, "").replace("holes = []\n", ""),
    );
    assert!(
        e.starts_with("cross.toml:5: body[0].outline: ") && e.contains("is not simple: segment"),
        "{e}"
    );
    println!(
        "100 000 crossing vertices refused in {:.2} s",
        t0.elapsed().as_secs_f64()
    );
}

/// An ellipse of semi-axes 2 and 1 centred at (2, 1) as an outline of `n`
/// vertices (TOML).
fn ellipse_outline(n: usize) -> String {
    let pts: Vec<String> = (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            format!("[{:.9}, {:.9}]", 2.0 + 2.0 * t.cos(), 1.0 + t.sin())
        })
        .collect();
    format!("[{}]", pts.join(", "))
}

/// A 1 000-segment hole (400 segments took 30 s and 1 000 did not finish
/// in 120 s: O(N²) and worse in the number of segments) and a 10 000-vertex
/// outline (its simplicity test alone was O(N²)) check and solve, and the
/// memory estimate of `check` is within 2× of the peak the run measures
/// (`summary.json`, itself checked against the OS by
/// `tests/memory_peak.rs`). The check's time is printed, not asserted (a
/// benchmark on a shared machine: `cargo test --release --test fuzz
/// large_polygons -- --nocapture`); a regression to the old cost would not
/// finish.
#[test]
fn regression_large_polygons_check_and_their_memory_estimate_holds() {
    let root = std::env::temp_dir().join(format!("efgdem-large-poly-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let cases = [
        (
            "hole1000",
            plate(
                SQUARE_4X2,
                "{ center = [2.0, 1.0], radius = 0.5, segments = 1000 }",
            ),
            "polygon with 1 hole(s)",
        ),
        (
            "outline10000",
            plate(&ellipse_outline(10_000), "")
                .replace("holes = []\n", "")
                .replace("segments = [0, 0]", "segments = [0, 4999]"),
            "polygon with 0 hole(s)",
        ),
    ];
    for (name, text, kind) in cases {
        let file = root.join(format!("{name}.toml"));
        std::fs::write(&file, &text).unwrap();
        let t0 = std::time::Instant::now();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
            .arg("check")
            .arg(&file)
            .output()
            .unwrap();
        let secs = t0.elapsed().as_secs_f64();
        let report = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(report.contains(kind), "{name}: {report}");
        let out = root.join(name);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_efgdem"))
            .args(["run", "-q"])
            .arg(&file)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let peak = summary["peak_memory_bytes"].as_f64().unwrap();
        let sc = scenario::parse(&text, name).unwrap();
        let estimate = scenario::build::memory_estimate(&sc).total();
        println!(
            "{name}: check {secs:.2} s; memory estimate {:.1} MiB, measured peak {:.1} MiB",
            estimate / 1048576.0,
            peak / 1048576.0
        );
        assert!(
            (0.5..=2.0).contains(&(peak / estimate)),
            "{name}: estimate {estimate:e} B, peak {peak:e} B"
        );
    }
    let _ = std::fs::remove_dir_all(&root);
}

/// A 1 000-vertex ellipse fixed all round under its own weight was
/// refused ("not positive definite … is the body fixed somewhere?") or
/// never finished: nodes at every vertex, far closer than the spacing.
/// Now the nodes keep `h/2` apart and the centre's deflection is the exact
/// one of a clamped ellipse in plane stress, `u_y = b_y / (2μ/a² + 2μ/b² +
/// 2(λ* + μ)/b²)` for `u = (0, C (1 − x²/a² − y²/b²))` (λ* = 2λμ/(λ + 2μ)),
/// within 2 % (a 0.1-spacing EFG model of a smooth field).
#[test]
fn regression_a_1000_vertex_ellipse_fixed_all_round_is_solved() {
    let (a, b) = (1.0f64, 0.5f64);
    let pts: Vec<String> = (0..1000)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / 1000.0;
            format!("[{:e}, {:e}]", a * t.cos(), b * t.sin())
        })
        .collect();
    let text = format!(
        r#"[simulation]
analysis = "static"
gravity = [0.0, -10.0]
[[body]]
name = "ellipse"
outline = [{}]
spacing = 0.1
elastic = {{ E = 1.0e6, nu = 0.25, density = 1000.0 }}
[[body.bc]]
edge = "outline"
fixed = true
[[probe]]
name = "uy"
point = [0.0, 0.0]
quantity = "uy"
"#,
        pts.join(", ")
    );
    let sc = scenario::parse(&text, "ellipse.toml").unwrap();
    let out = std::env::temp_dir().join(format!("efgdem-ellipse-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let summary = efgdem::run::run(
        &sc,
        &RunOptions {
            quiet: true,
            ..RunOptions::new(&out)
        },
    )
    .unwrap();
    let _ = std::fs::remove_dir_all(&out);
    let (e, nu, by) = (1.0e6, 0.25, -1000.0 * 10.0);
    let mu = e / (2.0 * (1.0 + nu));
    let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let lambda_star = 2.0 * lambda * mu / (lambda + 2.0 * mu);
    let exact =
        -by / (2.0 * mu / (a * a) + 2.0 * mu / (b * b) + 2.0 * (lambda_star + mu) / (b * b));
    let uy = summary["uy"].as_f64().unwrap();
    assert!(
        ((uy - -exact) / exact).abs() < 0.02,
        "centre u_y = {uy:e}, exact {:e}",
        -exact
    );
}

/// Any table could be written as a positional array: `rectangle = [[0.1,
/// 0.1], [0.3, 0.2]]` on a body was read as origin and size.
#[test]
fn regression_tables_given_as_arrays_are_refused_with_their_field() {
    let e = refused(
        "rect.toml",
        &cantilever("48.0, 12.0", "parabolic_shear = -1000.0").replace(
            "rectangle = { origin = [0.0, -6.0], size = [48.0, 12.0] }",
            "rectangle = [[0.1, 0.1], [0.3, 0.2]]",
        ),
    );
    assert!(
        e.starts_with("rect.toml:5: body[0].rectangle: invalid type: sequence, expected a table"),
        "{e}"
    );
    let e = refused(
        "el.toml",
        &cantilever("48.0, 12.0", "parabolic_shear = -1000.0").replace(
            "elastic = { E = 3.0e7, nu = 0.3 }",
            "elastic = [3.0e7, 0.3]",
        ),
    );
    assert!(
        e.starts_with("el.toml:7: body[0].elastic: invalid type: sequence"),
        "{e}"
    );
    // in an untagged form too: a circle hole, a prescribed drive
    let e = refused("hole.toml", &plate(SQUARE_4X2, "[[2.0, 1.0], 0.5, 24]"));
    assert!(e.contains("hole.toml:6: body[0].holes"), "{e}");
}

/// `from = [inf, 0]` was blamed on `to`; a radius of 1e-308 on the
/// thickness; a vertex of 5e-324 failed with a library's error name.
#[test]
fn regression_errors_name_the_value_that_is_wrong() {
    let walls = |from: &str, r: &str| {
        format!(
            r#"[simulation]
steps = 10
[[material]]
name = "m"
density = 1000.0
kn = 1.0e6
[granular]
material = "m"
discs = [[0.5, 0.5, {r}]]
[[wall]]
name = "w"
from = {from}
to = [1.0, 0.0]
"#
        )
    };
    let e = refused("wall.toml", &walls("[inf, 0.0]", "0.05"));
    assert!(
        e.starts_with("wall.toml:12: wall[0].from: must be two finite numbers (got [inf, 0.0])"),
        "{e}"
    );
    assert!(!e.contains("wall[0].to"), "{e}");
    let e = refused("r.toml", &walls("[0.0, 0.0]", "1e-308"));
    assert!(
        e.starts_with("r.toml:9: granular.discs[0]: disc 1: its mass"),
        "{e}"
    );
    let text = plate(
        "[[5e-324, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]]",
        "{ center = [2.0, 1.0], radius = 0.5 }",
    );
    let sc = scenario::parse(&text, "tiny.toml").unwrap();
    efgdem::run::check(&sc).unwrap();
}

/// A `settle_material` without `kn` passed `check` and failed after the
/// preparation with advice to reduce Δt.
#[test]
fn regression_a_settle_material_without_kn_is_refused_by_check() {
    let text = r#"[simulation]
steps = 10
gravity = [0.0, -9.81]
[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
[[material]]
name = "soft"
density = 2650.0
[granular]
material = "sand"
discs = { generate = "random", method = "deposit", box = [[0.0, 0.0], [0.1, 0.1]], radius = 0.004, settle_material = "soft" }
[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.1, 0.0]
"#;
    let e = refused("settle.toml", text);
    assert!(
        e.starts_with(
            "settle.toml:9: material[1].kn: material `soft` is the packing's settle_material"
        ),
        "{e}"
    );
}

/// A sudden prescribed jump was reported as an instability with a Δt to
/// try, though no Δt helps.
#[test]
fn regression_a_prescribed_jump_is_named_as_such() {
    let text = cantilever(
        "48.0, 12.0",
        "uy = { table = [[0.0, 0.0], [0.001, 0.0], [0.001, 1.0]] }",
    )
    .replace("analysis = \"static\"", "dt = 1e-4\nsteps = 30")
    .replace("nu = 0.3 }", "nu = 0.3, density = 1.0 }");
    let e = refused("jump.toml", &text);
    assert!(
        e.contains("body[0].bc[1].uy.table: a prescribed jump: the table goes from 0 to 1 at once at t = 0.001"),
        "{e}"
    );
}

/// A servo wall whose ends lie on long servo side walls wrote NaN
/// `wall_stress` from the first step with exit 0: the side walls' far
/// ends, within 10⁻⁹ × their 10⁸ m length of the top wall, were joined to
/// it.
#[test]
fn regression_a_servo_box_with_long_side_walls_stays_finite() {
    let text = r#"[simulation]
steps = 30
[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5
[granular]
material = "sand"
discs = { generate = "hex", box = [[0.0, 0.0], [0.1, 0.1]], radius = [0.002, 0.003] }
[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.1, 0.0]
[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 1.0e8]
servo = { stress = 5.0e4, max_velocity = 0.3 }
[[wall]]
name = "right"
from = [0.1, 0.0]
to = [0.1, 1.0e8]
servo = { stress = 5.0e4, max_velocity = 0.3 }
[[wall]]
name = "top"
from = [0.0, 0.1]
to = [0.1, 0.1]
servo = { stress = 5.0e4, max_velocity = 0.3 }
[[probe]]
name = "top_stress"
wall = "top"
quantity = "wall_stress"
"#;
    let sc = scenario::parse(text, "servo.toml").unwrap();
    let out = std::env::temp_dir().join(format!("efgdem-servo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    match short_run(sc, &out, 30) {
        RunOutcome::Clean => {}
        RunOutcome::NonFinite(row) => panic!("exit 0 with a non-finite row: {row}"),
        RunOutcome::Failed(e) | RunOutcome::Refused(e) | RunOutcome::Panic(e) => panic!("{e}"),
        RunOutcome::Skipped => unreachable!(),
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A `discs_final.csv` cut mid-row (`…,1.58e2,8.` for a radius of 0.855)
/// was accepted as a disc source: a disc ten times too large.
#[test]
fn regression_a_cut_discs_file_is_refused() {
    let dir = std::env::temp_dir().join(format!("efgdem-cutcsv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("cut.csv"),
        "x,y,r\n1.0e0,2.0e0,8.55e-1\n3.0e0,1.58e2,8.",
    )
    .unwrap();
    let text = r#"[simulation]
steps = 10
[[material]]
name = "m"
density = 1000.0
kn = 1.0e6
[granular]
material = "m"
discs = { csv = "cut.csv" }
"#;
    let mut sc = scenario::parse(text, "cut.toml").unwrap();
    sc.base_dir = dir.clone();
    let e = match efgdem::run::check(&sc) {
        Err(RunError::Scenario(e)) => e.to_string(),
        other => panic!("{other:?}"),
    };
    assert!(
        e.contains("granular.discs.csv:") && e.contains("line 3: the last line has no line end"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The memory estimate counted discs, not contacts: a dense stack of
/// overlapping discs estimated at a few hundred bytes per disc used tens
/// of times more. Discs given by their positions are sampled for their
/// contact pairs.
#[test]
fn regression_the_memory_estimate_counts_the_contacts_of_overlapping_discs() {
    let rows = |spacing: f64| {
        let mut s = String::from("[");
        for i in 0..40 {
            for j in 0..40 {
                s.push_str(&format!(
                    "[{}, {}, 0.01], ",
                    i as f64 * spacing,
                    j as f64 * spacing
                ));
            }
        }
        s.push(']');
        s
    };
    let text = |spacing| {
        format!(
            "[simulation]\nsteps = 1\n[[material]]\nname = \"m\"\ndensity = 1.0\nkn = 1.0\n[granular]\nmaterial = \"m\"\nallow_overlap = true\ndiscs = {}\n",
            rows(spacing)
        )
    };
    let apart = scenario::build::memory_estimate(&scenario::parse(&text(0.02), "a.toml").unwrap());
    assert_eq!(apart.extra_pairs, 0.0);
    let stacked =
        scenario::build::memory_estimate(&scenario::parse(&text(0.002), "b.toml").unwrap());
    // ~ π (2r + skin)² / s² ≈ 350 neighbours in range, 175 pairs per disc
    let per_disc = stacked.extra_pairs / 1600.0;
    assert!((100.0..250.0).contains(&per_disc), "{per_disc}");
    assert!(stacked.total() > 10.0 * apart.total());
}
