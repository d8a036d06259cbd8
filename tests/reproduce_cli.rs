//! `efgdem reproduce` end to end: every figure, data file and the report
//! are written, and the report carries the numbers the README quotes.

use std::process::Command;

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
    for f in [
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
    ] {
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
        "runs/ex1_paper/history.csv",
        "runs/nine_disc_efg_test2_E1.0e10/summary.json",
    ] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for needle in [
        "| `ex1_paper`",
        "| `ex1_thin_disc`",
        "EFG, E = 1.0e10",
        "### Fig. 17",
    ] {
        assert!(report.contains(needle), "report lacks {needle}");
    }
    // Fig. 14 data: the stiff plate follows the rigid plates (validation 4)
    let (cols, rows) = efgdem::output::csv::read(&dir.join("fig14_15_test1.csv")).unwrap();
    let (r, e) = (
        cols.iter().position(|c| c == "rigid").unwrap(),
        cols.iter().position(|c| c == "efg_E2.1e14").unwrap(),
    );
    let last = rows.last().unwrap();
    assert!((last[e] - last[r]).abs() < 0.01 * last[r]);
    std::fs::remove_dir_all(&dir).ok();
}
