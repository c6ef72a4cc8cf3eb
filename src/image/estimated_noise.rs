//! The levelled test of [`super::compare::compare`] for images that carry
//! no variance (another renderer's EXR: Mitsuba, Cycles, pbrt), with the
//! noise estimated from the two images themselves.
//!
//! Under H0 ("a and b have the same expectation") the difference D = a − b
//! has expectation zero in every pixel: edges, textures and lights cancel,
//! and what is left is noise, whichever image carries it (a nearly
//! converged reference just adds little). So the spread of D measures the
//! noise without the trouble a single image's local differences have at
//! edges. Per cell c of n pixels (4×4), with d_i = D_i − mean_c(D),
//!
//! ```text
//!     V_c = n / (n − φ_c) · Σ d_i²      estimates Var(Σ_c D) / φ_c
//! ```
//!
//! without bias also when the pixels' variances differ (Monte Carlo noise
//! is far from uniform: a pixel on a light's edge is noisier than its
//! neighbours), and is blind to a bias constant over the cell, so a biased
//! block does not hide in its own noise estimate. A block (a cell, 16×16,
//! the whole image) is tested by t = Σ_B D / √(φ_B Σ_c V_c), Student t with
//! Satterthwaite's degrees of freedom estimated from the same deviations
//! (3 (Σd²)² / Σd⁴, at most Σ (n − 1): heavy tails and a few dominating
//! pixels lower it, which widens the threshold; so does correlated noise,
//! by 1 + Σ_h ρ_h²), with the Šidák and Bonferroni corrections of
//! `compare`.
//!
//! φ is the variance inflation of a block sum by correlated noise between
//! neighbouring pixels: 1 + Σ_h ρ_h · (overlap of the block with itself
//! shifted by h), with ρ_h measured from D for offsets up to 2 pixels (the
//! median over 16×16 blocks, so a bias's structure is not taken for
//! correlation, corrected for the removal of each block's mean) and φ
//! never below 1. vkpt's pixels are independent (each sample lands in one
//! pixel, with a per-pixel scramble of the sampler), so φ ≈ 1; a renderer
//! that splats samples into several pixels (Mitsuba 3's default Gaussian
//! filter) makes neighbours' noise positively correlated, which without φ
//! would make block variances too small and reject true agreement.
//!
//! Single pixels are not tested: a pixel's own noise cannot be estimated
//! from its neighbours without assuming they share it, which fails exactly
//! at edges (a noisy edge pixel among quiet ones would be rejected under
//! H0). An outlier pixel is seen only through its cell.

use super::Image;
use super::compare::{Comparison, Finding, LevelResult, ensure_same_size, sidak};
use super::student_t::student_t_two_sided_p;
use anyhow::{Result, ensure};

/// Side of the cells whose spread of a − b estimates the noise; the tested
/// block sizes are multiples of it.
pub const CELL: u32 = 4;
/// Block sizes tested besides the cells and the whole image.
const BLOCKS: &[u32] = &[16];
/// Largest neighbour offset (pixels) whose noise correlation is measured.
const MAX_LAG: i64 = 2;

/// Sums of one cell and channel: pixel count, Σ D, Σ d², Σ d⁴.
#[derive(Clone, Copy, Default)]
struct CellSums {
    n: f64,
    sum: f64,
    s2: f64,
    s4: f64,
}

/// The difference a − b per channel, row-major, and how many pixel-channels
/// are non-finite in either image (those count as 0 in `d` and fail).
fn difference(a: &Image, b: &Image) -> (Vec<[f64; 3]>, usize, usize) {
    let (mut nonfinite, mut equal) = (0, 0);
    let d = a
        .mean
        .iter()
        .zip(&b.mean)
        .map(|(x, y)| {
            let mut d = [0.0; 3];
            for c in 0..3 {
                if x[c].is_finite() && y[c].is_finite() {
                    d[c] = x[c] as f64 - y[c] as f64;
                    equal += (d[c] == 0.0) as usize;
                } else {
                    nonfinite += 1;
                }
            }
            d
        })
        .collect();
    (d, nonfinite, equal)
}

/// Side of the blocks in which the correlation of neighbours' noise is
/// measured (large enough that removing their mean leaves pairs nearly
/// uncorrelated: -1/255).
const CORRELATION_BLOCK: usize = 16;

