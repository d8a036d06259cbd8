//! PNG line plots in the style of the paper's figures, drawn with plotters
//! and an embedded DejaVu Sans font (no system fonts needed).

use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Make the embedded font available to plotters as `sans-serif`.
fn register_font() {
    REGISTER.call_once(|| {
        // The font is compiled in; it parses (checked by the tests).
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// Solid line.
    Line,
    /// Dashed line (theory, references).
    Dashed,
    /// Circles at the data points, no line (sampled data).
    Points,
    /// Filled diamonds at the data points (values quoted from the paper).
    Diamonds,
    /// A dotted vertical line across the panel at the x of every point (the
    /// y values are ignored): instants or cycles the paper names. Drawn in
    /// the lower panel of a two-panel chart too (the x axis is shared).
    VLines,
}

/// An RGB colour, `(red, green, blue)`.
pub type Rgb = (u8, u8, u8);

/// Colour of the values quoted from the paper.
pub const PAPER_COLOR: Rgb = (0, 0, 0);
/// Colour of plain reference lines (e.g. the disc's weight m g).
pub const REFERENCE_COLOR: Rgb = (120, 120, 120);

const COLORS: [Rgb; 6] = [
    (0, 90, 181),
    (220, 50, 32),
    (0, 140, 60),
    (120, 60, 160),
    (230, 130, 0),
    (60, 60, 60),
];

/// The `i`-th colour of the palette that series without a colour of their
/// own take in order (so a deviation series can match its curve).
pub fn palette(i: usize) -> Rgb {
    COLORS[i % COLORS.len()]
}

/// One curve.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry; empty = not in the legend.
    pub label: String,
    /// Data points `(x, y)`, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// How the curve is drawn.
    pub mark: Mark,
    /// Colour; `None` = the next palette colour.
    pub color: Option<Rgb>,
    /// Short text written next to the points (by index; `(a)`, `(b)`, …);
    /// for [`Mark::VLines`] at the top of each line.
    pub tags: Vec<String>,
}

impl Series {
    /// A curve labelled `label` through `points`, drawn as `mark`.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, mark: Mark) -> Self {
        Series {
            label: label.into(),
            points,
            mark,
            color: None,
            tags: Vec::new(),
        }
    }

    /// Values quoted from the paper: drawn in [`PAPER_COLOR`].
    pub fn paper(label: impl Into<String>, points: Vec<(f64, f64)>, mark: Mark) -> Self {
        Series::new(label, points, mark).with_color(PAPER_COLOR)
    }

    /// Dotted vertical lines at `xs` (see [`Mark::VLines`]).
    pub fn vlines(label: impl Into<String>, xs: &[f64]) -> Self {
        Series::new(
            label,
            xs.iter().map(|&x| (x, f64::NAN)).collect(),
            Mark::VLines,
        )
    }

    /// The same series drawn in `color`.
    pub fn with_color(mut self, color: Rgb) -> Self {
        self.color = Some(color);
        self
    }

    /// The same series with `tags` written next to its points.
    pub fn with_tags<S: Into<String>>(mut self, tags: impl IntoIterator<Item = S>) -> Self {
        self.tags = tags.into_iter().map(Into::into).collect();
        self
    }
}

/// The lower panel of a two-panel chart: it shares the x axis (range and
/// caption) of the chart and is meant for deviations from a reference
/// curve, which the upper panel cannot show when curves overlap.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// y axis caption (quantity and unit).
    pub y_label: String,
    /// The curves, drawn in order (colours as in [`Series::color`]).
    pub series: Vec<Series>,
    /// y axis range; `None` = fitted to the data with a 5 % margin.
    pub y_range: Option<(f64, f64)>,
}

