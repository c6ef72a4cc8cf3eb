//! GPU-visible structs, defined once here and declared again in
//! `shaders/common/types.glsl`. `tests/suite/layout.rs` reads the compiled SPIR-V
//! and checks that every size and member offset agrees: a wrong offset gives
//! a wrong image with no validation error.
//!
//! The CPU reference reads the same packed arrays, so both back ends see
//! identical data. Every struct is packed in 16-byte rows (std430).

use bytemuck::{Pod, Zeroable};

/// Compressed wide BVH8 node (Ylitie, Karras and Laine, HPG 2017), 80 bytes,
/// in obvhs 0.4's encoding (`obvhs::cwbvh::node::CwBvhNode`, same field
/// order). GLSL has no 8-bit type, so the byte arrays are packed into u32
/// words, little-endian: byte `k` of an array is bits `8 * (k % 4) ..` of
/// word `k / 4`. The root is node 0.
///
/// - `p`: origin of the node's quantization grid (its bounds' minimum).
/// - `e_imask`: `e[0] | e[1] << 8 | e[2] << 16 | imask << 24`. The grid step
///   along axis `a` is the power of two with float exponent bits `e[a]`
///   (`f32::from_bits(e[a] << 23)`); bit `s` of `imask` is set when child
///   slot `s` is an inner node.
/// - `child_base_idx`: index of the first inner child; inner children are
///   stored consecutively in slot order.
/// - `primitive_base_idx`: first triangle (BVH slot) of the leaf children.
/// - `child_meta`: one byte per child slot: 0 empty; inner child
///   `0b001_00000 | (24 + slot)`; leaf child: its triangle count in unary in
///   the top 3 bits and its first triangle's offset from
///   `primitive_base_idx` in the low 5 (< 24).
/// - `qlo_*`, `qhi_*`: one byte per child slot, the child's bounds in grid
///   steps: `p + e * q`, computed in f32 (the product is exact), encloses the
///   child's exact bounds (`bvh::build` checks it, so traversal's box test
///   is conservative like `intersect_aabb`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct CwBvhNode {
    pub p: [f32; 3],
    pub e_imask: u32,
    pub child_base_idx: u32,
    pub primitive_base_idx: u32,
    pub child_meta: [u32; 2],
    pub qlo_x: [u32; 2],
    pub qhi_x: [u32; 2],
    pub qlo_y: [u32; 2],
    pub qhi_y: [u32; 2],
    pub qlo_z: [u32; 2],
    pub qhi_z: [u32; 2],
}

/// Triangle vertices for the watertight intersection test, 48 bytes.
/// `alpha_mask` is nonzero when the triangle's material is alpha MASK or
/// BLEND: traversal then looks its alpha up before accepting a hit (and
/// only then, so opaque triangles pay nothing). `shade_queue` is the
/// `SHADE_QUEUE_*` (basic or full) of the triangle's material: extend reads
/// it with the hit when shading is split by material.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct TriangleVerts {
    pub v0: [f32; 3],
    pub material: u32,
    pub v1: [f32; 3],
    pub alpha_mask: u32,
    pub v2: [f32; 3],
    pub shade_queue: u32,
}

/// What shading needs of a triangle besides its vertices, 48 bytes.
/// `light_pmf` is the probability that light sampling picks this triangle
/// among the emissive triangles (0 when it does not emit); MIS needs it when
/// a BSDF-sampled ray lands on the triangle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct TriangleShading {
    pub n0: [f32; 3],
    pub light_pmf: f32,
    pub n1: [f32; 3],
    pub _pad1: f32,
    pub n2: [f32; 3],
    pub _pad2: f32,
}

