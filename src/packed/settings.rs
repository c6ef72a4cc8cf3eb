//! What the user asked for, independent of the back end.

use crate::constants::{SAMPLER_DEFAULT, SAMPLER_INDEPENDENT, SAMPLER_SOBOL};
use crate::image::Region;

/// The most samples a pixel may count: the film counts them in an f32,
/// exact up to 2^24.
pub const MAX_SAMPLES: u32 = 1 << 24;

/// Settings of one render.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// The full image's size (the camera's frame), also when only a
    /// `region` of it is rendered.
    pub width: u32,
    pub height: u32,
    /// Samples per pixel this render takes: the sample indices
    /// `first_sample .. first_sample + spp`.
    pub spp: u32,
    /// The first sample index: a render of samples A..B draws, for each of
    /// them, the very numbers a render of 0..B draws, so renders of disjoint
    /// ranges merge into that render (`film::merge`).
    pub first_sample: u32,
    /// The rectangle of the image to render, `None` for all of it. Camera
    /// and pixel coordinates (and so the paths traced) stay the full
    /// image's; the film covers the region only.
    pub region: Option<Region>,
    /// Record the auxiliary outputs (albedo, normal, depth: `image::Aovs`).
    pub aov: bool,
    /// Longest path kept, in segments (Mitsuba's `max_depth`): 1 shows
    /// emitters only, 2 direct lighting, `None` no limit (Russian roulette
    /// ends paths without bias).
    pub max_depth: Option<u32>,
    /// Seed of the random-number function; renders with different seeds are
    /// independent.
    pub seed: u32,
    /// Index into `Scene::cameras`.
    pub camera: usize,
    /// How random numbers are drawn.
    pub sampler: Sampler,
    /// How textures are filtered when minified.
    pub texture_filter: TextureFilter,
}

/// Texture filtering (`textures.glsl`): trilinear between the mip levels a
/// pixel's footprint spans, or bilinear on the full-resolution image only.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TextureFilter {
    #[default]
    Mip,
    Bilinear,
}

impl TextureFilter {
    pub const NAMES: [&str; 2] = ["mip", "bilinear"];

    pub fn from_name(name: &str) -> Option<TextureFilter> {
        match name {
            "mip" => Some(TextureFilter::Mip),
            "bilinear" => Some(TextureFilter::Bilinear),
            _ => None,
        }
    }
}

/// The random-number sequence of a render (`rng.glsl`, `src/cpu/common/rng.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampler {
    /// A hash per (path, dimension): independent samples.
    Independent,
    /// Owen-scrambled Sobol with per-dimension index shuffles (Burley 2020):
    /// the first 2^k samples of a pixel are stratified in every 1D and 2D
    /// draw.
    Sobol,
}

impl Sampler {
    pub const NAMES: [&str; 2] = ["independent", "sobol"];

    pub fn from_name(name: &str) -> Option<Sampler> {
        match name {
            "independent" => Some(Sampler::Independent),
            "sobol" => Some(Sampler::Sobol),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Sampler::Independent => "independent",
            Sampler::Sobol => "sobol",
        }
    }

    /// `RenderParams::sampler`.
    pub fn id(self) -> u32 {
        match self {
            Sampler::Independent => SAMPLER_INDEPENDENT,
            Sampler::Sobol => SAMPLER_SOBOL,
        }
    }
}

impl Default for Sampler {
    fn default() -> Self {
        if SAMPLER_DEFAULT == SAMPLER_SOBOL {
            Sampler::Sobol
        } else {
            Sampler::Independent
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 512,
            height: 512,
            spp: 64,
            max_depth: None,
            seed: 0,
            camera: 0,
            sampler: Sampler::default(),
            first_sample: 0,
            region: None,
            aov: false,
            texture_filter: TextureFilter::default(),
        }
    }
}

impl RenderSettings {
    /// The rectangle rendered: `region`, or the whole image.
    pub fn film_region(&self) -> Region {
        self.region.unwrap_or(Region::full(self.width, self.height))
    }

    /// Pixels rendered (the film's): the region's.
    pub fn pixel_count(&self) -> u64 {
        self.film_region().pixel_count()
    }

    /// The sample indices rendered.
    pub fn samples(&self) -> std::ops::Range<u32> {
        self.first_sample..self.first_sample.saturating_add(self.spp)
    }

    pub fn validate(&self) -> anyhow::Result<()> {
        anyhow::ensure!(
            self.width > 0 && self.height > 0,
            "image size {}x{} is empty",
            self.width,
            self.height
        );
        anyhow::ensure!(
            self.width <= 16384 && self.height <= 16384,
            "image size {}x{} exceeds 16384 in one dimension",
            self.width,
            self.height
        );
        anyhow::ensure!(self.spp > 0, "samples per pixel must be at least 1");
        anyhow::ensure!(
            self.spp <= MAX_SAMPLES,
            "{} samples per pixel is above the {MAX_SAMPLES} the film counts exactly",
            self.spp
        );
        // A merge of ranges counts up to the range's end in one film.
        anyhow::ensure!(
            self.first_sample as u64 + self.spp as u64 <= MAX_SAMPLES as u64,
            "sample range {}..{} ends above the {MAX_SAMPLES} samples a film counts exactly",
            self.first_sample,
            self.first_sample as u64 + self.spp as u64
        );
        if let Some(region) = self.region {
            region.check_inside(self.width, self.height)?;
        }
        if let Some(d) = self.max_depth {
            anyhow::ensure!(
                d >= 1,
                "a maximum path depth must be at least 1 (or no limit)"
            );
        }
        Ok(())
    }
}
