//! Twin of `shaders/common/gltf_layers.glsl`: the lobes that
//! `KHR_materials_sheen` and `KHR_materials_diffuse_transmission` add to the
//! glTF model of `bsdf.rs`, composed around its lobes (`gltf_base_*`), in
//! the local frame (+z = the shading normal on wo's side).
//!
//! - Diffuse transmission: the diffuse base (weight (1 - metallic)(1 -
//!   transmission) times the specular layer's Fresnel-mix weight) reflects
//!   the fraction 1 - diffuseTransmission (`gltf_diffuse_reflected`) and
//!   transmits the rest as a Lambertian lobe on the other side, tinted by
//!   diffuseTransmissionColor. Thin: no refraction, straight through.
//! - Sheen (Khronos' layering): f = f_sheen + f_base · S, with the albedo
//!   scaling S = min(1 - max(sheenColor) E(cos θo), 1 - max(sheenColor)
//!   E(|cos θi|)) (`sheen.rs`): reciprocal, and at most 1 - max·E(cos θo),
//!   so the layer never adds energy. E is the lobe's directional albedo
//!   clamped to 1 (`sheen_energy`); where the fitted lobe reflects more
//!   than 1 (grazing, smooth sheen) it is divided by E(cos θo).
//!
//! Sampling stays one-sample MIS: a layer lobe is chosen first (sheen by
//! its albedo, diffuse transmission by its weight, the base by an upper
//! bound of its albedo), both layer lobes are cosine-weighted hemispheres
//! (broad lobes), and `gltf_pdf_local` is the mixture pdf. A material
//! without these lobes takes exactly the base's code path.

use super::bsdf::{
    gltf_base_eval_local, gltf_base_pdf_local, gltf_base_weight, gltf_reflection_color,
};
use super::sampling::{INV_PI, cosine_hemisphere_pdf, sample_cosine_hemisphere};
use super::sheen::{sheen_albedo, sheen_energy, sheen_eval_white};
use crate::constants::{LOBE_DIFFUSE_TRANSMISSION, LOBE_SHEEN};
use crate::packed::layout::MaterialData;
use glam::{Vec2, Vec3};

pub fn gltf_has_sheen(m: &MaterialData) -> bool {
    m.lobes & LOBE_SHEEN != 0
}

pub fn gltf_has_diffuse_transmission(m: &MaterialData) -> bool {
    m.lobes & LOBE_DIFFUSE_TRANSMISSION != 0
}

fn gltf_has_layers(m: &MaterialData) -> bool {
    gltf_has_sheen(m) || gltf_has_diffuse_transmission(m)
}

/// The fraction of the diffuse base that reflects (1 without diffuse
/// transmission).
pub fn gltf_diffuse_reflected(m: &MaterialData) -> f32 {
    if gltf_has_diffuse_transmission(m) {
        1.0 - m.diffuse_transmission
    } else {
        1.0
    }
}

fn mean(c: Vec3) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

