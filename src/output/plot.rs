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
}

/// One curve.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry.
    pub label: String,
    /// Data points `(x, y)`, in drawing order.
    pub points: Vec<(f64, f64)>,
    /// How the curve is drawn.
    pub mark: Mark,
}

impl Series {
    /// A curve labelled `label` through `points`, drawn as `mark`.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, mark: Mark) -> Self {
        Series {
            label: label.into(),
            points,
            mark,
        }
    }
}

/// A 2D line chart.
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

const COLORS: [RGBColor; 6] = [
    RGBColor(0, 90, 181),
    RGBColor(220, 50, 32),
    RGBColor(0, 140, 60),
    RGBColor(120, 60, 160),
    RGBColor(230, 130, 0),
    RGBColor(60, 60, 60),
];

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

/// Draw `chart` into a PNG of `width × height` pixels at `path`.
pub fn line_chart(path: &Path, chart: &Chart, width: u32, height: u32) -> Result<(), PlotError> {
    register_font();
    let err = |e: &dyn std::fmt::Display| PlotError {
        path: path.display().to_string(),
        message: e.to_string(),
    };
    let xr = chart.x_range.unwrap_or_else(|| {
        fitted(
            chart
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.0)),
        )
    });
    let yr = chart.y_range.unwrap_or_else(|| {
        fitted(
            chart
                .series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| p.1)),
        )
    });
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut cc = ChartBuilder::on(&root)
        .caption(&chart.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(|e| err(&e))?;
    cc.configure_mesh()
        .x_desc(&chart.x_label)
        .y_desc(&chart.y_label)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(|e| err(&e))?;
    for (i, s) in chart.series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let style = ShapeStyle::from(&color).stroke_width(2);
        let pts = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite());
        let anno = match s.mark {
            Mark::Line => cc.draw_series(LineSeries::new(pts, style)),
            Mark::Dashed => cc.draw_series(DashedLineSeries::new(pts, 8, 5, style)),
            Mark::Points => cc.draw_series(
                pts.map(|p| Circle::new(p, 4, ShapeStyle::from(&color).stroke_width(2))),
            ),
        }
        .map_err(|e| err(&e))?;
        if !s.label.is_empty() {
            anno.label(s.label.clone()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(3))
            });
        }
    }
    if chart.series.iter().any(|s| !s.label.is_empty()) {
        cc.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| err(&e))?;
    }
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
}
