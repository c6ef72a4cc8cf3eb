//! Twin of `shaders/common/shading_frame.glsl`: the one place where the
//! shading normal (interpolated vertex normals, later normal-mapped) is
//! reconciled with the geometric normal, the same on both back ends.
//!
//! A shading normal differs from the true surface's, so taken as is it
//! (a) can put the incoming direction or its mirror image below the actual
//! surface, which makes black rims on smooth-shaded meshes at grazing
//! angles, and (b) can send scattered rays through the surface (light
//! leaks). We (a) bend the shading normal until the mirror direction of
//! `wo` lies above the geometric surface (the approach of Keller et al.
//! 2017, "The Iray Light Transport Simulation and Rendering System", §A.3),
//! and (b) accept a scattered or light direction only where the shading and
//! geometric normals agree on which side it lies (`same_side`).

use super::anisotropy::anisotropy_active;
use super::bsdf::{ShadingFrame, frame_of_normal, reflect_about};
use super::clearcoat::clearcoat_active;
use super::sampling::build_onb;
use super::textures::perturb_normal;
use crate::constants::{NO_TEXTURE, SHADING_NORMAL_MIN_COS};
use crate::packed::PackedScene;
use crate::packed::layout::MaterialData;
use glam::{Vec2, Vec3};

/// The vertex normals interpolated at barycentrics (b1, b2), or `ng` where
/// they cancel out.
pub fn interpolate_normal(n0: Vec3, n1: Vec3, n2: Vec3, b12: Vec2, ng: Vec3) -> Vec3 {
    let n = (1.0 - b12.x - b12.y) * n0 + b12.x * n1 + b12.y * n2;
    let len = n.length();
    if len > 1e-12 { n / len } else { ng }
}

/// A shading normal usable for scattering `wo`: `ng` is the unit geometric
/// normal on wo's side (dot(wo, ng) >= 0), `ns` the shading normal turned to
/// the same side. Returns `ng` if `ns` points into the surface; otherwise
/// `ns`, bent toward `ng` where the mirror direction of `wo` would lie less
/// than SHADING_NORMAL_MIN_COS above the geometric surface (the result then
/// is the half vector of `wo` and that direction lifted to the bound).
pub fn reconcile_shading_normal(ng: Vec3, ns: Vec3, wo: Vec3) -> Vec3 {
    if ns.dot(ng) <= 0.0 {
        return ng;
    }
    let r = reflect_about(wo, ns);
    let height = r.dot(ng);
    if height >= SHADING_NORMAL_MIN_COS {
        return ns;
    }
    let tangent = r - height * ng;
    let len = tangent.length();
    if len <= 1e-12 {
        return ng;
    }
    let c = SHADING_NORMAL_MIN_COS;
    let lifted = tangent * ((1.0 - c * c).sqrt() / len) + c * ng;
    let h = wo + lifted;
    let hl = h.length();
    if hl <= 1e-12 { ng } else { h / hl }
}

/// Whether the geometric normal `ng` and the shading normal `ns` put `w` on
/// the same side of the surface (strictly off both planes).
pub fn same_side(ng: Vec3, ns: Vec3, w: Vec3) -> bool {
    w.dot(ng) * w.dot(ns) > 0.0
}

/// `KHR_materials_anisotropy`'s direction at `b12` of `tri`: the
/// interpolated vertex tangent made orthogonal to `ns`, turned by
/// `anisotropy_rotation` toward glTF's bitangent w · cross(front normal, t).
/// Where there is no usable tangent (a primitive without TANGENT whose UVs
/// are missing or degenerate, or a scene without texture coordinates):
/// `build_onb(ns)`'s t and b, a fixed but arbitrary direction.
#[allow(clippy::too_many_arguments)]
pub fn anisotropy_direction(
    scene: &PackedScene,
    m: &MaterialData,
    tri: u32,
    inst: u32,
    b12: Vec2,
    time: f32,
    ns: Vec3,
    front: bool,
) -> Vec3 {
    let (mut t, mut b) = build_onb(ns);
    if (tri as usize) < scene.textures.tri_texcoords.len() {
        let t4 = super::textures::interpolated_tangent(scene, tri, inst, b12, time);
        let tt = t4.truncate() - ns * ns.dot(t4.truncate());
        let len = tt.length();
        if len > 1e-6 {
            t = tt / len;
            let sign = if t4.w < 0.0 { -1.0 } else { 1.0 };
            b = sign * (if front { ns } else { -ns }).cross(t);
        }
    }
    m.anisotropy_rotation.cos() * t + m.anisotropy_rotation.sin() * b
}

/// The BSDF's frame (`bsdf::ShadingFrame`) at `b12` of `tri`: `ns` the
/// reconciled shading normal on wo's side, `n` the geometric normal on that
/// side, `n_vertex` the interpolated vertex normal (front side, before
/// normal mapping). An anisotropic material's t is its anisotropy
/// direction; a coated one's coat normal is `n_vertex` (the extension's:
/// the base normal map does not bend the coat) or its
/// clearcoatNormalTexture, reconciled like `ns`. Other materials get
/// `frame_of_normal(ns)`, the frame every material had before.
#[allow(clippy::too_many_arguments)]
pub fn shading_frame(
    scene: &PackedScene,
    m: &MaterialData,
    tri: u32,
    inst: u32,
    b12: Vec2,
    time: f32,
    n: Vec3,
    n_vertex: Vec3,
    ns: Vec3,
    front: bool,
    wo: Vec3,
) -> ShadingFrame {
    let mut f = frame_of_normal(ns);
    if anisotropy_active(m) {
        f.t = anisotropy_direction(scene, m, tri, inst, b12, time, ns, front);
        f.b = ns.cross(f.t);
    }
    if clearcoat_active(m) {
        let mut nc = n_vertex;
        if m.clearcoat_normal_texture != NO_TEXTURE && !scene.textures.textures.is_empty() {
            nc = perturb_normal(
                scene,
                m.clearcoat_normal_texture,
                m.clearcoat_normal_scale,
                tri,
                inst,
                b12,
                time,
                nc,
            );
        }
        f.coat_n = reconcile_shading_normal(n, if front { nc } else { -nc }, wo);
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bent_normal_keeps_the_mirror_direction_above_the_surface() {
        let ng = Vec3::Z;
        // Shading normal tilted 20° away from a grazing wo (5° above).
        let ns = Vec3::new(-(20f32.to_radians().sin()), 0.0, 20f32.to_radians().cos());
        let wo = Vec3::new(5f32.to_radians().cos(), 0.0, 5f32.to_radians().sin());
        assert!(
            reflect_about(wo, ns).dot(ng) < 0.0,
            "the raw normal reflects into the surface"
        );
        let n = reconcile_shading_normal(ng, ns, wo);
        assert!((n.length() - 1.0).abs() < 1e-5);
        let r = reflect_about(wo, n);
        assert!(
            (r.dot(ng) - SHADING_NORMAL_MIN_COS).abs() < 1e-4,
            "{}",
            r.dot(ng)
        );
        assert!(wo.dot(n) > 0.0);
        // A normal that already works is kept.
        let ok = Vec3::new(0.1, 0.0, 0.995).normalize();
        assert_eq!(
            reconcile_shading_normal(ng, ok, Vec3::new(0.0, 0.6, 0.8)),
            ok
        );
        // A shading normal below the surface gives way to the geometric one.
        assert_eq!(reconcile_shading_normal(ng, -ok, Vec3::Z), ng);
    }
}
