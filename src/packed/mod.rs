//! The scene flattened into the arrays the kernels read (the buffers of
//! the `bindings` table). The CPU reference reads the same arrays,
//! so both back ends see identical data.

pub mod bindings;
pub mod binned;
pub mod bvh;
pub mod collapse;
pub mod content_hash;
pub mod features;
pub mod instances;
pub mod layout;
pub mod light_bvh;
pub mod lights;
pub mod motion;
pub mod settings;
pub mod sheen_table;
pub mod textures;
pub mod triangle_records;

use crate::constants::{
    ALPHA_BLEND, ALPHA_OPAQUE, DEPTH_UNLIMITED, LIGHT_TREE_MIN_LIGHTS, MOTION_CAMERA_STILL,
    NO_TEXTURE, PROJECTION_ORTHOGRAPHIC, PROJECTION_PERSPECTIVE,
};
use crate::packed::layout::{
    CwBvhNode, Emitter, Instance, Light, LightParams, MaterialData, RenderParams, TriangleShading,
    TriangleVerts,
};
use crate::packed::light_bvh::LightTree;
use crate::packed::lights::pack_lights;
use crate::packed::settings::{RenderSettings, TextureFilter};
use crate::packed::textures::{PackedTextures, emissive_texture_mean, pack_textures};
use crate::scene::{AlphaMode, LightKind, LightSampler, Projection, Scene};
use bvh::Bvh;
use glam::Vec3;
use std::time::Duration;

pub struct PackedScene {
    /// Compressed wide BVH8 nodes (`layout::CwBvhNode`); the root is node 0.
    pub nodes: Vec<CwBvhNode>,
    /// Triangles in BVH order.
    pub tri_verts: Vec<TriangleVerts>,
    pub tri_shading: Vec<TriangleShading>,
    pub materials: Vec<MaterialData>,
    /// Emissive triangles with their power-proportional selection cdf.
    pub emitters: Vec<Emitter>,
    /// Texture table, texels and per-triangle texture coordinates.
    pub textures: PackedTextures,
    /// Uniform environment radiance, or the factor an environment map's
    /// texels are scaled by.
    pub environment: Vec3,
    pub bvh_build_time: Duration,
    /// Light selection and the environment map's shape (`light_params`).
    pub light_params: LightParams,
    /// Analytic lights (one unused entry when there are none).
    pub lights: Vec<Light>,
    /// Environment map cdfs and texels.
    pub env_cdf: Vec<f32>,
    pub env_radiance: Vec<[f32; 4]>,
    /// Probability that light sampling picks the environment.
    pub env_select_prob: f32,
    /// The light BVH (`light_params.tree_nodes > 0`), or one dummy node.
    pub light_tree: LightTree,
    /// The time steps of a scene that moves while the shutter is open.
    pub motion: Option<motion::PackedMotion>,
    /// A two-level scene's instances, in its top level's leaf order
    /// (`instances`); empty in a one-level scene.
    pub instances: Vec<Instance>,
    /// Nodes of the top level, stored first (0 in a one-level scene).
    pub top_nodes: u32,
    /// What a two-level scene holds, for the summary.
    pub instancing: Option<instances::InstancingStats>,
}

use crate::packed::lights::luminance;

/// Hands the heap the build and the packing freed back to the system
/// (glibc keeps freed blocks for reuse: 38 MiB of them after packing 5 M
/// triangles, which the CPU back end's copies then came on top of).
fn return_freed_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only releases free memory; it touches no live
    // allocation.
    unsafe {
        libc::malloc_trim(0);
    }
}

impl PackedScene {
    /// Packs `scene` for both back ends; the scene keeps its geometry.
    pub fn new(scene: &Scene) -> anyhow::Result<PackedScene> {
        Self::pack(scene, None)
    }

