//! Twin of `shaders/common/intersect.glsl`.

use super::sampling::FLT_MAX;
use glam::{Vec2, Vec3};

/// Per-ray shear of the watertight ray/triangle test (Woop, Benthin, Wald 2013).
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub k: [usize; 3],
    pub s: Vec3,
}

pub fn ray_shear(d: Vec3) -> RayShear {
    let a = d.abs();
    let kz = if a.x > a.y {
        if a.x > a.z { 0 } else { 2 }
    } else if a.y > a.z {
        1
    } else {
        2
    };
    let mut kx = if kz == 2 { 0 } else { kz + 1 };
    let mut ky = if kx == 2 { 0 } else { kx + 1 };
    if d[kz] < 0.0 {
        std::mem::swap(&mut kx, &mut ky);
    }
    RayShear {
        k: [kx, ky, kz],
        s: Vec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
    }
}

/// A hit with t in (0, t_max): (t, barycentrics of vertices 1 and 2).
pub fn intersect_triangle(
    o: Vec3,
    r: &RayShear,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    t_max: f32,
) -> Option<(f32, Vec2)> {
    let [kx, ky, kz] = r.k;
    let (a, b, c) = (v0 - o, v1 - o, v2 - o);
    let ax = a[kx] - r.s.x * a[kz];
    let ay = a[ky] - r.s.y * a[kz];
    let bx = b[kx] - r.s.x * b[kz];
    let by = b[ky] - r.s.y * b[kz];
    let cx = c[kx] - r.s.x * c[kz];
    let cy = c[ky] - r.s.y * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let az = r.s.z * a[kz];
    let bz = r.s.z * b[kz];
    let cz = r.s.z * c[kz];
    let tt = u * az + v * bz + w * cz;
    if det < 0.0 && (tt >= 0.0 || tt < t_max * det) {
        return None;
    }
    if det > 0.0 && (tt <= 0.0 || tt > t_max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = tt * inv_det;
    (t < t_max).then(|| (t, Vec2::new(v, w) * inv_det))
}

/// Entry distance of the slab test, or `FLT_MAX` on a miss.
pub fn intersect_aabb(o: Vec3, inv_d: Vec3, lo: Vec3, hi: Vec3, t_max: f32) -> f32 {
    let t0 = (lo - o) * inv_d;
    let t1 = (hi - o) * inv_d;
    let tn = t0.min(t1);
    let tf = t0.max(t1);
    let t_enter = tn.x.max(tn.y).max(tn.z.max(0.0));
    let t_exit = tf.x.min(tf.y).min(tf.z.min(t_max)) * 1.000_000_4;
    if t_enter <= t_exit { t_enter } else { FLT_MAX }
}

/// Moves p off its surface along n by a few ULPs (Wächter and Binder, RTG ch. 6).
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    const ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let offset = |p: f32, n: f32| {
        let of_i = (INT_SCALE * n) as i32;
        let p_i =
            f32::from_bits(
                (p.to_bits() as i32).wrapping_add(if p < 0.0 { -of_i } else { of_i }) as u32,
            );
        if p.abs() < ORIGIN {
            p + FLOAT_SCALE * n
        } else {
            p_i
        }
    };
    Vec3::new(offset(p.x, n.x), offset(p.y, n.y), offset(p.z, n.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_along_shared_edge_hits_once_or_more_never_zero() {
        // Two triangles sharing the edge x = 0 in the z = 0 plane.
        let (a, b, c, d) = (
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
        );
        for i in 0..1000 {
            let y = -0.99 + 1.98 * i as f32 / 1000.0;
            let o = Vec3::new(0.0, y, 1.0);
            let r = ray_shear(Vec3::new(0.0, 0.0, -1.0));
            let h1 = intersect_triangle(o, &r, a, b, c, FLT_MAX);
            let h2 = intersect_triangle(o, &r, a, d, b, FLT_MAX);
            assert!(
                h1.is_some() || h2.is_some(),
                "ray at y={y} escaped through the edge"
            );
        }
    }

    #[test]
    fn triangle_hit_gives_distance_and_barycentrics() {
        let r = ray_shear(Vec3::new(0.0, 0.0, -1.0));
        let o = Vec3::new(0.25, 0.25, 2.0);
        let (t, b) = intersect_triangle(o, &r, Vec3::ZERO, Vec3::X, Vec3::Y, FLT_MAX).unwrap();
        assert!((t - 2.0).abs() < 1e-6 && (b - Vec2::new(0.25, 0.25)).length() < 1e-6);
        assert!(intersect_triangle(o, &r, Vec3::ZERO, Vec3::X, Vec3::Y, 1.5).is_none());
        // Behind the origin: no hit.
        let o = Vec3::new(0.25, 0.25, -2.0);
        assert!(intersect_triangle(o, &r, Vec3::ZERO, Vec3::X, Vec3::Y, FLT_MAX).is_none());
    }

    #[test]
    fn offset_origin_leaves_the_plane_at_every_scale() {
        for scale in [1e-3f32, 1.0, 1e3, 1e5] {
            let p = Vec3::new(0.3, 0.7, 0.0) * scale + Vec3::new(0.0, 0.0, 0.5 * scale);
            let n = Vec3::Z;
            let q = offset_ray_origin(p, n);
            assert!(q.z > p.z, "scale {scale}");
            let q = offset_ray_origin(p, -n);
            assert!(q.z < p.z, "scale {scale}");
        }
    }
}
