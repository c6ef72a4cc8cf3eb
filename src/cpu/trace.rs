//! The two ray queries of a bounce (twin: shaders/common/trace.glsl).
//! Spherical lights are not in the BVH, so both also test them. The kernels'
//! `max_work` argument has no twin here: only lavapipe's loop limit needs it,
//! and the CPU always allows BVH_MAX_ITERATIONS. `time`: the ray's moment in
//! the shutter (`motion`).

use super::bvh::{Hit, NO_HIT, OVERFLOW_HIT, trace_ray};
use super::lights::intersect_sphere_lights;
use crate::constants::LIGHT_HIT_FLAG;
use crate::packed::PackedScene;
use glam::Vec3;

/// The nearest of the BVH's hit and the spherical lights' (`LIGHT_HIT_FLAG |
/// k`); `OVERFLOW_HIT` when traversal gave up.
pub fn closest_hit(scene: &PackedScene, o: Vec3, d: Vec3, coverage_seed: u32, time: f32) -> Hit {
    let hit = trace_ray(scene, o, d, f32::MAX, false, coverage_seed, time);
    nearest_with_sphere_lights(scene, o, d, hit)
}

/// `closest_hit` after the BVH's hit: a spherical light nearer than it
/// takes its place.
#[inline]
pub fn nearest_with_sphere_lights(scene: &PackedScene, o: Vec3, d: Vec3, mut hit: Hit) -> Hit {
    if hit.triangle == OVERFLOW_HIT {
        return hit;
    }
    let mut t = if hit.triangle == NO_HIT {
        f32::MAX
    } else {
        hit.t
    };
    let k = intersect_sphere_lights(scene, o, d, &mut t);
    if k != NO_HIT {
        hit.t = t;
        hit.triangle = LIGHT_HIT_FLAG | k;
        hit.b12 = glam::Vec2::ZERO;
    }
    hit
}

/// What blocks a shadow ray: `NO_HIT` when nothing does, `OVERFLOW_HIT` when
/// traversal gave up, anything else when a triangle or a spherical light does.
pub fn shadow_blocker(
    scene: &PackedScene,
    o: Vec3,
    d: Vec3,
    t_max: f32,
    coverage_seed: u32,
    time: f32,
) -> u32 {
    if let Some(blocker) = sphere_light_blocker(scene, o, d, t_max) {
        return blocker;
    }
    trace_ray(scene, o, d, t_max, true, coverage_seed, time).triangle
}

/// `shadow_blocker`'s first question: a spherical light before `t_max`.
#[inline]
pub fn sphere_light_blocker(scene: &PackedScene, o: Vec3, d: Vec3, t_max: f32) -> Option<u32> {
    let mut t = t_max;
    let sphere = intersect_sphere_lights(scene, o, d, &mut t);
    (sphere != NO_HIT).then_some(LIGHT_HIT_FLAG | sphere)
}
