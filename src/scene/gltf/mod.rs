//! The glTF 2.0 loader (`.gltf` with external or data-URI buffers, and `.glb`).
//!
//! What is read: the default scene (or the first) with its node hierarchy
//! (matrix or TRS transforms), `TRIANGLES` / `TRIANGLE_STRIP` /
//! `TRIANGLE_FAN` primitives (indexed or not, sparse accessors included),
//! vertex normals (flat normals when a primitive has none), materials
//! (glTF metallic-roughness with `KHR_materials_specular`, `_transmission`,
//! `_ior` and `_volume`; `emissiveFactor` times
//! `KHR_materials_emissive_strength` as emission, `doubleSided`; mirrors,
//! glass and Phong as described under "vkpt material extras") and
//! perspective and orthographic cameras (with a thin lens as described under
//! "vkpt camera extras"). Everything else the file uses is listed in
//! [`Scene::notes`]; nothing is dropped without a word.
//!
//! Defaults: a file without a camera gets one named "auto"
//! framed on the scene bounds; a scene without an emissive surface is lit by
//! a uniform white environment of radiance 1.
//!
//! # vkpt scene extras
//!
//! A glTF scene object may carry vkpt settings in its `extras`:
//!
//! ```json
//! "scenes": [{
//!   "nodes": [0, 1],
//!   "extras": { "vkpt": { "environment": [1.0, 1.0, 1.0] } }
//! }]
//! ```
//!
//! - `vkpt.environment`: `[r, g, b]`, the uniform radiance of the
//!   environment seen by rays that leave the scene (linear, non-negative,
//!   finite). When given, it is used as is (also in scenes with emissive
//!   surfaces) and no default light is added; `[0, 0, 0]` means a black
//!   environment.
//!
//! - `vkpt.environment_map`: an equirectangular `.exr` or `.hdr` file
//!   (relative to the glTF file) lighting the scene, importance sampled; row
//!   0 is straight up (+Y) and the map's centre faces -Z.
//!   `vkpt.environment` then scales its texels (default `[1, 1, 1]`).
//! - `vkpt.environment_rotation`: degrees the map turns about +Y.
//! - `vkpt.environment_hidden`: `true` makes camera rays that leave the
//!   scene see black; the environment still lights the scene.
//!
//! Anything else under `vkpt` is reported in a note and ignored; a malformed
//! value is an error.
//!
//! # Lights (KHR_lights_punctual)
//!
//! Point, spot and directional lights are placed by their node (position,
//! -Z as the direction). Intensities are used as given in the scene's linear
//! units, as the Khronos sample viewer does: candela as radiant intensity
//! (W/sr), lux as irradiance (W/m^2), no 683 lm/W factor. `range` applies the
//! extension's window max(min(1 - (d/range)^4, 1), 0); spot cones fall off
//! as the extension defines (clamp(cos * scale + offset, 0, 1)^2). A light's
//! `extras` may make it an area light:
//!
//! ```json
//! "extras": { "vkpt": { "radius": 0.05 } }              // point light -> sphere
//! "extras": { "vkpt": { "angular_diameter": 0.0093 } }  // directional -> sun disk (radians)
//! ```
//!
//! The sphere keeps the point light's intensity I in every direction
//! (radiance I / (pi r^2)); the sun disk keeps the directional light's
//! irradiance E on a surface facing it (radiance E / (pi sin^2(d / 2))).
//!
//! # vkpt camera extras
//!
//! A glTF camera may carry a thin lens, shutter time and ISO in its
//! `extras` (lengths in scene units, metres for glTF):
//!
//! ```json
//! "cameras": [{
//!   "type": "perspective", "perspective": { "yfov": 0.4, "znear": 0.01 },
//!   "extras": { "vkpt": {
//!     "lens": { "focal_length": 0.05, "fstop": 2.8, "focus_distance": 3.0,
//!               "sensor_height": 0.024, "blades": 6, "blade_rotation": 0 },
//!     "shutter": 0.01, "iso": 100 } }
//! }]
//! ```
//!
//! - `lens.fstop`: the f-number N (>= 0); 0 or absent means a pinhole.
//!   The aperture's diameter is focal length / N in scene units.
//! - `lens.focus_distance`: distance of the plane in focus along the view
//!   axis (> 0; required when N > 0).
//! - `lens.focal_length`: in scene units (0.05 is 50 mm). The field of view
//!   is always `yfov`: the focal length sets only the aperture. When absent
//!   it is derived from `yfov` and `lens.sensor_height` (default 0.024, a
//!   full-frame sensor) as h / (2 tan(yfov / 2)), with a note. When both
//!   are given and disagree with `yfov` by more than 1%, a note says that
//!   `yfov` wins.
//! - `lens.blades`: 0 (a round aperture) or 3 to 64 straight blades (a
//!   regular polygon inscribed in the aperture circle); `blade_rotation`:
//!   degrees from the camera's right axis toward its up axis to the first
//!   polygon vertex.
//! - `shutter` (seconds) and `iso`: with the f-number they set the PNG
//!   exposure (EV100; see `output::exposure_from_camera`).
//!
//! Command-line flags override each value. A lens on an orthographic camera
//! is ignored with a note. Unknown keys are reported in notes; malformed
//! values are errors naming the camera.
//!
//! # vkpt material extras
//!
//! A material may pick one of vkpt's scattering models in its `extras`
//! (at most one key of `phong`, `mirror`, `dielectric`; colours are linear,
//! non-negative `[r, g, b]`):
//!
//! ```json
//! "extras": { "vkpt": { "phong": { "kd": [0.1, 0.15, 0.5], "ks": [0.5, 0.5, 0.5], "n": 60 } } }
//! "extras": { "vkpt": { "mirror": { "tint": [0.9, 0.9, 0.9] } } }
//! "extras": { "vkpt": { "dielectric": { "ior": 0.75, "tint": [1, 1, 1] } } }
//! ```
//!
//! - `phong`: diffuse `kd` (default `baseColorFactor`), specular `ks` and
//!   shininess `n` (both required): f = kd/π + ks (n + 2)/(2π) cos^n α, α
//!   measured from the mirror direction. Where kd + ks > 1 in a channel both
//!   are scaled to sum to 1 and a `warning:` note names the material.
//! - `mirror`: perfect reflection tinted by `tint` (default
//!   `baseColorFactor`).
//! - `dielectric`: smooth glass, a closed volume of relative index `ior`
//!   (inside over outside, default 1.5, any value above 0: below 1 is, say,
//!   an air bubble in water), refraction tinted by `tint` (default
//!   `baseColorFactor`).
//!
//! Unknown keys are reported in notes; malformed values are errors naming
//! the material. Without extras, glTF's own description is used
//! (`MaterialKind::Gltf`): metallic 1 with roughness 0 is the mirror (tint
//! `baseColorFactor`), a non-metal without transmission and with
//! specularFactor 0 is exactly Lambertian; `KHR_materials_transmission` is
//! glass of `KHR_materials_ior` (default 1.5), a closed refractive volume
//! with `KHR_materials_volume` thickness > 0 (absorbing per
//! attenuationColor / attenuationDistance inside), otherwise thin-walled
//! (no bending), as the extensions say.

mod data;
mod textures;
mod uri;

use super::auto_camera;
use super::camera::{check_blades, check_length};
use super::tangents::generate_tangents;
use super::texture::Texcoords;
use super::{
    AlphaMode, Camera, Light, LightKind, LoadOptions, Material, MaterialKind, Projection, Scene,
    Triangle,
};
use anyhow::{Context, Result, anyhow, bail, ensure};
use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use data as gltf_data;
use data::{array, element, name_suffix};
use textures::ImageLoader;

/// Extensions a file may *require* and still be rendered meaningfully.
fn required_extension_supported(name: &str) -> bool {
    matches!(
        name,
        "KHR_materials_emissive_strength" | "KHR_lights_punctual" | "KHR_texture_transform"
    ) || name.starts_with("KHR_materials_")
}

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

/// Notes that are gathered per subject and emitted once, listing the subjects.
#[derive(Default)]
struct Grouped(BTreeMap<String, Vec<String>>);

impl Grouped {
    fn add(&mut self, key: impl Into<String>, subject: impl Into<String>) {
        let v = self.0.entry(key.into()).or_default();
        let s = subject.into();
        if !v.contains(&s) {
            v.push(s);
        }
    }
}