fn mirror_z(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

/// The sheen's albedo scaling of the base for cos θo = `co`, |cos θi| = `ci`.
fn sheen_scaling(m: &MaterialData, co: f32, ci: f32) -> f32 {
    if !gltf_has_sheen(m) {
        return 1.0;
    }
    let s = Vec3::from(m.sheen_color).max_element();
    let r = m.sheen_roughness;
    (1.0 - s * sheen_energy(co, r)).min(1.0 - s * sheen_energy(ci, r))
}

/// Weight of the diffuse base (before the colour) at cos(wo, h) = `c`.
fn diffuse_weight(m: &MaterialData, c: f32, eta: f32) -> f32 {
    (1.0 - m.metallic) * (1.0 - m.transmission) * gltf_base_weight(m, c, eta)
}

/// Probabilities of the sheen and diffuse transmission lobes; the base's
/// lobes (`gltf_lobe_probs`) share the rest.
pub fn gltf_layer_probs(m: &MaterialData, co: f32, eta: f32) -> (f32, f32) {
    let sheen = if gltf_has_sheen(m) {
        mean(Vec3::from(m.sheen_color)) * sheen_energy(co, m.sheen_roughness)
    } else {
        0.0
    };
    let s = sheen_scaling(m, co, co);
    let dt = if gltf_has_diffuse_transmission(m) {
        s * diffuse_weight(m, co, eta)
            * m.diffuse_transmission
            * mean(Vec3::from(m.diffuse_transmission_color))
    } else {
        0.0
    };
    // The base's lobe weights as gltf_lobe_probs estimates them.
    let under = (1.0 - m.metallic) * gltf_base_weight(m, co, eta) * mean(Vec3::from(m.base_color));
    let base = s
        * (under * ((1.0 - m.transmission) * gltf_diffuse_reflected(m) + m.transmission)
            + mean(gltf_reflection_color(m, co, eta)));
    let sum = sheen + dt + base;
    if sum > 0.0 {
        (sheen / sum, dt / sum)
    } else {
        (0.0, 0.0)
    }
}

/// f · |cos θi| of the whole material (see the file header).
pub fn gltf_eval_local(m: &MaterialData, eta: f32, wo: Vec3, wi: Vec3) -> Vec3 {
    let f = gltf_base_eval_local(m, eta, wo, wi);
    if !gltf_has_layers(m) || wo.z <= 0.0 {
        return f;
    }
    let mut f = f;
    if gltf_has_diffuse_transmission(m) && wi.z < 0.0 {
        let h = (wo + mirror_z(wi)).normalize();
        let w = diffuse_weight(m, wo.dot(h), eta) * m.diffuse_transmission * INV_PI * -wi.z;
        f += Vec3::from(m.diffuse_transmission_color) * w;
    }
    if gltf_has_sheen(m) {
        f *= sheen_scaling(m, wo.z, wi.z.abs());
        if wi.z > 0.0 {
            let r = m.sheen_roughness;
            let norm = sheen_albedo(wo.z, r).max(1.0);
            f += Vec3::from(m.sheen_color) * (sheen_eval_white(r, wo, wi) / norm);
        }
    }
    f
}

/// Solid-angle density of `gltf_sample` choosing wi (non-delta lobes).
pub fn gltf_pdf_local(m: &MaterialData, eta: f32, wo: Vec3, wi: Vec3) -> f32 {
    let pdf = gltf_base_pdf_local(m, eta, wo, wi);
    if !gltf_has_layers(m) || wo.z <= 0.0 {
        return pdf;
    }
    let (ps, pt) = gltf_layer_probs(m, wo.z, eta);
    let mut pdf = (1.0 - ps - pt) * pdf;
    if wi.z > 0.0 {
        pdf += ps * cosine_hemisphere_pdf(wi.z);
    } else if wi.z < 0.0 {
        pdf += pt * cosine_hemisphere_pdf(-wi.z);
    }
    pdf
}

/// The layer lobes' share of `gltf_sample`: a direction when `u_lobe`
/// picks the sheen or the diffuse transmission, otherwise `None` and
/// `u_lobe` rescaled to [0, 1) for the base's own choice.
pub fn gltf_layer_sample(
    m: &MaterialData,
    co: f32,
    eta: f32,
    u_lobe: f32,
    u: Vec2,
) -> (Option<Vec3>, f32) {
    if !gltf_has_layers(m) {
        return (None, u_lobe);
    }
    let (ps, pt) = gltf_layer_probs(m, co, eta);
    if u_lobe < ps {
        return (Some(sample_cosine_hemisphere(u)), u_lobe);
    }
    if u_lobe < ps + pt {
        return (Some(mirror_z(sample_cosine_hemisphere(u))), u_lobe);
    }
    let rest = (u_lobe - ps - pt) / (1.0 - ps - pt);
    (None, rest.min(0.99999994))
}

/// With layers, a sample of the base's reflecting lobes (`upper`: diffuse
/// or reflection) must stay above the surface and one of its transmission
/// lobe below it: otherwise the layers' lobes would give it a density that
/// is not the density it was drawn with. Without layers, true (today's
/// path).
pub fn gltf_layer_side_ok(m: &MaterialData, layer: bool, upper: bool, wi_z: f32) -> bool {
    !gltf_has_layers(m) || layer || (wi_z > 0.0) == upper
}

/// What a delta sample of the base (weight / its lobe probability) is
/// multiplied by: the sheen's albedo scaling over the base's share of the
/// lobe choice (1 without layers). `ci` = cos θi of the delta direction.
pub fn gltf_layer_delta_scale(m: &MaterialData, co: f32, eta: f32, ci: f32) -> f32 {
    if !gltf_has_layers(m) {
        return 1.0;
    }
    let (ps, pt) = gltf_layer_probs(m, co, eta);
    sheen_scaling(m, co, ci.abs()) / (1.0 - ps - pt)
}
