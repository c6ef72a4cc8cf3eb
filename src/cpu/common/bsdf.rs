//! Twin of `shaders/common/bsdf.glsl`; see its header for the conventions
//! (directions away from the surface, the `ShadingFrame` on the side of
//! `wo`, `front` =
//! that side is the front; eval returns f·|cos θi|, sample the weight
//! f·|cos θi|/pdf; delta lobes have eval = pdf = 0 and set `delta`; we
//! transport radiance, so refraction scales the weight by 1/η² with
//! η = n(wi side) / n(wo side)).

use super::anisotropy::{anisotropy_alpha, mf_d, mf_g2, mf_sample_vndf, mf_vndf_pdf};
use super::clearcoat::{
    clearcoat_active, clearcoat_blend, clearcoat_layer_eval, clearcoat_layer_pdf, clearcoat_rough,
    clearcoat_sample_wi,
};
use super::sampling::{INV_PI, build_onb, cosine_hemisphere_pdf, sample_cosine_hemisphere};
use super::sheen::{sheen_albedo, sheen_energy, sheen_eval_white};
use super::thin_film::{iridescent_base_weight, iridescent_reflection};
use crate::constants::{
    GGX_SMOOTH_ALPHA, LOBE_DIFFUSE_TRANSMISSION, LOBE_SHEEN, MATERIAL_GLTF, MATERIAL_LAMBERT,
    MATERIAL_MIRROR, MATERIAL_PHONG,
};
use crate::packed::layout::MaterialData;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// The frame the BSDF scatters in: `n` the shading normal on wo's side,
/// (`t`, `b`, `n`) right-handed (`build_onb(n)` unless the material is
/// anisotropic: then `t` is its anisotropy direction), `coat_n` the
/// clearcoat's normal on wo's side (`shading_frame.rs` builds it).
#[derive(Clone, Copy, Debug)]
pub struct ShadingFrame {
    pub n: Vec3,
    pub t: Vec3,
    pub b: Vec3,
    pub coat_n: Vec3,
}

/// The frame of a material that is neither anisotropic nor coated.
pub fn frame_of_normal(n: Vec3) -> ShadingFrame {
    let (t, b) = build_onb(n);
    ShadingFrame { n, t, b, coat_n: n }
}

pub struct BsdfSample {
    pub wi: Vec3,
    pub weight: Vec3,
    pub pdf: f32,
    pub delta: bool,
}

pub fn lambert_eval(albedo: Vec3, n: Vec3, wi: Vec3) -> Vec3 {
    albedo * (INV_PI * n.dot(wi).max(0.0))
}

pub fn lambert_pdf(n: Vec3, wi: Vec3) -> f32 {
    cosine_hemisphere_pdf(n.dot(wi))
}

/// Cosine-weighted in frame `f` (the shading frame's t and b: for a
/// Lambertian surface `frame_of_normal`'s, so no second basis is built).
pub fn lambert_sample(albedo: Vec3, f: &ShadingFrame, u: Vec2) -> BsdfSample {
    let (t, b, n) = (f.t, f.b, f.n);
    let l = sample_cosine_hemisphere(u);
    let pdf = cosine_hemisphere_pdf(l.z);
    BsdfSample {
        wi: (l.x * t + l.y * b + l.z * n).normalize(),
        weight: if pdf > 0.0 { albedo } else { Vec3::ZERO },
        pdf,
        delta: false,
    }
}

pub fn reflect_about(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * n.dot(wo) * n - wo
}

/// Exact unpolarized Fresnel reflectance of a smooth dielectric interface
/// for light from the side of index n_o at `cos_i` > 0 into index n_t,
/// `eta` = n_t / n_o. Returns (F, cos θt); F = 1 beyond the critical angle.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32) {
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    (0.5 * (rs * rs + rp * rp), cos_t)
}

fn rgb(a: [f32; 3]) -> Vec3 {
    Vec3::from(a)
}

pub fn phong_specular_prob(m: &MaterialData) -> f32 {
    let d = m.base_color[0] + m.base_color[1] + m.base_color[2];
    let s = m.specular[0] + m.specular[1] + m.specular[2];
    if d + s > 0.0 { s / (d + s) } else { 0.0 }
}

pub fn phong_lobe_pdf(shininess: f32, cos_alpha: f32) -> f32 {
    if cos_alpha > 0.0 {
        (shininess + 1.0) * (0.5 * INV_PI) * cos_alpha.powf(shininess)
    } else {
        0.0
    }
}

