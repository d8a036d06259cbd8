//! `efgdem reproduce` end to end: every figure, data file and the report
//! are written, and the report carries the numbers the Validation page
//! quotes;
//! the paper's values are shipped with their sources, every run behind a
//! figure is saved, and the report's numbers come from the figures' data.

use efgdem::output::csv::read;
use efgdem::reproduce::{PAPER_VALUES, paper_values};
use std::path::Path;
use std::process::Command;

/// A column of a CSV file.
fn col(path: &Path, name: &str) -> Vec<f64> {
    let (cols, rows) = read(path).unwrap();
    let i = cols
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("{} has no column {name}", path.display()));
    rows.iter().map(|r| r[i]).collect()
}

#[test]
fn reproduce_writes_every_figure_and_the_report() {
    let dir = std::env::temp_dir().join(format!("efgdem-reproduce-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_efgdem"))
        .args(["reproduce", "-q", "-o"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let figures = [
        "fig09_displacements.png",
        "fig10_axial_stress.png",
        "fig11_deflection.png",
        "fig12_contact_force.png",
        "fig12_thin_disc.png",
        "fig14_test1.png",
        "fig14_test2.png",
        "fig15_test1.png",
        "fig15_test2.png",
        "fig17_plate_displacement.png",
    ];
    for f in figures {
        let bytes = std::fs::read(dir.join(f)).unwrap();
        assert_eq!(&bytes[1..4], b"PNG", "{f}");
        assert!(
            bytes.len() > 20_000,
            "{f} looks empty ({} bytes)",
            bytes.len()
        );
    }
    for f in [
        "fig10_axial_stress.csv",
        "fig11_deflection.csv",
        "fig14_15_test1.csv",
        "fig14_15_test2.csv",
        "fig17_plate_displacement.csv",
        "paper_values.csv",
        "runs/ex1_newmark_1.5_0.8/history.csv",
        "runs/nine_disc_efg_test2_E1.0e10/summary.json",
    ] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    // the result (where the report and figures are) on stdout, progress
    // and timing on stderr
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(
        stdout.contains(&format!("report: {}", dir.join("report.md").display())),
        "{stdout}"
    );
    assert!(
        !stderr.contains("report:") && stderr.contains("done in"),
        "{stderr}"
    );
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for needle in [
        "| `ex1_newmark_1.5_0.8`",
        "| `ex1_newmark_0.5_0.25`",
        "| `ex1_thin_disc`",
        "EFG, E = 1.0e10",
        "### Fig. 17",
        "## Figures, their runs and the paper's values",
    ] {
        assert!(report.contains(needle), "report lacks {needle}");
    }
    // Fig. 14 data: the stiff plate follows the rigid plates (validation 4)
    let (cols, rows) = read(&dir.join("fig14_15_test1.csv")).unwrap();
    let (r, e) = (
        cols.iter().position(|c| c == "rigid").unwrap(),
        cols.iter().position(|c| c == "efg_E2.1e14").unwrap(),
    );
    let last = rows.last().unwrap();
    assert!((last[e] - last[r]).abs() < 0.01 * last[r]);

    // the paper's values: shipped as built in, with a source for each
    assert_eq!(
        std::fs::read_to_string(dir.join("paper_values.csv")).unwrap(),
        PAPER_VALUES
    );
    let paper = paper_values().unwrap();
    let xs = |fig: &str, kind: &str| -> Vec<f64> {
        paper
            .iter()
            .filter(|v| v.figure == fig && v.kind == kind)
            .filter_map(|v| v.x)
            .collect()
    };
    assert_eq!(xs("fig12", "vline"), [0.001, 0.05, 0.1, 0.143]);
    assert_eq!(xs("fig12", "point"), [0.05]);
    assert!(xs("fig09", "vline").contains(&0.1431));
    assert_eq!(xs("fig14_test1", "vline"), [40.0, 80.0]);
    assert_eq!(xs("fig14_test2", "vline"), [120.0, 20.0]);
    for v in &paper {
        if v.figure != "fig12_thin_disc" {
            assert!(
                v.source.contains("paper l"),
                "{} {}: no line in the source",
                v.figure,
                v.label
            );
        }
    }

    // every figure is in the report's table, and every run it names is saved
    let mut seen = 0;
    for line in report.lines().filter(|l| l.starts_with("| `fig")) {
        let cells: Vec<&str> = line.split(" | ").collect();
        let fig = cells[0].trim_start_matches("| `").trim_end_matches('`');
        assert!(figures.contains(&fig), "{fig}");
        let stem = fig.trim_end_matches(".png");
        assert!(
            paper.iter().any(|v| stem.starts_with(&v.figure)),
            "{fig}: no row in paper_values.csv (not even `none`)"
        );
        let runs: Vec<&str> = cells[2].split(", ").map(|r| r.trim_matches('`')).collect();
        assert!(!runs.is_empty() && !runs[0].is_empty(), "{fig}: no run");
        for r in runs {
            for f in ["history.csv", "summary.json"] {
                assert!(
                    dir.join("runs").join(r).join(f).is_file(),
                    "{fig}: runs/{r}/{f}"
                );
            }
        }
        seen += 1;
    }
    assert_eq!(
        seen,
        figures.len(),
        "figures missing from the report's table"
    );

    // the report's numbers are the figures' data: Example 1 histories have
    // every step, and the thin disc's peak in the table is its history's
    let ex1 = dir.join("runs/ex1_thin_disc/history.csv");
    let steps = col(&ex1, "step");
    assert_eq!(steps.len(), 2001, "Example 1 history at every step");
    let peak = col(&ex1, "contact_fn")
        .into_iter()
        .fold(f64::NEG_INFINITY, f64::max);
    let row = report
        .lines()
        .find(|l| l.starts_with("| `ex1_thin_disc`"))
        .unwrap();
    let quoted: f64 = row.split(" | ").nth(2).unwrap().trim().parse().unwrap();
    assert!(
        (quoted - peak).abs() < 0.005 + 1e-12,
        "thin disc: report {quoted} N, history {peak} N"
    );

    // Fig. 17 is the row of cycle 40 of a saved run's history
    let run17 = dir.join("runs/nine_disc_efg_test1_E1.0e12/history.csv");
    let (cols, rows) = read(&run17).unwrap();
    let row40 = rows.iter().find(|r| r[0] == 40.0).unwrap();
    let ux = col(&dir.join("fig17_plate_displacement.csv"), "ux");
    let probes: Vec<f64> = cols
        .iter()
        .zip(row40)
        .filter(|(c, _)| c.starts_with("edge_ux_"))
        .map(|(_, v)| *v)
        .collect();
    assert_eq!(probes, ux);
    validation_page_quotes_the_report(&report);
    std::fs::remove_dir_all(&dir).ok();
}

/// The cells of the report's table row that starts with `start`.
fn report_row<'a>(report: &'a str, start: &str) -> Vec<&'a str> {
    let row = report.lines().find(|l| l.starts_with(start));
    let row = row.unwrap_or_else(|| panic!("report has no row {start:?}"));
    row.split(" | ").map(str::trim).collect()
}

