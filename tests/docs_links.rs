//! The documentation points only at what the repository holds:
//!
//! - every relative link and image of `README.md`, `CHANGELOG.md`,
//!   `examples/README.md` and `docs/**/*.md` names a file or directory of
//!   the repository, and its `#anchor` (if any) is a heading or an
//!   `<a id>` of the page it names;
//! - every file path written in backticks (`src/…`, `tests/…`,
//!   `examples/…`, `docs/…`, `python/…`, `benches/…`, `assets/…`) exists;
//! - no page cites a file outside the repository (`shared/…`) or an issue
//!   number, and no source file cites `shared/…` either.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Files under `dir` (recursively) whose extension is one of `exts`.
fn files_with(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files_with(&p, exts, out);
        } else if p
            .extension()
            .is_some_and(|x| exts.contains(&x.to_str().unwrap()))
        {
            out.push(p);
        }
    }
}

fn pages() -> Vec<PathBuf> {
    let r = root();
    let mut v = vec![
        r.join("README.md"),
        r.join("CHANGELOG.md"),
        r.join("examples/README.md"),
    ];
    files_with(&r.join("docs"), &["md"], &mut v);
    v.sort();
    v
}

/// The page's prose and link syntax, with fenced code blocks blanked
/// (line numbers kept).
fn prose(text: &str) -> Vec<(usize, String)> {
    let mut fenced = false;
    text.lines()
        .enumerate()
        .map(|(i, l)| {
            if l.trim_start().starts_with("```") {
                fenced = !fenced;
                return (i + 1, String::new());
            }
            (i + 1, if fenced { String::new() } else { l.to_string() })
        })
        .collect()
}

/// Inline code spans of a line.
fn code_spans(line: &str) -> Vec<&str> {
    line.split('`').skip(1).step_by(2).collect()
}

/// The line without its code spans.
fn outside_code(line: &str) -> String {
    line.split('`').step_by(2).collect::<Vec<_>>().join(" ")
}

/// Targets of `[text](target)` and `![alt](target)` on a line (links
/// split over lines are joined by the caller).
fn link_targets(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let b = text.as_bytes();
    let mut i = 0;
    while let Some(k) = text[i..].find("](") {
        let start = i + k + 2;
        let mut depth = 1;
        let mut j = start;
        while j < b.len() && depth > 0 {
            match b[j] {
                b'(' => depth += 1,
                b')' => depth -= 1,
                _ => {}
            }
            j += 1;
        }
        let target = text[start..j.saturating_sub(1)].trim();
        let target = target.split_whitespace().next().unwrap_or("");
        out.push(target.trim_matches(['<', '>']).to_string());
        i = j;
    }
    out
}

/// GitHub's (and mdBook's) anchor of a heading: lower case, letters,
/// digits, `-` and `_` kept, spaces to `-`, everything else dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

fn anchors(page: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(page).unwrap();
    let mut set = BTreeSet::new();
    let mut seen = std::collections::BTreeMap::<String, usize>::new();
    for (_, line) in prose(&text) {
        if let Some(h) = line.strip_prefix('#') {
            let s = slug(h.trim_start_matches('#'));
            let n = seen.entry(s.clone()).or_insert(0);
            set.insert(if *n == 0 {
                s.clone()
            } else {
                format!("{s}-{n}")
            });
            *n += 1;
        }
        let mut rest = line.as_str();
        while let Some(k) = rest.find("id=\"") {
            let after = &rest[k + 4..];
            let end = after.find('"').unwrap_or(after.len());
            set.insert(after[..end].to_string());
            rest = &after[end..];
        }
    }
    set
}

fn rel(p: &Path) -> String {
    p.strip_prefix(root()).unwrap().display().to_string()
}

