//! The silo of `examples/silo.toml` against Janssen (manual:
//! docs/validation.md; about 1.5 minutes on 2 cores). Runs the scenario through the library (the
//! time-averaged wall tractions need every state, not the history), then
//! writes into the output directory `wall_left.csv`, `wall_right.csv`
//! (traction profiles), `bands.csv`, `janssen.csv`, `silo.json`,
//! `silo.png` and `silo_vertical.png`, and prints the comparison:
//!
//!     cargo run --release --example silo -- [SCENARIO] [-o out/silo] [--scale S] [--fills N]
//!
//! `--scale S` multiplies every length but the grains' radii (silo width
//! and height, wall node counts, disc count × S²; `efgdem::geotech::
//! scale_lengths`). The averaging window is the last 40 % of the run,
//! every 20 steps. `--fills N` (default 1) runs N independent fills (the
//! disc seeds `seed … seed + N − 1`, one after another) and compares the
//! wall pressure averaged over them, bin by bin, with Janssen
//! (`silo::ensemble`); the profiles and bands of fill k are then written
//! to `fill<k>/`.

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
    let fills = value("--fills")
        .map(|s| s.parse::<usize>().map_err(|e| format!("--fills {s}: {e}")))
        .transpose()?
        .unwrap_or(1);
    if fills == 0 {
        return Err("--fills must be at least 1".into());
    }
    let mut sc = efgdem::scenario::load(Path::new(&file)).map_err(|e| e.to_string())?;
    geotech::scale_lengths(&mut sc, scale)?;
    let s = silo::Silo::from_scenario(&sc)?;
    let opts = silo::Options {
        average_from: 0.6 * s.end_time,
        every: 20,
        bins: (12.0 * scale).round() as usize,
        bands: (11.0 * scale).round() as usize,
        rest: None,
    };
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    let runs = silo::run_fills(&sc, &opts, fills, |k, t| {
        eprint!(
            "\rfill {}/{fills}: t = {t:.4} s of {:.4} s",
            k + 1,
            s.end_time
        )
    })?;
    let secs = t0.elapsed().as_secs_f64();
    eprintln!();
    let ens = silo::ensemble(&runs, s.g)?;
    let e = |e: std::io::Error| e.to_string();
    let win = format!("averaged over t = {} … {} s", opts.average_from, s.end_time);
    for (k, r) in runs.iter().enumerate() {
        let dir = if fills == 1 {
            out.clone()
        } else {
            out.join(format!("fill{}", k + 1))
        };
        std::fs::create_dir_all(&dir).map_err(e)?;
        write_traction_csv(
            &dir.join("wall_left.csv"),
            &format!("left wall, right face; {win}"),
            &r.left,
            Some(r.surface),
        )
        .map_err(e)?;
        write_traction_csv(
            &dir.join("wall_right.csv"),
            &format!("right wall, left face; {win}"),
            &r.right,
            Some(r.surface),
        )
        .map_err(e)?;
        geotech::write_bands_csv(&dir.join("bands.csv"), &r.bands, r.surface).map_err(e)?;
    }
    let mut f = std::fs::File::create(out.join("janssen.csv")).map_err(e)?;
    writeln!(f, "depth,measured,std_error,spread,janssen,hydrostatic").map_err(e)?;
    for c in &ens.compared {
        writeln!(
            f,
            "{:e},{:e},{:e},{:e},{:e},{:e}",
            c.depth, c.measured, c.std_error, c.spread, c.janssen, c.hydrostatic
        )
        .map_err(e)?;
    }
    let mut json = serde_json::to_value(&ens).map_err(|e| e.to_string())?;
    json["fill_results"] = serde_json::to_value(&runs).map_err(|e| e.to_string())?;
    json["run_seconds"] = secs.into();
    json["scale"] = scale.into();
    json["average_from"] = opts.average_from.into();
    efgdem::output::write_json(&out.join("silo.json"), &json).map_err(e)?;
    silo::plot(&out, &runs, &ens, s.g).map_err(|e| e.to_string())?;
    for (k, r) in runs.iter().enumerate() {
        println!(
            "fill {}: H/W = {:.2}, kinetic {:.1e} J, ρ_b = {:.0} kg/m³, μ_w = {:.3} (left {:.3}, right {:.3}), K = {:.3}, balance {:+.3} %, Janssen (own μ_w, K) below z = W: thrust {:+.1} %, bins max |dev| {:.1} %",
            k + 1,
            r.height_over_width,
            r.kinetic,
            r.rho_b,
            r.mu_w,
            r.mu_w_walls[0],
            r.mu_w_walls[1],
            r.k,
            100.0 * r.balance_error,
            100.0 * r.thrust_deviation,
            100.0 * r.max_deviation
        );
    }
    println!(
        "silo W = {:.1} mm, {} fill(s), fill H/W = {:.2} (surface ±{:.2} mm), {} states averaged per fill; run {secs:.1} s",
        1e3 * ens.width,
        ens.fills,
        ens.height_over_width,
        1e3 * ens.surface_spread,
        runs[0].window.samples,
    );
    println!(
        "pooled: ρ_b = {:.0} kg/m³; μ_w = {:.3} (left {:.3}, right {:.3}); K = {:.3}; weight balance max |error| {:.3} %",
        ens.rho_b,
        ens.mu_w,
        ens.mu_w_walls[0],
        ens.mu_w_walls[1],
        ens.k,
        100.0 * ens.balance_error
    );
    println!(
        "Janssen below z = W: thrust {:+.1} %; bins: max |dev| {:.1} % ({} bins); σ_v∞ = {:.0} Pa",
        100.0 * ens.thrust_deviation,
        100.0 * ens.max_deviation,
        ens.compared.len(),
        ens.sigma_v_infinity
    );
    if fills > 1 {
        println!(
            "one fill's bin scatters by {:.1} % (rms over the bins) about the mean of {fills}",
            100.0 * ens.fill_scatter
        );
    }
    for c in &ens.compared {
        println!(
            "  z = {:6.1} mm: wall {:7.1} ± {:5.1} Pa (fills scatter {:4.1} %), K σ_v {:7.1} Pa ({:+.1} %), K ρ_b g z {:7.1} Pa",
            1e3 * c.depth,
            c.measured,
            c.std_error,
            100.0 * c.spread / c.measured,
            c.janssen,
            100.0 * c.deviation(),
            c.hydrostatic
        );
    }
    Ok(())
}
