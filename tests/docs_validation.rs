//! The Validation page (`docs/validation.md`) states only what the tests
//! assert: in every table with a *bound* and a *test* column, each row
//! names a test that exists (`tests/FILE.rs::function`), each bound (a
//! code span in the *bound* column) is written in that test file, and a
//! row is marked *(slow)* exactly when its test is `#[ignore]`d.

use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn cells(line: &str) -> Vec<String> {
    // split on `|` outside code spans (`\|` inside a cell stays)
    let mut out = vec![String::new()];
    let mut code = false;
    let mut prev = ' ';
    for c in line.trim().trim_matches('|').chars() {
        match c {
            '`' => code = !code,
            '|' if !code && prev != '\\' => {
                out.push(String::new());
                prev = c;
                continue;
            }
            _ => {}
        }
        out.last_mut().unwrap().push(c);
        prev = c;
    }
    out.iter().map(|s| s.trim().to_string()).collect()
}

fn code_spans(cell: &str) -> Vec<&str> {
    cell.split('`').skip(1).step_by(2).collect()
}

/// Whether `fn name(` in `src` is a test marked `#[ignore]`; None if it
/// is not there.
fn ignored(src: &str, name: &str) -> Option<bool> {
    let at = src.find(&format!("fn {name}("))?;
    let before: Vec<&str> = src[..at].lines().rev().take(4).collect();
    Some(
        before
            .iter()
            .any(|l| l.trim_start().starts_with("#[ignore")),
    )
}

#[test]
fn the_validation_table_is_what_the_tests_assert() {
    let page = std::fs::read_to_string(root().join("docs/validation.md")).unwrap();
    let mut failures = Vec::new();
    let mut rows = 0;
    let mut header: Option<(usize, usize)> = None;
    for (n, line) in page.lines().enumerate() {
        let n = n + 1;
        if !line.trim_start().starts_with('|') {
            header = None;
            continue;
        }
        let c = cells(line);
        if c.iter().all(|x| x.chars().all(|ch| ch == '-' || ch == ':')) {
            continue;
        }
        let Some((bound, test)) = header else {
            let find = |w: &str| c.iter().position(|x| x == w);
            header = find("bound").zip(find("test"));
            if header.is_none() {
                header = Some((usize::MAX, usize::MAX));
            }
            continue;
        };
        if bound == usize::MAX {
            continue;
        }
        rows += 1;
        let slow = c[0].contains("*(slow");
        let tests: Vec<&str> = code_spans(&c[test])
            .into_iter()
            .filter(|s| s.starts_with("tests/"))
            .collect();
        if tests.is_empty() {
            failures.push(format!("docs/validation.md:{n}: no test named"));
        }
        for t in tests {
            let (file, func) = t.split_once("::").unwrap_or((t, ""));
            let Ok(src) = std::fs::read_to_string(root().join(file)) else {
                failures.push(format!("docs/validation.md:{n}: no file {file}"));
                continue;
            };
            if !func.is_empty() {
                match ignored(&src, func) {
                    None => {
                        failures.push(format!("docs/validation.md:{n}: no `fn {func}` in {file}"))
                    }
                    Some(ig) if ig != slow => failures.push(format!(
                        "docs/validation.md:{n}: {t} is {}#[ignore]d but the row says {}",
                        if ig { "" } else { "not " },
                        if slow { "(slow)" } else { "nothing" }
                    )),
                    _ => {}
                }
            }
            let bounds = code_spans(&c[bound]);
            if bounds.is_empty() {
                failures.push(format!("docs/validation.md:{n}: no bound in `code`"));
            }
            for b in bounds {
                if !src.contains(b) {
                    failures.push(format!(
                        "docs/validation.md:{n}: bound `{b}` is not in {file}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(rows >= 40, "only {rows} validation rows found");
}
