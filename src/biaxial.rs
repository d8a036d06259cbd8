//! Post-processing of a biaxial test: from the scenario and
//! the `history.csv` of its run, the strains, the principal stresses, the
//! deviatoric stress `q = σ₁ − σ₃`, the mobilised friction angle
//! `sin φ = (σ₁ − σ₃)/(σ₁ + σ₃)`, the peak and critical-state friction
//! angles and the dilatancy angle. `examples/biaxial.toml` is such a test
//! and `examples/biaxial_post.rs` the command around this module.
//!
//! **The test the scenario must describe** ([`Setup::from_scenario`]): two
//! horizontal *axial* walls that follow a strain rate from some step on —
//! by `strain_rate`, usually as the last of their `phases` after a servo
//! consolidation — and two vertical *lateral* walls that are servos at
//! that step (σ₃ is their `stress`). The history needs each of the four
//! walls' `wall_stress` probe, `wall_y` of the axial and `wall_x` of the
//! lateral walls, and a row at the step where the strain rate begins (the
//! reference state of the strains). A rectangular `[[measure]]` that holds
//! the whole sample (the walls' box at t = 0 and every later one) with
//! `sxx` and `syy` columns gives the whole sample's Love–Weber stress: its
//! columns times (its area)/(the walls' box), which equals the walls'
//! stresses in equilibrium ([`Point::love_weber`]), in the rows where the
//! walls' box is inside it (a sample between frictionless platens may
//! drift sideways).
//!
//! **Conventions** (compression positive, as the walls' stresses):
//! - axial strain `ε₁ = (H₀ − H)/H₀`, lateral `ε₃ = (W₀ − W)/W₀`,
//!   volumetric (area) strain `ε_v = (A₀ − A)/A₀` with `A = H W`
//!   (engineering strains from the state where the strain rate begins);
//! - `σ₁`: mean of the two axial walls' stresses, `σ₃`: of the lateral
//!   walls'; `q = σ₁ − σ₃`, `p = (σ₁ + σ₃)/2`;
//! - dilatancy angle (2D, Vermeer & de Borst 1984; the brief's form):
//!   `sin ψ = −(dε_v/dε₁)/(2 − dε_v/dε₁)`, i.e.
//!   `−(dε₁ + dε₃)/(dε₁ − dε₃)`, with the slope of the logarithmic
//!   strains `ln(A₀/A)` against `ln(H₀/H)` (rates of deformation) by least
//!   squares over a window of ε₁; ψ > 0 dilates.
//!
//! **Summary** ([`summarize`]): the peak friction angle from the largest
//! `sin φ` of the curve smoothed by a moving average over a window of ε₁
//! (the wall stresses of a sample of a few thousand discs fluctuate by a
//! few per cent from row to row); the critical-state angle from the mean
//! `sin φ` over the last third of the axial strain, with `dε_v/dε₁` over
//! the same range, which is 0 at the critical state; the largest
//! dilatancy angle and the one at the stress peak.

pub use crate::output::csv::History;
use crate::output::plot::{Chart, Mark, PlotError, Series, line_chart};
use crate::scenario::Scenario;
use crate::scenario::granular::{DiscsSpec, Radius, ServoSpec, WallSpec};
use std::path::Path;

/// Where a biaxial test's quantities are (module docs).
#[derive(Debug, Clone)]
pub struct Setup {
    /// The step at which the axial walls begin to follow their strain
    /// rate: the reference state of the strains.
    pub shear_from: usize,
    /// The axial strain rate ε̇ (1/s, true strain, compression positive).
    pub strain_rate: f64,
    /// The confining stress σ₃ of the lateral servo walls.
    pub sigma3: f64,
    /// History columns of the axial walls' stresses (bottom, top).
    pub axial_stress: [String; 2],
    /// History columns of the axial walls' `wall_y` (bottom, top).
    pub axial_position: [String; 2],
    /// History columns of the lateral walls' stresses (left, right).
    pub lateral_stress: [String; 2],
    /// History columns of the lateral walls' `wall_x` (left, right).
    pub lateral_position: [String; 2],
    /// A `[[measure]]` rectangle around the whole sample: its name and
    /// `[[x0, y0], [x1, y1]]`.
    pub whole: Option<(String, [[f64; 2]; 2])>,
    /// Mean disc diameter d̄, when the scenario gives the radii (a
    /// generated packing: uniform radii; inline discs).
    pub mean_diameter: Option<f64>,
    /// Density of the discs' material.
    pub density: f64,
}

