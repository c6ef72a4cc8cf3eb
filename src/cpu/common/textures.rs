//! Twin of `shaders/common/textures.glsl`: texture application, alpha mask
//! test and normal mapping over the same arrays. Its first half, reading
//! the packed texel format (decoding, wrap modes, bilinear / nearest
//! filtering), lives with that format in `packed/textures.rs`, because
//! packing evaluates emissive textures with it; it is re-exported here
//! under the GLSL names.

use super::instances::world_tangent;
use super::rng::rng_coverage;
use crate::constants::*;
use crate::packed::PackedScene;
use crate::packed::layout::{MaterialData, RenderParams};
pub use crate::packed::textures::{
    NO_FOOTPRINT_VEC, decode_texel, fetch_triangle_uvs, floor_mod, texel_rgba8,
    texel_storage_words, texture_level, texture_lod, texture_sample, texture_sample_image,
    texture_st, wrap_texel,
};
use glam::{Vec2, Vec3, Vec4};

pub fn material_has_textures(m: &MaterialData) -> bool {
    [
        m.base_color_texture,
        m.metallic_roughness_texture,
        m.normal_texture,
        m.emissive_texture,
        m.specular_texture,
        m.specular_color_texture,
        m.transmission_texture,
        m.clearcoat_texture,
        m.clearcoat_roughness_texture,
        m.anisotropy_texture,
        m.sheen_color_texture,
        m.sheen_roughness_texture,
        m.iridescence_texture,
        m.iridescence_thickness_texture,
        m.diffuse_transmission_texture,
        m.diffuse_transmission_color_texture,
        m.thickness_texture,
    ]
    .iter()
    .any(|&t| t != NO_TEXTURE)
}

/// Twice the areas of triangle `tri`'s texture-coordinate triangles, sets 0
/// and 1.
pub fn triangle_uv_areas(scene: &PackedScene, tri: u32) -> Vec2 {
    let tc = &scene.textures.tri_texcoords[tri as usize];
    let cross = |a: Vec2, b: Vec2, c: Vec2| ((b - a).perp_dot(c - a)).abs();
    let (a, b) = (tc.uv0_01, tc.uv0_2_uv1_0);
    let c = tc.uv1_12;
    Vec2::new(
        cross(
            Vec2::new(a[0], a[1]),
            Vec2::new(a[2], a[3]),
            Vec2::new(b[0], b[1]),
        ),
        cross(
            Vec2::new(b[2], b[3]),
            Vec2::new(c[0], c[1]),
            Vec2::new(c[2], c[3]),
        ),
    )
}

/// The texture footprint of a hit at `p` on world triangle `v0 v1 v2`
/// (slot `tri`), for `texture_lod`: a cone from the camera one pixel wide
/// (`RenderParams::texture_spread`), its width at `p` over |cos| of the
/// view direction and the surface, as a log2 less half the log2 of the
/// triangle's world area (x), and half the log2 of its texture-coordinate
/// areas (y, z). The same cone serves every bounce: its width at p is
/// measured from the camera, as pbrt-v4's `Approximate_dp_dxy` does after
/// the first hit (see the GLSL twin). `NO_FOOTPRINT_VEC` when mip-mapping
/// is off.
pub fn texture_footprint(
    scene: &PackedScene,
    params: &RenderParams,
    tri: u32,
    [v0, v1, v2]: [Vec3; 3],
    p: Vec3,
) -> Vec3 {
    let ng_raw = (v1 - v0).cross(v2 - v0);
    let world = ng_raw.length();
    if !(params.texture_spread > 0.0) || !(world > 0.0) {
        return NO_FOOTPRINT_VEC;
    }
    let ortho = params.projection == PROJECTION_ORTHOGRAPHIC;
    let to_p = p - Vec3::from(params.cam_position);
    let dist = to_p.length();
    let view = if ortho {
        Vec3::from(params.cam_forward)
    } else {
        to_p / dist
    };
    let cos = (view.dot(ng_raw) / world).abs().max(FOOTPRINT_MIN_COS);
    let width = params.texture_spread * if ortho { 1.0 } else { dist };
    let uv = triangle_uv_areas(scene, tri);
    Vec3::new(
        (width / cos).log2() - 0.5 * world.log2(),
        0.5 * uv.x.log2(),
        0.5 * uv.y.log2(),
    )
}

