//! Twin of `shaders/common/bsdf.glsl`. Directions point away from the
//! surface; `n` is on the side of `wo`; eval returns f·|cos θi|; sample
//! returns the weight f·|cos θi|/pdf.

use super::sampling::{INV_PI, build_onb, cosine_hemisphere_pdf, sample_cosine_hemisphere};
use glam::{Vec2, Vec3};

pub struct BsdfSample {
    pub wi: Vec3,
    pub weight: Vec3,
    pub pdf: f32,
}

pub fn lambert_eval(albedo: Vec3, n: Vec3, wi: Vec3) -> Vec3 {
    albedo * (INV_PI * n.dot(wi).max(0.0))
}

pub fn lambert_pdf(n: Vec3, wi: Vec3) -> f32 {
    cosine_hemisphere_pdf(n.dot(wi))
}

pub fn lambert_sample(albedo: Vec3, n: Vec3, u: Vec2) -> BsdfSample {
    let (t, b) = build_onb(n);
    let l = sample_cosine_hemisphere(u);
    let pdf = cosine_hemisphere_pdf(l.z);
    BsdfSample {
        wi: (l.x * t + l.y * b + l.z * n).normalize(),
        weight: if pdf > 0.0 { albedo } else { Vec3::ZERO },
        pdf,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::sampling::{sample_uniform_sphere, uniform_sphere_pdf};

    #[test]
    fn lambert_eval_pdf_and_sample_agree() {
        let albedo = Vec3::new(0.8, 0.5, 0.2);
        let n = Vec3::new(0.3, -0.4, 0.866).normalize();
        for i in 0..400 {
            let u = Vec2::new(
                (i % 20) as f32 / 20.0 + 0.025,
                (i / 20) as f32 / 20.0 + 0.025,
            );
            let s = lambert_sample(albedo, n, u);
            assert!((s.pdf - lambert_pdf(n, s.wi)).abs() < 1e-4);
            let w = lambert_eval(albedo, n, s.wi) / s.pdf;
            assert!((w - s.weight).abs().max_element() < 1e-3);
        }
    }

    #[test]
    fn lambert_albedo_is_its_hemispherical_reflectance() {
        let albedo = Vec3::splat(0.7);
        let n = Vec3::Z;
        let m = 300;
        let mut sum = Vec3::ZERO;
        for i in 0..m * m {
            let u = Vec2::new(
                ((i % m) as f32 + 0.5) / m as f32,
                ((i / m) as f32 + 0.5) / m as f32,
            );
            let wi = sample_uniform_sphere(u);
            sum += lambert_eval(albedo, n, wi) / uniform_sphere_pdf();
        }
        let r = sum / (m * m) as f32;
        assert!((r - albedo).abs().max_element() < 2e-3, "{r}");
    }
}
