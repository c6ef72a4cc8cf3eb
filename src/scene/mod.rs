//! The scene as plain Rust data: the one source of truth both back ends are
//! built from. Loaders fill it; `packed` flattens it for the kernels.

mod auto_camera;
pub mod camera;
pub mod environment;
mod gltf;
pub mod motion;
mod tangents;
mod texture;

use glam::{DVec3, Vec3};
use std::path::{Path, PathBuf};

pub use camera::{CameraOverrides, FilterKind, PixelFilter, Projection, ThinLens};
pub use environment::EnvironmentMap;
pub use gltf::{GltfFile, load_gltf, load_gltf_with};
pub use texture::{
    MaterialTextures, Texcoords, TexelStorage, TextureImage, TextureRef, Wrap, mip_levels,
};

/// A triangle, its positions relative to [`Scene::world_origin`]. Its front face is the counter-clockwise side:
/// the geometric normal is `(p1 - p0) x (p2 - p0)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub positions: [Vec3; 3],
    /// Unit shading normals at the vertices (generated when the file has none).
    pub normals: [Vec3; 3],
    pub material: u32,
}

/// glTF alphaMode. A path tracer has no draw order to blend in, so BLEND
/// is read as coverage, as Cycles and pbrt-v4 read alpha: a ray meets the
/// surface with probability alpha and passes through it otherwise, which in
/// expectation composites the surface over what lies behind it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// The surface is there where alpha is at least `cutoff`.
    Mask { cutoff: f32 },
    /// The surface is there with probability alpha.
    Blend,
}

/// How a surface scatters light (`MaterialData::kind` on the GPU).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialKind {
    /// Lambertian diffuse with albedo `base_color`.
    Lambert,
    /// Diffuse `base_color` (kd) plus a normalized Phong lobe
    /// `specular` (ks) · (n + 2)/(2π) · cos^n α around the mirror direction,
    /// n = `shininess`.
    Phong,
    /// Perfect specular reflection tinted by `base_color`.
    Mirror,
    /// glTF 2.0 metallic-roughness (appendix B): Lambertian diffuse under a
    /// GGX specular layer (exact dielectric Fresnel with
    /// `KHR_materials_specular`'s factor and colour), mixed by `metallic`
    /// with a GGX metal (Schlick Fresnel, F0 = `base_color`);
    /// `transmission` replaces diffuse by glass of index `ior` (a closed
    /// refractive volume when `thickness` > 0, absorbing `attenuation` per
    /// unit length inside; thin-walled otherwise). Roughness² below
    /// `GGX_SMOOTH_ALPHA` makes the specular lobes deltas.
    Gltf,
}

impl MaterialKind {
    /// The `MATERIAL_*` constant the kernels switch on.
    pub fn gpu_kind(self) -> u32 {
        use crate::constants::*;
        match self {
            MaterialKind::Lambert => MATERIAL_LAMBERT,
            MaterialKind::Phong => MATERIAL_PHONG,
            MaterialKind::Mirror => MATERIAL_MIRROR,
            MaterialKind::Gltf => MATERIAL_GLTF,
        }
    }
}

/// A surface material: scattering `kind` with its parameters (unused ones
/// are ignored); `emission` is emitted radiance (glTF `emissiveFactor` times
/// `KHR_materials_emissive_strength`), leaving the front face only unless
/// `double_sided`.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub kind: MaterialKind,
    pub base_color: Vec3,
    pub emission: Vec3,
    pub double_sided: bool,
    /// Phong specular colour ks.
    pub specular: Vec3,
    /// Phong exponent n.
    pub shininess: f32,
    /// Index of refraction (inside over outside; the outside is the side the
    /// geometric normals point to; may be below 1 through the vkpt extras).
    pub ior: f32,
    /// glTF metallic factor, 0..1.
    pub metallic: f32,
    /// glTF perceptual roughness, 0..1 (GGX alpha is its square).
    pub roughness: f32,
    /// `KHR_materials_transmission` factor, 0..1.
    pub transmission: f32,
    /// `KHR_materials_specular`: specularColorFactor and specularFactor.
    pub specular_color: Vec3,
    pub specular_factor: f32,
    /// `KHR_materials_volume` absorption coefficient per scene unit
    /// (-ln(attenuationColor) / attenuationDistance); zero is clear.
    pub attenuation: Vec3,
    /// `KHR_materials_volume` thicknessFactor; 0 means thin-walled.
    pub thickness: f32,
    /// baseColorFactor's alpha.
    pub alpha: f32,
    /// glTF alphaMode: how alpha (`alpha` × baseColor texture A) decides
    /// whether a ray meets the surface.
    pub alpha_mode: AlphaMode,
    /// Normal texture scale.
    pub normal_scale: f32,
    /// Texture slots (each multiplies the factor beside it).
    pub textures: MaterialTextures,
    /// The glTF PBR extension lobes (clearcoat, sheen, ...); none by default.
    pub lobes: PbrLobes,
    /// `KHR_materials_unlit`: the base colour is emitted as is and nothing
    /// is scattered (the loader sets `emission` and `kind` so); it does not
    /// count as a lamp when deciding whether the scene needs default light.
    pub unlit: bool,
}