/// The motion of a wall at `step`: its servo and its strain rate (one of
/// them at most).
fn motion_at(w: &WallSpec, step: usize) -> (Option<&ServoSpec>, Option<f64>) {
    match &w.phases {
        None => (w.servo.as_ref(), w.strain_rate),
        Some(phases) => {
            let mut from = 0;
            for p in phases {
                let until = p.until_step.unwrap_or(usize::MAX);
                if step >= from && step < until {
                    return (p.servo.as_ref(), p.strain_rate);
                }
                from = until;
            }
            (None, None)
        }
    }
}

impl Setup {
    /// Find the test in a scenario (module docs); an error says what is
    /// missing.
    pub fn from_scenario(sc: &Scenario) -> Result<Setup, String> {
        let horizontal = |w: &WallSpec| (w.to[1] - w.from[1]).abs() < (w.to[0] - w.from[0]).abs();
        // the axial walls: horizontal, following a strain rate from some step
        let mut axial: Vec<(&WallSpec, usize, f64)> = sc
            .wall
            .iter()
            .filter(|w| horizontal(w))
            .filter_map(|w| {
                w.strain_rate_spans()
                    .first()
                    .map(|&(from, _, rate, _)| (w, from, rate))
            })
            .collect();
        if axial.len() != 2 {
            return Err(format!(
                "a biaxial test needs two horizontal walls that follow a strain rate (found {})",
                axial.len()
            ));
        }
        axial.sort_by(|a, b| a.0.from[1].total_cmp(&b.0.from[1]));
        let (shear_from, strain_rate) = (axial[0].1, axial[0].2);
        if axial[1].1 != shear_from || axial[1].2 != strain_rate {
            return Err(
                "the two axial walls must follow the same strain rate from the same step".into(),
            );
        }
        let mut lateral: Vec<(&WallSpec, f64)> = sc
            .wall
            .iter()
            .filter(|w| !horizontal(w))
            .filter_map(|w| motion_at(w, shear_from).0.map(|s| (w, s.stress)))
            .collect();
        if lateral.len() != 2 {
            return Err(format!(
                "a biaxial test needs two vertical servo walls while the axial walls are compressed, from step {shear_from} (found {})",
                lateral.len()
            ));
        }
        lateral.sort_by(|a, b| a.0.from[0].total_cmp(&b.0.from[0]));
        if lateral[0].1 != lateral[1].1 {
            return Err("the two lateral walls must hold the same stress σ₃".into());
        }
        let probe = |w: &WallSpec, q: &str| {
            sc.probe
                .iter()
                .find(|p| p.quantity == q && p.wall.as_deref() == Some(w.name.as_str()))
                .map(|p| p.name.clone())
                .ok_or_else(|| {
                    format!(
                        "the scenario needs a [[probe]] with quantity = \"{q}\", wall = \"{}\"",
                        w.name
                    )
                })
        };
        let g = sc
            .granular
            .as_ref()
            .ok_or("the scenario has no [granular]")?;
        let density = sc.material(&g.material).map_or(0.0, |m| m.density);
        let mean_diameter = match &g.discs {
            DiscsSpec::Table(t) => t.radius.map(|r| match r {
                Radius::One(r) => 2.0 * r,
                Radius::Range([a, b]) => a + b,
            }),
            DiscsSpec::Inline(rows) if !rows.is_empty() => {
                Some(2.0 * rows.iter().map(|r| r[2]).sum::<f64>() / rows.len() as f64)
            }
            DiscsSpec::Inline(_) => None,
        };
        // a measure rectangle around the whole sample at t = 0 (the
        // sample only shrinks axially; allow it to widen)
        let (x0, x1) = (
            lateral[0].0.from[0].min(lateral[0].0.to[0]),
            lateral[1].0.from[0].max(lateral[1].0.to[0]),
        );
        let (y0, y1) = (axial[0].0.from[1], axial[1].0.from[1]);
        let whole = sc.measure.iter().find_map(|m| {
            let [a, b] = m.rectangle?;
            let q = m.quantities();
            let has = |n: &str| q.iter().any(|x| x.name() == n);
            let w = x1 - x0;
            (a[0] <= x0 - 0.1 * w
                && b[0] >= x1 + 0.1 * w
                && a[1] <= y0
                && b[1] >= y1
                && has("sxx_cpos")
                && has("syy_cpos"))
            .then(|| (m.name.clone(), [a, b]))
        });
        Ok(Setup {
            shear_from,
            strain_rate,
            sigma3: lateral[0].1,
            axial_stress: [
                probe(axial[0].0, "wall_stress")?,
                probe(axial[1].0, "wall_stress")?,
            ],
            axial_position: [probe(axial[0].0, "wall_y")?, probe(axial[1].0, "wall_y")?],
            lateral_stress: [
                probe(lateral[0].0, "wall_stress")?,
                probe(lateral[1].0, "wall_stress")?,
            ],
            lateral_position: [
                probe(lateral[0].0, "wall_x")?,
                probe(lateral[1].0, "wall_x")?,
            ],
            whole,
            mean_diameter,
            density,
        })
    }

