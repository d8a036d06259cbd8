//! Post-processing of the strip footing test `examples/strip_footing.toml`
//! (manual: docs/validation.md): the load–settlement curve against the bearing
//! capacity of the footing with the friction angle measured by the
//! biaxial example on the same material.
//!
//!     efgdem run examples/strip_footing.toml -o out/strip_footing
//!     cargo run --release --example strip_footing_post -- examples/strip_footing.toml out/strip_footing [--phi-peak 23.7] [--phi-cs 21.4]
//!
//! writes into the output directory `footing.csv` (the curve: penetration,
//! mean, smallest and largest reaction per bin of 0.5 mm, and the theory),
//! `load_settlement.png` and `footing.json`, and prints the comparison.
//!
//! The scenario must have a body `footing` (its width B is the body's),
//! probes `reaction` (`contact_fy` of the footing) and `settlement` (`uy`
//! of a point of the footing), and a `[[measure]]` named `bed` with a
//! `porosity` column (the unit weight γ = ρ_s (1 − n) g of the bed, from
//! the rows before the footing touches it). Theory: `efgdem::geotech::bearing`.

use efgdem::geotech::bearing::{self, CurvePoint, NGamma};
use efgdem::output::csv::History;
use efgdem::output::plot::{Chart, Mark, Series, line_chart};
use efgdem::scenario::{self, Scenario};
use std::fmt::Write as _;
use std::path::Path;

fn main() {
    if let Err(e) = main_() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

/// Friction angles of the biaxial example's material (μ = 0.5, μ_r = 0.1;
/// docs/tutorial/biaxial.md).
const PHI_PEAK: f64 = 23.7;
const PHI_CS: f64 = 21.4;

fn main_() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| -> Result<Option<f64>, String> {
        match args.iter().position(|a| a == flag) {
            None => Ok(None),
            Some(i) => args
                .get(i + 1)
                .ok_or(format!("{flag} needs a value"))?
                .parse::<f64>()
                .map(Some)
                .map_err(|e| format!("{flag}: {e}")),
        }
    };
    let phi_peak = value("--phi-peak")?.unwrap_or(PHI_PEAK);
    let phi_cs = value("--phi-cs")?.unwrap_or(PHI_CS);
    let plain: Vec<&String> = args
        .iter()
        .enumerate()
        .filter(|(i, a)| !a.starts_with("--") && (*i == 0 || !args[i - 1].starts_with("--")))
        .map(|(_, a)| a)
        .collect();
    let [file, dir] = plain.as_slice() else {
        return Err(
            "usage: strip_footing_post SCENARIO OUT_DIR [--phi-peak DEG] [--phi-cs DEG]".into(),
        );
    };
    let sc = scenario::load(Path::new(file.as_str())).map_err(|e| e.to_string())?;
    let report = post(&sc, Path::new(dir.as_str()), phi_peak, phi_cs)?;
    print!("{report}");
    Ok(())
}

/// What the test needs from the scenario.
struct Setup {
    /// Footing width B (m).
    b: f64,
    /// Disc thickness t (m): the reaction is a force over the length t.
    t: f64,
    /// Grain density ρ_s (kg/m³).
    rho: f64,
    /// |g| (m/s²).
    g: f64,
}

fn setup(sc: &Scenario) -> Result<Setup, String> {
    let body = sc
        .body
        .iter()
        .find(|b| b.name == "footing")
        .ok_or("the scenario has no body `footing`")?;
    let gr = sc
        .granular
        .as_ref()
        .ok_or("the scenario has no [granular]")?;
    let mat = sc
        .material
        .iter()
        .find(|m| m.name == gr.material)
        .ok_or("no material of the discs")?;
    let [gx, gy] = sc.simulation.gravity;
    Ok(Setup {
        b: body.rectangle.size[0],
        t: gr.thickness,
        rho: mat.density,
        g: gx.hypot(gy),
    })
}

