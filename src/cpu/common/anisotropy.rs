//! Twin of `shaders/common/anisotropy.glsl`: `KHR_materials_anisotropy`'s
//! anisotropic GGX in a local frame whose +x is the anisotropy direction
//! (`ShadingFrame::t`) and +z the shading normal; alpha = (αt, αb).
//!
//! D(h) = 1 / (π αt αb (hx²/αt² + hy²/αb² + hz²)²), Smith
//! Λ(w) = (-1 + sqrt(1 + (αt² wx² + αb² wy²) / wz²)) / 2 with the
//! height-correlated G2 = 1 / (1 + Λ(wo) + Λ(wi)), and visible-normal
//! sampling by stretching with (αt, αb) (Heitz 2014, "Understanding the
//! Masking-Shadowing Function", §5.3 and §6; Heitz 2018, "Sampling the GGX
//! Distribution of Visible Normals", which is written for αx ≠ αy).
//! The `mf_*` functions are what the glTF lobes call: an isotropic alpha
//! (x == y) goes to `microfacet.rs` unchanged, so isotropic materials keep
//! their exact values.

use super::microfacet::{ggx_d, ggx_g2, ggx_vndf_pdf, sample_ggx_vndf_aniso};
use super::sampling::INV_PI;
use crate::constants::{GGX_SMOOTH_ALPHA, LOBE_ANISOTROPY};
use crate::packed::layout::MaterialData;
use glam::{Vec2, Vec3};

pub fn anisotropy_active(m: &MaterialData) -> bool {
    m.lobes & LOBE_ANISOTROPY != 0
}

/// (αt, αb) from α = roughness²: αt = mix(α, 1, strength²), αb = α (the
/// extension's), αb kept at least `GGX_SMOOTH_ALPHA` where αt makes the
/// lobe rough (the limit αb → 0 is a line, which GGX cannot hold).
pub fn anisotropy_alpha(m: &MaterialData, alpha: f32) -> Vec2 {
    if !anisotropy_active(m) {
        return Vec2::splat(alpha);
    }
    let s = m.anisotropy_strength.clamp(0.0, 1.0);
    let at = alpha + (1.0 - alpha) * (s * s);
    if !(s > 0.0) || at < GGX_SMOOTH_ALPHA {
        return Vec2::splat(alpha);
    }
    Vec2::new(at, alpha.max(GGX_SMOOTH_ALPHA))
}

pub fn ggx_d_aniso(h: Vec3, a: Vec2) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let x = h.x / a.x;
    let y = h.y / a.y;
    let d = x * x + y * y + h.z * h.z;
    INV_PI / (a.x * a.y * d * d)
}

pub fn ggx_lambda_aniso(w: Vec3, a: Vec2) -> f32 {
    let z2 = (w.z * w.z).max(1e-20);
    let t2 = (a.x * a.x * w.x * w.x + a.y * a.y * w.y * w.y) / z2;
    0.5 * ((1.0 + t2).sqrt() - 1.0)
}

pub fn ggx_g1_aniso(w: Vec3, a: Vec2) -> f32 {
    1.0 / (1.0 + ggx_lambda_aniso(w, a))
}

pub fn mf_d(h: Vec3, a: Vec2) -> f32 {
    if a.x != a.y {
        return ggx_d_aniso(h, a);
    }
    ggx_d(h, a.x)
}

pub fn mf_g2(wo: Vec3, wi: Vec3, a: Vec2) -> f32 {
    if a.x != a.y {
        return 1.0 / (1.0 + ggx_lambda_aniso(wo, a) + ggx_lambda_aniso(wi, a));
    }
    ggx_g2(wo, wi, a.x)
}

pub fn mf_vndf_pdf(wo: Vec3, h: Vec3, a: Vec2) -> f32 {
    if a.x != a.y {
        let woh = wo.dot(h);
        if wo.z <= 0.0 || woh <= 0.0 {
            return 0.0;
        }
        return ggx_g1_aniso(wo, a) * woh * ggx_d_aniso(h, a) / wo.z;
    }
    ggx_vndf_pdf(wo, h, a.x)
}

/// One sampler for both: the isotropic one is a.x == a.y.
pub fn mf_sample_vndf(wo: Vec3, a: Vec2, u: Vec2) -> Vec3 {
    sample_ggx_vndf_aniso(wo, a, u)
}
