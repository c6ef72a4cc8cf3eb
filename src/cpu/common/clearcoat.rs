//! Twin of `shaders/common/clearcoat.glsl`: `KHR_materials_clearcoat`, a
//! clear dielectric coat (IOR 1.5, so F0 = `CLEARCOAT_F0`) with its own GGX
//! roughness and normal over the glTF material.
//!
//! The model is the extension's: with blend = clearcoat · F(cos(wo, nc)),
//! F Schlick's with F0 = 0.04 at the coat normal nc,
//!
//!   f = f_base · (1 - blend) + blend · D G2 / (4 |wo·nc| |wi·nc|),
//!
//! the coat lobe a GGX reflection whose Fresnel is the blend (so it is
//! taken at wo, not per microfacet). The coated albedo is then
//! (1 - blend) E_base + blend E_ggx, never above 1 when E_base is not.
//! A smooth coat (alpha below `GGX_SMOOTH_ALPHA`) is a delta lobe.
//! Sampling picks the coat with probability blend, so a smooth coat's
//! delta weight is 1 and the base's delta weights keep their value; the
//! pdf is the mixture (1 - blend) pdf_base + blend pdf_coat.

use super::microfacet::{ggx_d, ggx_g2, ggx_vndf_pdf, sample_ggx_vndf};
use super::sampling::build_onb;
use crate::constants::{CLEARCOAT_F0, GGX_SMOOTH_ALPHA, LOBE_CLEARCOAT};
use crate::packed::layout::MaterialData;
use glam::{Vec2, Vec3};

pub fn clearcoat_active(m: &MaterialData) -> bool {
    m.lobes & LOBE_CLEARCOAT != 0 && m.clearcoat > 0.0
}

pub fn clearcoat_alpha(m: &MaterialData) -> f32 {
    m.clearcoat_roughness * m.clearcoat_roughness
}

/// A coat whose lobe has a density (not a delta).
pub fn clearcoat_rough(m: &MaterialData) -> bool {
    clearcoat_active(m) && clearcoat_alpha(m) >= GGX_SMOOTH_ALPHA
}

/// The spec's blend factor clearcoat · Schlick(F0, `co` = cos(wo, nc));
/// also the probability of sampling the coat.
pub fn clearcoat_blend(m: &MaterialData, co: f32) -> f32 {
    let x = (1.0 - co).clamp(0.0, 1.0);
    let x2 = x * x;
    m.clearcoat.clamp(0.0, 1.0) * (CLEARCOAT_F0 + (1.0 - CLEARCOAT_F0) * (x2 * x2 * x))
}

fn clearcoat_local(w: Vec3, nc: Vec3) -> Vec3 {
    let (t, b) = build_onb(nc);
    Vec3::new(w.dot(t), w.dot(b), w.dot(nc))
}

/// The coat lobe's f · cos, Fresnel left to the blend (local to nc).
pub fn clearcoat_spec_local(alpha: f32, wo: Vec3, wi: Vec3) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 || alpha < GGX_SMOOTH_ALPHA {
        return 0.0;
    }
    let h = (wo + wi).normalize();
    ggx_d(h, alpha) * ggx_g2(wo, wi, alpha) / (4.0 * wo.z)
}

pub fn clearcoat_pdf_local(alpha: f32, wo: Vec3, wi: Vec3) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 || alpha < GGX_SMOOTH_ALPHA {
        return 0.0;
    }
    let h = (wo + wi).normalize();
    ggx_vndf_pdf(wo, h, alpha) / (4.0 * wo.dot(h))
}

/// The coated material's f · cos from the base's (world directions).
pub fn clearcoat_layer_eval(m: &MaterialData, nc: Vec3, wo: Vec3, wi: Vec3, base: Vec3) -> Vec3 {
    let blend = clearcoat_blend(m, wo.dot(nc));
    let spec = clearcoat_spec_local(
        clearcoat_alpha(m),
        clearcoat_local(wo, nc),
        clearcoat_local(wi, nc),
    );
    base * (1.0 - blend) + Vec3::splat(blend * spec)
}

/// The coated material's pdf from the base's.
pub fn clearcoat_layer_pdf(m: &MaterialData, nc: Vec3, wo: Vec3, wi: Vec3, base_pdf: f32) -> f32 {
    let blend = clearcoat_blend(m, wo.dot(nc));
    let coat = clearcoat_pdf_local(
        clearcoat_alpha(m),
        clearcoat_local(wo, nc),
        clearcoat_local(wi, nc),
    );
    base_pdf * (1.0 - blend) + blend * coat
}

/// A direction from the coat lobe (world): wo mirrored about nc for a
/// smooth coat (a delta), else about a visible GGX normal.
pub fn clearcoat_sample_wi(m: &MaterialData, nc: Vec3, wo: Vec3, u: Vec2) -> Vec3 {
    let alpha = clearcoat_alpha(m);
    if alpha < GGX_SMOOTH_ALPHA {
        return 2.0 * nc.dot(wo) * nc - wo;
    }
    let (t, b) = build_onb(nc);
    let wl = Vec3::new(wo.dot(t), wo.dot(b), wo.dot(nc));
    let h = sample_ggx_vndf(wl, alpha, u);
    let r = 2.0 * h.dot(wl) * h - wl;
    (r.x * t + r.y * b + r.z * nc).normalize()
}
