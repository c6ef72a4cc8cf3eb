//! What the user asked for, independent of the back end.

use crate::constants::{SAMPLER_DEFAULT, SAMPLER_INDEPENDENT, SAMPLER_SOBOL};

/// Settings of one render.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
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
}

/// The random-number sequence of a render (`rng.glsl`, `src/cpu/rng.rs`).
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
        }
    }
}

impl RenderSettings {
    pub fn pixel_count(&self) -> u64 {
        self.width as u64 * self.height as u64
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
        // The film counts samples in an f32, exact up to 2^24.
        anyhow::ensure!(
            self.spp <= 1 << 24,
            "{} samples per pixel is above the 16777216 the film counts exactly",
            self.spp
        );
        if let Some(d) = self.max_depth {
            anyhow::ensure!(
                d >= 1,
                "a maximum path depth must be at least 1 (or no limit)"
            );
        }
        Ok(())
    }
}