/// The material at barycentrics `b12` of `tri`, every textured factor
/// multiplied by its texture (see the GLSL twin). The kernels compile in
/// only the slots some material fills (`TEXTURE_SLOT_MASK`), which changes
/// nothing a slot without a texture would do, so this twin tests them all.
/// `footprint` (`texture_footprint`) picks the mip levels of every slot
/// but the emission, which is read at full resolution: a light sample reads
/// it there too, and MIS weighs the two as estimates of one integrand.
pub fn apply_textures(
    scene: &PackedScene,
    m: &MaterialData,
    tri: u32,
    b12: Vec2,
    footprint: Vec3,
) -> MaterialData {
    let mut m = *m;
    if !material_has_textures(&m) {
        return m;
    }
    let (uv0, uv1) = fetch_triangle_uvs(&scene.textures, tri, b12);
    let sample = |t: u32, srgb: bool| texture_sample(&scene.textures, t, uv0, uv1, srgb, footprint);
    if m.base_color_texture != NO_TEXTURE {
        let c = sample(m.base_color_texture, true);
        m.base_color = (Vec3::from(m.base_color) * c.truncate()).into();
        m.alpha *= c.w;
    }
    if m.metallic_roughness_texture != NO_TEXTURE {
        let c = sample(m.metallic_roughness_texture, false);
        m.roughness *= c.y;
        m.metallic *= c.z;
    }
    if m.emissive_texture != NO_TEXTURE {
        let c = texture_sample_image(&scene.textures, m.emissive_texture, uv0, uv1, true);
        m.emission = (Vec3::from(m.emission) * c.truncate()).into();
    }
    if m.specular_texture != NO_TEXTURE {
        m.specular_factor *= sample(m.specular_texture, false).w;
    }
    if m.specular_color_texture != NO_TEXTURE {
        m.specular_color = (Vec3::from(m.specular_color)
            * sample(m.specular_color_texture, true).truncate())
        .into();
    }
    if m.transmission_texture != NO_TEXTURE {
        m.transmission *= sample(m.transmission_texture, false).x;
    }
    // KHR_materials_clearcoat: factor by R, roughness by G.
    if m.clearcoat_texture != NO_TEXTURE {
        m.clearcoat *= sample(m.clearcoat_texture, false).x;
    }
    if m.clearcoat_roughness_texture != NO_TEXTURE {
        m.clearcoat_roughness *= sample(m.clearcoat_roughness_texture, false).y;
    }
    // KHR_materials_anisotropy: strength by B; RG a direction in [-1, 1]²
    // in tangent space, which turns the rotation by its angle.
    if m.anisotropy_texture != NO_TEXTURE {
        let c = sample(m.anisotropy_texture, false);
        m.anisotropy_strength *= c.z;
        let d = Vec2::new(c.x, c.y) * 2.0 - Vec2::ONE;
        if d.dot(d) > 0.0 {
            m.anisotropy_rotation += d.y.atan2(d.x);
        }
    }
    // KHR_materials_sheen: colour × RGB (sRGB), roughness × A.
    if m.sheen_color_texture != NO_TEXTURE {
        let c = sample(m.sheen_color_texture, true).truncate();
        m.sheen_color = (Vec3::from(m.sheen_color) * c).into();
    }
    if m.sheen_roughness_texture != NO_TEXTURE {
        m.sheen_roughness *= sample(m.sheen_roughness_texture, false).w;
    }
    // KHR_materials_iridescence: factor × R; the film thickness is
    // mix(min, max, G), kept in `iridescence_thickness_max` (thin_film.rs).
    if m.iridescence_texture != NO_TEXTURE {
        m.iridescence *= sample(m.iridescence_texture, false).x;
    }
    if m.iridescence_thickness_texture != NO_TEXTURE {
        let g = sample(m.iridescence_thickness_texture, false).y;
        m.iridescence_thickness_max = m.iridescence_thickness_min
            + (m.iridescence_thickness_max - m.iridescence_thickness_min) * g;
    }
    // KHR_materials_diffuse_transmission: factor × A, colour × RGB (sRGB).
    if m.diffuse_transmission_texture != NO_TEXTURE {
        m.diffuse_transmission *= sample(m.diffuse_transmission_texture, false).w;
    }
    if m.diffuse_transmission_color_texture != NO_TEXTURE {
        let c = sample(m.diffuse_transmission_color_texture, true).truncate();
        m.diffuse_transmission_color = (Vec3::from(m.diffuse_transmission_color) * c).into();
    }
    // KHR_materials_volume: thickness × G; 0 makes the point thin-walled.
    if m.thickness_texture != NO_TEXTURE {
        m.thickness *= sample(m.thickness_texture, false).y;
    }
    m
}

/// Radiance a light sample at `b12` of emissive `tri` receives from `m`
/// (see the GLSL twin, which applies only the base colour and emissive
/// slots: the others do not touch the emission or the alpha).
pub fn textured_emission(scene: &PackedScene, m: &MaterialData, tri: u32, b12: Vec2) -> Vec3 {
    let mut emission = Vec3::from(m.emission);
    let mut alpha = m.alpha;
    // Only the emission and the alpha matter here, both read at full
    // resolution (`apply_texture_slots` says why for the emission).
    if material_has_textures(m) {
        let (uv0, uv1) = fetch_triangle_uvs(&scene.textures, tri, b12);
        if m.base_color_texture != NO_TEXTURE {
            alpha *= texture_sample_image(&scene.textures, m.base_color_texture, uv0, uv1, true).w;
        }
        if m.emissive_texture != NO_TEXTURE {
            emission *= texture_sample_image(&scene.textures, m.emissive_texture, uv0, uv1, true)
                .truncate();
        }
    }
    emission * alpha_coverage(alpha, m.alpha_cutoff)
}

