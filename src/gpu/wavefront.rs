//! The wavefront driver: per chunk of pixel-samples, `generate`, then per
//! bounce `ray_queue_args`, `extend`, `shade`, `shadow_queue_args`, `shadow`,
//! and finally `accumulate`. Queue sizes live on the GPU; the next kernel is
//! launched with vkCmdDispatchIndirect from arguments a one-invocation kernel
//! writes. The host only reads the ray count after a batch of bounces, to
//! learn whether the chunk's paths have all ended.

use super::buffer::Buffer;
use super::context::Context;
use super::limits::DeviceLimits;
use super::pipeline::{
    FIRST_LIGHT_BINDING, LAST_BUFFER_BINDING, LAST_LIGHT_BINDING, Pipelines, TEXEL_VIEWS,
    binding_type,
};
use super::textures::TextureBuffers;
use super::timestamps::Timestamps;
use crate::constants::*;
use crate::film::Film;
use crate::film::passes::{PassControl, Progress, pass_spp};
use crate::packed::PackedScene;
use crate::packed::layout::{FilmPixel, PushConstants, RenderParams};
use anyhow::Context as _;
use ash::vk;
use bytemuck::{Pod, bytes_of, cast_slice};

/// Bounces recorded per submission before the host checks the ray count.
const BOUNCES_PER_BATCH: u32 = 8;

/// The device buffers of one render, indexed by binding number.
pub struct WavefrontBuffers {
    buffers: Vec<Buffer>,
    /// Light sampling's buffers, bindings FIRST_LIGHT_BINDING..=LAST_LIGHT_BINDING.
    light_buffers: Vec<Buffer>,
    /// Texel views of scene buffers, for `TEXEL_VIEWS`.
    views: Vec<vk::BufferView>,
    counters_readback: Buffer,
    descriptor_pool: vk::DescriptorPool,
    descriptor_set: vk::DescriptorSet,
    textures: Option<TextureBuffers>,
}

const PARAMS: usize = 0;
const COUNTERS: usize = 15;
const DISPATCH_ARGS: usize = 16;
const FILM: usize = 17;

