//! A silo with flexible walls against Janssen
//! (`examples/silo.toml`, `examples/silo.rs`; manual: validation, "Silo").
//!
//! **The scenario** ([`Silo::from_scenario`]): a coupled run with two
//! rectangular bodies side by side (the walls; the one on the left
//! touched on its right edge, the other on its left edge), grains between
//! them and a `[[wall]]` named `floor`. The inner faces are `x0 < x1`, the
//! silo width `W = x1 − x0`.
//!
//! **What is measured** ([`run`]), averaged over the states every
//! `every` steps from `average_from` to the end (or, with
//! [`Options::rest`], over a window of states at rest):
//! - the wall tractions `σ_h` (normal) and `τ` (shear, +y) per depth bin
//!   on both inner faces ([`EdgeTraction`]);
//! - the mobilised wall friction `μ_w = −Σ τ / Σ σ_h` over both walls
//!   (the grains drag the walls down: `τ < 0`);
//! - Love–Weber σ_xx, σ_yy and the porosity n of full-width horizontal
//!   bands ([`Bands`]); the lateral stress ratio `K = Σ σ_xx / Σ σ_yy`
//!   over the bands below the top one (the top band holds the rough
//!   surface);
//! - the bulk density `ρ_b = ρ_s (1 − n̄)` with the same bands' mean n;
//! - the free surface `z = 0` ([`super::surface`]) at the start of the
//!   window; depths `z = surface − y`.
//!
//! **Janssen** (2D, a slice of width W between two walls):
//! `σ_v(z) = ρ_b g W / (2 μ_w K) (1 − exp(−2 μ_w K z / W))`, and the wall
//! pressure `σ_h = K σ_v` — no free parameter once `ρ_b`, `μ_w` and `K`
//! are measured. Compared at the bins deeper than W.
//!
//! **Weight balance**: the weight of the grains `Σ m g` against the floor's
//! reaction plus the walls' vertical resultant (averaged).
//!
//! **Ensemble of fills** ([`run_fills`], [`ensemble`]): the grains of one
//! fill are at rest, so its force chains are frozen and time averaging
//! does not remove their spatial scatter (a wall bin of ≈ 13 grains
//! holds 5–9 contacts). The wall pressure Janssen predicts is the mean
//! over independent fills; the ensemble runs the same scenario with the
//! disc generator's seeds `seed, seed + 1, …`, pools μ_w, K and ρ_b over
//! the fills and compares the per-bin mean pressure (with its standard
//! error and the scatter between fills) with Janssen's curve.

pub use super::Options;
use super::{BandMean, Bands, Window, grain_density, sample_until, surface, weight};
use crate::continuum::Edge;
use crate::model::probe::{global_quantity, wall_quantity};
use crate::model::traction::{EdgeTraction, TractionBin};
use crate::output::plot::{Chart, Mark, PlotError, REFERENCE_COLOR, Series, line_chart, palette};
use crate::scenario::Scenario;
use crate::scenario::granular::DiscsSpec;
use std::path::Path;

/// The silo a scenario describes.
#[derive(Debug, Clone)]
pub struct Silo {
    /// Body index of the left wall.
    pub left: usize,
    /// Body index of the right wall.
    pub right: usize,
    /// Index of the `floor` wall.
    pub floor: usize,
    /// x of the left wall's inner (right) face.
    pub x0: f64,
    /// x of the right wall's inner (left) face.
    pub x1: f64,
    /// Bottom and top of the walls (y).
    pub y_range: (f64, f64),
    /// Thickness t of the bodies (the forces are per t).
    pub thickness: f64,
    /// Density of the grains' material ρ_s (kg/m³).
    pub rho_s: f64,
    /// Gravity `|g|` (m/s²).
    pub g: f64,
    /// End time of the run (s).
    pub end_time: f64,
}

