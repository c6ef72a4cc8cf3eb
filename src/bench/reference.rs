//! The converged image a benchmark measures error against: rendered once at
//! high spp and cached as EXR, or given by the user (`--reference`).
//!
//! The cache key covers everything the image depends on: the scene file's
//! bytes, size, depth limit, camera, spp and `REFERENCE_VERSION` (bump it
//! when the estimator's expectation changes, e.g. a BSDF fix).

use crate::cache::{FNV_OFFSET, cache_dir, fnv1a};
use crate::image::Image;
use crate::image::{PngSettings, read_exr, write_image};
use crate::packed::settings::{RenderSettings, TextureFilter};
use anyhow::Context as _;
use std::path::{Path, PathBuf};

/// Version of the renderer's expectation; part of the cache key.
pub const REFERENCE_VERSION: u32 = 1;

/// The reference's seed: far from the seeds of the measured renders, whose
/// samples must be independent of the reference's (a shared seed would
/// share paths and make the error look smaller than it is).
pub const REFERENCE_SEED: u32 = 0x5EED_0001;

/// The cache file for a scene and settings (spp and seed included).
pub fn cache_path(scene_file: &Path, settings: &RenderSettings) -> anyhow::Result<PathBuf> {
    let dir = cache_dir().ok_or_else(|| {
        anyhow::anyhow!(
            "no cache directory (set HOME, XDG_CACHE_HOME or VKPT_CACHE_DIR) for the reference \
             image; give one (BenchConfig::reference)"
        )
    })?;
    let bytes = std::fs::read(scene_file)
        .with_context(|| format!("cannot read {}", scene_file.display()))?;
    let mut h = fnv1a(&bytes, FNV_OFFSET);
    let key = format!(
        "v{REFERENCE_VERSION} {}x{} depth {:?} camera {} spp {} seed {}",
        settings.width,
        settings.height,
        settings.max_depth,
        settings.camera,
        settings.spp,
        settings.seed
    );
    h = fnv1a(key.as_bytes(), h);
    // References made before mip-mapping are bilinear ones: their key stays.
    if settings.texture_filter == TextureFilter::Mip {
        h = fnv1a(b" texture-filter mip", h);
    }
    let stem = scene_file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(dir.join("references").join(format!(
        "{stem}-{}x{}-{}spp-{h:016x}.exr",
        settings.width, settings.height, settings.spp
    )))
}

/// Reads a reference and checks it fits the benchmark's image size.
pub fn load(path: &Path, width: u32, height: u32) -> anyhow::Result<Image> {
    let image = read_exr(path)?;
    anyhow::ensure!(
        (image.width, image.height) == (width, height),
        "{}: the reference is {}x{} but the benchmark renders {width}x{height} \
         (set BenchConfig::width and height to match)",
        path.display(),
        image.width,
        image.height
    );
    Ok(image)
}

/// Stores a freshly rendered reference.
pub fn store(path: &Path, image: &Image) -> anyhow::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    write_image(path, image, &PngSettings::default())
}
