//! Descriptor set layout, pool and writes, made by iterating the binding
//! table (`packed::bindings`): one descriptor per row, so nothing here names
//! a binding.

use super::buffer::Buffer;
use super::context::Context;
use crate::packed::bindings::{BINDINGS, Binding, Kind, Schedule, TexelFormat};
use ash::vk;

/// The rows the kernels of `schedule` bind: the wavefront binds them all; a
/// schedule without path state in memory binds only the `Any` rows.
pub fn rows(schedule: Schedule) -> impl Iterator<Item = &'static Binding> {
    BINDINGS
        .iter()
        .filter(move |b| schedule == Schedule::Wavefront || b.schedule == Schedule::Any)
}

pub fn descriptor_type(b: &Binding) -> vk::DescriptorType {
    match b.kind {
        Kind::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
        Kind::ReadOnly | Kind::ReadWrite => vk::DescriptorType::STORAGE_BUFFER,
        Kind::Texels(_) | Kind::View { .. } => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
    }
}

pub fn vk_format(format: TexelFormat) -> vk::Format {
    match format {
        TexelFormat::Rgba32Uint => vk::Format::R32G32B32A32_UINT,
        TexelFormat::R32Uint => vk::Format::R32_UINT,
    }
}

/// The set layout every kernel of `schedule` shares.
pub fn create_set_layout(
    ctx: &Context,
    schedule: Schedule,
) -> anyhow::Result<vk::DescriptorSetLayout> {
    let bindings: Vec<vk::DescriptorSetLayoutBinding> = rows(schedule)
        .map(|b| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(b.binding)
                .descriptor_type(descriptor_type(b))
                .descriptor_count(b.descriptor_count())
                .stage_flags(vk::ShaderStageFlags::COMPUTE)
        })
        .collect();
    let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
    // SAFETY: valid device and create info.
    Ok(unsafe { ctx.device.create_descriptor_set_layout(&info, None) }?)
}

/// A pool with room for exactly one set of `schedule`'s layout.
pub fn create_pool(ctx: &Context, schedule: Schedule) -> anyhow::Result<vk::DescriptorPool> {
    let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
    for b in rows(schedule) {
        let ty = descriptor_type(b);
        let count = b.descriptor_count();
        match sizes.iter_mut().find(|s| s.ty == ty) {
            Some(size) => size.descriptor_count += count,
            None => sizes.push(
                vk::DescriptorPoolSize::default()
                    .ty(ty)
                    .descriptor_count(count),
            ),
        }
    }
    let info = vk::DescriptorPoolCreateInfo::default()
        .max_sets(1)
        .pool_sizes(&sizes);
    // SAFETY: valid device and create info.
    Ok(unsafe { ctx.device.create_descriptor_pool(&info, None) }?)
}

/// What a binding's descriptors point at.
pub enum Target<'a> {
    /// A buffer, whole or its first `range` bytes.
    Buffer(&'a Buffer, Option<u64>),
    /// Texel views, one per descriptor of the binding.
    Views(&'a [vk::BufferView]),
}

/// Points every binding of `set` at its target.
pub fn write_set(ctx: &Context, set: vk::DescriptorSet, targets: &[(&Binding, Target)]) {
    let infos: Vec<[vk::DescriptorBufferInfo; 1]> = targets
        .iter()
        .map(|(_, t)| match t {
            Target::Buffer(buffer, None) => buffer.descriptor_info(),
            Target::Buffer(buffer, Some(range)) => [vk::DescriptorBufferInfo::default()
                .buffer(buffer.raw)
                .range(*range)],
            Target::Views(_) => [vk::DescriptorBufferInfo::default()],
        })
        .collect();
    let writes: Vec<vk::WriteDescriptorSet> = targets
        .iter()
        .enumerate()
        .map(|(k, (b, target))| {
            let write = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(b.binding)
                .descriptor_type(descriptor_type(b));
            match target {
                Target::Buffer(..) => write.buffer_info(&infos[k]),
                Target::Views(views) => write.texel_buffer_view(views),
            }
        })
        .collect();
    // SAFETY: every buffer and view is alive and bound to memory; the set is
    // not in use by any pending command buffer.
    unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
}
