//! The wavefront driver: per chunk of pixel-samples, `generate`, then per
//! bounce `ray_queue_args`, `extend`, `shade`, `shadow_queue_args`, `shadow`,
//! and finally `accumulate`. With shading split by material
//! (`KernelFeatures::split_shade`), `shade_queue_args`, `shade_basic` and
//! `shade` take the two shading queues extend filled. Queue sizes live on the GPU; the next kernel is
//! launched with vkCmdDispatchIndirect from arguments a one-invocation kernel
//! writes. The host only reads the ray count after a batch of bounces, to
//! learn whether the chunk's paths have all ended.
//!
//! Under the per-path loop schedule (`Schedule::PathLoop`) `path_loop`
//! replaces `generate` and traces the chunk's paths to their end; the few it
//! parks (lavapipe's loop limit, `path_loop.comp`) are in ray queue 0, and
//! the same bounce loop finishes them.

use super::buffer::Buffer;
use super::context::Context;
use super::limits::DeviceLimits;
use super::pipeline::Pipelines;
use super::resources::Resources;
use super::timestamps::Timestamps;
use crate::constants::*;
use crate::film::Film;
use crate::film::passes::{PassControl, Progress, pass_spp};
use crate::packed::PackedScene;
use crate::packed::bindings::{self, row_of};
use crate::packed::layout::{AovPixel, FilmPixel, PushConstants, RenderParams};
use anyhow::Context as _;
use ash::vk;
use bytemuck::{Pod, bytes_of, cast_slice};

/// Bounces recorded per submission before the host checks the ray count.
const BOUNCES_PER_BATCH: u32 = 8;

/// Invocations of one `path_loop` dispatch: enough workgroups to share among
/// the cores, few enough that each invocation traces many paths.
const PATH_LOOP_INVOCATIONS: u32 = 8192;

/// How a chunk's paths are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Schedule {
    /// A kernel per stage of a bounce, paths in queues between them: keeps
    /// a GPU's SIMD lanes full.
    Wavefront,
    /// One loop per path in one kernel, the path in registers (as Cycles X
    /// on CPUs); measured faster on some scenes under lavapipe.
    PathLoop,
}

impl Schedule {
    pub const NAMES: [&'static str; 2] = ["wavefront", "loop"];

    pub fn from_name(name: &str) -> Option<Schedule> {
        match name {
            "wavefront" => Some(Schedule::Wavefront),
            "loop" => Some(Schedule::PathLoop),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Schedule::Wavefront => "wavefront",
            Schedule::PathLoop => "loop",
        }
    }
}

/// The bindings the host touches between kernels (checked names).
const COUNTERS: &str = row_of("counters").name;
const DISPATCH_ARGS: &str = row_of("dispatch_args").name;
const FILM: &str = row_of("film").name;
const FILM_AOV: &str = row_of("film_aov").name;

/// The device buffers of one render: every binding's, and a host-visible
/// copy of the counters.
pub struct WavefrontBuffers {
    bound: Resources,
    counters_readback: Buffer,
}

impl WavefrontBuffers {
    pub fn new(
        ctx: &Context,
        pipelines: &Pipelines,
        packed: &PackedScene,
        params: &RenderParams,
        limits: &DeviceLimits,
    ) -> anyhow::Result<WavefrontBuffers> {
        let mut bound = Resources::new(
            ctx,
            pipelines.set_layout,
            bindings::Schedule::Wavefront,
            packed,
            params,
            limits,
        )?;
        match Buffer::readback(ctx, "counters (readback)", 4 * COUNTER_COUNT as u64) {
            Ok(counters_readback) => Ok(WavefrontBuffers {
                bound,
                counters_readback,
            }),
            Err(e) => {
                bound.destroy(ctx);
                Err(e)
            }
        }
    }

    /// Bytes of scene data uploaded when these buffers were made.
    pub fn uploaded_bytes(&self) -> u64 {
        self.bound.uploaded
    }

    /// Refills the buffers for another render of the same sizes, uploading
    /// only what changed: the bytes uploaded, or `None` when sizes differ.
    pub fn update(
        &mut self,
        ctx: &Context,
        packed: &PackedScene,
        params: &RenderParams,
        limits: &DeviceLimits,
    ) -> anyhow::Result<Option<u64>> {
        self.bound
            .update(ctx, bindings::Schedule::Wavefront, packed, params, limits)
    }