/// `'a', 'b', 'c' and 4 more`.
fn list(items: &[String]) -> String {
    const MAX: usize = 5;
    let shown = items
        .iter()
        .take(MAX)
        .map(|s| format!("'{s}'"))
        .collect::<Vec<_>>()
        .join(", ");
    if items.len() > MAX {
        format!("{shown} and {} more", items.len() - MAX)
    } else {
        shown
    }
}

fn plural(n: usize, one: &str, many: &str) -> String {
    if n == 1 {
        format!("1 {one}")
    } else {
        format!("{n} {many}")
    }
}

fn load(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let file = gltf_data::read_file(path)?;
    let json = &file.json;
    ensure!(
        json.is_object(),
        "the top-level JSON value is not an object"
    );
    let version = json
        .get("asset")
        .and_then(|a| a.get("version"))
        .and_then(Value::as_str)
        .unwrap_or("");
    ensure!(
        version.starts_with("2."),
        "asset.version is {version:?}: vkpt reads glTF 2.0"
    );
    for ext in array(json, "extensionsRequired") {
        let name = ext.as_str().unwrap_or("?");
        ensure!(
            required_extension_supported(name),
            "the file requires extension {name}, which vkpt does not support"
        );
    }
    let base = path.parent().unwrap_or(Path::new("."));
    check_image_uris(json, base, options.allow_outside_uris)?;
    let buffers = gltf_data::load_buffers(json, base, file.bin, options.allow_outside_uris)?;

    let mut scene = Scene {
        source: path.to_path_buf(),
        ..Scene::default()
    };
    let mut notes = Vec::new();

    let mut image_loader = ImageLoader::new(json, base, &buffers);
    let materials = load_materials(json, &mut image_loader, &mut notes)?;
    scene.images = image_loader.finish(&mut notes);
    scene.materials = materials;
    check_images(json, base, &mut notes);
    note_unused_extensions(json, &mut notes);

    let walk = walk_scene(json, &buffers, &mut scene, &mut notes)?;

    // Cameras.
    if scene.cameras.is_empty() {
        if let Some(cam) = auto_camera::frame_triangles(&scene.triangles) {
            notes.push(format!(
                "no camera in the file: added camera 'auto' ({}° vertical field of view, looking toward -Z at the scene bounds)",
                auto_camera::AUTO_CAMERA_YFOV_DEGREES
            ));
            scene.cameras.push(cam);
        }
    }

    // Lights and environment.
    if let Some(file) = &walk.extras.environment_map {
        let map = super::EnvironmentMap::load(&base.join(file))
            .with_context(|| "scene extras vkpt.environment_map".to_string())?;
        scene.environment_map = Some(map);
        scene.environment = Some(walk.extras.environment.unwrap_or(Vec3::ONE));
    } else if let Some(env) = walk.extras.environment {
        scene.environment = Some(env);
    }
    scene.environment_rotation = walk.extras.environment_rotation;
    scene.environment_hidden = walk.extras.environment_hidden;
    // Surfaces whose emission comes from a texture are glowing details (a
    // helmet's displays), not lamps: on their own they still get the
    // default light.
    let lamps = scene
        .triangles
        .iter()
        .filter(|t| {
            let m = &scene.materials[t.material as usize];
            m.is_emissive() && m.textures.emissive.is_none()
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
    scene.notes = notes;
    Ok(scene)
}

fn f32_array<const N: usize>(v: Option<&Value>, what: &str) -> Result<Option<[f32; N]>> {
    let Some(v) = v else { return Ok(None) };
    let arr = v
        .as_array()
        .filter(|a| a.len() == N)
        .ok_or_else(|| anyhow!("{what} is not an array of {N} numbers: {v}"))?;
    let mut out = [0.0f32; N];
    for (o, x) in out.iter_mut().zip(arr) {
        *o = x
            .as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite())
            .ok_or_else(|| anyhow!("{what} is not an array of {N} finite numbers: {v}"))?;
    }
    Ok(Some(out))
}

fn index(v: Option<&Value>, what: &str) -> Result<Option<usize>> {
    match v {
        None | Some(Value::Null) => Ok(None),
        Some(v) => v
            .as_u64()
            .map(|u| Some(u as usize))
            .ok_or_else(|| anyhow!("{what} is not a non-negative integer: {v}")),
    }
}

fn material_name(m: &Value, i: usize) -> String {
    m.get("name")
        .and_then(Value::as_str)
        .map(str::to_string)
        .unwrap_or_else(|| format!("material #{i}"))
}

/// Texture slots that are rendered (or, for occlusion, deliberately left
/// to the path tracer).
const RENDERED_TEXTURE_SLOTS: [&str; 8] = [
    "baseColorTexture",
    "metallicRoughnessTexture",
    "normalTexture",
    "occlusionTexture",
    "emissiveTexture",
    "specularTexture",
    "specularColorTexture",
    "transmissionTexture",
];

/// Every texture reference in a material: (slot name such as
/// "baseColorTexture", texture index). Extension slots are found too.
fn texture_slots(v: &Value, out: &mut Vec<(String, Option<u64>)>) {
    if let Value::Object(map) = v {
        for (k, child) in map {
            if k.ends_with("Texture") && child.is_object() {
                out.push((k.clone(), child.get("index").and_then(Value::as_u64)));
            }
            texture_slots(child, out);
        }
    }
}

fn non_negative(v: Option<&Value>, what: &str) -> Result<Option<f32>> {
    match v {
        None => Ok(None),
        Some(v) => v
            .as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite() && *f >= 0.0)
            .map(Some)
            .ok_or_else(|| anyhow!("{what} is not a finite non-negative number: {v}")),
    }
}

fn rgb(v: Option<&Value>, what: &str) -> Result<Option<Vec3>> {
    let Some(c) = f32_array::<3>(v, what)?.map(Vec3::from) else {
        return Ok(None);
    };
    ensure!(
        c.min_element() >= 0.0,
        "{what} has a negative component: {c}"
    );
    Ok(Some(c))
}

fn positive_ior(v: Option<&Value>, what: &str) -> Result<f32> {
    let ior = non_negative(v, what)?.unwrap_or(1.5);
    ensure!(ior > 0.0, "{what} must be above 0, found {ior}");
    Ok(ior)
}

/// Sets `material`'s scattering model from the vkpt material extras, else
/// from glTF (transmission -> dielectric, metallic 1 roughness 0 -> mirror);
/// returns the material extensions it rendered.
fn scattering(
    m: &Value,
    label: &str,
    spec_gloss: bool,
    material: &mut Material,
    notes: &mut Vec<String>,
) -> Result<Vec<&'static str>> {
    let name = material.name.clone();
    if let Some(vkpt) = m.get("extras").and_then(|e| e.get("vkpt")) {
        let obj = vkpt
            .as_object()
            .ok_or_else(|| anyhow!("{label}: extras \"vkpt\" must be an object, found {vkpt}"))?;
        let models: Vec<&String> = obj
            .keys()
            .filter(|k| ["phong", "mirror", "dielectric"].contains(&k.as_str()))
            .collect();
        ensure!(
            models.len() <= 1,
            "{label}: extras vkpt names more than one material model ({models:?})"
        );
        for key in obj.keys() {
            if !models.contains(&key) {
                notes.push(format!(
                    "material '{name}': extras vkpt.{key} is not understood: ignored"
                ));
            }
        }
        if let Some(model) = models.first() {
            let p = &obj[model.as_str()];
            ensure!(
                p.is_object(),
                "{label}: extras vkpt.{model} must be an object, found {p}"
            );
            let what = |k: &str| format!("{label}: extras vkpt.{model}.{k}");
            for key in p.as_object().into_iter().flat_map(|o| o.keys()) {
                let known: &[&str] = match model.as_str() {
                    "phong" => &["kd", "ks", "n"],
                    "mirror" => &["tint"],
                    _ => &["ior", "tint"],
                };
                if !known.contains(&key.as_str()) {
                    notes.push(format!(
                        "material '{name}': extras vkpt.{model}.{key} is not understood: ignored"
                    ));
                }
            }
            match model.as_str() {
                "phong" => {
                    let kd = rgb(p.get("kd"), &what("kd"))?.unwrap_or(material.base_color);
                    let ks = rgb(p.get("ks"), &what("ks"))?
                        .ok_or_else(|| anyhow!("{} is missing", what("ks")))?;
                    let n = non_negative(p.get("n"), &what("n"))?
                        .ok_or_else(|| anyhow!("{} is missing", what("n")))?;
                    let sum = kd + ks;
                    let (mut kd, mut ks) = (kd, ks);
                    if sum.max_element() > 1.0 {
                        let s = Vec3::select(sum.cmpgt(Vec3::ONE), Vec3::ONE / sum, Vec3::ONE);
                        kd *= s;
                        ks *= s;
                        notes.push(format!(
                            "warning: material '{name}': Phong kd + ks = {sum} is above 1 (it would create energy): \
                             scaled down to kd {kd}, ks {ks}"
                        ));
                    }
                    material.kind = MaterialKind::Phong;
                    material.base_color = kd;
                    material.specular = ks;
                    material.shininess = n;
                }
                "mirror" => {
                    material.kind = MaterialKind::Mirror;
                    material.base_color =
                        rgb(p.get("tint"), &what("tint"))?.unwrap_or(material.base_color);
                }
                _ => {
                    // Smooth clear glass: the glTF model's closed volume.
                    material.kind = MaterialKind::Gltf;
                    material.ior = positive_ior(p.get("ior"), &what("ior"))?;
                    material.base_color =
                        rgb(p.get("tint"), &what("tint"))?.unwrap_or(material.base_color);
                    material.metallic = 0.0;
                    material.roughness = 0.0;
                    material.transmission = 1.0;
                    material.thickness = 1.0;
                    material.specular_factor = 1.0;
                    material.specular_color = Vec3::ONE;
                }
            }
            return Ok(Vec::new());
        }
    }

    if spec_gloss {
        return Ok(Vec::new());
    }
    metallic_roughness(m, label, material)
}