/// A report cell as a number (`0.486 %` → 0.486).
fn number(cell: &str) -> f64 {
    let v = cell.trim_end_matches('%').trim().parse();
    v.unwrap_or_else(|_| panic!("not a number: {cell:?}"))
}

/// docs/validation.md's section on the paper's examples quotes this
/// report: Example 1 with the paper's Newmark parameters (the force
/// reaching m g, the peak and its time, the fall-off and the centre
/// passing the corner) and the nine-disc test's plates (the stiff ones'
/// largest deviation from the all-rigid run, the soft one's).
fn validation_page_quotes_the_report(report: &str) {
    let page = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/validation.md");
    let page = std::fs::read_to_string(page).unwrap();
    let c = report_row(report, "| `ex1_newmark_1.5_0.8`");
    let at = |i: usize| format!("{:.4}", number(c[i]));
    let peak = format!("{:.1}", number(c[2]));
    for quoted in [
        format!("| {} s |", at(1)),
        format!("{peak} N at {} s", at(3)),
        format!("{} s (the centre passes the corner at {} s)", at(4), at(5)),
    ] {
        assert!(
            page.contains(&quoted),
            "docs/validation.md does not quote the report's {quoted:?}"
        );
    }
    let relative = |test: u32, plate: &str| {
        number(report_row(report, &format!("| {test} | EFG, E = {plate} |"))[5])
    };
    let stiff = [1, 2]
        .iter()
        .flat_map(|&t| ["2.1e14", "2.1e13"].map(|e| relative(t, e)))
        .fold(0.0f64, f64::max);
    assert!(
        stiff <= 0.72 && page.contains("(within 0.72 % of the all-rigid run)"),
        "stiff plates: {stiff} %"
    );
    for t in [1, 2] {
        let soft = relative(t, "1.0e10");
        assert!(
            soft.round() == 48.0 && page.contains("by up to 48 %"),
            "soft plate, test {t}: {soft} %"
        );
    }
}