    pub fn destroy(&mut self, ctx: &Context) {
        self.bound.destroy(ctx);
        self.counters_readback.destroy(ctx);
    }
}

/// Records and submits the wavefront kernels.
pub struct Wavefront<'a> {
    pub ctx: &'a Context,
    pub pipelines: &'a Pipelines,
    pub timestamps: &'a mut Timestamps,
    pub cmd: vk::CommandBuffer,
    pub fence: vk::Fence,
    pub buffers: &'a mut WavefrontBuffers,
    pub schedule: Schedule,
    /// `PushConstants::loop_budget` for `path_loop`.
    pub loop_budget: u32,
}

/// Totals read from the counters buffer at the end of a render.
pub struct WavefrontCounts {
    pub extension_rays: u64,
    pub shadow_rays: u64,
    pub traversal_overflows: u64,
    pub nonfinite_samples: u64,
    /// Paths `path_loop` parked for the wavefront kernels to finish.
    pub paths_parked: u64,
}

impl Wavefront<'_> {
    fn begin(&mut self) -> anyhow::Result<()> {
        let d = &self.ctx.device;
        let info = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the previous submission of cmd has completed (we waited on the fence).
        unsafe {
            d.reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())?;
            d.begin_command_buffer(self.cmd, &info)?;
            d.cmd_bind_descriptor_sets(
                self.cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.pipelines.layout,
                0,
                &[self.buffers.bound.set],
                &[],
            );
        }
        self.timestamps.begin(self.ctx, self.cmd);
        Ok(())
    }

    /// Copies the counters for the host, ends, submits and waits.
    fn submit_and_wait(&mut self) -> anyhow::Result<[u32; COUNTER_COUNT as usize]> {
        let d = &self.ctx.device;
        let counters = self.buffers.bound.buffer(COUNTERS);
        let region = vk::BufferCopy::default().size(counters.size.min(4 * COUNTER_COUNT as u64));
        // SAFETY: cmd is recording; buffers are alive.
        unsafe {
            self.barrier(
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            );
            d.cmd_copy_buffer(
                self.cmd,
                counters.raw,
                self.buffers.counters_readback.raw,
                &[region],
            );
            let to_host = vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::HOST_READ);
            d.cmd_pipeline_barrier(
                self.cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &[to_host],
                &[],
                &[],
            );
            d.end_command_buffer(self.cmd)?;
            let cmds = [self.cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            d.reset_fences(&[self.fence])?;
            d.queue_submit(self.ctx.queue, &submit, self.fence)
                .context("submitting wavefront kernels")?;
            d.wait_for_fences(&[self.fence], true, u64::MAX)
                .context("waiting for wavefront kernels")?;
        }
        self.timestamps.collect(self.ctx)?;
        let bytes = self
            .buffers
            .counters_readback
            .mapped_bytes()
            .context("counters readback is not host-visible")?;
        let mut out = [0u32; COUNTER_COUNT as usize];
        out.copy_from_slice(cast_slice(&bytes[..4 * COUNTER_COUNT as usize]));
        Ok(out)
    }

    /// Makes all earlier compute and transfer writes visible to what follows.
    fn barrier(&self, dst_stage: vk::PipelineStageFlags, dst_access: vk::AccessFlags) {
        let b = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(dst_access);
        // SAFETY: cmd is recording.
        unsafe {
            self.ctx.device.cmd_pipeline_barrier(
                self.cmd,
                vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                dst_stage,
                vk::DependencyFlags::empty(),
                &[b],
                &[],
                &[],
            )
        };
    }

    fn kernel_barrier(&self) {
        self.barrier(
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::DRAW_INDIRECT,
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::INDIRECT_COMMAND_READ,
        );
    }

    fn bind(&self, name: &str, pc: &PushConstants) -> u32 {
        let kernel = self.pipelines.kernel(name);
        // SAFETY: cmd is recording; the pipeline uses the bound layout.
        unsafe {
            self.ctx.device.cmd_bind_pipeline(
                self.cmd,
                vk::PipelineBindPoint::COMPUTE,
                kernel.pipeline,
            );
            self.ctx.device.cmd_push_constants(
                self.cmd,
                self.pipelines.layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytes_of(pc),
            );
        }
        kernel.local_size_x
    }

    /// Dispatches `name` over `items` invocations.
    fn dispatch(&mut self, name: &'static str, pc: &PushConstants, items: u32) {
        let local = self.bind(name, pc);
        // SAFETY: cmd is recording with a bound compute pipeline.
        unsafe {
            self.ctx
                .device
                .cmd_dispatch(self.cmd, items.div_ceil(local), 1, 1)
        };
        self.timestamps.mark(self.ctx, self.cmd, name);
        self.kernel_barrier();
    }

    /// Dispatches `name` with workgroup counts read from `dispatch_args`.
    fn dispatch_indirect(&mut self, name: &'static str, pc: &PushConstants, args: usize) {
        self.bind(name, pc);
        let buffer = self.buffers.bound.buffer(DISPATCH_ARGS).raw;
        // SAFETY: args * 12 is inside the 48-byte argument buffer.
        unsafe {
            self.ctx
                .device
                .cmd_dispatch_indirect(self.cmd, buffer, (args * 12) as u64)
        };
        self.timestamps.mark(self.ctx, self.cmd, name);
        self.kernel_barrier();
    }

    fn record_bounce(&mut self, chunk: &PushConstants, bounce: u32) {
        let pc = PushConstants { bounce, ..*chunk };
        self.dispatch("ray_queue_args", &pc, 1);
        self.dispatch_indirect("extend", &pc, 0);
        if self.pipelines.features.split_shade {
            // extend sorted the hits by material: a kernel per queue.
            self.dispatch("shade_queue_args", &pc, 1);
            self.dispatch_indirect("shade_basic", &pc, 2);
            self.dispatch_indirect("shade", &pc, 3);
        } else {
            self.dispatch_indirect("shade", &pc, 0);
        }
        self.dispatch("shadow_queue_args", &pc, 1);
        self.dispatch_indirect("shadow", &pc, 1);
    }

    /// Sets counter `index` to `value` before the kernels that follow.
    fn set_counter(&mut self, index: u32, value: u32) {
        let counters = self.buffers.bound.buffer(COUNTERS).raw;
        // SAFETY: cmd is recording; index < COUNTER_COUNT is inside the buffer.
        unsafe {
            self.ctx
                .device
                .cmd_fill_buffer(self.cmd, counters, 4 * index as u64, 4, value)
        };
    }

    /// Traces the chunk with `path_loop`, submitting until every path slot
    /// was taken, and returns how many paths it parked in ray queue 0. The
    /// command buffer is left submitted. `None`: the loop budget does not
    /// cover one bounce of this scene (thousands of spherical lights), and
    /// no slot was touched: the wavefront must trace the chunk.
    fn trace_path_loop(&mut self, chunk: &PushConstants) -> anyhow::Result<Option<u32>> {
        self.set_counter(COUNTER_RAYS_0, 0);
        self.set_counter(COUNTER_NEXT_PATH, 0);
        self.kernel_barrier();
        let pc = PushConstants {
            loop_budget: self.loop_budget,
            ..*chunk
        };
        loop {
            self.dispatch("path_loop", &pc, PATH_LOOP_INVOCATIONS.min(chunk.count));
            let counters = self.submit_and_wait()?;
            let taken = counters[COUNTER_NEXT_PATH as usize];
            if taken == 0 {
                // Every dispatch starts with the whole budget, so only the
                // first can fail to take a path.
                return Ok(None);
            }
            if taken >= chunk.count {
                return Ok(Some(counters[COUNTER_RAYS_0 as usize]));
            }
            self.begin()?;
        }
    }

    fn read_film(&mut self, params: &RenderParams) -> anyhow::Result<Film> {
        let pixels = params.film_pixels();
        let bytes = self
            .buffers
            .bound
            .buffer_mut(FILM)
            .read(self.ctx, (pixels * 32) as usize)?;
        let aov = if params.aov != 0 {
            let bytes = self
                .buffers
                .bound
                .buffer_mut(FILM_AOV)
                .read(self.ctx, (pixels * 48) as usize)?;
            pod_vec::<AovPixel>(&bytes)
        } else {
            Vec::new()
        };
        Ok(Film {
            width: params.region_width,
            height: params.region_height,
            pixels: pod_vec::<FilmPixel>(&bytes),
            aov,
        })
    }

    /// Renders up to `spp` samples of every pixel in passes of `pass_spp`
    /// (`PassControl`) and returns the film with its sample count. Chunks never
    /// straddle a pass boundary, so at a stop every pixel has the same count.
    pub fn render(
        &mut self,
        params: &RenderParams,
        spp: u32,
        progress: Progress,
        control: &mut dyn PassControl,
    ) -> anyhow::Result<(Film, u32, WavefrontCounts)> {
        // Chunks walk the film (the region), sample after sample.
        let pixels = params.film_pixels();
        let total = pixels * spp as u64;
        // Tracing starts now (kernels compiled, scene uploaded).
        progress(0, total);
        let pool = params.pool_size as u64;
        let pass = pass_spp(pixels, pool) as u64;
        let depth_limit = params.max_depth.min(MAX_BOUNCES_HARD);

        self.begin()?;
        // SAFETY: cmd is recording; the buffers are alive.
        unsafe {
            let d = &self.ctx.device;
            d.cmd_fill_buffer(
                self.cmd,
                self.buffers.bound.buffer(FILM).raw,
                0,
                vk::WHOLE_SIZE,
                0,
            );
            d.cmd_fill_buffer(
                self.cmd,
                self.buffers.bound.buffer(FILM_AOV).raw,
                0,
                vk::WHOLE_SIZE,
                0,
            );
            d.cmd_fill_buffer(
                self.cmd,
                self.buffers.bound.buffer(COUNTERS).raw,
                0,
                vk::WHOLE_SIZE,
                0,
            );
        }
        self.kernel_barrier();

        let mut pending_accumulate: Option<PushConstants> = None;
        let mut done = 0u64;
        let mut paths_parked = 0u64;
        while done < total {
            let pass_end = ((done / pixels / pass + 1) * pass * pixels).min(total);
            let chunk = PushConstants {
                pixel_start: (done % pixels) as u32,
                sample_start: (done / pixels) as u32,
                count: (pass_end - done).min(pool) as u32,
                bounce: 0,
                loop_budget: 0,
            };
            if let Some(previous) = pending_accumulate.take() {
                self.dispatch("accumulate", &previous, pixels as u32);
            }
            let mut parked = None;
            match self.schedule {
                Schedule::Wavefront => self.dispatch("generate", &chunk, chunk.count),
                Schedule::PathLoop => match self.trace_path_loop(&chunk)? {
                    None => {
                        self.begin()?;
                        self.dispatch("generate", &chunk, chunk.count);
                    }
                    Some(n) => {
                        paths_parked += n as u64;
                        parked = Some(n);
                        if n > 0 {
                            self.begin()?;
                        } else {
                            pending_accumulate = Some(chunk);
                        }
                    }
                },
            }
            let mut bounce = 0;
            while parked != Some(0) {
                let end = (bounce + BOUNCES_PER_BATCH).min(depth_limit);
                for b in bounce..end {
                    self.record_bounce(&chunk, b);
                }
                bounce = end;
                if bounce == depth_limit {
                    self.dispatch("accumulate", &chunk, pixels as u32);
                    self.submit_and_wait()?;
                    break;
                }
                let counters = self.submit_and_wait()?;
                if counters[(COUNTER_RAYS_0 + (bounce & 1)) as usize] == 0 {
                    pending_accumulate = Some(chunk);
                    break;
                }
                self.begin()?;
            }
            done += chunk.count as u64;
            progress(done, total);
            self.begin()?;
            if done == pass_end && done < total {
                let mut fetch = || -> anyhow::Result<Film> {
                    if let Some(previous) = pending_accumulate.take() {
                        self.dispatch("accumulate", &previous, pixels as u32);
                    }
                    self.submit_and_wait()?;
                    let film = self.read_film(params);
                    self.begin()?;
                    film
                };
                if !control.after_pass((done / pixels) as u32, &mut fetch)? {
                    break;
                }
            }
        }
        if let Some(previous) = pending_accumulate.take() {
            self.dispatch("accumulate", &previous, pixels as u32);
        }
        let counters = self.submit_and_wait()?;
        let film = self.read_film(params)?;
        let wide =
            |lo: u32, hi: u32| counters[lo as usize] as u64 | (counters[hi as usize] as u64) << 32;
        Ok((
            film,
            (done / pixels) as u32,
            WavefrontCounts {
                extension_rays: wide(COUNTER_EXTENSION_RAYS_LO, COUNTER_EXTENSION_RAYS_HI),
                shadow_rays: wide(COUNTER_SHADOW_RAYS_LO, COUNTER_SHADOW_RAYS_HI),
                traversal_overflows: counters[COUNTER_BVH_OVERFLOW as usize] as u64,
                nonfinite_samples: counters[COUNTER_NONFINITE as usize] as u64,
                paths_parked,
            },
        ))
    }
}

fn pod_vec<T: Pod>(bytes: &[u8]) -> Vec<T> {
    bytes
        .chunks_exact(std::mem::size_of::<T>())
        .map(bytemuck::pod_read_unaligned)
        .collect()
}
