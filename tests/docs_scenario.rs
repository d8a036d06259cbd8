//! The scenario manual cannot fall behind the code:
//!
//! - every field of the scenario types (the `Deserialize` structs and enums
//!   in `src/scenario/` and the continuum value types it embeds, as serde
//!   names them) appears in `docs/scenario.md`
//!   as a field name in backticks, and every value of a named enum (e.g.
//!   `"critical-ratio"`) appears in backticks;
//! - every ```` ```toml ```` block of the manual that starts with
//!   `# complete scenario` passes `efgdem check`; every other one is valid
//!   TOML;
//! - the *example* column of each table passes `efgdem check` once inserted
//!   into a small scenario of the kind named by the `<!-- examples: … -->`
//!   comment above the table;
//! - every tutorial scenario in `docs/tutorial/` passes `efgdem check`, and
//!   the TOML excerpts in `docs/tutorial.md` are copied from them.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn manual() -> String {
    std::fs::read_to_string(root().join("docs/scenario.md")).expect("docs/scenario.md")
}

/// `efgdem check FILE`: Ok(stdout) or Err(stderr).
fn check(file: &Path) -> Result<String, String> {
    let out = Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .arg("check")
        .arg(file)
        .output()
        .expect("efgdem runs");
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).into_owned())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

fn scratch_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("efgdem-docs-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

// ---------------------------------------------------------------------------
// A small lexer and item scanner for the scenario sources (no `syn`).

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    Str(String),
    Punct(char),
}

/// Identifiers (and numbers), string literals and punctuation; comments,
/// char literals and lifetimes dropped.
fn lex(src: &str) -> Vec<Tok> {
    let c: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < c.len() && !(c[i] == '*' && c[i + 1] == '/') {
                i += 1;
            }
            i += 2;
        } else if ch == '"' {
            let mut s = String::new();
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    i += 1;
                }
                if i < c.len() {
                    s.push(c[i]);
                }
                i += 1;
            }
            i += 1;
            out.push(Tok::Str(s));
        } else if ch == 'r' && matches!(c.get(i + 1), Some('"') | Some('#')) && {
            // raw string r"…" or r#"…"#
            let mut j = i + 1;
            while c.get(j) == Some(&'#') {
                j += 1;
            }
            c.get(j) == Some(&'"')
        } {
            let mut j = i + 1;
            let mut hashes = 0;
            while c[j] == '#' {
                hashes += 1;
                j += 1;
            }
            j += 1;
            let start = j;
            loop {
                if j >= c.len() {
                    break;
                }
                if c[j] == '"' && (0..hashes).all(|h| c.get(j + 1 + h) == Some(&'#')) {
                    break;
                }
                j += 1;
            }
            out.push(Tok::Str(c[start..j.min(c.len())].iter().collect()));
            i = j + 1 + hashes;
        } else if ch == '\'' {
            // char literal ('x', '\n', '\'') or lifetime ('a)
            if c.get(i + 1) == Some(&'\\') {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
        } else if ch.is_alphanumeric() || ch == '_' {
            let mut s = String::new();
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                s.push(c[i]);
                i += 1;
            }
            out.push(Tok::Ident(s));
        } else {
            out.push(Tok::Punct(ch));
            i += 1;
        }
    }
    out
}

/// The tokens of one `#[…]` attribute starting at `i` (at `#`), and the
/// index after it.
fn attribute(t: &[Tok], i: usize) -> (Vec<Tok>, usize) {
    let mut j = i + 1;
    if t.get(j) == Some(&Tok::Punct('!')) {
        j += 1;
    }
    let mut depth = 0;
    let start = j;
    while j < t.len() {
        match t[j] {
            Tok::Punct('[') => depth += 1,
            Tok::Punct(']') => {
                depth -= 1;
                if depth == 0 {
                    return (t[start + 1..j].to_vec(), j + 1);
                }
            }
            _ => {}
        }
        j += 1;
    }
    (t[start..].to_vec(), j)
}