fn post(sc: &Scenario, dir: &Path, phi_peak: f64, phi_cs: f64) -> Result<String, String> {
    let s = setup(sc)?;
    let h = History::read(&dir.join("history.csv"))?;
    let uy = h.values("settlement")?;
    let f = h.values("reaction")?;
    let n = h.values("bed_porosity")?;
    let k0 = bearing::first_contact(&f).ok_or("the footing never touches the bed")?;
    if k0 == 0 {
        return Err(
            "the footing touches the bed in the first row: no row measures the bed alone".into(),
        );
    }
    let porosity = n[..k0].iter().sum::<f64>() / k0 as f64;
    let gamma = s.rho * (1.0 - porosity) * s.g;
    let bin = 5e-4;
    let c = bearing::curve(&uy, &f, bin);
    // theory: q_u(D) B t with D the penetration
    let cases = [
        (NGamma::Vesic, phi_peak),
        (NGamma::Meyerhof, phi_peak),
        (NGamma::Hansen, phi_peak),
        (NGamma::Meyerhof, phi_cs),
    ];
    let theory = |p: &CurvePoint, (m, phi): (NGamma, f64)| {
        bearing::ultimate_pressure(gamma, s.b, p.penetration, phi.to_radians(), m) * s.b * s.t
    };
    // the comparison over the bins past 5 % of B (the footing is seated)
    let seated: Vec<&CurvePoint> = c.iter().filter(|p| p.penetration >= 0.05 * s.b).collect();
    let ratios: Vec<f64> = cases
        .iter()
        .map(|&case| {
            seated.iter().map(|p| p.mean / theory(p, case)).sum::<f64>()
                / seated.len().max(1) as f64
        })
        .collect();
    // CSV
    let mut csv = String::from("penetration,mean,min,max,rows");
    for (m, phi) in cases {
        write!(csv, ",{}_{phi}", m.name()).unwrap();
    }
    csv.push('\n');
    for p in &c {
        write!(
            csv,
            "{:e},{:e},{:e},{:e},{}",
            p.penetration, p.mean, p.min, p.max, p.rows
        )
        .unwrap();
        for &case in &cases {
            write!(csv, ",{:e}", theory(p, case)).unwrap();
        }
        csv.push('\n');
    }
    std::fs::write(dir.join("footing.csv"), csv).map_err(|e| e.to_string())?;
    // plot: pressure (kPa) against penetration (mm)
    let kpa = 1e-3 / (s.b * s.t);
    // the mean per bin (the smallest and largest of each bin are in the
    // CSV: single rows range from 0 to 4 × the mean)
    let mut series = vec![Series::new(
        "measured: mean per 0.5 mm of penetration",
        c.iter()
            .map(|p| (1e3 * p.penetration, kpa * p.mean))
            .collect(),
        Mark::Line,
    )];
    for &(m, phi) in &cases {
        series.push(Series::new(
            format!("γ D Nq + ½ γ B Nγ, {} Nγ, φ = {phi}°", m.name()),
            c.iter()
                .map(|p| (1e3 * p.penetration, kpa * theory(p, (m, phi))))
                .collect(),
            Mark::Dashed,
        ));
    }
    let chart = Chart {
        title: "Strip footing on a bed of discs: load–settlement".into(),
        x_label: "penetration D [mm]".into(),
        y_label: "footing pressure q = F/(B t) [kPa]".into(),
        series,
        notes: vec![
            format!(
                "B = {} mm, γ = {:.0} N/m³ (porosity {porosity:.3})",
                1e3 * s.b,
                gamma
            ),
            format!("φ from the biaxial example: peak {phi_peak}°, critical state {phi_cs}°"),
        ],
        ..Default::default()
    };
    line_chart(&dir.join("load_settlement.png"), &chart, 1400, 800).map_err(|e| e.to_string())?;
    let json = serde_json::json!({
        "width": s.b,
        "porosity": porosity,
        "unit_weight": gamma,
        "first_contact_row": k0,
        "phi_peak": phi_peak,
        "phi_cs": phi_cs,
        "bins": c.len(),
        "largest_mean_reaction": c.iter().map(|p| p.mean).fold(0.0, f64::max),
        "ratio_measured_to_theory": cases.iter().zip(&ratios).map(|(&(m, phi), r)| {
            serde_json::json!({"n_gamma": m.name(), "phi": phi, "ratio": r})
        }).collect::<Vec<_>>(),
    });
    efgdem::output::write_json(&dir.join("footing.json"), &json).map_err(|e| e.to_string())?;
    let mut out = String::new();
    writeln!(
        out,
        "B = {} mm, porosity {porosity:.3}, γ = {gamma:.0} N/m³; first contact at row {k0}",
        1e3 * s.b
    )
    .unwrap();
    writeln!(out, "penetration [mm]  mean reaction [N]  theory [N]: Vesić/Meyerhof/Hansen at φ_peak, Meyerhof at φ_cs").unwrap();
    for p in &c {
        write!(out, "{:8.2} {:12.1}   ", 1e3 * p.penetration, p.mean).unwrap();
        for &case in &cases {
            write!(out, " {:8.1}", theory(p, case)).unwrap();
        }
        out.push('\n');
    }
    for (&(m, phi), r) in cases.iter().zip(&ratios) {
        writeln!(
            out,
            "measured / theory ({} N_γ, φ = {phi}°), mean over D ≥ 0.05 B: {r:.2}",
            m.name()
        )
        .unwrap();
    }
    Ok(out)
}
