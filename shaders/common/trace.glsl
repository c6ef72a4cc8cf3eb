// The two ray queries of a bounce, shared by the wavefront kernels (extend,
// shadow) and the per-path loop (path_loop.comp); twin: src/cpu/common/trace.rs.
// Spherical lights are not in the BVH, so both also test them. `max_work`
// is trace_ray_bounded's (GPU only); `time` the ray's moment in the shutter
// (motion.glsl).
#ifndef TRACE_GLSL
#define TRACE_GLSL

#include "bvh.glsl"
#include "lights.glsl"

// The nearest of the BVH's hit and the spherical lights' (LIGHT_HIT_FLAG | k);
// OVERFLOW_HIT when traversal gave up.
Hit closest_hit(vec3 o, vec3 d, uint coverage_seed, float time, uint max_work) {
    Hit hit = trace_ray_bounded(o, d, FLT_MAX, false, coverage_seed, time, max_work);
    if (hit.triangle == OVERFLOW_HIT) return hit;
    float t = hit.triangle == NO_HIT ? FLT_MAX : hit.t;
    uint k = intersect_sphere_lights(o, d, t);
    if (k != NO_HIT) {
        hit.t = t;
        hit.triangle = LIGHT_HIT_FLAG | k;
        hit.b12 = vec2(0.0);
    }
    return hit;
}

// What blocks a shadow ray: NO_HIT when nothing does, OVERFLOW_HIT when
// traversal gave up, anything else when a triangle or a spherical light does.
uint shadow_blocker(vec3 o, vec3 d, float t_max, uint coverage_seed, float time, uint max_work) {
    float t = t_max;
    uint sphere = intersect_sphere_lights(o, d, t);
    if (sphere != NO_HIT) return LIGHT_HIT_FLAG | sphere;
    return trace_ray_bounded(o, d, t_max, true, coverage_seed, time, max_work).triangle;
}

#endif