/// The value of `key = "…"` inside `serde(…)` attributes.
fn serde_str(attrs: &[Vec<Tok>], key: &str) -> Option<String> {
    for a in attrs {
        if a.first() != Some(&Tok::Ident("serde".into())) {
            continue;
        }
        for w in a.windows(3) {
            if let [Tok::Ident(k), Tok::Punct('='), Tok::Str(v)] = w
                && k == key
            {
                return Some(v.clone());
            }
        }
    }
    None
}

/// Does a `serde(…)` attribute contain the bare word `word` (e.g. `skip`)?
fn serde_flag(attrs: &[Vec<Tok>], word: &str) -> bool {
    attrs.iter().any(|a| {
        a.first() == Some(&Tok::Ident("serde".into()))
            && a.iter().enumerate().any(|(k, x)| {
                *x == Tok::Ident(word.into()) && a.get(k + 1) != Some(&Tok::Punct('='))
            })
    })
}

fn derives_deserialize(attrs: &[Vec<Tok>]) -> bool {
    attrs.iter().any(|a| {
        a.first() == Some(&Tok::Ident("derive".into()))
            && a.iter().any(|x| *x == Tok::Ident("Deserialize".into()))
    })
}

/// Serde's `rename_all` rule applied to a Rust name (field: snake_case,
/// variant: PascalCase).
fn rename_all(name: &str, rule: Option<&str>) -> String {
    let words: Vec<String> = if name.contains('_') || name.chars().all(|c| !c.is_uppercase()) {
        name.split('_').map(str::to_lowercase).collect()
    } else {
        let mut w = vec![];
        let mut cur = String::new();
        for ch in name.chars() {
            if ch.is_uppercase() && !cur.is_empty() {
                w.push(std::mem::take(&mut cur));
            }
            cur.extend(ch.to_lowercase());
        }
        w.push(cur);
        w
    };
    match rule {
        None => name.to_string(),
        Some("lowercase") => name.to_lowercase(),
        Some("UPPERCASE") => name.to_uppercase(),
        Some("snake_case") => words.join("_"),
        Some("kebab-case") => words.join("-"),
        Some("SCREAMING_SNAKE_CASE") => words.join("_").to_uppercase(),
        Some(r) => panic!("rename_all = {r:?} not handled by this test: extend `rename_all`"),
    }
}

/// Index of the token closing the bracket opened at `i`.
fn closing(t: &[Tok], i: usize) -> usize {
    let (open, close) = match t[i] {
        Tok::Punct('{') => ('{', '}'),
        Tok::Punct('(') => ('(', ')'),
        Tok::Punct('[') => ('[', ']'),
        _ => panic!("not a bracket"),
    };
    let mut depth = 0;
    for (j, x) in t.iter().enumerate().skip(i) {
        if *x == Tok::Punct(open) {
            depth += 1;
        } else if *x == Tok::Punct(close) {
            depth -= 1;
            if depth == 0 {
                return j;
            }
        }
    }
    t.len()
}

/// Named fields between braces (`body` without the braces): `name: Type`
/// at nesting depth 0, with their attributes.
fn named_fields(body: &[Tok], rule: Option<&str>) -> Vec<String> {
    let mut out = vec![];
    let mut attrs = vec![];
    let mut depth = 0i32;
    let mut i = 0;
    while i < body.len() {
        match &body[i] {
            Tok::Punct('#') if depth == 0 => {
                let (a, j) = attribute(body, i);
                attrs.push(a);
                i = j;
                continue;
            }
            Tok::Punct('(' | '[' | '{' | '<') => depth += 1,
            Tok::Punct(')' | ']' | '}' | '>') => depth -= 1,
            Tok::Punct(',') if depth == 0 => attrs.clear(),
            Tok::Ident(name)
                if depth == 0
                    && body.get(i + 1) == Some(&Tok::Punct(':'))
                    && body.get(i + 2) != Some(&Tok::Punct(':'))
                    && (i == 0 || body[i - 1] != Tok::Punct(':'))
                    && !serde_flag(&attrs, "skip")
                    && !serde_flag(&attrs, "flatten") =>
            {
                out.push(serde_str(&attrs, "rename").unwrap_or_else(|| rename_all(name, rule)));
            }
            _ => {}
        }
        i += 1;
    }
    out
}

