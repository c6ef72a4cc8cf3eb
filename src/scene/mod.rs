//! The scene as plain Rust data: the one source of truth both back ends are
//! built from. Loaders fill it; `packed` flattens it for the kernels.

mod auto_camera;
mod gltf_data;
mod load_gltf;
mod uri;

use glam::Vec3;
use std::path::{Path, PathBuf};

pub use load_gltf::{load_gltf, load_gltf_with};

/// A world-space triangle. Its front face is the counter-clockwise side:
/// the geometric normal is `(p1 - p0) x (p2 - p0)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Triangle {
    pub positions: [Vec3; 3],
    /// Unit shading normals at the vertices (generated when the file has none).
    pub normals: [Vec3; 3],
    pub material: u32,
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
    /// Smooth glass: exact Fresnel reflection and Snell refraction with
    /// relative index `ior` (inside over outside; the outside is the side the
    /// geometric normals point to); refraction tinted by `base_color`.
    Dielectric,
}

impl MaterialKind {
    /// The `MATERIAL_*` constant the kernels switch on.
    pub fn gpu_kind(self) -> u32 {
        use crate::constants::*;
        match self {
            MaterialKind::Lambert => MATERIAL_LAMBERT,
            MaterialKind::Phong => MATERIAL_PHONG,
            MaterialKind::Mirror => MATERIAL_MIRROR,
            MaterialKind::Dielectric => MATERIAL_DIELECTRIC,
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
    /// Dielectric index of refraction (inside over outside).
    pub ior: f32,
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
        }
    }

    /// The glTF default material, used by primitives that name none.
    pub fn gltf_default() -> Self {
        Material::lambert("(glTF default material)", Vec3::ONE)
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// A pinhole camera in world space. `forward`, `up` are unit and orthogonal;
/// `yfov` is the full vertical field of view in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub name: String,
    pub position: Vec3,
    pub forward: Vec3,
    pub up: Vec3,
    pub yfov: f32,
    /// The aspect ratio the file asks for (width / height), if any.
    pub aspect_ratio: Option<f32>,
}

impl Camera {
    pub fn right(&self) -> Vec3 {
        self.forward.cross(self.up).normalize()
    }
}

/// Choices the user makes about how a scene file is read.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Read buffers and images that the file's URIs place outside its own
    /// folder (absolute paths, `..`, symbolic links leading out); refused
    /// by default (`--allow-outside-uris`).
    pub allow_outside_uris: bool,
}

/// Everything a render needs to know about the world.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub source: PathBuf,
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    /// Cameras in the file, in glTF node-traversal order. When the file has
    /// none, the loader adds one framed on the scene bounds.
    pub cameras: Vec<Camera>,
    /// Uniform environment radiance seen by rays that leave the scene.
    pub environment: Option<Vec3>,
    /// What vkpt decided on the user's behalf (default light, automatic
    /// camera, skipped primitives): printed before rendering.
    pub notes: Vec<String>,
}

impl Scene {
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

    /// World-space bounds of all triangles, or `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.triangles.iter().flat_map(|t| t.positions.iter());
        let first = *it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
    }

    pub fn emissive_triangle_count(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| self.materials[t.material as usize].is_emissive())
            .count()
    }
}
