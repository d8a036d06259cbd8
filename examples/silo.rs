//! The silo of `examples/silo.toml` against Janssen (issue 15 §3; README
//! "Silo (Janssen)"). Runs the scenario through the library (the
//! time-averaged wall tractions need every state, not the history), then
//! writes into the output directory `wall_left.csv`, `wall_right.csv`
//! (traction profiles), `bands.csv`, `janssen.csv`, `silo.json`,
//! `silo.png` and `silo_vertical.png`, and prints the comparison:
//!
//!     cargo run --release --example silo -- [SCENARIO] [-o out/silo] [--scale S]
//!
//! `--scale S` multiplies every length but the grains' radii (silo width
//! and height, wall node counts, disc count × S²; `efgdem::geotech::
//! scale_lengths`). The averaging window is the last 40 % of the run,
//! every 20 steps.

use efgdem::geotech::{self, silo};
use efgdem::output::traction::write_traction_csv;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() {
    if let Err(e) = main_() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn main_() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let file = args
        .first()
        .filter(|a| !a.starts_with('-'))
        .cloned()
        .unwrap_or("examples/silo.toml".into());
    let out = PathBuf::from(value("-o").unwrap_or("out/silo".into()));
    let scale = value("--scale")
        .map(|s| s.parse::<f64>().map_err(|e| format!("--scale {s}: {e}")))
        .transpose()?
        .unwrap_or(1.0);
    let mut sc = efgdem::scenario::load(Path::new(&file)).map_err(|e| e.to_string())?;
    geotech::scale_lengths(&mut sc, scale)?;
    let s = silo::Silo::from_scenario(&sc)?;
    let opts = silo::Options {
        average_from: 0.6 * s.end_time,
        every: 20,
        bins: (12.0 * scale).round() as usize,
        bands: (11.0 * scale).round() as usize,
    };
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    let r = silo::run(&sc, &opts, |t| {
        eprint!("\rt = {t:.4} s of {:.4} s", s.end_time)
    })?;
    let secs = t0.elapsed().as_secs_f64();
    eprintln!();
    let e = |e: std::io::Error| e.to_string();
    let win = format!("averaged over t = {} … {} s", opts.average_from, s.end_time);
    write_traction_csv(
        &out.join("wall_left.csv"),
        &format!("left wall, right face; {win}"),
        &r.left,
        Some(r.surface),
    )
    .map_err(e)?;
    write_traction_csv(
        &out.join("wall_right.csv"),
        &format!("right wall, left face; {win}"),
        &r.right,
        Some(r.surface),
    )
    .map_err(e)?;
    geotech::write_bands_csv(&out.join("bands.csv"), &r.bands, r.surface).map_err(e)?;
    let mut f = std::fs::File::create(out.join("janssen.csv")).map_err(e)?;
    writeln!(f, "depth,measured,janssen,hydrostatic").map_err(e)?;
    for c in &r.compared {
        writeln!(
            f,
            "{:e},{:e},{:e},{:e}",
            c.depth, c.measured, c.janssen, c.hydrostatic
        )
        .map_err(e)?;
    }
    let mut json = serde_json::to_value(&r).map_err(|e| e.to_string())?;
    json["run_seconds"] = secs.into();
    json["scale"] = scale.into();
    json["average_from"] = opts.average_from.into();
    efgdem::output::write_json(&out.join("silo.json"), &json).map_err(e)?;
    silo::plot(&out, &r, s.g).map_err(|e| e.to_string())?;
    println!(
        "silo W = {:.1} mm, fill H/W = {:.2}, {} states averaged, mean kinetic energy {:.2e} J; run {secs:.1} s",
        1e3 * r.width,
        r.height_over_width,
        r.samples,
        r.kinetic
    );
    println!(
        "ρ_b = {:.0} kg/m³ (porosity {:.3}); μ_w = {:.3} (left {:.3}, right {:.3}); K = {:.3}",
        r.rho_b, r.porosity, r.mu_w, r.mu_w_walls[0], r.mu_w_walls[1], r.k
    );
    println!(
        "weight {:.2} N; floor {:.2} N + walls {:.2} + {:.2} N: balance error {:+.2} %",
        r.weight,
        r.floor,
        r.walls_vertical[0],
        r.walls_vertical[1],
        100.0 * r.balance_error
    );
    println!(
        "Janssen below z = W: thrust {:+.1} %; bins: max |dev| {:.1} %, mean {:+.1} % ({} bins); σ_v∞ = {:.0} Pa",
        100.0 * r.thrust_deviation,
        100.0 * r.max_deviation,
        100.0 * r.mean_deviation,
        r.compared.len(),
        r.sigma_v_infinity
    );
    println!(
        "grains' σ_yy (bands) against Janssen's σ_v below z = W: {:+.1} %",
        100.0 * r.sigma_v_deviation
    );
    for c in &r.compared {
        println!(
            "  z = {:6.1} mm: wall {:7.1} Pa, K σ_v {:7.1} Pa ({:+.1} %), K ρ_b g z {:7.1} Pa",
            1e3 * c.depth,
            c.measured,
            c.janssen,
            100.0 * (c.measured / c.janssen - 1.0),
            c.hydrostatic
        );
    }
    Ok(())
}
