//! The Validation page (`docs/validation.md`) states only what the tests
//! assert: in every table with a *bound* and a *test* column, each row
//! names a test that exists (`tests/FILE.rs::function`), each bound (a
//! code span in the *bound* column) is written in that test function or a
//! function of its file it calls, and a
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

/// The text of `fn name` in `src`: from its signature to the next item at
/// the file's top level (the whole file when no function is named).
fn function_body<'a>(src: &'a str, name: &str) -> &'a str {
    let Some(at) = (!name.is_empty())
        .then(|| src.find(&format!("fn {name}(")))
        .flatten()
    else {
        return src;
    };
    let rest = &src[at..];
    let end = rest
        .match_indices("\n}")
        .next()
        .map_or(rest.len(), |(i, _)| i + 2);
    &rest[..end]
}

/// The text of `fn name` and of the functions of the same file it calls,
/// and those they call (a test often asserts in a shared helper).
fn with_callees(src: &str, name: &str) -> String {
    let mut seen = vec![name.to_string()];
    let mut text = String::new();
    let mut next = 0;
    while next < seen.len() {
        let body = function_body(src, &seen[next]);
        next += 1;
        text.push_str(body);
        for (at, _) in body.match_indices('(') {
            let start = body[..at]
                .rfind(|c: char| !(c.is_alphanumeric() || c == '_'))
                .map_or(0, |i| {
                    i + body[i..].chars().next().map_or(1, char::len_utf8)
                });
            let callee = &body[start..at];
            if !callee.is_empty()
                && !seen.iter().any(|s| s == callee)
                && src.contains(&format!("fn {callee}("))
            {
                seen.push(callee.to_string());
            }
        }
    }
    text
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
            let body = with_callees(&src, func);
            let bounds = code_spans(&c[bound]);
            if bounds.is_empty() {
                failures.push(format!("docs/validation.md:{n}: no bound in `code`"));
            }
            for b in bounds {
                if !body.contains(b) {
                    failures.push(format!("docs/validation.md:{n}: bound `{b}` is not in {t}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(rows >= 40, "only {rows} validation rows found");
}
