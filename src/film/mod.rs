//! Accumulation of samples into a film (both back ends write one), and the
//! protocol a back end follows between passes (`passes.rs`).
//!
//! The GPU accumulate kernel and the CPU reference both call the same Welford
//! update (`film_add_sample` here, its GLSL twin in the shaders), so a film
//! read back from the GPU means exactly what a CPU film means.

use crate::image::{Aovs, Image};
use crate::packed::layout::{AovPixel, FilmPixel};

pub mod merge;
pub mod passes;

/// Welford's update of one pixel with one sample.
///
/// The GLSL kernel performs exactly these f32 operations in this order; keep
/// them identical (and unfused) so both back ends agree to the last bit where
/// the shader compiler allows it.
#[inline]
pub fn film_add_sample(pixel: &mut FilmPixel, rgb: [f32; 3]) {
    let n = pixel.mean[3] + 1.0;
    for (c, &x) in rgb.iter().enumerate() {
        let delta = x - pixel.mean[c];
        pixel.mean[c] += delta / n;
        pixel.m2[c] += delta * (x - pixel.mean[c]);
    }
    pixel.mean[3] = n;
}

/// One sample's auxiliary outputs added to a pixel's running means (twin of
/// `aov_add_sample` in accumulate.comp); depth over the samples that hit
/// something (finite depth).
#[inline]
pub fn aov_add_sample(pixel: &mut AovPixel, albedo: [f32; 3], normal: [f32; 3], depth: f32) {
    let n = pixel.albedo[3] + 1.0;
    for c in 0..3 {
        pixel.albedo[c] += (albedo[c] - pixel.albedo[c]) / n;
        pixel.normal[c] += (normal[c] - pixel.normal[c]) / n;
    }
    pixel.albedo[3] = n;
    if !depth.is_infinite() {
        let h = pixel.depth[1] + 1.0;
        pixel.depth[0] += (depth - pixel.depth[0]) / h;
        pixel.depth[1] = h;
    }
}

/// Two pixels' auxiliary outputs as one: means weighted by their counts.
fn aov_merge_pixel(a: &mut AovPixel, b: &AovPixel) {
    let mix = |x: f32, y: f32, nx: f32, ny: f32| {
        if nx + ny == 0.0 {
            0.0
        } else {
            ((x as f64 * nx as f64 + y as f64 * ny as f64) / (nx as f64 + ny as f64)) as f32
        }
    };
    let (na, nb) = (a.albedo[3], b.albedo[3]);
    for c in 0..3 {
        a.albedo[c] = mix(a.albedo[c], b.albedo[c], na, nb);
        a.normal[c] = mix(a.normal[c], b.normal[c], na, nb);
    }
    a.albedo[3] = na + nb;
    a.depth[0] = mix(a.depth[0], b.depth[0], a.depth[1], b.depth[1]);
    a.depth[1] += b.depth[1];
}

/// Chan et al.'s parallel combination of two Welford states, in f64 so that
/// merging two large renders loses nothing beyond the final f32 rounding.
pub fn film_merge_pixel(a: &mut FilmPixel, b: &FilmPixel) {
    let na = a.mean[3] as f64;
    let nb = b.mean[3] as f64;
    let n = na + nb;
    if nb == 0.0 {
        return;
    }
    if na == 0.0 {
        *a = *b;
        return;
    }
    for c in 0..3 {
        let ma = a.mean[c] as f64;
        let mb = b.mean[c] as f64;
        let delta = mb - ma;
        a.mean[c] = (ma + delta * (nb / n)) as f32;
        a.m2[c] = (a.m2[c] as f64 + b.m2[c] as f64 + delta * delta * (na * nb / n)) as f32;
    }
    a.mean[3] = n as f32;
}

/// A film as the GPU accumulates it: one Welford state per pixel, row-major
/// with y = 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<FilmPixel>,
    /// The auxiliary outputs, one per pixel; empty when not recorded
    /// (`RenderSettings::aov`).
    pub aov: Vec<AovPixel>,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            pixels: vec![FilmPixel::default(); width as usize * height as usize],
            aov: Vec::new(),
        }
    }

    /// A film that also records the auxiliary outputs.
    pub fn with_aov(width: u32, height: u32) -> Self {
        let mut film = Film::new(width, height);
        film.aov = vec![AovPixel::default(); film.pixels.len()];
        film
    }

    #[inline]
    pub fn add_sample(&mut self, pixel_index: usize, rgb: [f32; 3]) {
        film_add_sample(&mut self.pixels[pixel_index], rgb);
    }

    /// Combines another render of the same image (independent samples) into
    /// this one, as if all samples had been added here.
    ///
    /// # Panics
    /// If the sizes differ: merging different images is a caller bug.
    pub fn merge(&mut self, other: &Film) {
        assert_eq!(
            (self.width, self.height),
            (other.width, other.height),
            "Film::merge: films of different sizes"
        );
        for (a, b) in self.pixels.iter_mut().zip(&other.pixels) {
            film_merge_pixel(a, b);
        }
        if self.aov.is_empty() || other.aov.is_empty() {
            self.aov.clear();
        }
        for (a, b) in self.aov.iter_mut().zip(&other.aov) {
            aov_merge_pixel(a, b);
        }
    }

    pub fn to_image(&self) -> Image {
        let mut mean = Vec::with_capacity(self.pixels.len());
        let mut variance = Vec::with_capacity(self.pixels.len());
        let mut samples = Vec::with_capacity(self.pixels.len());
        for p in &self.pixels {
            let n = p.mean[3];
            mean.push([p.mean[0], p.mean[1], p.mean[2]]);
            variance.push(variance_of_mean(p.m2, n));
            samples.push(n);
        }
        Image {
            width: self.width,
            height: self.height,
            mean,
            variance: Some(variance),
            samples: Some(samples),
            denoised: None,
            aovs: self.aovs(),
        }
    }

    /// The auxiliary outputs as image layers (none when not recorded). A
    /// pixel no sample of which hit anything has depth +inf.
    fn aovs(&self) -> Aovs {
        if self.aov.is_empty() {
            return Aovs::default();
        }
        let xyz = |v: [f32; 4]| [v[0], v[1], v[2]];
        Aovs {
            albedo: Some(self.aov.iter().map(|a| xyz(a.albedo)).collect()),
            normal: Some(self.aov.iter().map(|a| xyz(a.normal)).collect()),
            depth: Some(
                self.aov
                    .iter()
                    .map(|a| {
                        if a.depth[1] > 0.0 {
                            a.depth[0]
                        } else {
                            f32::INFINITY
                        }
                    })
                    .collect(),
            ),
        }
    }
}