/// The glTF PBR extensions' parameters, as their specifications name them
/// (`KHR_materials_clearcoat`, `_sheen`, `_iridescence`, `_anisotropy`,
/// `_diffuse_transmission`, `_dispersion`). An extension the file does not
/// use keeps its factor at 0, which turns its lobe off.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PbrLobes {
    pub clearcoat: f32,
    /// Perceptual roughness of the coat (GGX alpha is its square).
    pub clearcoat_roughness: f32,
    pub clearcoat_normal_scale: f32,
    pub sheen_color: Vec3,
    pub sheen_roughness: f32,
    pub iridescence: f32,
    pub iridescence_ior: f32,
    /// Film thickness in nanometres where the thickness texture reads 0 and 1.
    pub iridescence_thickness_min: f32,
    pub iridescence_thickness_max: f32,
    pub anisotropy_strength: f32,
    /// Radians, counter-clockwise from the tangent toward the bitangent.
    pub anisotropy_rotation: f32,
    pub diffuse_transmission: f32,
    pub diffuse_transmission_color: Vec3,
    /// 20 / Abbe number (the spec's definition); 0 is no dispersion.
    pub dispersion: f32,
}

impl PbrLobes {
    /// The `LOBE_*` mask of the lobes that can scatter light.
    pub fn mask(&self) -> u32 {
        use crate::constants::*;
        let mut m = 0;
        if self.clearcoat > 0.0 {
            m |= LOBE_CLEARCOAT;
        }
        if self.sheen_color.max_element() > 0.0 {
            m |= LOBE_SHEEN;
        }
        if self.iridescence > 0.0 {
            m |= LOBE_IRIDESCENCE;
        }
        if self.anisotropy_strength > 0.0 {
            m |= LOBE_ANISOTROPY;
        }
        if self.diffuse_transmission > 0.0 {
            m |= LOBE_DIFFUSE_TRANSMISSION;
        }
        if self.dispersion > 0.0 {
            m |= LOBE_DISPERSION;
        }
        m
    }
}

impl Material {
    /// A Lambertian material with albedo `base_color`, no emission.
    pub fn lambert(name: &str, base_color: Vec3) -> Self {
        Material {
            name: name.to_string(),
            kind: MaterialKind::Lambert,
            base_color,
            emission: Vec3::ZERO,
            double_sided: false,
            specular: Vec3::ZERO,
            shininess: 0.0,
            ior: 1.5,
            metallic: 0.0,
            roughness: 1.0,
            transmission: 0.0,
            specular_color: Vec3::ONE,
            specular_factor: 1.0,
            attenuation: Vec3::ZERO,
            thickness: 0.0,
            alpha: 1.0,
            alpha_mode: AlphaMode::Opaque,
            normal_scale: 1.0,
            textures: MaterialTextures::default(),
            lobes: PbrLobes::default(),
            unlit: false,
        }
    }