pub fn sample_phong_lobe(r: Vec3, shininess: f32, u: Vec2) -> Vec3 {
    let c = u.x.powf(1.0 / (shininess + 1.0));
    let s = (1.0 - c * c).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let (t, b) = build_onb(r);
    (s * phi.cos() * t + s * phi.sin() * b + c * r).normalize()
}

pub fn phong_eval(m: &MaterialData, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    let cos_i = n.dot(wi);
    if cos_i <= 0.0 {
        return Vec3::ZERO;
    }
    let cos_alpha = reflect_about(wo, n).dot(wi);
    let lobe = if cos_alpha > 0.0 {
        (m.shininess + 2.0) * (0.5 * INV_PI) * cos_alpha.powf(m.shininess)
    } else {
        0.0
    };
    (rgb(m.base_color) * INV_PI + rgb(m.specular) * lobe) * cos_i
}

pub fn phong_pdf(m: &MaterialData, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let ps = phong_specular_prob(m);
    let cos_alpha = reflect_about(wo, n).dot(wi);
    (1.0 - ps) * cosine_hemisphere_pdf(n.dot(wi)) + ps * phong_lobe_pdf(m.shininess, cos_alpha)
}

/// Schlick's approximation, which glTF uses for metals (appendix B):
/// F0 + (1 - F0)(1 - c)^5, F0 = the base colour.
pub fn fresnel_schlick(f0: Vec3, c: f32) -> Vec3 {
    let x = (1.0 - c).clamp(0.0, 1.0);
    let x2 = x * x;
    f0 + (Vec3::ONE - f0) * (x2 * x2 * x)
}

/// The dielectric specular layer's reflectance at cos θ = `c` (to the
/// microfacet normal): the exact Fresnel equations for relative index
/// `eta`, with `KHR_materials_specular`'s colour. The extension scales the
/// normal-incidence F0 by specularColorFactor (clamped to 1) and keeps the
/// rise toward 1 at grazing; we keep that rise exact instead of Schlick's:
/// fr = F0c + (1 - F0c)(F(c) - F0)/(1 - F0), which is F(c) itself for a
/// white specular colour (so glass conserves energy exactly) and 1 under
/// total internal reflection. `specularFactor` multiplies this (`gltf_*`).
pub fn specular_fresnel(m: &MaterialData, c: f32, eta: f32) -> Vec3 {
    let (f, _) = fresnel_dielectric(c, eta);
    let f0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let f0c = (f0 * rgb(m.specular_color)).min(Vec3::ONE);
    let rise = if f0 < 1.0 {
        ((f - f0) / (1.0 - f0)).max(0.0)
    } else {
        1.0
    };
    f0c + (Vec3::ONE - f0c) * rise
}

/// Relative index across the surface (wi's side over wo's side when
/// refracting). A thin-walled surface (thickness 0) or an opaque one hit
/// from outside sees `ior`; the back face of a closed volume sees 1/ior.
pub fn gltf_eta(m: &MaterialData, front: bool) -> f32 {
    if m.thickness > 0.0 && !front {
        1.0 / m.ior
    } else {
        m.ior
    }
}

/// Transmission through a thin wall (or an interface of index 1) goes
/// straight through: no bending, no 1/η² scaling.
pub fn gltf_thin(m: &MaterialData) -> bool {
    m.thickness <= 0.0 || (m.ior - 1.0).abs() < 1e-4
}

pub fn gltf_alpha(m: &MaterialData) -> f32 {
    m.roughness * m.roughness
}

/// (αt, αb): equal unless the material is anisotropic (`anisotropy.rs`).
pub fn gltf_alpha2(m: &MaterialData) -> Vec2 {
    anisotropy_alpha(m, gltf_alpha(m))
}

pub fn gltf_smooth(m: &MaterialData) -> bool {
    gltf_alpha2(m).x < GGX_SMOOTH_ALPHA
}

/// Colour of the microfacet reflection lobe at cos(wo, h) = `c`: the
/// metal's Schlick Fresnel tinted by the base colour, mixed by `metallic`
/// with the dielectric's specular layer.
pub fn gltf_reflection_color(m: &MaterialData, c: f32, eta: f32) -> Vec3 {
    let metal = fresnel_schlick(rgb(m.base_color), c);
    let dielectric = m.specular_factor * specular_fresnel(m, c, eta);
    let (metal, dielectric) = iridescent_reflection(m, c, eta, metal, dielectric);
    m.metallic * metal + (1.0 - m.metallic) * dielectric
}