/// ρ_h per channel for the offsets h of one half plane (|dx|, |dy| ≤
/// `MAX_LAG`): in each 16×16 block, the mean product of D's deviations
/// (about the block's mean) at offset h over their mean square; then the
/// median over blocks. The median keeps a bias from passing for
/// correlation: where the images differ in expectation, the difference
/// has structure (a relative bias is largest at a light's edge) that looks
/// like correlated noise in the few blocks holding such edges, whereas a
/// renderer's filter correlates neighbours everywhere.
fn correlations(d: &[[f64; 3]], w: u32, h: u32) -> Vec<((i64, i64), [f64; 3])> {
    let (wu, hu) = (w as usize, h as usize);
    let side = CORRELATION_BLOCK;
    let mut lags = Vec::new();
    for dy in 0..=MAX_LAG {
        for dx in -MAX_LAG..=MAX_LAG {
            if dy > 0 || dx > 0 {
                lags.push((dx, dy));
            }
        }
    }
    // Per lag and channel, each block's ratio.
    let mut ratios = vec![[Vec::new(), Vec::new(), Vec::new()]; lags.len()];
    for by in (0..hu).step_by(side) {
        for bx in (0..wu).step_by(side) {
            let (x1, y1) = ((bx + side).min(wu), (by + side).min(hu));
            let n = ((x1 - bx) * (y1 - by)) as f64;
            for c in 0..3 {
                let at = |x: usize, y: usize| d[y * wu + x][c];
                let pixels = || (by..y1).flat_map(|y| (bx..x1).map(move |x| (x, y)));
                let mean = pixels().map(|(x, y)| at(x, y)).sum::<f64>() / n;
                let var = pixels()
                    .map(|(x, y)| (at(x, y) - mean).powi(2))
                    .sum::<f64>()
                    / n;
                if var <= 0.0 {
                    continue;
                }
                for (l, &(dx, dy)) in lags.iter().enumerate() {
                    let (mut cov, mut pairs) = (0.0, 0usize);
                    for (x, y) in pixels() {
                        let (x2, y2) = (x as i64 + dx, y as i64 + dy);
                        if x2 < bx as i64 || x2 >= x1 as i64 || y2 >= y1 as i64 {
                            continue;
                        }
                        cov += (at(x, y) - mean) * (at(x2 as usize, y2 as usize) - mean);
                        pairs += 1;
                    }
                    if pairs > 0 {
                        ratios[l][c].push(cov / pairs as f64 / var);
                    }
                }
            }
        }
    }
    let mut rho: Vec<((i64, i64), [f64; 3])> = lags
        .iter()
        .zip(ratios)
        .map(|(&lag, per_channel)| (lag, per_channel.map(median)))
        .collect();
    // Removing a block's mean lowers every ratio: E ρ̂ ≈ (ρ - b) / (1 - b)
    // with b = φ / n the variance of the block's mean over a pixel's.
    let n = (side.min(wu) * side.min(hu)) as f64;
    for c in 0..3 {
        let b = inflation(&rho, side.min(wu) as u32, side.min(hu) as u32, c) / n;
        for (_, r) in &mut rho {
            r[c] = r[c] * (1.0 - b) + b;
        }
    }
    rho
}

/// How much correlation between neighbours thins the information in a sum
/// of squared deviations: Var(Σ d²) grows by 1 + Σ_h ρ_h² (over all h ≠ 0),
/// so the degrees of freedom of a variance estimate shrink by that factor.
fn dof_thinning(rho: &[((i64, i64), [f64; 3])], c: usize) -> f64 {
    1.0 + 2.0 * rho.iter().map(|(_, r)| r[c] * r[c]).sum::<f64>()
}

/// The median (0 for no values).
fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// φ for a `bw` × `bh` block in channel `c`: Var(Σ D) / Σ Var(D), at least 1.
fn inflation(rho: &[((i64, i64), [f64; 3])], bw: u32, bh: u32, c: usize) -> f64 {
    let (bw, bh) = (bw as f64, bh as f64);
    let mut phi = 1.0;
    for &((dx, dy), r) in rho {
        let overlap = (bw - dx.abs() as f64).max(0.0) * (bh - dy.abs() as f64).max(0.0) / (bw * bh);
        phi += 2.0 * r[c] * overlap;
    }
    phi.max(1.0)
}

