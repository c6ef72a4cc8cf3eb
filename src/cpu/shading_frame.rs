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

use super::bsdf::reflect_about;
use crate::constants::SHADING_NORMAL_MIN_COS;
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