/// What the dielectric's specular layer leaves to the base (diffuse or
/// transmission) beneath it: glTF's fresnel_mix, 1 - specular · max(fr).
pub fn gltf_base_weight(m: &MaterialData, c: f32, eta: f32) -> f32 {
    let w = 1.0 - m.specular_factor * specular_fresnel(m, c, eta).max_element();
    iridescent_base_weight(m, c, eta, w)
}

fn mean(c: Vec3) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// Probabilities of sampling the diffuse, reflection and transmission lobes:
/// each lobe's albedo estimated with the Fresnel terms at the macro normal
/// (`co` = cos θo). They sum to 1, or are all 0 for a black surface.
pub fn gltf_lobe_probs(m: &MaterialData, co: f32, eta: f32) -> (f32, f32, f32) {
    let base = (1.0 - m.metallic) * gltf_base_weight(m, co, eta) * mean(rgb(m.base_color));
    let d = (1.0 - m.transmission) * base;
    let d = d * gltf_diffuse_reflected(m);
    let r = mean(gltf_reflection_color(m, co, eta));
    let t = m.transmission * base;
    let sum = d + r + t;
    if sum > 0.0 {
        (d / sum, r / sum, t / sum)
    } else {
        (0.0, 0.0, 0.0)
    }
}

/// The refracted direction of `wo` about the (micro)normal `h` (wo·h > 0)
/// for relative index `eta`, or `None` under total internal reflection.
pub fn refract_about(wo: Vec3, h: Vec3, eta: f32) -> Option<Vec3> {
    let c = wo.dot(h);
    let (f, cos_t) = fresnel_dielectric(c, eta);
    if f >= 1.0 {
        return None;
    }
    Some((-wo / eta + (c / eta - cos_t) * h).normalize())
}

/// Half vector of a refraction pair (Walter et al. 2007, eq. 16) on the +z
/// side, or `None` where it is degenerate or a microfacet would face away
/// from either direction.
fn refraction_half(wo: Vec3, wi: Vec3, eta: f32) -> Option<Vec3> {
    let h = wo + eta * wi;
    if h.length_squared() < 1e-12 {
        return None;
    }
    let h = if h.z < 0.0 { -h } else { h }.normalize();
    (wo.dot(h) > 0.0 && wi.dot(h) < 0.0).then_some(h)
}

/// Thin-walled transmission mirrors the reflection lobe to the other side
/// (as the `KHR_materials_transmission` reference does).
fn mirror_z(w: Vec3) -> Vec3 {
    Vec3::new(w.x, w.y, -w.z)
}

/// f · |cos θi| of the non-delta lobes in the local frame (+z = shading
/// normal on wo's side), before the glTF layers (below).
pub fn gltf_base_eval_local(m: &MaterialData, eta: f32, wo: Vec3, wi: Vec3) -> Vec3 {
    let co = wo.z;
    if co <= 0.0 {
        return Vec3::ZERO;
    }
    let alpha = gltf_alpha2(m);
    let smooth = alpha.x < GGX_SMOOTH_ALPHA;
    let base_color = rgb(m.base_color);
    if wi.z > 0.0 {
        let h = (wo + wi).normalize();
        let c = wo.dot(h);
        let diffuse = (1.0 - m.metallic) * (1.0 - m.transmission) * gltf_base_weight(m, c, eta);
        let diffuse = diffuse * gltf_diffuse_reflected(m);
        let mut f = base_color * (diffuse * INV_PI * wi.z);
        if !smooth {
            let g = mf_d(h, alpha) * mf_g2(wo, wi, alpha) / (4.0 * co);
            f += gltf_reflection_color(m, c, eta) * g;
        }
        return f;
    }
    if wi.z == 0.0 || smooth || m.transmission <= 0.0 || m.metallic >= 1.0 {
        return Vec3::ZERO;
    }
    let weight = (1.0 - m.metallic) * m.transmission;
    if gltf_thin(m) {
        let r = mirror_z(wi);
        let h = (wo + r).normalize();
        let g = mf_d(h, alpha) * mf_g2(wo, r, alpha) / (4.0 * co);
        return base_color * (weight * gltf_base_weight(m, wo.dot(h), eta) * g);
    }
    let Some(h) = refraction_half(wo, wi, eta) else {
        return Vec3::ZERO;
    };
    let (woh, wih) = (wo.dot(h), wi.dot(h));
    let denom = eta * wih + woh;
    // Walter et al. 2007 eq. 21 for radiance: the η² of the radiance scaling
    // cancels the one of the half-vector Jacobian.
    let g = mf_d(h, alpha) * mf_g2(wo, wi, alpha) * woh * (-wih) / (co * denom * denom);
    base_color * (weight * gltf_base_weight(m, woh, eta) * g)
}

