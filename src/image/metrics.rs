//! Error metrics of one image against another that need no variance, so
//! they work on any pair of EXRs (another renderer's included): mean and
//! bias per channel, RMSE, relMSE and the block that deviates most.
//! `stats::compare` adds the variance-aware test when both images have it.

use crate::image::compare::{ensure_same_size, rel_mse};
use crate::image::{Image, REL_MSE_EPSILON};
use anyhow::Result;
use std::fmt;

/// Side of the square blocks searched for the worst deviation: large enough
/// to average out most noise, small enough to point at a place.
pub const WORST_BLOCK: u32 = 16;

/// The block whose average deviates most, relative to the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockDeviation {
    /// Top-left pixel of the block.
    pub x: u32,
    pub y: u32,
    pub channel: usize,
    pub mean_a: f64,
    pub mean_b: f64,
    /// (a - b) / sqrt(b^2 + 0.01): relMSE's weighting, so dark blocks do
    /// not win on tiny absolute differences.
    pub relative: f64,
}

#[derive(Clone, Debug, PartialEq)]
pub struct ErrorMetrics {
    pub mean_a: [f64; 3],
    pub mean_b: [f64; 3],
    /// mean_a - mean_b.
    pub bias: [f64; 3],
    /// Root mean square of a - b per channel.
    pub rmse: [f64; 3],
    pub rel_mse: f64,
    pub worst_block: Option<BlockDeviation>,
}

const CHANNELS: [char; 3] = ['R', 'G', 'B'];

/// How far two images are from being the same numbers: for a merged render
/// against one render of the same samples, where only float rounding may
/// differ (`vkpt compare --tolerance`).
#[derive(Clone, Debug, PartialEq)]
pub struct Closeness {
    /// Pixels with a channel differing by more than `tolerance * (1 + |b|)`.
    pub differing: usize,
    /// The largest `|a - b| / (1 + |b|)` and its pixel.
    pub largest: f64,
    pub at: (u32, u32),
    /// Pixels whose sample counts differ (when both images have them).
    pub counts_differing: usize,
}

/// `Closeness` of `a` to `b` at `tolerance`.
pub fn closeness(a: &Image, b: &Image, tolerance: f64) -> Result<Closeness> {
    ensure_same_size(a, b)?;
    let mut c = Closeness {
        differing: 0,
        largest: 0.0,
        at: (0, 0),
        counts_differing: 0,
    };
    for (i, (pa, pb)) in a.mean.iter().zip(&b.mean).enumerate() {
        let d = (0..3)
            .map(|k| (pa[k] as f64 - pb[k] as f64).abs() / (1.0 + (pb[k] as f64).abs()))
            .fold(
                0.0,
                |m: f64, x| if x.is_nan() { f64::INFINITY } else { m.max(x) },
            );
        if d > tolerance {
            c.differing += 1;
        }
        if d > c.largest {
            c.largest = d;
            c.at = (i as u32 % a.width, i as u32 / a.width);
        }
    }
    if let (Some(na), Some(nb)) = (&a.samples, &b.samples) {
        c.counts_differing = na.iter().zip(nb).filter(|(x, y)| x != y).count();
    }
    Ok(c)
}

