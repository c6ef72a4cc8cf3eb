//! One render, on either back end, with what it measured: which back end
//! (`DeviceChoice`), progressive passes with stopping rules (`progressive`),
//! the header of what it holds (`header`).

pub mod auto_device;
pub mod header;
pub mod motion;
pub mod progressive;

pub use crate::film::passes::{PassControl, Progress, RenderAll, RenderResult, pass_spp};
pub use crate::packed::settings::{RenderSettings, Sampler, TextureFilter};

pub use crate::gpu::Schedule;
use crate::gpu::context::VulkanDevice;
use crate::packed::PackedScene;
use crate::scene::Scene;

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
    pub const NAMES: [&'static str; 4] = ["auto", "gpu", "lavapipe", "cpu"];

    pub fn from_name(name: &str) -> Option<DeviceChoice> {
        match name {
            "auto" => Some(DeviceChoice::Auto),
            "gpu" => Some(DeviceChoice::Gpu),
            "lavapipe" => Some(DeviceChoice::Lavapipe),
            "cpu" => Some(DeviceChoice::Cpu),
            _ => None,
        }
    }

    /// The Vulkan device this choice asks for; `None` for the CPU reference.
    pub fn vulkan(self) -> Option<VulkanDevice> {
        match self {
            DeviceChoice::Auto => Some(VulkanDevice::Best),
            DeviceChoice::Gpu => Some(VulkanDevice::Hardware),
            DeviceChoice::Lavapipe => Some(VulkanDevice::Lavapipe),
            DeviceChoice::Cpu => None,
        }
    }
}

/// An opened back end, ready to render any number of times.
pub enum Backend {
    Vulkan(Box<crate::gpu::GpuRenderer>),
    Cpu,
}

impl Backend {
    /// Opens the chosen back end for rendering `scene` with `settings`.
    /// `Auto` takes a GPU when there is one, else the back end (and, for
    /// lavapipe, the schedule unless `schedule` fixes it) measured faster on
    /// this machine (`auto_device`). A Vulkan back end traces with
    /// `schedule`, the wavefront by default. The string says which back end
    /// and why, for the summary.
    pub fn open(
        choice: DeviceChoice,
        schedule: Option<Schedule>,
        scene: &Scene,
        packed: &PackedScene,
        settings: &RenderSettings,
    ) -> anyhow::Result<(Backend, String)> {
        if choice == DeviceChoice::Auto {
            let c = auto_device::choose(scene, packed, settings, schedule)?;
            return Ok((c.backend, c.why));
        }
        match choice.vulkan() {
            None => Ok((Backend::Cpu, "as asked".into())),
            Some(vulkan) => {
                let mut gpu = crate::gpu::GpuRenderer::new(vulkan)?;
                gpu.schedule = schedule.unwrap_or(Schedule::Wavefront);
                let why = format!("as asked, {} schedule", gpu.schedule.name());
                Ok((Backend::Vulkan(Box::new(gpu)), why))
            }
        }
    }

    /// The device's name, as `RenderResult::device_name` gives it.
    pub fn name(&self) -> String {
        match self {
            Backend::Cpu => crate::cpu::render::device_name(),
            Backend::Vulkan(gpu) => gpu.device_name(),
        }
    }

    /// Renders, asking `control` after every pass whether to go on.
    pub fn render_progressive(
        &mut self,
        scene: &Scene,
        packed: &PackedScene,
        settings: &RenderSettings,
        progress: Progress,
        control: &mut dyn PassControl,
    ) -> anyhow::Result<RenderResult> {
        settings.validate()?;
        match self {
            Backend::Cpu => {
                crate::cpu::render::render_progressive(scene, packed, settings, progress, control)
            }
            Backend::Vulkan(gpu) => {
                gpu.render_progressive(scene, packed, settings, progress, control)
            }
        }
    }
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
    let (mut backend, _) = Backend::open(device, None, scene, packed, settings)?;
    backend.render_progressive(scene, packed, settings, progress, control)
}
