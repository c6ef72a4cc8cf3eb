//! The glTF 2.0 loader (`.gltf` with external or data-URI buffers, and
//! `.glb`). What vkpt reads from a file, and the vkpt extras a file may
//! carry, are described in the README ("What vkpt reads from glTF", "vkpt
//! extras"); whatever else the file uses is listed in [`Scene::notes`], so
//! nothing is dropped without a word. A file without a camera gets one named
//! "auto" framed on the scene bounds; a scene without lights is lit by a
//! uniform white environment of radiance 1.
//!
//! The file is read through the `gltf` crate's typed document
//! (`document.rs`, checked by `validation.rs`); the file's JSON is kept for
//! what the crate does not model (vkpt's extras, extensions it does not
//! know). One file per job: `data` (file, GLB, buffers, accessors),
//! `materials` (+ `material_extras`), `textures` and `images`, `nodes`
//! (the walk, with `cameras`, `lights`, and `mesh` + `uv`), `origin` (the
//! world point every f32 position is measured from), `extensions`
//! (which are supported, required or reported); `json` and `notes` are
//! small helpers.

mod cameras;
mod data;
mod document;
mod extensions;
mod images;
mod json;
mod lights;
mod material_extras;
mod materials;
mod mesh;
mod nodes;
mod notes;
mod origin;
mod pbr_lobes;
mod spec_gloss;
mod textures;
mod uri;
mod uv;
mod validation;
mod variants;

use super::auto_camera;
use super::{LoadOptions, Scene};
use anyhow::{Context, Result, bail};
use document::Gltf;
use glam::Vec3;
use images::ImageLoader;
use nodes::SceneExtras;
use std::path::Path;
use textures::TextureLoader;

/// Loads a glTF 2.0 file into a [`Scene`]. Errors name the file and the
/// mesh / primitive / accessor / node concerned; no input makes it panic.
pub fn load_gltf(path: &Path) -> Result<Scene> {
    load_gltf_with(path, &LoadOptions::default())
}

/// [`load_gltf`] with the user's [`LoadOptions`].
pub fn load_gltf_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let scene =
        load(path, options).with_context(|| format!("{}: cannot load glTF", path.display()))?;
    if scene.triangles.is_empty() {
        bail!("{}: no triangles to render", path.display());
    }
    Ok(scene)
}

fn load(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let file = data::read_file(path)?;
    let mut gltf = Gltf::new(file.json)?;
    let base = path.parent().unwrap_or(Path::new("."));
    images::check_image_uris(&gltf, base, options.allow_outside_uris)?;
    let buffers = data::load_buffers(&gltf.doc, base, file.bin, options.allow_outside_uris)?;

    let mut scene = Scene {
        source: path.to_path_buf(),
        ..Scene::default()
    };
    let mut notes = Vec::new();
    gltf.variant = variants::choose_variant(&gltf, options.variant.as_deref(), &mut notes)?;

    let mut textures = TextureLoader::new(&gltf, ImageLoader::new(&gltf, base, &buffers));
    let (materials, spec_gloss) = materials::load_materials(&gltf, &mut textures, &mut notes)?;
    scene.images = textures.finish(&mut notes);
    scene.materials = materials;
    spec_gloss::convert_all(&spec_gloss, &mut scene, &mut notes);
    images::check_images(&gltf, base, &mut notes);
    extensions::note_unused_extensions(&gltf, &mut notes);

    let camera = options.camera.as_deref();
    let extras = nodes::walk_scene(&gltf, &buffers, camera, &mut scene, &mut notes)?;
    if scene.cameras.is_empty() {
        if let Some(cam) = auto_camera::frame_triangles(&scene.triangles) {
            notes.push(format!(
                "no camera in the file: added camera 'auto' ({}° vertical field of view, looking toward -Z at the scene bounds)",
                auto_camera::AUTO_CAMERA_YFOV_DEGREES
            ));
            scene.cameras.push(cam);
        }
    }
    light_the_scene(&mut scene, extras, base, &mut notes)?;
    scene.notes = notes;
    Ok(scene)
}

/// The environment from the scene extras, else, when nothing lights the
/// scene, a uniform white one (with a note).
fn light_the_scene(
    scene: &mut Scene,
    extras: SceneExtras,
    base: &Path,
    notes: &mut Vec<String>,
) -> Result<()> {
    if let Some(file) = &extras.environment_map {
        let map = super::EnvironmentMap::load(&base.join(file))
            .with_context(|| "scene extras vkpt.environment_map".to_string())?;
        scene.environment_map = Some(map);
        scene.environment = Some(extras.environment.unwrap_or(Vec3::ONE));
    } else if let Some(env) = extras.environment {
        scene.environment = Some(env);
    }
    scene.environment_rotation = extras.environment_rotation;
    scene.environment_hidden = extras.environment_hidden;
    // Surfaces whose emission comes from a texture are glowing details (a
    // helmet's displays), not lamps, and unlit surfaces show their colour:
    // on their own they still get the default light.
    let lamps = scene
        .triangles
        .iter()
        .filter(|t| {
            let m = &scene.materials[t.material as usize];
            m.is_emissive() && m.textures.emissive.is_none() && !m.unlit
        })
        .count();
    if scene.environment.is_none()
        && !scene.triangles.is_empty()
        && lamps == 0
        && scene.lights.is_empty()
    {
        scene.environment = Some(Vec3::ONE);
        notes.push(if scene.emissive_triangle_count() > 0 {
            "scene has no lights besides emissive-textured surfaces: also lit by a uniform white environment (radiance 1)".to_string()
        } else {
            "scene has no lights: lit by a uniform white environment (radiance 1)".to_string()
        });
    }
    Ok(())
}