/// A block's sums over its cells in one channel: Σ D, Σ V_c, Σ d⁴, the
/// cells' degrees of freedom, its pixels, and the pixels in cells with an
/// estimate.
struct BlockSums {
    sum: f64,
    v: f64,
    s4: f64,
    dof: f64,
    pixels: f64,
    estimated: f64,
}

fn block_sums(
    cells: &[[CellSums; 3]],
    cw: u32,
    (w, h): (u32, u32),
    (bx, by, bx1, by1): (u32, u32, u32, u32),
    c: usize,
) -> BlockSums {
    let mut out = BlockSums {
        sum: 0.0,
        v: 0.0,
        s4: 0.0,
        dof: 0.0,
        pixels: 0.0,
        estimated: 0.0,
    };
    for cy in by / CELL..by1.div_ceil(CELL) {
        for cx in bx / CELL..bx1.div_ceil(CELL) {
            let s = cells[(cy * cw + cx) as usize][c];
            out.sum += s.sum;
            let size =
                ((cx * CELL + CELL).min(w) - cx * CELL) * ((cy * CELL + CELL).min(h) - cy * CELL);
            out.pixels += size as f64;
            if s.n > 0.0 {
                out.v += s.s2;
                out.s4 += s.s4;
                out.dof += s.n - 1.0;
                out.estimated += s.n;
            }
        }
    }
    out
}