    /// The inertial number of the shearing, `I = ε̇ d̄ √(ρ/σ₃)` (GDR MiDi
    /// 2004; da Cruz et al. 2005): quasi-static below about 10⁻³.
    pub fn inertial_number(&self) -> Option<f64> {
        self.mean_diameter
            .map(|d| self.strain_rate * d * (self.density / self.sigma3).sqrt())
    }
}

/// One row of the shearing.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Point {
    /// Step of the row.
    pub step: usize,
    /// Time (s).
    pub t: f64,
    /// Axial strain `(H₀ − H)/H₀`.
    pub eps1: f64,
    /// Lateral strain `(W₀ − W)/W₀` (negative: the sample widens).
    pub eps3: f64,
    /// Volumetric (area) strain `(A₀ − A)/A₀` (negative: dilation).
    pub epsv: f64,
    /// `ln(H₀/H)`.
    pub log1: f64,
    /// `ln(A₀/A)`.
    pub logv: f64,
    /// σ₁: mean stress of the two axial walls.
    pub sigma1: f64,
    /// σ₃: mean stress of the two lateral walls.
    pub sigma3: f64,
    /// The two lateral walls' stresses.
    pub lateral: [f64; 2],
    /// `q = σ₁ − σ₃`.
    pub q: f64,
    /// `sin φ = (σ₁ − σ₃)/(σ₁ + σ₃)`.
    pub sin_phi: f64,
    /// The whole sample's Love–Weber stress `[axial (σ_yy), lateral
    /// (σ_xx)]`: the whole-sample measure's columns × (its area)/(H W);
    /// `None` when the walls' box is not inside that measure's rectangle.
    pub love_weber: Option<[f64; 2]>,
}

