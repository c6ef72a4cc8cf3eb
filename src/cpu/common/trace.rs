//! The two ray queries of a bounce (twin: shaders/common/trace.glsl):
//! their spherical-light halves. Spherical lights are not in the BVH, so
//! both queries also test them; `closest_hit` and `shadow_blocker`
//! themselves are in `cpu::traversal`, which picks the BVH traversal. The kernels'
//! `max_work` argument has no twin here: only lavapipe's loop limit needs it,
//! and the CPU always allows BVH_MAX_ITERATIONS. `time`: the ray's moment in
//! the shutter (`motion`).

use super::bvh::{Hit, NO_HIT, OVERFLOW_HIT};
use super::lights::intersect_sphere_lights;
use crate::constants::LIGHT_HIT_FLAG;
use crate::packed::PackedScene;
use glam::Vec3;

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

/// `shadow_blocker`'s first question: a spherical light before `t_max`.
#[inline]
pub fn sphere_light_blocker(scene: &PackedScene, o: Vec3, d: Vec3, t_max: f32) -> Option<u32> {
    let mut t = t_max;
    let sphere = intersect_sphere_lights(scene, o, d, &mut t);
    (sphere != NO_HIT).then_some(LIGHT_HIT_FLAG | sphere)
}
