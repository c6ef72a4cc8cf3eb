//! One render, on either back end, with what it measured.

use crate::film::Film;
use crate::packed::PackedScene;
use crate::scene::Scene;
use crate::settings::RenderSettings;
use std::time::Duration;

/// Which back end renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceChoice {
    /// The best Vulkan device (discrete > integrated > virtual > CPU driver).
    Auto,
    /// A Vulkan device that is not a CPU driver.
    Gpu,
    /// Mesa's lavapipe (a Vulkan driver running on the CPU).
    Lavapipe,
    /// The CPU reference path tracer, no Vulkan.
    Cpu,
}

impl DeviceChoice {
    pub fn from_name(name: &str) -> Option<DeviceChoice> {
        match name {
            "auto" => Some(DeviceChoice::Auto),
            "gpu" => Some(DeviceChoice::Gpu),
            "lavapipe" => Some(DeviceChoice::Lavapipe),
            "cpu" => Some(DeviceChoice::Cpu),
            _ => None,
        }
    }
}

/// What a render produced and measured.
pub struct RenderResult {
    pub film: Film,
    /// Samples every pixel of `film` has: the spp asked for, or fewer when a
    /// `PassControl` stopped the render early.
    pub spp: u32,
    /// "CPU reference (N threads)" or the Vulkan device's name.
    pub device_name: String,
    pub render_time: Duration,
    pub extension_rays: u64,
    pub shadow_rays: u64,
    /// Rays whose BVH traversal exceeded the stack or iteration bound.
    pub traversal_overflows: u64,
    /// Samples dropped because they were NaN or infinite.
    pub nonfinite_samples: u64,
    /// The features the kernels were specialized to (Vulkan only).
    pub kernel_variant: Option<String>,
    /// Total time per kernel, from timestamp queries (GPU only).
    pub kernel_times: Vec<(String, Duration)>,
}

/// Progress callback: samples finished so far, out of the total.
pub type Progress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// Both back ends render in passes, each adding the same number of samples to
/// every pixel, so between passes the film is a consistent image (every pixel
/// has the same sample count). After each pass the renderer asks its
/// `PassControl` whether to go on.
pub trait PassControl {
    /// Called after each pass with the samples per pixel finished so far;
    /// `film()` returns the film as it is now (on the GPU, a read-back: call
    /// it only when needed). Returns `false` to stop here.
    fn after_pass(
        &mut self,
        spp: u32,
        film: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool>;
}

/// Renders every sample asked for.
pub struct RenderAll;

impl PassControl for RenderAll {
    fn after_pass(
        &mut self,
        _: u32,
        _: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool> {
        Ok(true)
    }
}

/// Paths per pass the back ends aim for: passes are whole samples of every
/// pixel, as many as fit (at least one).
pub fn pass_spp(pixels: u64, paths: u64) -> u32 {
    (paths / pixels.max(1)).clamp(1, u32::MAX as u64) as u32
}

/// Renders on the chosen back end.
pub fn render(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    device: DeviceChoice,
    progress: Progress,
) -> anyhow::Result<RenderResult> {
    render_progressive(scene, packed, settings, device, progress, &mut RenderAll)
}

/// Renders on the chosen back end, asking `control` after every pass whether
/// to go on.
pub fn render_progressive(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    device: DeviceChoice,
    progress: Progress,
    control: &mut dyn PassControl,
) -> anyhow::Result<RenderResult> {
    settings.validate()?;
    match device {
        DeviceChoice::Cpu => {
            crate::cpu::render::render_progressive(scene, packed, settings, progress, control)
        }
        _ => {
            let mut renderer = crate::gpu::GpuRenderer::new(device)?;
            renderer.render_progressive(scene, packed, settings, progress, control)
        }
    }
}