/// A 2D line chart, with an optional lower panel on the same x axis. The
/// legend and the notes are drawn in a column right of the plot area, so
/// they never cover data.
#[derive(Debug, Clone, Default)]
pub struct Chart {
    /// Title above the plot area.
    pub title: String,
    /// x axis caption (quantity and unit).
    pub x_label: String,
    /// y axis caption (quantity and unit).
    pub y_label: String,
    /// The curves, drawn in order.
    pub series: Vec<Series>,
    /// x axis range; `None` = fitted to the data with a 5 % margin.
    pub x_range: Option<(f64, f64)>,
    /// y axis range; `None` = fitted to the data with a 5 % margin.
    pub y_range: Option<(f64, f64)>,
    /// A second panel below the first (deviations), sharing the x axis.
    pub lower: Option<Panel>,
    /// Lines of text under the legend (what is zoomed, what the paper
    /// does not give, …); each is wrapped to the legend's width.
    pub notes: Vec<String>,
}

/// Why a plot could not be drawn.
#[derive(Debug, thiserror::Error)]
#[error("plot {path}: {message}")]
pub struct PlotError {
    /// The PNG file being drawn.
    pub path: String,
    /// What plotters reported.
    pub message: String,
}

/// Width of the legend column, in pixels.
const LEGEND_W: u32 = 350;
/// Width of the y label area (the same in both panels, so they align).
const Y_AREA: u32 = 92;

fn fitted(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
    (lo - 0.05 * span, hi + 0.05 * span)
}

fn rgb(c: Rgb) -> RGBColor {
    RGBColor(c.0, c.1, c.2)
}

/// The colour of every series of a chart, upper panel first: explicit
/// colours as given, the others from the palette in order.
fn colors(chart: &Chart) -> (Vec<Rgb>, Vec<Rgb>) {
    let mut next = 0;
    let mut pick = |s: &Series| {
        s.color.unwrap_or_else(|| {
            next += 1;
            palette(next - 1)
        })
    };
    let upper = chart.series.iter().map(&mut pick).collect();
    let lower = chart
        .lower
        .iter()
        .flat_map(|p| p.series.iter())
        .map(&mut pick)
        .collect();
    (upper, lower)
}

/// Decimals that tell the ticks of an axis spanning `span` apart (about
/// ten ticks): 0.2 → 2, 16 → 0, 0.0013 → 4.
fn tick_decimals(span: f64) -> usize {
    if !(span.is_finite() && span > 0.0) {
        return 1;
    }
    (-(span / 10.0).log10()).ceil().clamp(0.0, 8.0) as usize
}

