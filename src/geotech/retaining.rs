//! A flexible cantilever retaining wall, at rest or translated away from
//! its backfill (`examples/retaining_wall.toml`,
//! `examples/retaining_wall_active.toml`, `examples/retaining_wall.rs`,
//! manual: validation, "Retaining wall").
//!
//! **The scenario** ([`Wall::from_scenario`]): a coupled run with one
//! rectangular body (the wall, clamped on its bottom edge, the backfill
//! against its right edge) and grains to its right.
//!
//! **What is measured** ([`run`]), averaged over the states every
//! `every` steps from `average_from` to the end (or, with
//! [`Options::rest`], over a window of states at rest):
//! - the earth pressure σ_h and shear τ per height bin on the wall's right
//!   face ([`EdgeTraction`]), the thrust `P = Σ σ_h Δy t` and its height;
//! - the wall's deflection at the top of its centre line relative to
//!   its base, `u_x(top) − u_x(base)`, and the base's `u_x` (a translated
//!   wall: its clamp is a moving edge)
//!   ([`BodyRef::sample`](crate::model::body::BodyRef::sample));
//! - Love–Weber σ_xx, σ_yy and porosity of horizontal bands of the
//!   backfill away from the wall ([`Bands`]), their `K = σ_xx/σ_yy`;
//! - the free surface of the backfill.
//!
//! **Theory**: Jaky's `K₀ = 1 − sin φ` (φ of the biaxial test on the same
//! grains, peak or critical) gives the thrust `K₀ ρ_b g H²/2` at rest,
//! Rankine's `K_a = (1 − sin φ)/(1 + sin φ)` once the wall has moved
//! away far enough, or, for a rough wall, Coulomb's `K_a(φ, δ)` with the
//! wall friction δ = atan(drag/thrust) the run measures
//! ([`jaky_k0`], [`rankine_ka`], [`coulomb_ka`]); beam
//! theory ([`tip_deflection`]) under the *measured* binned pressure
//! (and the moment `τ h/2` of the shear traction on the face about the
//! wall's centre line) gives the top deflection, with `EI = E' h³/12`,
//! `κGA = 5/6 G h` (plane strain: `E' = E/(1 − ν²)`).

pub use super::Options;
use super::{BandMean, Bands, Window, grain_density, sample_until, surface};
use crate::continuum::cantilever::{LoadBin, tip_deflection};
use crate::continuum::{Edge, Plane};
use crate::geom::Vec2;
use crate::model::probe::global_quantity;
use crate::model::traction::{EdgeTraction, TractionBin};
use crate::output::plot::{Chart, Mark, PlotError, REFERENCE_COLOR, Series, line_chart, palette};
use crate::scenario::Scenario;
use std::path::Path;

/// Jaky's (1944) coefficient of earth pressure at rest of a normally
/// consolidated soil, `K₀ = 1 − sin φ` (φ in degrees).
pub fn jaky_k0(phi_deg: f64) -> f64 {
    1.0 - phi_deg.to_radians().sin()
}

/// Rankine's (1857) active earth pressure coefficient behind a smooth
/// vertical wall with a horizontal backfill,
/// `K_a = (1 − sin φ)/(1 + sin φ) = tan²(45° − φ/2)` (φ in degrees).
pub fn rankine_ka(phi_deg: f64) -> f64 {
    let s = phi_deg.to_radians().sin();
    (1.0 - s) / (1.0 + s)
}

/// Coulomb's (1776) active earth pressure coefficient of a vertical wall
/// with wall friction δ and a horizontal backfill (the planar wedge that
/// gives the largest thrust; e.g. Das, *Principles of Foundation
/// Engineering*, Eq. for `K_a` with α = 90°, β = 0):
///
/// `K_a = cos²φ / (cos δ (1 + √(sin(φ + δ) sin φ / cos δ))²)`,
///
/// the thrust `P_a = K_a γ H²/2` acting at δ to the wall's normal, so
/// that its horizontal component is `K_a cos δ γ H²/2`: compare a
/// measured horizontal thrust with `K_a cos δ`. δ = 0 gives
/// [`rankine_ka`]. Angles in degrees, `0 ≤ δ`, `0 < φ < 90°`.
pub fn coulomb_ka(phi_deg: f64, delta_deg: f64) -> f64 {
    let (phi, delta) = (phi_deg.to_radians(), delta_deg.to_radians());
    let root = ((phi + delta).sin() * phi.sin() / delta.cos()).sqrt();
    phi.cos().powi(2) / (delta.cos() * (1.0 + root).powi(2))
}