impl Silo {
    /// Read the silo from `sc` (see the module docs).
    pub fn from_scenario(sc: &Scenario) -> Result<Silo, String> {
        if sc.body.len() != 2 {
            return Err(format!(
                "a silo has two wall bodies; the scenario has {}",
                sc.body.len()
            ));
        }
        let (l, r) = if sc.body[0].rectangle.origin[0] <= sc.body[1].rectangle.origin[0] {
            (0, 1)
        } else {
            (1, 0)
        };
        let floor = sc
            .wall
            .iter()
            .position(|w| w.name == "floor")
            .ok_or("a silo needs a [[wall]] named `floor`")?;
        let bl = &sc.body[l].rectangle;
        let br = &sc.body[r].rectangle;
        let x0 = bl.origin[0] + bl.size[0];
        let x1 = br.origin[0];
        if x1 <= x0 {
            return Err("the walls overlap".into());
        }
        let g = sc.simulation.gravity;
        let dt = sc
            .simulation
            .dt
            .ok_or("the scenario needs [simulation] dt")?;
        let end_time = sc
            .simulation
            .end_time
            .or(sc.simulation.steps.map(|n| n as f64 * dt))
            .ok_or("the scenario needs [simulation] end_time or steps")?;
        Ok(Silo {
            left: l,
            right: r,
            floor,
            x0,
            x1,
            y_range: (bl.origin[1], bl.origin[1] + bl.size[1]),
            thickness: sc.body[l].elastic.thickness,
            rho_s: grain_density(sc)?,
            g: (g[0] * g[0] + g[1] * g[1]).sqrt(),
            end_time,
        })
    }

    /// The silo width W (m).
    pub fn width(&self) -> f64 {
        self.x1 - self.x0
    }
}

/// One depth of the Janssen comparison.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Compared {
    /// Depth of the bin's middle below the surface (m).
    pub depth: f64,
    /// Wall pressure, mean of the two walls (Pa).
    pub measured: f64,
    /// Janssen's `K σ_v(z)` (Pa).
    pub janssen: f64,
    /// `K ρ_b g z`: the pressure without wall friction (Pa).
    pub hydrostatic: f64,
}

/// Everything [`run`] measures.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SiloResult {
    /// Silo width W (m).
    pub width: f64,
    /// Free surface (y, m) at the start of the averaging window.
    pub surface: f64,
    /// Fill height (surface − floor) over W.
    pub height_over_width: f64,
    /// The states averaged.
    pub window: Window,
    /// Mean kinetic energy of the grains over the window (J).
    pub kinetic: f64,
    /// Left wall's profile (bottom to top).
    #[serde(skip)]
    pub left: Vec<TractionBin>,
    /// Right wall's profile.
    #[serde(skip)]
    pub right: Vec<TractionBin>,
    /// Bands (bottom to top).
    pub bands: Vec<BandMean>,
    /// Mean porosity of the bands below the top one.
    pub porosity: f64,
    /// Bulk density ρ_b = ρ_s (1 − n) (kg/m³).
    pub rho_b: f64,
    /// Mobilised wall friction μ_w (both walls, whole height).
    pub mu_w: f64,
    /// μ_w of the left and right walls.
    pub mu_w_walls: [f64; 2],
    /// Lateral stress ratio K (bands below the top one).
    pub k: f64,
    /// K of each band (bottom to top).
    pub k_bands: Vec<f64>,
    /// Weight of the grains (N per t).
    pub weight: f64,
    /// Floor reaction (N per t).
    pub floor: f64,
    /// Vertical force of the grains on the two walls, downward positive
    /// (N per t).
    pub walls_vertical: [f64; 2],
    /// (floor + walls − weight) / weight.
    pub balance_error: f64,
    /// Horizontal forces of the grains on the walls (N per t; outward
    /// positive).
    pub walls_horizontal: [f64; 2],
    /// Janssen comparison at the bins deeper than W.
    pub compared: Vec<Compared>,
    /// Largest |measured/janssen − 1| over `compared`.
    pub max_deviation: f64,
    /// Mean of measured/janssen − 1 over `compared`.
    pub mean_deviation: f64,
    /// Σ measured / Σ janssen − 1 over `compared`: the wall's thrust below
    /// z = W against Janssen's.
    pub thrust_deviation: f64,
    /// Σ σ_yy / Σ σ_v(z) − 1 over the bands whose middle is deeper than
    /// W (the top band excluded): the grains' vertical stress against
    /// Janssen's.
    pub sigma_v_deviation: f64,
    /// Janssen's σ_v asymptote ρ_b g W/(2 μ_w K) (Pa).
    pub sigma_v_infinity: f64,
}