    /// The glTF default material, used by primitives that name none: every
    /// property at its default (glTF 2.0, "Default Material"), so white
    /// base color, metallic 1 and roughness 1, a rough white metal, as the
    /// Khronos sample viewer and three.js render it.
    pub fn gltf_default() -> Self {
        Material {
            kind: MaterialKind::Gltf,
            metallic: 1.0,
            roughness: 1.0,
            ..Material::lambert("(glTF default material)", Vec3::ONE)
        }
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// A camera, its position relative to [`Scene::world_origin`]. `forward`, `up` are unit and orthogonal; `yfov`
/// is the full vertical field of view in radians (perspective cameras; the
/// view's height for an orthographic one is in `projection`). See
/// `camera.rs` for the lens, filter and exposure model.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub name: String,
    pub position: Vec3,
    pub forward: Vec3,
    pub up: Vec3,
    pub yfov: f32,
    /// The aspect ratio the file asks for (width / height), if any.
    pub aspect_ratio: Option<f32>,
    pub projection: Projection,
    /// The thin lens (a pinhole unless its f-number is above 0).
    pub lens: ThinLens,
    pub filter: PixelFilter,
    /// Shutter time in seconds and ISO sensitivity: with the f-number they
    /// set the PNG exposure (EV100, see `output::exposure_from_camera`).
    pub shutter: Option<f32>,
    pub iso: Option<f32>,
    /// Added by vkpt to a file without cameras, framed on the posed scene
    /// (`auto_camera`): over a shutter it holds still where the shutter
    /// opens (`motion::pose_over_shutter`) instead of following the bounds.
    pub framed_automatically: bool,
}

impl Camera {
    /// A pinhole perspective camera with a box filter and no exposure
    /// settings; `forward` and `up` unit and orthogonal, `yfov` in radians.
    pub fn pinhole(name: &str, position: Vec3, forward: Vec3, up: Vec3, yfov: f32) -> Camera {
        Camera {
            name: name.to_string(),
            position,
            forward,
            up,
            yfov,
            aspect_ratio: None,
            projection: Projection::Perspective,
            lens: Default::default(),
            filter: Default::default(),
            shutter: None,
            iso: None,
            framed_automatically: false,
        }
    }

    pub fn right(&self) -> Vec3 {
        self.forward.cross(self.up).normalize()
    }
}

/// What an analytic light is (`LIGHT_*` on the GPU).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// KHR_lights_punctual point light.
    Point,
    /// KHR_lights_punctual spot light; cone angles in radians from the axis.
    Spot { inner_cone: f32, outer_cone: f32 },
    /// KHR_lights_punctual directional light.
    Directional,
    /// A point light given a radius (vkpt light extras): a sphere of uniform
    /// radiance I / (pi r^2), which has the point light's radiant intensity I
    /// in every direction.
    Sphere { radius: f32 },
    /// A directional light given an angular diameter (vkpt light extras): a
    /// disk at infinity of uniform radiance E / (pi sin^2(diameter / 2)), which
    /// gives the directional light's irradiance E on a surface facing it.
    Sun { angular_diameter: f32 },
}

/// An analytic light, its position relative to [`Scene::world_origin`]. `color` is the glTF colour times the
/// intensity: radiant intensity (W/sr, from candela as given) for point,
/// spot and sphere lights, irradiance (W/m^2, from lux as given) for
/// directional and sun lights; no 683 lm/W factor.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    pub position: Vec3,
    /// Unit direction the light travels (the node's -Z).
    pub direction: Vec3,
    pub color: Vec3,
    /// glTF `range` (point and spot lights).
    pub range: Option<f32>,
}

/// Choices the user makes about how a scene file is read.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Read buffers and images that the file's URIs place outside its own
    /// folder (absolute paths, `..`, symbolic links leading out); refused
    /// by default (the command line's `--allow-outside-uris`).
    pub allow_outside_uris: bool,
    /// The camera that will render (a name or an index, as `--camera`
    /// takes it; `None`: the first): its position becomes
    /// [`Scene::world_origin`], where f32 coordinates are finest.
    pub camera: Option<String>,
    /// The `KHR_materials_variants` variant to render, by name or index
    /// (`--variant`); `None`: the file's default materials.
    pub variant: Option<String>,
    /// The instant to pose the scene at, in seconds (`--time`): every
    /// animation that plays is sampled there (see `gltf/animation.rs`).
    pub time: f64,
    /// The one animation that plays, by name or index (`--animation`);
    /// `None`: all of them.
    pub animation: Option<String>,
    /// Which meshes placed more than once are kept once (`--instancing`).
    pub instancing: InstancingMode,
}