fn unit_interval(v: Option<&Value>, what: &str, default: f32) -> Result<f32> {
    let x = non_negative(v, what)?.unwrap_or(default);
    ensure!(x <= 1.0, "{what} must be between 0 and 1, found {x}");
    Ok(x)
}

/// glTF metallic-roughness with `KHR_materials_specular`, `_transmission`,
/// `_ior` and `_volume` (MaterialKind::Gltf). Two parameter cases get
/// their exact, cheaper kinds: metallic 1 with roughness 0 (and no
/// metallic-roughness texture) is the tinted mirror, and a non-metal without
/// transmission whose specularFactor is 0 is Lambertian.
fn metallic_roughness(
    m: &Value,
    label: &str,
    material: &mut Material,
) -> Result<Vec<&'static str>> {
    let ext = |e: &str| m.get("extensions").and_then(|x| x.get(e));
    let pbr = m.get("pbrMetallicRoughness");
    let get = |key: &str| pbr.and_then(|p| p.get(key));
    let what = |key: &str| format!("{label}: {key}");
    material.metallic = unit_interval(get("metallicFactor"), &what("metallicFactor"), 1.0)?;
    material.roughness = unit_interval(get("roughnessFactor"), &what("roughnessFactor"), 1.0)?;

    let transmission = ext("KHR_materials_transmission");
    material.transmission = unit_interval(
        transmission.and_then(|t| t.get("transmissionFactor")),
        &what("KHR_materials_transmission transmissionFactor"),
        0.0,
    )?;
    material.ior = positive_ior(
        ext("KHR_materials_ior").and_then(|i| i.get("ior")),
        &what("KHR_materials_ior ior"),
    )?;
    let specular = ext("KHR_materials_specular");
    material.specular_factor = unit_interval(
        specular.and_then(|s| s.get("specularFactor")),
        &what("KHR_materials_specular specularFactor"),
        1.0,
    )?;
    material.specular_color = rgb(
        specular.and_then(|s| s.get("specularColorFactor")),
        &what("KHR_materials_specular specularColorFactor"),
    )?
    .unwrap_or(Vec3::ONE);
    let volume = ext("KHR_materials_volume");
    material.thickness = non_negative(
        volume.and_then(|v| v.get("thicknessFactor")),
        &what("KHR_materials_volume thicknessFactor"),
    )?
    .unwrap_or(0.0);
    let distance = non_negative(
        volume.and_then(|v| v.get("attenuationDistance")),
        &what("KHR_materials_volume attenuationDistance"),
    )?;
    let color = rgb(
        volume.and_then(|v| v.get("attenuationColor")),
        &what("KHR_materials_volume attenuationColor"),
    )?
    .unwrap_or(Vec3::ONE);
    ensure!(
        color.max_element() <= 1.0,
        "{label}: KHR_materials_volume attenuationColor must be at most 1, found {color}"
    );
    // Beer–Lambert: attenuationColor is what remains after
    // attenuationDistance, so the coefficient is -ln(color) / distance.
    material.attenuation = match distance {
        Some(d) if d > 0.0 => {
            let c = color.max(Vec3::splat(1e-6));
            Vec3::new(-c.x.ln(), -c.y.ln(), -c.z.ln()) / d
        }
        _ => Vec3::ZERO,
    };

    let mr_texture = pbr.is_some_and(|p| p.get("metallicRoughnessTexture").is_some());
    material.kind = if material.metallic == 1.0
        && material.roughness == 0.0
        && material.transmission == 0.0
        && !mr_texture
    {
        MaterialKind::Mirror
    } else if material.metallic == 0.0
        && material.transmission == 0.0
        && material.specular_factor == 0.0
    {
        MaterialKind::Lambert
    } else {
        MaterialKind::Gltf
    };
    Ok(vec![
        "KHR_materials_transmission",
        "KHR_materials_ior",
        "KHR_materials_volume",
        "KHR_materials_specular",
    ])
}

fn load_materials(
    json: &Value,
    images: &mut ImageLoader,
    notes: &mut Vec<String>,
) -> Result<Vec<Material>> {
    let mut out = Vec::new();
    let mut textured = Grouped::default();
    let mut extensions = Grouped::default();
    let mut blended = Vec::new();
    let mut emissive_textured = Vec::new();
    for (i, m) in array(json, "materials").iter().enumerate() {
        let name = material_name(m, i);
        let label = format!("material #{i}{}", name_suffix(m));
        let pbr = m.get("pbrMetallicRoughness");
        let base = f32_array::<4>(
            pbr.and_then(|p| p.get("baseColorFactor")),
            "baseColorFactor",
        )
        .with_context(|| label.clone())?;
        let spec_gloss = m
            .get("extensions")
            .and_then(|e| e.get("KHR_materials_pbrSpecularGlossiness"));
        let diffuse = f32_array::<4>(
            spec_gloss.and_then(|s| s.get("diffuseFactor")),
            "diffuseFactor",
        )
        .with_context(|| label.clone())?;
        let base_color = match (base, diffuse) {
            (Some(b), _) => Vec3::new(b[0], b[1], b[2]),
            (None, Some(d)) => Vec3::new(d[0], d[1], d[2]),
            (None, None) => Vec3::ONE,
        };
        ensure!(
            base_color.min_element() >= 0.0,
            "{label}: baseColorFactor has a negative component"
        );
        let emissive = f32_array::<3>(m.get("emissiveFactor"), "emissiveFactor")
            .with_context(|| label.clone())?
            .map(Vec3::from)
            .unwrap_or(Vec3::ZERO);
        let strength = match m
            .get("extensions")
            .and_then(|e| e.get("KHR_materials_emissive_strength"))
            .and_then(|e| e.get("emissiveStrength"))
        {
            None => 1.0,
            Some(v) => v
                .as_f64()
                .map(|f| f as f32)
                .filter(|f| f.is_finite() && *f >= 0.0)
                .ok_or_else(|| {
                    anyhow!("{label}: emissiveStrength is not a non-negative number: {v}")
                })?,
        };
        let textures = images.material_textures(m, &name, notes);
        let mut emission = emissive * strength;
        if m.get("emissiveTexture").is_some()
            && textures.emissive.is_none()
            && emission != Vec3::ZERO
        {
            // The factor only scales the texture; without the texture the
            // whole surface would glow at full strength, which is worse than
            // not glowing.
            emission = Vec3::ZERO;
            emissive_textured.push(name.clone());
        }
        ensure!(
            emission.min_element() >= 0.0 && emission.is_finite(),
            "{label}: emission {emission} is negative or not finite"
        );
        let double_sided = m
            .get("doubleSided")
            .and_then(Value::as_bool)
            .unwrap_or(false);

        let alpha_mode = match m.get("alphaMode") {
            None => AlphaMode::Opaque,
            Some(mode) => match mode.as_str() {
                Some("OPAQUE") => AlphaMode::Opaque,
                Some("MASK") => AlphaMode::Mask {
                    cutoff: non_negative(m.get("alphaCutoff"), &format!("{label}: alphaCutoff"))?
                        .unwrap_or(0.5),
                },
                Some("BLEND") => {
                    blended.push(name.clone());
                    AlphaMode::Blend
                }
                _ => bail!("{label}: alphaMode must be OPAQUE, MASK or BLEND, found {mode}"),
            },
        };
        let normal_scale = match m.get("normalTexture").and_then(|t| t.get("scale")) {
            None => 1.0,
            Some(v) => v
                .as_f64()
                .map(|f| f as f32)
                .filter(|f| f.is_finite())
                .ok_or_else(|| anyhow!("{label}: normalTexture.scale is not a number: {v}"))?,
        };
        let mut material = Material {
            base_color,
            emission,
            double_sided,
            alpha: base.or(diffuse).map_or(1.0, |c| c[3]),
            alpha_mode,
            normal_scale,
            textures,
            ..Material::lambert(&name, base_color)
        };
        let handled = scattering(m, &label, spec_gloss.is_some(), &mut material, notes)?;

        // What is not rendered yet.
        let mut slots = Vec::new();
        texture_slots(m, &mut slots);
        for (slot, _) in &slots {
            if !RENDERED_TEXTURE_SLOTS.contains(&slot.as_str()) {
                textured.add(slot.clone(), name.clone());
            }
        }
        if let Some(Value::Object(exts)) = m.get("extensions") {
            for ext in exts.keys() {
                if ext != "KHR_materials_emissive_strength" && !handled.contains(&ext.as_str()) {
                    extensions.add(ext.clone(), name.clone());
                }
            }
        }
        out.push(material);
    }
    if !textured.0.is_empty() {
        let parts: Vec<String> = textured
            .0
            .iter()
            .map(|(slot, mats)| format!("{slot} on {}", list(mats)))
            .collect();
        notes.push(format!(
            "these textures are not rendered yet (the materials' factors are used): {}",
            parts.join("; ")
        ));
    }
    for (ext, mats) in extensions.0 {
        let what = if ext == "KHR_materials_pbrSpecularGlossiness" {
            " (its diffuseFactor is used as the base color)"
        } else {
            ""
        };
        notes.push(format!(
            "{ext} on {} {} is not rendered yet{what}",
            if mats.len() == 1 {
                "material"
            } else {
                "materials"
            },
            list(&mats)
        ));
    }
    if !emissive_textured.is_empty() {
        notes.push(format!(
            "emission set to 0 on {} {}: its emission comes from an emissiveTexture that cannot be used",
            if emissive_textured.len() == 1 { "material" } else { "materials" },
            list(&emissive_textured)
        ));
    }
    if !blended.is_empty() {
        notes.push(format!(
            "alphaMode BLEND on {} {} is rendered as coverage: a ray meets the surface with probability alpha",
            if blended.len() == 1 {
                "material"
            } else {
                "materials"
            },
            list(&blended)
        ));
    }
    Ok(out)
}