/// Janssen's vertical stress at depth z in a 2D silo of width `w`.
pub fn janssen(rho_b: f64, g: f64, w: f64, mu_w: f64, k: f64, z: f64) -> f64 {
    let a = 2.0 * mu_w * k / w;
    if a.abs() < 1e-300 {
        return rho_b * g * z;
    }
    rho_b * g / a * (1.0 - (-a * z).exp())
}

/// Run the silo scenario `sc` to its end time, averaging as `opts` says;
/// `progress(t)` is called every 1000 steps.
pub fn run(sc: &Scenario, opts: &Options, progress: impl FnMut(f64)) -> Result<SiloResult, String> {
    let silo = Silo::from_scenario(sc)?;
    let mut model = sc.build().map_err(|e| e.to_string())?;
    let (y0, y1) = silo.y_range;
    let mut left = EdgeTraction::new(silo.left, Edge::Right, y0, y1, opts.bins, silo.thickness)
        .map_err(|e| e.to_string())?;
    let mut right = EdgeTraction::new(silo.right, Edge::Left, y0, y1, opts.bins, silo.thickness)
        .map_err(|e| e.to_string())?;
    let mut bands: Option<Bands> = None;
    let mut surf = f64::NAN;
    let (mut floor, mut kin) = (0.0, 0.0);
    let t_disc = sc.granular.as_ref().map_or(1.0, |g| g.thickness);
    let win = sample_until(
        &mut model,
        silo.end_time,
        opts,
        progress,
        |m, g, c, fresh| {
            if fresh {
                // a window (again): everything averaged from here
                left.reset();
                right.reset();
                bands = None;
                (floor, kin) = (0.0, 0.0);
            }
            let b = bands.get_or_insert_with(|| {
                surf = surface(g, silo.x0, silo.x1, 8);
                Bands::new(silo.x0, silo.x1, y0, surf, opts.bands)
            });
            b.add(m);
            left.add(&c.contacts);
            right.add(&c.contacts);
            floor += -wall_quantity(&g.walls[silo.floor], "wall_fy", t_disc);
            kin += global_quantity(g, "kinetic");
            Ok(())
        },
    )?;
    let bands = bands.ok_or("no state in the averaging window")?;
    let g = model.granular().ok_or("no grains")?;
    let weight = weight(g, sc.simulation.gravity);
    let per = 1.0 / win.samples as f64;
    let means = bands.means();
    let bulk = &means[..means.len().saturating_sub(1).max(1)];
    let porosity = bulk.iter().map(|b| b.porosity).sum::<f64>() / bulk.len() as f64;
    let rho_b = silo.rho_s * (1.0 - porosity);
    let k = bulk.iter().map(|b| b.sxx).sum::<f64>() / bulk.iter().map(|b| b.syy).sum::<f64>();
    let k_bands = means.iter().map(|b| b.sxx / b.syy).collect();
    let (rl, rr) = (left.resultant(), right.resultant());
    let mu_l = rl.y / rl.x;
    let mu_r = -rr.y / rr.x;
    // resultants: left (−P_l, S_l), right (P_r, S_r) with P the normal
    // forces and S the shear forces along +y (< 0: dragged down)
    let mu_w = -(rl.y + rr.y) / (rr.x - rl.x);
    let floor = floor * per;
    let walls_vertical = [-rl.y, -rr.y];
    let balance_error = (floor + walls_vertical[0] + walls_vertical[1] - weight) / weight;
    let w = silo.width();
    let (pl, pr) = (left.profile(), right.profile());
    let compared: Vec<Compared> = pl
        .iter()
        .zip(&pr)
        .filter_map(|(a, b)| {
            let z = surf - a.mid();
            (z >= w).then(|| Compared {
                depth: z,
                measured: 0.5 * (a.normal + b.normal),
                janssen: k * janssen(rho_b, silo.g, w, mu_w, k, z),
                hydrostatic: k * rho_b * silo.g * z,
            })
        })
        .collect();
    let dev: Vec<f64> = compared
        .iter()
        .map(|c| c.measured / c.janssen - 1.0)
        .collect();
    let (mut sy, mut sj) = (0.0, 0.0);
    for b in bulk {
        let z = surf - 0.5 * (b.y_lo + b.y_hi);
        if z >= w {
            sy += b.syy;
            sj += janssen(rho_b, silo.g, w, mu_w, k, z);
        }
    }
    Ok(SiloResult {
        sigma_v_deviation: sy / sj - 1.0,
        width: w,
        surface: surf,
        height_over_width: (surf - y0) / w,
        window: win,
        kinetic: kin * per,
        left: pl,
        right: pr,
        bands: means.clone(),
        porosity,
        rho_b,
        mu_w,
        mu_w_walls: [mu_l, mu_r],
        k,
        k_bands,
        weight,
        floor,
        walls_vertical,
        balance_error,
        walls_horizontal: [-rl.x, rr.x],
        max_deviation: dev.iter().fold(0.0f64, |a, d| a.max(d.abs())),
        mean_deviation: dev.iter().sum::<f64>() / dev.len().max(1) as f64,
        thrust_deviation: compared.iter().map(|c| c.measured).sum::<f64>()
            / compared.iter().map(|c| c.janssen).sum::<f64>()
            - 1.0,
        compared,
        sigma_v_infinity: rho_b * silo.g * w / (2.0 * mu_w * k),
    })
}

