//! Twin of `shaders/common/thin_film.glsl`: `KHR_materials_iridescence`,
//! the thin-film interference Fresnel of Belcour & Barla 2017 ("A Practical
//! Extension to Microfacet Theory for the Modeling of Varying Iridescence")
//! as the extension's specification evaluates it: an air / film / base
//! stack, Schlick reflectances at both interfaces, the base's index from its
//! F0 per channel, the first two interference orders integrated against
//! Gaussian fits of the CIE XYZ matching functions in Fourier space, then
//! XYZ to linear Rec.709 (RGB, not spectral).
//!
//! The film replaces the specular Fresnel of the glTF model, mixed by the
//! iridescence factor (`bsdf.rs` calls `iridescent_reflection` and
//! `iridescent_base_weight`): the metal's F0 is its base colour, the
//! dielectric's the F0 of its IOR times the specular colour. Thickness is
//! `iridescence_thickness_max` (textures.rs puts mix(min, max, G) there);
//! 0 is no film. The film is on the outside: seen from inside a volume
//! (eta < 1) the surface is not iridescent. The result is clamped to
//! [0, 1] per channel (the XYZ fit can leave the gamut), so the base below
//! keeps a weight 1 - max(F) ≥ 0.

use crate::constants::LOBE_IRIDESCENCE;
use crate::packed::layout::MaterialData;
use glam::Vec3;
use std::f32::consts::PI;

/// The film of material `m` is present and seen from outside (eta ≥ 1).
pub fn gltf_iridescent(m: &MaterialData, eta: f32) -> bool {
    m.lobes & LOBE_IRIDESCENCE != 0 && m.iridescence_thickness_max > 0.0 && eta >= 1.0
}

/// The XYZ matching functions (Gaussian fits) in Fourier space at optical
/// path difference `opd` (nm) and phase shift `shift`, as linear Rec.709.
fn eval_sensitivity(opd: f32, shift: Vec3) -> Vec3 {
    let phase = 2.0 * PI * opd * 1.0e-9;
    let val = Vec3::new(5.4856e-13, 4.4201e-13, 5.2481e-13);
    let pos = Vec3::new(1.6810e+06, 1.7953e+06, 2.2084e+06);
    let var = Vec3::new(4.3278e+09, 9.3046e+09, 6.6121e+09);
    let p2 = phase * phase;
    let gauss = |v: f32, p: f32, s: f32, sh: f32| {
        v * (2.0 * PI * s).sqrt() * (p * phase + sh).cos() * (-p2 * s).exp()
    };
    let x =
        gauss(val.x, pos.x, var.x, shift.x) + gauss(9.7470e-14, 2.2399e+06, 4.5282e+09, shift.x);
    let y = gauss(val.y, pos.y, var.y, shift.y);
    let z = gauss(val.z, pos.z, var.z, shift.z);
    let (x, y, z) = (x / 1.0685e-7, y / 1.0685e-7, z / 1.0685e-7);
    Vec3::new(
        3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
        -0.969266 * x + 1.8760108 * y + 0.0415560 * z,
        0.0556434 * x - 0.2040259 * y + 1.0572252 * z,
    )
}

fn schlick(f0: f32, c: f32) -> f32 {
    let x = (1.0 - c).clamp(0.0, 1.0);
    let x2 = x * x;
    f0 + (1.0 - f0) * (x2 * x2 * x)
}

fn ior_to_f0(t: f32, i: f32) -> f32 {
    let q = (t - i) / (t + i);
    q * q
}

/// Reflectance of the air / film (index `film_ior`, `thickness` nm) / base
/// (normal-incidence reflectance `base_f0`) stack at cos θ = `cos1`.
pub fn thin_film_fresnel(film_ior: f32, cos1: f32, thickness: f32, base_f0: Vec3) -> Vec3 {
    let outside = 1.0f32;
    // The film's index fades to the outside's as the film vanishes.
    let t = (thickness / 0.03).clamp(0.0, 1.0);
    let eta2 = outside + (film_ior - outside) * (t * t * (3.0 - 2.0 * t));
    let sin2_sq = (outside / eta2) * (outside / eta2) * (1.0 - cos1 * cos1);
    let cos2_sq = 1.0 - sin2_sq;
    if cos2_sq < 0.0 {
        return Vec3::ONE;
    }
    let cos2 = cos2_sq.sqrt();
    let r12 = schlick(ior_to_f0(eta2, outside), cos1);
    let t121 = 1.0 - r12;
    let phi12 = if eta2 < outside { PI } else { 0.0 };
    let phi21 = PI - phi12;
    let opd = 2.0 * eta2 * thickness * cos2;
    let mut out = [0.0f32; 3];
    let mut r123 = [0.0f32; 3];
    let mut phi = [0.0f32; 3];
    let mut cm = [0.0f32; 3];
    for ch in 0..3 {
        let sf0 = base_f0[ch].clamp(0.0, 0.9999).sqrt();
        let base_ior = (1.0 + sf0) / (1.0 - sf0);
        let r23 = schlick(ior_to_f0(base_ior, eta2), cos2);
        let phi23 = if base_ior < eta2 { PI } else { 0.0 };
        r123[ch] = (r12 * r23).clamp(1e-5, 0.9999);
        let rs = t121 * t121 * r23 / (1.0 - r123[ch]);
        out[ch] = r12 + rs;
        cm[ch] = rs - t121;
        phi[ch] = phi21 + phi23;
    }
    let (r123, phi, mut cm) = (Vec3::from(r123), Vec3::from(phi), Vec3::from(cm));
    let r123_sqrt = Vec3::new(r123.x.sqrt(), r123.y.sqrt(), r123.z.sqrt());
    let mut i = Vec3::from(out);
    for m in 1..=2 {
        let mf = m as f32;
        cm *= r123_sqrt;
        i += cm * (2.0 * eval_sensitivity(mf * opd, mf * phi));
    }
    i.clamp(Vec3::ZERO, Vec3::ONE)
}

/// The metal's and the dielectric's reflection colours (`gltf_reflection_
/// color`) with the film mixed in by the iridescence factor.
pub fn iridescent_reflection(
    m: &MaterialData,
    c: f32,
    eta: f32,
    metal: Vec3,
    dielectric: Vec3,
) -> (Vec3, Vec3) {
    if !gltf_iridescent(m, eta) {
        return (metal, dielectric);
    }
    let d = m.iridescence_thickness_max;
    let fm = thin_film_fresnel(m.iridescence_ior, c, d, Vec3::from(m.base_color));
    let fd = thin_film_fresnel(m.iridescence_ior, c, d, dielectric_f0(m, eta));
    let k = m.iridescence;
    (
        metal + (fm - metal) * k,
        dielectric + (m.specular_factor * fd - dielectric) * k,
    )
}

/// The weight the dielectric's specular layer leaves to the base
/// (`gltf_base_weight`) with the film mixed in.
pub fn iridescent_base_weight(m: &MaterialData, c: f32, eta: f32, w: f32) -> f32 {
    if !gltf_iridescent(m, eta) {
        return w;
    }
    let d = m.iridescence_thickness_max;
    let fd = thin_film_fresnel(m.iridescence_ior, c, d, dielectric_f0(m, eta));
    w + (1.0 - m.specular_factor * fd.max_element() - w) * m.iridescence
}

fn dielectric_f0(m: &MaterialData, eta: f32) -> Vec3 {
    let q = (eta - 1.0) / (eta + 1.0);
    (q * q * Vec3::from(m.specular_color)).min(Vec3::ONE)
}