#[derive(Debug, Default)]
struct Names {
    /// (type, field name as written in a scenario file)
    fields: Vec<(String, String)>,
    /// (type, enum value as written in a scenario file)
    values: Vec<(String, String)>,
    types: BTreeSet<String>,
}

fn scan(src: &str, names: &mut Names) {
    let t = lex(src);
    let mut attrs: Vec<Vec<Tok>> = vec![];
    let mut i = 0;
    while i < t.len() {
        match &t[i] {
            Tok::Punct('#') => {
                let (a, j) = attribute(&t, i);
                attrs.push(a);
                i = j;
                continue;
            }
            Tok::Ident(kw) if kw == "struct" || kw == "enum" => {
                let Some(Tok::Ident(ty)) = t.get(i + 1) else {
                    i += 1;
                    continue;
                };
                let ty = ty.clone();
                // the body: the first `{` before any `;` or `(` (tuple struct)
                let mut j = i + 2;
                while j < t.len() && !matches!(t[j], Tok::Punct('{' | ';' | '(')) {
                    j += 1;
                }
                if j >= t.len() || t[j] != Tok::Punct('{') || !derives_deserialize(&attrs) {
                    attrs.clear();
                    i = j;
                    continue;
                }
                let end = closing(&t, j);
                let body = &t[j + 1..end];
                let rule = serde_str(&attrs, "rename_all");
                names.types.insert(ty.clone());
                if kw == "struct" {
                    for f in named_fields(body, rule.as_deref()) {
                        names.fields.push((ty.clone(), f));
                    }
                } else {
                    let untagged = serde_flag(&attrs, "untagged");
                    if let Some(tag) = serde_str(&attrs, "tag") {
                        names.fields.push((ty.clone(), tag));
                    }
                    if let Some(tag) = serde_str(&attrs, "content") {
                        names.fields.push((ty.clone(), tag));
                    }
                    let fields_rule = serde_str(&attrs, "rename_all_fields");
                    // variants: Ident at depth 0, with their attributes
                    let mut vattrs = vec![];
                    let mut k = 0;
                    while k < body.len() {
                        match &body[k] {
                            Tok::Punct('#') => {
                                let (a, n) = attribute(body, k);
                                vattrs.push(a);
                                k = n;
                                continue;
                            }
                            Tok::Ident(v) => {
                                if !untagged && !serde_flag(&vattrs, "skip") {
                                    let name = serde_str(&vattrs, "rename")
                                        .unwrap_or_else(|| rename_all(v, rule.as_deref()));
                                    names.values.push((ty.clone(), name));
                                }
                                // skip the variant's payload up to the next `,`
                                let mut n = k + 1;
                                if let Some(Tok::Punct('{')) = body.get(n) {
                                    let e = closing(body, n);
                                    for f in named_fields(&body[n + 1..e], fields_rule.as_deref()) {
                                        names.fields.push((ty.clone(), f));
                                    }
                                    n = e + 1;
                                } else if let Some(Tok::Punct('(')) = body.get(n) {
                                    n = closing(body, n) + 1;
                                }
                                while n < body.len() && body[n] != Tok::Punct(',') {
                                    n += 1;
                                }
                                vattrs.clear();
                                k = n + 1;
                                continue;
                            }
                            _ => {}
                        }
                        k += 1;
                    }
                }
                attrs.clear();
                i = end + 1;
                continue;
            }
            Tok::Ident(w) if w == "pub" || w == "crate" => {}
            Tok::Punct('(' | ')') => {}
            _ => attrs.clear(),
        }
        i += 1;
    }
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn scenario_names() -> Names {
    let mut files = vec![];
    // the schema: src/scenario/, and the continuum's value types it embeds
    // (rectangle, elastic, edge conditions, prescribed motions) — not the
    // continuum's saved state (checkpoints), which is serde too
    rust_files(&root().join("src/scenario"), &mut files);
    for f in ["body_params.rs", "conditions.rs", "drive.rs"] {
        files.push(root().join("src/continuum").join(f));
    }
    files.sort();
    let mut names = Names::default();
    for f in &files {
        scan(&std::fs::read_to_string(f).unwrap(), &mut names);
    }
    // the scanner must see the types it is meant to check
    for ty in ["Scenario", "Simulation", "Material", "Probe", "Output"] {
        assert!(
            names.types.contains(ty),
            "the scanner found no Deserialize type `{ty}` under src/scenario/ (found {:?}); \
             if it moved, point this test at its new place",
            names.types
        );
    }
    assert!(names.types.len() >= 15, "{:?}", names.types);
    names
}

/// The backtick spans of a Markdown text (`` `…` `` and ``` ``…`` ```),
/// outside fenced code blocks; table escapes `\|` undone.
fn code_spans(md: &str) -> Vec<String> {
    let mut out = vec![];
    let mut in_fence = false;
    // a code span may continue on the next line of its paragraph
    let mut para = String::new();
    for line in md.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            out.extend(spans_of(&std::mem::take(&mut para)));
            continue;
        }
        if in_fence {
            continue;
        }
        if line.trim().is_empty() || line.trim_start().starts_with('|') {
            out.extend(spans_of(&std::mem::take(&mut para)));
            out.extend(spans_of(line));
        } else {
            para.push_str(line);
            para.push(' ');
        }
    }
    out.extend(spans_of(&para));
    out
}

