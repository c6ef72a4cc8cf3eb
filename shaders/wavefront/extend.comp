#version 460
#extension GL_GOOGLE_include_directive : require
// extend: closest hit for every ray in this bounce's queue.
// reads: ray queue (bounce parity), path origin/direction, BVH, triangles,
// spherical lights;
// writes: path hit, overflow counter.
#include "bindings.glsl"
#include "path_state.glsl"
#include "bvh.glsl"
#include "lights.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void main() {
    uint k = gl_GlobalInvocationID.x;
    uint q = pc.bounce & 1u;
    if (k >= counters[COUNTER_RAYS_0 + q]) return;
    uint path = ray_queue[q * params.pool_size + k];
    vec3 o = read_path_origin(path).xyz;
    vec3 d = read_path_direction(path);
    uint coverage_seed = FEATURE_ALPHA_MASK ? rng_coverage_seed(path_rng_key(path), pc.bounce, 0u) : 0u;
    Hit hit = trace_ray(o, d, FLT_MAX, false, coverage_seed);
    if (hit.triangle == OVERFLOW_HIT) {
        atomicAdd(counters[COUNTER_BVH_OVERFLOW], 1u);
    } else {
        // Spherical lights are not in the BVH: the nearer of the two wins.
        float t = hit.triangle == NO_HIT ? FLT_MAX : hit.t;
        uint k = intersect_sphere_lights(o, d, t);
        if (k != NO_HIT) {
            hit.t = t;
            hit.triangle = LIGHT_HIT_FLAG | k;
            hit.b12 = vec2(0.0);
        }
    }
    write_path_hit(path, uvec4(floatBitsToUint(hit.t), hit.triangle, floatBitsToUint(hit.b12)));
}