/// Refuses images whose URIs leave the scene's folder (see `uri.rs`).
fn check_image_uris(json: &Value, base: &Path, allow_outside: bool) -> Result<()> {
    for (i, img) in array(json, "images").iter().enumerate() {
        let Some(uri) = img.get("uri").and_then(Value::as_str) else {
            continue;
        };
        if !(uri.starts_with("data:") || uri.contains("://")) {
            uri::resolve(base, uri, allow_outside)
                .with_context(|| format!("image #{i}{}", name_suffix(img)))?;
        }
    }
    Ok(())
}

/// Checks that every external image exists and every texture names an
/// existing image; problems are notes naming the users.
fn check_images(json: &Value, base: &Path, notes: &mut Vec<String>) {
    let images = array(json, "images");
    let textures = array(json, "textures");
    // texture index -> "material 'm' (slot)" users.
    let mut users: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    for (i, m) in array(json, "materials").iter().enumerate() {
        let mut slots = Vec::new();
        texture_slots(m, &mut slots);
        for (slot, tex) in slots {
            if let Some(t) = tex {
                users
                    .entry(t)
                    .or_default()
                    .push(format!("material '{}' ({slot})", material_name(m, i)));
            }
        }
    }
    let used_by = |t: u64| match users.get(&t) {
        Some(u) => format!("used by {}", u.join(", ")),
        None => "not used by any material".to_string(),
    };
    for (t, tex) in textures.iter().enumerate() {
        let Some(src) = tex.get("source").and_then(Value::as_u64) else {
            continue;
        };
        if src as usize >= images.len() {
            notes.push(format!(
                "warning: texture #{t}{} refers to image #{src}, which is missing (the file defines {}); {}",
                name_suffix(tex),
                plural(images.len(), "image", "images"),
                used_by(t as u64)
            ));
        }
    }
    for (i, img) in images.iter().enumerate() {
        let Some(uri) = img.get("uri").and_then(Value::as_str) else {
            continue;
        };
        if uri.starts_with("data:") || uri.contains("://") {
            continue;
        }
        let file = base.join(gltf_data::percent_decode(uri));
        if !file.is_file() {
            let mut who: Vec<String> = Vec::new();
            for (t, tex) in textures.iter().enumerate() {
                if tex.get("source").and_then(Value::as_u64) == Some(i as u64) {
                    who.push(format!(
                        "texture #{t}{} {}",
                        name_suffix(tex),
                        used_by(t as u64)
                    ));
                }
            }
            notes.push(format!(
                "warning: image #{i}{} is missing: {} not found ({})",
                name_suffix(img),
                file.display(),
                if who.is_empty() {
                    "not used by any texture".to_string()
                } else {
                    who.join("; ")
                }
            ));
        }
    }
}

/// Notes extensions the file uses that nothing else reports.
fn note_unused_extensions(json: &Value, notes: &mut Vec<String>) {
    for ext in array(json, "extensionsUsed") {
        let Some(name) = ext.as_str() else { continue };
        let on_a_material = array(json, "materials")
            .iter()
            .any(|m| m.get("extensions").and_then(|e| e.get(name)).is_some());
        let reported_elsewhere = on_a_material
            || name == "KHR_materials_emissive_strength"
            || name == "KHR_lights_punctual"
            || name == "KHR_texture_transform"
            || name.starts_with("KHR_materials_");
        if !reported_elsewhere {
            notes.push(format!("extension {name} is not supported: ignored"));
        }
    }
    let n_anim = array(json, "animations").len();
    if n_anim > 0 {
        notes.push(format!(
            "{} ignored: the scene is rendered in its rest pose",
            plural(n_anim, "animation", "animations")
        ));
    }
}

struct Walk {
    extras: SceneExtras,
}

/// The vkpt scene extras (see the module docs).
#[derive(Default)]
struct SceneExtras {
    environment: Option<Vec3>,
    environment_map: Option<String>,
    environment_rotation: f32,
    environment_hidden: bool,
}

fn local_transform(node: &Value) -> Result<Mat4> {
    if let Some(m) = f32_array::<16>(node.get("matrix"), "matrix")? {
        return Ok(Mat4::from_cols_array(&m));
    }
    let t = f32_array::<3>(node.get("translation"), "translation")?.unwrap_or([0.0; 3]);
    let r = f32_array::<4>(node.get("rotation"), "rotation")?.unwrap_or([0.0, 0.0, 0.0, 1.0]);
    let s = f32_array::<3>(node.get("scale"), "scale")?.unwrap_or([1.0; 3]);
    let q = Quat::from_array(r);
    ensure!(q.length() > 0.0, "rotation is the zero quaternion");
    Ok(Mat4::from_scale_rotation_translation(
        Vec3::from(s),
        q.normalize(),
        Vec3::from(t),
    ))
}