/// The wall a scenario describes.
#[derive(Debug, Clone)]
pub struct Wall {
    /// Left edge x, face (right edge) x.
    pub x: (f64, f64),
    /// Base and top y.
    pub y: (f64, f64),
    /// Thickness t of the body (out of plane).
    pub thickness: f64,
    /// Bending stiffness E' I per t (N m²).
    pub ei: f64,
    /// Shear stiffness κ G A per t (N).
    pub kga: f64,
    /// Far end of the backfill (x): the first `[[wall]]` right of the face
    /// that is vertical, or face + 3 × height.
    pub x_far: f64,
    /// Grain material density ρ_s.
    pub rho_s: f64,
    /// |g|.
    pub g: f64,
    /// End time of the run.
    pub end_time: f64,
}

impl Wall {
    /// Read the wall from `sc` (see the module docs).
    pub fn from_scenario(sc: &Scenario) -> Result<Wall, String> {
        let [b] = sc.body.as_slice() else {
            return Err(format!(
                "a retaining wall scenario has one body; it has {}",
                sc.body.len()
            ));
        };
        let r = &b.rectangle;
        let e = &b.elastic;
        let h = r.size[0];
        let (ep, nu) = match e.plane {
            Plane::Strain => (e.e / (1.0 - e.nu * e.nu), e.nu / (1.0 - e.nu)),
            Plane::Stress => (e.e, e.nu),
        };
        let gmod = ep / (2.0 * (1.0 + nu));
        let face = r.origin[0] + h;
        let top = r.origin[1] + r.size[1];
        let x_far = sc
            .wall
            .iter()
            .filter(|w| (w.from[0] - w.to[0]).abs() < 1e-12 && w.from[0] > face)
            .map(|w| w.from[0])
            .fold(f64::INFINITY, f64::min);
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
        Ok(Wall {
            x: (r.origin[0], face),
            y: (r.origin[1], top),
            thickness: e.thickness,
            ei: ep * e.thickness * h.powi(3) / 12.0,
            kga: 5.0 / 6.0 * gmod * e.thickness * h,
            x_far: if x_far.is_finite() {
                x_far
            } else {
                face + 3.0 * r.size[1]
            },
            rho_s: grain_density(sc)?,
            g: (g[0] * g[0] + g[1] * g[1]).sqrt(),
            end_time,
        })
    }
}

/// Everything [`run`] measures.
#[derive(Debug, Clone, serde::Serialize)]
pub struct WallResult {
    /// Free surface of the backfill (y) at the start of the window.
    pub surface: f64,
    /// Backfill height H (surface − base).
    pub height: f64,
    /// The states averaged.
    pub window: Window,
    /// Mean kinetic energy of the grains over the window (J).
    pub kinetic: f64,
    /// The face's profile (bottom to top).
    #[serde(skip)]
    pub profile: Vec<TractionBin>,
    /// Bands of the backfill (bottom to top).
    pub bands: Vec<BandMean>,
    /// Mean porosity of the bands below the top one.
    pub porosity: f64,
    /// ρ_b = ρ_s (1 − n).
    pub rho_b: f64,
    /// Thrust on the wall (N per t).
    pub thrust: f64,
    /// Height of the thrust above the base over H.
    pub thrust_height_over_h: f64,
    /// Vertical force of the grains on the face, downward positive.
    pub drag: f64,
    /// K of the wall: thrust / (ρ_b g H² t/2).
    pub k_wall: f64,
    /// K = Σσ_xx/Σσ_yy of the bands below the top one.
    pub k_bands: f64,
    /// Averaged top deflection at the centre line relative to the base,
    /// `u_x(top) − u_x(base)` (m).
    pub deflection: f64,
    /// Averaged `u_x` of the base centre (m): the wall's translation (0
    /// for a wall at rest).
    pub base_displacement: f64,
    /// Beam theory's top deflection under the measured load: bending,
    /// shear (m; signed like u_x).
    pub beam: [f64; 2],
    /// deflection / (bending + shear) − 1.
    pub beam_error: f64,
    /// Largest |u_x(top)| change over the window relative to its mean
    /// (quasi-static check).
    pub deflection_spread: f64,
    /// Change of the mean `u_x(top)` from the first to the second half of
    /// the window relative to its mean: a wall still moving (its load
    /// still changing) drifts, one at rest only fluctuates about its mean
    /// (a grain's impact moves single states, not the halves' means).
    pub deflection_drift: f64,
}