/// Metrics of `a` against the reference `b`.
pub fn error_metrics(a: &Image, b: &Image) -> Result<ErrorMetrics> {
    ensure_same_size(a, b)?;
    let (mean_a, mean_b) = (a.average(), b.average());
    let mut sq = [0.0f64; 3];
    for (pa, pb) in a.mean.iter().zip(&b.mean) {
        for c in 0..3 {
            let d = pa[c] as f64 - pb[c] as f64;
            sq[c] += d * d;
        }
    }
    let n = a.mean.len().max(1) as f64;
    let mut worst: Option<BlockDeviation> = None;
    for by in (0..a.height).step_by(WORST_BLOCK as usize) {
        for bx in (0..a.width).step_by(WORST_BLOCK as usize) {
            let (mut sa, mut sb, mut count) = ([0.0f64; 3], [0.0f64; 3], 0.0);
            for y in by..(by + WORST_BLOCK).min(a.height) {
                for x in bx..(bx + WORST_BLOCK).min(a.width) {
                    let i = a.index(x, y);
                    for c in 0..3 {
                        sa[c] += a.mean[i][c] as f64;
                        sb[c] += b.mean[i][c] as f64;
                    }
                    count += 1.0;
                }
            }
            for c in 0..3 {
                let (ma, mb) = (sa[c] / count, sb[c] / count);
                let relative = (ma - mb) / (mb * mb + REL_MSE_EPSILON).sqrt();
                // NaN never wins a comparison; count a NaN block as worst.
                let better = worst.is_none_or(|w| !(relative.abs() <= w.relative.abs()));
                if better {
                    worst = Some(BlockDeviation {
                        x: bx,
                        y: by,
                        channel: c,
                        mean_a: ma,
                        mean_b: mb,
                        relative,
                    });
                }
            }
        }
    }
    Ok(ErrorMetrics {
        mean_a,
        mean_b,
        bias: [0, 1, 2].map(|c| mean_a[c] - mean_b[c]),
        rmse: sq.map(|s| (s / n).sqrt()),
        rel_mse: rel_mse(a, b),
        worst_block: worst,
    })
}

impl fmt::Display for ErrorMetrics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let three = |v: [f64; 3]| v.map(|x| format!("{x:.6}")).join(" ");
        let rel = [0, 1, 2].map(|c| {
            if self.mean_b[c] == 0.0 {
                "n/a".to_string()
            } else {
                format!("{:+.3}%", 100.0 * self.bias[c] / self.mean_b[c])
            }
        });
        writeln!(
            f,
            "  mean       a [{}], b [{}]",
            three(self.mean_a),
            three(self.mean_b)
        )?;
        writeln!(
            f,
            "  bias a-b   [{}] ({} of b)",
            three(self.bias),
            rel.join(" ")
        )?;
        writeln!(f, "  RMSE       [{}]", three(self.rmse))?;
        write!(f, "  relMSE     {:.3e}", self.rel_mse)?;
        if let Some(w) = &self.worst_block {
            write!(
                f,
                "\n  worst {WORST_BLOCK}x{WORST_BLOCK} block at ({}, {}) {}: a {:.6} vs b {:.6} \
                 ({:+.2}% relative)",
                w.x,
                w.y,
                CHANNELS[w.channel],
                w.mean_a,
                w.mean_b,
                100.0 * w.relative
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(w: u32, h: u32, v: [f32; 3]) -> Image {
        let mut image = Image::new(w, h);
        image.mean = vec![v; (w * h) as usize];
        image
    }

    #[test]
    fn metrics_bias_rmse_and_worst_block() {
        let b = flat(40, 20, [0.5, 0.25, 1.0]);
        let mut a = b.clone();
        // A uniform +0.1 on green, and one block with red raised by 0.4.
        for p in &mut a.mean {
            p[1] += 0.1;
        }
        for y in 16..20 {
            for x in 32..40 {
                let i = a.index(x, y);
                a.mean[i][0] += 0.4;
            }
        }
        let m = error_metrics(&a, &b).unwrap();
        assert!((m.bias[1] - 0.1).abs() < 1e-6, "{m}");
        assert!((m.rmse[1] - 0.1).abs() < 1e-6, "{m}");
        assert_eq!(m.bias[2], 0.0);
        // 32 of 800 pixels off by 0.4 in red.
        assert!(
            (m.rmse[0] - (0.16f64 * 32.0 / 800.0).sqrt()).abs() < 1e-6,
            "{m}"
        );
        let w = m.worst_block.unwrap();
        assert_eq!((w.x, w.y, w.channel), (32, 16, 0), "{m}");
        // The edge block is 8x4 pixels, all raised.
        assert!((w.mean_a - 0.9).abs() < 1e-6, "{m}");
        let text = m.to_string();
        assert!(text.contains("bias a-b") && text.contains("RMSE") && text.contains("worst 16x16"));
    }

    #[test]
    fn metrics_reject_different_sizes() {
        assert!(error_metrics(&flat(2, 2, [0.0; 3]), &flat(2, 3, [0.0; 3])).is_err());
    }
}