/// `sc` with the disc generator's seed replaced by `seed` (the fills of
/// an ensemble); an error if the discs are not generated.
pub fn with_seed(sc: &Scenario, seed: u64) -> Result<Scenario, String> {
    let mut sc = sc.clone();
    match sc.granular.as_mut().map(|g| &mut g.discs) {
        Some(DiscsSpec::Table(t)) if t.generate.is_some() => {
            t.seed = seed;
            Ok(sc)
        }
        _ => Err("an ensemble of fills needs generated discs (`discs = { generate = … }`)".into()),
    }
}

/// Run `fills` fills of the silo `sc`: the disc seeds `seed, seed + 1, …`
/// from the scenario's own; `progress(fill, t)` as in [`run`]. The fills
/// run side by side on the rayon pool (each one's result does not depend
/// on the threads); the results are in seed order.
pub fn run_fills(
    sc: &Scenario,
    opts: &Options,
    fills: usize,
    progress: impl Fn(usize, f64) + Sync,
) -> Result<Vec<SiloResult>, String> {
    use rayon::prelude::*;
    let seed0 = match sc.granular.as_ref().map(|g| &g.discs) {
        Some(DiscsSpec::Table(t)) => t.seed,
        _ => 1,
    };
    (0..fills)
        .into_par_iter()
        .map(|k| {
            let s = with_seed(sc, seed0 + k as u64)?;
            run(&s, opts, |t| progress(k, t))
        })
        .collect()
}

/// One wall bin of the ensemble comparison.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EnsembleBin {
    /// Depth of the bin's middle below the mean surface (m).
    pub depth: f64,
    /// The bin's wall pressure (mean of the two walls) in each fill (Pa).
    pub fills: Vec<f64>,
    /// Mean over the fills (Pa).
    pub measured: f64,
    /// Standard deviation between the fills (Pa; 0 for one fill).
    pub spread: f64,
    /// Standard error of the mean, `spread / √N` (Pa).
    pub std_error: f64,
    /// Janssen's `K σ_v(z)` with the pooled μ_w, K, ρ_b (Pa).
    pub janssen: f64,
    /// `K ρ_b g z` (Pa).
    pub hydrostatic: f64,
}