/// Everything a render needs to know about the world.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub source: PathBuf,
    /// The world point (in the file's coordinates, f64) that every position
    /// in this scene is measured from: triangles, cameras and lights are
    /// stored in f32 *relative to it*. The loader composes node transforms
    /// in f64 and subtracts this origin before anything becomes f32, and
    /// chooses it as the position of the camera that will render
    /// ([`LoadOptions::camera`]; for a file without cameras, the centre of
    /// the scene's bounds, a few radii from the automatic camera). So the
    /// scene's place in the world does not matter: a Cornell box 1e7 m from
    /// the file's origin gets the same f32 coordinates as one at the origin,
    /// and float steps are finest where the image is made (camera-relative
    /// rendering, as large-world engines do). Rebasing here, at load, keeps
    /// one source of truth: the packer, both back ends, the scene hash and
    /// every test read the same camera-relative f32 data, and nothing
    /// downstream needs f64. Hand-built scenes leave it at zero.
    pub world_origin: DVec3,
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    /// Decoded images the materials' textures read.
    pub images: Vec<TextureImage>,
    /// Texture coordinates and tangents of each triangle (same index as
    /// `triangles`), or empty when no material has a texture.
    pub texcoords: Vec<Texcoords>,
    /// Cameras in the file, in glTF node-traversal order. When the file has
    /// none, the loader adds one framed on the scene bounds.
    pub cameras: Vec<Camera>,
    /// Uniform environment radiance seen by rays that leave the scene; with
    /// an `environment_map`, the factor its texels are scaled by.
    pub environment: Option<Vec3>,
    /// Analytic lights (KHR_lights_punctual, spheres, suns).
    pub lights: Vec<Light>,
    /// An equirectangular environment map (`--env`, scene extras).
    pub environment_map: Option<EnvironmentMap>,
    /// Rotation of the environment map about +Y, in degrees.
    pub environment_rotation: f32,
    /// Camera rays that leave the scene see black; the environment still lights.
    pub environment_hidden: bool,
    /// What vkpt decided on the user's behalf (default light, automatic
    /// camera, skipped primitives): printed before rendering, each as
    /// [`note_line`] words it. A note that starts with `warning: ` is one.
    pub notes: Vec<String>,
    /// The scene at more moments of an open shutter, when it moves then
    /// and the kernels follow it (`motion::pose_over_shutter`).
    pub motion: Option<motion::SceneMotion>,
    /// Meshes kept once and placed more than once: then `triangles` holds
    /// the triangles in place first and each such mesh once after them,
    /// in its own space (a two-level scene). `None`: every triangle is in
    /// place (one level).
    pub instancing: Option<Instancing>,
    /// How light sampling picks a light (`--light-sampler`).
    pub light_sampler: LightSampler,
}

/// How light sampling picks the light for a shading point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSampler {
    /// The light BVH where the scene has `LIGHT_TREE_MIN_LIGHTS` emitters
    /// or more (and does not move during the shutter), else `Power`.
    #[default]
    Auto,
    /// In proportion to each light's power, wherever the point is.
    Power,
    /// By the light BVH: each light's importance to the point.
    Bvh,
}

/// The meshes of a two-level scene and where they are placed: what the
/// top-level BVH (`packed::instances`) is built from.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Instancing {
    /// `Scene::triangles[..placed]` are in place, relative to the world
    /// origin, as in a one-level scene.
    pub placed: usize,
    /// The meshes kept once: ranges of `Scene::triangles` after `placed`,
    /// each in the mesh's own space.
    pub meshes: Vec<std::ops::Range<usize>>,
    /// The placements.
    pub instances: Vec<Instance>,
}

/// One placement of a mesh of [`Instancing::meshes`].
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    pub mesh: usize,
    /// Object to world, relative to [`Scene::world_origin`], composed in f64.
    pub to_world: glam::DMat4,
}

