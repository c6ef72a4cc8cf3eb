//! Twin of `shaders/common/sampling.glsl`.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
pub const FLT_MAX: f32 = f32::MAX;

pub fn build_onb(n: Vec3) -> (Vec3, Vec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let c = n.x * n.y * a;
    (
        Vec3::new(1.0 + s * n.x * n.x * a, s * c, -s * n.x),
        Vec3::new(c, s + n.y * n.y * a, -n.y),
    )
}

pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, (PI / 4.0) * (o.y / o.x))
    } else {
        (o.y, (PI / 2.0) - (PI / 4.0) * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u);
    let z = (1.0 - d.dot(d)).max(0.0).sqrt();
    d.extend(z)
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * INV_PI
}

/// Inverse of `sample_cosine_hemisphere` (used by tests): the square point
/// that maps to the local direction `w` (z >= 0).
pub fn invert_cosine_hemisphere(w: Vec3) -> Vec2 {
    invert_concentric_disk(Vec2::new(w.x, w.y))
}

fn invert_concentric_disk(p: Vec2) -> Vec2 {
    let r = p.length();
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    let mut phi = p.y.atan2(p.x);
    if phi < -PI / 4.0 {
        phi += 2.0 * PI;
    }
    let (a, b) = if phi < PI / 4.0 {
        (r, phi * 4.0 / PI * r)
    } else if phi < 3.0 * PI / 4.0 {
        (-(phi - PI / 2.0) * 4.0 / PI * r, r)
    } else if phi < 5.0 * PI / 4.0 {
        (-r, -(phi - PI) * 4.0 / PI * r)
    } else {
        ((phi - 3.0 * PI / 2.0) * 4.0 / PI * r, -r)
    };
    Vec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0))
}

pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub fn uniform_sphere_pdf() -> f32 {
    1.0 / (4.0 * PI)
}

pub fn sample_uniform_triangle(u: Vec2) -> Vec2 {
    let su = u.x.sqrt();
    Vec2::new(1.0 - su, u.y * su)
}

pub fn power_heuristic(f_pdf: f32, g_pdf: f32) -> f32 {
    let f2 = f_pdf * f_pdf;
    let g2 = g_pdf * g_pdf;
    if f2 + g2 > 0.0 { f2 / (f2 + g2) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: u32) -> impl Iterator<Item = Vec2> {
        (0..n * n).map(move |i| {
            Vec2::new(
                ((i % n) as f32 + 0.5) / n as f32,
                ((i / n) as f32 + 0.5) / n as f32,
            )
        })
    }

    #[test]
    fn cosine_hemisphere_sample_inverts() {
        for u in grid(37) {
            let w = sample_cosine_hemisphere(u);
            let back = invert_cosine_hemisphere(w);
            assert!(
                (back - u).abs().max_element() < 1e-4,
                "{u} -> {w} -> {back}"
            );
        }
    }

    #[test]
    fn cosine_hemisphere_pdf_integrates_to_one() {
        // Integrate pdf over the sphere with a uniform-sphere estimator.
        let n = 200;
        let sum: f32 = grid(n)
            .map(|u| cosine_hemisphere_pdf(sample_uniform_sphere(u).z) / uniform_sphere_pdf())
            .sum();
        let integral = sum / (n * n) as f32;
        assert!((integral - 1.0).abs() < 1e-3, "integral {integral}");
    }

    #[test]
    fn onb_is_orthonormal() {
        for u in grid(20) {
            let n = sample_uniform_sphere(u);
            let (t, b) = build_onb(n);
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
            assert!(t.dot(n).abs() < 1e-5 && b.dot(n).abs() < 1e-5 && t.dot(b).abs() < 1e-5);
            assert!((t.cross(b) - n).length() < 1e-4);
        }
    }

    #[test]
    fn uniform_triangle_samples_are_inside() {
        for u in grid(30) {
            let b = sample_uniform_triangle(u);
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
        }
    }
}
