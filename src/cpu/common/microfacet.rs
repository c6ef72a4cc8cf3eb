//! Twin of `shaders/common/microfacet.glsl`: the isotropic GGX
//! (Trowbridge–Reitz) microfacet distribution in a local frame whose +z is
//! the shading normal. `alpha` is the perceptual roughness squared.
//!
//! Facts from Walter et al. 2007 ("Microfacet Models for Refraction through
//! Rough Surfaces"), Heitz 2014 ("Understanding the Masking-Shadowing
//! Function", height-correlated Smith G2) and Heitz 2018 ("Sampling the GGX
//! Distribution of Visible Normals").

use super::sampling::INV_PI;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// GGX normal distribution D(h) for a microfacet normal h (unit, local).
pub fn ggx_d(h: Vec3, alpha: f32) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = h.z * h.z * (a2 - 1.0) + 1.0;
    a2 * INV_PI / (d * d)
}

/// Smith Λ(w) for GGX: (-1 + sqrt(1 + α² tan²θ)) / 2.
pub fn ggx_lambda(w: Vec3, alpha: f32) -> f32 {
    let z2 = (w.z * w.z).max(1e-20);
    let tan2 = (1.0 - z2).max(0.0) / z2;
    0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
}

/// Smith masking G1(w) = 1 / (1 + Λ(w)).
pub fn ggx_g1(w: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + ggx_lambda(w, alpha))
}

/// Height-correlated masking-shadowing G2 = 1 / (1 + Λ(wo) + Λ(wi)).
pub fn ggx_g2(wo: Vec3, wi: Vec3, alpha: f32) -> f32 {
    1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha))
}

/// A microfacet normal drawn from the distribution of normals visible from
/// `wo` (wo.z > 0), D_wo(h) = G1(wo) max(0, wo·h) D(h) / wo.z (Heitz 2018:
/// stretch to the hemisphere configuration, sample the projected disk,
/// unstretch), for roughness a = (αx, αy); the isotropic distribution is
/// a.x == a.y (`sample_ggx_vndf`).
pub fn sample_ggx_vndf_aniso(wo: Vec3, a: Vec2, u: Vec2) -> Vec3 {
    let vh = Vec3::new(a.x * wo.x, a.y * wo.y, wo.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(a.x * nh.x, a.y * nh.y, nh.z.max(0.0)).normalize()
}

/// `sample_ggx_vndf_aniso` of the isotropic distribution.
pub fn sample_ggx_vndf(wo: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    sample_ggx_vndf_aniso(wo, Vec2::splat(alpha), u)
}

/// Density of `sample_ggx_vndf` choosing h (per solid angle of h).
pub fn ggx_vndf_pdf(wo: Vec3, h: Vec3, alpha: f32) -> f32 {
    let woh = wo.dot(h);
    if wo.z <= 0.0 || woh <= 0.0 {
        return 0.0;
    }
    ggx_g1(wo, alpha) * woh * ggx_d(h, alpha) / wo.z
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ D(h) cos θh dh = 1 (the projected microfacet area is the
    /// macrosurface), by the midpoint rule in (cos θ, φ).
    #[test]
    fn ggx_d_projected_area_is_one() {
        for alpha in [0.05f32, 0.3, 0.8, 1.0] {
            let n = 4000;
            let mut sum = 0.0f64;
            for i in 0..n {
                // Dense near cos θ = 1, where a narrow D lives: c = 1 - x².
                let x = (i as f64 + 0.5) / n as f64;
                let c = 1.0 - x * x;
                let dc = 2.0 * x / n as f64;
                let s = (1.0 - c * c).max(0.0).sqrt();
                let h = Vec3::new(s as f32, 0.0, c as f32);
                sum += ggx_d(h, alpha) as f64 * c * dc * 2.0 * std::f64::consts::PI;
            }
            assert!((sum - 1.0).abs() < 2e-3, "alpha {alpha}: {sum}");
        }
    }

    /// The visible normals' density integrates to 1 over the hemisphere:
    /// that is G1's definition, so this checks D, Λ and the pdf together.
    #[test]
    fn ggx_vndf_pdf_integrates_to_one() {
        for (alpha, theta) in [(0.1f32, 0.3f32), (0.5, 1.2), (0.9, 0.7), (0.3, 1.5)] {
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            let (nc, np) = (2000, 128);
            let mut sum = 0.0f64;
            for i in 0..nc {
                let x = (i as f64 + 0.5) / nc as f64;
                let c = 1.0 - x * x;
                let dc = 2.0 * x / nc as f64;
                let s = (1.0 - c * c).max(0.0).sqrt();
                for j in 0..np {
                    let phi = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
                    let h = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
                    sum += ggx_vndf_pdf(wo, h, alpha) as f64 * dc * 2.0 * std::f64::consts::PI
                        / np as f64;
                }
            }
            assert!((sum - 1.0).abs() < 3e-3, "alpha {alpha}, θ {theta}: {sum}");
        }
    }

    /// Sampled normals are visible (wo·h > 0) and unit.
    #[test]
    fn ggx_vndf_samples_are_visible_unit_normals() {
        let wo = Vec3::new(0.8, 0.1, 0.2).normalize();
        for i in 0..1000 {
            let u = Vec2::new((i % 37) as f32 / 37.0, (i / 37) as f32 / 28.0);
            let h = sample_ggx_vndf(wo, 0.4, u);
            assert!((h.length() - 1.0).abs() < 1e-5 && h.z >= 0.0 && wo.dot(h) >= -1e-6);
        }
    }
}