/// A material as the kernels see it, 144 bytes (nine 16-byte rows; GLSL
/// reads it as nine texels in `fetch_material`, `scene_fetch.glsl`). Texture
/// slots index the texture table (`NO_TEXTURE` when absent); a texture
/// multiplies the factor beside it, as glTF defines.
///
/// - row 0: `base_color` (Lambertian albedo; Phong diffuse `kd`; mirror tint;
///   glTF baseColorFactor), `kind` (`MATERIAL_*` in `constants.rs`).
/// - row 1: `emission`, radiance leaving the front face (both faces when
///   `double_sided != 0`).
/// - row 2: `specular` (Phong `ks`), `shininess` (Phong exponent `n`).
/// - row 3: `ior`, index of refraction relative to the outside (the side the
///   geometric normals point to; may be below 1); glTF `metallic`,
///   `roughness` (perceptual, squared to GGX alpha), `transmission`.
/// - row 4: `KHR_materials_specular`: `specular_color`, `specular_factor`.
/// - row 5: `KHR_materials_volume`: `attenuation`, the absorption
///   coefficient per scene unit (-ln(attenuationColor) / attenuationDistance;
///   0 = clear), `thickness` (0 = thin-walled).
/// - row 6: `alpha` (baseColorFactor's alpha), `alpha_cutoff` (the MASK
///   cutoff, at least 0; `ALPHA_OPAQUE` or `ALPHA_BLEND` otherwise),
///   `normal_scale`, `base_color_texture`.
/// - rows 7–8: the other texture slots.
/// - rows 9–13: the glTF PBR extension lobes (`lobes`, a `LOBE_*` mask of
///   those present). `KHR_materials_clearcoat`: `clearcoat` factor,
///   `clearcoat_roughness` (perceptual), `clearcoat_normal_scale`.
///   `KHR_materials_sheen`: `sheen_color`, `sheen_roughness`.
///   `KHR_materials_iridescence`: `iridescence` factor, `iridescence_ior`,
///   the film thickness range in nanometres (min is where the thickness
///   texture reads 0, max the factor without a texture).
///   `KHR_materials_diffuse_transmission`: `diffuse_transmission_color`,
///   `diffuse_transmission` factor. `KHR_materials_anisotropy`:
///   `anisotropy_strength`, `anisotropy_rotation` (radians, from the
///   tangent toward the bitangent). `KHR_materials_dispersion`:
///   `dispersion` (20 / Abbe number; 0 = none).
/// - rows 14–16: the extensions' texture slots, and
///   `KHR_materials_volume`'s `thickness_texture` (G × thickness).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct MaterialData {
    pub base_color: [f32; 3],
    pub kind: u32,
    pub emission: [f32; 3],
    pub double_sided: u32,
    pub specular: [f32; 3],
    pub shininess: f32,
    pub ior: f32,
    pub metallic: f32,
    pub roughness: f32,
    pub transmission: f32,
    pub specular_color: [f32; 3],
    pub specular_factor: f32,
    pub attenuation: [f32; 3],
    pub thickness: f32,
    pub alpha: f32,
    pub alpha_cutoff: f32,
    pub normal_scale: f32,
    pub base_color_texture: u32,
    pub metallic_roughness_texture: u32,
    pub normal_texture: u32,
    pub emissive_texture: u32,
    pub specular_texture: u32,
    pub specular_color_texture: u32,
    pub transmission_texture: u32,
    pub _pad1: u32,
    pub _pad2: u32,
    pub clearcoat: f32,
    pub clearcoat_roughness: f32,
    pub clearcoat_normal_scale: f32,
    pub lobes: u32,
    pub sheen_color: [f32; 3],
    pub sheen_roughness: f32,
    pub iridescence: f32,
    pub iridescence_ior: f32,
    pub iridescence_thickness_min: f32,
    pub iridescence_thickness_max: f32,
    pub diffuse_transmission_color: [f32; 3],
    pub diffuse_transmission: f32,
    pub anisotropy_strength: f32,
    pub anisotropy_rotation: f32,
    pub dispersion: f32,
    pub _pad3: u32,
    pub clearcoat_texture: u32,
    pub clearcoat_roughness_texture: u32,
    pub clearcoat_normal_texture: u32,
    pub sheen_color_texture: u32,
    pub sheen_roughness_texture: u32,
    pub iridescence_texture: u32,
    pub iridescence_thickness_texture: u32,
    pub anisotropy_texture: u32,
    pub diffuse_transmission_texture: u32,
    pub diffuse_transmission_color_texture: u32,
    pub thickness_texture: u32,
    pub _pad4: u32,
}

