//! Twin of `shaders/common/intersect.glsl`.

use super::sampling::FLT_MAX;
use crate::constants::{GAMMA1, GAMMA7, OFFSET_EDGE_FRACTION};
use glam::{Vec2, Vec3};

/// Per-ray shear of the watertight ray/triangle test (Woop, Benthin, Wald 2013).
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub k: [usize; 3],
    pub s: Vec3,
}

/// The components are read from an array by index: `Vec3`'s own indexing
/// is a match, which compiles to a cascade of branches on the axes, and a
/// bounce's random directions mispredict them.
pub fn ray_shear(d: Vec3) -> RayShear {
    let a = d.abs();
    // kz = x if a.x > a.y and a.x > a.z, else y if a.y > a.z, else z: the
    // nested ifs' answer, from the three comparisons without a branch (a
    // bounce's random directions mispredicted them about a third of the
    // time).
    let x_largest = a.x > a.y && a.x > a.z;
    let y_largest = !(a.x > a.y) && a.y > a.z;
    let kz = 2 - 2 * usize::from(x_largest) - usize::from(y_largest);
    let d = d.to_array();
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

/// A hit in front of the origin (t > 0, at any distance): (t, barycentrics
/// of vertices 1 and 2). Whether it is the nearest is asked of t itself
/// (`bvh::nearer_hit`), so that the answer cannot depend on the order in
/// which a traversal meets triangles at equal distance.
pub fn triangle_hit(o: Vec3, r: &RayShear, v0: Vec3, v1: Vec3, v2: Vec3) -> Option<(f32, Vec2)> {
    let [kx, ky, kz] = r.k;
    let (a, b, c) = (
        (v0 - o).to_array(),
        (v1 - o).to_array(),
        (v2 - o).to_array(),
    );
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
    // In front of the origin: tt has det's sign (t > 0 without dividing).
    if (det < 0.0 && tt >= 0.0) || (det > 0.0 && tt <= 0.0) {
        return None;
    }
    let inv_det = 1.0 / det;
    Some((tt * inv_det, Vec2::new(v, w) * inv_det))
}

/// A hit with t in (0, t_max): (t, barycentrics of vertices 1 and 2).
#[cfg(test)]
pub fn intersect_triangle(
    o: Vec3,
    r: &RayShear,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    t_max: f32,
) -> Option<(f32, Vec2)> {
    triangle_hit(o, r, v0, v1, v2).filter(|&(t, _)| t < t_max)
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

/// The point with barycentrics `b12` of vertices 1 and 2, from the edges
/// (exact for small triangles far from the origin, by Sterbenz).
pub fn triangle_point(b12: Vec2, v0: Vec3, v1: Vec3, v2: Vec3) -> Vec3 {
    v0 + (b12.x * (v1 - v0) + b12.y * (v2 - v0))
}

/// Error bound of [`triangle_point`]: gamma(1) |p| for the last addition,
/// gamma(7) (|b1 e1| + |b2 e2|) for the rest, at least `OFFSET_EDGE_FRACTION`
/// of the largest edge component (the watertight test's own rounding).
pub fn triangle_point_error(b12: Vec2, v0: Vec3, v1: Vec3, v2: Vec3, p: Vec3) -> Vec3 {
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let e = e1.abs().max(e2.abs());
    let floor_e = OFFSET_EDGE_FRACTION * e.x.max(e.y.max(e.z));
    let bound = GAMMA1 * p.abs() + GAMMA7 * ((b12.x * e1).abs() + (b12.y * e2).abs());
    bound.max(Vec3::splat(floor_e))
}

/// The float after x away from zero in the direction of sign s.
fn next_float_toward(x: f32, s: f32) -> f32 {
    if s == 0.0 {
        return x;
    }
    if x == 0.0 {
        let tiny = f32::from_bits(1);
        return if s > 0.0 { tiny } else { -tiny };
    }
    let bits = x.to_bits();
    f32::from_bits(if (x > 0.0) == (s > 0.0) {
        bits + 1
    } else {
        bits - 1
    })
}

/// One component of [`offset_ray_origin`]: p + o, one float further when
/// rounding took back part of o.
pub fn offset_component(p: f32, o: f32) -> f32 {
    let po = p + o;
    if (po - p).abs() < o.abs() {
        next_float_toward(po, o)
    } else {
        po
    }
}

/// Moves p (known to within `p_error`) off its surface along n by the
/// bound's projection on n (pbrt-v4, OffsetRayOrigin), stepping a component
/// one float further only where rounding shortened its offset.
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let o = d * n;
    Vec3::new(
        offset_component(p.x, o.x),
        offset_component(p.y, o.y),
        offset_component(p.z, o.z),
    )
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
        // A tilted triangle at several scales and translations; points inside
        // it, offset to either side, must see it at t > 0 only on the side
        // they were moved away from (never a self-hit).
        let base = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(0.9, 0.25, 0.35),
            Vec3::new(0.2, 0.8, 0.6),
        ];
        for (scale, shift) in [(1e-3f32, 0.0f32), (1.0, 0.0), (1e4, 0.0), (1.0, 1e5)] {
            let v = base.map(|p| p * scale + Vec3::splat(shift));
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
            for i in 1..200 {
                let b1 = (i as f32 * 0.618_034).fract() * 0.5;
                let b2 = (i as f32 * 0.414_213_6).fract() * 0.5;
                let b = Vec2::new(b1, b2);
                let p = triangle_point(b, v[0], v[1], v[2]);
                let err = triangle_point_error(b, v[0], v[1], v[2], p);
                for side in [n, -n] {
                    let q = offset_ray_origin(p, err, side);
                    // ... and it moves no further than the coordinates'
                    // precision requires (a 256-ULP offset is 2 m at 1e5).
                    let ulp = |x: f32| f32::from_bits(x.to_bits() + 1) - x;
                    let bound = 1e-5 * scale + 16.0 * ulp(shift);
                    assert!(
                        (q - p).length() <= bound,
                        "offset {} above {bound} at scale {scale} shift {shift}",
                        (q - p).length()
                    );
                    // Rays leaving on the offset side, in many directions.
                    for k in 0..16 {
                        let a = k as f32 * 0.4;
                        let t = side.any_orthonormal_vector();
                        let d = (side * 0.05 + t * a.cos() + side.cross(t) * a.sin()).normalize();
                        let r = ray_shear(d);
                        assert!(
                            intersect_triangle(q, &r, v[0], v[1], v[2], FLT_MAX).is_none(),
                            "self-hit at scale {scale} shift {shift}"
                        );
                    }
                }
            }
        }
    }
}
