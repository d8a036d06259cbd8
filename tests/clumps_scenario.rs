//! Clumps from a scenario file, through the command line: discs replaced
//! by three-disc clumps settle in a box; `discs_final.csv`, the frames and
//! `summary.json` say which disc is in which clump, and the members of a
//! clump keep their distances (rigid). Bad `[clumps]` input is reported
//! with file, line and field, exit code 2.

use std::path::PathBuf;

#[allow(dead_code)]
mod common;

fn efgdem(args: &[&str]) -> std::process::Output {
    common::bin().args(args).output().expect("runs")
}

fn scratch(name: &str) -> PathBuf {
    common::tmpdir(&format!("clumps-{name}"))
}

const PILE: &str = include_str!("common/clump_pile.toml");

#[test]
fn clumps_settle_and_every_output_names_them() {
    let dir = scratch("pile");
    let file = dir.join("pile.toml");
    std::fs::write(
        &file,
        format!("{PILE}\n[output]\nevery = 100\nvtk_every = 1500\n"),
    )
    .unwrap();
    let out_dir = dir.join("out");
    let out = efgdem(&[
        "run",
        file.to_str().unwrap(),
        "-o",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // discs_final.csv: x,y,r,id,clump; clumps of three discs
    let text = std::fs::read_to_string(out_dir.join("discs_final.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("x,y,r,id,clump"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let n_clumps = rows.iter().map(|r| r[4] as usize).max().unwrap();
    let members = rows.iter().filter(|r| r[4] > 0.0).count();
    let free = rows.len() - members;
    println!("{} discs: {n_clumps} clumps, {free} free discs", rows.len());
    assert_eq!(members, 3 * n_clumps);
    assert_eq!(rows.len(), free + 3 * n_clumps);
    // 80 discs, a fifth of them kept on average: the draw is seeded
    assert!(free > 5 && free < 30 && free + n_clumps == 80);
    // a clump's members are consecutive and kept their template's
    // distances: the template [[-0.5, 0, 0.6], [0.5, 0, 0.6], [0, 0.7, 0.5]]
    // scaled by the radius ratio r_1 / 0.6
    for c in 1..=n_clumps {
        let m: Vec<&Vec<f64>> = rows.iter().filter(|r| r[4] == c as f64).collect();
        let s = m[0][2] / 0.6;
        let d = |a: &Vec<f64>, b: &Vec<f64>| (a[0] - b[0]).hypot(a[1] - b[1]) / s;
        assert!((d(m[0], m[1]) - 1.0).abs() < 1e-9);
        assert!((d(m[0], m[2]) - (0.25f64 + 0.49).sqrt()).abs() < 1e-9);
        assert!((m[2][2] / s - 0.5).abs() < 1e-12);
        assert!(m[0][3] + 1.0 == m[1][3] && m[1][3] + 1.0 == m[2][3]);
    }
    // settled on the floor: every disc below its drop height, none through
    assert!(rows.iter().all(|r| r[1] > 0.0 && r[1] < 0.3));
    let frame = std::fs::read(out_dir.join("frames/discs_0003000.vtp")).unwrap();
    assert!(String::from_utf8_lossy(&frame).contains("Name=\"clump\""));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["clumps"]["count"].as_u64(), Some(n_clumps as u64));
    // the written discs file reads back as a disc source (its clump column
    // ignored), with the same clumps given explicitly by disc number
    let groups: Vec<String> = (1..=n_clumps)
        .map(|c| {
            let ids: Vec<String> = rows
                .iter()
                .filter(|r| r[4] == c as f64)
                .map(|r| format!("{}", r[3]))
                .collect();
            format!("[{}]", ids.join(", "))
        })
        .collect();
    let from_csv = PILE
        .lines()
        .map(|l| match l {
            l if l.starts_with("discs = ") => format!(
                "discs = {{ csv = {:?} }}\nallow_overlap = true",
                out_dir.join("discs_final.csv")
            ),
            l if l.starts_with("template = ") => format!("members = [{}]", groups.join(", ")),
            l if l.starts_with("fraction") || l.starts_with("seed") => String::new(),
            l => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n");
    let file2 = dir.join("again.toml");
    std::fs::write(&file2, from_csv.replace("steps = 3000", "steps = 100")).unwrap();
    let out = efgdem(&[
        "run",
        file2.to_str().unwrap(),
        "-q",
        "-o",
        dir.join("again").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let back = std::fs::read_to_string(dir.join("again/discs_final.csv")).unwrap();
    let clump_of = |t: &str| -> Vec<String> {
        t.lines()
            .skip(1)
            .map(|l| l.rsplit(',').next().unwrap().to_string())
            .collect()
    };
    assert_eq!(clump_of(&back), clump_of(&text));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_clumps_input_reports_file_line_field_and_exits_2() {
    let dir = scratch("bad");
    let explicit = PILE.replace(
        "template = [[-0.5, 0.0, 0.6], [0.5, 0.0, 0.6], [0.0, 0.7, 0.5]]\nfraction = 0.8\nseed = 2",
        "members = [[1, 2], [3, 4]]",
    );
    assert!(explicit.contains("members = [[1, 2], [3, 4]]"));
    for (name, src, field, says) in [
        (
            "one.toml",
            explicit.replace("[3, 4]]", "[3]]"),
            "clumps.members[1]",
            "two discs or more",
        ),
        (
            "twice.toml",
            explicit.replace("[3, 4]]", "[2, 4]]"),
            "clumps.members[1][0]",
            "in two clumps",
        ),
        (
            "range.toml",
            explicit.replace("[3, 4]]", "[3, 400]]"),
            "clumps.members[1][1]",
            "no disc 400",
        ),
        (
            "both.toml",
            explicit.replace(
                "members = [[1, 2], [3, 4]]",
                "members = [[1, 2]]\ntemplate = [[0, 0, 1], [1, 0, 1]]",
            ),
            "clumps",
            "one of the two",
        ),
        (
            "radius.toml",
            PILE.replace("[0.0, 0.7, 0.5]]", "[0.0, 0.7, -0.5]]"),
            "clumps.template[2]",
            "r > 0",
        ),
        (
            "fraction.toml",
            PILE.replace("fraction = 0.8", "fraction = 1.5"),
            "clumps.fraction",
            "(0, 1]",
        ),
        (
            "fit.toml",
            PILE.replace("fraction = 0.8", "fraction = 0.8\nfit = \"outside\""),
            "clumps.fit",
            "",
        ),
    ] {
        let file = dir.join(name);
        std::fs::write(&file, &src).unwrap();
        let out = efgdem(&["check", file.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(&format!("{name}:")) && err.contains(field) && err.contains(says),
            "{name}: {err}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}