fn scene_extras(scene_json: &Value, notes: &mut Vec<String>) -> Result<SceneExtras> {
    let mut out = SceneExtras::default();
    let Some(vkpt) = scene_json.get("extras").and_then(|e| e.get("vkpt")) else {
        return Ok(out);
    };
    let obj = vkpt
        .as_object()
        .ok_or_else(|| anyhow!("scene extras \"vkpt\" must be an object, found {vkpt}"))?;
    for key in obj.keys() {
        if !matches!(
            key.as_str(),
            "environment" | "environment_map" | "environment_rotation" | "environment_hidden"
        ) {
            notes.push(format!(
                "scene extras vkpt.{key} is not understood: ignored"
            ));
        }
    }
    if let Some(env) = obj.get("environment") {
        let rgb = f32_array::<3>(Some(env), "scene extras vkpt.environment")?
            .map(Vec3::from)
            .ok_or_else(|| anyhow!("scene extras vkpt.environment is missing"))?;
        ensure!(
            rgb.min_element() >= 0.0,
            "scene extras vkpt.environment must be non-negative [r, g, b] radiance, found {env}"
        );
        out.environment = Some(rgb);
    }
    if let Some(v) = obj.get("environment_map") {
        out.environment_map = Some(
            v.as_str()
                .filter(|s| !s.is_empty())
                .ok_or_else(|| {
                    anyhow!("scene extras vkpt.environment_map must be a file name (.exr or .hdr), found {v}")
                })?
                .to_string(),
        );
    }
    if let Some(v) = obj.get("environment_rotation") {
        out.environment_rotation = v
            .as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite())
            .ok_or_else(|| {
                anyhow!(
                    "scene extras vkpt.environment_rotation must be a number of degrees, found {v}"
                )
            })?;
    }
    if let Some(v) = obj.get("environment_hidden") {
        out.environment_hidden = v.as_bool().ok_or_else(|| {
            anyhow!("scene extras vkpt.environment_hidden must be true or false, found {v}")
        })?;
    }
    Ok(out)
}

/// The KHR_lights_punctual light `li` placed by `node`'s world transform.
fn node_light(json: &Value, li: usize, world: &Mat4, notes: &mut Vec<String>) -> Result<Light> {
    let lights = json
        .get("extensions")
        .and_then(|e| e.get("KHR_lights_punctual"))
        .map(|e| array(e, "lights"))
        .unwrap_or_default();
    let l = element(lights, "KHR_lights_punctual light", li)?;
    let name = l
        .get("name")
        .and_then(Value::as_str)
        .map(str::to_string)
        .unwrap_or_else(|| format!("light #{li}"));
    let label = format!("KHR_lights_punctual light #{li}{}", name_suffix(l));
    let number = |key: &str| -> Result<Option<f32>> {
        match l
            .get(key)
            .or_else(|| l.get("spot").and_then(|s| s.get(key)))
        {
            None | Some(Value::Null) => Ok(None),
            Some(v) => Ok(Some(
                v.as_f64()
                    .map(|f| f as f32)
                    .filter(|f| f.is_finite())
                    .ok_or_else(|| anyhow!("{label}: {key} must be a number, found {v}"))?,
            )),
        }
    };
    let color =
        Vec3::from(f32_array::<3>(l.get("color"), &format!("{label}: color"))?.unwrap_or([1.0; 3]));
    ensure!(
        color.min_element() >= 0.0,
        "{label}: color must be non-negative"
    );
    let intensity = number("intensity")?.unwrap_or(1.0);
    ensure!(
        intensity >= 0.0,
        "{label}: intensity must be non-negative, found {intensity}"
    );
    let range = number("range")?;
    if let Some(r) = range {
        ensure!(r > 0.0, "{label}: range must be above 0, found {r}");
    }
    let extras = l.get("extras").and_then(|e| e.get("vkpt"));
    let extra = |key: &str| -> Result<Option<f32>> {
        match extras.and_then(|v| v.get(key)) {
            None => Ok(None),
            Some(v) => Ok(Some(
                v.as_f64()
                    .map(|f| f as f32)
                    .filter(|f| f.is_finite() && *f >= 0.0)
                    .ok_or_else(|| {
                        anyhow!(
                            "{label}: extras vkpt.{key} must be a non-negative number, found {v}"
                        )
                    })?,
            )),
        }
    };
    let radius = extra("radius")?.filter(|&r| r > 0.0);
    let diameter = extra("angular_diameter")?.filter(|&d| d > 0.0);
    let type_ = l.get("type").and_then(Value::as_str).unwrap_or("");
    // Extras that do not apply to this type of light are reported.
    if let Some(obj) = extras.and_then(Value::as_object) {
        for key in obj.keys() {
            let applies = matches!(
                (type_, key.as_str()),
                ("point", "radius") | ("directional", "angular_diameter")
            );
            if !applies {
                notes.push(format!(
                    "{label}: extras vkpt.{key} does not apply to a {type_} light: ignored (vkpt reads radius on point lights, angular_diameter on directional ones)"
                ));
            }
        }
    }
    let kind = match type_ {
        "point" => match radius {
            Some(radius) => LightKind::Sphere { radius },
            None => LightKind::Point,
        },
        "spot" => {
            let inner_cone = number("innerConeAngle")?.unwrap_or(0.0);
            let outer_cone = number("outerConeAngle")?.unwrap_or(std::f32::consts::FRAC_PI_4);
            ensure!(
                0.0 <= inner_cone
                    && inner_cone < outer_cone
                    && outer_cone <= std::f32::consts::FRAC_PI_2,
                "{label}: spot cone angles must satisfy 0 <= innerConeAngle < outerConeAngle <= pi/2, found {inner_cone} and {outer_cone}"
            );
            LightKind::Spot {
                inner_cone,
                outer_cone,
            }
        }
        "directional" => match diameter {
            Some(d) => {
                ensure!(
                    d < std::f32::consts::PI,
                    "{label}: extras vkpt.angular_diameter must be below pi radians, found {d}"
                );
                LightKind::Sun {
                    angular_diameter: d,
                }
            }
            None => LightKind::Directional,
        },
        _ => bail!("{label}: unknown light type {type_:?} (point, spot or directional)"),
    };
    if matches!(kind, LightKind::Sphere { .. }) && range.is_some() {
        notes.push(format!(
            "{label}: range is not applied to a spherical light"
        ));
    }
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    ensure!(
        position.is_finite() && direction != Vec3::ZERO,
        "{label}: the node's world transform is degenerate (zero scale?)"
    );
    Ok(Light {
        name,
        kind,
        position,
        direction,
        color: color * intensity,
        range,
    })
}

fn walk_scene(
    json: &Value,
    buffers: &[Vec<u8>],
    scene: &mut Scene,
    notes: &mut Vec<String>,
) -> Result<Walk> {
    let nodes = array(json, "nodes");
    let scenes = array(json, "scenes");
    let (roots, extras): (Vec<usize>, SceneExtras) = if scenes.is_empty() {
        // No scene: render every root node (node that is nobody's child).
        let mut is_child = vec![false; nodes.len()];
        for n in nodes {
            for c in array(n, "children") {
                if let Some(c) = c.as_u64().filter(|&c| (c as usize) < nodes.len()) {
                    is_child[c as usize] = true;
                }
            }
        }
        if !nodes.is_empty() {
            notes.push("the file defines no scene: all root nodes are rendered".to_string());
        }
        (
            (0..nodes.len()).filter(|&i| !is_child[i]).collect(),
            SceneExtras::default(),
        )
    } else {
        let si = index(json.get("scene"), "scene")?.unwrap_or(0);
        let sj = element(scenes, "scene", si)?;
        let label = format!("scene #{si}{}", name_suffix(sj));
        let mut roots = Vec::new();
        for (k, n) in array(sj, "nodes").iter().enumerate() {
            roots.push(
                index(Some(n), &format!("nodes[{k}]"))
                    .with_context(|| label.clone())?
                    .unwrap_or(usize::MAX),
            );
        }
        let extras = scene_extras(sj, notes).with_context(|| label.clone())?;
        (roots, extras)
    };

    let mut mesh_loader = MeshLoader::new(json, buffers, scene.materials.len());
    mesh_loader.texture_needs = scene
        .materials
        .iter()
        .map(|m| TextureNeeds {
            any: m.textures.any(),
            sets: [0, 1].map(|set| {
                m.textures
                    .slots()
                    .iter()
                    .flatten()
                    .any(|t| t.texcoord == set)
            }),
            normal_texcoord: m.textures.normal.map(|t| t.texcoord),
        })
        .collect();
    let mut visited = vec![false; nodes.len()];
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&r| (r, Mat4::IDENTITY)).collect();
    let mut skinned = 0usize;
    while let Some((ni, parent)) = stack.pop() {
        let node = element(nodes, "node", ni)?;
        let label = format!("node #{ni}{}", name_suffix(node));
        ensure!(
            !visited[ni],
            "{label} is reached twice: the node hierarchy is not a tree (a cycle or a node with two parents)"
        );
        visited[ni] = true;
        let world = parent * local_transform(node).with_context(|| label.clone())?;
        if let Some(mi) = index(node.get("mesh"), "mesh").with_context(|| label.clone())? {
            if node.get("skin").is_some() {
                skinned += 1;
            }
            mesh_loader
                .load_mesh(mi, &world, &mut scene.triangles)
                .with_context(|| label.clone())?;
        }
        if let Some(ci) = index(node.get("camera"), "camera").with_context(|| label.clone())? {
            let cam = node_camera(json, ci, node, &world, notes).with_context(|| label.clone())?;
            scene.cameras.push(cam);
        }
        if let Some(ext) = node
            .get("extensions")
            .and_then(|e| e.get("KHR_lights_punctual"))
        {
            let li = index(ext.get("light"), "KHR_lights_punctual.light")
                .with_context(|| label.clone())?
                .ok_or_else(|| anyhow!("{label}: KHR_lights_punctual names no light"))?;
            let light = node_light(json, li, &world, notes).with_context(|| label.clone())?;
            scene.lights.push(light);
        }
        for c in array(node, "children").iter().rev() {
            let c = index(Some(c), "children").with_context(|| label.clone())?;
            stack.push((c.unwrap_or(usize::MAX), world));
        }
    }
    if skinned > 0 {
        notes.push(format!(
            "skinning ignored on {}: meshes are rendered in their bind pose",
            plural(skinned, "node", "nodes")
        ));
    }
    mesh_loader.finish(scene, notes);
    Ok(Walk { extras })
}

