//! The Vulkan back end: one file per Vulkan concept, and `wavefront.rs`,
//! the driver that reads like the bounce loop.

pub mod buffer;
pub mod context;
pub mod descriptors;
pub mod limits;
pub mod pipeline;
pub mod pipeline_cache;
pub mod resources;
pub mod specialize;
pub mod split;
pub mod timestamps;
pub mod wavefront;

use crate::film::passes::{PassControl, Progress, RenderAll, RenderResult};
use crate::packed::PackedScene;
use crate::packed::features::KernelFeatures;
use crate::packed::layout::RenderParams;
use crate::packed::settings::RenderSettings;
use crate::scene::Scene;
use ash::vk;
use context::Context;
use context::VulkanDevice;
use limits::DeviceLimits;
use pipeline::Pipelines;
use pipeline_cache::{CacheUse, PipelineCache};
use std::time::{Duration, Instant};
use timestamps::Timestamps;
pub use wavefront::Schedule;
use wavefront::{Wavefront, WavefrontBuffers};

/// Where a Vulkan renderer's start-up time went (speed includes start-up).
#[derive(Clone, Copy, Debug)]
pub struct Startup {
    /// Instance, device and memory allocator.
    pub device: Duration,
    /// Creating the compute pipelines, so far: the driver compiles the
    /// kernels here (and at their first dispatch, as lavapipe does). They
    /// are made at the first render that needs them (each kernel variant
    /// and schedule once), not with the renderer.
    pub pipelines: Duration,
    pub pipeline_cache: CacheUse,
}

pub struct GpuRenderer {
    // Field order is drop order: everything made from the device goes first.
    pipelines: Pipelines,
    pipeline_cache: PipelineCache,
    pub startup: Startup,
    /// Creating and filling the last render's buffers (scene upload).
    pub last_upload_time: Duration,
    /// Bytes the last render uploaded, and whether it kept the buffers of
    /// the render before (a frame of a sequence re-uploads only the arrays
    /// that changed).
    pub last_upload: Upload,
    /// The last render's buffers, kept for the next one.
    kept: Option<WavefrontBuffers>,
    timestamps: Timestamps,
    command_pool: vk::CommandPool,
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
    limits: DeviceLimits,
    /// Render with the all-features kernels instead of specializing them
    /// to the scene (`VKPT_KERNELS=all`; benchmarks and tests compare both).
    pub all_features: bool,
    /// On lavapipe, hand the driver the large kernels specialized ahead by
    /// `spirv-opt` (`specialize.rs`); off for tests that compare both
    /// (`VKPT_SPIRV_OPT=off` turns it off for every renderer). Read when
    /// kernels are compiled: set it before the first render.
    pub specialize_ahead: bool,
    /// Split shading by material where a scene has both kinds
    /// (`KernelFeatures::split_shade`); off for tests that compare both
    /// (`VKPT_SPLIT_SHADE=off` turns it off for every renderer).
    pub split_shade: bool,
    /// How paths are traced (`--schedule`); the wavefront unless chosen.
    pub schedule: Schedule,
    /// Loop iterations a `path_loop` subgroup may spend per dispatch
    /// (`PATH_LOOP_BUDGET`; tests lower it so that paths park often).
    pub loop_budget: u32,
    /// Further lavapipe devices with one thread each, beside this one
    /// (`split`): empty on a GPU, or when lavapipe runs as one device.
    replicas: Vec<GpuRenderer>,
    ctx: Context,
}

impl GpuRenderer {
    pub fn new(choice: VulkanDevice) -> anyhow::Result<GpuRenderer> {
        Self::with_validation(choice, None)
    }

    /// As `new`, with the validation layer forced on or off (`None`: follow
    /// `VKPT_VALIDATION`). Tests turn it on wherever the layer is installed.
    pub fn with_validation(
        choice: VulkanDevice,
        validation: Option<bool>,
    ) -> anyhow::Result<GpuRenderer> {
        let one = Self::open_device(choice, validation)?;
        let devices = split::lavapipe_devices(&one)?;
        Self::with_devices(one, devices, || Self::open_device(choice, validation))
    }