/// Run the scenario `sc` to its end time, averaging as `opts` says;
/// `progress(t)` every 1000 steps.
pub fn run(sc: &Scenario, opts: &Options, progress: impl FnMut(f64)) -> Result<WallResult, String> {
    let w = Wall::from_scenario(sc)?;
    let mut model = sc.build().map_err(|e| e.to_string())?;
    let mut face = EdgeTraction::new(0, Edge::Right, w.y.0, w.y.1, opts.bins, w.thickness)
        .map_err(|e| e.to_string())?;
    let top = Vec2::new(0.5 * (w.x.0 + w.x.1), w.y.1);
    let base = Vec2::new(0.5 * (w.x.0 + w.x.1), w.y.0);
    let mut bands: Option<Bands> = None;
    let mut surf = f64::NAN;
    let mut kin = 0.0;
    let mut ux = vec![];
    let mut ux_base = 0.0;
    let height = w.y.1 - w.y.0;
    let win = sample_until(&mut model, w.end_time, opts, progress, |m, g, c, fresh| {
        if fresh {
            // a window (again): everything averaged from here
            face.reset();
            bands = None;
            (kin, ux_base) = (0.0, 0.0);
            ux.clear();
        }
        let b = bands.get_or_insert_with(|| {
            // the backfill away from the wall: from one wall height
            // beside it (or its middle third if it is narrower)
            let x_lo = (w.x.1 + height).min(w.x.1 + (w.x_far - w.x.1) / 3.0);
            let x_hi = w
                .x_far
                .min(x_lo + height)
                .max(x_lo + (w.x_far - w.x.1) / 3.0)
                .min(w.x_far);
            surf = surface(g, w.x.1, w.x_far, 8);
            Bands::new(x_lo, x_hi, w.y.0, surf, opts.bands)
        });
        b.add(m);
        face.add(&c.contacts);
        kin += global_quantity(g, "kinetic");
        let (s, b) = (m.body(0).sample(top), m.body(0).sample(base));
        let (s, b) = (s.map_err(|e| e.to_string())?, b.map_err(|e| e.to_string())?);
        ux.push(s.u.x - b.u.x);
        ux_base += b.u.x;
        Ok(())
    })?;
    let bands = bands.ok_or("no state in the averaging window")?;
    let means = bands.means();
    let bulk = &means[..means.len().saturating_sub(1).max(1)];
    let porosity = bulk.iter().map(|b| b.porosity).sum::<f64>() / bulk.len() as f64;
    let rho_b = w.rho_s * (1.0 - porosity);
    let k_bands = bulk.iter().map(|b| b.sxx).sum::<f64>() / bulk.iter().map(|b| b.syy).sum::<f64>();
    let profile = face.profile();
    let res = face.resultant();
    let thrust = -res.x;
    let moment: f64 = profile
        .iter()
        .map(|b| b.normal * (b.to - b.from) * w.thickness * (b.mid() - w.y.0))
        .sum();
    let h = surf - w.y.0;
    let hw = w.x.1 - w.x.0;
    // the grains push the wall towards −x: q along −x; the shear τ (+y) on
    // the face at +h/2 from the centre line is a moment τ h/2 (ccw), which
    // bends it towards +x: in the sense of the deflection (−x) it is −τ h/2
    let loads: Vec<LoadBin> = profile
        .iter()
        .map(|b| LoadBin {
            from: b.from - w.y.0,
            to: b.to - w.y.0,
            q: b.normal * w.thickness,
            m: b.shear * w.thickness * 0.5 * hw,
        })
        .collect();
    let (bend, shear) = tip_deflection(height, &loads, w.ei, w.kga);
    let mean_ux = ux.iter().sum::<f64>() / ux.len() as f64;
    let spread = ux.iter().fold(0.0f64, |a, u| a.max((u - mean_ux).abs())) / mean_ux.abs();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let (first, second) = ux.split_at(ux.len() / 2);
    let drift = (mean(second) - mean(first)).abs() / mean_ux.abs();
    let beam = [-bend, -shear];
    Ok(WallResult {
        surface: surf,
        height: h,
        window: win,
        kinetic: kin / win.samples as f64,
        bands: means.clone(),
        porosity,
        rho_b,
        thrust,
        thrust_height_over_h: moment / thrust / h,
        drag: -res.y,
        k_wall: thrust / (0.5 * rho_b * w.g * h * h * w.thickness),
        k_bands,
        deflection: mean_ux,
        base_displacement: ux_base / win.samples as f64,
        beam,
        beam_error: mean_ux / (beam[0] + beam[1]) - 1.0,
        deflection_spread: spread,
        deflection_drift: drift,
        profile,
    })
}