/// The camera on a node: perspective or orthographic, with its vkpt camera
/// extras.
fn node_camera(
    json: &Value,
    ci: usize,
    node: &Value,
    world: &Mat4,
    notes: &mut Vec<String>,
) -> Result<Camera> {
    let cam = element(array(json, "cameras"), "camera", ci)?;
    let name = cam
        .get("name")
        .and_then(Value::as_str)
        .or_else(|| node.get("name").and_then(Value::as_str))
        .map(str::to_string)
        .unwrap_or_else(|| format!("camera #{ci}"));
    let label = format!("camera #{ci} '{name}'");
    let type_ = cam.get("type").and_then(Value::as_str).unwrap_or("");
    let positive = |v: Option<&Value>, what: &str| -> Result<Option<f32>> {
        match v {
            None | Some(Value::Null) => Ok(None),
            Some(v) => Ok(Some(
                v.as_f64()
                    .map(|f| f as f32)
                    .filter(|f| f.is_finite() && *f > 0.0)
                    .ok_or_else(|| {
                        anyhow!("{label}: {what} must be a positive number, found {v}")
                    })?,
            )),
        }
    };
    let (projection, yfov, aspect_ratio) = match type_ {
        "perspective" => {
            let persp = cam
                .get("perspective")
                .ok_or_else(|| anyhow!("{label}: perspective parameters are missing"))?;
            let yfov = persp
                .get("yfov")
                .and_then(Value::as_f64)
                .map(|f| f as f32)
                .filter(|f| f.is_finite() && *f > 0.0 && *f < std::f32::consts::PI)
                .ok_or_else(|| anyhow!("{label}: yfov must be a number of radians in (0, pi)"))?;
            let aspect = positive(persp.get("aspectRatio"), "aspectRatio")?;
            (Projection::Perspective, yfov, aspect)
        }
        "orthographic" => {
            let ortho = cam
                .get("orthographic")
                .ok_or_else(|| anyhow!("{label}: orthographic parameters are missing"))?;
            // glTF: xmag and ymag must not be 0 and should not be negative;
            // a negative one is used as its magnitude.
            let mag = |key: &str| -> Result<f32> {
                ortho
                    .get(key)
                    .and_then(Value::as_f64)
                    .map(|f| (f as f32).abs())
                    .filter(|f| f.is_finite() && *f > 0.0)
                    .ok_or_else(|| anyhow!("{label}: orthographic.{key} must be a non-zero number"))
            };
            let (xmag, ymag) = (mag("xmag")?, mag("ymag")?);
            (
                Projection::Orthographic { half_height: ymag },
                0.0,
                Some(xmag / ymag),
            )
        }
        _ => bail!("{label}: unknown camera type {type_:?}"),
    };
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up_raw = world.transform_vector3(Vec3::Y);
    let up = (up_raw - forward * up_raw.dot(forward)).normalize_or_zero();
    ensure!(
        position.is_finite() && forward != Vec3::ZERO && up != Vec3::ZERO,
        "{label}: the node's world transform is degenerate (zero scale?)"
    );
    if let Projection::Orthographic { half_height } = projection {
        // Scale in the node's transform scales the view rectangle.
        let scale = world.transform_vector3(Vec3::Y).length();
        if (scale - 1.0).abs() > 1e-4 {
            notes.push(format!(
                "{label}: the node's scale ({scale}) does not change the orthographic view height ({half_height} half height)"
            ));
        }
    }
    let mut camera = Camera {
        name,
        position,
        forward,
        up,
        yfov,
        aspect_ratio,
        projection,
        lens: Default::default(),
        filter: Default::default(),
        shutter: None,
        iso: None,
    };
    camera_extras(cam, &label, &mut camera, notes)?;
    camera.check_lens(notes).with_context(|| label.clone())?;
    Ok(camera)
}

/// Reads the vkpt camera extras (see "vkpt camera extras" above) into
/// `camera`.
fn camera_extras(
    cam: &Value,
    label: &str,
    camera: &mut Camera,
    notes: &mut Vec<String>,
) -> Result<()> {
    let Some(vkpt) = cam.get("extras").and_then(|e| e.get("vkpt")) else {
        return Ok(());
    };
    let obj = vkpt
        .as_object()
        .ok_or_else(|| anyhow!("{label}: extras \"vkpt\" must be an object, found {vkpt}"))?;
    let number = |v: &Value, what: &str| -> Result<f32> {
        v.as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite())
            .ok_or_else(|| anyhow!("{label}: extras vkpt.{what} must be a number, found {v}"))
    };
    for (key, v) in obj {
        match key.as_str() {
            "shutter" => {
                camera.shutter = Some(check_length(
                    &format!("{label}: extras vkpt.shutter (seconds)"),
                    number(v, "shutter")?,
                    false,
                )?)
            }
            "iso" => {
                camera.iso = Some(check_length(
                    &format!("{label}: extras vkpt.iso"),
                    number(v, "iso")?,
                    false,
                )?)
            }
            "lens" => {
                let lens_obj = v.as_object().ok_or_else(|| {
                    anyhow!("{label}: extras vkpt.lens must be an object, found {v}")
                })?;
                let lens = &mut camera.lens;
                for (k, x) in lens_obj {
                    let what = format!("{label}: extras vkpt.lens.{k}");
                    let n = number(x, &format!("lens.{k}"))?;
                    match k.as_str() {
                        "focal_length" => lens.focal_length = Some(check_length(&what, n, false)?),
                        "sensor_height" => {
                            lens.sensor_height = Some(check_length(&what, n, false)?)
                        }
                        "fstop" => lens.fstop = check_length(&what, n, true)?,
                        "focus_distance" => {
                            lens.focus_distance = Some(check_length(&what, n, false)?)
                        }
                        "blades" => {
                            ensure!(
                                n.fract() == 0.0 && n >= 0.0,
                                "{what} must be an integer, found {x}"
                            );
                            lens.blades = check_blades(&what, n as u32)?;
                        }
                        "blade_rotation" => lens.blade_rotation = n.to_radians(),
                        _ => notes.push(format!(
                            "{label}: extras vkpt.lens.{k} is not understood: ignored"
                        )),
                    }
                }
                if let (Some(f), Some(h), Projection::Perspective) =
                    (lens.focal_length, lens.sensor_height, camera.projection)
                {
                    let h_fov = 2.0 * f * (0.5 * camera.yfov).tan();
                    if (h_fov / h - 1.0).abs() > 0.01 {
                        notes.push(format!(
                            "{label}: a {:.1} mm lens on a {:.1} mm sensor would see {:.2}° but yfov is {:.2}°: yfov sets the field of view, the focal length only the aperture",
                            f * 1e3,
                            h * 1e3,
                            (2.0 * (0.5 * h / f).atan()).to_degrees(),
                            camera.yfov.to_degrees()
                        ));
                    }
                }
            }
            _ => notes.push(format!(
                "{label}: extras vkpt.{key} is not understood: ignored"
            )),
        }
    }
    Ok(())
}

fn mode_name(mode: u64) -> &'static str {
    match mode {
        0 => "POINTS",
        1 => "LINES",
        2 => "LINE_LOOP",
        3 => "LINE_STRIP",
        4 => "TRIANGLES",
        5 => "TRIANGLE_STRIP",
        6 => "TRIANGLE_FAN",
        _ => "(invalid)",
    }
}

