//! The header a render's EXR (and each checkpoint) carries: what it holds,
//! so parts rendered apart can be checked and merged (`film::merge`).

use crate::image::RenderHeader;
use crate::packed::PackedScene;
use crate::packed::content_hash::scene_hash_hex;
use crate::packed::settings::RenderSettings;
use crate::scene::Scene;

/// The header of a render of `settings` that has taken `spp` samples per
/// pixel so far (fewer than asked when stopped early or at a checkpoint),
/// on the back end named `backend`.
pub fn render_header(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    spp: u32,
    backend: &str,
) -> anyhow::Result<RenderHeader> {
    let params = packed.render_params(scene, settings, 0)?;
    let camera = &scene.cameras[settings.camera];
    Ok(RenderHeader {
        version: env!("CARGO_PKG_VERSION").to_string(),
        scene: scene.source.display().to_string(),
        scene_hash: scene_hash_hex(packed, &params),
        camera: camera.name.clone(),
        width: settings.width,
        height: settings.height,
        region: settings.film_region(),
        samples: settings.first_sample..settings.first_sample + spp,
        seed: settings.seed,
        sampler: settings.sampler.name().to_string(),
        filter: format!("{} {}", camera.filter.kind.name(), camera.filter.radius),
        max_depth: settings.max_depth,
        backend: backend.to_string(),
    })
}