/// A tick label with `d` decimals (no "-0").
fn tick(v: f64, d: usize) -> String {
    let s = format!("{v:.d$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// Split `text` into lines no wider than `max_w` pixels (at word breaks).
fn wrap(area: &Area, text: &str, style: &TextStyle, max_w: u32) -> Vec<String> {
    let width = |s: &str| area.estimate_text_size(s, style).map_or(0, |(w, _)| w);
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let cand = if line.is_empty() {
            word.to_string()
        } else {
            format!("{line} {word}")
        };
        if !line.is_empty() && width(&cand) > max_w {
            lines.push(std::mem::replace(&mut line, word.to_string()));
        } else {
            line = cand;
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// Draw one panel: mesh, curves, tags; `vlines_only` = the vertical
/// lines of the other panel, drawn here without tags.
#[allow(clippy::too_many_arguments)]
fn panel<E: Fn(&dyn std::fmt::Display) -> PlotError>(
    area: &Area,
    xr: (f64, f64),
    yr: (f64, f64),
    x_label: Option<&str>,
    y_label: &str,
    series: &[(&Series, Rgb)],
    vlines_only: &[(&Series, Rgb)],
    zero_line: bool,
    err: &E,
) -> Result<(), PlotError> {
    let mut cb = ChartBuilder::on(area);
    cb.margin_left(8)
        .margin_right(16)
        .margin_top(8)
        .margin_bottom(4)
        .y_label_area_size(Y_AREA)
        .x_label_area_size(if x_label.is_some() { 48 } else { 6 });
    let mut cc = cb
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(|e| err(&e))?;
    let no_labels = |_: &f64| String::new();
    let (dx, dy) = (tick_decimals(xr.1 - xr.0), tick_decimals(yr.1 - yr.0));
    let x_ticks = move |v: &f64| tick(*v, dx);
    let y_ticks = move |v: &f64| tick(*v, dy);
    {
        let mut mesh = cc.configure_mesh();
        mesh.y_desc(y_label)
            .y_label_formatter(&y_ticks)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 16))
            .light_line_style(RGBColor(235, 235, 235));
        match x_label {
            Some(l) => mesh.x_desc(l).x_label_formatter(&x_ticks),
            None => mesh.x_label_formatter(&no_labels),
        };
        mesh.draw().map_err(|e| err(&e))?;
    }
    if zero_line && yr.0 < 0.0 && yr.1 > 0.0 {
        cc.draw_series(LineSeries::new(
            [(xr.0, 0.0), (xr.1, 0.0)],
            BLACK.stroke_width(1),
        ))
        .map_err(|e| err(&e))?;
    }
    let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let vline = |cc: &mut ChartContext<_, _>, x: f64, color: RGBColor| {
        cc.draw_series(DashedLineSeries::new(
            [(x, yr.0), (x, yr.1)],
            3,
            4,
            color.stroke_width(2),
        ))
        .map(|_| ())
    };
    for (s, c) in vlines_only {
        for p in &s.points {
            vline(&mut cc, p.0, rgb(*c)).map_err(|e| err(&e))?;
        }
    }
    for (s, c) in series {
        let color = rgb(*c);
        let style = ShapeStyle::from(&color).stroke_width(2);
        let pts = s.points.iter().filter(finite).copied();
        match s.mark {
            Mark::Line => {
                cc.draw_series(LineSeries::new(pts, style))
                    .map_err(|e| err(&e))?;
            }
            Mark::Dashed => {
                cc.draw_series(DashedLineSeries::new(pts, 8, 5, style))
                    .map_err(|e| err(&e))?;
            }
            Mark::Points => {
                cc.draw_series(pts.map(|p| Circle::new(p, 4, style)))
                    .map_err(|e| err(&e))?;
            }
            Mark::Diamonds => {
                cc.draw_series(pts.map(|p| {
                    EmptyElement::at(p)
                        + Polygon::new(vec![(0, -7), (7, 0), (0, 7), (-7, 0)], color.filled())
                }))
                .map_err(|e| err(&e))?;
            }
            Mark::VLines => {
                for p in s.points.iter().filter(|p| p.0.is_finite()) {
                    vline(&mut cc, p.0, color).map_err(|e| err(&e))?;
                }
            }
        }
        let font = ("sans-serif", 15).into_font().color(&color);
        for (p, tag) in s.points.iter().zip(&s.tags) {
            if tag.is_empty() || !p.0.is_finite() {
                continue;
            }
            let (at, off) = match s.mark {
                Mark::VLines => ((p.0, yr.1), (4, 3)),
                _ if p.1.is_finite() => ((p.0, p.1), (9, -22)),
                _ => continue,
            };
            cc.draw_series(std::iter::once(
                EmptyElement::at(at) + Text::new(tag.clone(), off, font.clone()),
            ))
            .map_err(|e| err(&e))?;
        }
    }
    Ok(())
}

/// The legend column: one entry per distinct label, then the notes.
fn legend(area: &Area, chart: &Chart, entries: &[(&Series, Rgb)]) -> Result<(), String> {
    let font = ("sans-serif", 15).into_font();
    let note_font = ("sans-serif", 14).into_font().color(&RGBColor(70, 70, 70));
    let (x_text, max_w) = (46, LEGEND_W - 46 - 10);
    let mut y = 14;
    let mut seen: Vec<&str> = Vec::new();
    for (s, c) in entries {
        if s.label.is_empty() || seen.contains(&s.label.as_str()) {
            continue;
        }
        seen.push(&s.label);
        let color = rgb(*c);
        let style = ShapeStyle::from(&color).stroke_width(2);
        let mid = y + 8;
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        match s.mark {
            Mark::Line => area
                .draw(&PathElement::new(
                    vec![(8, mid), (38, mid)],
                    color.stroke_width(3),
                ))
                .map_err(e)?,
            Mark::Dashed => {
                for x in [8, 21, 34] {
                    area.draw(&PathElement::new(
                        vec![(x, mid), ((x + 8).min(40), mid)],
                        color.stroke_width(3),
                    ))
                    .map_err(e)?;
                }
            }
            Mark::Points => area.draw(&Circle::new((23, mid), 4, style)).map_err(e)?,
            Mark::Diamonds => area
                .draw(&Polygon::new(
                    vec![(23, mid - 7), (30, mid), (23, mid + 7), (16, mid)],
                    color.filled(),
                ))
                .map_err(e)?,
            Mark::VLines => {
                for y0 in [mid - 9, mid - 2, mid + 5] {
                    area.draw(&PathElement::new(
                        vec![(23, y0), (23, y0 + 4)],
                        color.stroke_width(2),
                    ))
                    .map_err(e)?;
                }
            }
        }
        for line in wrap(area, &s.label, &font.clone().into(), max_w) {
            area.draw_text(&line, &font.clone().into(), (x_text, y))
                .map_err(|e| e.to_string())?;
            y += 19;
        }
        y += 6;
    }
    y += 8;
    for note in &chart.notes {
        for line in wrap(area, note, &note_font, LEGEND_W - 18) {
            area.draw_text(&line, &note_font, (8, y))
                .map_err(|e| e.to_string())?;
            y += 18;
        }
        y += 8;
    }
    Ok(())
}

/// Draw `chart` into a PNG of `width × height` pixels at `path` (the
/// legend column takes 350 px of the width).
pub fn line_chart(path: &Path, chart: &Chart, width: u32, height: u32) -> Result<(), PlotError> {
    register_font();
    let err = |e: &dyn std::fmt::Display| PlotError {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let lower_series = chart.lower.iter().flat_map(|p| p.series.iter());
    let xr = chart.x_range.unwrap_or_else(|| {
        fitted(
            chart
                .series
                .iter()
                .chain(lower_series.clone())
                .flat_map(|s| s.points.iter().map(|p| p.0)),
        )
    });
    let yr = chart.y_range.unwrap_or_else(|| {
        let (lo, hi) = fitted(
            chart
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1)),
        );
        // room above the data for the tags of vertical lines
        let tagged = chart
            .series
            .iter()
            .any(|s| s.mark == Mark::VLines && s.tags.iter().any(|t| !t.is_empty()));
        (lo, if tagged { hi + 0.08 * (hi - lo) } else { hi })
    });
    let (cu, cl) = colors(chart);
    let upper: Vec<(&Series, Rgb)> = chart.series.iter().zip(cu).collect();
    let lower: Vec<(&Series, Rgb)> = lower_series.zip(cl).collect();
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let body = root
        .titled(&chart.title, ("sans-serif", 21))
        .map_err(|e| err(&e))?;
    let (plots, side) = body.split_horizontally(width.saturating_sub(LEGEND_W));
    match &chart.lower {
        None => panel(
            &plots,
            xr,
            yr,
            Some(&chart.x_label),
            &chart.y_label,
            &upper,
            &[],
            false,
            &err,
        )?,
        Some(low) => {
            let h = plots.dim_in_pixel().1;
            let (top, bottom) = plots.split_vertically((h as f64 * 0.6) as u32);
            panel(&top, xr, yr, None, &chart.y_label, &upper, &[], false, &err)?;
            let ylr = low.y_range.unwrap_or_else(|| {
                fitted(low.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)))
            });
            let shared: Vec<(&Series, Rgb)> = upper
                .iter()
                .filter(|(s, _)| s.mark == Mark::VLines)
                .copied()
                .collect();
            panel(
                &bottom,
                xr,
                ylr,
                Some(&chart.x_label),
                &low.y_label,
                &lower,
                &shared,
                true,
                &err,
            )?;
        }
    }
    let entries: Vec<(&Series, Rgb)> = upper.iter().chain(&lower).copied().collect();
    legend(&side, chart, &entries).map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_font_parses() {
        assert!(ab_glyph_font_ok());
    }

    fn ab_glyph_font_ok() -> bool {
        plotters::style::register_font("efgdem-test", FontStyle::Normal, FONT).is_ok()
    }

    #[test]
    fn draws_a_png_with_text_and_curves() {
        let dir = std::env::temp_dir().join(format!("efgdem-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("sine.png");
        let pts: Vec<(f64, f64)> = (0..200)
            .map(|i| (i as f64 * 0.05, (i as f64 * 0.05).sin()))
            .collect();
        let chart = Chart {
            title: "Test chart".into(),
            x_label: "t (s)".into(),
            y_label: "u (m)".into(),
            series: vec![
                Series::new("sin", pts.clone(), Mark::Line),
                Series::new(
                    "samples",
                    pts.iter().step_by(20).copied().collect(),
                    Mark::Points,
                ),
                Series::new(
                    "theory",
                    pts.iter().map(|&(x, y)| (x, 0.8 * y)).collect(),
                    Mark::Dashed,
                ),
            ],
            ..Default::default()
        };
        line_chart(&p, &chart, 800, 500).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        assert!(
            bytes.len() > 5_000,
            "a chart with text and curves is not tiny"
        );
        if std::env::var_os("EFGDEM_KEEP_PLOT").is_some() {
            std::fs::copy(&p, "/tmp/efgdem-plot-test.png").unwrap();
        }
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn ticks_show_their_differences() {
        assert_eq!(tick_decimals(0.22), 2);
        assert_eq!(tick_decimals(16.0), 0);
        assert_eq!(tick_decimals(0.0013), 4);
        assert_eq!(tick(-0.0001, 2), "0.00");
        assert_eq!(tick(-1.5, 1), "-1.5");
    }

    #[test]
    fn colours_follow_the_palette_unless_given() {
        let chart = Chart {
            series: vec![
                Series::new("a", vec![], Mark::Line),
                Series::paper("p", vec![], Mark::Diamonds),
                Series::new("b", vec![], Mark::Line),
            ],
            lower: Some(Panel {
                series: vec![Series::new("d", vec![], Mark::Line).with_color(palette(0))],
                ..Default::default()
            }),
            ..Default::default()
        };
        let (up, low) = colors(&chart);
        assert_eq!(up, [palette(0), PAPER_COLOR, palette(1)]);
        assert_eq!(low, [palette(0)]);
    }

    #[test]
    fn draws_two_panels_with_reference_lines_and_notes() {
        let dir = std::env::temp_dir().join(format!("efgdem-plot2-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("two.png");
        let a: Vec<(f64, f64)> = (0..200)
            .map(|i| (i as f64 * 0.01, (i as f64 * 0.01).sin()))
            .collect();
        let b: Vec<(f64, f64)> = a.iter().map(|&(x, y)| (x, y * 1.001)).collect();
        let dev: Vec<(f64, f64)> = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (p.0, (q.1 - p.1) * 1e3))
            .collect();
        let chart = Chart {
            title: "Two panels".into(),
            x_label: "t (s)".into(),
            y_label: "u (m)".into(),
            series: vec![
                Series::new("ours, a", a, Mark::Line),
                Series::new("ours, b", b, Mark::Dashed),
                Series::vlines("paper (text): instants", &[0.5, 1.5])
                    .with_color(PAPER_COLOR)
                    .with_tags(["(a)", "(b)"]),
                Series::paper("paper (text): a value", vec![(1.0, 0.8)], Mark::Diamonds),
            ],
            lower: Some(Panel {
                y_label: "b − a (mm)".into(),
                series: vec![Series::new("b − a", dev, Mark::Line).with_color(palette(1))],
                y_range: None,
            }),
            notes: vec![
                "A note long enough to be wrapped over more than one line of the legend column."
                    .into(),
            ],
            ..Default::default()
        };
        line_chart(&p, &chart, 1200, 820).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        assert!(bytes.len() > 10_000);
        if std::env::var_os("EFGDEM_KEEP_PLOT").is_some() {
            std::fs::copy(&p, "/tmp/efgdem-plot-test2.png").unwrap();
        }
        std::fs::remove_dir_all(dir).unwrap();
    }
}