    /// As `with_validation`, as `devices` lavapipe devices that split every
    /// pass (`split`; tests compare one and several). A GPU stays one.
    pub fn with_lavapipe_devices(
        choice: VulkanDevice,
        validation: Option<bool>,
        devices: usize,
    ) -> anyhow::Result<GpuRenderer> {
        let one = Self::open_device(choice, validation)?;
        let devices = if one.is_cpu_device() { devices } else { 1 };
        Self::with_devices(one, devices, || Self::open_device(choice, validation))
    }

    /// `one` and, where `devices` > 1, that many devices in all (`open`
    /// opens each further one).
    fn with_devices(
        mut one: GpuRenderer,
        devices: usize,
        open: impl Fn() -> anyhow::Result<GpuRenderer>,
    ) -> anyhow::Result<GpuRenderer> {
        one.replicas = (1..devices)
            .map(|_| open())
            .collect::<anyhow::Result<_>>()?;
        Ok(one)
    }

    /// One Vulkan device and what renders on it.
    fn open_device(choice: VulkanDevice, validation: Option<bool>) -> anyhow::Result<GpuRenderer> {
        let start = Instant::now();
        let ctx = Context::new(choice, validation)?;
        let device_time = start.elapsed();
        let start = Instant::now();
        let mut pipeline_cache = PipelineCache::open(&ctx)?;
        let pipelines = match Pipelines::new(&ctx) {
            Ok(p) => p,
            Err(e) => {
                pipeline_cache.destroy(&ctx);
                return Err(e);
            }
        };
        let startup = Startup {
            device: device_time,
            pipelines: start.elapsed(),
            pipeline_cache: pipeline_cache.used,
        };
        let timestamps = Timestamps::new(&ctx)?;
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid device and create info.
        let command_pool = unsafe { ctx.device.create_command_pool(&info, None) }?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool is valid.
        let cmd = unsafe { ctx.device.allocate_command_buffers(&alloc) }?[0];
        // SAFETY: valid device.
        let fence = unsafe {
            ctx.device
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }?;
        let limits = DeviceLimits::query(&ctx);
        Ok(GpuRenderer {
            limits,
            all_features: std::env::var("VKPT_KERNELS").is_ok_and(|v| v == "all"),
            specialize_ahead: true,
            split_shade: std::env::var("VKPT_SPLIT_SHADE").map_or(true, |v| v != "off"),
            schedule: Schedule::Wavefront,
            loop_budget: crate::constants::PATH_LOOP_BUDGET,
            pipelines,
            pipeline_cache,
            startup,
            last_upload_time: Duration::ZERO,
            last_upload: Upload::default(),
            kept: None,
            timestamps,
            command_pool,
            cmd,
            fence,
            replicas: Vec::new(),
            ctx,
        })
    }

    pub fn device_name(&self) -> String {
        match self.replicas.len() {
            0 => self.ctx.device_name(),
            n => format!(
                "{}, {} devices of one thread each",
                self.ctx.device_name(),
                n + 1
            ),
        }
    }

    /// How many Vulkan devices render (more than one only for lavapipe:
    /// `split`).
    pub fn device_count(&self) -> usize {
        1 + self.replicas.len()
    }