/// Coordinates beyond this (in scene units, after the node transforms) are
/// treated like infinities: the watertight ray/triangle test multiplies
/// three coordinate differences, which must stay far below f32::MAX
/// ((4e12)^3 is 6.4e37).
const MAX_COORDINATE: f32 = 1e12;

/// Kinds of bad geometry the loader drops, each reported once per file
/// with a count per mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Dropped {
    /// A vertex position is NaN, infinite or beyond `MAX_COORDINATE`.
    NonFinitePosition,
    /// Zero area (collinear or duplicated vertices), or so small that its
    /// normal cannot be computed in f32.
    ZeroArea,
    /// A vertex normal that is NaN, infinite or zero: replaced by the
    /// triangle's face normal (the triangle is kept).
    BadNormal,
}

impl Dropped {
    const ALL: [Dropped; 3] = [
        Dropped::NonFinitePosition,
        Dropped::ZeroArea,
        Dropped::BadNormal,
    ];

    fn describe(self, n: usize) -> String {
        match self {
            Dropped::NonFinitePosition => format!(
                "dropped {} with NaN, infinite or out-of-range (beyond {MAX_COORDINATE:e}) positions",
                plural(n, "triangle", "triangles")
            ),
            Dropped::ZeroArea => format!(
                "dropped {} (collinear or repeated vertices)",
                plural(n, "zero-area triangle", "zero-area triangles")
            ),
            Dropped::BadNormal => format!(
                "replaced {} (NaN, infinite or zero) by the face normal",
                plural(n, "bad vertex normal", "bad vertex normals")
            ),
        }
    }
}

/// What a material's textures need from the vertices.
#[derive(Clone, Copy, Default)]
struct TextureNeeds {
    any: bool,
    /// Which texture coordinate sets its textures read.
    sets: [bool; 2],
    /// The texture coordinate set of its normal texture, if it has one.
    normal_texcoord: Option<u32>,
}

/// Turns glTF meshes into world-space triangles, counting what it skips.
struct MeshLoader<'a> {
    json: &'a Value,
    buffers: &'a [Vec<u8>],
    n_materials: usize,
    /// By material index; empty when no material has a texture.
    texture_needs: Vec<TextureNeeds>,
    /// One per triangle emitted, when any material has a texture.
    texcoords: Vec<Texcoords>,
    /// Textured primitives lacking the TEXCOORD_n their textures read.
    missing_texcoords: BTreeMap<u32, usize>,
    generated_tangents: usize,
    nonfinite_texcoords: usize,
    uses_default_material: bool,
    skipped_modes: BTreeMap<&'static str, usize>,
    no_positions: usize,
    /// Per kind of bad geometry, how many were dropped in each mesh.
    dropped: BTreeMap<Dropped, BTreeMap<String, usize>>,
    trailing_indices: usize,
    morph_targets: usize,
}

impl<'a> MeshLoader<'a> {
    fn new(json: &'a Value, buffers: &'a [Vec<u8>], n_materials: usize) -> Self {
        MeshLoader {
            json,
            buffers,
            n_materials,
            texture_needs: Vec::new(),
            texcoords: Vec::new(),
            missing_texcoords: BTreeMap::new(),
            generated_tangents: 0,
            nonfinite_texcoords: 0,
            uses_default_material: false,
            skipped_modes: BTreeMap::new(),
            no_positions: 0,
            dropped: BTreeMap::new(),
            trailing_indices: 0,
            morph_targets: 0,
        }
    }

    fn load_mesh(&mut self, mi: usize, world: &Mat4, out: &mut Vec<Triangle>) -> Result<()> {
        let mesh = element(array(self.json, "meshes"), "mesh", mi)?;
        let mesh_name = match mesh.get("name").and_then(Value::as_str) {
            Some(n) => format!("mesh '{n}'"),
            None => format!("mesh #{mi}"),
        };
        for (pi, prim) in array(mesh, "primitives").iter().enumerate() {
            self.load_primitive(prim, world, &mesh_name, out)
                .with_context(|| format!("mesh #{mi}{} primitive #{pi}", name_suffix(mesh)))?;
        }
        Ok(())
    }