impl WavefrontBuffers {
    pub fn new(
        ctx: &Context,
        pipelines: &Pipelines,
        packed: &PackedScene,
        params: &RenderParams,
        limits: &DeviceLimits,
    ) -> anyhow::Result<WavefrontBuffers> {
        let pool = params.pool_size as u64;
        let pixels = params.width as u64 * params.height as u64;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let sizes: [(&str, u64); (LAST_BUFFER_BINDING + 1) as usize] = [
            ("params", std::mem::size_of::<RenderParams>() as u64),
            (
                "bvh_nodes",
                std::mem::size_of_val(packed.nodes.as_slice()) as u64,
            ),
            (
                "tri_verts",
                std::mem::size_of_val(packed.tri_verts.as_slice()) as u64,
            ),
            (
                "tri_shading",
                std::mem::size_of_val(packed.tri_shading.as_slice()) as u64,
            ),
            (
                "materials",
                std::mem::size_of_val(packed.materials.as_slice()) as u64,
            ),
            (
                "emitters",
                std::mem::size_of_val(packed.emitters.as_slice()) as u64,
            ),
            ("path_origin", 16 * pool),
            ("path_direction", 16 * pool),
            ("path_hit", 16 * pool),
            ("path_throughput", 16 * pool),
            ("path_radiance", 16 * pool),
            ("ray_queue", 2 * 4 * pool),
            ("shadow_origin", 16 * pool),
            ("shadow_direction", 16 * pool),
            ("shadow_contribution", 16 * pool),
            ("counters", 4 * COUNTER_COUNT as u64),
            ("dispatch_args", 4 * 6),
            ("film", std::mem::size_of::<FilmPixel>() as u64 * pixels),
        ];
        let light_data: [(&str, &[u8]); (LAST_LIGHT_BINDING - FIRST_LIGHT_BINDING + 1) as usize] = [
            ("light_params", bytes_of(&packed.light_params)),
            ("lights", cast_slice(&packed.lights)),
            ("env_cdf", cast_slice(&packed.env_cdf)),
            ("env_radiance", cast_slice(&packed.env_radiance)),
        ];
        let checked: Vec<(&str, u64, bool)> = sizes
            .iter()
            .enumerate()
            .skip(1) // params is a small uniform buffer
            .map(|(binding, &(name, size))| {
                let viewed = TEXEL_VIEWS.iter().any(|&(_, b)| b as usize == binding);
                (name, size, viewed)
            })
            .chain(
                light_data
                    .iter()
                    .map(|(name, data)| (*name, data.len() as u64, false)),
            )
            .collect();
        limits.check(&checked)?;

        let mut buffers = Vec::with_capacity(sizes.len());
        let mut light_buffers = Vec::with_capacity(light_data.len());
        let mut make = || -> anyhow::Result<()> {
            for (binding, (name, size)) in sizes.iter().enumerate() {
                let viewed = TEXEL_VIEWS.iter().any(|&(_, b)| b as usize == binding);
                let usage = match binding {
                    PARAMS => vk::BufferUsageFlags::UNIFORM_BUFFER,
                    DISPATCH_ARGS => storage | vk::BufferUsageFlags::INDIRECT_BUFFER,
                    _ if viewed => storage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
                    _ => storage,
                };
                buffers.push(Buffer::gpu_only(ctx, name, *size, usage)?);
            }
            for (name, data) in &light_data {
                light_buffers.push(Buffer::gpu_only(ctx, name, data.len() as u64, storage)?);
            }
            Ok(())
        };
        let made = make();
        let counters_readback =
            Buffer::readback(ctx, "counters (readback)", 4 * COUNTER_COUNT as u64);
        let (counters_readback, ()) = match (counters_readback, made) {
            (Ok(c), Ok(())) => (c, ()),
            (c, m) => {
                if let Ok(mut c) = c {
                    c.destroy(ctx);
                }
                for mut b in buffers.into_iter().chain(light_buffers) {
                    b.destroy(ctx);
                }
                return Err(m
                    .err()
                    .unwrap_or_else(|| anyhow::anyhow!("allocating a readback buffer failed")));
            }
        };

        let pool_sizes = [
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(1),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(LAST_BUFFER_BINDING + light_data.len() as u32 + 2), // + texture table, tri_texcoords
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::UNIFORM_TEXEL_BUFFER)
                .descriptor_count(TEXEL_VIEWS.len() as u32 + 1), // + texture_texels
        ];
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&pool_sizes);
        // SAFETY: valid device and create info.
        let descriptor_pool = unsafe { ctx.device.create_descriptor_pool(&info, None) }?;
        let layouts = [pipelines.set_layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(descriptor_pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for exactly this set.
        let descriptor_set = unsafe { ctx.device.allocate_descriptor_sets(&info) }?[0];

        let mut views = Vec::new();
        for &(_, viewed) in &TEXEL_VIEWS {
            let info = vk::BufferViewCreateInfo::default()
                .buffer(buffers[viewed as usize].raw)
                .format(vk::Format::R32G32B32A32_UINT)
                .range(vk::WHOLE_SIZE);
            // SAFETY: the buffer was created with UNIFORM_TEXEL_BUFFER usage.
            views.push(unsafe { ctx.device.create_buffer_view(&info, None) }?);
        }
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> =
            buffers.iter().map(Buffer::descriptor_info).collect();
        let mut writes: Vec<vk::WriteDescriptorSet> = infos
            .iter()
            .enumerate()
            .map(|(binding, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(descriptor_set)
                    .dst_binding(binding as u32)
                    .descriptor_type(binding_type(binding as u32))
                    .buffer_info(info)
            })
            .collect();
        for (view, &(binding, _)) in views.iter().zip(&TEXEL_VIEWS) {
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(descriptor_set)
                    .dst_binding(binding)
                    .descriptor_type(binding_type(binding))
                    .texel_buffer_view(std::slice::from_ref(view)),
            );
        }
        let light_infos: Vec<[vk::DescriptorBufferInfo; 1]> =
            light_buffers.iter().map(Buffer::descriptor_info).collect();
        for (k, info) in light_infos.iter().enumerate() {
            let binding = FIRST_LIGHT_BINDING + k as u32;
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(descriptor_set)
                    .dst_binding(binding)
                    .descriptor_type(binding_type(binding))
                    .buffer_info(info),
            );
        }
        // SAFETY: every buffer and view is alive and bound to memory.
        unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };

        let mut wb = WavefrontBuffers {
            buffers,
            light_buffers,
            views,
            counters_readback,
            descriptor_pool,
            descriptor_set,
            textures: None,
        };
        match TextureBuffers::new(ctx, packed, descriptor_set) {
            Ok(t) => wb.textures = Some(t),
            Err(e) => {
                wb.destroy(ctx);
                return Err(e);
            }
        }
        let uploads: [(usize, &[u8]); 6] = [
            (PARAMS, bytes_of(params)),
            (1, cast_slice(&packed.nodes)),
            (2, cast_slice(&packed.tri_verts)),
            (3, cast_slice(&packed.tri_shading)),
            (4, cast_slice(&packed.materials)),
            (5, cast_slice(&packed.emitters)),
        ];
        for (binding, data) in uploads {
            if let Err(e) = wb.buffers[binding].upload(ctx, data) {
                wb.destroy(ctx);
                return Err(e);
            }
        }
        for (k, (_, data)) in light_data.iter().enumerate() {
            if let Err(e) = wb.light_buffers[k].upload(ctx, data) {
                wb.destroy(ctx);
                return Err(e);
            }
        }
        Ok(wb)
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for view in self.views.drain(..) {
            // SAFETY: the device is idle.
            unsafe { ctx.device.destroy_buffer_view(view, None) };
        }
        for b in self.buffers.iter_mut().chain(&mut self.light_buffers) {
            b.destroy(ctx);
        }
        self.counters_readback.destroy(ctx);
        if let Some(t) = &mut self.textures {
            t.destroy(ctx);
        }
        // SAFETY: the device is idle; destroying the pool frees the set.
        unsafe {
            ctx.device
                .destroy_descriptor_pool(self.descriptor_pool, None)
        };
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
}