#[test]
fn relative_links_and_anchors_resolve() {
    let mut failures = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        let dir = page.parent().unwrap();
        // join each paragraph so that a link may wrap across lines
        let lines = prose(&text);
        let joined: Vec<(usize, String)> =
            lines.iter().map(|(n, l)| (*n, format!("{l} "))).collect();
        let mut para = String::new();
        let mut first = 0;
        let mut paragraphs = Vec::new();
        for (n, l) in joined {
            if l.trim().is_empty() {
                if !para.is_empty() {
                    paragraphs.push((first, std::mem::take(&mut para)));
                }
            } else {
                if para.is_empty() {
                    first = n;
                }
                para.push_str(&outside_code(&l));
            }
        }
        paragraphs.push((first, para));
        for (line, p) in paragraphs {
            for t in link_targets(&p) {
                if t.is_empty() || t.contains("://") || t.starts_with("mailto:") {
                    continue;
                }
                checked += 1;
                let (file, anchor) = t.split_once('#').unwrap_or((&t, ""));
                let target = if file.is_empty() {
                    page.clone()
                } else {
                    dir.join(file)
                };
                let Ok(target) = target.canonicalize() else {
                    failures.push(format!("{}:{line}: dead link `{t}`", rel(&page)));
                    continue;
                };
                if !target.starts_with(root().canonicalize().unwrap()) {
                    failures.push(format!(
                        "{}:{line}: `{t}` leaves the repository",
                        rel(&page)
                    ));
                    continue;
                }
                let is_md = target.extension().is_some_and(|x| x == "md");
                if !anchor.is_empty() && is_md && !anchors(&target).contains(anchor) {
                    failures.push(format!(
                        "{}:{line}: `{t}`: no heading or id `{anchor}` in {}",
                        rel(&page),
                        rel(&target)
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked > 100, "only {checked} links found");
}

/// A code span that names a file of the repository: starts with one of
/// its top directories, no placeholder or pattern in it.
fn repo_path(span: &str) -> Option<&str> {
    const TOPS: [&str; 7] = [
        "src/",
        "tests/",
        "examples/",
        "docs/",
        "python/",
        "benches/",
        "assets/",
    ];
    let path = span.split([' ', ':', '#']).next()?;
    let path = path.trim_end_matches([',', '.', ')']);
    let placeholder = ['*', '{', '<', '…', '$'];
    (TOPS.iter().any(|t| path.starts_with(t))
        && !path.contains(placeholder)
        && !path.contains("NNN"))
    .then_some(path)
}

#[test]
fn file_paths_in_backticks_exist() {
    let mut failures = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for (line, l) in prose(&text) {
            for span in code_spans(&l) {
                if let Some(p) = repo_path(span) {
                    checked += 1;
                    if !root().join(p).exists() {
                        failures.push(format!(
                            "{}:{line}: `{p}` is not in the repository",
                            rel(&page)
                        ));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked > 50, "only {checked} paths found");
}

/// `issue 12`, `Issue 4`, `issues 3 and 5`: a reader cannot look them up.
fn cites_an_issue(line: &str) -> bool {
    let lower = line.to_lowercase();
    let mut rest = lower.as_str();
    while let Some(k) = rest.find("issue") {
        let after = rest[k + 5..].trim_start_matches('s').trim_start();
        if after.starts_with(|c: char| c.is_ascii_digit()) {
            return true;
        }
        rest = &rest[k + 5..];
    }
    false
}

#[test]
fn no_page_cites_outside_files_or_issue_numbers() {
    let mut failures = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        for (n, l) in text.lines().enumerate() {
            if l.contains("shared/") {
                failures.push(format!("{}:{}: cites shared/: {l}", rel(&page), n + 1));
            }
            if cites_an_issue(l) {
                failures.push(format!("{}:{}: cites an issue: {l}", rel(&page), n + 1));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn no_source_cites_files_outside_the_repository() {
    let mut files = Vec::new();
    for d in ["src", "tests", "examples", "benches", "python"] {
        files_with(&root().join(d), &["rs", "toml", "py", "pyi"], &mut files);
    }
    let needle = ["shared", "/paper/"].concat();
    let failures: Vec<String> = files
        .iter()
        .filter(|f| std::fs::read_to_string(f).unwrap().contains(&needle))
        .map(|f| rel(f))
        .collect();
    assert!(failures.is_empty(), "cite {needle}: {failures:?}");
}

#[test]
fn the_checks_see_what_they_should() {
    assert_eq!(slug(" `[[probe]]`"), "probe");
    assert_eq!(
        slug(" Runs that stop, and restarts"),
        "runs-that-stop-and-restarts"
    );
    assert_eq!(
        link_targets("a [b](c.md#d) and ![e](f.png)"),
        ["c.md#d", "f.png"]
    );
    assert!(cites_an_issue("see also issue 14"));
    assert!(!cites_an_issue("an issue of the paper"));
    assert_eq!(
        repo_path("tests/docs_links.rs::x"),
        Some("tests/docs_links.rs")
    );
    assert_eq!(repo_path("frames/<body>_NNNNNNN.vtu"), None);
}

/// Every paper correction the code cites ("ERRATA E7") is explained on
/// the theory page under its anchor (`docs/theory.md#e7`).
#[test]
fn every_cited_correction_is_on_the_theory_page() {
    let theory = anchors(&root().join("docs/theory.md"));
    let mut files = Vec::new();
    files_with(&root().join("src"), &["rs"], &mut files);
    let mut cited = BTreeSet::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (k, _) in text.match_indices("ERRATA E") {
            let digits: String = text[k + 8..]
                .chars()
                .take_while(|c| c.is_ascii_digit())
                .collect();
            cited.insert(format!("e{digits}"));
        }
    }
    assert!(cited.len() >= 10, "{cited:?}");
    let missing: Vec<_> = cited.difference(&theory).collect();
    assert!(
        missing.is_empty(),
        "not explained in docs/theory.md: {missing:?}"
    );
}

/// The Rust API page shows the library's own doc test (`src/lib.rs`),
/// not a copy that could drift from it.
#[test]
fn the_rust_api_page_shows_the_doc_test() {
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).unwrap();
    let code: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| l.strip_prefix(' ').unwrap_or(l))
        .skip_while(|l| !l.starts_with("```"))
        .skip(1)
        .take_while(|l| !l.starts_with("```"))
        .filter(|l| !l.starts_with("# "))
        .collect();
    assert!(code.len() > 10);
    let page = std::fs::read_to_string(root().join("docs/reference/rust-api.md")).unwrap();
    assert!(
        page.contains(&code.join("\n")),
        "docs/reference/rust-api.md does not show src/lib.rs's doc test as it is"
    );
}
