//! The main job right after the tests must not compile the dependencies a
//! second time. Cargo builds a crate once per set of enabled features; a
//! dev-dependency that switches on more features of a crate the library
//! also uses makes `cargo test` and `cargo build` build that crate (and
//! all that depends on it: faer, rayon, …) twice. This test resolves the
//! features both ways with `cargo tree` and requires them to be equal for
//! every crate the library uses (Cargo.toml enables the dev-dependencies'
//! extra features in `[dependencies]`).

use std::collections::BTreeMap;
use std::process::Command;

/// `package version` → features, as `cargo tree` resolves them with
/// `edges` (`no-dev`: `cargo build`; `all`: `cargo test`).
fn features(edges: &str) -> BTreeMap<String, String> {
    let out = Command::new(env!("CARGO"))
        .args(["tree", "--offline", "--prefix", "none", "--no-dedupe"])
        .args(["-e", edges, "-f", "{p}|{f}", "-p", "efgdem"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let (p, f) = l.split_once('|')?;
            // `name vX.Y.Z`, without a path or `(proc-macro)`
            let p: Vec<&str> = p.split_whitespace().take(2).collect();
            Some((p.join(" "), f.trim().to_string()))
        })
        .collect()
}

#[test]
fn the_tests_and_the_main_build_enable_the_same_features() {
    let (build, test) = (features("no-dev"), features("all"));
    assert!(build.len() > 50, "{build:?}");
    let differ: Vec<String> = build
        .iter()
        .filter_map(|(p, f)| {
            let t = test.get(p)?;
            (t != f).then(|| format!("{p}: `cargo build` [{f}], `cargo test` [{t}]"))
        })
        .collect();
    assert!(
        differ.is_empty(),
        "dev-dependencies enable other features of these crates, so the main build after the tests compiles them again; enable the same features in [dependencies]:\n{}",
        differ.join("\n")
    );
}
