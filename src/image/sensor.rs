//! A Bayer sensor behind the lens (`--sensor bayer`), applied to the finished
//! linear image on the host: the renderer's RGB film sees colour at every
//! pixel, a camera sees one colour per photosite and counts electrons.
//!
//! The model, in order:
//! 1. **Colour filter array.** RGGB: R at (even x, even y), G at (odd, even)
//!    and (even, odd), B at (odd, odd), counted from the image's top-left
//!    pixel (for a `--region` render, the region's). Each photosite keeps
//!    only its own channel of the linear image.
//! 2. **Exposure to electrons.** electrons = radiance × k, k =
//!    2^exposure_ev × `FULL_WELL_E`, where `exposure_ev` is the PNG's
//!    exposure (`tonemap::exposure_from_camera`: EV100 from shutter, ISO and
//!    f-number, plus `--exposure`). An exposed value of 1, the saturation
//!    point of the EV100 convention, fills the well, so a radiance the PNG
//!    maps to mid-grey (exposed 0.18) collects 18% of full well (1,800 e⁻).
//! 3. **Noise** (unless switched off): Poisson shot noise of mean electrons,
//!    plus Gaussian read noise of `READ_NOISE_E` RMS.
//! 4. **Clipping and quantisation.** Electrons are clipped to [0, full well]
//!    (no black-level offset) and rounded to N-bit ADU: full well is
//!    2^N − 1 ADU.
//! 5. **Back to radiance.** ADU × (e⁻ per ADU) / k, so the demosaiced
//!    image is comparable with the ideal one.
//! 6. **Demosaic**: bilinear, or Malvar, He and Cutler's gradient-corrected
//!    linear interpolation (ICASSP 2004), both with mirrored borders.
//!
//! Random numbers come from splitmix64 streams keyed by the render seed and
//! the photosite index, so the noise does not depend on evaluation order.

/// Electrons a photosite holds before it saturates.
pub const FULL_WELL_E: f64 = 10_000.0;
/// Read noise, electrons RMS, added to every photosite.
pub const READ_NOISE_E: f64 = 3.0;
/// ADC bit depth without `--sensor-bits`.
pub const DEFAULT_BITS: u32 = 12;
/// Exposed value (radiance × 2^exposure_ev) that fills the well.
pub const EXPOSED_AT_FULL_WELL: f64 = 1.0;
/// Below this mean the Poisson sampler multiplies uniforms (Knuth); at and
/// above it, a rounded normal of the same mean and variance.
pub const POISSON_KNUTH_BELOW: f64 = 30.0;

/// How the missing two colours of each photosite are interpolated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Demosaic {
    /// Average of the nearest photosites of the missing colour.
    Bilinear,
    /// Malvar, He and Cutler 2004: bilinear plus a Laplacian correction from
    /// the photosite's own colour, 5×5 filters.
    #[default]
    Mhc,
}

impl Demosaic {
    /// Names accepted by `from_name`, for command-line help.
    pub const NAMES: &'static [&'static str] = &["bilinear", "mhc"];

    pub fn from_name(name: &str) -> Option<Self> {
        match name.to_ascii_lowercase().as_str() {
            "bilinear" => Some(Demosaic::Bilinear),
            "mhc" | "malvar" => Some(Demosaic::Mhc),
            _ => None,
        }
    }
}

/// What the sensor does with the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorSettings {
    /// ADC bits, 1 to 16.
    pub bits: u32,
    /// Shot and read noise; off gives a noiseless (still quantised) mosaic.
    pub noise: bool,
    pub demosaic: Demosaic,
    /// The PNG's exposure in stops (radiance × 2^exposure_ev is exposed).
    pub exposure_ev: f32,
    pub seed: u64,
}

impl SensorSettings {
    /// k: electrons per unit of radiance.
    pub fn electrons_per_radiance(&self) -> f64 {
        (self.exposure_ev as f64).exp2() * FULL_WELL_E / EXPOSED_AT_FULL_WELL
    }

    /// The largest ADU, 2^N − 1, which full well maps to.
    pub fn max_adu(&self) -> f64 {
        ((1u64 << self.bits) - 1) as f64
    }

    /// Electrons per ADU (the conversion gain's inverse).
    pub fn electrons_per_adu(&self) -> f64 {
        FULL_WELL_E / self.max_adu()
    }

    /// Radiance per ADU: what one count means in the output image.
    pub fn radiance_per_adu(&self) -> f64 {
        self.electrons_per_adu() / self.electrons_per_radiance()
    }
}

