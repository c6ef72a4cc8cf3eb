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
    /// `maxTexelBufferElements` × 16 bytes (vkpt's texels are RGBA32).
    pub max_texel_buffer_bytes: u64,
    /// `maxMemoryAllocationSize` (Vulkan 1.1): the largest single allocation.
    pub max_memory_allocation_size: u64,
    /// The largest device-local memory heap: all buffers together must fit.
    pub device_memory: u64,
}

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
            max_texel_buffer_bytes: limits.max_texel_buffer_elements as u64 * 16,
            max_memory_allocation_size: max_alloc,
            device_memory,
        }
    }

    /// Checks buffers `(name, bytes, read through a texel view)` against
    /// every limit; the error names the buffer, the limit and by how much
    /// it is exceeded.
    pub fn check(&self, buffers: &[(&str, u64, bool)]) -> Result<()> {
        for &(name, size, texel) in buffers {
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
            if size > self.max_storage_buffer_range {
                bail!(over(
                    self.max_storage_buffer_range,
                    "storage buffer",
                    "maxStorageBufferRange"
                ));
            }
            if texel && size > self.max_texel_buffer_bytes {
                bail!(over(
                    self.max_texel_buffer_bytes,
                    "texel buffer",
                    "maxTexelBufferElements of 16 bytes"
                ));
            }
            if size > self.max_memory_allocation_size {
                bail!(over(
                    self.max_memory_allocation_size,
                    "allocation",
                    "maxMemoryAllocationSize"
                ));
            }
        }
        let total: u64 = buffers.iter().map(|b| b.1).sum();
        if total > self.device_memory {
            bail!(
                "the render needs {} of device memory in all; this device's largest memory heap \
                 has {}, {} over (render a smaller image or a smaller scene)",
                mib(total),
                mib(self.device_memory),
                mib(total - self.device_memory)
            );
        }
        Ok(())
    }
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
        other => format!("'{other}'"),
    }
}

fn advice(name: &str) -> &'static str {
    match name {
        "film" => " (render a smaller image)",
        "bvh_nodes" | "tri_verts" | "tri_shading" | "emitters" => {
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
            max_texel_buffer_bytes: 256 * MIB,
            max_memory_allocation_size: 1024 * MIB,
            device_memory: 2048 * MIB,
        }
    }

    #[test]
    fn a_buffer_over_the_binding_limit_is_refused_with_the_excess() {
        let err = limits()
            .check(&[("materials", MIB, true), ("bvh_nodes", 212 * MIB, true)])
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
        let err = l.check(&[("tri_verts", 300 * MIB, true)]).unwrap_err();
        assert!(err.to_string().contains("maxTexelBufferElements"), "{err}");
        assert!(l.check(&[("path_hit", 300 * MIB, false)]).is_ok());
        let err = l.check(&[("film", 1100 * MIB, false)]).unwrap_err();
        assert!(err.to_string().contains("maxMemoryAllocationSize"), "{err}");
        assert!(err.to_string().contains("76.0 MiB over"), "{err}");
        let many: Vec<_> = (0..3).map(|_| ("path_hit", 1000 * MIB, false)).collect();
        let err = l.check(&many).unwrap_err();
        assert!(err.to_string().contains("952.0 MiB over"), "{err}");
        assert!(l.check(&many[..2]).is_ok());
    }
}