fn spans_of(text: &str) -> Vec<String> {
    let b: Vec<char> = text.chars().collect();
    let mut out = vec![];
    let mut i = 0;
    while i < b.len() {
        if b[i] != '`' {
            i += 1;
            continue;
        }
        let mut n = 0;
        while i + n < b.len() && b[i + n] == '`' {
            n += 1;
        }
        let start = i + n;
        let mut j = start;
        let mut found = None;
        while j < b.len() {
            if b[j] == '`' {
                let mut m = 0;
                while j + m < b.len() && b[j + m] == '`' {
                    m += 1;
                }
                if m == n {
                    found = Some(j);
                    break;
                }
                j += m;
            } else {
                j += 1;
            }
        }
        match found {
            Some(e) => {
                let s: String = b[start..e].iter().collect();
                out.push(s.trim().replace("\\|", "|"));
                i = e + n;
            }
            None => i = start,
        }
    }
    out
}

/// Is `field` written as a field in one of the spans: `` `field` ``,
/// `` `field = …` ``, or a section header `` `[field]` `` / `` `[[x.field]]` ``?
fn documents_field(spans: &[String], field: &str) -> bool {
    spans.iter().any(|s| {
        s == field
            || s.strip_prefix(field)
                .is_some_and(|r| r.trim_start().starts_with('='))
            || s == &format!("[{field}]")
            || s == &format!("[[{field}]]")
            || s.ends_with(&format!(".{field}]]"))
    })
}

/// Is `value` one of the words of a span (`"critical-ratio"`, `kind = "local"`)?
fn documents_value(spans: &[String], value: &str) -> bool {
    spans.iter().any(|s| {
        s.split(|c: char| !(c.is_alphanumeric() || c == '_' || c == '-'))
            .any(|w| w == value)
    })
}

#[test]
fn every_scenario_field_is_documented() {
    let names = scenario_names();
    let spans = code_spans(&manual());
    let missing: Vec<String> = names
        .fields
        .iter()
        .filter(|(_, f)| !documents_field(&spans, f))
        .map(|(ty, f)| format!("`{f}` (field of {ty})"))
        .collect();
    assert!(
        missing.is_empty(),
        "docs/scenario.md does not document these scenario fields (write each as `name` or `name = …` in backticks): {}",
        missing.join(", ")
    );
}

#[test]
fn every_enum_value_is_documented() {
    let names = scenario_names();
    let spans = code_spans(&manual());
    let missing: Vec<String> = names
        .values
        .iter()
        .filter(|(_, v)| !documents_value(&spans, v))
        .map(|(ty, v)| format!("`\"{v}\"` (value of {ty})"))
        .collect();
    assert!(
        missing.is_empty(),
        "docs/scenario.md does not document these values: {}",
        missing.join(", ")
    );
}

