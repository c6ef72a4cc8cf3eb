//! The buffers and texel views of one render, one per row of the binding
//! table (`packed::bindings`), and the descriptor set pointing at them. The
//! table says what each binding is; `contents` below says what fills it.

use super::buffer::Buffer;
use super::context::Context;
use super::descriptors::{self, Target};
use super::limits::{BufferNeed, DeviceLimits};
use crate::constants::COUNTER_COUNT;
use crate::packed::PackedScene;
use crate::packed::bindings::{Binding, Kind, Schedule, views_of};
use crate::packed::content_hash::bytes_hash;
use crate::packed::layout::{AovPixel, FilmPixel, RenderParams};
use anyhow::Context as _;
use ash::vk;
use bytemuck::{bytes_of, cast_slice};

/// What fills a binding's buffer.
enum Contents<'a> {
    /// Uploaded before the render (the scene).
    Data(&'a [u8]),
    /// Written and read only by the kernels; `u64` bytes.
    Scratch(u64),
    /// As `Scratch`, also read by `vkCmdDispatchIndirect`.
    IndirectArgs(u64),
}

/// The contents of the buffer of each table row that has one, by name.
fn contents<'a>(
    name: &str,
    packed: &'a PackedScene,
    params: &'a RenderParams,
) -> Option<Contents<'a>> {
    use Contents::{Data, IndirectArgs, Scratch};
    let pool = params.pool_size as u64;
    let pixels = params.film_pixels();
    let t = &packed.textures;
    Some(match name {
        "params" => Data(bytes_of(params)),
        "bvh_nodes" => Data(cast_slice(&packed.nodes)),
        "tri_verts" => Data(cast_slice(&packed.tri_verts)),
        "tri_shading" => Data(cast_slice(&packed.tri_shading)),
        "materials" => Data(cast_slice(&packed.materials)),
        "emitters" => Data(cast_slice(&packed.emitters)),
        "path_origin"
        | "path_direction"
        | "path_hit"
        | "path_throughput"
        | "path_radiance"
        | "shadow_origin"
        | "shadow_direction"
        | "shadow_contribution" => Scratch(16 * pool),
        "ray_queue" => Scratch(2 * 4 * pool),
        "counters" => Scratch(4 * COUNTER_COUNT as u64),
        "dispatch_args" => IndirectArgs(4 * 12),
        "shade_queue" => Scratch(4 * pool),
        "film" => Scratch(std::mem::size_of::<FilmPixel>() as u64 * pixels),
        "path_aov" if params.aov != 0 => Scratch(32 * pool),
        "film_aov" if params.aov != 0 => Scratch(std::mem::size_of::<AovPixel>() as u64 * pixels),
        "path_aov" | "film_aov" => Scratch(16),
        "textures" => Data(cast_slice(&t.textures)),
        "texture_texels" => Data(cast_slice(&t.texels)),
        "tri_texcoords" => Data(cast_slice(&t.tri_texcoords)),
        "light_params" => Data(bytes_of(&packed.light_params)),
        "lights" => Data(cast_slice(&packed.lights)),
        "env_cdf" => Data(cast_slice(&packed.env_cdf)),
        "env_radiance" => Data(cast_slice(&packed.env_radiance)),
        "motion_texels" => Data(match &packed.motion {
            Some(m) => cast_slice(&m.texels),
            None => &[0u8; 16],
        }),
        "instances" => Data(if packed.instances.is_empty() {
            &[0u8; 16]
        } else {
            cast_slice(&packed.instances)
        }),
        "sheen_albedo_table" => Data(cast_slice(&crate::packed::sheen_table::SHEEN_ALBEDO[..])),
        _ => return None,
    })
}

impl Contents<'_> {
    fn bytes(&self) -> u64 {
        match self {
            Contents::Data(data) => data.len() as u64,
            Contents::Scratch(bytes) | Contents::IndirectArgs(bytes) => *bytes,
        }
    }
}

/// The size and usage of the buffer of `b`, and its contents.
struct Plan<'a> {
    binding: &'static Binding,
    contents: Contents<'a>,
    usage: vk::BufferUsageFlags,
}

fn plan<'a>(
    b: &'static Binding,
    packed: &'a PackedScene,
    params: &'a RenderParams,
) -> anyhow::Result<Plan<'a>> {
    let contents = contents(b.name, packed, params).with_context(|| {
        format!(
            "binding '{}' of packed::bindings has no contents in gpu/resources.rs",
            b.name
        )
    })?;
    let viewed = views_of(b.name).next().is_some();
    let mut usage = match b.kind {
        Kind::Uniform => vk::BufferUsageFlags::UNIFORM_BUFFER,
        Kind::ReadOnly | Kind::ReadWrite => vk::BufferUsageFlags::STORAGE_BUFFER,
        Kind::Texels(_) => vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
        Kind::View { .. } => unreachable!("views own no buffer"),
    };
    if viewed {
        usage |= vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
    }
    if let Contents::IndirectArgs(_) = contents {
        usage |= vk::BufferUsageFlags::INDIRECT_BUFFER;
    }
    Ok(Plan {
        binding: b,
        contents,
        usage,
    })
}

