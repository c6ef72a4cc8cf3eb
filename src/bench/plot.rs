//! The benchmark's plot: relMSE against wall seconds, log-log, one coloured
//! line per back end, dashed lines at the reported thresholds. Drawn pixel by
//! pixel with the `image` crate and `font.rs`, to need no plotting library.

use super::SceneReport;
use super::font::{draw_text, text_width};
use anyhow::Context as _;
use image::{Rgb, RgbImage};
use std::path::Path;

const WIDTH: u32 = 800;
const HEIGHT: u32 = 520;
/// Plot area: left, top, right, bottom.
const AREA: (i32, i32, i32, i32) = (90, 50, 770, 450);
const PALETTE: [[u8; 3]; 5] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [255, 127, 14],
    [148, 103, 189],
];
const TEXT_SCALE: u32 = 2;

struct Canvas {
    img: RgbImage,
}

impl Canvas {
    fn set(&mut self, x: i32, y: i32, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u32) < WIDTH && (y as u32) < HEIGHT {
            self.img.put_pixel(x as u32, y as u32, Rgb(c));
        }
    }

    fn text(&mut self, text: &str, x: i32, y: i32, c: [u8; 3]) {
        draw_text(text, x, y, TEXT_SCALE, &mut |px, py| self.set(px, py, c));
    }

    /// A line `thickness` pixels wide; `dash` > 0 leaves gaps of that length.
    fn line(&mut self, a: (f64, f64), b: (f64, f64), c: [u8; 3], thickness: i32, dash: u32) {
        let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as u32).max(1);
        let r = thickness / 2;
        for i in 0..=n {
            if dash > 0 && (i / dash) % 2 == 1 {
                continue;
            }
            let t = i as f64 / n as f64;
            let x = (a.0 + (b.0 - a.0) * t).round() as i32;
            let y = (a.1 + (b.1 - a.1) * t).round() as i32;
            for dy in -r..=r {
                for dx in -r..=r {
                    self.set(x + dx, y + dy, c);
                }
            }
        }
    }
}

/// Whole decades [lo, hi] covering the positive values, at least one wide.
fn decades(values: impl Iterator<Item = f64>) -> Option<(i32, i32)> {
    let logs: Vec<f64> = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .map(f64::log10)
        .collect();
    let lo = logs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if logs.is_empty() {
        return None;
    }
    let (lo, mut hi) = (lo.floor() as i32, hi.ceil() as i32);
    if hi <= lo {
        hi = lo + 1;
    }
    Some((lo, hi))
}

/// "0.01", "1", "100" near 1; "1E-5" further out.
fn decade_label(e: i32) -> String {
    match e {
        0..=4 => format!("{}", 10u32.pow(e as u32)),
        -3..=-1 => format!("{:.*}", (-e) as usize, 10f64.powi(e)),
        _ => format!("1E{e}"),
    }
}