#[test]
fn the_scanner_reads_serde_names() {
    let names = scenario_names();
    let has = |ty: &str, f: &str| names.fields.iter().any(|(t, x)| t == ty && x == f);
    // renamed fields, tags and fields of struct variants
    assert!(has("Elastic", "E"), "{:?}", names.fields);
    assert!(has("DiscsTable", "box"));
    assert!(has("TimoshenkoSpec", "P"));
    assert!(has("DampingSpec", "kind"));
    assert!(has("DampingSpec", "zeta_shear"));
    assert!(
        !has("Scenario", "base_dir"),
        "serde(skip) fields are not scenario fields"
    );
    let val = |ty: &str, v: &str| names.values.iter().any(|(t, x)| t == ty && x == v);
    assert!(val("DampingSpec", "critical-ratio"));
    assert!(val("Method", "fem-q4"));
    assert!(val("Analysis", "static"));
    assert!(
        !names.values.iter().any(|(t, _)| t == "DiscsSpec"),
        "untagged"
    );
}

// ---------------------------------------------------------------------------
// Examples of the manual.

/// ```` ```toml ```` blocks of the manual: (line of the fence, text).
fn toml_blocks(md: &str) -> Vec<(usize, String)> {
    let mut out = vec![];
    let mut cur: Option<(usize, String)> = None;
    for (k, line) in md.lines().enumerate() {
        let t = line.trim_start();
        match &mut cur {
            None if t.starts_with("```toml") => cur = Some((k + 1, String::new())),
            Some(_) if t.starts_with("```") => out.push(cur.take().unwrap()),
            Some((_, s)) => {
                s.push_str(line);
                s.push('\n');
            }
            None => {}
        }
    }
    out
}

#[test]
fn toml_blocks_of_the_manual_parse() {
    let md = manual();
    let dir = scratch_dir("blocks");
    let mut complete = 0;
    for (line, text) in toml_blocks(&md) {
        if text.starts_with("# complete scenario") {
            complete += 1;
            let f = dir.join(format!("scenario_md_line_{line}.toml"));
            std::fs::write(&f, &text).unwrap();
            if let Err(e) = check(&f) {
                panic!("docs/scenario.md:{line}: the complete scenario fails `efgdem check`:\n{e}");
            }
        } else if let Err(e) = text.parse::<toml::Table>() {
            panic!("docs/scenario.md:{line}: the TOML fragment does not parse:\n{e}");
        }
    }
    assert!(
        complete >= 3,
        "expected the manual's complete scenarios (```toml blocks starting with `# complete scenario`)"
    );
}

const GRANULAR: &str = r#"
[simulation]
steps = 10
gravity = [0.0, -9.81]

[[material]]
name = "sand"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[[material]]
name = "steel"
density = 7800.0
kn = 1.0e7
ks = 5.0e6
friction = 0.3

[granular]
material = "sand"
discs = [[0.1, 0.1, 0.05], [0.2, 0.1, 0.05]]

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [1.0, 0.0]

[[wall]]
name = "lid"
from = [0.0, 1.0]
to = [1.0, 1.0]
"#;

const BODY: &str = r#"
[[body]]
name = "block"
rectangle = { origin = [0.0, 0.15], size = [0.4, 0.1] }
nodes = [9, 3]
elastic = { E = 1.0e7, nu = 0.3, density = 2000.0 }
# dissipative, so that the examples of servo drives pass `check`
newmark = { gamma = 0.6, beta = 0.3025 }

[[body.bc]]
edge = "top"
fixed = true

[[body.bc]]
name = "load"
edge = "top"
traction = [0.0, -1000.0]
"#;

fn base(kind: &str) -> toml::Table {
    let text = match kind {
        "granular" => GRANULAR.to_string(),
        "coupled" => format!("{GRANULAR}\n{BODY}"),
        // the same body alone, fixed on its left edge, dynamic
        "continuum" => format!(
            "[simulation]\ndt = 1.0e-3\nsteps = 10\n{}\n[[body.bc]]\nedge = \"left\"\nfixed = true\n",
            BODY
        ),
        _ => unreachable!(),
    };
    text.parse().unwrap()
}

