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

/// Renders on the chosen back end.
pub fn render(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    device: DeviceChoice,
    progress: Progress,
) -> anyhow::Result<RenderResult> {
    settings.validate()?;
    match device {
        DeviceChoice::Cpu => crate::cpu::render::render(scene, packed, settings, progress),
        _ => {
            let mut renderer = crate::gpu::GpuRenderer::new(device)?;
            renderer.render(scene, packed, settings, progress)
        }
    }
}
