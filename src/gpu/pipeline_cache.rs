//! A `VkPipelineCache` kept on disk between runs, so a driver that caches
//! compiled kernels does not compile them again.
//!
//! The file is `<cache dir>/pipelines-<vendor>-<device>-<cache uuid>-<driver
//! uuid>.bin`: the driver promises to read back only data written under the
//! same `pipelineCacheUUID`, and the name keeps different drivers' files
//! apart. The data's header is checked against the device before it is
//! handed to the driver (Vulkan spec, "Pipeline Cache Header"), since not
//! every driver survives foreign data.

use super::context::Context;
use crate::cache::{cache_dir, write_atomically};
use ash::vk;
use std::path::PathBuf;

/// What the cache file held when the renderer started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CacheUse {
    /// No cache directory (`VKPT_CACHE_DIR` empty, no `HOME`).
    Off,
    /// No usable file yet: kernels were compiled and the file written.
    Miss,
    /// A file from an earlier run, with this many bytes, was loaded.
    Loaded(usize),
}

pub struct PipelineCache {
    pub cache: vk::PipelineCache,
    path: Option<PathBuf>,
    pub used: CacheUse,
}

/// Header version one: length, version, vendor ID, device ID, cache UUID.
pub const HEADER_BYTES: usize = 32;

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// True when `data` starts with a version-one header written by this device.
fn header_matches(data: &[u8], props: &vk::PhysicalDeviceProperties) -> bool {
    if data.len() < HEADER_BYTES {
        return false;
    }
    let word = |i: usize| u32::from_le_bytes([data[i], data[i + 1], data[i + 2], data[i + 3]]);
    word(0) as usize >= HEADER_BYTES
        && word(4) == vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32
        && word(8) == props.vendor_id
        && word(12) == props.device_id
        && data[16..32] == props.pipeline_cache_uuid
}

impl PipelineCache {
    /// Opens the cache for this device. Never fails because of the file:
    /// an unreadable or foreign file means compiling afresh.
    pub fn open(ctx: &Context) -> anyhow::Result<PipelineCache> {
        let props = &ctx.properties;
        let path = cache_dir().map(|dir| {
            dir.join(format!(
                "pipelines-{:04x}-{:04x}-{}-{}.bin",
                props.vendor_id,
                props.device_id,
                hex(&props.pipeline_cache_uuid),
                hex(&ctx.driver_uuid),
            ))
        });
        let data = path
            .as_ref()
            .and_then(|p| std::fs::read(p).ok())
            .filter(|d| header_matches(d, props));
        let used = match (&path, &data) {
            (None, _) => CacheUse::Off,
            (Some(_), None) => CacheUse::Miss,
            (Some(_), Some(d)) => CacheUse::Loaded(d.len()),
        };
        let info =
            vk::PipelineCacheCreateInfo::default().initial_data(data.as_deref().unwrap_or(&[]));
        // SAFETY: valid device; the initial data's header was checked above.
        let cache = unsafe { ctx.device.create_pipeline_cache(&info, None) }?;
        Ok(PipelineCache { cache, path, used })
    }

    /// Writes the cache's current contents to its file. A failure to write
    /// costs only the next run's compile time, so it is reported, not fatal.
    pub fn save(&self, ctx: &Context) {
        let Some(path) = &self.path else { return };
        // SAFETY: the cache was made from this device.
        let data = match unsafe { ctx.device.get_pipeline_cache_data(self.cache) } {
            Ok(d) => d,
            Err(e) => {
                eprintln!("note: could not read the pipeline cache back ({e}); not saved");
                return;
            }
        };
        if let Err(e) = write_atomically(path, &data) {
            eprintln!(
                "note: could not save the pipeline cache to {} ({e})",
                path.display()
            );
        }
    }

    pub fn destroy(&mut self, ctx: &Context) {
        // SAFETY: no pipeline creation uses the cache any more.
        unsafe { ctx.device.destroy_pipeline_cache(self.cache, None) };
        self.cache = vk::PipelineCache::null();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pipeline_cache_header_must_match_the_device() {
        let props = vk::PhysicalDeviceProperties {
            vendor_id: 0x10005,
            device_id: 7,
            pipeline_cache_uuid: [3; vk::UUID_SIZE],
            ..Default::default()
        };
        let mut data = Vec::new();
        for word in [32u32, 1, 0x10005, 7] {
            data.extend_from_slice(&word.to_le_bytes());
        }
        data.extend_from_slice(&[3; vk::UUID_SIZE]);
        data.extend_from_slice(b"driver data");
        assert!(header_matches(&data, &props));
        assert!(!header_matches(&data[..31], &props), "truncated");
        let mut other = data.clone();
        other[20] = 4;
        assert!(!header_matches(&other, &props), "another driver's UUID");
        let mut other = data.clone();
        other[12] = 8;
        assert!(!header_matches(&other, &props), "another device");
        let mut other = data;
        other[4] = 2;
        assert!(!header_matches(&other, &props), "an unknown header version");
    }
}