/// The sensor's output: the raw mosaic in ADU (one value per pixel, row
/// major) and the demosaiced linear RGB image in radiance units.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorImage {
    pub mosaic_adu: Vec<f32>,
    pub rgb: Vec<[f32; 3]>,
}

/// The channel (0 R, 1 G, 2 B) the RGGB filter passes at (x, y).
#[inline]
pub fn cfa_channel(x: u32, y: u32) -> usize {
    match (x & 1, y & 1) {
        (0, 0) => 0,
        (1, 1) => 2,
        _ => 1,
    }
}

use crate::splitmix::SplitMix64;

/// A Poisson draw of mean `mean` ≥ 0. Below `POISSON_KNUTH_BELOW`, Knuth's
/// method (count uniforms until their product falls below e^-mean:
/// exact); above, round(mean + √mean·z) clamped at 0, the normal
/// approximation (variance mean + 1/12 from the rounding; its skewness
/// 1/√mean ≤ 0.18 is lost).
pub fn poisson(rng: &mut SplitMix64, mean: f64) -> f64 {
    if mean <= 0.0 {
        return 0.0;
    }
    if mean < POISSON_KNUTH_BELOW {
        let limit = (-mean).exp();
        let mut k = 0.0;
        let mut p = rng.uniform();
        while p > limit {
            k += 1.0;
            p *= rng.uniform();
        }
        k
    } else {
        (mean + mean.sqrt() * rng.normal()).round().max(0.0)
    }
}