/// A texture reference as the kernels see it, 48 bytes: one row of the
/// texture table that `MaterialData`'s texture slots index (one row per
/// distinct image, texture coordinate set, transform and sampler).
///
/// - `transform_s`, `transform_t`: the `KHR_texture_transform` matrix's
///   rows: `(s, t) = (dot(transform_s, (u, v, 1)), dot(transform_t, (u, v, 1)))`
///   (identity without the extension).
/// - `offset`: the image's first word in the texel buffer (one RGBA8 texel
///   per u32 word, red in the low byte, rows top to bottom; grey images a
///   byte per texel, grey with alpha two, first texel in the low bits);
///   `width`, `height` in texels.
/// - `flags`: wrap S (bits 0-1) and T (bits `TEXTURE_WRAP_T_SHIFT`..) as
///   `WRAP_*`, `TEXTURE_NEAREST`, `TEXTURE_TEXCOORD_1`, and the storage,
///   `TEXTURE_GREY` or `TEXTURE_GREY_ALPHA` (`constants.rs`).
/// - `levels`: mip levels stored (1: the image alone). Level k + 1 follows
///   level k in the texel buffer, each halved (odd sizes round up) and
///   starting on a word, down to 1x1 (`texture_level`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct TextureInfo {
    pub transform_s: [f32; 3],
    pub offset: u32,
    pub transform_t: [f32; 3],
    pub flags: u32,
    pub width: u32,
    pub height: u32,
    pub levels: u32,
    pub _pad2: u32,
}

/// A triangle's texture coordinates and tangents, 96 bytes, in the same
/// (BVH) order as `TriangleVerts`; the buffer is only filled when the scene
/// has textures.
///
/// - `uv0_01`: TEXCOORD_0 of vertices 0 (xy) and 1 (zw); `uv0_2_uv1_0`:
///   TEXCOORD_0 of vertex 2, TEXCOORD_1 of vertex 0; `uv1_12`: TEXCOORD_1 of
///   vertices 1 and 2.
/// - `tangent0..2`: per-vertex tangent (xyz, world space) and the
///   bitangent sign w (bitangent = w · cross(normal, tangent), as glTF).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct TriangleTexcoords {
    pub uv0_01: [f32; 4],
    pub uv0_2_uv1_0: [f32; 4],
    pub uv1_12: [f32; 4],
    pub tangent0: [f32; 4],
    pub tangent1: [f32; 4],
    pub tangent2: [f32; 4],
}

/// An emissive triangle for light sampling, 16 bytes. Emitters are chosen
/// with probability proportional to power; `cdf` is the inclusive running sum
/// of those probabilities.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Emitter {
    pub triangle: u32,
    pub cdf: f32,
    pub pmf: f32,
    pub area: f32,
}

/// One placement of a mesh's BVH in a two-level scene, 112 bytes (seven
/// 16-byte rows; GLSL reads it as `INSTANCE_TEXELS` texels in
/// `fetch_instance`, `instances.glsl`). A ray enters the mesh's BVH in the
/// mesh's own space, through `to_object`; what it hits is placed in the
/// world through `to_world`. The ids of hits number every (instance,
/// triangle) pair: instance k's triangle in slot s has id `s -
/// first_triangle + id_base`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Instance {
    /// Object to world (relative to the scene's world origin): the rows of
    /// a 3x4 matrix, composed in f64.
    pub to_world_x: [f32; 4],
    pub to_world_y: [f32; 4],
    pub to_world_z: [f32; 4],
    /// World to object: the inverse, computed in f64.
    pub to_object_x: [f32; 4],
    pub to_object_y: [f32; 4],
    pub to_object_z: [f32; 4],
    /// The root node of the mesh's BVH.
    pub root: u32,
    /// The id of the instance's first triangle.
    pub id_base: u32,
    /// The slot of the mesh's first triangle.
    pub first_triangle: u32,
    /// `INSTANCE_MIRRORED` when the transform mirrors.
    pub flags: u32,
}

