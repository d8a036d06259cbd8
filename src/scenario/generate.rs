//! Disc files: CSV read into packing rows. Without a header the columns
//! are `x,y,r[,material]`; a header line naming its columns (`x`, `y`, `r`,
//! and optionally `material` and `id`, in any order, as `discs_final.csv`
//! writes `x,y,r,id`) is read by name. An `id` column must number the rows
//! 1, 2, 3, … in order: disc numbers are row numbers. Every data line has
//! the same number of fields (the header's, else the first line's; a row
//! without a material leaves the field empty: `0.1,0.2,0.01,`), and the
//! text ends with a line end: a file cut short (half a row, a disc of the
//! wrong size) is refused, not read.

use crate::dem::packing::DiscRow;
use crate::geom::Vec2;

/// Column names a header may use.
/// (`clump`, as `discs_final.csv` writes it for a run with clumps, is read
/// and ignored: clumps come from the `[clumps]` section.)
const NAMES: [&str; 6] = ["x", "y", "r", "material", "id", "clump"];

/// Read discs from CSV text (see the module doc), `#` comments and blank
/// lines ignored. Every data line has the same number of fields (the
/// header's, else the first line's; a row without a material leaves the
/// field empty: `0.1,0.2,0.01,`), and the text ends with a line end: a
/// file cut short (half a row, a disc of the wrong size) is refused, not
/// read. Errors name the line.
pub fn discs_from_csv(text: &str) -> Result<Vec<DiscRow>, String> {
    let mut out = Vec::new();
    // the position of x, y, r, material, id in a row
    let mut cols: [Option<usize>; 6] = [Some(0), Some(1), Some(2), Some(3), None, None];
    let mut named = false;
    // the number of fields, and where it comes from
    let mut width: Option<(usize, &str)> = None;
    for (k, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if out.is_empty() && f[0].parse::<f64>().is_err() && k == first_data_line(text) {
            // `x,y,r` (or `x,y,r,material`) is the positional layout
            if let Some(n) =
                header(&f, k)?.filter(|n| n[..3] != cols[..3] || n[4..].iter().any(Option::is_some))
            {
                (cols, named) = (n, true);
            }
            width = Some((f.len(), "header"));
            continue;
        }
        if !named && !(3..=4).contains(&f.len()) {
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
        let field = |c: usize| cols[c].and_then(|i| f.get(i).copied());
        let num = |c: usize| {
            let s = field(c).unwrap_or("");
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("line {}: {} `{s}` is not a finite number", k + 1, NAMES[c]))
        };
        let (x, y, r) = (num(0)?, num(1)?, num(2)?);
        if r <= 0.0 {
            return Err(format!("line {}: radius must be > 0 (got {r})", k + 1));
        }
        if let Some(id) = field(4) {
            let want = out.len() + 1;
            if id.parse::<usize>().ok() != Some(want) {
                return Err(format!(
                    "line {}: id `{id}` where {want} is expected: disc numbers are row numbers (1, 2, 3, … in order); renumber the rows or leave the id column out",
                    k + 1
                ));
            }
        }
        out.push(DiscRow {
            pos: Vec2::new(x, y),
            r,
            material: field(3).filter(|s| !s.is_empty()).map(|s| s.to_string()),
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

/// The columns a header line names, if it names `x`, `y` and `r`: `None`
/// for another header (skipped; the columns are then positional), an error
/// for a column name read as a disc file's that is unknown or repeated.
fn header(f: &[&str], k: usize) -> Result<Option<[Option<usize>; 6]>, String> {
    let lower: Vec<String> = f.iter().map(|s| s.to_ascii_lowercase()).collect();
    if !["x", "y", "r"].iter().all(|n| lower.iter().any(|c| c == n)) {
        return Ok(None);
    }
    let mut cols = [None; 6];
    for (i, c) in lower.iter().enumerate() {
        let Some(n) = NAMES.iter().position(|n| n == c) else {
            return Err(format!(
                "line {}: unknown column `{}` (a header names x, y, r and optionally material, id and clump)",
                k + 1,
                f[i]
            ));
        };
        if cols[n].replace(i).is_some() {
            return Err(format!("line {}: column `{}` is given twice", k + 1, f[i]));
        }
    }
    Ok(Some(cols))
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

    #[test]
    fn a_header_names_the_columns_and_ids_are_row_numbers() {
        // what discs_final.csv writes
        let d = discs_from_csv("x,y,r,id\n0,0,1,1\n2.5,0,1,2\n").unwrap();
        assert_eq!(d.len(), 2);
        assert_eq!(
            (d[1].pos.x, d[1].r, d[1].material.as_deref()),
            (2.5, 1.0, None)
        );
        let d = discs_from_csv("id,material,r,y,x\n1,glass,0.5,2,3\n").unwrap();
        assert_eq!((d[0].pos.x, d[0].pos.y, d[0].r), (3.0, 2.0, 0.5));
        assert_eq!(d[0].material.as_deref(), Some("glass"));
        let e = discs_from_csv("x,y,r,id\n0,0,1,1\n2.5,0,1,3\n").unwrap_err();
        assert!(e.contains("line 3") && e.contains("row numbers"), "{e}");
        let e = discs_from_csv("x,y,r,q\n0,0,1,1\n").unwrap_err();
        assert!(e.contains("unknown column `q`"), "{e}");
        let e = discs_from_csv("x,y,r,id\n0,0,1\n").unwrap_err();
        assert!(e.contains("3 fields where the header has 4"), "{e}");
        // another header is skipped, as before
        assert_eq!(
            discs_from_csv("X [m],Y [m],R [m]\n0,0,1\n").unwrap().len(),
            1
        );
    }
}
