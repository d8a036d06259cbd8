//! Geotechnical examples (`examples/silo.toml`,
//! `examples/retaining_wall.toml`, `examples/strip_footing.toml`): drivers that run a coupled scenario
//! through the library, average what a geotechnical engineer reads (the
//! earth pressure on a wall from the disc–body contacts, the stress and
//! density of the grains in horizontal bands) over the last part of the
//! run, and compare it with the classical theories (Janssen; Jaky and
//! beam theory). The shared pieces live here: horizontal measurement
//! bands ([`Bands`]), the free surface of a fill ([`surface`]), the weight
//! of the grains, and the scale knob ([`scale_lengths`]).

pub mod bearing;
pub mod retaining;
pub mod silo;

use crate::coupling::CoupledModel;
use crate::dem::Granular;
use crate::dem::measure::{self, OuterContact, Quantity, Region};
use crate::geom::Vec2;
use crate::model::Model;
use crate::scenario::Scenario;
use std::ops::ControlFlow;

/// How a driver averages: the window, the sampling and the bins.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// Start of the averaging window (s).
    pub average_from: f64,
    /// Steps between the states averaged.
    pub every: usize,
    /// Bins along the wall(s) (over the wall's height).
    pub bins: usize,
    /// Measurement bands of the grains (floor to surface).
    pub bands: usize,
    /// Average only states at rest ([`Rest`]); `None`: every state from
    /// `average_from` to the end.
    pub rest: Option<Rest>,
}

/// A window of states at rest. A granular fill re-settles now and then (a
/// grain toppling off the surface, an arch in a silo giving way, a slip of
/// the backfill): averages meant for a fill at rest (Janssen, Jaky, the
/// weight balance) take a window of `window` seconds in which the grains'
/// momentum stays within `|Σ m v| ≤ balance · W · window / 2` (`W` their
/// weight) at every state sampled; a state beyond it restarts the window.
/// Over such a window the grains' momentum changes by at most
/// `balance · W · window`, so the averaged forces on the grains balance
/// their weight to `balance` (Newton's second law), whatever moved before.
/// The run ends with the window (or fails at `end_time` without one).
#[derive(Debug, Clone, Copy)]
pub struct Rest {
    /// Length of the window (s).
    pub window: f64,
    /// The momentum bound as a fraction of the weight's impulse over the
    /// window (see above).
    pub balance: f64,
}

/// The states a driver averaged: how many, from and to which time.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Window {
    /// States averaged.
    pub samples: usize,
    /// Time of the first (s).
    pub from: f64,
    /// Time of the last (s).
    pub to: f64,
}

/// Is the grains' momentum within `rest`'s bound?
fn at_rest(g: &Granular, rest: &Rest) -> bool {
    let p = &g.particles;
    let (mut px, mut py, mut mass) = (0.0, 0.0, 0.0);
    for (m, v) in p.mass.iter().zip(&p.vel) {
        px += m * v.x;
        py += m * v.y;
        mass += m;
    }
    let weight = mass * g.gravity.norm();
    px.hypot(py) <= 0.5 * rest.balance * weight * rest.window
}