/// Whether a transform can place a mesh: finite and invertible.
pub fn placeable(m: &glam::DMat4) -> bool {
    let det = m.determinant();
    m.is_finite() && det.is_finite() && det.abs() > 1e-30
}

/// How meshes placed more than once are stored (`--instancing`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InstancingMode {
    /// Kept once where the copies would add many triangles
    /// (`AUTO_MIN_SAVED_TRIANGLES`); small repeats are copied, which
    /// spares every ray the top level.
    #[default]
    Auto,
    /// Every mesh placed more than once is kept once.
    On,
    /// Every placement is a copy (one level).
    Off,
}

impl Instancing {
    /// Triangles the scene places: those in place and every instance's.
    pub fn placed_triangles(&self) -> u64 {
        self.placed as u64
            + self
                .instances
                .iter()
                .map(|i| self.meshes[i.mesh].len() as u64)
                .sum::<u64>()
    }
}

impl Scene {
    /// Frees the triangles and their texture coordinates once a
    /// `PackedScene` holds them: a render reads the packed arrays only,
    /// and a big mesh's triangles are 76 bytes each (docs/performance.md,
    /// "Memory per triangle"). The scene is then only good for what a
    /// render reads besides them (cameras, lights, materials).
    pub fn release_geometry(&mut self) {
        self.triangles = Vec::new();
        self.texcoords = Vec::new();
    }

    /// Loads a scene file, choosing the loader by extension.
    pub fn load(path: &Path) -> anyhow::Result<Scene> {
        Self::load_with(path, &LoadOptions::default())
    }

    /// [`Scene::load`] with the user's [`LoadOptions`].
    pub fn load_with(path: &Path, options: &LoadOptions) -> anyhow::Result<Scene> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("gltf") | Some("glb") => load_gltf_with(path, options),
            _ => anyhow::bail!(
                "{}: unsupported scene format (vkpt reads glTF 2.0: .gltf or .glb)",
                path.display()
            ),
        }
    }

    /// Opens a scene file to pose at any time ([`GltfFile::at`]), choosing
    /// the loader by extension.
    pub fn open_file(path: &Path, options: &LoadOptions) -> anyhow::Result<GltfFile> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("gltf") | Some("glb") => GltfFile::open(path, options),
            _ => anyhow::bail!(
                "{}: unsupported scene format (vkpt reads glTF 2.0: .gltf or .glb)",
                path.display()
            ),
        }
    }

    /// Where `p` (relative to [`Scene::world_origin`]) is in the file's
    /// world coordinates.
    pub fn world_position(&self, p: Vec3) -> DVec3 {
        self.world_origin + p.as_dvec3()
    }

    /// Bounds of all triangles where they are placed (relative to the
    /// world origin), or `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let Some(inst) = &self.instancing else {
            return triangle_bounds(&self.triangles);
        };
        let mut bounds = triangle_bounds(&self.triangles[..inst.placed]);
        for i in &inst.instances {
            let Some((lo, hi)) = triangle_bounds(&self.triangles[inst.meshes[i.mesh].clone()])
            else {
                continue;
            };
            for k in 0..8 {
                let corner = DVec3::new(
                    if k & 1 == 0 { lo.x } else { hi.x } as f64,
                    if k & 2 == 0 { lo.y } else { hi.y } as f64,
                    if k & 4 == 0 { lo.z } else { hi.z } as f64,
                );
                let p = i.to_world.transform_point3(corner).as_vec3();
                bounds = Some(bounds.map_or((p, p), |(a, b)| (a.min(p), b.max(p))));
            }
        }
        bounds
    }

    pub fn emissive_triangle_count(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| self.materials[t.material as usize].is_emissive())
            .count()
    }
}

/// Bounds of the triangles' vertices, or `None` for none.
pub fn triangle_bounds(triangles: &[Triangle]) -> Option<(Vec3, Vec3)> {
    let mut it = triangles.iter().flat_map(|t| t.positions.iter());
    let first = *it.next()?;
    Some(it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
}

/// How a scene note is printed: `warning: ...` for a warning (a note that
/// starts so), `note: ...` for anything else.
pub fn note_line(note: &str) -> String {
    if note.starts_with("warning: ") {
        note.to_string()
    } else {
        format!("note: {note}")
    }
}
