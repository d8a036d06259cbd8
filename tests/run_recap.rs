//! What `efgdem run` prints when it ends (docs/reference/cli.md): on
//! stdout, and only there, the results that matter — each probe's final
//! value, its extremes and their times, as in `history.csv`; the energy
//! balance, as in `summary.json`; the files written — and nothing of the
//! progress or diagnostics, which go to stderr.

#[allow(dead_code)]
mod common;
use common::{bin, run_with, summary, tmpdir};
use efgdem::output::csv::read;

/// The number after `key` in `line` (up to a space, `,`, `;` or `)`).
fn after(line: &str, key: &str) -> f64 {
    let rest = &line[line.find(key).unwrap_or_else(|| panic!("{key} in {line}")) + key.len()..];
    let end = rest.find([' ', ',', ';', ')']).unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|_| panic!("{key}: {:?}", &rest[..end]))
}

/// `a` printed to four significant digits is `b`.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 5e-4 * b.abs().max(1e-300) + 1e-300
}

#[test]
fn a_coupled_run_ends_with_its_probes_energy_and_files_on_stdout() {
    let root = tmpdir("recap-coupled");
    let example = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/paper_cantilever_disc.toml"
    );
    let out = root.join("out");
    let o = bin()
        .args(["run", example, "-o", out.to_str().unwrap()])
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{stderr}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(
        lines[0].starts_with("coupled run completed: 2000 steps, t = "),
        "{stdout}"
    );
    // progress and timing are diagnostics
    assert!(stderr.contains("done in"), "{stderr}");
    assert!(
        !stdout.contains("done in") && !stdout.contains("ETA"),
        "{stdout}"
    );
    // every probe: final, min and max with their times, as in history.csv
    let (cols, rows) = read(&out.join("history.csv")).unwrap();
    let t = cols.iter().position(|c| c == "t").unwrap();
    for name in ["tip_uy", "tip_ux", "disc_uy", "disc_ux"] {
        let line = lines
            .iter()
            .find(|l| l.trim_start().starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("no line for {name}: {stdout}"));
        let k = cols.iter().position(|c| c == name).unwrap();
        let v: Vec<f64> = rows.iter().map(|r| r[k]).collect();
        let last = *v.last().unwrap();
        let (imin, imax) = (0..v.len()).fold((0, 0), |(a, b), i| {
            (
                if v[i] < v[a] { i } else { a },
                if v[i] > v[b] { i } else { b },
            )
        });
        let fin: f64 = line
            .split_whitespace()
            .nth(1)
            .unwrap()
            .trim_end_matches(';')
            .parse()
            .unwrap();
        assert!(close(fin, last), "{name}: final {fin} vs {last}");
        assert!(close(after(line, "min "), v[imin]), "{name}: {line}");
        assert!(close(after(line, "max "), v[imax]), "{name}: {line}");
        let (tmin, tmax) = (
            after(&line[line.find("min ").unwrap()..], "at t = "),
            after(&line[line.find("max ").unwrap()..], "at t = "),
        );
        assert!(close(tmin, rows[imin][t]), "{name}: {line}");
        assert!(close(tmax, rows[imax][t]), "{name}: {line}");
    }
    // the disc falls onto the beam: the tip goes down
    let tip = lines.iter().find(|l| l.contains("tip_uy")).unwrap();
    assert!(after(tip, "min ") < 0.0, "{tip}");
    // the energy balance, as in summary.json: W_ext = ΔE_stored + E_diss
    let e = &summary(&out)["energy"];
    let energy = lines
        .iter()
        .find(|l| l.starts_with("energy:"))
        .unwrap_or_else(|| panic!("{stdout}"));
    let w = e["W_ext"].as_f64().unwrap();
    assert!(w > 0.0, "gravity does work on the falling disc: {w}");
    assert!(close(after(energy, "W_ext = "), w), "{energy}");
    assert!(
        close(after(energy, "E_diss = "), e["E_diss"].as_f64().unwrap()),
        "{energy}"
    );
    let stored: f64 = [
        "E_kin_dem",
        "E_kin_body",
        "E_strain",
        "E_penalty",
        "E_contact",
    ]
    .iter()
    .map(|k| e[*k].as_f64().unwrap())
    .sum();
    assert!(close(after(energy, "stored now "), stored), "{energy}");
    // where the files are, and how to look at them
    let files = lines.iter().find(|l| l.starts_with("files in ")).unwrap();
    for f in ["history.csv", "summary.json", "beam.pvd", "discs.pvd"] {
        assert!(files.contains(f), "{f}: {files}");
    }
    // only what a user looks at: no lock, no temporary file
    assert!(!files.contains(" .") && !files.contains(".tmp"), "{files}");
    assert!(
        stdout.contains(&format!("efgdem view {}", out.display())),
        "{stdout}"
    );
    std::fs::remove_dir_all(root).unwrap();
}

