#version 460
#extension GL_GOOGLE_include_directive : require
// shadow: any-hit test for every shadow ray; unoccluded ones add their
// contribution to their path (one shadow ray per path per bounce: no race).
// reads: shadow queue, BVH, triangles, spherical lights; writes: path radiance, overflow counter.
#include "bindings.glsl"
#include "trace.glsl"
#include "path_state.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= counters[COUNTER_SHADOW]) return;
    vec4 o = read_shadow_origin(k);
    vec4 d = read_shadow_direction(k);
    uint path = floatBitsToUint(d.w);
    uvec4 contribution = read_shadow_contribution_bounce(k);   // w: the path's bounce
    uint coverage_seed = FEATURE_ALPHA_MASK ? rng_coverage_seed(path_rng_key(path), contribution.w, 1u) : 0u;
    float time = motion_on() ? path_time(path_rng_key(path)) : 0.0;
    uint blocker = shadow_blocker(o.xyz, d.xyz, o.w, coverage_seed, time, BVH_MAX_ITERATIONS);
    if (blocker == OVERFLOW_HIT) {
        atomicAdd(counters[COUNTER_BVH_OVERFLOW], 1u);
    } else if (blocker == NO_HIT) {
        uvec4 radiance = read_path_radiance_bounce(path);
        write_path_radiance(path, uintBitsToFloat(radiance.xyz) + uintBitsToFloat(contribution.xyz),
                            radiance.w);
    }
}