impl WallResult {
    /// The top moved away from the base by more than 0.1 % of H (7× the
    /// at-rest example's bending): the clamp turns (a rotation about the
    /// toe), so the top's displacement is mostly rigid and beam theory
    /// does not apply to it.
    pub fn turned(&self) -> bool {
        self.deflection < -1e-3 * self.height
    }

    /// Translated (the base moved away by more than 10⁻⁴ H) or turned:
    /// compared with the active state.
    pub fn moved(&self) -> bool {
        self.base_displacement < -1e-4 * self.height || self.turned()
    }
}

/// `retaining_wall.png` in `dir`: the measured earth pressure against
/// depth (kPa) with Jaky's `K₀ ρ_b g z` for the two angles `phi` (the
/// biaxial test's peak and critical, or a measured angle and its lower
/// bound), or, for a
/// wall that has moved away (base displacement below −10⁻⁴ H, or its top
/// more than 10⁻³ H further than its base: a rotation about the toe),
/// Rankine's `K_a ρ_b g z`.
pub fn plot(dir: &Path, r: &WallResult, g: f64, phi: [f64; 2]) -> Result<(), PlotError> {
    let pts: Vec<(f64, f64)> = r
        .profile
        .iter()
        .filter(|b| b.mid() < r.surface)
        .map(|b| (1e3 * (r.surface - b.mid()), 1e-3 * b.normal))
        .collect();
    let line = |k: f64| -> Vec<(f64, f64)> {
        vec![
            (0.0, 0.0),
            (1e3 * r.height, 1e-3 * k * r.rho_b * g * r.height),
        ]
    };
    let active = r.moved();
    let k0 = |p: f64| if active { rankine_ka(p) } else { jaky_k0(p) };
    let name = if active { "Rankine K_a" } else { "Jaky K₀" };
    let chart = Chart {
        title: if r.turned() {
            format!(
                "Retaining wall, active (turned about its toe, top {:.2} mm beyond the base): earth pressure against depth",
                -1e3 * r.deflection
            )
        } else if active {
            format!(
                "Retaining wall, active (base moved {:.2} mm away): earth pressure against depth",
                -1e3 * r.base_displacement
            )
        } else {
            "Retaining wall at rest: earth pressure against depth".into()
        },
        x_label: "depth below the backfill surface z (mm)".into(),
        y_label: "earth pressure σ_h (kPa)".into(),
        series: vec![
            Series::new("measured (contact forces, binned)", pts, Mark::Points)
                .with_color(palette(0)),
            Series::new(
                format!("{name} = {:.3} (φ = {}°)", k0(phi[0]), phi[0]),
                line(k0(phi[0])),
                Mark::Line,
            )
            .with_color(palette(2)),
            Series::new(
                format!("{name} = {:.3} (φ = {}°)", k0(phi[1]), phi[1]),
                line(k0(phi[1])),
                Mark::Dashed,
            )
            .with_color(palette(1)),
            Series::new(
                format!("K = {:.3} of the backfill (bands)", r.k_bands),
                line(r.k_bands),
                Mark::Dashed,
            )
            .with_color(REFERENCE_COLOR),
        ],
        notes: vec![
            format!(
                "thrust {:.1} N/m: K_wall = {:.3}, at {:.2} H",
                r.thrust, r.k_wall, r.thrust_height_over_h
            ),
            if r.turned() {
                format!(
                    "top {:.0} µm beyond the base: the clamp turns (no beam check)",
                    -1e6 * r.deflection
                )
            } else {
                format!(
                    "top deflection (rel. to the base) {:.2} µm; beam theory under the measured load {:.2} µm ({:+.1} %)",
                    1e6 * r.deflection,
                    1e6 * (r.beam[0] + r.beam[1]),
                    100.0 * r.beam_error
                )
            },
        ],
        ..Chart::default()
    };
    line_chart(&dir.join("retaining_wall.png"), &chart, 1000, 600)
}
