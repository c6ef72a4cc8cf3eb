//! Buffers with named, intent-revealing constructors. Uploads and readbacks
//! map the memory when it is host-visible and coherent (lavapipe, integrated
//! GPUs) and go through a staging buffer otherwise (discrete GPUs).

use super::context::Context;
use anyhow::Context as _;
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

pub struct Buffer {
    pub raw: vk::Buffer,
    pub size: u64,
    pub name: String,
    allocation: Option<Allocation>,
}

impl Buffer {
    /// The whole buffer as a descriptor (one element, as `buffer_info` takes).
    pub fn descriptor_info(&self) -> [vk::DescriptorBufferInfo; 1] {
        [vk::DescriptorBufferInfo::default()
            .buffer(self.raw)
            .range(vk::WHOLE_SIZE)]
    }

    fn new(
        ctx: &Context,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> anyhow::Result<Buffer> {
        let size = size.max(16);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device and create info.
        let raw = unsafe { ctx.device.create_buffer(&info, None) }
            .with_context(|| format!("creating buffer '{name}' ({size} bytes)"))?;
        // SAFETY: raw was just created from this device.
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let allocation = ctx
            .allocator
            .lock()
            .expect("allocator lock")
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .with_context(|| format!("allocating {size} bytes for buffer '{name}'"))?;
        // SAFETY: memory and offset come from an allocation for these requirements.
        unsafe {
            ctx.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        }
        .with_context(|| format!("binding memory of buffer '{name}'"))?;
        Ok(Buffer {
            raw,
            size,
            name: name.to_string(),
            allocation: Some(allocation),
        })
    }

    /// Device memory the kernels read and write; filled and read by transfers.
    pub fn gpu_only(
        ctx: &Context,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
    ) -> anyhow::Result<Buffer> {
        let usage = usage | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC;
        Self::new(ctx, name, size, usage, MemoryLocation::GpuOnly)
    }

    /// Host memory the GPU copies into, for reading results back.
    pub fn readback(ctx: &Context, name: &str, size: u64) -> anyhow::Result<Buffer> {
        Self::new(
            ctx,
            name,
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )
    }

    fn staging(ctx: &Context, name: &str, size: u64) -> anyhow::Result<Buffer> {
        Self::new(
            ctx,
            name,
            size,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )
    }

    /// Mapped memory the host may use without flushes, if any.
    fn coherent_mapping(&mut self) -> Option<&mut [u8]> {
        let allocation = self.allocation.as_mut()?;
        let coherent = allocation
            .memory_properties()
            .contains(vk::MemoryPropertyFlags::HOST_COHERENT);
        if coherent {
            allocation.mapped_slice_mut()
        } else {
            None
        }
    }

    /// Writes `data` at the start of the buffer.
    pub fn upload(&mut self, ctx: &Context, data: &[u8]) -> anyhow::Result<()> {
        anyhow::ensure!(
            data.len() as u64 <= self.size,
            "upload overflows '{}'",
            self.name
        );
        if let Some(mapped) = self.coherent_mapping() {
            mapped[..data.len()].copy_from_slice(data);
            return Ok(());
        }
        let mut staging =
            Self::staging(ctx, &format!("{} (staging)", self.name), data.len() as u64)?;
        staging
            .coherent_mapping()
            .context("staging memory is not host-visible")?[..data.len()]
            .copy_from_slice(data);
        let region = vk::BufferCopy::default().size(data.len() as u64);
        one_shot(ctx, |cmd| {
            // SAFETY: both buffers are alive until one_shot waits for completion.
            unsafe {
                ctx.device
                    .cmd_copy_buffer(cmd, staging.raw, self.raw, &[region])
            };
        })?;
        staging.destroy(ctx);
        Ok(())
    }

    /// Reads the first `len` bytes (the GPU must be idle for this buffer).
    pub fn read(&mut self, ctx: &Context, len: usize) -> anyhow::Result<Vec<u8>> {
        if let Some(mapped) = self.coherent_mapping() {
            return Ok(mapped[..len].to_vec());
        }
        let mut readback = Self::readback(ctx, &format!("{} (readback)", self.name), len as u64)?;
        let region = vk::BufferCopy::default().size(len as u64);
        one_shot(ctx, |cmd| {
            // SAFETY: both buffers are alive until one_shot waits for completion.
            unsafe {
                ctx.device
                    .cmd_copy_buffer(cmd, self.raw, readback.raw, &[region])
            };
        })?;
        let allocation = readback
            .allocation
            .as_mut()
            .context("readback buffer has memory")?;
        let mapped = allocation
            .mapped_slice()
            .context("readback memory is not mapped")?;
        let bytes = mapped[..len].to_vec();
        readback.destroy(ctx);
        Ok(bytes)
    }

    /// Reads memory the host may see directly (a `readback` buffer).
    pub fn mapped_bytes(&self) -> Option<&[u8]> {
        self.allocation.as_ref()?.mapped_slice()
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if let Some(allocation) = self.allocation.take() {
            let _ = ctx
                .allocator
                .lock()
                .expect("allocator lock")
                .free(allocation);
            // SAFETY: the GPU no longer uses the buffer (callers wait first).
            unsafe { ctx.device.destroy_buffer(self.raw, None) };
        }
    }
}

/// Records commands into a temporary command buffer, submits and waits.
pub fn one_shot(ctx: &Context, record: impl FnOnce(vk::CommandBuffer)) -> anyhow::Result<()> {
    let pool_info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(ctx.queue_family)
        .flags(vk::CommandPoolCreateFlags::TRANSIENT);
    // SAFETY: valid device and create info.
    let pool = unsafe { ctx.device.create_command_pool(&pool_info, None) }?;
    let alloc = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .level(vk::CommandBufferLevel::PRIMARY)
        .command_buffer_count(1);
    let result = (|| -> anyhow::Result<()> {
        // SAFETY: pool is valid; one primary buffer.
        let cmd = unsafe { ctx.device.allocate_command_buffers(&alloc) }?[0];
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: cmd is a fresh command buffer.
        unsafe { ctx.device.begin_command_buffer(cmd, &begin) }?;
        record(cmd);
        // SAFETY: recording began above.
        unsafe { ctx.device.end_command_buffer(cmd) }?;
        let cmds = [cmd];
        let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
        // SAFETY: the queue belongs to this device; we wait for idle below.
        unsafe {
            ctx.device
                .queue_submit(ctx.queue, &submit, vk::Fence::null())
        }?;
        // SAFETY: as above.
        unsafe { ctx.device.queue_wait_idle(ctx.queue) }?;
        Ok(())
    })();
    // SAFETY: the queue is idle, so the pool's buffers are no longer in use.
    unsafe { ctx.device.destroy_command_pool(pool, None) };
    result
}