/// The shearing part of a history: one [`Point`] per row from the row at
/// [`Setup::shear_from`] (ε = 0) on.
pub fn curve(setup: &Setup, h: &History) -> Result<Vec<Point>, String> {
    let col = |n: &str| h.column(n);
    let pair = |n: &[String; 2]| -> Result<[usize; 2], String> { Ok([col(&n[0])?, col(&n[1])?]) };
    let (step, t) = (col("step")?, col("t")?);
    let (sa, ya) = (pair(&setup.axial_stress)?, pair(&setup.axial_position)?);
    let (sl, xl) = (pair(&setup.lateral_stress)?, pair(&setup.lateral_position)?);
    let whole = match &setup.whole {
        Some((name, rect)) => Some((
            col(&format!("{name}_syy_cpos"))?,
            col(&format!("{name}_sxx_cpos"))?,
            *rect,
        )),
        None => None,
    };
    let first = h
        .rows
        .iter()
        .position(|r| r[step] as usize == setup.shear_from)
        .ok_or_else(|| {
            format!(
                "history.csv has no row at step {} (where the strain rate begins, the reference state of the strains): set [output] every to a divisor of it",
                setup.shear_from
            )
        })?;
    let size = |r: &[f64]| (r[ya[1]] - r[ya[0]], r[xl[1]] - r[xl[0]]);
    let (h0, w0) = size(&h.rows[first]);
    Ok(h.rows[first..]
        .iter()
        .map(|r| {
            let (hh, ww) = size(r);
            let sigma1 = 0.5 * (r[sa[0]] + r[sa[1]]);
            let sigma3 = 0.5 * (r[sl[0]] + r[sl[1]]);
            Point {
                step: r[step] as usize,
                t: r[t],
                eps1: (h0 - hh) / h0,
                eps3: (w0 - ww) / w0,
                epsv: (h0 * w0 - hh * ww) / (h0 * w0),
                log1: (h0 / hh).ln(),
                logv: (h0 * w0 / (hh * ww)).ln(),
                sigma1,
                sigma3,
                lateral: [r[sl[0]], r[sl[1]]],
                q: sigma1 - sigma3,
                sin_phi: (sigma1 - sigma3) / (sigma1 + sigma3),
                love_weber: whole.and_then(|(yy, xx, [a, b])| {
                    // only while the walls' box is inside the rectangle
                    // (the sample may drift sideways)
                    let inside = r[xl[0]] >= a[0]
                        && r[xl[1]] <= b[0]
                        && r[ya[0]] >= a[1]
                        && r[ya[1]] <= b[1];
                    let s = (b[0] - a[0]) * (b[1] - a[1]) / (hh * ww);
                    inside.then(|| [r[yy] * s, r[xx] * s])
                }),
            }
        })
        .collect())
}

/// Windows of the [`summarize`] estimates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Width (in ε₁) of the moving average of `sin φ` whose largest value
    /// is the peak.
    pub smooth: f64,
    /// Width (in ε₁) of the least-squares slope `dε_v/dε₁`.
    pub slope: f64,
    /// The critical state is averaged over `ε₁ ≥ cs_from × ε₁,end`.
    pub cs_from: f64,
}

impl Default for Options {
    /// A 1 % window for both, the last third for the critical state.
    fn default() -> Self {
        Options {
            smooth: 0.01,
            slope: 0.01,
            cs_from: 2.0 / 3.0,
        }
    }
}

/// The results of a biaxial test ([`summarize`]); angles in degrees.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Peak friction angle φ_peak.
    pub phi_peak: f64,
    /// Axial strain at the peak.
    pub eps1_peak: f64,
    /// Critical-state friction angle φ_cs: from the mean `sin φ` over
    /// `[cs_from, cs_to]`.
    pub phi_cs: f64,
    /// Standard deviation of the smoothed `sin φ` over that range, as an angle
    /// about φ_cs (how steady the state is).
    pub phi_cs_spread: f64,
    /// Start of the critical-state range (ε₁).
    pub cs_from: f64,
    /// End of the test (ε₁).
    pub cs_to: f64,
    /// `dε_v/dε₁` over the critical-state range (0 at the critical state;
    /// negative: still dilating).
    pub dilatancy_rate_cs: f64,
    /// Largest dilatancy angle ψ_max.
    pub psi_max: f64,
    /// Axial strain where ψ is largest.
    pub eps1_psi_max: f64,
    /// Dilatancy angle at the stress peak.
    pub psi_peak: f64,
    /// Largest volumetric compression (ε_v > 0) before the sample dilates.
    pub epsv_max: f64,
    /// Final volumetric strain.
    pub epsv_end: f64,
    /// Largest `|σ_wall − σ₃|/σ₃` of either lateral wall over the shearing.
    pub sigma3_error: f64,
    /// Mean `(σ_wall − σ₃)/σ₃` of the lateral walls over the shearing.
    pub sigma3_bias: f64,
    /// Fraction of the lateral walls' stresses (two per row) within 1 %
    /// of σ₃.
    pub sigma3_within_1pc: f64,
    /// Largest relative difference between the whole sample's Love–Weber
    /// stress and the walls' (σ₁ and σ₃), both as moving averages over the
    /// window `smooth` of ε₁ (what is left is the inertia of the discs,
    /// which averages out in a quasi-static test).
    pub love_weber_error: Option<f64>,
    /// The same row by row (a rearrangement's inertia shows in single rows).
    pub love_weber_error_rows: Option<f64>,
    /// Rows whose walls' box was inside the whole-sample measure (the
    /// Love–Weber comparison uses these).
    pub love_weber_rows: usize,
    /// Rows of the shearing.
    pub rows: usize,
}

