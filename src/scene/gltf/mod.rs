//! The glTF 2.0 loader (`.gltf` with external or data-URI buffers, and
//! `.glb`). What vkpt reads from a file, and the vkpt extras a file may
//! carry, are described in docs/gltf-support.md ("Extensions", "Core
//! glTF", "Details", "vkpt extras"); whatever else the file uses is
//! listed in [`Scene::notes`], so nothing is dropped without a word. A
//! file without a camera gets one named "auto" framed on the scene
//! bounds; a scene without lights is lit by a uniform white environment of
//! radiance 1.
//!
//! The file is read through the `gltf` crate's typed document
//! (`document.rs`, checked by `validation.rs`); the file's JSON is kept for
//! what the crate does not model (vkpt's extras, extensions it does not
//! know). One file per job: `data` (file, GLB, buffers, accessors;
//! `buffer`: a `.bin` mapped rather than read),
//! `materials` (+ `material_extras`), `textures` and `images`, `nodes`
//! (the walk, with `cameras`, `lights`, and `mesh` + `uv`), `origin` (the
//! world point every f32 position is measured from), `extensions`
//! (which are supported, required or reported), `compressed` (with
//! `draco` and `meshopt`: compressed geometry decoded into plain
//! accessors before anything reads them); `json` and `notes` are small
//! helpers.

mod animation;
mod buffer;
mod cameras;
mod compressed;
mod data;
mod decoder_panic;
mod document;
mod draco;
mod extensions;
mod images;
mod instancing;
mod json;
mod keyframes;
mod lights;
mod material_extras;
mod materials;
mod mesh;
mod meshopt;
mod nodes;
mod notes;
mod origin;
mod pbr_lobes;
mod skin;
mod spec_gloss;
mod textures;
mod uri;
mod uv;
mod validation;
mod variants;

use super::auto_camera;
use super::{LoadOptions, Scene};
use anyhow::{Context, Result, bail, ensure};
use buffer::Buffer;
use document::Gltf;
use glam::{DVec3, Vec3};
use images::ImageLoader;
use nodes::SceneExtras;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use textures::TextureLoader;

/// Loads a glTF 2.0 file into a [`Scene`]. Errors name the file and the
/// mesh / primitive / accessor / node concerned; no input makes it panic.
pub fn load_gltf(path: &Path) -> Result<Scene> {
    load_gltf_with(path, &LoadOptions::default())
}

/// [`load_gltf`] with the user's [`LoadOptions`]: the scene at
/// `options.time` under the animations `options.animation` selects.
pub fn load_gltf_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    GltfFile::open(path, options)?.at(options.time)
}

/// A glTF file read once (JSON, buffers, materials, textures, environment
/// map, animations) and posed at any instant with [`GltfFile::at`]: a
/// sequence or a shutter interval re-walks only the node hierarchy.
pub struct GltfFile {
    path: PathBuf,
    gltf: Gltf,
    buffers: Vec<Buffer>,
    roots: Vec<usize>,
    extras: SceneExtras,
    camera: Option<String>,
    instancing: crate::scene::InstancingMode,
    /// The scene without geometry, cameras or lights: materials, images,
    /// environment map.
    base: Scene,
    /// Notes that do not depend on the time.
    notes: Vec<String>,
    /// The animations that play, and how many the file has.
    playing: Vec<animation::Animation>,
    animation_count: usize,
}

impl GltfFile {
    /// Reads and checks the file; errors name it.
    pub fn open(path: &Path, options: &LoadOptions) -> Result<GltfFile> {
        Self::read(path, options).with_context(|| format!("{}: cannot load glTF", path.display()))
    }

    fn read(path: &Path, options: &LoadOptions) -> Result<GltfFile> {
        let file = data::read_file(path)?;
        let mut gltf = Gltf::new(file.json)?;
        let base_dir = path.parent().unwrap_or(Path::new("."));
        images::check_image_uris(&gltf, base_dir, options.allow_outside_uris)?;
        let mut buffers =
            data::load_buffers(&gltf.doc, base_dir, file.bin, options.allow_outside_uris)?;
        let mut base = Scene {
            source: path.to_path_buf(),
            ..Scene::default()
        };
        let mut notes = Vec::new();
        compressed::decode_geometry(&mut gltf, &mut buffers, &mut notes)?;
        gltf.variant = variants::choose_variant(&gltf, options.variant.as_deref(), &mut notes)?;
        let mut textures = TextureLoader::new(&gltf, ImageLoader::new(&gltf, base_dir, &buffers));
        let (materials, spec_gloss) = materials::load_materials(&gltf, &mut textures, &mut notes)?;
        base.materials = materials;
        base.images = textures.finish(&mut notes);
        spec_gloss::convert_all(&spec_gloss, &mut base, &mut notes);
        images::check_images(&gltf, base_dir, &mut notes);
        extensions::note_unused_extensions(&gltf, &mut notes);
        let (roots, extras) = nodes::scene_roots(&gltf, &mut notes)?;
        if let Some(file) = &extras.environment_map {
            let map = super::EnvironmentMap::load(&base_dir.join(file))
                .with_context(|| "scene extras vkpt.environment_map".to_string())?;
            base.environment_map = Some(map);
        }
        let all = animation::load_animations(&gltf, &buffers, &mut notes)?;
        let animation_count = all.len();
        let playing = animation::select(all, options.animation.as_deref())?;
        Ok(GltfFile {
            path: path.to_path_buf(),
            gltf,
            buffers,
            roots,
            extras,
            camera: options.camera.clone(),
            instancing: options.instancing,
            base,
            notes,
            playing,
            animation_count,
        })
    }