/// Solid-angle density of `gltf_sample` choosing wi through a non-delta
/// lobe of the base (local frame; the glTF layers below add theirs).
pub fn gltf_base_pdf_local(m: &MaterialData, eta: f32, wo: Vec3, wi: Vec3) -> f32 {
    let co = wo.z;
    if co <= 0.0 {
        return 0.0;
    }
    let (pd, pr, pt) = gltf_lobe_probs(m, co, eta);
    let alpha = gltf_alpha2(m);
    let smooth = alpha.x < GGX_SMOOTH_ALPHA;
    if wi.z > 0.0 {
        let mut pdf = pd * cosine_hemisphere_pdf(wi.z);
        if !smooth {
            let h = (wo + wi).normalize();
            pdf += pr * mf_vndf_pdf(wo, h, alpha) / (4.0 * wo.dot(h));
        }
        return pdf;
    }
    if wi.z == 0.0 || smooth || pt <= 0.0 {
        return 0.0;
    }
    if gltf_thin(m) {
        let h = (wo + mirror_z(wi)).normalize();
        return pt * mf_vndf_pdf(wo, h, alpha) / (4.0 * wo.dot(h));
    }
    let Some(h) = refraction_half(wo, wi, eta) else {
        return 0.0;
    };
    let denom = eta * wi.dot(h) + wo.dot(h);
    pt * mf_vndf_pdf(wo, h, alpha) * eta * eta * (-wi.dot(h)) / (denom * denom)
}

fn to_local(w: Vec3, t: Vec3, b: Vec3, n: Vec3) -> Vec3 {
    Vec3::new(w.dot(t), w.dot(b), w.dot(n))
}

pub fn gltf_eval(m: &MaterialData, f: &ShadingFrame, front: bool, wo: Vec3, wi: Vec3) -> Vec3 {
    let v = gltf_eval_local(
        m,
        gltf_eta(m, front),
        to_local(wo, f.t, f.b, f.n),
        to_local(wi, f.t, f.b, f.n),
    );
    if clearcoat_active(m) {
        return clearcoat_layer_eval(m, f.coat_n, wo, wi, v);
    }
    v
}

pub fn gltf_pdf(m: &MaterialData, f: &ShadingFrame, front: bool, wo: Vec3, wi: Vec3) -> f32 {
    let p = gltf_pdf_local(
        m,
        gltf_eta(m, front),
        to_local(wo, f.t, f.b, f.n),
        to_local(wi, f.t, f.b, f.n),
    );
    if clearcoat_active(m) {
        return clearcoat_layer_pdf(m, f.coat_n, wo, wi, p);
    }
    p
}

/// A coated material's non-delta sample: the mixture pdf and eval / pdf.
fn gltf_coated_weight(
    m: &MaterialData,
    f: &ShadingFrame,
    front: bool,
    wo: Vec3,
    mut s: BsdfSample,
) -> BsdfSample {
    s.pdf = gltf_pdf(m, f, front, wo, s.wi);
    s.weight = if s.pdf > 0.0 {
        gltf_eval(m, f, front, wo, s.wi) / s.pdf
    } else {
        Vec3::ZERO
    };
    s.pdf = s.pdf.max(0.0);
    s
}