/// `sin ψ = −s/(2 − s)` of a slope `s = dε_v/dε₁`, as an angle (degrees).
pub fn dilatancy_angle(s: f64) -> f64 {
    (-s / (2.0 - s)).asin().to_degrees()
}

/// Indices of the rows whose ε₁ is within `w/2` of row `i`'s (`p` in
/// increasing ε₁, as [`curve`] gives it; never empty).
pub fn window(p: &[Point], i: usize, w: f64) -> std::ops::Range<usize> {
    let e = p[i].eps1;
    let lo = p.partition_point(|x| x.eps1 < e - 0.5 * w);
    let hi = p.partition_point(|x| x.eps1 <= e + 0.5 * w);
    lo..hi.max(lo + 1)
}

/// Least-squares slope of `logv` against `log1` over rows `r`.
fn slope(p: &[Point], r: std::ops::Range<usize>) -> f64 {
    let n = r.len() as f64;
    if r.len() < 3 {
        return f64::NAN;
    }
    let (mx, my) = p[r.clone()]
        .iter()
        .fold((0.0, 0.0), |(a, b), x| (a + x.log1 / n, b + x.logv / n));
    let (sxy, sxx) = p[r].iter().fold((0.0, 0.0), |(a, b), x| {
        (
            a + (x.log1 - mx) * (x.logv - my),
            b + (x.log1 - mx) * (x.log1 - mx),
        )
    });
    sxy / sxx
}