/// Draws `report`'s curves into a PNG at `path`.
pub fn plot_report(path: &Path, report: &SceneReport, thresholds: &[f64]) -> anyhow::Result<()> {
    let backends = report.backends();
    let curves: Vec<(String, Vec<(f64, f64)>)> = backends
        .iter()
        .map(|b| (b.clone(), report.curve(b)))
        .collect();
    let all = || curves.iter().flat_map(|(_, c)| c.iter().copied());
    let (x_lo, x_hi) = decades(all().map(|p| p.0)).unwrap_or((-1, 1));
    let (y_lo, y_hi) =
        decades(all().map(|p| p.1).chain(thresholds.iter().copied())).unwrap_or((-4, 0));

    let (left, top, right, bottom) = AREA;
    let to_px = |t: f64, r: f64| -> (f64, f64) {
        let fx = (t.log10() - x_lo as f64) / (x_hi - x_lo) as f64;
        let fy = (r.log10() - y_lo as f64) / (y_hi - y_lo) as f64;
        (
            left as f64 + fx * (right - left) as f64,
            bottom as f64 - fy * (bottom - top) as f64,
        )
    };

    let mut c = Canvas {
        img: RgbImage::from_pixel(WIDTH, HEIGHT, Rgb([255, 255, 255])),
    };
    let (grid, minor, black) = ([205, 205, 205], [235, 235, 235], [0, 0, 0]);
    // Minor lines at 2..9 times each decade, then decade lines and labels.
    for e in x_lo..x_hi {
        for m in 2..10 {
            let (x, _) = to_px(m as f64 * 10f64.powi(e), 1.0);
            c.line((x, top as f64), (x, bottom as f64), minor, 1, 0);
        }
    }
    for e in y_lo..y_hi {
        for m in 2..10 {
            let (_, y) = to_px(1.0, m as f64 * 10f64.powi(e));
            c.line((left as f64, y), (right as f64, y), minor, 1, 0);
        }
    }
    for e in x_lo..=x_hi {
        let (x, _) = to_px(10f64.powi(e), 1.0);
        c.line((x, top as f64), (x, bottom as f64), grid, 1, 0);
        let label = decade_label(e);
        let w = text_width(&label, TEXT_SCALE) as i32;
        c.text(&label, x as i32 - w / 2, bottom + 8, black);
    }
    for e in y_lo..=y_hi {
        let (_, y) = to_px(1.0, 10f64.powi(e));
        c.line((left as f64, y), (right as f64, y), grid, 1, 0);
        let label = decade_label(e);
        let w = text_width(&label, TEXT_SCALE) as i32;
        c.text(&label, left - 8 - w, y as i32 - 5, black);
    }
    for &t in thresholds {
        let (_, y) = to_px(1.0, t);
        c.line((left as f64, y), (right as f64, y), [120, 120, 120], 1, 6);
    }
    // Axes (a frame).
    let (l, t, r, b) = (left as f64, top as f64, right as f64, bottom as f64);
    for (p, q) in [
        ((l, t), (r, t)),
        ((r, t), (r, b)),
        ((r, b), (l, b)),
        ((l, b), (l, t)),
    ] {
        c.line(p, q, black, 1, 0);
    }
    let x_title = "WALL SECONDS";
    let w = text_width(x_title, TEXT_SCALE) as i32;
    c.text(x_title, (left + right) / 2 - w / 2, bottom + 32, black);
    c.text("RELMSE", 10, top - 22, black);
    let stem = Path::new(&report.scene)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = format!(
        "{stem} {}X{}: RELMSE AGAINST TIME (LOG-LOG)",
        report.width, report.height
    );
    let w = text_width(&title, TEXT_SCALE) as i32;
    c.text(&title, (left + right) / 2 - w / 2, 14, black);

    for (i, (name, points)) in curves.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let px: Vec<(f64, f64)> = points
            .iter()
            .filter(|(t, r)| *t > 0.0 && *r > 0.0 && t.is_finite() && r.is_finite())
            .map(|&(t, r)| to_px(t, r))
            .collect();
        for w in px.windows(2) {
            c.line(w[0], w[1], colour, 2, 0);
        }
        for &p in &px {
            c.line((p.0 - 3.0, p.1), (p.0 + 3.0, p.1), colour, 5, 0);
        }
        // Legend, top right inside the plot.
        let y = top + 10 + i as i32 * 18;
        let label_w = text_width(name, TEXT_SCALE) as i32;
        let x = right - 12 - label_w;
        c.line(
            ((x - 30) as f64, (y + 5) as f64),
            ((x - 8) as f64, (y + 5) as f64),
            colour,
            3,
            0,
        );
        c.text(name, x, y, black);
    }
    c.img
        .save(path)
        .with_context(|| format!("cannot write the plot {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_decades_cover_the_values() {
        assert_eq!(decades([0.05, 3.0].into_iter()), Some((-2, 1)));
        assert_eq!(decades([1.0].into_iter()), Some((0, 1)));
        assert_eq!(decades([0.0, f64::NAN].into_iter()), None);
        assert_eq!(decade_label(-2), "0.01");
        assert_eq!(decade_label(2), "100");
        assert_eq!(decade_label(-5), "1E-5");
    }
}