impl Instance {
    /// The rows of `to_world`.
    pub fn to_world(&self) -> [[f32; 4]; 3] {
        [self.to_world_x, self.to_world_y, self.to_world_z]
    }

    /// The rows of `to_object`.
    pub fn to_object(&self) -> [[f32; 4]; 3] {
        [self.to_object_x, self.to_object_y, self.to_object_z]
    }
}

/// Everything uniform across a render, 176 bytes (a uniform buffer).
/// The camera looks along `cam_forward`. A film point `sx, sy` in [-1, 1]
/// (y up) is `film = sx * tan_half_fov * aspect * right + sy * tan_half_fov * up`.
/// Perspective: the pinhole ray leaves `cam_position` along `forward + film`;
/// with a lens it leaves a point of the aperture toward where the pinhole ray
/// meets the focus plane. Orthographic: `tan_half_fov` holds the view's half
/// height in scene units (glTF `ymag`) and rays leave `cam_position + film`
/// along `forward`. See `shaders/common/camera.glsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct RenderParams {
    pub cam_position: [f32; 3],
    pub tan_half_fov: f32,
    pub cam_right: [f32; 3],
    pub aspect: f32,
    pub cam_up: [f32; 3],
    /// Instances of a two-level scene (`Instance`); 0: one level.
    pub num_instances: u32,
    pub cam_forward: [f32; 3],
    /// Texture mip-mapping (`textures.glsl`): the width of one pixel's
    /// footprint per unit distance from the camera (per unit, orthographic),
    /// `2 tan(fov / 2) / height`; 0 with `--texture-filter bilinear`.
    pub texture_spread: f32,
    /// Circumradius of the aperture in scene units (half of focal length /
    /// f-number); 0 for a pinhole.
    pub lens_radius: f32,
    /// Distance of the plane in focus along `cam_forward`, scene units.
    pub focus_distance: f32,
    /// Straight blades of a polygonal aperture; 0 for a circle.
    pub aperture_blades: u32,
    /// Angle of the first blade vertex from `cam_right` toward `cam_up`, radians.
    pub blade_rotation: f32,
    /// `PROJECTION_*`.
    pub projection: u32,
    /// `FILTER_*`, and the filter's radius in pixels.
    pub filter_kind: u32,
    pub filter_radius: f32,
    /// Motion (`FEATURE_MOTION`, `PackedMotion`): the texel of the render
    /// camera's first step in `motion_texels`, or `MOTION_CAMERA_STILL`.
    pub motion_camera_base: u32,
    /// Uniform environment radiance, and the probability that light sampling
    /// picks the environment rather than an emissive triangle.
    pub environment: [f32; 3],
    pub env_select_prob: f32,
    pub width: u32,
    pub height: u32,
    /// Number of segments a path may have (`DEPTH_UNLIMITED` for no limit).
    pub max_depth: u32,
    pub seed: u32,
    pub num_emitters: u32,
    pub num_triangles: u32,
    /// Path slots in the wavefront pool (each ray queue holds this many).
    pub pool_size: u32,
    /// How random numbers are drawn (`SAMPLER_*` in `constants.rs`).
    pub rng_sampler: u32,
    /// The rectangle rendered (`RenderSettings::region`): the film is
    /// `region_width` x `region_height` pixels, its first at image pixel
    /// (`region_x`, `region_y`). `width` and `height` stay the full image's.
    pub region_x: u32,
    pub region_y: u32,
    pub region_width: u32,
    pub region_height: u32,
    /// The first sample index rendered (`RenderSettings::first_sample`):
    /// `path_pixel_sample` (camera.glsl) adds it to a path's sample.
    pub sample_offset: u32,
    /// Nonzero: record the auxiliary outputs (`aov.glsl`, `FEATURE_AOV`).
    pub aov: u32,
    /// Motion: the time steps over the shutter (0 without motion), and the
    /// texel where the triangles' vertex positions start in `motion_texels`.
    pub motion_steps: u32,
    pub motion_vertex_base: u32,
}