/// The random stream of photosite `index`: independent of the order in
/// which photosites are visited.
fn photosite_rng(seed: u64, index: usize) -> SplitMix64 {
    let mut mix = SplitMix64::new(seed ^ 0x5e45_0b5e_45e0_0001);
    let key = mix.next_u64() ^ (index as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    SplitMix64::new(SplitMix64::new(key).next_u64())
}

/// Electrons a photosite reports for `mean` expected electrons, before
/// clipping: Poisson(mean) + N(0, READ_NOISE_E²). Variance mean + 9.
pub fn noisy_electrons(mean: f64, rng: &mut SplitMix64) -> f64 {
    poisson(rng, mean) + READ_NOISE_E * rng.normal()
}

/// Clips electrons to [0, full well] and rounds to ADU.
pub fn quantise(electrons: f64, settings: &SensorSettings) -> f32 {
    let e = electrons.clamp(0.0, FULL_WELL_E);
    (e / settings.electrons_per_adu()).round() as f32
}

/// The raw mosaic in ADU of a linear RGB image (`width` × `height`, row
/// major): steps 1 to 4 of the module doc.
pub fn expose(width: u32, height: u32, linear: &[[f32; 3]], settings: &SensorSettings) -> Vec<f32> {
    assert_eq!(linear.len(), width as usize * height as usize);
    let k = settings.electrons_per_radiance();
    let mut mosaic = Vec::with_capacity(linear.len());
    for y in 0..height {
        for x in 0..width {
            let i = y as usize * width as usize + x as usize;
            let radiance = linear[i][cfa_channel(x, y)] as f64;
            let radiance = if radiance.is_finite() {
                radiance.max(0.0)
            } else if radiance > 0.0 {
                f64::MAX
            } else {
                0.0
            };
            let mean = (radiance * k).min(4.0 * FULL_WELL_E);
            let electrons = if settings.noise {
                noisy_electrons(mean, &mut photosite_rng(settings.seed, i))
            } else {
                mean
            };
            mosaic.push(quantise(electrons, settings));
        }
    }
    mosaic
}

/// Index into a row or column of length `n` with mirrored borders (the
/// edge sample not repeated: −1 → 1, n → n − 2), which keeps the CFA's
/// parity, so a mirrored neighbour has the colour its position says.
#[inline]
fn mirror(i: i64, n: u32) -> u32 {
    let n = n as i64;
    if n == 1 {
        return 0;
    }
    let period = 2 * (n - 1);
    let mut i = i.rem_euclid(period);
    if i >= n {
        i = period - i;
    }
    i as u32
}

/// A 5×5 filter, weights × 16 (all integers), centred on the photosite;
/// row index is dy + 2, column dx + 2.
type Kernel = [[i32; 5]; 5];

/// Kernels from Malvar, He and Cutler 2004, figure 2 (weights there are
/// over 8; here over 16 so that the ½ and 3/2 entries are integers).
/// G at an R or B site: the 4 green neighbours plus the own colour's
/// Laplacian at half weight.
const MHC_G_AT_RB: Kernel = [
    [0, 0, -2, 0, 0],
    [0, 0, 4, 0, 0],
    [-2, 4, 8, 4, -2],
    [0, 0, 4, 0, 0],
    [0, 0, -2, 0, 0],
];
/// R at a G site in an R row (or B at a G site in a B row): the two
/// horizontal neighbours, corrected by green.
const MHC_ROW_AT_G: Kernel = [
    [0, 0, 1, 0, 0],
    [0, -2, 0, -2, 0],
    [-2, 8, 10, 8, -2],
    [0, -2, 0, -2, 0],
    [0, 0, 1, 0, 0],
];
/// R at a G site in a B row (or B at a G site in an R row): the two
/// vertical neighbours; the transpose of `MHC_ROW_AT_G`.
const MHC_COLUMN_AT_G: Kernel = [
    [0, 0, -2, 0, 0],
    [0, -2, 8, -2, 0],
    [1, 0, 10, 0, 1],
    [0, -2, 8, -2, 0],
    [0, 0, -2, 0, 0],
];
/// R at a B site (or B at an R site): the 4 diagonal neighbours, corrected
/// by the own colour at 3/4 weight.
const MHC_DIAGONAL: Kernel = [
    [0, 0, -3, 0, 0],
    [0, 4, 0, 4, 0],
    [-3, 0, 12, 0, -3],
    [0, 4, 0, 4, 0],
    [0, 0, -3, 0, 0],
];
/// Bilinear: the same neighbours without the corrections.
const BILINEAR_G_AT_RB: Kernel = [
    [0, 0, 0, 0, 0],
    [0, 0, 4, 0, 0],
    [0, 4, 0, 4, 0],
    [0, 0, 4, 0, 0],
    [0, 0, 0, 0, 0],
];
const BILINEAR_ROW_AT_G: Kernel = [
    [0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0],
    [0, 8, 0, 8, 0],
    [0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0],
];
const BILINEAR_COLUMN_AT_G: Kernel = [
    [0, 0, 0, 0, 0],
    [0, 0, 8, 0, 0],
    [0, 0, 0, 0, 0],
    [0, 0, 8, 0, 0],
    [0, 0, 0, 0, 0],
];
const BILINEAR_DIAGONAL: Kernel = [
    [0, 0, 0, 0, 0],
    [0, 4, 0, 4, 0],
    [0, 0, 0, 0, 0],
    [0, 4, 0, 4, 0],
    [0, 0, 0, 0, 0],
];

/// The filter that estimates `channel` at a photosite of `site` colour
/// in an R row (`r_row`: y even) or a B row; None where the photosite
/// measured it.
fn kernel_for(
    method: Demosaic,
    site: usize,
    r_row: bool,
    channel: usize,
) -> Option<&'static Kernel> {
    if site == channel {
        return None;
    }
    let (g_at_rb, row_at_g, column_at_g, diagonal) = match method {
        Demosaic::Mhc => (&MHC_G_AT_RB, &MHC_ROW_AT_G, &MHC_COLUMN_AT_G, &MHC_DIAGONAL),
        Demosaic::Bilinear => (
            &BILINEAR_G_AT_RB,
            &BILINEAR_ROW_AT_G,
            &BILINEAR_COLUMN_AT_G,
            &BILINEAR_DIAGONAL,
        ),
    };
    Some(match (site, channel) {
        (0, 1) | (2, 1) => g_at_rb,
        (1, 0) if r_row => row_at_g,
        (1, 0) => column_at_g,
        (1, 2) if r_row => column_at_g,
        (1, 2) => row_at_g,
        _ => diagonal, // (0, 2), (2, 0)
    })
}

/// Interpolates the full RGB image from a mosaic (any units), borders
/// mirrored.
pub fn demosaic(width: u32, height: u32, mosaic: &[f32], method: Demosaic) -> Vec<[f32; 3]> {
    assert_eq!(mosaic.len(), width as usize * height as usize);
    let at = |x: i64, y: i64| {
        mosaic[mirror(y, height) as usize * width as usize + mirror(x, width) as usize]
    };
    let mut rgb = Vec::with_capacity(mosaic.len());
    for y in 0..height {
        for x in 0..width {
            let site = cfa_channel(x, y);
            let own = at(x as i64, y as i64);
            let mut pixel = [0.0f32; 3];
            for (channel, out) in pixel.iter_mut().enumerate() {
                *out = match kernel_for(method, site, y & 1 == 0, channel) {
                    None => own,
                    Some(kernel) => {
                        let mut sum = 0.0f32;
                        for (row, weights) in kernel.iter().enumerate() {
                            for (col, &w) in weights.iter().enumerate() {
                                if w != 0 {
                                    let v =
                                        at(x as i64 + col as i64 - 2, y as i64 + row as i64 - 2);
                                    sum += w as f32 * v;
                                }
                            }
                        }
                        sum / 16.0
                    }
                };
            }
            rgb.push(pixel);
        }
    }
    rgb
}

