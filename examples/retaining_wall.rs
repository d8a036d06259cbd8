//! The cantilever retaining wall of `examples/retaining_wall.toml` at
//! rest (manual: docs/validation.md, "Geotechnical cases"; about 1.5
//! minutes on 2 cores). Runs the scenario
//! through the library, then writes into the output directory
//! `wall_face.csv` (earth pressure profile), `bands.csv`,
//! `retaining_wall.json` and `retaining_wall.png`, and prints the thrust
//! against Jaky's K₀ and the wall's top deflection against beam theory
//! under the measured pressure:
//!
//!     cargo run --release --example retaining_wall -- [SCENARIO] [-o out/retaining_wall] [--scale S] [--phi 23.7,21.4] [--end T]
//!
//! With `examples/retaining_wall_active.toml` (the wall translated away
//! from the backfill) or `retaining_wall_rotation.toml` the thrust is
//! also compared with Rankine's K_a and with Coulomb's K_a cos δ at the
//! wall friction δ = atan(drag/thrust) the run mobilises.
//!
//! `--scale S` multiplies every length but the grains' radii
//! (`efgdem::geotech::scale_lengths`); `--phi` the friction angles (peak,
//! critical) of the grains from the biaxial test (docs/tutorial/biaxial.md,
//! μ_r = 0.1). The averaging window is the last 40 % of the run, every 20
//! steps; `--end T` ends the run at `T` s instead of the scenario's end
//! time (the slow rotation to 1.0 s: the window 0.6–1.0 s, where the thrust
//! has levelled off, before the wall is held).