/// Totals read from the counters buffer at the end of a render.
pub struct WavefrontCounts {
    pub extension_rays: u64,
    pub shadow_rays: u64,
    pub traversal_overflows: u64,
    pub nonfinite_samples: u64,
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
                &[self.buffers.descriptor_set],
                &[],
            );
        }
        self.timestamps.begin(self.ctx, self.cmd);
        Ok(())
    }

    /// Copies the counters for the host, ends, submits and waits.
    fn submit_and_wait(&mut self) -> anyhow::Result<[u32; COUNTER_COUNT as usize]> {
        let d = &self.ctx.device;
        let counters = &self.buffers.buffers[COUNTERS];
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
        let buffer = self.buffers.buffers[DISPATCH_ARGS].raw;
        // SAFETY: args * 12 is inside the 24-byte argument buffer.
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
        self.dispatch_indirect("shade", &pc, 0);
        self.dispatch("shadow_queue_args", &pc, 1);
        self.dispatch_indirect("shadow", &pc, 1);
    }

    fn read_film(&mut self, params: &RenderParams) -> anyhow::Result<Film> {
        let pixels = params.width as u64 * params.height as u64;
        let bytes = self.buffers.buffers[FILM].read(self.ctx, (pixels * 32) as usize)?;
        Ok(Film {
            width: params.width,
            height: params.height,
            pixels: pod_vec::<FilmPixel>(&bytes),
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
        let pixels = params.width as u64 * params.height as u64;
        let total = pixels * spp as u64;
        let pool = params.pool_size as u64;
        let pass = pass_spp(pixels, pool) as u64;
        let depth_limit = params.max_depth.min(MAX_BOUNCES_HARD);

        self.begin()?;
        // SAFETY: cmd is recording; the buffers are alive.
        unsafe {
            let d = &self.ctx.device;
            d.cmd_fill_buffer(
                self.cmd,
                self.buffers.buffers[FILM].raw,
                0,
                vk::WHOLE_SIZE,
                0,
            );
            d.cmd_fill_buffer(
                self.cmd,
                self.buffers.buffers[COUNTERS].raw,
                0,
                vk::WHOLE_SIZE,
                0,
            );
        }
        self.kernel_barrier();

        let mut pending_accumulate: Option<PushConstants> = None;
        let mut done = 0u64;
        while done < total {
            let pass_end = ((done / pixels / pass + 1) * pass * pixels).min(total);
            let chunk = PushConstants {
                pixel_start: (done % pixels) as u32,
                sample_start: (done / pixels) as u32,
                count: (pass_end - done).min(pool) as u32,
                bounce: 0,
            };
            if let Some(previous) = pending_accumulate.take() {
                self.dispatch("accumulate", &previous, pixels as u32);
            }
            self.dispatch("generate", &chunk, chunk.count);
            let mut bounce = 0;
            loop {
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