    fn load_primitive(
        &mut self,
        prim: &Value,
        world: &Mat4,
        mesh_name: &str,
        out: &mut Vec<Triangle>,
    ) -> Result<()> {
        let mode = match prim.get("mode") {
            None => 4,
            Some(v) => v
                .as_u64()
                .ok_or_else(|| anyhow!("mode is not an integer: {v}"))?,
        };
        ensure!(mode <= 6, "invalid mode {mode}");
        if mode < 4 {
            *self.skipped_modes.entry(mode_name(mode)).or_default() += 1;
            return Ok(());
        }
        let attributes = prim.get("attributes");
        let Some(pos_index) = index(attributes.and_then(|a| a.get("POSITION")), "POSITION")? else {
            self.no_positions += 1;
            return Ok(());
        };
        if prim.get("targets").is_some() {
            self.morph_targets += 1;
        }
        let to_f32 = |f: f64| f as f32;
        let positions =
            gltf_data::read_accessor(self.json, self.buffers, pos_index, "VEC3", to_f32, 0.0)
                .context("attribute POSITION")?;
        let n_vertices = positions.len() / 3;
        let normals = match index(attributes.and_then(|a| a.get("NORMAL")), "NORMAL")? {
            None => None,
            Some(ni) => {
                let n = gltf_data::read_accessor(self.json, self.buffers, ni, "VEC3", to_f32, 0.0)
                    .context("attribute NORMAL")?;
                ensure!(
                    n.len() == positions.len(),
                    "attribute NORMAL has {} elements but POSITION has {n_vertices}",
                    n.len() / 3
                );
                Some(n)
            }
        };
        let indices: Vec<u32> = match index(prim.get("indices"), "indices")? {
            None => {
                ensure!(n_vertices <= u32::MAX as usize, "too many vertices");
                (0..n_vertices as u32).collect()
            }
            Some(ii) => {
                let component_type = array(self.json, "accessors")
                    .get(ii)
                    .and_then(|a| a.get("componentType"))
                    .and_then(Value::as_u64);
                ensure!(
                    matches!(component_type, Some(5121 | 5123 | 5125)),
                    "indices: accessor #{ii} has componentType {component_type:?}, not an unsigned integer type"
                );
                let idx = gltf_data::read_accessor(
                    self.json,
                    self.buffers,
                    ii,
                    "SCALAR",
                    |f| f as u32,
                    0,
                )
                .context("indices")?;
                if let Some((k, &bad)) = idx
                    .iter()
                    .enumerate()
                    .find(|(_, v)| **v as usize >= n_vertices)
                {
                    bail!("indices: index #{k} is {bad}, but there are only {n_vertices} vertices");
                }
                idx
            }
        };
        let material = match index(prim.get("material"), "material")? {
            Some(m) => {
                ensure!(
                    m < self.n_materials,
                    "material #{m} does not exist (the file has {})",
                    self.n_materials
                );
                m as u32
            }
            None => {
                self.uses_default_material = true;
                self.n_materials as u32
            }
        };

        // World-space vertices.
        let normal_matrix = Mat3::from_mat4(*world).inverse().transpose();
        let flip = Mat3::from_mat4(*world).determinant() < 0.0;
        let wp: Vec<Vec3> = positions
            .chunks_exact(3)
            .map(|p| world.transform_point3(Vec3::new(p[0], p[1], p[2])))
            .collect();
        let wn: Option<Vec<Vec3>> = normals.map(|n| {
            n.chunks_exact(3)
                .map(|n| (normal_matrix * Vec3::new(n[0], n[1], n[2])).normalize_or_zero())
                .collect()
        });

        let mut dropped = [0usize; Dropped::ALL.len()];
        // Triangles as vertex index triples in the file's winding.
        let mut tris: Vec<[u32; 3]> = Vec::new();
        match mode {
            4 => {
                let chunks = indices.chunks_exact(3);
                self.trailing_indices += chunks.remainder().len();
                tris.extend(chunks.map(|t| [t[0], t[1], t[2]]));
            }
            5 => {
                // Strip: winding alternates so every triangle keeps the front face.
                for i in 0..indices.len().saturating_sub(2) {
                    tris.push(if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i + 1], indices[i], indices[i + 2]]
                    });
                }
            }
            _ => {
                for i in 1..indices.len().saturating_sub(1) {
                    tris.push([indices[i], indices[i + 1], indices[0]]);
                }
            }
        }
        let texcoords = self.primitive_texcoords(attributes, material, &positions, &tris)?;

        for (k, &[a, b, c]) in tris.iter().enumerate() {
            let (a, b, c) = (a as usize, b as usize, c as usize);
            let corners = if flip { [0, 2, 1] } else { [0, 1, 2] };
            let (b, c) = if flip { (c, b) } else { (b, c) };
            let p = [wp[a], wp[b], wp[c]];
            let in_range = |v: &Vec3| v.is_finite() && v.abs().max_element() <= MAX_COORDINATE;
            if !p.iter().all(in_range) {
                dropped[Dropped::NonFinitePosition as usize] += 1;
                continue;
            }
            // The kernels normalize this cross product: its squared length
            // must be a normal float (GPUs flush denormals to zero).
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let len2 = cross.length_squared();
            if !(len2 >= f32::MIN_POSITIVE && len2.is_finite()) {
                dropped[Dropped::ZeroArea as usize] += 1;
                continue;
            }
            let face = cross / len2.sqrt();
            let normals = match &wn {
                Some(wn) => [a, b, c].map(|v| {
                    let n = wn[v];
                    if n.is_finite() && n != Vec3::ZERO {
                        n
                    } else {
                        dropped[Dropped::BadNormal as usize] += 1;
                        face
                    }
                }),
                None => [face; 3],
            };
            out.push(Triangle {
                positions: p,
                normals,
                material,
            });
            if self.any_textured() {
                let t = texcoords.as_ref().map_or(Texcoords::default(), |t| {
                    let src = &t[k];
                    let linear = Mat3::from_mat4(*world);
                    let sign = if flip { -1.0 } else { 1.0 };
                    Texcoords {
                        uv: src.uv.map(|set| corners.map(|i| set[i])),
                        tangents: corners.map(|i| {
                            let t = src.tangents[i];
                            (linear * t.truncate())
                                .normalize_or_zero()
                                .extend(t.w * sign)
                        }),
                    }
                });
                self.texcoords.push(t);
            }
        }
        for kind in Dropped::ALL {
            if dropped[kind as usize] > 0 {
                *self
                    .dropped
                    .entry(kind)
                    .or_default()
                    .entry(mesh_name.to_string())
                    .or_default() += dropped[kind as usize];
            }
        }
        Ok(())
    }

    fn any_textured(&self) -> bool {
        self.texture_needs.iter().any(|n| n.any)
    }

    /// Object-space texture coordinates and tangents of each triangle of a
    /// primitive (`None` when its material has no texture).
    fn primitive_texcoords(
        &mut self,
        attributes: Option<&Value>,
        material: u32,
        positions: &[f32],
        tris: &[[u32; 3]],
    ) -> Result<Option<Vec<Texcoords>>> {
        let needs = self
            .texture_needs
            .get(material as usize)
            .copied()
            .unwrap_or_default();
        if !needs.any {
            return Ok(None);
        }
        let n_vertices = positions.len() / 3;
        let to_f32 = |f: f64| f as f32;
        let mut sets: [Option<Vec<Vec2>>; 2] = [None, None];
        for (set, out) in sets.iter_mut().enumerate() {
            let key = format!("TEXCOORD_{set}");
            let Some(ai) = index(attributes.and_then(|a| a.get(&key)), &key)? else {
                continue;
            };
            let raw = gltf_data::read_accessor(self.json, self.buffers, ai, "VEC2", to_f32, 0.0)
                .with_context(|| format!("attribute {key}"))?;
            ensure!(
                raw.len() == 2 * n_vertices,
                "attribute {key} has {} elements but POSITION has {n_vertices}",
                raw.len() / 2
            );
            *out = Some(
                raw.chunks_exact(2)
                    .map(|c| {
                        let uv = Vec2::new(c[0], c[1]);
                        if uv.is_finite() {
                            uv
                        } else {
                            self.nonfinite_texcoords += 1;
                            Vec2::ZERO
                        }
                    })
                    .collect(),
            );
        }
        for (set, uv) in sets.iter().enumerate() {
            if uv.is_none() && needs.sets[set] {
                *self.missing_texcoords.entry(set as u32).or_default() += 1;
            }
        }
        let uv_or_zero = |set: usize| sets[set].clone().unwrap_or(vec![Vec2::ZERO; n_vertices]);
        let uv = [uv_or_zero(0), uv_or_zero(1)];
        let corner_tangents: Vec<[Vec4; 3]> = match needs.normal_texcoord {
            None => vec![[Vec4::new(0.0, 0.0, 0.0, 1.0); 3]; tris.len()],
            Some(set) => match index(attributes.and_then(|a| a.get("TANGENT")), "TANGENT")? {
                Some(ai) => {
                    let raw =
                        gltf_data::read_accessor(self.json, self.buffers, ai, "VEC4", to_f32, 0.0)
                            .context("attribute TANGENT")?;
                    ensure!(
                        raw.len() == 4 * n_vertices,
                        "attribute TANGENT has {} elements but POSITION has {n_vertices}",
                        raw.len() / 4
                    );
                    let t: Vec<Vec4> = raw
                        .chunks_exact(4)
                        .map(|c| {
                            let t =
                                Vec4::new(c[0], c[1], c[2], if c[3] < 0.0 { -1.0 } else { 1.0 });
                            if t.is_finite() {
                                t
                            } else {
                                Vec4::new(0.0, 0.0, 0.0, 1.0)
                            }
                        })
                        .collect();
                    tris.iter().map(|tri| tri.map(|v| t[v as usize])).collect()
                }
                None => {
                    self.generated_tangents += 1;
                    let p: Vec<Vec3> = positions
                        .chunks_exact(3)
                        .map(|p| Vec3::new(p[0], p[1], p[2]))
                        .collect();
                    generate_tangents(&p, &uv[set as usize], tris)
                }
            },
        };
        Ok(Some(
            tris.iter()
                .zip(corner_tangents)
                .map(|(tri, tangents)| Texcoords {
                    uv: [0, 1].map(|set| tri.map(|v| uv[set][v as usize])),
                    tangents,
                })
                .collect(),
        ))
    }

    fn finish(self, scene: &mut Scene, notes: &mut Vec<String>) {
        if self.uses_default_material {
            scene.materials.push(Material::gltf_default());
            notes.push(
                "primitives without a material use the glTF default material (white, metallic 1, roughness 1)"
                    .into(),
            );
        }
        scene.texcoords = self.texcoords;
        for (set, n) in &self.missing_texcoords {
            notes.push(format!(
                "{} with a texture reading TEXCOORD_{set} {} no TEXCOORD_{set}: the texture is read at (0, 0) there",
                plural(*n, "primitive", "primitives"),
                if *n == 1 { "has" } else { "have" }
            ));
        }
        if self.generated_tangents > 0 {
            notes.push(format!(
                "generated tangents for normal mapping on {} without TANGENT (from the UVs, per vertex and handedness)",
                plural(self.generated_tangents, "primitive", "primitives")
            ));
        }
        if self.nonfinite_texcoords > 0 {
            notes.push(format!(
                "replaced {} non-finite texture coordinates by (0, 0)",
                self.nonfinite_texcoords
            ));
        }
        for (mode, n) in &self.skipped_modes {
            notes.push(format!(
                "skipped {} with mode {mode} (only triangle modes are rendered yet)",
                plural(*n, "primitive", "primitives")
            ));
        }
        if self.no_positions > 0 {
            notes.push(format!(
                "skipped {} without POSITION",
                plural(self.no_positions, "primitive", "primitives")
            ));
        }
        for (kind, per_mesh) in &self.dropped {
            let total: usize = per_mesh.values().sum();
            let meshes: Vec<String> = per_mesh
                .iter()
                .map(|(mesh, n)| {
                    if per_mesh.len() == 1 {
                        mesh.clone()
                    } else {
                        format!("{mesh} ({n})")
                    }
                })
                .collect();
            let shown = meshes
                .iter()
                .take(5)
                .cloned()
                .collect::<Vec<_>>()
                .join(", ");
            let more = match meshes.len() {
                n if n > 5 => format!(" and {} more meshes", n - 5),
                _ => String::new(),
            };
            notes.push(format!(
                "warning: {} in {shown}{more}",
                kind.describe(total)
            ));
        }
        if self.trailing_indices > 0 {
            notes.push(format!(
                "ignored {} left over after the last whole triangle",
                plural(self.trailing_indices, "index", "indices")
            ));
        }
        if self.morph_targets > 0 {
            notes.push(format!(
                "morph targets ignored on {}: the base shape is rendered",
                plural(self.morph_targets, "primitive", "primitives")
            ));
        }
    }
}