impl EnsembleBin {
    /// measured / janssen − 1.
    pub fn deviation(&self) -> f64 {
        self.measured / self.janssen - 1.0
    }
}

/// The fills of [`run_fills`] pooled ([`ensemble`]).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Ensemble {
    /// Number of fills.
    pub fills: usize,
    /// Silo width W (m).
    pub width: f64,
    /// Mean free surface (y, m).
    pub surface: f64,
    /// Largest |surface − mean| over the fills (m).
    pub surface_spread: f64,
    /// Fill height over W (mean surface).
    pub height_over_width: f64,
    /// Mean bulk density over the fills (kg/m³).
    pub rho_b: f64,
    /// Pooled wall friction `Σ walls' vertical / Σ walls' normal` over
    /// both walls and all fills.
    pub mu_w: f64,
    /// Pooled μ_w of the left and right walls.
    pub mu_w_walls: [f64; 2],
    /// μ_w of each fill.
    pub mu_w_fills: Vec<f64>,
    /// Pooled K: Σ σ_xx / Σ σ_yy over the bands below the top one of all
    /// fills.
    pub k: f64,
    /// K of each fill.
    pub k_fills: Vec<f64>,
    /// Largest |weight balance error| over the fills.
    pub balance_error: f64,
    /// Wall bins deeper than W (bottom to top).
    pub compared: Vec<EnsembleBin>,
    /// Largest |deviation| over `compared`.
    pub max_deviation: f64,
    /// Σ measured / Σ janssen − 1 over `compared`.
    pub thrust_deviation: f64,
    /// Root mean square over `compared` of spread / measured: the
    /// relative scatter of one fill's bin.
    pub fill_scatter: f64,
    /// Janssen's σ_v asymptote with the pooled parameters (Pa).
    pub sigma_v_infinity: f64,
}