    /// Packs `scene` and releases its geometry (`Scene::release_geometry`),
    /// the triangles as they are packed: a big mesh's peak memory then
    /// holds its triangles or their packed records, not both in full
    /// (docs/performance.md, "Memory per triangle"). The same arrays as
    /// `new`'s.
    pub fn from_scene(scene: &mut Scene) -> anyhow::Result<PackedScene> {
        let packed = if scene.motion.is_none() && scene.instancing.is_none() {
            let triangles = std::mem::take(&mut scene.triangles);
            Self::pack(scene, Some(triangles))
        } else {
            Self::new(scene)
        };
        scene.release_geometry();
        return_freed_heap();
        packed
    }

    /// `new`, reading the triangles from `owned` (then consumed) when given
    /// and from the scene otherwise.
    fn pack(
        scene: &Scene,
        owned: Option<Vec<crate::scene::Triangle>>,
    ) -> anyhow::Result<PackedScene> {
        let mut two_level = None;
        let Bvh {
            nodes,
            order,
            build_time,
        } = match (&scene.motion, &scene.instancing) {
            (None, None) => bvh::build(owned.as_deref().unwrap_or(&scene.triangles))?,
            (Some(m), None) => {
                let steps: Vec<&[crate::scene::Triangle]> =
                    m.steps.iter().map(|s| &s.triangles[..]).collect();
                bvh::build_swept(&steps)?
            }
            (None, Some(inst)) => {
                let t = instances::build(scene, inst)?;
                let bvh = Bvh {
                    nodes: t.nodes,
                    order: t.order,
                    build_time: t.stats.bottom_build_time + t.stats.top_build_time,
                };
                two_level = Some((t.instances, t.top_nodes, t.stats));
                bvh
            }
            (Some(_), Some(_)) => {
                anyhow::bail!("a scene that moves during the shutter is kept in one level")
            }
        };
        let (mut tri_verts, mut tri_shading) = match owned {
            Some(triangles) => triangle_records::consume(triangles, &order, &scene.materials),
            None => triangle_records::gather(&scene.triangles, &order, &scene.materials),
        };
        let mut materials: Vec<MaterialData> = scene
            .materials
            .iter()
            .map(|m| MaterialData {
                base_color: m.base_color.into(),
                kind: m.kind.gpu_kind(),
                emission: m.emission.into(),
                double_sided: m.double_sided as u32,
                specular: m.specular.into(),
                shininess: m.shininess,
                ior: m.ior,
                metallic: m.metallic,
                roughness: m.roughness,
                transmission: m.transmission,
                specular_color: m.specular_color.into(),
                specular_factor: m.specular_factor,
                attenuation: m.attenuation.into(),
                // Only glTF materials refract, so only they can enclose a volume.
                thickness: if m.kind.gpu_kind() == crate::constants::MATERIAL_GLTF {
                    m.thickness
                } else {
                    0.0
                },
                alpha: m.alpha,
                alpha_cutoff: match m.alpha_mode {
                    AlphaMode::Opaque => ALPHA_OPAQUE,
                    AlphaMode::Mask { cutoff } => cutoff,
                    AlphaMode::Blend => ALPHA_BLEND,
                },
                normal_scale: m.normal_scale,
                clearcoat: m.lobes.clearcoat,
                clearcoat_roughness: m.lobes.clearcoat_roughness,
                clearcoat_normal_scale: m.lobes.clearcoat_normal_scale,
                lobes: m.lobes.mask(),
                sheen_color: m.lobes.sheen_color.into(),
                sheen_roughness: m.lobes.sheen_roughness,
                iridescence: m.lobes.iridescence,
                iridescence_ior: m.lobes.iridescence_ior,
                iridescence_thickness_min: m.lobes.iridescence_thickness_min,
                iridescence_thickness_max: m.lobes.iridescence_thickness_max,
                diffuse_transmission_color: m.lobes.diffuse_transmission_color.into(),
                diffuse_transmission: m.lobes.diffuse_transmission,
                anisotropy_strength: m.lobes.anisotropy_strength,
                anisotropy_rotation: m.lobes.anisotropy_rotation,
                dispersion: m.lobes.dispersion,
                base_color_texture: NO_TEXTURE,
                metallic_roughness_texture: NO_TEXTURE,
                normal_texture: NO_TEXTURE,
                emissive_texture: NO_TEXTURE,
                specular_texture: NO_TEXTURE,
                specular_color_texture: NO_TEXTURE,
                transmission_texture: NO_TEXTURE,
                ..Default::default()
            })
            .collect();

        let textures = pack_textures(scene, &order, &mut materials)?;
        let keeps_gltf = features::basic_keeps_gltf(&materials);
        for tv in &mut tri_verts {
            let m = &materials[tv.material as usize];
            tv.shade_queue = features::shade_queue_of(m, keeps_gltf);
        }

        // Emitters are picked in proportion to the power they emit.
        let (emitters, total) = match &two_level {
            None => one_level_emitters(
                scene,
                &order,
                &tri_verts,
                &mut tri_shading,
                &materials,
                &textures,
            ),
            Some((instances, _, stats)) => instanced_emitters(
                scene,
                instances,
                stats.placed_triangles as u32,
                &tri_verts,
                &mut tri_shading,
                &materials,
                &textures,
            ),
        };

        // Many emitters: light selection by the light BVH (light_bvh).
        let tree_lights = emitters.len()
            + scene
                .lights
                .iter()
                .filter(|l| {
                    matches!(
                        l.kind,
                        LightKind::Sphere { .. } | LightKind::Point | LightKind::Spot { .. }
                    )
                })
                .count();
        let use_tree = scene.motion.is_none()
            && tree_lights > 0
            && match scene.light_sampler {
                LightSampler::Power => false,
                LightSampler::Bvh => true,
                LightSampler::Auto => tree_lights >= LIGHT_TREE_MIN_LIGHTS as usize,
            };
        let mut packed_lights = pack_lights(scene, total, use_tree);
        let instances_placed = two_level.as_ref().map_or(&[][..], |t| &t.0[..]);
        let light_tree = if use_tree {
            let emitter_power: Vec<f64> = emitters
                .iter()
                .map(|e| std::f64::consts::PI * e.pmf as f64 * total)
                .collect();
            light_bvh::build(
                &emitters,
                &emitter_power,
                &tri_verts,
                &materials,
                instances_placed,
                &packed_lights.lights[..packed_lights.light_params.num_lights as usize],
                &packed_lights.powers,
            )
        } else {
            None
        };
        let light_tree = match light_tree {
            Some(tree) => {
                packed_lights.light_params.tree_nodes = tree.nodes.len() as u32;
                tree
            }
            None => {
                if use_tree {
                    // No light with power: nothing to choose between.
                    packed_lights = pack_lights(scene, total, false);
                }
                LightTree::none()
            }
        };
        Ok(PackedScene {
            nodes,
            tri_verts,
            tri_shading,
            materials,
            emitters,
            textures,
            environment: scene.environment.unwrap_or(Vec3::ZERO),
            bvh_build_time: build_time,
            light_params: packed_lights.light_params,
            lights: packed_lights.lights,
            env_cdf: packed_lights.env_cdf,
            env_radiance: packed_lights.env_radiance,
            env_select_prob: packed_lights.env_select_prob,
            light_tree,
            motion: scene
                .motion
                .as_ref()
                .map(|m| motion::pack_motion(scene, m, &order)),
            instances: two_level.as_ref().map_or(Vec::new(), |t| t.0.clone()),
            top_nodes: two_level.as_ref().map_or(0, |t| t.1),
            instancing: two_level.as_ref().map(|t| t.2),
        })
    }