/// Peak and critical-state friction angles, dilatancy and the checks
/// (module docs) of the [`curve`] `p` of the test `setup`.
pub fn summarize(setup: &Setup, p: &[Point], o: &Options) -> Summary {
    let n = p.len();
    let average = |f: &dyn Fn(&Point) -> f64| -> Vec<f64> {
        (0..n)
            .map(|i| {
                let r = window(p, i, o.smooth);
                p[r.clone()].iter().map(f).sum::<f64>() / r.len() as f64
            })
            .collect()
    };
    let smooth = average(&|x| x.sin_phi);
    // over the rows whose whole window has the Love–Weber stress
    let love_weber_error = p.first().and_then(|x| x.love_weber).map(|_| {
        let lw = |k: usize| move |x: &Point| x.love_weber.map_or(f64::NAN, |l| l[k]);
        let (a1, a3) = (average(&lw(0)), average(&lw(1)));
        let (w1, w3) = (average(&|x| x.sigma1), average(&|x| x.sigma3));
        (0..n)
            .filter(|&i| a1[i].is_finite() && a3[i].is_finite())
            .fold(0.0f64, |e, i| {
                e.max(((a1[i] - w1[i]) / w1[i]).abs())
                    .max(((a3[i] - w3[i]) / w3[i]).abs())
            })
    });
    let ipk = (0..n)
        .max_by(|&a, &b| smooth[a].total_cmp(&smooth[b]))
        .unwrap_or(0);
    let slopes: Vec<f64> = (0..n).map(|i| slope(p, window(p, i, o.slope))).collect();
    let psi: Vec<f64> = slopes.iter().map(|&s| dilatancy_angle(s)).collect();
    let ipsi = (0..n)
        .filter(|&i| psi[i].is_finite())
        .max_by(|&a, &b| psi[a].total_cmp(&psi[b]))
        .unwrap_or(0);
    let end = p.last().map_or(0.0, |x| x.eps1);
    let cs_from = o.cs_from * end;
    let k0 = p.partition_point(|x| x.eps1 < cs_from);
    let cs = &p[k0..];
    let m = cs.len().max(1) as f64;
    let sin_cs = cs.iter().map(|x| x.sin_phi).sum::<f64>() / m;
    let var = smooth[k0..]
        .iter()
        .map(|s| (s - sin_cs) * (s - sin_cs))
        .sum::<f64>()
        / m;
    let deg = |s: f64| s.asin().to_degrees();
    let errors = || {
        p.iter()
            .flat_map(|x| x.lateral)
            .map(|s| (s - setup.sigma3) / setup.sigma3)
    };
    Summary {
        phi_peak: deg(smooth[ipk]),
        eps1_peak: p[ipk].eps1,
        phi_cs: deg(sin_cs),
        phi_cs_spread: deg((sin_cs + var.sqrt()).min(1.0)) - deg(sin_cs),
        cs_from,
        cs_to: end,
        dilatancy_rate_cs: slope(p, k0..n),
        psi_max: psi[ipsi],
        eps1_psi_max: p[ipsi].eps1,
        psi_peak: psi[ipk],
        epsv_max: p.iter().map(|x| x.epsv).fold(0.0, f64::max),
        epsv_end: p.last().map_or(0.0, |x| x.epsv),
        sigma3_error: errors().fold(0.0, |m, e| m.max(e.abs())),
        sigma3_bias: errors().sum::<f64>() / (2 * n).max(1) as f64,
        sigma3_within_1pc: errors().filter(|e| e.abs() <= 0.01).count() as f64
            / (2 * n).max(1) as f64,
        love_weber_error,
        love_weber_error_rows: love_weber_error.map(|_| {
            p.iter()
                .filter_map(|x| x.love_weber.map(|l| (x, l)))
                .fold(0.0f64, |e, (x, [a, l])| {
                    e.max(((a - x.sigma1) / x.sigma1).abs())
                        .max(((l - x.sigma3) / x.sigma3).abs())
                })
        }),
        love_weber_rows: p.iter().filter(|x| x.love_weber.is_some()).count(),
        rows: n,
    }
}

/// Write the curve `p` as CSV: `step, t, eps1, eps3, epsv, sigma1,
/// sigma3, q, p, sin_phi` (stresses in Pa), then `lw_sigma1, lw_sigma3`
/// when the whole sample's Love–Weber stress is known.
pub fn write_csv(path: &Path, p: &[Point]) -> std::io::Result<()> {
    use std::io::Write;
    let lw = p.first().is_some_and(|x| x.love_weber.is_some());
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    write!(f, "step,t,eps1,eps3,epsv,sigma1,sigma3,q,p,sin_phi")?;
    writeln!(f, "{}", if lw { ",lw_sigma1,lw_sigma3" } else { "" })?;
    for x in p {
        write!(
            f,
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            x.step,
            x.t,
            x.eps1,
            x.eps3,
            x.epsv,
            x.sigma1,
            x.sigma3,
            x.q,
            0.5 * (x.sigma1 + x.sigma3),
            x.sin_phi
        )?;
        match x.love_weber {
            Some([a, l]) if lw => writeln!(f, ",{a:e},{l:e}")?,
            _ => writeln!(f)?,
        }
    }
    f.flush()
}