/// Pool the fills `runs` (same scenario, other seeds): μ_w, K from the
/// summed forces and band stresses, ρ_b and the surface averaged, each
/// wall bin's pressure averaged over the fills at its height, and compare
/// with Janssen at the mean surface. `g` = |gravity|.
pub fn ensemble(runs: &[SiloResult], g: f64) -> Result<Ensemble, String> {
    let first = runs.first().ok_or("no fill")?;
    let n = runs.len() as f64;
    if runs
        .iter()
        .any(|r| r.left.len() != first.left.len() || r.width != first.width)
    {
        return Err("the fills differ in geometry or bins".into());
    }
    let surface = runs.iter().map(|r| r.surface).sum::<f64>() / n;
    let surface_spread = runs
        .iter()
        .fold(0.0f64, |a, r| a.max((r.surface - surface).abs()));
    let rho_b = runs.iter().map(|r| r.rho_b).sum::<f64>() / n;
    let sum = |f: &dyn Fn(&SiloResult) -> f64| runs.iter().map(f).sum::<f64>();
    let mu_w = sum(&|r| r.walls_vertical[0] + r.walls_vertical[1])
        / sum(&|r| r.walls_horizontal[0] + r.walls_horizontal[1]);
    let mu_w_walls =
        [0, 1].map(|k| sum(&|r| r.walls_vertical[k]) / sum(&|r| r.walls_horizontal[k]));
    let bulk = |r: &SiloResult| r.bands.len().saturating_sub(1).max(1);
    let k = sum(&|r| r.bands[..bulk(r)].iter().map(|b| b.sxx).sum())
        / sum(&|r| r.bands[..bulk(r)].iter().map(|b| b.syy).sum());
    let w = first.width;
    let y0 = first.surface - first.height_over_width * w;
    let compared: Vec<EnsembleBin> = (0..first.left.len())
        .filter_map(|i| {
            let z = surface - first.left[i].mid();
            if z < w {
                return None;
            }
            let fills: Vec<f64> = runs
                .iter()
                .map(|r| 0.5 * (r.left[i].normal + r.right[i].normal))
                .collect();
            let measured = fills.iter().sum::<f64>() / n;
            let spread = if runs.len() > 1 {
                (fills.iter().map(|p| (p - measured).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
            } else {
                0.0
            };
            Some(EnsembleBin {
                depth: z,
                fills,
                measured,
                spread,
                std_error: spread / n.sqrt(),
                janssen: k * janssen(rho_b, g, w, mu_w, k, z),
                hydrostatic: k * rho_b * g * z,
            })
        })
        .collect();
    let m = compared.len().max(1) as f64;
    Ok(Ensemble {
        fills: runs.len(),
        width: w,
        surface,
        surface_spread,
        height_over_width: (surface - y0) / w,
        rho_b,
        mu_w,
        mu_w_walls,
        mu_w_fills: runs.iter().map(|r| r.mu_w).collect(),
        k,
        k_fills: runs.iter().map(|r| r.k).collect(),
        balance_error: runs
            .iter()
            .fold(0.0f64, |a, r| a.max(r.balance_error.abs())),
        max_deviation: compared
            .iter()
            .fold(0.0f64, |a, c| a.max(c.deviation().abs())),
        thrust_deviation: compared.iter().map(|c| c.measured).sum::<f64>()
            / compared.iter().map(|c| c.janssen).sum::<f64>()
            - 1.0,
        fill_scatter: (compared
            .iter()
            .map(|c| (c.spread / c.measured).powi(2))
            .sum::<f64>()
            / m)
            .sqrt(),
        compared,
        sigma_v_infinity: rho_b * g * w / (2.0 * mu_w * k),
    })
}

/// `silo.png` in `dir`: the wall pressure against depth (kPa) — each
/// fill's bins (mean of the two walls; for one fill each wall) and their
/// mean over the fills — with Janssen's `K σ_v(z)` of the pooled
/// parameters, its ±15 % band and the frictionless `K ρ_b g z`; and
/// `silo_vertical.png`: the bands' σ_yy of every fill against Janssen's
/// σ_v and `ρ_b g z`.
pub fn plot(dir: &Path, runs: &[SiloResult], e: &Ensemble, g: f64) -> Result<(), PlotError> {
    let depth = |b: &TractionBin| 1e3 * (e.surface - b.mid());
    let Some(first) = runs.first() else {
        return Ok(());
    };
    let filled: Vec<usize> = (0..first.left.len())
        .filter(|&i| first.left[i].mid() < e.surface)
        .collect();
    let wall = |f: &dyn Fn(&SiloResult, usize) -> f64| -> Vec<(f64, f64)> {
        runs.iter()
            .flat_map(|r| {
                filled
                    .iter()
                    .map(move |&i| (depth(&r.left[i]), 1e-3 * f(r, i)))
            })
            .collect()
    };
    let mean: Vec<(f64, f64)> = filled
        .iter()
        .map(|&i| {
            let p = runs
                .iter()
                .map(|r| 0.5 * (r.left[i].normal + r.right[i].normal))
                .sum::<f64>()
                / runs.len() as f64;
            (depth(&first.left[i]), 1e-3 * p)
        })
        .collect();
    let zmax = e.height_over_width * e.width;
    let curve = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..=100)
            .map(|i| {
                let z = zmax * i as f64 / 100.0;
                (1e3 * z, 1e-3 * f(z))
            })
            .collect()
    };
    let jan = |z: f64| janssen(e.rho_b, g, e.width, e.mu_w, e.k, z);
    let mut series = if runs.len() == 1 {
        vec![
            Series::new("left wall", wall(&|r, i| r.left[i].normal), Mark::Points)
                .with_color(palette(0)),
            Series::new("right wall", wall(&|r, i| r.right[i].normal), Mark::Points)
                .with_color(palette(1)),
        ]
    } else {
        vec![
            Series::new(
                "single fills (mean of the two walls)",
                wall(&|r, i| 0.5 * (r.left[i].normal + r.right[i].normal)),
                Mark::Points,
            )
            .with_color(REFERENCE_COLOR),
        ]
    };
    series.extend([
        Series::new(
            if runs.len() == 1 {
                "mean of the two walls".to_string()
            } else {
                format!("mean of {} fills (both walls)", runs.len())
            },
            mean,
            Mark::Diamonds,
        )
        .with_color(palette(3)),
        Series::new("Janssen K σ_v(z)", curve(&|z| e.k * jan(z)), Mark::Line)
            .with_color(palette(2)),
        Series::new(
            "Janssen ± 15 %",
            curve(&|z| 1.15 * e.k * jan(z)),
            Mark::Dashed,
        )
        .with_color(palette(2)),
        Series::new(
            "Janssen ± 15 %",
            curve(&|z| 0.85 * e.k * jan(z)),
            Mark::Dashed,
        )
        .with_color(palette(2)),
        Series::new(
            "no wall friction K ρ_b g z",
            curve(&|z| e.k * e.rho_b * g * z),
            Mark::Dashed,
        )
        .with_color(REFERENCE_COLOR),
        Series::vlines("z = W", &[1e3 * e.width]),
    ]);
    let chart = Chart {
        title: "Silo: wall pressure against depth".into(),
        x_label: "depth below the surface z (mm)".into(),
        y_label: "wall normal stress σ_h (kPa)".into(),
        series,
        notes: vec![
            format!(
                "measured, pooled over {} fill{}: μ_w = {:.3}, K = {:.3}, ρ_b = {:.0} kg/m³, W = {:.0} mm",
                e.fills,
                if e.fills == 1 { "" } else { "s" },
                e.mu_w,
                e.k,
                e.rho_b,
                1e3 * e.width
            ),
            format!(
                "below z = W: thrust {:+.1} %, bins: max |dev| {:.1} %",
                100.0 * e.thrust_deviation,
                100.0 * e.max_deviation
            ),
        ],
        ..Chart::default()
    };
    line_chart(&dir.join("silo.png"), &chart, 1000, 600)?;
    let bands: Vec<(f64, f64)> = runs
        .iter()
        .flat_map(|r| {
            r.bands
                .iter()
                .filter(|b| b.y_hi <= r.surface)
                .map(|b| (1e3 * (r.surface - 0.5 * (b.y_lo + b.y_hi)), 1e-3 * b.syy))
        })
        .collect();
    let v = Chart {
        title: "Silo: vertical stress in the grains against depth".into(),
        x_label: "depth below the surface z (mm)".into(),
        y_label: "σ_yy (kPa)".into(),
        series: vec![
            Series::new("bands σ_yy (Love–Weber)", bands, Mark::Points).with_color(palette(0)),
            Series::new("Janssen σ_v(z)", curve(&jan), Mark::Line).with_color(palette(2)),
            Series::new(
                "no wall friction ρ_b g z",
                curve(&|z| e.rho_b * g * z),
                Mark::Dashed,
            )
            .with_color(REFERENCE_COLOR),
        ],
        ..Chart::default()
    };
    line_chart(&dir.join("silo_vertical.png"), &v, 1000, 600)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fill of a 40 mm silo whose wall bins (20 mm, floor at y = 0)
    /// press `factor × pressure(z)`, z below `surface`.
    fn fill(
        surface: f64,
        vertical: [f64; 2],
        horizontal: [f64; 2],
        band: (f64, f64),
        pressure: &dyn Fn(f64) -> f64,
        factor: f64,
    ) -> SiloResult {
        let bins = |_| -> Vec<TractionBin> {
            (0..12)
                .map(|i| {
                    let (from, to) = (0.02 * i as f64, 0.02 * (i + 1) as f64);
                    TractionBin {
                        from,
                        to,
                        normal: factor * pressure(0.12 - 0.5 * (from + to)),
                        shear: 0.0,
                        contacts: 5.0,
                    }
                })
                .collect()
        };
        let b = |y_lo, sxx, syy| BandMean {
            y_lo,
            y_hi: y_lo + 0.06,
            sxx,
            syy,
            sxy: 0.0,
            porosity: 0.2,
        };
        SiloResult {
            width: 0.04,
            surface,
            height_over_width: surface / 0.04,
            window: Window {
                samples: 10,
                from: 0.0,
                to: 0.0,
            },
            kinetic: 0.0,
            left: bins(0),
            right: bins(1),
            // the top band (surface) must not count in K
            bands: vec![b(0.0, band.0, band.1), b(0.06, 1e6, 1.0)],
            porosity: 0.2,
            rho_b: 2000.0,
            mu_w: 0.0,
            mu_w_walls: [0.0; 2],
            k: 0.0,
            k_bands: vec![],
            weight: 1.0,
            floor: 1.0,
            walls_vertical: vertical,
            balance_error: 1e-4,
            walls_horizontal: horizontal,
            compared: vec![],
            max_deviation: 0.0,
            mean_deviation: 0.0,
            thrust_deviation: 0.0,
            sigma_v_deviation: 0.0,
            sigma_v_infinity: 0.0,
        }
    }

    /// `with_seed` sets the generator's seed of a copy and refuses
    /// discs that are not generated.
    #[test]
    fn with_seed_replaces_the_generators_seed() {
        let sc = crate::scenario::load(Path::new("examples/silo.toml")).unwrap();
        let s = with_seed(&sc, 7).unwrap();
        let seed = |sc: &Scenario| match sc.granular.as_ref().map(|g| &g.discs) {
            Some(DiscsSpec::Table(t)) => t.seed,
            _ => 0,
        };
        assert_eq!((seed(&sc), seed(&s)), (1, 7));
        let mut inline = sc.clone();
        inline.granular.as_mut().unwrap().discs = DiscsSpec::Inline(vec![[0.0, 0.0, 1.0]]);
        assert!(with_seed(&inline, 2).is_err());
    }

    /// Two fills pressing 1.1 and 0.9 × Janssen's pressure of the pooled
    /// parameters (μ_w = Σ vertical / Σ normal = 8/60 over both walls, K =
    /// Σ σ_xx / Σ σ_yy = 4/4 without the top bands, the mean surface
    /// 0.12 m): the mean is Janssen to round-off, the scatter between the
    /// fills √2 · 0.1 and the standard error 0.1 of the pressure.
    #[test]
    fn ensemble_pools_the_fills() {
        let (mu, k, g) = (8.0 / 60.0, 1.0, 9.81);
        let p = |z: f64| k * janssen(2000.0, g, 0.04, mu, k, z);
        let a = fill(0.121, [1.0, 3.0], [10.0, 10.0], (1.0, 2.0), &p, 1.1);
        let b = fill(0.119, [2.0, 2.0], [10.0, 30.0], (3.0, 2.0), &p, 0.9);
        let e = ensemble(&[a, b], g).unwrap();
        assert!((e.mu_w - mu).abs() < 1e-15, "{}", e.mu_w);
        assert!((e.mu_w_walls[0] - 3.0 / 20.0).abs() < 1e-15);
        assert!((e.mu_w_walls[1] - 5.0 / 40.0).abs() < 1e-15);
        assert!((e.k - 1.0).abs() < 1e-15, "{}", e.k);
        assert!((e.surface - 0.12).abs() < 1e-15 && (e.surface_spread - 0.001).abs() < 1e-12);
        assert_eq!(e.compared.len(), 4, "bins deeper than W = 40 mm");
        for c in &e.compared {
            assert!(c.deviation().abs() < 1e-12, "{c:?}");
            assert!((c.spread - 2f64.sqrt() * 0.1 * c.janssen).abs() < 1e-9 * c.janssen);
            assert!((c.std_error - 0.1 * c.janssen).abs() < 1e-9 * c.janssen);
        }
        assert!(e.max_deviation < 1e-12 && e.thrust_deviation.abs() < 1e-12);
        assert!((e.fill_scatter - 0.02f64.sqrt()).abs() < 1e-9);
        assert_eq!(e.balance_error, 1e-4);
    }
}
