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
                .descriptor_count(1)
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
        match sizes.iter_mut().find(|s| s.ty == ty) {
            Some(size) => size.descriptor_count += 1,
            None => sizes.push(vk::DescriptorPoolSize::default().ty(ty).descriptor_count(1)),
        }
    }
    let info = vk::DescriptorPoolCreateInfo::default()
        .max_sets(1)
        .pool_sizes(&sizes);
    // SAFETY: valid device and create info.
    Ok(unsafe { ctx.device.create_descriptor_pool(&info, None) }?)
}

/// What one descriptor points at.
pub enum Target<'a> {
    Buffer(&'a Buffer),
    View(vk::BufferView),
}

/// Points every binding of `set` at its target.
pub fn write_set(ctx: &Context, set: vk::DescriptorSet, targets: &[(&Binding, Target)]) {
    let infos: Vec<[vk::DescriptorBufferInfo; 1]> = targets
        .iter()
        .map(|(_, t)| match t {
            Target::Buffer(buffer) => buffer.descriptor_info(),
            Target::View(_) => [vk::DescriptorBufferInfo::default()],
        })
        .collect();
    let views: Vec<[vk::BufferView; 1]> = targets
        .iter()
        .map(|(_, t)| match t {
            Target::View(view) => [*view],
            Target::Buffer(_) => [vk::BufferView::null()],
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
                Target::Buffer(_) => write.buffer_info(&infos[k]),
                Target::View(_) => write.texel_buffer_view(&views[k]),
            }
        })
        .collect();
    // SAFETY: every buffer and view is alive and bound to memory; the set is
    // not in use by any pending command buffer.
    unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
}