    /// Whether any animation plays (otherwise every time gives the same
    /// scene).
    pub fn is_animated(&self) -> bool {
        self.playing.iter().any(|a| !a.channels.is_empty())
    }

    /// Whether the animations that play change anything between `open`
    /// and `close` (some channel has keyframes on both sides of a moment
    /// inside): then a shutter over that interval blurs.
    pub fn moves_during(&self, open: f64, close: f64) -> bool {
        self.playing
            .iter()
            .flat_map(|a| a.channels.iter().map(|c| a.samplers[c.sampler].range()))
            .any(|(lo, hi)| hi > lo && open < hi && close > lo)
    }

    /// The scene at `time` seconds; errors name the file.
    pub fn at(&self, time: f64) -> Result<Scene> {
        self.at_from(time, None)
    }

    /// [`GltfFile::at`], with positions measured from `origin` instead of
    /// the render camera's position then (`Scene::world_origin`): the poses
    /// of one shutter share the first one's, or a moving camera would carry
    /// every light and still object along with it.
    pub fn at_from(&self, time: f64, origin: Option<DVec3>) -> Result<Scene> {
        self.posed(time, origin, self.instancing)
    }

    /// [`GltfFile::at_from`] with every placement copied (one level): the
    /// poses the kernels interpolate over a shutter (`scene::motion`)
    /// must hold the same triangles in the same order.
    pub fn at_from_in_one_level(&self, time: f64, origin: Option<DVec3>) -> Result<Scene> {
        self.posed(time, origin, crate::scene::InstancingMode::Off)
    }

    fn posed(
        &self,
        time: f64,
        origin: Option<DVec3>,
        instancing: crate::scene::InstancingMode,
    ) -> Result<Scene> {
        let scene = self
            .pose(time, origin, instancing)
            .with_context(|| format!("{}: cannot load glTF", self.path.display()))?;
        if scene.triangles.is_empty() {
            bail!("{}: no triangles to render", self.path.display());
        }
        Ok(scene)
    }

    fn pose(
        &self,
        time: f64,
        origin: Option<DVec3>,
        instancing: crate::scene::InstancingMode,
    ) -> Result<Scene> {
        ensure!(time.is_finite(), "time {time} s is not a finite number");
        let mut scene = self.base.clone();
        let mut notes = self.notes.clone();
        animation::describe(&self.playing, self.animation_count, time, &mut notes);
        let poses = animation::pose_at(&self.playing, self.gltf.doc.nodes().len(), time);
        nodes::walk_scene(
            &self.gltf,
            &self.buffers,
            &self.roots,
            &poses,
            self.camera.as_deref(),
            origin,
            instancing,
            &mut scene,
            &mut notes,
        )?;
        if scene.cameras.is_empty()
            && let Some(cam) = auto_camera::frame_scene(&scene)
        {
            notes.push(format!(
                    "no camera in the file: added camera 'auto' ({}° vertical field of view, looking toward -Z at the scene bounds)",
                    auto_camera::AUTO_CAMERA_YFOV_DEGREES
                ));
            scene.cameras.push(cam);
        }
        light_the_scene(&mut scene, &self.extras, &mut notes);
        scene.notes = notes;
        Ok(scene)
    }
}

/// The environment from the scene extras, else, when nothing lights the
/// scene, a uniform white one (with a note).
/// (The map itself was loaded by [`GltfFile::open`].)
fn light_the_scene(scene: &mut Scene, extras: &SceneExtras, notes: &mut Vec<String>) {
    if scene.environment_map.is_some() {
        scene.environment = Some(extras.environment.unwrap_or(Vec3::ONE));
    } else if let Some(env) = extras.environment {
        scene.environment = Some(env);
    }
    scene.environment_rotation = extras.environment_rotation;
    scene.environment_hidden = extras.environment_hidden;
    // Surfaces whose emission comes from a texture are glowing details (a
    // helmet's displays), not lamps, and unlit surfaces show their colour:
    // on their own they still get the default light. (On every core, and
    // done at the first lamp: a pass over 5 M triangles took 0.04 s.)
    let is_lamp = |t: &crate::scene::Triangle| {
        let m = &scene.materials[t.material as usize];
        m.is_emissive() && m.textures.emissive.is_none() && !m.unlit
    };
    if scene.environment.is_none()
        && !scene.triangles.is_empty()
        && scene.lights.is_empty()
        && !scene.triangles.par_iter().any(is_lamp)
    {
        scene.environment = Some(Vec3::ONE);
        notes.push(if scene.emissive_triangle_count() > 0 {
            "scene has no lights besides emissive-textured surfaces: also lit by a uniform white environment (radiance 1)".to_string()
        } else {
            "scene has no lights: lit by a uniform white environment (radiance 1)".to_string()
        });
    }
}
