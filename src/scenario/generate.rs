//! Disc files: `x,y,r[,material]` CSV read into packing rows.

use crate::dem::packing::DiscRow;
use crate::geom::Vec2;

/// Read discs from CSV text: `x,y,r[,material]` per line, an optional
/// header line, `#` comments and blank lines ignored. Errors name the line.
pub fn discs_from_csv(text: &str) -> Result<Vec<DiscRow>, String> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if out.is_empty() && f[0].parse::<f64>().is_err() && k == first_data_line(text) {
            continue; // header
        }
        if f.len() < 3 || f.len() > 4 {
            return Err(format!(
                "line {}: expected x,y,r[,material], got {} fields",
                k + 1,
                f.len()
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
        let d = discs_from_csv("x,y,r\n0,0,1\n# c\n2.5,0,1,glass\n").unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(d[1].material.as_deref(), Some("glass"));
        let e = discs_from_csv("0,0,1\n1,abc,1\n").unwrap_err();
        assert!(e.contains("line 2"), "{e}");
        assert!(discs_from_csv("0,0,-1\n").is_err());
    }
}