/// One-sample MIS over the lobes: pick a lobe with `gltf_lobe_probs`
/// (`u_lobe`), draw wi from it (`u`); a non-delta sample reports the mixture
/// pdf and weight eval/pdf, a delta sample (smooth reflection or
/// transmission) its value over the lobe's probability. A clearcoat is
/// picked first, with probability blend (`clearcoat.rs`); the rest of
/// `u_lobe` picks among the base's lobes.
pub fn gltf_sample(
    m: &MaterialData,
    f: &ShadingFrame,
    front: bool,
    wo_world: Vec3,
    mut u_lobe: f32,
    u: Vec2,
) -> BsdfSample {
    let mut s = BsdfSample {
        wi: Vec3::ZERO,
        weight: Vec3::ZERO,
        pdf: 0.0,
        delta: false,
    };
    let coated = clearcoat_active(m);
    if coated {
        let blend = clearcoat_blend(m, wo_world.dot(f.coat_n));
        if u_lobe < blend {
            let wi = clearcoat_sample_wi(m, f.coat_n, wo_world, u);
            if clearcoat_rough(m) {
                // A failed draw (below the coat) stays failed: the base
                // may have density there, the coat's draw does not.
                if wi.dot(f.coat_n) <= 0.0 {
                    return s;
                }
                s.wi = wi;
                return gltf_coated_weight(m, f, front, wo_world, s);
            }
            // blend / blend; the base's delta weights below likewise keep
            // their value ((1 - blend) / (1 - blend)).
            s.wi = wi;
            s.delta = true;
            s.weight = Vec3::ONE;
            return s;
        }
        u_lobe = (u_lobe - blend) / (1.0 - blend);
    }
    let (t, b, n) = (f.t, f.b, f.n);
    let wo = to_local(wo_world, t, b, n);
    let co = wo.z;
    if co <= 0.0 {
        return s;
    }
    let eta = gltf_eta(m, front);
    let (pd, pr, pt) = gltf_lobe_probs(m, co, eta);
    let alpha = gltf_alpha2(m);
    let smooth = alpha.x < GGX_SMOOTH_ALPHA;
    let base_color = rgb(m.base_color);
    let (layer_wi, u_lobe) = gltf_layer_sample(m, co, eta, u_lobe, u);
    let wi = if let Some(wi) = layer_wi {
        wi
    } else if u_lobe < pd {
        sample_cosine_hemisphere(u)
    } else if u_lobe < pd + pr {
        if smooth {
            s.delta = true;
            s.weight = gltf_reflection_color(m, co, eta) / pr;
            mirror_z(-wo)
        } else {
            let h = mf_sample_vndf(wo, alpha, u);
            reflect_about(wo, h)
        }
    } else if pt > 0.0 {
        let thin = gltf_thin(m);
        if smooth {
            let Some(wi) = (if thin {
                Some(-wo)
            } else {
                refract_about(wo, Vec3::Z, eta)
            }) else {
                return s;
            };
            let scale = if thin { 1.0 } else { 1.0 / (eta * eta) };
            s.delta = true;
            s.weight = base_color
                * ((1.0 - m.metallic) * m.transmission * gltf_base_weight(m, co, eta) * scale / pt);
            wi
        } else {
            let h = mf_sample_vndf(wo, alpha, u);
            if thin {
                mirror_z(reflect_about(wo, h))
            } else {
                let Some(wi) = refract_about(wo, h, eta) else {
                    return s;
                };
                wi
            }
        }
    } else {
        return s;
    };
    if !gltf_layer_side_ok(m, layer_wi.is_some(), u_lobe < pd + pr, wi.z) {
        return s;
    }
    s.wi = (wi.x * t + wi.y * b + wi.z * n).normalize();
    if s.delta {
        s.weight *= gltf_layer_delta_scale(m, co, eta, wi.z);
        return s;
    }
    if coated {
        // Likewise a base draw where the base has no density.
        if !(gltf_pdf_local(m, eta, wo, wi) > 0.0) {
            return BsdfSample {
                wi: Vec3::ZERO,
                ..s
            };
        }
        return gltf_coated_weight(m, f, front, wo_world, s);
    }
    s.pdf = gltf_pdf_local(m, eta, wo, wi);
    if s.pdf > 0.0 {
        s.weight = gltf_eval_local(m, eta, wo, wi) / s.pdf;
    } else {
        s.pdf = 0.0;
    }
    s
}

/// The albedo AOV (`aov.rs`): the colour the surface reflects, textures
/// applied. Lambert and glTF: the base colour (a metal's is its F0); Phong:
/// diffuse plus specular colour, at most 1.
pub fn bsdf_albedo(m: &MaterialData) -> Vec3 {
    if m.kind == MATERIAL_PHONG {
        return (rgb(m.base_color) + rgb(m.specular)).min(Vec3::ONE);
    }
    rgb(m.base_color)
}