/// What the device limits see of a buffer (the small uniform block aside).
fn need<'a>(p: &Plan<'a>) -> Option<BufferNeed<'a>> {
    let b = p.binding;
    let (storage, texel) = match b.kind {
        Kind::Uniform | Kind::View { .. } => return None,
        Kind::ReadOnly | Kind::ReadWrite => (true, views_of(b.name).next()),
        Kind::Texels(_) => (false, Some(b)),
    };
    Some(BufferNeed {
        name: b.name,
        bytes: p.contents.bytes(),
        storage,
        texel_bytes: texel.and_then(|v| v.texel_format()).map(|f| f.bytes()),
    })
}

/// The buffers, views and descriptor set of one render, kept for the next
/// render (a frame of a sequence) when the sizes still fit
/// ([`Resources::update`]).
pub struct Resources {
    /// Each bound row with its buffer (`None` for a view) and its texel view
    /// (null unless it is a texel buffer), in table order.
    rows: Vec<(&'static Binding, Option<Buffer>, vk::BufferView)>,
    /// The size each buffer was asked for and the hash of what was last
    /// uploaded into it (0 for scratch), by row name.
    filled: Vec<(&'static str, u64, u64)>,
    /// Bytes of scene data the constructor uploaded.
    pub uploaded: u64,
    pool: vk::DescriptorPool,
    pub set: vk::DescriptorSet,
}

impl Resources {
    /// Checks the buffers against the device limits, creates and fills
    /// them, makes the texel views and writes a descriptor set of
    /// `set_layout` (made by `descriptors::create_set_layout(schedule)`).
    pub fn new(
        ctx: &Context,
        set_layout: vk::DescriptorSetLayout,
        schedule: Schedule,
        packed: &PackedScene,
        params: &RenderParams,
        limits: &DeviceLimits,
    ) -> anyhow::Result<Resources> {
        let plans = descriptors::rows(schedule)
            .filter(|b| b.owns_buffer())
            .map(|b| plan(b, packed, params))
            .collect::<anyhow::Result<Vec<Plan>>>()?;
        let needs: Vec<BufferNeed> = plans.iter().filter_map(need).collect();
        limits.check(&needs)?;

        let mut resources = Resources {
            rows: Vec::new(),
            filled: Vec::new(),
            uploaded: 0,
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
        };
        if let Err(e) = resources.fill(ctx, set_layout, schedule, &plans) {
            resources.destroy(ctx);
            return Err(e);
        }
        Ok(resources)
    }

    fn fill(
        &mut self,
        ctx: &Context,
        set_layout: vk::DescriptorSetLayout,
        schedule: Schedule,
        plans: &[Plan],
    ) -> anyhow::Result<()> {
        for b in descriptors::rows(schedule) {
            let plan = plans.iter().find(|p| p.binding.name == b.name);
            let buffer = match plan {
                Some(p) => Some(Buffer::gpu_only(ctx, b.name, p.contents.bytes(), p.usage)?),
                None => None,
            };
            self.rows.push((b, buffer, vk::BufferView::null()));
            if let Some(p) = plan {
                let hash = match p.contents {
                    Contents::Data(data) => bytes_hash(data),
                    _ => 0,
                };
                self.filled.push((b.name, p.contents.bytes(), hash));
            }
            if let Some(Contents::Data(data)) = plan.map(|p| &p.contents)
                && !data.is_empty()
            {
                self.buffer_mut(b.name).upload(ctx, data)?;
                self.uploaded += data.len() as u64;
            }
        }
        for k in 0..self.rows.len() {
            let (b, _, _) = self.rows[k];
            let (viewed, format) = match b.kind {
                Kind::View { of, format } => (of, format),
                Kind::Texels(format) => (b.name, format),
                _ => continue,
            };
            let info = vk::BufferViewCreateInfo::default()
                .buffer(self.buffer(viewed).raw)
                .format(descriptors::vk_format(format))
                .range(vk::WHOLE_SIZE);
            // SAFETY: the buffer was created with UNIFORM_TEXEL_BUFFER usage.
            self.rows[k].2 = unsafe { ctx.device.create_buffer_view(&info, None) }?;
        }

        self.pool = descriptors::create_pool(ctx, schedule)?;
        let layouts = [set_layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for exactly this set.
        self.set = unsafe { ctx.device.allocate_descriptor_sets(&info) }?[0];
        let targets: Vec<(&Binding, Target)> = self
            .rows
            .iter()
            .map(|(b, buffer, view)| match buffer {
                Some(buffer) if b.texel_format().is_none() => (*b, Target::Buffer(buffer)),
                _ => (*b, Target::View(*view)),
            })
            .collect();
        descriptors::write_set(ctx, self.set, &targets);
        Ok(())
    }

    /// Refills these buffers for another render of the same layout (the
    /// next frame of a sequence): uploads only the arrays whose bytes
    /// changed, keeping buffers, views and the descriptor set. Returns the
    /// bytes uploaded, or `None` when a buffer would change size (the
    /// caller then makes new resources).
    pub fn update(
        &mut self,
        ctx: &Context,
        schedule: Schedule,
        packed: &PackedScene,
        params: &RenderParams,
    ) -> anyhow::Result<Option<u64>> {
        let plans = descriptors::rows(schedule)
            .filter(|b| b.owns_buffer())
            .map(|b| plan(b, packed, params))
            .collect::<anyhow::Result<Vec<Plan>>>()?;
        let fits = plans.len() == self.filled.len()
            && plans.iter().zip(&self.filled).all(|(p, (name, bytes, _))| {
                p.binding.name == *name && p.contents.bytes() == *bytes
            });
        if !fits {
            return Ok(None);
        }
        let mut uploaded = 0;
        for (p, filled) in plans.iter().zip(&mut self.filled) {
            if let Contents::Data(data) = p.contents {
                let hash = bytes_hash(data);
                if hash != filled.2 && !data.is_empty() {
                    uploaded += data.len() as u64;
                    upload_into(&mut self.rows, ctx, p.binding.name, data)?;
                }
                filled.2 = hash;
            }
        }
        Ok(Some(uploaded))
    }

    /// The buffer of the row named `name` (a name from the table).
    pub fn buffer(&self, name: &str) -> &Buffer {
        self.rows
            .iter()
            .find_map(|(b, buffer, _)| buffer.as_ref().filter(|_| b.name == name))
            .unwrap_or_else(|| panic!("no buffer for binding '{name}'"))
    }

    pub fn buffer_mut(&mut self, name: &str) -> &mut Buffer {
        self.rows
            .iter_mut()
            .find_map(|(b, buffer, _)| buffer.as_mut().filter(|_| b.name == name))
            .unwrap_or_else(|| panic!("no buffer for binding '{name}'"))
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for (_, buffer, view) in &mut self.rows {
            if *view != vk::BufferView::null() {
                // SAFETY: the device is idle.
                unsafe { ctx.device.destroy_buffer_view(*view, None) };
                *view = vk::BufferView::null();
            }
            if let Some(buffer) = buffer {
                buffer.destroy(ctx);
            }
        }
        self.rows.clear();
        self.filled.clear();
        if self.pool != vk::DescriptorPool::null() {
            // SAFETY: the device is idle; destroying the pool frees the set.
            unsafe { ctx.device.destroy_descriptor_pool(self.pool, None) };
            self.pool = vk::DescriptorPool::null();
        }
    }
}

/// Uploads `data` into the buffer of row `name`.
fn upload_into(
    rows: &mut [(&'static Binding, Option<Buffer>, vk::BufferView)],
    ctx: &Context,
    name: &str,
    data: &[u8],
) -> anyhow::Result<()> {
    let buffer = rows
        .iter_mut()
        .find_map(|(b, buffer, _)| buffer.as_mut().filter(|_| b.name == name))
        .with_context(|| format!("no buffer for binding '{name}'"))?;
    buffer.upload(ctx, data)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packed::bindings::BINDINGS;
    use crate::packed::settings::RenderSettings;
    use crate::scene::Scene;

    #[test]
    fn every_buffer_of_the_table_has_contents() {
        // Untextured: its texture buffers are empty, which is allowed (they
        // get 16-byte dummies); what is checked is that each has an arm.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.gltf");
        let scene = Scene::load(&path).expect("the bundled Cornell box loads");
        let packed = PackedScene::new(&scene).expect("and packs");
        let settings = RenderSettings::default();
        let params = packed
            .render_params(&scene, &settings, 1024)
            .expect("render parameters");
        for b in BINDINGS.iter().filter(|b| b.owns_buffer()) {
            if let Err(e) = plan(b, &packed, &params) {
                panic!("{e}");
            }
        }
    }
}
