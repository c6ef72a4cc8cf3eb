//! Images as files and as data to measure: the finished image (`Image`),
//! EXR/PNG files (`io`) and the record of what a render holds (`header`,
//! `region`), tone mapping and exposure (`tonemap`), error metrics against
//! a reference (`metrics`), the statistical test of whether two renders
//! have the same expectation (`compare`; `estimated_noise` when the images
//! carry no variance, with `student_t` for its estimated variances),
//! denoising with Open Image Denoise (`denoise`) and a Bayer camera sensor
//! applied to the finished image (`sensor`).

pub mod compare;
pub mod denoise;
pub mod estimated_noise;
pub mod header;
pub mod io;
pub mod metrics;
pub mod region;
pub mod sensor;
pub mod student_t;
pub mod tonemap;

pub use header::RenderHeader;
pub use io::{
    SUPPORTED_EXTENSIONS, read_exr, read_exr_header, read_exr_part, write_image,
    write_image_with_header, write_mosaic,
};
pub use region::Region;
pub use tonemap::{PngSettings, ToneMap};

/// The relMSE epsilon: keeps near-black pixels from dominating relative errors.
pub const REL_MSE_EPSILON: f64 = 0.01;

/// A finished image: linear radiance per pixel (row-major, y = 0 at the top),
/// optionally with the per-channel variance of each pixel's mean (infinite
/// where it is unknown, see `Film::to_image`) and the sample count, and
/// optionally a denoised version of `mean` (`denoise`), which the EXR keeps
/// as a layer beside the raw beauty and the PNG shows instead of it. Every
/// measurement (compare, merge, relMSE) reads `mean`, never `denoised`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub mean: Vec<[f32; 3]>,
    pub variance: Option<Vec<[f32; 3]>>,
    pub samples: Option<Vec<f32>>,
    pub denoised: Option<Vec<[f32; 3]>>,
    /// Auxiliary outputs, each written as its own EXR layer when present.
    pub aovs: Aovs,
}

/// Per-pixel auxiliary outputs (AOVs) of a render: the mean over a pixel's
/// samples of the first rough surface's albedo and shading normal (world
/// space), and the mean distance along the camera ray of the samples that
/// hit something (+inf where none did). See `shaders/common/aov.glsl`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Aovs {
    pub albedo: Option<Vec<[f32; 3]>>,
    pub normal: Option<Vec<[f32; 3]>>,
    pub depth: Option<Vec<f32>>,
}

impl Aovs {
    pub fn is_empty(&self) -> bool {
        self.albedo.is_none() && self.normal.is_none() && self.depth.is_none()
    }
}

impl Image {
    /// A black image without variance or sample counts.
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            mean: vec![[0.0; 3]; width as usize * height as usize],
            variance: None,
            samples: None,
            aovs: Aovs::default(),
            denoised: None,
        }
    }

    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Expected relative MSE of this image against its own expectation,
    /// estimated from the variance of each pixel's mean. NaN when the image has
    /// no variance; infinite when any pixel's variance is unknown (fewer than
    /// two samples).
    pub fn estimated_rel_mse(&self) -> f64 {
        let Some(variance) = &self.variance else {
            return f64::NAN;
        };
        if self.mean.is_empty() {
            return 0.0;
        }
        let mut sum = 0.0f64;
        for (m, v) in self.mean.iter().zip(variance) {
            for c in 0..3 {
                let mc = m[c] as f64;
                sum += v[c] as f64 / (mc * mc + REL_MSE_EPSILON);
            }
        }
        sum / (3 * self.mean.len()) as f64
    }

    /// Estimated relative RMS error (square root of `estimated_rel_mse`).
    pub fn estimated_rel_error(&self) -> f64 {
        self.estimated_rel_mse().sqrt()
    }

    /// Average of the pixel means per channel.
    pub fn average(&self) -> [f64; 3] {
        let mut sum = [0.0f64; 3];
        for m in &self.mean {
            for c in 0..3 {
                sum[c] += m[c] as f64;
            }
        }
        let n = self.mean.len().max(1) as f64;
        sum.map(|s| s / n)
    }

    /// Number of pixels whose mean has a NaN or infinite channel.
    pub fn count_nonfinite(&self) -> usize {
        self.mean
            .iter()
            .filter(|m| m.iter().any(|v| !v.is_finite()))
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_estimated_error_and_average() {
        let mut image = Image::new(2, 1);
        image.mean = vec![[1.0, 0.0, 2.0], [3.0, 0.0, 4.0]];
        assert!(image.estimated_rel_mse().is_nan());
        image.variance = Some(vec![[0.0101, 0.0, 0.0], [0.0, 0.0, 0.0]]);
        assert_eq!(image.count_nonfinite(), 0);
        let avg = image.average();
        assert_eq!(avg[0], 2.0);
        // Only the first pixel's red channel contributes: 0.0101 / 1.01 / 6.
        let expected = 0.0101f32 as f64 / 1.01 / 6.0;
        assert!((image.estimated_rel_mse() - expected).abs() < 1e-9);
        assert!((image.estimated_rel_error() - expected.sqrt()).abs() < 1e-9);
        image.mean[1][2] = f32::NAN;
        image.mean[0][1] = f32::INFINITY;
        assert_eq!(image.count_nonfinite(), 2);
    }
}