    /// Bytes of the arrays the kernels read (what a render uploads).
    pub fn memory_bytes(&self) -> u64 {
        use std::mem::size_of_val;
        let t = &self.textures;
        (size_of_val(&self.nodes[..])
            + size_of_val(&self.tri_verts[..])
            + size_of_val(&self.tri_shading[..])
            + size_of_val(&self.materials[..])
            + size_of_val(&self.emitters[..])
            + size_of_val(&t.textures[..])
            + size_of_val(&t.texels[..])
            + size_of_val(&t.tri_texcoords[..])
            + size_of_val(&self.lights[..])
            + size_of_val(&self.env_cdf[..])
            + size_of_val(&self.env_radiance[..])
            + size_of_val(&self.instances[..])
            + size_of_val(&self.light_tree.nodes[..])
            + size_of_val(&self.light_tree.trails[..])
            + self
                .motion
                .as_ref()
                .map_or(0, |m| size_of_val(&m.texels[..]))) as u64
    }

    pub fn has_environment(&self) -> bool {
        self.environment.max_element() > 0.0
    }

    /// The uniform parameters of a render of this scene.
    pub fn render_params(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        pool_size: u32,
    ) -> anyhow::Result<RenderParams> {
        let camera = scene.cameras.get(settings.camera).ok_or_else(|| {
            anyhow::anyhow!(
                "camera {} does not exist: {} has {} camera(s)",
                settings.camera,
                scene.source.display(),
                scene.cameras.len()
            )
        })?;
        let [_, right, up, _] = motion::camera_frame(camera);
        camera.check_lens(&mut Vec::new())?;
        let (projection, tan_half_fov, lens_radius) = match camera.projection {
            Projection::Perspective => (
                PROJECTION_PERSPECTIVE,
                (0.5 * camera.yfov).tan(),
                camera.lens.aperture_radius(camera.yfov),
            ),
            Projection::Orthographic { half_height } => (PROJECTION_ORTHOGRAPHIC, half_height, 0.0),
        };
        let region = settings.film_region();
        Ok(RenderParams {
            cam_position: camera.position.into(),
            tan_half_fov,
            cam_right: right.into(),
            aspect: settings.width as f32 / settings.height as f32,
            cam_up: up.into(),
            cam_forward: camera.forward.into(),
            // One pixel's footprint per unit distance (per unit, orthographic).
            texture_spread: match settings.texture_filter {
                TextureFilter::Mip => 2.0 * tan_half_fov / settings.height as f32,
                TextureFilter::Bilinear => 0.0,
            },
            lens_radius,
            focus_distance: camera.lens.focus_distance.unwrap_or(1.0),
            aperture_blades: camera.lens.blades,
            blade_rotation: camera.lens.blade_rotation,
            projection,
            filter_kind: camera.filter.kind.gpu_kind(),
            filter_radius: camera.filter.radius,
            environment: self.environment.into(),
            env_select_prob: self.env_select_prob,
            width: settings.width,
            height: settings.height,
            max_depth: settings.max_depth.unwrap_or(DEPTH_UNLIMITED),
            seed: settings.seed,
            num_emitters: self.emitters.len() as u32,
            num_triangles: self.tri_verts.len() as u32,
            pool_size,
            rng_sampler: settings.sampler.id(),
            region_x: region.x0,
            region_y: region.y0,
            region_width: region.width(),
            region_height: region.height(),
            sample_offset: settings.first_sample,
            aov: settings.aov as u32,
            motion_steps: self.motion.as_ref().map_or(0, |m| m.steps),
            // 0 in still scenes, as the pad word was (the scene hash reads it).
            motion_camera_base: match &self.motion {
                Some(m) if m.camera_moves(settings.camera) => 4 * m.steps * settings.camera as u32,
                Some(_) => MOTION_CAMERA_STILL,
                None => 0,
            },
            motion_vertex_base: self.motion.as_ref().map_or(0, |m| m.vertex_base),
            num_instances: self.instances.len() as u32,
        })
    }
}