/// Unbiased variance of the mean, m2 / (n - 1) / n.
///
/// With fewer than two samples the variance is unknown, and we say so with
/// `f32::INFINITY` rather than 0: a zero would claim the pixel is exact, while
/// infinity makes the comparison treat the pixel as uninformative and makes
/// the estimated error of the image honestly infinite.
fn variance_of_mean(m2: [f32; 4], n: f32) -> [f32; 3] {
    if n < 2.0 {
        return [f32::INFINITY; 3];
    }
    let n = n as f64;
    let f = |m: f32| (m.max(0.0) as f64 / (n - 1.0) / n) as f32;
    [f(m2[0]), f(m2[1]), f(m2[2])]
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::splitmix::SplitMix64;

    fn uniform(state: &mut SplitMix64) -> f64 {
        state.uniform()
    }

    #[test]
    fn film_welford_matches_two_pass() {
        let mut state = SplitMix64::new(7);
        // Skewed, path-tracer-like samples: mostly small, sometimes large.
        let samples: Vec<[f32; 3]> = (0..10_000)
            .map(|_| {
                let u = uniform(&mut state);
                let e = -(1.0 - uniform(&mut state)).ln();
                [u as f32, (e * 2.0) as f32, (0.3 + 0.01 * u) as f32]
            })
            .collect();
        let mut film = Film::new(1, 1);
        for s in &samples {
            film.add_sample(0, *s);
        }
        let p = film.pixels[0];
        assert_eq!(p.mean[3], 10_000.0);
        let n = samples.len() as f64;
        for c in 0..3 {
            let mean: f64 = samples.iter().map(|s| s[c] as f64).sum::<f64>() / n;
            let m2: f64 = samples
                .iter()
                .map(|s| (s[c] as f64 - mean).powi(2))
                .sum::<f64>();
            let rel_mean = ((p.mean[c] as f64 - mean) / mean).abs();
            let rel_m2 = ((p.m2[c] as f64 - m2) / m2).abs();
            assert!(rel_mean < 1e-5, "channel {c}: mean rel error {rel_mean}");
            assert!(rel_m2 < 1e-5, "channel {c}: m2 rel error {rel_m2}");
        }
        let image = film.to_image();
        let var = image.variance.unwrap()[0];
        for (v, m2) in var.iter().zip(p.m2) {
            let expected = m2 as f64 / (n - 1.0) / n;
            assert!(((*v as f64 - expected) / expected).abs() < 1e-6);
        }
    }

    #[test]
    fn film_merge_equals_single_film() {
        let mut state = SplitMix64::new(99);
        let samples: Vec<[f32; 3]> = (0..3000)
            .map(|_| {
                [
                    uniform(&mut state) as f32,
                    5.0 * uniform(&mut state) as f32,
                    1.0,
                ]
            })
            .collect();
        let mut all = Film::new(1, 1);
        let mut a = Film::new(1, 1);
        let mut b = Film::new(1, 1);
        for (i, s) in samples.iter().enumerate() {
            all.add_sample(0, *s);
            if i < 1000 {
                a.add_sample(0, *s);
            } else {
                b.add_sample(0, *s);
            }
        }
        let mut merged = a.clone();
        merged.merge(&b);
        let (m, e) = (merged.pixels[0], all.pixels[0]);
        assert_eq!(m.mean[3], e.mean[3]);
        for c in 0..3 {
            assert!((m.mean[c] - e.mean[c]).abs() <= 1e-5 * e.mean[c].abs());
            assert!((m.m2[c] - e.m2[c]).abs() <= 1e-4 * e.m2[c].abs() + 1e-6);
        }
        // Merging into an empty film copies.
        let mut empty = Film::new(1, 1);
        empty.merge(&a);
        assert_eq!(empty, a);
    }

    #[test]
    fn film_variance_unknown_below_two_samples() {
        let mut film = Film::new(2, 1);
        film.add_sample(0, [1.0, 2.0, 3.0]);
        let image = film.to_image();
        let var = image.variance.as_ref().unwrap();
        assert!(var[0].iter().all(|v| v.is_infinite()));
        assert!(var[1].iter().all(|v| v.is_infinite()));
        assert!(image.estimated_rel_mse().is_infinite());
        assert_eq!(image.samples.as_ref().unwrap()[0], 1.0);
    }
}
