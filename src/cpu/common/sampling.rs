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

/// Shirley and Chiu's concentric map of the square to the disk. The angle
/// is π/4 (y/x) in the wedges about the x axis and π/2 − π/4 (x/y) about y;
/// there cos and sin of it are sin and cos of π/4 (x/y), so both wedges
/// take sine and cosine of an angle within ±π/4 (`sin_cos_octant`).
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    if o.x.abs() > o.y.abs() {
        let (s, c) = sin_cos_octant((PI / 4.0) * (o.y / o.x));
        o.x * Vec2::new(c, s)
    } else {
        let (s, c) = sin_cos_octant((PI / 4.0) * (o.x / o.y));
        o.y * Vec2::new(s, c)
    }
}

/// Sine and cosine of `a` within ±π/4, by the minimax polynomials of
/// Moshier's Cephes `sinf`/`cosf` for that range (about an ulp of error):
/// no range reduction and no branch, so the lanes compute eight at once
/// with the same operations (`lanes::concentric_disk8`).
#[inline(always)]
pub fn sin_cos_octant(a: f32) -> (f32, f32) {
    let z = a * a;
    let sin = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * a + a;
    let cos = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (sin, cos)
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

    /// Within about an ulp of f64's sine and cosine over ±π/4.
    #[test]
    fn octant_sine_and_cosine_are_accurate() {
        let n = 100_000;
        let mut worst = (0f64, 0f64);
        for i in 0..=n {
            let a = (-1.0 + 2.0 * i as f32 / n as f32) * (PI / 4.0);
            let (s, c) = sin_cos_octant(a);
            let (s64, c64) = (a as f64).sin_cos();
            worst.0 = worst.0.max((s as f64 - s64).abs());
            worst.1 = worst.1.max((c as f64 - c64).abs());
        }
        // An ulp of numbers below 1 is at most 6e-8.
        assert!(worst.0 < 1.2e-7 && worst.1 < 1.2e-7, "{worst:?}");
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