/// PNG plots of one or more tests, each with its label: `q.png` (q in kPa
/// against ε₁ in %) and `volumetric.png` (ε_v in % against ε₁ in %,
/// compression positive) in `dir`.
pub fn plot(dir: &Path, runs: &[(String, Vec<Point>)]) -> Result<(), PlotError> {
    let series = |f: &dyn Fn(&Point) -> f64| {
        runs.iter()
            .map(|(label, p)| {
                Series::new(
                    label.clone(),
                    p.iter().map(|x| (100.0 * x.eps1, f(x))).collect(),
                    Mark::Line,
                )
            })
            .collect()
    };
    let q = Chart {
        title: "Biaxial test: deviatoric stress".into(),
        x_label: "axial strain ε₁ (%)".into(),
        y_label: "q = σ₁ − σ₃ (kPa)".into(),
        series: series(&|x| 1e-3 * x.q),
        ..Chart::default()
    };
    line_chart(&dir.join("q.png"), &q, 900, 560)?;
    let v = Chart {
        title: "Biaxial test: volumetric strain (compression positive)".into(),
        x_label: "axial strain ε₁ (%)".into(),
        y_label: "ε_v (%)".into(),
        series: series(&|x| 100.0 * x.epsv),
        ..Chart::default()
    };
    line_chart(&dir.join("volumetric.png"), &v, 900, 560)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilatancy_angle_of_simple_slopes() {
        // no volume change: ψ = 0; ε₃ = −ε₁ (dε_v = 0) ... and pure
        // dilation at dε_v/dε₁ = −2/3: sin ψ = (2/3)/(8/3) = 1/4
        assert_eq!(dilatancy_angle(0.0), 0.0);
        assert!((dilatancy_angle(-2.0 / 3.0) - 0.25f64.asin().to_degrees()).abs() < 1e-12);
        // contraction: ψ < 0
        assert!(dilatancy_angle(0.5) < 0.0);
    }

    #[test]
    fn history_parses_and_names_columns() {
        let h = History::parse("step,t,a\n0,0.0,1.5\n10,1e-3,2.5\n").unwrap();
        assert_eq!(h.column("a"), Ok(2));
        assert_eq!(h.rows[1], vec![10.0, 1e-3, 2.5]);
        assert!(h.column("b").is_err());
        assert!(History::parse("step,t\n0,1,2\n").is_err());
    }

    /// A made-up test: σ₃ = 1, σ₁ = 3 (sin φ = ½) up to ε₁ = 5 %, then
    /// σ₁ = 2 (sin φ = ⅓); the width grows so that dε_v/dε₁ = −0.5 in
    /// logarithmic strains, then stays.
    #[test]
    fn summary_of_a_made_up_test() {
        let setup = Setup {
            shear_from: 0,
            strain_rate: 1.0,
            sigma3: 1.0,
            axial_stress: ["sb".into(), "st".into()],
            axial_position: ["yb".into(), "yt".into()],
            lateral_stress: ["sl".into(), "sr".into()],
            lateral_position: ["xl".into(), "xr".into()],
            whole: None,
            mean_diameter: Some(1e-3),
            density: 1e6,
        };
        let mut text = String::from("step,t,sb,st,yb,yt,sl,sr,xl,xr\n");
        for k in 0..=150 {
            let e1 = 1e-3 * k as f64; // logarithmic axial strain
            let (s1, ev) = if e1 <= 0.05 {
                (3.0, -0.5 * e1)
            } else {
                (2.0, -0.025)
            };
            let h = (-e1).exp();
            let w = (-ev).exp() / h;
            text += &format!("{k},{k},{s1},{s1},0,{h},1,1,0,{w}\n");
        }
        let h = History::parse(&text).unwrap();
        let p = curve(&setup, &h).unwrap();
        assert!((p[10].eps1 - (1.0 - (-0.01f64).exp())).abs() < 1e-12);
        let s = summarize(&setup, &p, &Options::default());
        assert!((s.phi_peak - 30.0).abs() < 1e-9, "{s:?}");
        assert!((s.phi_cs - (1.0f64 / 3.0).asin().to_degrees()).abs() < 1e-9);
        assert!((s.psi_max - dilatancy_angle(-0.5)).abs() < 1e-9, "{s:?}");
        assert!(s.dilatancy_rate_cs.abs() < 1e-12);
        assert_eq!(s.sigma3_error, 0.0);
        assert!((setup.inertial_number().unwrap() - 1.0).abs() < 1e-12);
    }
}