use efgdem::geotech::{self, retaining};
use efgdem::output::traction::write_traction_csv;
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
        .unwrap_or("examples/retaining_wall.toml".into());
    let out = PathBuf::from(value("-o").unwrap_or("out/retaining_wall".into()));
    let scale = value("--scale")
        .map(|s| s.parse::<f64>().map_err(|e| format!("--scale {s}: {e}")))
        .transpose()?
        .unwrap_or(1.0);
    let phi: Vec<f64> = value("--phi")
        .unwrap_or("23.7,21.4".into())
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<f64>()
                .map_err(|e| format!("--phi {p}: {e}"))
        })
        .collect::<Result<_, _>>()?;
    let [phi_peak, phi_cs] = phi[..] else {
        return Err("--phi takes two angles: peak,critical".into());
    };
    let mut sc = efgdem::scenario::load(Path::new(&file)).map_err(|e| e.to_string())?;
    if let Some(t) = value("--end") {
        let t: f64 = t.parse().map_err(|e| format!("--end {t}: {e}"))?;
        if !(t > 0.0 && t.is_finite()) {
            return Err(format!("--end must be a time > 0 (got {t})"));
        }
        sc.simulation.end_time = Some(t);
    }
    geotech::scale_lengths(&mut sc, scale)?;
    let w = retaining::Wall::from_scenario(&sc)?;
    let opts = retaining::Options {
        average_from: 0.6 * w.end_time,
        every: 20,
        bins: (10.0 * scale).round() as usize,
        bands: (9.0 * scale).round() as usize,
        rest: None,
    };
    std::fs::create_dir_all(&out).map_err(|e| e.to_string())?;
    let t0 = Instant::now();
    let r = retaining::run(&sc, &opts, |t| {
        eprint!("\rt = {t:.4} s of {:.4} s", w.end_time)
    })?;
    let secs = t0.elapsed().as_secs_f64();
    eprintln!();
    let e = |e: std::io::Error| e.to_string();
    let win = format!(
        "wall face; averaged over t = {} … {} s",
        opts.average_from, w.end_time
    );
    write_traction_csv(
        &out.join("wall_face.csv"),
        &win,
        &r.profile,
        Some(r.surface),
    )
    .map_err(e)?;
    geotech::write_bands_csv(&out.join("bands.csv"), &r.bands, r.surface).map_err(e)?;
    let k0 = retaining::jaky_k0;
    let ka = retaining::rankine_ka;
    // the wall friction the run mobilises, and Coulomb's K_a with it
    // (horizontal component: K_a cos δ, what the thrust measures)
    let delta = (r.drag / r.thrust).atan().to_degrees().max(0.0);
    let kc = |p: f64| retaining::coulomb_ka(p, delta) * delta.to_radians().cos();
    let mut json = serde_json::to_value(&r).map_err(|e| e.to_string())?;
    json["run_seconds"] = secs.into();
    json["scale"] = scale.into();
    json["average_from"] = opts.average_from.into();
    json["phi_peak"] = phi_peak.into();
    json["phi_cs"] = phi_cs.into();
    json["k0_peak"] = k0(phi_peak).into();
    json["k0_cs"] = k0(phi_cs).into();
    json["ka_peak"] = ka(phi_peak).into();
    json["ka_cs"] = ka(phi_cs).into();
    json["delta"] = delta.into();
    json["coulomb_ka_h_peak"] = kc(phi_peak).into();
    json["coulomb_ka_h_cs"] = kc(phi_cs).into();
    efgdem::output::write_json(&out.join("retaining_wall.json"), &json).map_err(e)?;
    retaining::plot(&out, &r, w.g, [phi_peak, phi_cs]).map_err(|e| e.to_string())?;
    println!(
        "backfill H = {:.1} mm, {} states averaged, mean kinetic energy {:.2e} J; run {secs:.1} s",
        1e3 * r.height,
        r.window.samples,
        r.kinetic
    );
    println!(
        "ρ_b = {:.0} kg/m³ (porosity {:.3}); K of the backfill (bands) {:.3}",
        r.rho_b, r.porosity, r.k_bands
    );
    println!(
        "thrust {:.2} N/m at {:.3} H: K_wall = {:.3}; Jaky K₀ = {:.3} (φ_peak {phi_peak}°: {:+.1} %), {:.3} (φ_cs {phi_cs}°: {:+.1} %); wall drag {:.2} N/m",
        r.thrust,
        r.thrust_height_over_h,
        r.k_wall,
        k0(phi_peak),
        100.0 * (r.k_wall / k0(phi_peak) - 1.0),
        k0(phi_cs),
        100.0 * (r.k_wall / k0(phi_cs) - 1.0),
        r.drag
    );
    println!(
        "Rankine K_a = {:.3} (φ_peak: K_wall {:+.1} %), {:.3} (φ_cs: {:+.1} %); base displacement u_x = {:.4} mm",
        ka(phi_peak),
        100.0 * (r.k_wall / ka(phi_peak) - 1.0),
        ka(phi_cs),
        100.0 * (r.k_wall / ka(phi_cs) - 1.0),
        1e3 * r.base_displacement
    );
    println!(
        "wall friction mobilised δ = atan(drag/thrust) = {delta:.1}°; Coulomb K_a cos δ = {:.3} (φ_peak: K_wall {:+.1} %), {:.3} (φ_cs: {:+.1} %)",
        kc(phi_peak),
        100.0 * (r.k_wall / kc(phi_peak) - 1.0),
        kc(phi_cs),
        100.0 * (r.k_wall / kc(phi_cs) - 1.0),
    );
    if r.turned() {
        println!(
            "top {:.1} µm beyond the base: the clamp turns, the top's displacement is mostly rigid (no beam check)",
            -1e6 * r.deflection
        );
    } else {
        println!(
            "top deflection relative to the base {:.4} µm (spread over the window {:.2} %); beam theory {:.4} µm (bending {:.4}, shear {:.4}): {:+.2} %",
            1e6 * r.deflection,
            100.0 * r.deflection_spread,
            1e6 * (r.beam[0] + r.beam[1]),
            1e6 * r.beam[0],
            1e6 * r.beam[1],
            100.0 * r.beam_error
        );
    }
    Ok(())
}
