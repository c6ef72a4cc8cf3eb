//! The device limits a render's buffers must fit in, checked before anything
//! is allocated so that a scene too large for the device is refused with a
//! message naming the limit and the excess, not a driver error (or a silent
//! truncation: a descriptor range beyond maxStorageBufferRange is undefined
//! behaviour).

use super::context::Context;
use anyhow::{Result, bail};
use ash::vk;

/// Limits in bytes. Queried from the device; tests lower them (through
/// `GpuRenderer::limits_mut`) to see the refusal without a huge scene.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceLimits {
    /// `maxStorageBufferRange`: the largest storage-buffer binding.
    pub max_storage_buffer_range: u64,
    /// `maxTexelBufferElements`: the most texels one texel buffer view holds.
    pub max_texel_buffer_elements: u64,
    /// `maxMemoryAllocationSize` (Vulkan 1.1): the largest single allocation.
    pub max_memory_allocation_size: u64,
    /// The largest device-local memory heap: all buffers together must fit.
    pub device_memory: u64,
}

/// Where a split scene array's parts are capped (see `scene_view_shift`):
/// the kernels index texels with 32-bit ints, and `SCENE_VIEWS` parts of
/// 2^27 texels (2 GiB of 16-byte ones) stay below 2^31.
const MAX_VIEW_SHIFT: u32 = 27;

impl DeviceLimits {
    pub fn query(ctx: &Context) -> DeviceLimits {
        let mut maintenance3 = vk::PhysicalDeviceMaintenance3Properties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut maintenance3);
        // SAFETY: a Vulkan 1.2 physical device of this instance (pick_device
        // requires 1.2); the chain outlives the call.
        unsafe {
            ctx.instance
                .get_physical_device_properties2(ctx.physical_device, &mut props2)
        };
        let limits = props2.properties.limits;
        let max_alloc = maintenance3.max_memory_allocation_size;
        // SAFETY: as above.
        let memory = unsafe {
            ctx.instance
                .get_physical_device_memory_properties(ctx.physical_device)
        };
        let heaps = &memory.memory_heaps[..memory.memory_heap_count as usize];
        let device_memory = heaps
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .chain(heaps.iter())
            .map(|h| h.size)
            .max()
            .unwrap_or(0);
        DeviceLimits {
            max_storage_buffer_range: limits.max_storage_buffer_range as u64,
            max_texel_buffer_elements: limits.max_texel_buffer_elements as u64,
            max_memory_allocation_size: max_alloc,
            device_memory,
        }
    }

    /// log2 of the most texels one part of a split scene array holds
    /// (`packed::bindings`): the largest power of two within
    /// `maxTexelBufferElements` whose 16-byte texels fit one allocation
    /// (`maxMemoryAllocationSize`). lavapipe: 2^27 texels, 2 GiB.
    pub fn scene_view_shift(&self) -> u32 {
        let texels = self
            .max_texel_buffer_elements
            .min(self.max_memory_allocation_size / 16)
            .max(2);
        (63 - texels.leading_zeros()).min(MAX_VIEW_SHIFT)
    }

    /// Checks that `bytes` of a split array (`name`) in parts of
    /// `part_bytes` take at most `SCENE_VIEWS` views.
    pub fn check_parts(&self, name: &str, bytes: u64, part_bytes: u64, texel: u64) -> Result<()> {
        let views = crate::packed::bindings::SCENE_VIEWS as u64;
        if bytes.div_ceil(part_bytes) > views {
            bail!(
                "the render needs {} of {}; this device's texel views hold {} each \
                 (maxTexelBufferElements of {texel} bytes, maxMemoryAllocationSize), and an \
                 array takes at most {views} of them, {} over{}",
                mib(bytes),
                describe(name),
                mib(part_bytes),
                mib(bytes - views * part_bytes),
                advice(name)
            );
        }
        Ok(())
    }

    /// Checks buffers against every limit; the error names the buffer, the
    /// limit and by how much it is exceeded.
    pub fn check(&self, buffers: &[BufferNeed]) -> Result<()> {
        for need in buffers {
            let (name, size) = (need.name, need.bytes);
            let what = describe(name);
            let over = |limit: u64, per: &str, field: &str| {
                format!(
                    "the render needs {} of {what} in one buffer; this device allows {} per {per} \
                     ({field}), {} over{}",
                    mib(size),
                    mib(limit),
                    mib(size - limit),
                    advice(name)
                )
            };
            if need.storage && size > self.max_storage_buffer_range {
                bail!(over(
                    self.max_storage_buffer_range,
                    "storage buffer",
                    "maxStorageBufferRange"
                ));
            }
            if let Some(texel) = need.texel_bytes {
                let limit = self.max_texel_buffer_elements * texel;
                if size > limit {
                    bail!(over(
                        limit,
                        "texel buffer",
                        &format!("maxTexelBufferElements of {texel} bytes")
                    ));
                }
            }
            if size > self.max_memory_allocation_size {
                bail!(over(
                    self.max_memory_allocation_size,
                    "allocation",
                    "maxMemoryAllocationSize"
                ));
            }
        }
        let total: u64 = buffers.iter().map(|b| b.bytes).sum();
        if total > self.device_memory {
            let textures: u64 = buffers
                .iter()
                .filter(|b| b.name == "texture_texels")
                .map(|b| b.bytes)
                .sum();
            let of_which = if textures > 0 {
                format!(" ({} of them textures)", mib(textures))
            } else {
                String::new()
            };
            bail!(
                "the render needs {} of device memory in all{of_which}; this device's largest \
                 memory heap has {}, {} over (render a smaller image or a smaller scene, or \
                 render on the CPU: --device cpu)",
                mib(total),
                mib(self.device_memory),
                mib(total - self.device_memory)
            );
        }
        Ok(())
    }
}