/// The whole model: mosaic in ADU, and the demosaiced image in radiance.
pub fn simulate(
    width: u32,
    height: u32,
    linear: &[[f32; 3]],
    settings: &SensorSettings,
) -> SensorImage {
    let mosaic_adu = expose(width, height, linear, settings);
    let per_adu = settings.radiance_per_adu() as f32;
    let radiance: Vec<f32> = mosaic_adu.iter().map(|&a| a * per_adu).collect();
    let rgb = demosaic(width, height, &radiance, settings.demosaic);
    SensorImage { mosaic_adu, rgb }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(noise: bool) -> SensorSettings {
        SensorSettings {
            bits: DEFAULT_BITS,
            noise,
            demosaic: Demosaic::Mhc,
            exposure_ev: 0.0,
            seed: 7,
        }
    }

    /// Mosaic of a linear image, no noise, no quantisation.
    fn mosaic_of(width: u32, height: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Vec<f32> {
        let mut m = Vec::new();
        for y in 0..height {
            for x in 0..width {
                m.push(f(x, y)[cfa_channel(x, y)]);
            }
        }
        m
    }

    #[test]
    fn cfa_has_twice_as_many_green_sites_as_red_or_blue() {
        let mut count = [0usize; 3];
        for y in 0..64 {
            for x in 0..48 {
                count[cfa_channel(x, y)] += 1;
            }
        }
        assert_eq!(count[1], 2 * count[0]);
        assert_eq!(count[0], count[2]);
        assert_eq!(
            (
                cfa_channel(0, 0),
                cfa_channel(1, 0),
                cfa_channel(0, 1),
                cfa_channel(1, 1)
            ),
            (0, 1, 1, 2)
        );
    }

    #[test]
    fn demosaic_of_a_constant_image_is_exact_everywhere() {
        let c = [0.25f32, 1.5, 3.0];
        let (w, h) = (9, 7);
        let m = mosaic_of(w, h, |_, _| c);
        for method in [Demosaic::Bilinear, Demosaic::Mhc] {
            for p in demosaic(w, h, &m, method) {
                assert_eq!(p, c, "{method:?}");
            }
        }
    }

    /// Each channel its own linear function a + b·x + c·y (integer
    /// coefficients, so every sum is exact in f32): both methods give it
    /// back exactly at every pixel at least 2 from the border (the 5×5
    /// support; mirroring bends a ramp into a tent at the border). The
    /// filters' weights on each colour sum to 16 (interpolated colour) or 0
    /// (correction) and are point-symmetric, so they pass constants and
    /// kill first moments.
    #[test]
    fn demosaic_of_linear_ramps_is_exact_in_the_interior() {
        let (w, h) = (12, 10);
        type Ramp = fn(u32, u32) -> [f32; 3];
        let ramps: [(&str, Ramp); 3] = [
            ("x", |x, _| {
                [x as f32, 2.0 * x as f32 + 1.0, 5.0 - 3.0 * x as f32]
            }),
            ("y", |_, y| [3.0 * y as f32, 7.0 - y as f32, 2.0 * y as f32]),
            ("diagonal", |x, y| {
                let (x, y) = (x as f32, y as f32);
                [x + y, 2.0 * x - 3.0 * y + 40.0, 10.0 - x + 4.0 * y]
            }),
        ];
        for (name, f) in ramps {
            let m = mosaic_of(w, h, f);
            for method in [Demosaic::Bilinear, Demosaic::Mhc] {
                let out = demosaic(w, h, &m, method);
                for y in 2..h - 2 {
                    for x in 2..w - 2 {
                        assert_eq!(
                            out[(y * w + x) as usize],
                            f(x, y),
                            "{name} ramp, {method:?}, ({x}, {y})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn mirror_keeps_parity() {
        for n in [2u32, 5, 6] {
            for i in -4i64..n as i64 + 4 {
                let m = mirror(i, n);
                assert!(m < n);
                assert_eq!(m as i64 % 2, i.rem_euclid(2), "n {n} i {i}");
            }
        }
    }

    /// Var = mean + read², estimated from n draws; the sample variance's
    /// standard error is about σ²·√(2/(n−1)) (plus the excess kurtosis
    /// term, mean/σ⁴, which is small here); tolerance 5 standard errors.
    #[test]
    fn noise_variance_is_mean_plus_read_noise_squared() {
        let n = 200_000;
        for mean in [0.0, 2.0, 12.0, 29.0, 30.0, 400.0, 5000.0] {
            let mut sum = 0.0;
            let mut sum2 = 0.0;
            for i in 0..n {
                let e = noisy_electrons(mean, &mut photosite_rng(3, i));
                sum += e;
                sum2 += e * e;
            }
            let m = sum / n as f64;
            let var = (sum2 - sum * m) / (n - 1) as f64;
            let expected = mean + READ_NOISE_E * READ_NOISE_E;
            let se = expected * (2.0 / (n - 1) as f64).sqrt() + (mean / n as f64).sqrt();
            assert!(
                (var - expected).abs() < 5.0 * se,
                "mean {mean}: variance {var}, expected {expected} ± {se}"
            );
            assert!(
                (m - mean).abs() < 5.0 * (expected / n as f64).sqrt(),
                "mean {mean}: got {m}"
            );
        }
    }

    #[test]
    fn noiseless_mosaic_is_within_half_an_adu() {
        let s = settings(false);
        let (w, h) = (8, 8);
        // Radiances up to just below full well (exposed 1).
        let linear: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let v = i as f32 / (w * h) as f32;
                [v, 0.5 * v, 0.99 - v * 0.9]
            })
            .collect();
        let mosaic = expose(w, h, &linear, &s);
        let per_adu = s.radiance_per_adu();
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let truth = linear[i][cfa_channel(x, y)] as f64;
                let err = (mosaic[i] as f64 * per_adu - truth).abs();
                assert!(
                    err <= 0.5 * per_adu * (1.0 + 1e-6),
                    "({x}, {y}): error {err}"
                );
                assert_eq!(mosaic[i], mosaic[i].round());
            }
        }
        // Saturation clips at 2^N - 1.
        let bright = expose(2, 2, &[[5.0; 3]; 4], &s);
        assert!(bright.iter().all(|&a| a as f64 == s.max_adu()));
    }

    #[test]
    fn mid_grey_fills_18_percent_of_full_well() {
        let mut s = settings(false);
        s.exposure_ev = -3.0;
        // Radiance 0.18 · 2^3 is exposed to 0.18.
        let mosaic = expose(1, 1, &[[0.18 * 8.0; 3]], &s);
        let electrons = mosaic[0] as f64 * s.electrons_per_adu();
        assert!((electrons - 0.18 * FULL_WELL_E).abs() <= s.electrons_per_adu());
    }

    /// The whole chain without noise gives a constant image back within
    /// half an ADU, in radiance, in every channel of every pixel (borders
    /// too), for both demosaicing methods and an exposure from EV100.
    #[test]
    fn noiseless_sensor_returns_a_constant_image() {
        let c = [0.3f32, 0.05, 0.7];
        for demosaic in [Demosaic::Bilinear, Demosaic::Mhc] {
            let mut s = settings(false);
            s.demosaic = demosaic;
            s.exposure_ev = crate::image::tonemap::exposure_from_camera(2.8, 1.0 / 60.0, 400.0);
            // Radiance c · 1.2 · 2^EV100 is exposed to c.
            let ev = crate::image::tonemap::ev100(2.8, 1.0 / 60.0, 400.0);
            let linear = vec![c.map(|v| v * 1.2 * ev.exp2()); 35];
            let out = simulate(7, 5, &linear, &s);
            let tolerance = 0.5 * s.radiance_per_adu() as f32 * 1.0001;
            for p in &out.rgb {
                for ch in 0..3 {
                    assert!(
                        (p[ch] - linear[0][ch]).abs() <= tolerance,
                        "{demosaic:?}: {p:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn noise_is_deterministic_per_seed() {
        let linear = vec![[0.3f32, 0.2, 0.1]; 16];
        let a = simulate(4, 4, &linear, &settings(true));
        let b = simulate(4, 4, &linear, &settings(true));
        assert_eq!(a, b);
        let mut other = settings(true);
        other.seed = 8;
        assert_ne!(a.mosaic_adu, simulate(4, 4, &linear, &other).mosaic_adu);
    }
}