impl RenderParams {
    /// Pixels of the film: the rendered region's (`film_pixel_count` in
    /// camera.glsl).
    pub fn film_pixels(&self) -> u64 {
        self.region_width as u64 * self.region_height as u64
    }
}

/// An analytic light, 80 bytes (`LIGHT_*` in `constants.rs` names the kind).
///
/// - `position`: point, spot and sphere: the centre.
/// - `direction`: spot, directional and sun: the unit direction the light
///   travels (the node's -Z).
/// - `range`: point and spot: glTF `range`, 0 for none. The window
///   max(min(1 - (d/range)^4, 1), 0) / d^2 of KHR_lights_punctual applies.
/// - `emission`: point and spot: radiant intensity (glTF intensity (cd) times
///   colour, used as W/sr); directional: irradiance on a surface facing it
///   (lux as W/m^2); sphere and sun: radiance.
/// - `radius`: sphere radius.
/// - `cos_max`, `one_minus_cos_max`: sun: the cone of its disk (half angle),
///   1 - cos computed in f64 on the host so small disks keep their size.
/// - `spot_scale`, `spot_offset`: spot: attenuation
///   clamp(cos * scale + offset, 0, 1)^2 (the extension's formula).
/// - `pmf`: probability that light sampling picks this light; `cdf`: the
///   inclusive running sum of pmfs within the analytic lights, over 1.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Light {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub range: f32,
    pub emission: [f32; 3],
    pub radius: f32,
    pub cos_max: f32,
    pub one_minus_cos_max: f32,
    pub spot_scale: f32,
    pub spot_offset: f32,
    pub pmf: f32,
    pub cdf: f32,
    pub _pad1: f32,
    pub _pad2: f32,
}

/// How light sampling is split and the environment map's shape, 48 bytes
/// (the storage buffer `light_params`).
///
/// Light sampling maps its selection number u to: the environment on
/// [0, `RenderParams::env_select_prob`), the emissive triangles on the next
/// `tri_select_prob`, the analytic lights (`lights`, by their `cdf`) on the
/// rest. With an environment map (`env_width > 0`) the environment's
/// radiance is `RenderParams::environment` (the intensity) times the map's
/// texel (nearest lookup, equirectangular, +Y up, the map's centre toward
/// -Z before the rotation `env_rot_cos`, `env_rot_sin` about +Y).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct LightParams {
    pub num_lights: u32,
    pub tri_select_prob: f32,
    pub env_width: u32,
    pub env_height: u32,
    pub env_rot_cos: f32,
    pub env_rot_sin: f32,
    /// 1: camera rays that miss see black; the environment still lights.
    pub env_hidden: u32,
    /// `ENV_SAMPLE_IMPORTANCE` or `ENV_SAMPLE_UNIFORM` (for tests).
    pub env_sampling: u32,
    /// Number of spherical lights, stored first in `lights` (ray tests loop
    /// over them).
    pub num_spheres: u32,
    /// Number of sun disks, stored right after the spheres.
    pub num_suns: u32,
    /// Nodes of the light BVH (`light_tree`), 0 where selection is by
    /// power alone. With the tree, `tri_select_prob` is the probability
    /// of the tree (emissive triangles, spheres, point and spot lights)
    /// and the `lights` cdf covers only the lights at infinity.
    pub tree_nodes: u32,
    pub _pad2: u32,
}