/// Insert the example `lines` (each `key = value`) for table context `ctx`.
fn with_example(ctx: &str, lines: &[String]) -> Result<toml::Table, String> {
    let mut ex = toml::Table::new();
    for l in lines {
        let t: toml::Table = l
            .parse()
            .map_err(|e| format!("`{l}` is not a TOML `key = value` line: {e}"))?;
        ex.extend(t);
    }
    let (kind, path) = match ctx {
        "simulation" => ("coupled", "simulation"),
        "output" => ("coupled", "output"),
        "material" => ("granular", "material"),
        "granular" => ("granular", "granular"),
        "wall" => ("granular", "wall"),
        "body" => ("coupled", "body"),
        "bc" => ("coupled", "bc"),
        "probe-continuum" => ("continuum", "probe"),
        "probe-granular" => ("granular", "probe"),
        "probe-coupled" => ("coupled", "probe"),
        "measure" => ("granular", "measure"),
        "bonds" => ("granular", "bonds"),
        "clumps" => ("granular", "clumps"),
        _ => return Err(format!("unknown example context `{ctx}`")),
    };
    let mut sc = base(kind);
    let first = |sc: &toml::Table, k: &str| -> toml::Table {
        sc[k].as_array().unwrap()[0].as_table().unwrap().clone()
    };
    let merge = |into: &mut toml::Table, ex: &toml::Table, exclusive: &[(&str, &str)]| {
        for (a, b) in exclusive {
            if ex.contains_key(*a) {
                into.remove(*b);
            }
            if ex.contains_key(*b) {
                into.remove(*a);
            }
        }
        for (k, v) in ex {
            into.insert(k.clone(), v.clone());
        }
    };
    match path {
        "simulation" | "output" | "granular" => {
            let mut t = sc
                .get(path)
                .and_then(|v| v.as_table())
                .cloned()
                .unwrap_or_default();
            merge(&mut t, &ex, &[("steps", "end_time")]);
            sc.insert(path.into(), toml::Value::Table(t));
        }
        "material" | "wall" | "body" => {
            if path == "body" {
                // an example rectangle may cover the base's two discs: the
                // example is about the field, not about the start state
                sc["granular"]
                    .as_table_mut()
                    .unwrap()
                    .insert("allow_overlap".into(), true.into());
            }
            let mut t = first(&sc, path);
            merge(&mut t, &ex, &[("velocity", "history")]);
            sc[path].as_array_mut().unwrap()[0] = toml::Value::Table(t);
        }
        "bc" => {
            let mut bc = toml::Table::new();
            bc.insert("edge".into(), "left".into());
            merge(&mut bc, &ex, &[]);
            let kinds = [
                "fixed",
                "ux",
                "uy",
                "timoshenko",
                "traction",
                "parabolic_shear",
            ];
            if !kinds.iter().any(|k| bc.contains_key(*k)) {
                bc.insert("fixed".into(), true.into());
            }
            let body = sc["body"].as_array_mut().unwrap()[0]
                .as_table_mut()
                .unwrap();
            body["bc"]
                .as_array_mut()
                .unwrap()
                .push(toml::Value::Table(bc));
        }
        "measure" => {
            let mut m = toml::Table::new();
            m.insert("name".into(), "m".into());
            merge(&mut m, &ex, &[]);
            if !m.contains_key("rectangle") && !m.contains_key("centre") {
                m.insert(
                    "rectangle".into(),
                    "[[0.0, 0.0], [0.3, 0.2]]".parse::<toml::Value>().unwrap(),
                );
            }
            sc.insert(
                "measure".into(),
                toml::Value::Array(vec![toml::Value::Table(m)]),
            );
        }
        "bonds" => {
            let mut b: toml::Table = "kn = 2.0e11\nks = 1.0e11\ntensile = 5.0e6\nshear = 1.0e7"
                .parse()
                .unwrap();
            merge(&mut b, &ex, &[("cohesion", "shear")]);
            sc.insert("bonds".into(), toml::Value::Table(b));
        }
        "clumps" => {
            let mut c: toml::Table = "members = [[1, 2]]".parse().unwrap();
            merge(&mut c, &ex, &[("template", "members")]);
            sc.insert("clumps".into(), toml::Value::Table(c));
        }
        "probe" => {
            let mut p = toml::Table::new();
            p.insert("name".into(), "p".into());
            merge(&mut p, &ex, &[]);
            sc.entry("probe")
                .or_insert_with(|| toml::Value::Array(vec![]))
                .as_array_mut()
                .unwrap()
                .push(toml::Value::Table(p));
        }
        _ => unreachable!(),
    }
    Ok(sc)
}