    /// Whether this device can run the per-path loop schedule (it needs
    /// subgroup arithmetic).
    /// The kernels compiled for the current variant, by name (none before
    /// the first render).
    pub fn compiled_kernels(&self) -> Vec<&'static str> {
        self.pipelines.kernels.iter().map(|k| k.name).collect()
    }

    /// Where the current variant's kernel `name` came from: specialized
    /// ahead (`specialize.rs`) or not, and why not; `None` before it is
    /// compiled.
    pub fn kernel_module(&self, name: &str) -> Option<&specialize::Specialized> {
        self.pipelines
            .kernels
            .iter()
            .find(|k| k.name == name)
            .map(|k| &k.specialized)
    }

    pub fn supports_path_loop(&self) -> bool {
        self.ctx.subgroup_arithmetic
    }

    /// A Vulkan driver running on the CPU (lavapipe), not a GPU.
    pub fn is_cpu_device(&self) -> bool {
        self.ctx.is_cpu_device()
    }

    /// The limits every render's buffers are checked against. Tests lower
    /// them to see a scene refused without building a huge one.
    pub fn limits_mut(&mut self) -> &mut DeviceLimits {
        &mut self.limits
    }

    /// Path slots in flight: as many as the device's limits and a memory
    /// budget allow, independent of image size and spp (capped at 1024 per
    /// pixel so `accumulate` stays far below lavapipe's loop limit).
    fn pool_size(&self, pixels: u64) -> u32 {
        // 16 bytes per slot in each path-state buffer, read as one texel.
        let by_binding =
            (self.limits.max_storage_buffer_range / 16).min(self.limits.max_texel_buffer_elements);
        let by_dispatch = self.ctx.properties.limits.max_compute_work_group_count[0] as u64 * 64;
        let budget: u64 = match std::env::var("VKPT_POOL_SIZE")
            .ok()
            .and_then(|v| v.parse().ok())
        {
            Some(n) => n,
            None if self.ctx.is_cpu_device() => 1 << 18,
            None => 1 << 20,
        };
        budget
            .min(by_binding)
            .min(by_dispatch)
            .min(pixels * 1024)
            .max(1) as u32
    }

    pub fn render(
        &mut self,
        scene: &Scene,
        packed: &PackedScene,
        settings: &RenderSettings,
        progress: Progress,
    ) -> anyhow::Result<RenderResult> {
        self.render_progressive(scene, packed, settings, progress, &mut RenderAll)
    }

    /// As `render`, asking `control` after every pass whether to go on.
    pub fn render_progressive(
        &mut self,
        scene: &Scene,
        packed: &PackedScene,
        settings: &RenderSettings,
        progress: Progress,
        control: &mut dyn PassControl,
    ) -> anyhow::Result<RenderResult> {
        if !self.replicas.is_empty() {
            return self.render_split(scene, packed, settings, progress, control);
        }
        self.render_on_this_device(scene, packed, settings, progress, control)
    }

    /// Compiles the kernels a render of `settings` needs on this device
    /// (none when an earlier render compiled them); returns the render's
    /// parameters and the kernels' variant.
    fn prepare_kernels(
        &mut self,
        scene: &Scene,
        packed: &PackedScene,
        settings: &RenderSettings,
    ) -> anyhow::Result<(RenderParams, KernelFeatures)> {
        anyhow::ensure!(
            self.schedule == Schedule::Wavefront || self.supports_path_loop(),
            "the per-path loop schedule needs subgroup arithmetic, which {} lacks; use \
             --schedule wavefront",
            self.device_name()
        );
        let pool_size = self.pool_size(settings.pixel_count());
        let params = packed.render_params(scene, settings, pool_size)?;
        let features = if self.all_features {
            KernelFeatures::ALL
        } else {
            let of = KernelFeatures::of(packed, &params);
            KernelFeatures {
                split_shade: of.split_shade && self.split_shade,
                ..of
            }
        };
        let features = KernelFeatures {
            scene_view_shift: resources::scene_view_shift(packed, &params, &self.limits),
            ..features
        };
        let path_loop = self.schedule == Schedule::PathLoop;
        self.startup.pipelines += self.pipelines.prepare(
            &self.ctx,
            self.pipeline_cache.cache,
            features,
            path_loop,
            self.specialize_ahead,
        )?;
        Ok((params, features))
    }

    /// `render_progressive` on this renderer's own device alone.
    fn render_on_this_device(
        &mut self,
        scene: &Scene,
        packed: &PackedScene,
        settings: &RenderSettings,
        progress: Progress,
        control: &mut dyn PassControl,
    ) -> anyhow::Result<RenderResult> {
        let (params, features) = self.prepare_kernels(scene, packed, settings)?;
        let upload_start = Instant::now();
        let mut buffers = self.buffers_for(packed, &params)?;
        self.last_upload_time = upload_start.elapsed();
        self.timestamps.totals.clear();
        let start = Instant::now();
        let result = Wavefront {
            ctx: &self.ctx,
            pipelines: &self.pipelines,
            timestamps: &mut self.timestamps,
            cmd: self.cmd,
            fence: self.fence,
            buffers: &mut buffers,
            schedule: self.schedule,
            loop_budget: self.loop_budget,
        }
        .render(&params, settings.spp, progress, control);
        let render_time = start.elapsed();
        // SAFETY: waiting for idle before the buffers are reused or freed.
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
        }
        if result.is_ok() {
            self.kept = Some(buffers);
        } else {
            buffers.destroy(&self.ctx);
        }
        let (film, spp, counts) = result?;
        Ok(RenderResult {
            film,
            spp,
            device_name: self.device_name(),
            render_time,
            extension_rays: counts.extension_rays,
            shadow_rays: counts.shadow_rays,
            traversal_overflows: counts.traversal_overflows,
            nonfinite_samples: counts.nonfinite_samples,
            paths_parked: counts.paths_parked,
            kernel_variant: Some(match self.kernel_module("shade") {
                Some(m) if self.is_cpu_device() => {
                    format!("{} ({})", features.describe(), m.describe())
                }
                _ => features.describe(),
            }),
            kernel_times: self
                .timestamps
                .totals
                .iter()
                .map(|(n, d)| (n.to_string(), *d))
                .collect(),
        })
    }
}