/// A node of the light BVH, 64 bytes (four 16-byte rows; GLSL reads it as
/// 4 texels in `fetch_light_tree_node`, `light_bvh.glsl`). It bounds the
/// lights below it (Conty Estevez and Kulla 2018): their positions (a
/// sphere: `centre`, `radius` and its square `r2`, holding their bounding
/// box), their total power (`power`, luminance, the units of
/// `packed::lights`), and the directions they emit into: every light's
/// normal lies within `theta_o` of `axis` (`cos_theta_o`, `sin_theta_o`),
/// and emits up to `theta_e` beyond its normal (`cos_theta_e`, with a
/// small margin). What the importance needs is stored, not recomputed at
/// each visit. An interior node's children are nodes `child_or_light` and
/// `child_or_light + 1`; a leaf (`LIGHT_TREE_LEAF`) names its light.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct LightTreeNode {
    pub centre: [f32; 3],
    pub power: f32,
    pub axis: [f32; 3],
    pub cos_theta_o: f32,
    pub radius: f32,
    pub r2: f32,
    pub sin_theta_o: f32,
    pub cos_theta_e: f32,
    pub child_or_light: u32,
    /// `LIGHT_TREE_LEAF`, `LIGHT_TREE_TWO_SIDED`, `LIGHT_TREE_ANALYTIC`.
    pub flags: u32,
    pub _pad1: u32,
    pub _pad2: u32,
}

/// Per-dispatch values, 16 bytes of push constants. A chunk is `count` paths;
/// path `i` renders film pixel `(pixel_start + i) % pixels` for the render's
/// sample `sample_start + (pixel_start + i) / pixels`, `pixels` the film's
/// (the region's) pixel count (`path_pixel_sample` in camera.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct PushConstants {
    pub pixel_start: u32,
    pub sample_start: u32,
    pub count: u32,
    /// Bounce round of the wavefront: picks the ray queue by parity. A path's
    /// own bounce index travels with its state (`path_radiance`'s w), since
    /// paths the per-path loop parked join the wavefront at any bounce.
    pub bounce: u32,
    /// Loop iterations one subgroup of `path_loop` may spend
    /// (`PATH_LOOP_BUDGET`; tests lower it to make paths park often).
    pub loop_budget: u32,
}

/// One pixel of the film, 32 bytes: running mean (Welford) with the sample
/// count in `mean.w`, and the sum of squared deviations in `m2.rgb`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct FilmPixel {
    pub mean: [f32; 4],
    pub m2: [f32; 4],
}

/// The auxiliary outputs of one pixel, 48 bytes: running means over its
/// samples (`aov_add_sample` in `film/mod.rs` and accumulate.comp).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct AovPixel {
    /// rgb: mean albedo; w: samples.
    pub albedo: [f32; 4],
    /// xyz: mean shading normal; w: unused.
    pub normal: [f32; 4],
    /// x: mean depth of the samples that hit a surface; y: those samples.
    pub depth: [f32; 4],
}

const _: () = {
    assert!(std::mem::size_of::<CwBvhNode>() == 80);
    assert!(std::mem::size_of::<TriangleVerts>() == 48);
    assert!(std::mem::size_of::<TriangleShading>() == 48);
    assert!(std::mem::size_of::<MaterialData>() == 16 * crate::constants::MATERIAL_TEXELS as usize);
    assert!(std::mem::size_of::<Emitter>() == 16);
    assert!(std::mem::size_of::<TextureInfo>() == 48);
    assert!(std::mem::size_of::<TriangleTexcoords>() == 96);
    assert!(std::mem::size_of::<RenderParams>() == 176);
    assert!(std::mem::size_of::<PushConstants>() == 20);
    assert!(std::mem::size_of::<Light>() == 80);
    assert!(std::mem::size_of::<LightParams>() == 48);
    assert!(std::mem::size_of::<LightTreeNode>() == 64);
    assert!(std::mem::size_of::<FilmPixel>() == 32);
    assert!(std::mem::size_of::<AovPixel>() == 48);
};