/// One buffer of a render, as the limits see it (each part of a split
/// array is one).
#[derive(Clone, Copy, Debug)]
pub struct BufferNeed<'a> {
    pub name: &'a str,
    pub bytes: u64,
    /// Bound as a storage buffer (`maxStorageBufferRange` applies).
    pub storage: bool,
    /// The texel size of a texel buffer view of it, if it has one.
    pub texel_bytes: Option<u64>,
}

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1024.0 * 1024.0))
}

/// What a buffer holds, in the user's words.
fn describe(name: &str) -> String {
    match name {
        "bvh_nodes" => "BVH nodes".into(),
        "tri_verts" => "triangle vertices".into(),
        "tri_shading" => "triangle normals and materials".into(),
        "materials" => "materials".into(),
        "emitters" => "emitters (light triangles)".into(),
        "film" => "image (film)".into(),
        "texture_texels" => "textures".into(),
        "tri_texcoords" => "per-triangle texture coordinates".into(),
        "motion_texels" => "vertex positions over the shutter".into(),
        other => format!("'{other}'"),
    }
}

fn advice(name: &str) -> &'static str {
    match name {
        "film" => " (render a smaller image)",
        "bvh_nodes" | "tri_verts" | "tri_shading" | "emitters" | "tri_texcoords" => {
            " (the scene has too many triangles for this device)"
        }
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIB: u64 = 1 << 20;

    fn limits() -> DeviceLimits {
        DeviceLimits {
            max_storage_buffer_range: 128 * MIB,
            max_texel_buffer_elements: 16 * MIB,
            max_memory_allocation_size: 1024 * MIB,
            device_memory: 2048 * MIB,
        }
    }

    /// A storage buffer read through RGBA32 texels (the scene arrays).
    fn viewed(name: &str, bytes: u64) -> BufferNeed<'_> {
        BufferNeed {
            name,
            bytes,
            storage: true,
            texel_bytes: Some(16),
        }
    }

    fn storage(name: &str, bytes: u64) -> BufferNeed<'_> {
        BufferNeed {
            texel_bytes: None,
            ..viewed(name, bytes)
        }
    }

    #[test]
    fn a_buffer_over_the_binding_limit_is_refused_with_the_excess() {
        let err = limits()
            .check(&[viewed("materials", MIB), viewed("bvh_nodes", 212 * MIB)])
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "the render needs 212.0 MiB of BVH nodes in one buffer; this device allows 128.0 MiB \
             per storage buffer (maxStorageBufferRange), 84.0 MiB over (the scene has too many \
             triangles for this device)"
        );
    }

    #[test]
    fn texel_allocation_and_memory_limits_are_checked() {
        let mut l = limits();
        l.max_storage_buffer_range = 4096 * MIB;
        let err = l.check(&[viewed("tri_verts", 300 * MIB)]).unwrap_err();
        assert!(err.to_string().contains("maxTexelBufferElements"), "{err}");
        assert!(l.check(&[storage("path_hit", 300 * MIB)]).is_ok());
        let err = l.check(&[storage("film", 1100 * MIB)]).unwrap_err();
        assert!(err.to_string().contains("maxMemoryAllocationSize"), "{err}");
        assert!(err.to_string().contains("76.0 MiB over"), "{err}");
        let many: Vec<_> = (0..3).map(|_| storage("path_hit", 1000 * MIB)).collect();
        let err = l.check(&many).unwrap_err();
        assert!(err.to_string().contains("952.0 MiB over"), "{err}");
        assert!(l.check(&many[..2]).is_ok());
    }

    #[test]
    fn a_texel_limit_counts_texels_of_the_views_size() {
        // 16 Mi texels: 64 MiB of 4-byte texels, 256 MiB of 16-byte ones.
        let texels = BufferNeed {
            name: "texture_texels",
            bytes: 100 * MIB,
            storage: false,
            texel_bytes: Some(4),
        };
        let err = limits().check(&[texels]).unwrap_err().to_string();
        assert!(
            err.contains("100.0 MiB of textures")
                && err.contains("64.0 MiB per texel buffer (maxTexelBufferElements of 4 bytes)"),
            "{err}"
        );
        // Not a storage buffer: maxStorageBufferRange (128 MiB) does not apply.
        let mut l = limits();
        l.max_texel_buffer_elements = 64 * MIB;
        let big = BufferNeed {
            bytes: 200 * MIB,
            ..texels
        };
        assert!(l.check(&[big]).is_ok());
    }

    #[test]
    fn parts_are_the_largest_power_of_two_views_within_one_allocation() {
        let mut l = limits();
        // 16 Mi texels, and 1 GiB / 16 bytes = 64 Mi: 2^24.
        assert_eq!(l.scene_view_shift(), 24);
        l.max_memory_allocation_size = 100 * MIB;
        // 6.25 Mi 16-byte texels in one allocation: 2^22.
        assert_eq!(l.scene_view_shift(), 22);
        l.max_texel_buffer_elements = u32::MAX as u64;
        l.max_memory_allocation_size = u64::MAX;
        assert_eq!(l.scene_view_shift(), MAX_VIEW_SHIFT);
    }

    #[test]
    fn an_array_beyond_its_views_is_refused_with_the_excess() {
        let l = limits();
        assert!(
            l.check_parts("tri_verts", 8 * 64 * MIB, 64 * MIB, 16)
                .is_ok()
        );
        let err = l
            .check_parts("tri_verts", 8 * 64 * MIB + MIB, 64 * MIB, 16)
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "the render needs 513.0 MiB of triangle vertices; this device's texel views hold \
             64.0 MiB each (maxTexelBufferElements of 16 bytes, maxMemoryAllocationSize), and an \
             array takes at most 8 of them, 1.0 MiB over (the scene has too many triangles for \
             this device)"
        );
    }
}