/// What a render uploaded before it started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Upload {
    pub bytes: u64,
    /// The buffers of the render before were kept (same sizes).
    pub reused: bool,
}

impl GpuRenderer {
    /// The buffers for a render: those of the last render with only the
    /// changed arrays re-uploaded when every size still fits, else new ones.
    fn buffers_for(
        &mut self,
        packed: &PackedScene,
        params: &RenderParams,
    ) -> anyhow::Result<WavefrontBuffers> {
        if let Some(mut kept) = self.kept.take() {
            match kept.update(&self.ctx, packed, params, &self.limits) {
                Ok(Some(bytes)) => {
                    self.last_upload = Upload {
                        bytes,
                        reused: true,
                    };
                    return Ok(kept);
                }
                Ok(None) => kept.destroy(&self.ctx),
                Err(e) => {
                    kept.destroy(&self.ctx);
                    return Err(e);
                }
            }
        }
        let buffers =
            WavefrontBuffers::new(&self.ctx, &self.pipelines, packed, params, &self.limits)?;
        self.last_upload = Upload {
            bytes: buffers.uploaded_bytes(),
            reused: false,
        };
        Ok(buffers)
    }
}

impl Drop for GpuRenderer {
    fn drop(&mut self) {
        // SAFETY: idle device; these objects were made from it.
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
        }
        if let Some(mut kept) = self.kept.take() {
            kept.destroy(&self.ctx);
        }
        // SAFETY: idle device; these objects were made from it.
        unsafe {
            self.ctx.device.destroy_fence(self.fence, None);
            self.ctx
                .device
                .destroy_command_pool(self.command_pool, None);
        }
        self.timestamps.destroy(&self.ctx);
        self.pipelines.destroy(&self.ctx);
        // Saved last: a driver that compiles at first dispatch may only now
        // have put the kernels into the cache.
        self.pipeline_cache.save(&self.ctx);
        self.pipeline_cache.destroy(&self.ctx);
    }
}
