//! Twin of `shaders/common/sheen.glsl`: the `KHR_materials_sheen` lobe, the
//! "Charlie" microfiber distribution of Estevez & Kulla 2017 ("Production
//! Friendly Microfacet Sheen BRDF") with their fitted visibility term (the
//! one the Khronos specification recommends), in the local frame (+z = the
//! shading normal on wo's side).
//!
//! The layer's directional albedo E(cos θo, roughness) = ∫ f_sheen cos θi
//! dωi (white sheen colour) scales the base below it (the glTF layers of `bsdf.rs`), so
//! a white sheen over a white base creates no energy. E comes from a
//! 32 × 32 table (`sheen_table.rs`, computed by f64 quadrature in this
//! file's tests, which check it against a fresh quadrature), interpolated
//! bilinearly; the kernels read the same f32 values from the binding
//! `sheen_albedo_table`, so both back ends use identical bits.

use super::sampling::INV_PI;
use crate::constants::{SHEEN_MIN_ROUGHNESS, SHEEN_TABLE_SIZE};
use crate::packed::sheen_table::SHEEN_ALBEDO;
use glam::Vec3;

/// Charlie alpha of perceptual sheen roughness `r` (clamped, see
/// `SHEEN_MIN_ROUGHNESS`).
pub fn sheen_alpha(r: f32) -> f32 {
    let r = r.max(SHEEN_MIN_ROUGHNESS);
    r * r
}

/// Charlie distribution D(h) = (2 + 1/α) sin^(1/α) θh / (2π), h.z = `cos_h`.
pub fn charlie_d(cos_h: f32, alpha: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) * (0.5 * INV_PI)
}

/// Estevez & Kulla's fit L(x) of the Charlie shadowing exponent, between
/// their two fits at α = 0 and α = 1 ((1 - α)² as the weight).
fn sheen_l(x: f32, alpha: f32) -> f32 {
    let w = (1.0 - alpha) * (1.0 - alpha);
    let lerp = |a: f32, b: f32| a + (b - a) * w;
    let a = lerp(21.5473, 25.3245);
    let b = lerp(3.82987, 3.32435);
    let c = lerp(0.19823, 0.16801);
    let d = lerp(-1.97760, -1.27393);
    let e = lerp(-4.32054, -4.85967);
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// Λ(cos θ) of the Charlie distribution (the fit mirrored above 0.5).
fn sheen_lambda(c: f32, alpha: f32) -> f32 {
    if c < 0.5 {
        sheen_l(c, alpha).exp()
    } else {
        (2.0 * sheen_l(0.5, alpha) - sheen_l(1.0 - c, alpha)).exp()
    }
}

/// f_sheen · cos θi for a white sheen colour (wo.z, wi.z > 0): D V cos θi
/// with V = 1 / ((1 + Λ(wo) + Λ(wi)) 4 cos θo cos θi); the cos θi cancels.
pub fn sheen_eval_white(roughness: f32, wo: Vec3, wi: Vec3) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let alpha = sheen_alpha(roughness);
    let h = (wo + wi).normalize();
    let g = 1.0 + sheen_lambda(wo.z, alpha) + sheen_lambda(wi.z, alpha);
    charlie_d(h.z, alpha) / (4.0 * wo.z * g)
}

/// Directional albedo of the white sheen lobe at cos θo = `mu` and
/// perceptual roughness `r`: the table, bilinear in (√mu, r). The fitted
/// visibility does not conserve energy at grazing angles for smooth sheen
/// (E reaches 2.9 at cos θo = 0.001 for roughness ≤ 0.07, 1.15 for 0.2;
/// below 1 from roughness 0.3): `bsdf.rs`'s glTF layers divide the lobe by
/// max(1, E(cos θo)) and scales the base by min(1, E).
pub fn sheen_albedo(mu: f32, r: f32) -> f32 {
    let last = (SHEEN_TABLE_SIZE - 1) as f32;
    let x = mu.clamp(0.0, 1.0).sqrt() * last;
    let y = r.clamp(0.0, 1.0) * last;
    let i = (x as u32).min(SHEEN_TABLE_SIZE - 2);
    let j = (y as u32).min(SHEEN_TABLE_SIZE - 2);
    let fx = x - i as f32;
    let fy = y - j as f32;
    let at = |i: u32, j: u32| SHEEN_ALBEDO[(j * SHEEN_TABLE_SIZE + i) as usize];
    let lo = at(i, j) * (1.0 - fx) + at(i + 1, j) * fx;
    let hi = at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx;
    lo * (1.0 - fy) + hi * fy
}

/// The sheen lobe's energy: min(1, E).
pub fn sheen_energy(mu: f32, r: f32) -> f32 {
    sheen_albedo(mu, r).min(1.0)
}

#[cfg(test)]
#[path = "tests/sheen.rs"]
mod tests;