/// Tests whether `a` and `b` have the same expectation when neither carries
/// a variance layer (see the module doc for the noise model): cells of 4×4,
/// 16×16 blocks and the whole image, Šidák within a level and Bonferroni
/// across levels at family-wise level `alpha`. The result's `noise_model`
/// says what was estimated.
pub fn compare_estimating_noise(a: &Image, b: &Image, alpha: f64) -> Result<Comparison> {
    ensure!(
        alpha > 0.0 && alpha < 1.0,
        "significance level must be in (0, 1), got {alpha}"
    );
    ensure_same_size(a, b)?;
    let (w, h) = (a.width, a.height);
    let n = w as usize * h as usize;
    ensure!(
        a.mean.len() == n && b.mean.len() == n,
        "pixel count does not match the image size"
    );
    ensure!(
        w >= CELL && h >= CELL,
        "a {w}x{h} image is too small to estimate its noise from {CELL}x{CELL} cells"
    );
    let (d, nonfinite, exact_matches) = difference(a, b);
    let rho = correlations(&d, w, h);

    // Cell sums, with deviations about each cell's own mean.
    let (cw, ch) = (w.div_ceil(CELL), h.div_ceil(CELL));
    let mut cells = vec![[CellSums::default(); 3]; (cw * ch) as usize];
    for cy in 0..ch {
        for cx in 0..cw {
            let (x0, y0) = (cx * CELL, cy * CELL);
            let (x1, y1) = ((x0 + CELL).min(w), (y0 + CELL).min(h));
            let cell = &mut cells[(cy * cw + cx) as usize];
            for (c, s) in cell.iter_mut().enumerate() {
                let idx = |x: u32, y: u32| y as usize * w as usize + x as usize;
                let pixels = (y0..y1).flat_map(|y| (x0..x1).map(move |x| (x, y)));
                s.n = ((x1 - x0) * (y1 - y0)) as f64;
                s.sum = pixels.clone().map(|(x, y)| d[idx(x, y)][c]).sum();
                let mean = s.sum / s.n;
                for (x, y) in pixels {
                    let dev = d[idx(x, y)][c] - mean;
                    s.s2 += dev * dev;
                    s.s4 += dev * dev * dev * dev;
                }
                // Unbiased for Σ Var(D) / φ: E Σd² = Σσ² (n − φ_cell) / n.
                let phi_cell = inflation(&rho, x1 - x0, y1 - y0, c);
                if s.n > phi_cell {
                    s.s2 *= s.n / (s.n - phi_cell);
                    s.s4 *= (s.n / (s.n - phi_cell)).powi(2);
                } else {
                    s.n = 0.0; // a one-pixel cell at the border: no estimate
                }
            }
        }
    }

    let mut sizes = vec![CELL];
    sizes.extend(BLOCKS.iter().copied().filter(|&k| k < w.max(h)));
    let whole = w.max(h);
    sizes.push(whole);
    let alpha_per_level = alpha / sizes.len() as f64;
    let mut levels = Vec::new();
    let mut pixel_min_p = vec![1.0f32; n];
    let mut exact_mismatches = 0;
    let mut first_exact_mismatch = None;
    for &k in &sizes {
        let is_whole = k == whole;
        let (mut tests, mut worst, mut small_p) = (0usize, None::<Finding>, Vec::new());
        let step = if is_whole { w.max(h) } else { k };
        for by in (0..h).step_by(step as usize) {
            for bx in (0..w).step_by(step as usize) {
                let (bx1, by1) = if is_whole {
                    (w, h)
                } else {
                    ((bx + k).min(w), (by + k).min(h))
                };
                for c in 0..3 {
                    let phi = inflation(&rho, bx1 - bx, by1 - by, c);
                    let BlockSums {
                        sum,
                        v,
                        s4,
                        mut dof,
                        pixels,
                        estimated,
                    } = block_sums(&cells, cw, (w, h), (bx, by, bx1, by1), c);
                    if estimated == 0.0 {
                        continue;
                    }
                    // Cells without an estimate count at the others' mean.
                    let variance = phi * v * pixels / estimated;
                    if variance == 0.0 {
                        if sum != 0.0 {
                            exact_mismatches += 1;
                            first_exact_mismatch.get_or_insert((bx, by, c));
                        }
                        continue;
                    }
                    if s4 > 0.0 {
                        dof = dof.min(3.0 * v * v / s4);
                    }
                    dof /= dof_thinning(&rho, c);
                    let t = sum / variance.sqrt();
                    let p = student_t_two_sided_p(t, dof.max(1.0));
                    tests += 1;
                    if worst.is_none_or(|f| p < f.p) {
                        worst = Some(Finding {
                            block: k,
                            x: bx,
                            y: by,
                            channel: c,
                            z: t,
                            p,
                            alpha: 0.0,
                        });
                    }
                    if p < alpha_per_level {
                        small_p.push(p);
                    }
                    if k == CELL {
                        for y in by..by1 {
                            for x in bx..bx1 {
                                let i = y as usize * w as usize + x as usize;
                                pixel_min_p[i] = pixel_min_p[i].min(p as f32);
                            }
                        }
                    }
                }
            }
        }
        let level_alpha = sidak(alpha_per_level, tests);
        if let Some(f) = &mut worst {
            f.alpha = level_alpha;
        }
        levels.push(LevelResult {
            block: k,
            whole_image: is_whole,
            tests,
            alpha: level_alpha,
            rejections: small_p.iter().filter(|&&p| p < level_alpha).count(),
            worst,
        });
    }

    let phi_16 = (0..3)
        .map(|c| inflation(&rho, 16.min(w), 16.min(h), c))
        .fold(1.0f64, f64::max);
    let phi_whole = (0..3)
        .map(|c| inflation(&rho, w, h, c))
        .fold(1.0f64, f64::max);
    let noise_model = format!(
        "estimated from the images (no variance layer): the spread of a - b within each \
         {CELL}x{CELL} cell, Student t with Satterthwaite's degrees of freedom; noise correlated \
         between neighbouring pixels scales block variances by up to {phi_16:.3} (16x16) and \
         {phi_whole:.3} (whole image); single pixels are not tested"
    );
    let average_a = a.average();
    let average_b = b.average();
    let mut mean_bias = [0.0; 3];
    let mut rel_difference = [0.0; 3];
    for c in 0..3 {
        mean_bias[c] = average_a[c] - average_b[c];
        rel_difference[c] = if mean_bias[c] == 0.0 {
            0.0
        } else {
            mean_bias[c] / average_b[c]
        };
    }
    let worst = levels
        .iter()
        .filter_map(|l| l.worst)
        .min_by(|x, y| (x.p / x.alpha).total_cmp(&(y.p / y.alpha)));
    Ok(Comparison {
        width: w,
        height: h,
        alpha,
        noise_model,
        levels,
        worst,
        exact_mismatches,
        first_exact_mismatch,
        nonfinite,
        exact_matches,
        unknown_variance: 0,
        average_a,
        average_b,
        mean_bias,
        rel_difference,
        pixel_min_p,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::splitmix::SplitMix64 as Rng;

    /// A 64×64 image of a smooth truth with a bright square (an edge with
    /// 10× the noise), plus noise that a 3×3 binomial filter spreads over
    /// neighbours when `splat` (as a renderer splatting samples through a
    /// pixel filter does): independent per pixel otherwise.
    fn synthetic(seed: u64, splat: bool) -> Image {
        let size = 64u32;
        let mut rng = Rng::new(seed);
        let truth = |x: u32, y: u32| -> f64 {
            let bright = (20..36).contains(&x) && (24..40).contains(&y);
            if bright {
                5.0
            } else {
                0.5 + 0.3 * (x as f64 / 9.0).sin()
            }
        };
        let (pad, wide) = (1i64, size as i64 + 2);
        let raw: Vec<[f64; 3]> = (0..wide * wide)
            .map(|_| [rng.normal(), rng.normal(), rng.normal()])
            .collect();
        let kernel = [0.25, 0.5, 0.25];
        let mut image = Image::new(size, size);
        for y in 0..size {
            for x in 0..size {
                let mut noise = [0.0; 3];
                if splat {
                    for (j, ky) in kernel.iter().enumerate() {
                        for (i, kx) in kernel.iter().enumerate() {
                            let (sx, sy) =
                                (x as i64 + pad + i as i64 - 1, y as i64 + pad + j as i64 - 1);
                            let r = raw[(sy * wide + sx) as usize];
                            for (n, r) in noise.iter_mut().zip(r) {
                                *n += kx * ky * r;
                            }
                        }
                    }
                } else {
                    noise = raw[((y as i64 + pad) * wide + x as i64 + pad) as usize];
                }
                let mu = truth(x, y);
                let i = image.index(x, y);
                for (m, n) in image.mean[i].iter_mut().zip(noise) {
                    *m = (mu * (1.0 + 0.1 * n)) as f32;
                }
            }
        }
        image
    }

    #[test]
    fn noise_correlated_between_neighbours_is_allowed_for() {
        // Spread by the binomial filter, a whole-image sum has 7.1 times
        // the variance of independent pixels of the same variance.
        let mut rejected = 0;
        let mut phi = 0.0;
        for seed in 0..50 {
            let a = synthetic(2 * seed + 1, true);
            let b = synthetic(2 * seed + 2, true);
            let cmp = compare_estimating_noise(&a, &b, 0.01).unwrap();
            if !cmp.passed() {
                rejected += 1;
                println!("{cmp}");
            }
            let at = cmp.noise_model.find("and ").unwrap() + 4;
            phi += cmp.noise_model[at..at + 5].parse::<f64>().unwrap() / 50.0;
        }
        println!(
            "splatted noise: {rejected} of 50 pairs rejected; mean whole-image inflation {phi:.2}"
        );
        assert!(rejected <= 2, "{rejected} of 50 pairs rejected");
        assert!((5.5..9.0).contains(&phi), "inflation {phi}");
    }

    #[test]
    fn independent_noise_with_a_noisy_edge_passes_and_a_bias_does_not() {
        let mut rejected = 0;
        for seed in 0..50 {
            let a = synthetic(1000 + 2 * seed, false);
            let b = synthetic(1001 + 2 * seed, false);
            rejected += !compare_estimating_noise(&a, &b, 0.01).unwrap().passed() as usize;
        }
        println!("independent noise: {rejected} of 50 pairs rejected");
        assert!(rejected <= 2, "{rejected} of 50 pairs rejected");
        let a = synthetic(7, false);
        let mut b = synthetic(8, false);
        for p in &mut b.mean {
            p.iter_mut().for_each(|c| *c *= 1.01);
        }
        let cmp = compare_estimating_noise(&a, &b, 0.01).unwrap();
        assert!(!cmp.passed(), "{cmp}");
    }

    #[test]
    fn identical_images_agree_and_a_constant_shift_is_a_mismatch() {
        let a = synthetic(3, false);
        let cmp = compare_estimating_noise(&a, &a, 0.01).unwrap();
        assert!(
            cmp.passed() && cmp.levels.iter().all(|l| l.tests == 0),
            "{cmp}"
        );
        let mut b = a.clone();
        b.mean.iter_mut().for_each(|p| p[0] += 0.25);
        let cmp = compare_estimating_noise(&a, &b, 0.01).unwrap();
        assert!(!cmp.passed() && cmp.exact_mismatches > 0, "{cmp}");
        let small = Image::new(3, 8);
        assert!(compare_estimating_noise(&small, &small, 0.01).is_err());
    }
}