const DISCS: &str = r#"
[simulation]
steps = 400
gravity = [0.0, -9.81]

[[material]]
name = "m"
density = 1000.0
kn = 1.0e5

[granular]
material = "m"
discs = [[0.0, 0.1, 0.01], [0.05, 0.1, 0.01]]

[[probe]]
name = "y1"
disc = 1
quantity = "y"
"#;

#[test]
fn a_granular_run_ends_with_the_discs_energies() {
    let root = tmpdir("recap-granular");
    let file = root.join("discs.toml");
    std::fs::write(&file, DISCS).unwrap();
    let out = root.join("out");
    let o = run_with(&file, &out, &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert!(
        stdout.starts_with("granular run completed: 400 steps"),
        "{stdout}"
    );
    let line = stdout
        .lines()
        .find(|l| l.starts_with("energy of the discs"))
        .unwrap();
    let e = &s["energies"];
    // two free-falling discs: kinetic energy m g h after falling h
    let ke = e["kinetic"].as_f64().unwrap();
    assert!(ke > 0.0);
    assert!(close(after(line, "kinetic "), ke), "{line}");
    assert!(
        close(
            after(line, "gravity potential "),
            e["gravity"].as_f64().unwrap()
        ),
        "{line}"
    );
    let y1 = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("y1 "))
        .unwrap();
    assert!(close(after(y1, "max "), 0.1), "{y1}");
    assert!(after(y1, "min ") < 0.1, "{y1}");
    std::fs::remove_dir_all(root).unwrap();
}

/// Timoshenko's cantilever (examples/timoshenko.toml), bent down by its
/// tip load: the top fibre at the root is in tension, σ_xx = P L c / I =
/// 1000 · 48 · 6 / 144 = 2000 Pa. The summary says which way a stress
/// counts, next to its value.
#[test]
fn a_stress_probe_says_its_sign_convention() {
    let root = tmpdir("recap-sign");
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/timoshenko.toml");
    let out = root.join("out");
    let o = bin()
        .args(["run", example, "-q", "-o", out.to_str().unwrap()])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    let top = &s["probes"]["sxx_root_top"];
    assert_eq!(top["sign"], "tension positive");
    let v = top["final"].as_f64().unwrap();
    assert!((v - 2000.0).abs() < 0.05 * 2000.0, "{v}");
    let line = stdout.lines().find(|l| l.contains("sxx_root_top")).unwrap();
    assert!(line.ends_with("(tension positive)"), "{line}");
    // a displacement has no sign convention to state
    assert!(s["probes"]["tip_uy"].get("sign").is_none());
    std::fs::remove_dir_all(root).unwrap();
}

/// Discs pressing on a floor: the `[[measure]]` stress and the wall's
/// stress are compression positive, and > 0.
#[test]
fn granular_stresses_are_compression_positive() {
    let root = tmpdir("recap-cpos");
    let file = root.join("bed.toml");
    std::fs::write(
        &file,
        r#"
[simulation]
steps = 3000
gravity = [0.0, -9.81]

[[material]]
name = "m"
density = 2650.0
kn = 1.0e6
ks = 5.0e5
friction = 0.5

[granular]
material = "m"
discs = { generate = "hex", box = [[0.0, 0.0], [0.1, 0.05]], radius = 0.004 }
damping = { kind = "critical-ratio", zeta = 0.5 }

[[wall]]
name = "floor"
from = [0.0, 0.0]
to = [0.1, 0.0]

[[wall]]
name = "left"
from = [0.0, 0.0]
to = [0.0, 0.1]

[[wall]]
name = "right"
from = [0.1, 0.0]
to = [0.1, 0.1]

[[probe]]
name = "floor_s"
wall = "floor"
quantity = "wall_stress"

[[measure]]
name = "bed"
rectangle = [[0.0, 0.0], [0.1, 0.05]]
quantities = ["syy_cpos", "porosity"]
"#,
    )
    .unwrap();
    let out = root.join("out");
    let o = run_with(&file, &out, &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p = &summary(&out)["probes"];
    for name in ["floor_s", "bed_syy_cpos"] {
        assert_eq!(p[name]["sign"], "compression positive", "{name}");
        assert!(p[name]["final"].as_f64().unwrap() > 0.0, "{name}: {p}");
        let line = stdout.lines().find(|l| l.contains(name)).unwrap();
        assert!(line.ends_with("(compression positive)"), "{line}");
    }
    assert!(p["bed_porosity"].get("sign").is_none());
    std::fs::remove_dir_all(root).unwrap();
}