/// Split a Markdown table row into cells (`\|` is not a separator).
fn cells(row: &str) -> Vec<String> {
    let r = row.trim().trim_start_matches('|').trim_end_matches('|');
    let mut out = vec![];
    let mut cur = String::new();
    let mut prev = ' ';
    for ch in r.chars() {
        if ch == '|' && prev != '\\' {
            out.push(std::mem::take(&mut cur));
        } else {
            cur.push(ch);
        }
        prev = ch;
    }
    out.push(cur);
    out.into_iter().map(|c| c.trim().to_string()).collect()
}

#[test]
fn table_examples_pass_check() {
    let md = manual();
    let dir = scratch_dir("tables");
    // for `discs = { csv = "bed.csv" }`
    std::fs::write(dir.join("bed.csv"), "x,y,r\n0.1,0.1,0.05\n0.2,0.1,0.05\n").unwrap();
    let lines: Vec<&str> = md.lines().collect();
    let mut checked = 0;
    let mut failures = vec![];
    let mut k = 0;
    while k < lines.len() {
        let l = lines[k].trim();
        let Some(ctxs) = l
            .strip_prefix("<!-- examples:")
            .and_then(|s| s.strip_suffix("-->"))
        else {
            k += 1;
            continue;
        };
        let ctxs: Vec<&str> = ctxs.split_whitespace().collect();
        let header = cells(lines[k + 1]);
        let col = header
            .iter()
            .position(|h| h == "example")
            .unwrap_or_else(|| {
                panic!(
                    "docs/scenario.md:{}: table without an `example` column",
                    k + 2
                )
            });
        let mut r = k + 3;
        while r < lines.len() && lines[r].trim_start().starts_with('|') {
            let row = cells(lines[r]);
            let ex = spans_of(row.get(col).map(String::as_str).unwrap_or(""));
            if ex.is_empty() {
                failures.push(format!("docs/scenario.md:{}: no example", r + 1));
            }
            for ctx in &ctxs {
                match with_example(ctx, &ex) {
                    Err(e) => failures.push(format!("docs/scenario.md:{}: {e}", r + 1)),
                    Ok(sc) => {
                        let f = dir.join(format!("line_{}_{ctx}.toml", r + 1));
                        std::fs::write(&f, toml::to_string(&sc).unwrap()).unwrap();
                        if let Err(e) = check(&f) {
                            failures.push(format!(
                                "docs/scenario.md:{}: example {ex:?} in a {ctx} scenario fails `efgdem check`: {}",
                                r + 1,
                                e.trim()
                            ));
                        }
                        checked += 1;
                    }
                }
            }
            r += 1;
        }
        k = r;
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked >= 100, "only {checked} table examples found");
}

#[test]
fn tutorial_scenarios_pass_check() {
    let dir = root().join("docs/tutorial");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("docs/tutorial/")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "{files:?}");
    for f in &files {
        if let Err(e) = check(f) {
            panic!("{} fails `efgdem check`:\n{e}", f.display());
        }
    }
}

#[test]
fn tutorial_excerpts_are_from_the_tutorial_files() {
    let dir = root().join("docs/tutorial");
    let files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    let md = std::fs::read_to_string(root().join("docs/tutorial.md")).expect("docs/tutorial.md");
    let blocks = toml_blocks(&md);
    assert!(!blocks.is_empty());
    for (line, text) in blocks {
        assert!(
            files.iter().any(|f| f.contains(text.trim())),
            "docs/tutorial.md:{line}: this excerpt is not (no longer) in any docs/tutorial/*.toml:\n{text}"
        );
    }
}