/// The emissive triangles of a one-level scene with their
/// power-proportional cdf; each triangle's `light_pmf` is its probability.
/// Returns them and the total power.
fn one_level_emitters(
    scene: &Scene,
    order: &[u32],
    tri_verts: &[TriangleVerts],
    tri_shading: &mut [TriangleShading],
    materials: &[MaterialData],
    textures: &PackedTextures,
) -> (Vec<Emitter>, f64) {
    let mut emitters = Vec::new();
    let mut total = 0.0f64;
    for (slot, tv) in tri_verts.iter().enumerate() {
        let m = &scene.materials[tv.material as usize];
        if !m.is_emissive() {
            continue;
        }
        let (v0, v1, v2) = (Vec3::from(tv.v0), Vec3::from(tv.v1), Vec3::from(tv.v2));
        // A moving emitter is picked by its largest area over the
        // shutter (sampling uses its area at the path's time).
        let area = match &scene.motion {
            None => 0.5 * (v1 - v0).cross(v2 - v0).length(),
            Some(m) => m
                .steps
                .iter()
                .map(|s| {
                    let [a, b, c] = s.triangles[order[slot] as usize].positions;
                    0.5 * (b - a).cross(c - a).length()
                })
                .fold(0.0f32, f32::max),
        };
        if !(area > 0.0) || !area.is_finite() {
            continue;
        }
        let sides = if m.double_sided { 2.0 } else { 1.0 };
        let textured = materials[tv.material as usize].emissive_texture;
        let texture_mean = if textured == NO_TEXTURE {
            1.0
        } else {
            emissive_texture_mean(textures, textured, slot as u32)
        };
        let power = luminance(m.emission) as f64 * area as f64 * sides * texture_mean as f64;
        if !(power > 0.0) {
            continue;
        }
        total += power;
        emitters.push((slot as u32, power, area));
    }
    let mut running = 0.0f64;
    let emitters: Vec<Emitter> = emitters
        .iter()
        .enumerate()
        .map(|(k, &(slot, power, area))| {
            running += power;
            let pmf = (power / total) as f32;
            tri_shading[slot as usize].light_pmf = pmf;
            Emitter {
                triangle: slot,
                // The last cdf is exactly 1 so every u in [0, 1) finds an emitter.
                cdf: if k + 1 == emitters.len() {
                    1.0
                } else {
                    (running / total) as f32
                },
                pmf,
                area,
            }
        })
        .collect();

    (emitters, total)
}