/// Only delta lobes: next-event estimation has nothing to evaluate (a
/// rough clearcoat over a delta-only base has a density).
pub fn bsdf_is_delta(m: &MaterialData) -> bool {
    m.kind == MATERIAL_MIRROR
        || (m.kind == MATERIAL_GLTF
            && gltf_smooth(m)
            && (1.0 - m.metallic) * (1.0 - m.transmission) <= 0.0
            && !clearcoat_rough(m)
            && !gltf_has_sheen(m))
}

pub fn bsdf_eval(m: &MaterialData, f: &ShadingFrame, front: bool, wo: Vec3, wi: Vec3) -> Vec3 {
    let n = f.n;
    match m.kind {
        MATERIAL_LAMBERT => lambert_eval(rgb(m.base_color), n, wi),
        MATERIAL_PHONG => phong_eval(m, n, wo, wi),
        MATERIAL_GLTF => gltf_eval(m, f, front, wo, wi),
        _ => Vec3::ZERO,
    }
}

pub fn bsdf_pdf(m: &MaterialData, f: &ShadingFrame, front: bool, wo: Vec3, wi: Vec3) -> f32 {
    let n = f.n;
    match m.kind {
        MATERIAL_LAMBERT => lambert_pdf(n, wi),
        MATERIAL_PHONG => phong_pdf(m, n, wo, wi),
        MATERIAL_GLTF => gltf_pdf(m, f, front, wo, wi),
        _ => 0.0,
    }
}

pub fn bsdf_sample(
    m: &MaterialData,
    f: &ShadingFrame,
    front: bool,
    wo: Vec3,
    u_lobe: f32,
    u: Vec2,
) -> BsdfSample {
    let n = f.n;
    if m.kind == MATERIAL_LAMBERT {
        return lambert_sample(rgb(m.base_color), f, u);
    }
    if m.kind == MATERIAL_PHONG {
        let wi = if u_lobe < phong_specular_prob(m) {
            sample_phong_lobe(reflect_about(wo, n), m.shininess, u)
        } else {
            lambert_sample(rgb(m.base_color), f, u).wi
        };
        let pdf = phong_pdf(m, n, wo, wi);
        let weight = if pdf > 0.0 {
            phong_eval(m, n, wo, wi) / pdf
        } else {
            Vec3::ZERO
        };
        return BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
        };
    }
    if m.kind == MATERIAL_GLTF {
        return gltf_sample(m, f, front, wo, u_lobe, u);
    }
    // MATERIAL_MIRROR: perfect reflection tinted by the base colour.
    BsdfSample {
        wi: reflect_about(wo, n),
        weight: if m.kind == MATERIAL_MIRROR {
            rgb(m.base_color)
        } else {
            Vec3::ZERO
        },
        pdf: 0.0,
        delta: m.kind == MATERIAL_MIRROR,
    }
}

// The glTF layers: the lobes that `KHR_materials_sheen` and
// `KHR_materials_diffuse_transmission` add to the glTF model above,
// composed around its lobes (`gltf_base_*`), in the local frame (+z = the
// shading normal on wo's side). (They call the base and `gltf_sample`
// calls them, so they share its file, as they share bsdf.glsl.)
//
// - Diffuse transmission: the diffuse base (weight (1 - metallic)(1 -
//   transmission) times the specular layer's Fresnel-mix weight) reflects
//   the fraction 1 - diffuseTransmission (`gltf_diffuse_reflected`) and
//   transmits the rest as a Lambertian lobe on the other side, tinted by
//   diffuseTransmissionColor. Thin: no refraction, straight through.
// - Sheen (Khronos' layering): f = f_sheen + f_base · S, with the albedo
//   scaling S = min(1 - max(sheenColor) E(cos θo), 1 - max(sheenColor)
//   E(|cos θi|)) (`sheen.rs`): reciprocal, and at most 1 - max·E(cos θo),
//   so the layer never adds energy. E is the lobe's directional albedo
//   clamped to 1 (`sheen_energy`); where the fitted lobe reflects more
//   than 1 (grazing, smooth sheen) it is divided by E(cos θo).
//
// Sampling stays one-sample MIS: a layer lobe is chosen first (sheen by
// its albedo, diffuse transmission by its weight, the base by an upper
// bound of its albedo), both layer lobes are cosine-weighted hemispheres
// (broad lobes), and `gltf_pdf_local` is the mixture pdf. A material
// without these lobes takes exactly the base's code path.

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

#[cfg(test)]
#[path = "tests/bsdf.rs"]
mod tests;
