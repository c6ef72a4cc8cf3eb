#version 460
#extension GL_GOOGLE_include_directive : require
// shadow: any-hit test for every shadow ray; unoccluded ones add their
// contribution to their path (one shadow ray per path per bounce: no race).
// reads: shadow queue, BVH, triangles, spherical lights; writes: path radiance, overflow counter.
#include "bindings.glsl"
#include "bvh.glsl"
#include "lights.glsl"
#include "path_state.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= counters[COUNTER_SHADOW]) return;
    vec4 o = read_shadow_origin(k);
    vec4 d = read_shadow_direction(k);
    float t_max = o.w;
    if (intersect_sphere_lights(o.xyz, d.xyz, t_max) != NO_HIT) return;   // a spherical light occludes
    uint path = floatBitsToUint(d.w);
    uint coverage_seed = FEATURE_ALPHA_MASK ? rng_coverage_seed(path_rng_key(path), pc.bounce, 1u) : 0u;
    Hit hit = trace_ray(o.xyz, d.xyz, o.w, true, coverage_seed);
    if (hit.triangle == OVERFLOW_HIT) {
        atomicAdd(counters[COUNTER_BVH_OVERFLOW], 1u);
    } else if (hit.triangle == NO_HIT) {
        write_path_radiance(path, read_path_radiance(path) + read_shadow_contribution(k));
    }
}
