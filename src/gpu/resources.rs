//! The buffers and texel views of one render, one per row of the binding
//! table (`packed::bindings`), and the descriptor set pointing at them. The
//! table says what each binding is; `contents` below says what fills it.
//! The buffer of a split array is cut into parts of `1 << shift` texels
//! (`scene_view_shift`), one buffer and one view each.

use super::buffer::Buffer;
use super::context::Context;
use super::descriptors::{self, Target};
use super::limits::{BufferNeed, DeviceLimits};
use crate::constants::COUNTER_COUNT;
use crate::packed::PackedScene;
use crate::packed::bindings::{BINDINGS, Binding, Kind, Schedule, views_of};
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
        "light_tree" => Data(cast_slice(&packed.light_tree.nodes)),
        "light_trails" => Data(cast_slice(&packed.light_tree.trails)),
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

/// What the device limits see of a buffer (the small uniform block aside):
/// one need per part of a split array, whose storage binding covers no more
/// than the limit allows (the kernels read it through its views).
fn needs<'a>(p: &Plan<'a>, shift: u32) -> Vec<BufferNeed<'a>> {
    let b = p.binding;
    let (storage, texel) = match b.kind {
        Kind::Uniform | Kind::View { .. } => return Vec::new(),
        Kind::ReadOnly | Kind::ReadWrite => (true, views_of(b.name).next()),
        Kind::Texels(_) => (false, Some(b)),
    };
    let texel_bytes = texel.and_then(|v| v.texel_format()).map(|f| f.bytes());
    let bytes = p.contents.bytes();
    match part_bytes(b, shift) {
        Some(part) => (0..bytes.div_ceil(part).max(1))
            .map(|k| BufferNeed {
                name: b.name,
                bytes: (bytes - k * part).min(part),
                storage: false,
                texel_bytes,
            })
            .collect(),
        None => vec![BufferNeed {
            name: b.name,
            bytes,
            // A split array's storage binding is clamped (module doc).
            storage: storage && b.parts_format().is_none(),
            texel_bytes,
        }],
    }
}

/// The bytes of each part of `b`'s buffer where it is cut into parts (a
/// split array with a nonzero shift).
fn part_bytes(b: &Binding, shift: u32) -> Option<u64> {
    let format = b.parts_format()?;
    (shift != 0).then(|| format.bytes() << shift)
}

/// The view shift of a render (`KernelFeatures::scene_view_shift`): 0 where
/// every split array fits one view of the device, else the largest shift
/// the limits allow (`DeviceLimits::scene_view_shift`).
pub fn scene_view_shift(packed: &PackedScene, params: &RenderParams, limits: &DeviceLimits) -> u32 {
    let shift = limits.scene_view_shift();
    let fits = BINDINGS.iter().all(|b| {
        let (Some(format), Some(contents)) = (b.parts_format(), contents(b.name, packed, params))
        else {
            return true;
        };
        contents.bytes() <= format.bytes() << shift
    });
    if fits { 0 } else { shift }
}

/// One bound row of the table.
struct Row {
    binding: &'static Binding,
    /// Its buffer, or the parts of a split array's buffer in order; none for
    /// a view.
    buffers: Vec<Buffer>,
    /// Its texel views (`Binding::descriptor_count` of them); none unless it
    /// is a texel buffer.
    views: Vec<vk::BufferView>,
}

/// The buffers, views and descriptor set of one render, kept for the next
/// render (a frame of a sequence) when the sizes still fit
/// ([`Resources::update`]).
pub struct Resources {
    /// Each bound row, in table order.
    rows: Vec<Row>,
    /// log2 of the texels per part of a split array; 0: one part each.
    shift: u32,
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
        let shift = scene_view_shift(packed, params, limits);
        for p in &plans {
            if let (Some(part), Some(format)) =
                (part_bytes(p.binding, shift), p.binding.parts_format())
            {
                limits.check_parts(p.binding.name, p.contents.bytes(), part, format.bytes())?;
            }
        }
        let needs: Vec<BufferNeed> = plans.iter().flat_map(|p| needs(p, shift)).collect();
        limits.check(&needs)?;