/// Run `model` to `end_time` and call `sample(model, grains, coupling,
/// fresh)` on every `opts.every`-th step from `opts.average_from` on
/// (with `opts.rest`: on the states of a window at rest, `fresh` at the
/// first state of each window tried: the caller starts its averages
/// again); `progress(t)` every 1000 steps. Stops at the first error of
/// `sample`. Returns the window averaged.
pub fn sample_until(
    model: &mut Model,
    end_time: f64,
    opts: &Options,
    mut progress: impl FnMut(f64),
    mut sample: impl FnMut(&Model, &Granular, &CoupledModel, bool) -> Result<(), String>,
) -> Result<Window, String> {
    let every = opts.every.max(1);
    let mut step = 0usize;
    let mut win = Window {
        samples: 0,
        from: f64::NAN,
        to: f64::NAN,
    };
    let mut err = None;
    let mut full = false;
    model
        .run_until(end_time, |m| {
            step += 1;
            if step.is_multiple_of(1000) {
                progress(m.time());
            }
            if m.time() < opts.average_from || !step.is_multiple_of(every) {
                return ControlFlow::Continue(());
            }
            let (Some(g), Some(c)) = (m.granular(), m.coupled()) else {
                err = Some("not a coupled run with grains".to_string());
                return ControlFlow::Break(());
            };
            if opts.rest.is_some_and(|r| !at_rest(g, &r)) {
                // the grains move: the window starts again
                win.samples = 0;
                return ControlFlow::Continue(());
            }
            let fresh = win.samples == 0;
            if fresh {
                win.from = m.time();
            }
            if let Err(e) = sample(m, g, c, fresh) {
                err = Some(e);
                return ControlFlow::Break(());
            }
            win.samples += 1;
            win.to = m.time();
            full = opts.rest.is_some_and(|r| win.to - win.from >= r.window);
            if full {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .map_err(|e| e.to_string())?;
    if let Some(e) = err {
        return Err(e);
    }
    match opts.rest {
        Some(r) if !full => Err(format!(
            "the grains were not at rest for {} s before t = {end_time} s (their momentum within {} of their weight's impulse)",
            r.window, r.balance
        )),
        _ => Ok(win),
    }
}

/// Time-averaged Love–Weber stress and porosity of horizontal bands of
/// the grains (the `[[measure]]` quantities of `dem::measure`, computed
/// over regions set once the fill has settled).
#[derive(Debug, Clone)]
pub struct Bands {
    /// The band rectangles, bottom to top.
    pub regions: Vec<Region>,
    /// Σ of (σ_xx, σ_yy, σ_xy, porosity) over the states added.
    sums: Vec<[f64; 4]>,
    /// States added.
    samples: usize,
}

/// The averaged state of one band.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct BandMean {
    /// Bottom of the band (m).
    pub y_lo: f64,
    /// Top of the band (m).
    pub y_hi: f64,
    /// Love–Weber σ_xx, compression positive (Pa).
    pub sxx: f64,
    /// σ_yy (Pa).
    pub syy: f64,
    /// σ_xy (Pa).
    pub sxy: f64,
    /// Porosity.
    pub porosity: f64,
}

/// Write `bands.csv`: per band its bottom, top, depth of its middle below
/// `surface`, σ_xx, σ_yy, σ_xy, porosity and K = σ_xx/σ_yy.
pub fn write_bands_csv(
    path: &std::path::Path,
    bands: &[BandMean],
    surface: f64,
) -> std::io::Result<()> {
    use std::io::Write;
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    writeln!(f, "y_lo,y_hi,depth_mid,sxx,syy,sxy,porosity,K")?;
    for b in bands {
        writeln!(
            f,
            "{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            b.y_lo,
            b.y_hi,
            surface - 0.5 * (b.y_lo + b.y_hi),
            b.sxx,
            b.syy,
            b.sxy,
            b.porosity,
            b.sxx / b.syy
        )?;
    }
    f.flush()
}

impl Bands {
    /// `n` bands of equal height between `y0` and `y1`, spanning
    /// `x0 … x1`.
    pub fn new(x0: f64, x1: f64, y0: f64, y1: f64, n: usize) -> Self {
        let h = (y1 - y0) / n as f64;
        let regions = (0..n)
            .map(|k| Region::Rectangle {
                lo: Vec2::new(x0, y0 + k as f64 * h),
                hi: Vec2::new(x1, y0 + (k + 1) as f64 * h),
            })
            .collect();
        Bands {
            regions,
            sums: vec![[0.0; 4]; n],
            samples: 0,
        }
    }

    /// Add the present state of `model`.
    pub fn add(&mut self, model: &Model) {
        let Some(g) = model.granular() else { return };
        for (r, s) in self.regions.iter().zip(&mut self.sums) {
            let outer = model.coupled().into_iter().flat_map(|m| {
                m.contacts.iter().map(|c| OuterContact {
                    slot: g.slot(c.disc as usize),
                    point: c.point,
                    normal: c.normal,
                    force: c.force,
                })
            });
            let c = measure::contacts(g, r, outer);
            s[0] += c.get(Quantity::Sxx);
            s[1] += c.get(Quantity::Syy);
            s[2] += c.get(Quantity::Sxy);
            s[3] += measure::porosity(g, r);
        }
        self.samples += 1;
    }

    /// The averages, bottom to top.
    pub fn means(&self) -> Vec<BandMean> {
        let per = 1.0 / self.samples.max(1) as f64;
        self.regions
            .iter()
            .zip(&self.sums)
            .map(|(r, s)| {
                let (lo, hi) = match r {
                    Region::Rectangle { lo, hi } => (lo.y, hi.y),
                    Region::Circle { centre, radius } => (centre.y - radius, centre.y + radius),
                };
                BandMean {
                    y_lo: lo,
                    y_hi: hi,
                    sxx: s[0] * per,
                    syy: s[1] * per,
                    sxy: s[2] * per,
                    porosity: s[3] * per,
                }
            })
            .collect()
    }
}

/// Height of the free surface of the grains between `x0` and `x1`: the
/// mean over `columns` equal columns of the highest disc top (`y + r`)
/// whose centre is in the column (empty columns are skipped).
pub fn surface(g: &Granular, x0: f64, x1: f64, columns: usize) -> f64 {
    let p = &g.particles;
    let w = (x1 - x0) / columns as f64;
    let mut top = vec![f64::NEG_INFINITY; columns];
    for (x, r) in p.pos.iter().zip(&p.radius) {
        if x.x < x0 || x.x >= x1 {
            continue;
        }
        let k = (((x.x - x0) / w) as usize).min(columns - 1);
        top[k] = top[k].max(x.y + r);
    }
    let full: Vec<f64> = top.into_iter().filter(|t| t.is_finite()).collect();
    full.iter().sum::<f64>() / full.len().max(1) as f64
}

/// Weight of all the grains, `Σ m |g|` (N per the disc length t).
pub fn weight(g: &Granular, gravity: [f64; 2]) -> f64 {
    let gn = (gravity[0] * gravity[0] + gravity[1] * gravity[1]).sqrt();
    g.particles.mass.iter().sum::<f64>() * gn
}

/// Density of the grains' material `ρ_s` (kg/m³): of `[granular]
/// material`.
pub fn grain_density(sc: &Scenario) -> Result<f64, String> {
    let g = sc
        .granular
        .as_ref()
        .ok_or("the scenario has no [granular]")?;
    sc.material(&g.material)
        .map(|m| m.density)
        .ok_or_else(|| format!("no material `{}`", g.material))
}

/// The scale knob of the examples: multiply every length of the scenario
/// by `s` except the grains' radii — body rectangles (and their node
/// counts along each side, so the node spacing stays), walls, the disc
/// generation box (and its disc count by `s²`), probe points and
/// `[[measure]]` rectangles — so a larger `s` is a larger structure in the
/// same grains. The deposit's `settle_steps` grow by `√s` (the fall time).
pub fn scale_lengths(sc: &mut Scenario, s: f64) -> Result<(), String> {
    if s.is_nan() || s <= 0.0 || !s.is_finite() {
        return Err(format!("scale must be > 0 (got {s})"));
    }
    for b in &mut sc.body {
        for k in 0..2 {
            b.rectangle.origin[k] *= s;
            b.rectangle.size[k] *= s;
            let n = b.nodes[k];
            b.nodes[k] = (((n - 1) as f64 * s).round() as usize).max(2) + 1;
        }
        if let Some(c) = &mut b.cells {
            for v in c.iter_mut() {
                *v = ((*v as f64 * s).round() as usize).max(1);
            }
        }
    }
    for w in &mut sc.wall {
        for k in 0..2 {
            w.from[k] *= s;
            w.to[k] *= s;
        }
    }
    for p in &mut sc.probe {
        if let Some(pt) = &mut p.point {
            for v in pt.iter_mut() {
                *v *= s;
            }
        }
    }
    for m in &mut sc.measure {
        if let Some(r) = &mut m.rectangle {
            for c in r.iter_mut() {
                for v in c.iter_mut() {
                    *v *= s;
                }
            }
        }
    }
    if let Some(g) = &mut sc.granular
        && let crate::scenario::granular::DiscsSpec::Table(t) = &mut g.discs
    {
        if let Some(r) = &mut t.region {
            for c in r.iter_mut() {
                for v in c.iter_mut() {
                    *v *= s;
                }
            }
        }
        if let Some(c) = &mut t.count {
            *c = (*c as f64 * s * s).round() as usize;
        }
        if let Some(n) = &mut t.settle_steps {
            *n = (*n as f64 * s.sqrt()).round() as usize;
        }
    }
    Ok(())
}
