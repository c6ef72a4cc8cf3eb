//! The benchmark's plot: relMSE against wall seconds, log-log, one line per
//! back end, dashed lines at the reported thresholds, with axis labels and a
//! legend. Drawn with plotters as SVG: text stays text (no font files needed
//! on the machine) and the plot scales in any browser.

use super::SceneReport;
use anyhow::Context as _;
use plotters::prelude::*;
use std::path::Path;

pub const WIDTH: u32 = 800;
pub const HEIGHT: u32 = 520;
const PALETTE: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
];

/// Whole decades [lo, hi] covering the positive values, at least one wide.
fn decades(values: impl Iterator<Item = f64>) -> Option<(i32, i32)> {
    let logs: Vec<f64> = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(f64::log10)
        .collect();
    if logs.is_empty() {
        return None;
    }
    let lo = logs.iter().copied().fold(f64::INFINITY, f64::min).floor() as i32;
    let hi = logs
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil() as i32;
    Some((lo, hi.max(lo + 1)))
}

fn plot_error(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("drawing the plot: {e}")
}

/// Draws `report`'s curves as an SVG file at `path`.
pub fn plot_report(path: &Path, report: &SceneReport, thresholds: &[f64]) -> anyhow::Result<()> {
    let svg = plot_svg(report, thresholds)?;
    crate::cache::write_atomically(path, svg.as_bytes())
        .with_context(|| format!("cannot write the plot {}", path.display()))
}

/// The plot as SVG text.
pub fn plot_svg(report: &SceneReport, thresholds: &[f64]) -> anyhow::Result<String> {
    let curves: Vec<(String, Vec<(f64, f64)>)> = report
        .backends()
        .into_iter()
        .map(|b| {
            let points = report
                .curve(&b)
                .into_iter()
                .filter(|(t, r)| *t > 0.0 && *r > 0.0 && t.is_finite() && r.is_finite())
                .collect();
            (b, points)
        })
        .collect();
    let all = || curves.iter().flat_map(|(_, c)| c.iter().copied());
    let (x_lo, x_hi) = decades(all().map(|p| p.0)).unwrap_or((-1, 1));
    let (y_lo, y_hi) =
        decades(all().map(|p| p.1).chain(thresholds.iter().copied())).unwrap_or((-4, 0));
    let stem = Path::new(&report.scene)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{stem} {}x{}: relMSE against time",
                    report.width, report.height
                ),
                ("sans-serif", 22),
            )
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (10f64.powi(x_lo)..10f64.powi(x_hi)).log_scale(),
                (10f64.powi(y_lo)..10f64.powi(y_hi)).log_scale(),
            )
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("wall time per image (s)")
            .y_desc("relMSE against the reference")
            .x_label_formatter(&|x| format!("{x:.0e}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()
            .map_err(plot_error)?;
        let (t0, t1) = (10f64.powi(x_lo), 10f64.powi(x_hi));
        for &t in thresholds {
            chart
                .draw_series(DashedLineSeries::new(
                    [(t0, t), (t1, t)],
                    6,
                    4,
                    RGBColor(120, 120, 120).stroke_width(1),
                ))
                .map_err(plot_error)?;
        }
        for (i, (name, points)) in curves.iter().enumerate() {
            let colour = PALETTE[i % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(
                    points.iter().copied(),
                    colour.stroke_width(2),
                ))
                .map_err(plot_error)?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(3))
                });
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(plot_error)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_decades_cover_the_values() {
        assert_eq!(decades([0.05, 3.0].into_iter()), Some((-2, 1)));
        assert_eq!(decades([1.0].into_iter()), Some((0, 1)));
        assert_eq!(decades([0.0, f64::NAN].into_iter()), None);
    }
}