        let mut resources = Resources {
            rows: Vec::new(),
            shift,
            filled: Vec::new(),
            uploaded: 0,
            pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
        };
        if let Err(e) = resources.fill(ctx, set_layout, schedule, &plans, limits) {
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
        limits: &DeviceLimits,
    ) -> anyhow::Result<()> {
        for b in descriptors::rows(schedule) {
            let plan = plans.iter().find(|p| p.binding.name == b.name);
            self.rows.push(Row {
                binding: b,
                buffers: Vec::new(),
                views: Vec::new(),
            });
            let Some(p) = plan else { continue };
            let bytes = p.contents.bytes();
            let parts = match part_bytes(b, self.shift) {
                Some(part) => (0..bytes.div_ceil(part).max(1))
                    .map(|k| (bytes - k * part).min(part))
                    .collect(),
                None => vec![bytes],
            };
            for (k, &size) in parts.iter().enumerate() {
                let name = match parts.len() {
                    1 => b.name.to_string(),
                    n => format!("{} (part {} of {n})", b.name, k + 1),
                };
                let buffer = Buffer::gpu_only(ctx, &name, size, p.usage)?;
                self.rows.last_mut().expect("pushed").buffers.push(buffer);
            }
            let hash = match p.contents {
                Contents::Data(data) => bytes_hash(data),
                _ => 0,
            };
            self.filled.push((b.name, bytes, hash));
            if let Contents::Data(data) = p.contents
                && !data.is_empty()
            {
                upload_into(&mut self.rows, ctx, b.name, data)?;
                self.uploaded += data.len() as u64;
            }
        }
        for k in 0..self.rows.len() {
            let b = self.rows[k].binding;
            let (viewed, format) = match b.kind {
                Kind::View { of, format } => (of, format),
                Kind::Texels(format) => (b.name, format),
                _ => continue,
            };
            let parts: Vec<vk::Buffer> = self.buffers(viewed).iter().map(|p| p.raw).collect();
            let count = b.descriptor_count() as usize;
            for part in parts.iter().take(count) {
                let info = vk::BufferViewCreateInfo::default()
                    .buffer(*part)
                    .format(descriptors::vk_format(format))
                    .range(vk::WHOLE_SIZE);
                // SAFETY: the buffer was created with UNIFORM_TEXEL_BUFFER usage.
                let view = unsafe { ctx.device.create_buffer_view(&info, None) }?;
                self.rows[k].views.push(view);
            }
            // A view for every descriptor of the row: the parts it lacks
            // (never read) repeat the first.
            let views = &mut self.rows[k].views;
            let first = *views.first().context("a texel buffer without a buffer")?;
            views.resize(count, first);
        }

        self.pool = descriptors::create_pool(ctx, schedule)?;
        let layouts = [set_layout];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.pool)
            .set_layouts(&layouts);
        // SAFETY: the pool has room for exactly this set.
        self.set = unsafe { ctx.device.allocate_descriptor_sets(&info) }?[0];
        // A split array's storage binding covers its first part, at most
        // maxStorageBufferRange of it: the kernels read it through its views.
        let range = limits.max_storage_buffer_range;
        let targets: Vec<(&Binding, Target)> = self
            .rows
            .iter()
            .map(|row| match row.buffers.first() {
                Some(buffer) if row.binding.texel_format().is_none() => {
                    let range = row.binding.parts_format().map(|_| range.min(buffer.size));
                    (row.binding, Target::Buffer(buffer, range))
                }
                _ => (row.binding, Target::Views(&row.views)),
            })
            .collect();
        descriptors::write_set(ctx, self.set, &targets);
        Ok(())
    }

    /// Refills these buffers for another render of the same layout (the
    /// next frame of a sequence): uploads only the arrays whose bytes
    /// changed, keeping buffers, views and the descriptor set. Returns the
    /// bytes uploaded, or `None` when a buffer would change size (the
    /// caller then makes new resources), as when the arrays would be cut
    /// into other parts.
    pub fn update(
        &mut self,
        ctx: &Context,
        schedule: Schedule,
        packed: &PackedScene,
        params: &RenderParams,
        limits: &DeviceLimits,
    ) -> anyhow::Result<Option<u64>> {
        if scene_view_shift(packed, params, limits) != self.shift {
            return Ok(None);
        }
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

    /// The buffer of the row named `name` (a name from the table; the first
    /// part of a split array).
    pub fn buffer(&self, name: &str) -> &Buffer {
        self.buffers(name)
            .first()
            .unwrap_or_else(|| panic!("no buffer for binding '{name}'"))
    }

    pub fn buffer_mut(&mut self, name: &str) -> &mut Buffer {
        self.rows
            .iter_mut()
            .find(|row| row.binding.name == name)
            .and_then(|row| row.buffers.first_mut())
            .unwrap_or_else(|| panic!("no buffer for binding '{name}'"))
    }

    /// The buffer of the row named `name`, or the parts of a split array.
    fn buffers(&self, name: &str) -> &[Buffer] {
        self.rows
            .iter()
            .find(|row| row.binding.name == name)
            .map_or(&[], |row| row.buffers.as_slice())
    }

    pub fn destroy(&mut self, ctx: &Context) {
        for row in &mut self.rows {
            let mut views = std::mem::take(&mut row.views);
            views.sort();
            views.dedup();
            for view in views {
                // SAFETY: the device is idle.
                unsafe { ctx.device.destroy_buffer_view(view, None) };
            }
            for buffer in &mut row.buffers {
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

/// Uploads `data` into the buffer of row `name`, or across its parts.
fn upload_into(rows: &mut [Row], ctx: &Context, name: &str, data: &[u8]) -> anyhow::Result<()> {
    let row = rows
        .iter_mut()
        .find(|row| row.binding.name == name && !row.buffers.is_empty())
        .with_context(|| format!("no buffer for binding '{name}'"))?;
    let mut rest = data;
    for part in &mut row.buffers {
        let (now, later) = rest.split_at(rest.len().min(part.size as usize));
        if !now.is_empty() {
            part.upload(ctx, now)?;
        }
        rest = later;
    }
    anyhow::ensure!(rest.is_empty(), "upload overflows the parts of '{name}'");
    Ok(())
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