/// The emitters of a two-level scene: every emissive triangle of every
/// instance, its power from its area where the instance places it, without
/// copying the triangle (an `Emitter`'s `triangle` is the pair's hit id).
/// A triangle's `light_pmf` is its probability per unit of placed area,
/// the same for every instance of it: `shade_path` multiplies it by the
/// area it finds. Returns the emitters and the total power.
fn instanced_emitters(
    scene: &Scene,
    instances: &[Instance],
    placed_triangles: u32,
    tri_verts: &[TriangleVerts],
    tri_shading: &mut [TriangleShading],
    materials: &[MaterialData],
    textures: &PackedTextures,
) -> (Vec<Emitter>, f64) {
    // Power per unit area of each emissive slot.
    let density: Vec<(u32, f64)> = tri_verts
        .iter()
        .enumerate()
        .filter_map(|(slot, tv)| {
            let m = &scene.materials[tv.material as usize];
            if !m.is_emissive() {
                return None;
            }
            let sides = if m.double_sided { 2.0 } else { 1.0 };
            let textured = materials[tv.material as usize].emissive_texture;
            let texture_mean = if textured == NO_TEXTURE {
                1.0
            } else {
                emissive_texture_mean(textures, textured, slot as u32)
            };
            let d = luminance(m.emission) as f64 * sides * texture_mean as f64;
            (d > 0.0).then_some((slot as u32, d))
        })
        .collect();
    let mut emitters = Vec::new();
    let mut total = 0.0f64;
    if !density.is_empty() {
        for (k, inst) in instances.iter().enumerate() {
            let count = instances
                .get(k + 1)
                .map_or(placed_triangles, |next| next.id_base)
                - inst.id_base;
            let slots = inst.first_triangle..inst.first_triangle + count;
            let m = glam::DMat3::from_cols_array_2d(
                &[0, 1, 2].map(|c| [0, 1, 2].map(|r| inst.to_world()[r][c] as f64)),
            );
            let start = density.partition_point(|&(s, _)| s < slots.start);
            for &(slot, d) in density[start..]
                .iter()
                .take_while(|(s, _)| slots.contains(s))
            {
                let tv = &tri_verts[slot as usize];
                let (v0, v1, v2) = (Vec3::from(tv.v0), Vec3::from(tv.v1), Vec3::from(tv.v2));
                let e1 = m * (v1 - v0).as_dvec3();
                let e2 = m * (v2 - v0).as_dvec3();
                let area = 0.5 * e1.cross(e2).length();
                let power = d * area;
                if !(power > 0.0) || !power.is_finite() {
                    continue;
                }
                total += power;
                emitters.push((
                    slot - inst.first_triangle + inst.id_base,
                    power,
                    area as f32,
                ));
            }
        }
    }
    for &(slot, d) in &density {
        tri_shading[slot as usize].light_pmf = if total > 0.0 { (d / total) as f32 } else { 0.0 };
    }
    let mut running = 0.0f64;
    let n = emitters.len();
    let emitters = emitters
        .into_iter()
        .enumerate()
        .map(|(k, (id, power, area))| {
            running += power;
            Emitter {
                triangle: id,
                cdf: if k + 1 == n {
                    1.0
                } else {
                    (running / total) as f32
                },
                pmf: (power / total) as f32,
                area,
            }
        })
        .collect();
    (emitters, total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Triangle};

    /// A bumpy height field of `2 * side * side` triangles.
    fn bumpy_mesh(side: usize) -> Scene {
        let at = |i: usize, j: usize| {
            let (x, z) = (i as f32 * 0.01, j as f32 * 0.01);
            Vec3::new(x, 0.05 * (x * 37.0).sin() * (z * 23.0).cos(), z)
        };
        let tri = |a: Vec3, b: Vec3, c: Vec3| Triangle {
            positions: [a, b, c],
            normals: [Vec3::Y; 3],
            material: 0,
        };
        let triangles = (0..side * side)
            .flat_map(|k| {
                let (i, j) = (k % side, k / side);
                let [a, b, c, d] = [at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)];
                [tri(a, c, b), tri(b, c, d)]
            })
            .collect();
        Scene {
            source: "bumpy mesh".into(),
            triangles,
            materials: vec![Material::lambert("white", Vec3::splat(0.8))],
            ..Default::default()
        }
    }

    /// What a big static mesh costs the kernels grows with its triangles
    /// as the arrays say it should: a vertex and a shading record each, and
    /// nodes for at most one in four (obvhs' CWBVH holds up to three
    /// triangles per leaf and eight children per node; bumpy-1.31m has
    /// one node per 9.3 triangles). A per-triangle array added to the
    /// packed scene, or a collapse that leaves a node per triangle, breaks it.
    #[test]
    fn a_big_mesh_packs_in_its_vertices_shading_and_a_few_nodes() {
        let scene = bumpy_mesh(160);
        let n = scene.triangles.len();
        let packed = PackedScene::new(&scene).unwrap();
        let per_triangle = size_of::<TriangleVerts>() + size_of::<TriangleShading>();
        let bound = n * per_triangle + n / 4 * size_of::<CwBvhNode>() + 4096;
        assert!(
            packed.memory_bytes() as usize <= bound,
            "{} bytes for {n} triangles: {:.1} per triangle, bound {:.1}",
            packed.memory_bytes(),
            packed.memory_bytes() as f64 / n as f64,
            bound as f64 / n as f64
        );
        assert!(
            packed.nodes.len() * 4 <= n,
            "{} nodes for {n} triangles",
            packed.nodes.len()
        );
    }
}
