//! Disc files: `x,y,r[,material]` CSV read into packing rows.

use crate::dem::packing::DiscRow;
use crate::geom::Vec2;

/// Read discs from CSV text: `x,y,r[,material]` per line, an optional
/// header line, `#` comments and blank lines ignored. Every data line has
/// the same number of fields (the header's, else the first line's; a row
/// without a material leaves the field empty: `0.1,0.2,0.01,`), and the
/// text ends with a line end: a file cut short (half a row, a disc of the
/// wrong size) is refused, not read. Errors name the line.
pub fn discs_from_csv(text: &str) -> Result<Vec<DiscRow>, String> {
    let mut out = Vec::new();
    // the number of fields, and where it comes from
    let mut width: Option<(usize, &str)> = None;
    for (k, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if out.is_empty() && f[0].parse::<f64>().is_err() && k == first_data_line(text) {
            width = Some((f.len(), "header"));
            continue;
        }
        if f.len() < 3 || f.len() > 4 {
            return Err(format!(
                "line {}: expected x,y,r[,material], got {} fields",
                k + 1,
                f.len()
            ));
        }
        let (want, from) = *width.get_or_insert((f.len(), "first line"));
        if f.len() != want {
            return Err(format!(
                "line {}: {} fields where the {from} has {want} (every line has the same fields; leave a material empty rather than out)",
                k + 1,
                f.len(),
            ));
        }
        let num = |s: &str, what: &str| {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("line {}: {what} `{s}` is not a finite number", k + 1))
        };
        let (x, y, r) = (num(f[0], "x")?, num(f[1], "y")?, num(f[2], "r")?);
        if r <= 0.0 {
            return Err(format!("line {}: radius must be > 0 (got {r})", k + 1));
        }
        out.push(DiscRow {
            pos: Vec2::new(x, y),
            r,
            material: f.get(3).filter(|s| !s.is_empty()).map(|s| s.to_string()),
        });
    }
    if out.is_empty() {
        return Err("no discs in the file".into());
    }
    if !text.ends_with('\n') {
        return Err(format!(
            "line {}: the last line has no line end: the file may have been cut short (if it is whole, end it with a line break)",
            text.lines().count()
        ));
    }
    Ok(out)
}

fn first_data_line(text: &str) -> usize {
    text.lines()
        .position(|l| {
            let l = l.trim();
            !l.is_empty() && !l.starts_with('#')
        })
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_with_header_and_errors() {
        let d = discs_from_csv("x,y,r,material\n0,0,1,\n# c\n2.5,0,1,glass\n").unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(d[0].material, None);
        assert_eq!(d[1].material.as_deref(), Some("glass"));
        // a row of another width, a file cut short
        let e = discs_from_csv("x,y,r\n0,0,1\n2.5,0,1,glass\n").unwrap_err();
        assert!(
            e.starts_with("line 3: 4 fields where the header has 3"),
            "{e}"
        );
        let e = discs_from_csv("0,0,1,a\n2.5,0,1\n").unwrap_err();
        assert!(
            e.starts_with("line 2: 3 fields where the first line has 4"),
            "{e}"
        );
        let e = discs_from_csv("x,y,r\n0,0,1\n2.5,0,8.").unwrap_err();
        assert!(
            e.starts_with("line 3: the last line has no line end"),
            "{e}"
        );
        let e = discs_from_csv("0,0,1\n1,abc,1\n").unwrap_err();
        assert!(e.contains("line 2"), "{e}");
        assert!(discs_from_csv("0,0,-1\n").is_err());
    }
}
