//! The texture buffers of `shaders/common/bindings.glsl` (bindings 23-25):
//! the texture table, the texels (read through an R32UI uniform texel
//! buffer: lavapipe gathers texel fetches as vectors, while its
//! storage-buffer loads run lane by lane) and the per-triangle texture
//! coordinates. Untextured scenes get 16-byte dummies.

use super::buffer::Buffer;
use super::context::Context;
use crate::packed::PackedScene;
use ash::vk;
use bytemuck::cast_slice;

pub const TEXTURE_TABLE_BINDING: u32 = 23;
pub const TEXTURE_TEXELS_BINDING: u32 = 24;
pub const TRI_TEXCOORDS_BINDING: u32 = 25;

pub struct TextureBuffers {
    /// Table, texels, per-triangle texture coordinates.
    buffers: Vec<Buffer>,
    texel_view: vk::BufferView,
}

impl TextureBuffers {
    /// Creates and fills the buffers and points `set`'s bindings at them.
    pub fn new(
        ctx: &Context,
        packed: &PackedScene,
        set: vk::DescriptorSet,
    ) -> anyhow::Result<TextureBuffers> {
        let t = &packed.textures;
        let limits = &ctx.properties.limits;
        let texel_bytes = std::mem::size_of_val(t.texels.as_slice()) as u64;
        let texel_limit = limits.max_texel_buffer_elements as u64 * 4;
        anyhow::ensure!(
            texel_bytes <= texel_limit,
            "the scene's textures need {:.1} MiB, above this device's maxTexelBufferElements ({:.1} MiB of 4-byte texels)",
            texel_bytes as f64 / 1048576.0,
            texel_limit as f64 / 1048576.0
        );
        let coords_bytes = std::mem::size_of_val(t.tri_texcoords.as_slice()) as u64;
        anyhow::ensure!(
            coords_bytes <= limits.max_storage_buffer_range as u64,
            "the scene's per-triangle texture coordinates need {:.1} MiB, above this device's maxStorageBufferRange of {:.1} MiB",
            coords_bytes as f64 / 1048576.0,
            limits.max_storage_buffer_range as f64 / 1048576.0
        );
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let contents: [(&str, &[u8], vk::BufferUsageFlags); 3] = [
            ("textures", cast_slice(&t.textures), storage),
            (
                "texture_texels",
                cast_slice(&t.texels),
                vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
            ),
            ("tri_texcoords", cast_slice(&t.tri_texcoords), storage),
        ];
        let mut out = TextureBuffers {
            buffers: Vec::new(),
            texel_view: vk::BufferView::null(),
        };
        let fill = |out: &mut TextureBuffers| -> anyhow::Result<()> {
            for (name, data, usage) in contents {
                out.buffers
                    .push(Buffer::gpu_only(ctx, name, data.len() as u64, usage)?);
                if !data.is_empty() {
                    out.buffers
                        .last_mut()
                        .expect("just pushed")
                        .upload(ctx, data)?;
                }
            }
            let info = vk::BufferViewCreateInfo::default()
                .buffer(out.buffers[1].raw)
                .format(vk::Format::R32_UINT)
                .range(vk::WHOLE_SIZE);
            // SAFETY: the buffer was created with UNIFORM_TEXEL_BUFFER usage.
            out.texel_view = unsafe { ctx.device.create_buffer_view(&info, None) }?;
            Ok(())
        };
        if let Err(e) = fill(&mut out) {
            out.destroy(ctx);
            return Err(e);
        }

        let infos: Vec<[vk::DescriptorBufferInfo; 1]> =
            [0, 2].map(|k| out.buffers[k].descriptor_info()).to_vec();
        let views = [out.texel_view];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(TEXTURE_TABLE_BINDING)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&infos[0]),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(TEXTURE_TEXELS_BINDING)
                .descriptor_type(vk::DescriptorType::UNIFORM_TEXEL_BUFFER)
                .texel_buffer_view(&views),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(TRI_TEXCOORDS_BINDING)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(&infos[1]),
        ];
        // SAFETY: the buffers and the view are alive; the set is not in use.
        unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
        Ok(out)
    }

    pub fn destroy(&mut self, ctx: &Context) {
        if self.texel_view != vk::BufferView::null() {
            // SAFETY: the device is idle.
            unsafe { ctx.device.destroy_buffer_view(self.texel_view, None) };
            self.texel_view = vk::BufferView::null();
        }
        for b in &mut self.buffers {
            b.destroy(ctx);
        }
        self.buffers.clear();
    }
}