/// The fraction of rays that meet a surface of this `alpha` and
/// `alpha_cutoff` (`MaterialData`): MASK 0 or 1 by the cutoff, BLEND
/// alpha, opaque 1.
pub fn alpha_coverage(alpha: f32, cutoff: f32) -> f32 {
    if cutoff == ALPHA_BLEND {
        return alpha.clamp(0.0, 1.0);
    }
    if alpha >= cutoff { 1.0 } else { 0.0 }
}

/// Alpha MASK and BLEND: whether a hit at `b12` on `tri` (material `mi`,
/// not opaque) is kept (see the GLSL twin).
pub fn alpha_test_passes(
    scene: &PackedScene,
    mi: u32,
    tri: u32,
    b12: Vec2,
    coverage_seed: u32,
) -> bool {
    let m = &scene.materials[mi as usize];
    let mut alpha = m.alpha;
    if m.base_color_texture != NO_TEXTURE {
        let (uv0, uv1) = fetch_triangle_uvs(&scene.textures, tri, b12);
        alpha *= texture_sample_image(&scene.textures, m.base_color_texture, uv0, uv1, false).w;
    }
    if m.alpha_cutoff == ALPHA_BLEND {
        alpha > rng_coverage(coverage_seed, tri)
    } else {
        alpha >= m.alpha_cutoff
    }
}

/// The vertex tangents (xyz, bitangent sign w) blended at `b12`, with the
/// triangle where it is at `time` (`motion`), placed by instance `inst`.
pub fn interpolated_tangent(
    scene: &PackedScene,
    tri: u32,
    inst: u32,
    b12: Vec2,
    time: f32,
) -> Vec4 {
    let tc = &scene.textures.tri_texcoords[tri as usize];
    let [t0, t1, t2] = match &scene.motion {
        Some(m) => super::motion::moving_triangle_tangents(scene, m, tri, time),
        None => [tc.tangent0.into(), tc.tangent1.into(), tc.tangent2.into()],
    };
    let [t0, t1, t2] = [t0, t1, t2].map(|t| world_tangent(scene, inst, t));
    let b0 = 1.0 - b12.x - b12.y;
    b0 * t0 + b12.x * t1 + b12.y * t2
}

/// The base normal map's perturbation of the unit shading normal `ns`.
pub fn apply_normal_map(
    scene: &PackedScene,
    m: &MaterialData,
    tri: u32,
    inst: u32,
    b12: Vec2,
    time: f32,
    ns: Vec3,
) -> Vec3 {
    perturb_normal(
        scene,
        m.normal_texture,
        m.normal_scale,
        tri,
        inst,
        b12,
        time,
        ns,
    )
}

/// A normal map's (texture `tex`, XY scaled by `normal_scale`)
/// perturbation of the unit shading normal `ns` (see the GLSL twin); also
/// `KHR_materials_clearcoat`'s clearcoatNormalTexture.
#[allow(clippy::too_many_arguments)]
pub fn perturb_normal(
    scene: &PackedScene,
    tex: u32,
    normal_scale: f32,
    tri: u32,
    inst: u32,
    b12: Vec2,
    time: f32,
    ns: Vec3,
) -> Vec3 {
    let t4 = interpolated_tangent(scene, tri, inst, b12, time);
    let t = t4.truncate() - ns * ns.dot(t4.truncate());
    let len = t.length();
    if !(len > 1e-6) {
        return ns;
    }
    let t = t / len;
    let b = if t4.w < 0.0 { -1.0 } else { 1.0 } * ns.cross(t);
    let (uv0, uv1) = fetch_triangle_uvs(&scene.textures, tri, b12);
    let c = texture_sample_image(&scene.textures, tex, uv0, uv1, false).truncate() * 2.0 - 1.0;
    let (cx, cy) = (c.x * normal_scale, c.y * normal_scale);
    let n = cx * t + cy * b + c.z * ns;
    let n_len = n.length();
    if n_len > 0.0 { n / n_len } else { ns }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes_match_gltf_at_and_beyond_the_edges() {
        // n = 4: texels 0..3.
        let r: Vec<i32> = (-5..9).map(|i| wrap_texel(i, 4, WRAP_REPEAT)).collect();
        assert_eq!(r, [3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0]);
        let c: Vec<i32> = (-2..6)
            .map(|i| wrap_texel(i, 4, WRAP_CLAMP_TO_EDGE))
            .collect();
        assert_eq!(c, [0, 0, 0, 1, 2, 3, 3, 3]);
        let m: Vec<i32> = (-5..13)
            .map(|i| wrap_texel(i, 4, WRAP_MIRRORED_REPEAT))
            .collect();
        assert_eq!(m, [3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1, 2, 3, 3]);
    }

    #[test]
    fn glsl_floor_mod_formula_equals_rem_euclid() {
        // The GLSL twin computes floor_mod with integer division only.
        let glsl = |i: i32, n: i32| {
            let q = if i >= 0 { i / n } else { -((-i - 1) / n) - 1 };
            i - q * n
        };
        for n in 1..7 {
            for i in -50..50 {
                assert_eq!(glsl(i, n), floor_mod(i, n), "{i} mod {n}");
            }
        }
    }
}
