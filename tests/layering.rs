//! The crate's layers (README, "Architecture"): each module uses only the
//! layers below it. Checked on the source text (code lines, not comments):
//! a `crate::<module>` path or a `use` of a higher layer fails the test.

use std::path::Path;

/// Layers from the bottom; a module may use modules of lower layers only.
const LAYERS: &[&[&str]] = &[
    &["geom", "sparse", "strict"],
    &["continuum"],
    &["efg", "fem", "dem"],
    &["coupling"],
    &["decomp"],
    &["model"],
    &["scenario"],
    &["output"],
    &["run"],
    &["study", "reproduce", "biaxial", "geotech"],
];

fn layer_of(module: &str) -> usize {
    LAYERS
        .iter()
        .position(|l| l.contains(&module))
        .unwrap_or_else(|| panic!("module `{module}` is in no layer: add it to LAYERS"))
}

/// The code lines of a file (comments and doc comments dropped).
fn code_of(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .map(|l| format!("{l}\n"))
        .collect()
}

/// Code lines of every `.rs` file under `dir` (comments and doc comments dropped).
fn sources(dir: &Path, out: &mut Vec<(String, String)>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push((p.display().to_string(), code_of(&p)));
        }
    }
}

#[test]
fn every_module_uses_only_lower_layers() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut violations = Vec::new();
    for layer in LAYERS {
        for module in *layer {
            let mut files = Vec::new();
            let dir = src.join(module);
            if dir.is_dir() {
                sources(&dir, &mut files);
            } else {
                let f = src.join(format!("{module}.rs"));
                files.push((f.display().to_string(), code_of(&f)));
            }
            let own = layer_of(module);
            for (file, code) in &files {
                for other in LAYERS.iter().flat_map(|l| l.iter()) {
                    if *other == *module {
                        continue;
                    }
                    let used = code.contains(&format!("crate::{other}::"))
                        || code.contains(&format!("crate::{other};"))
                        || code.contains(&format!("crate::{other}}}"))
                        || code.contains(&format!("crate::{{{other}"))
                        || code.contains(&format!(", {other}::")) && code.contains("use crate::{");
                    // a module of the same layer is not a lower layer either
                    if used && layer_of(other) >= own {
                        violations.push(format!("{file}: `{module}` uses `{other}`"));
                    }
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "layering violations:\n{}",
        violations.join("\n")
    );
}

/// The two continuum methods and the granular physics know neither each
/// other nor files: no serde schema types, no writers, no progress bars.
#[test]
fn physics_modules_know_no_files() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    for module in ["continuum", "efg", "fem", "dem", "coupling"] {
        let mut files = Vec::new();
        sources(&src.join(module), &mut files);
        for (file, code) in files {
            for banned in ["indicatif", "std::fs::", "File::create", "toml::"] {
                assert!(!code.contains(banned), "{file} uses `{banned}`");
            }
        }
    }
}
