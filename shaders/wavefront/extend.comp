#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
// extend: closest hit for every ray in this bounce's queue; when shading is
// split by material (SHADE_QUEUE != SHADE_QUEUE_NONE), also sorts the hits
// into the basic and full shading queues, and ends the paths whose rays
// escape a scene where nothing at infinity shines (escapes_are_dark).
// reads: ray queue (bounce parity), path origin/direction, BVH, triangles,
// spherical lights;
// writes: path hit, overflow counter, shading queues.
#include "bindings.glsl"
#include "path_state.glsl"
#include "queues.glsl"
#include "trace.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

// Whether shading an escaped ray would do nothing but end its path: no
// environment, no sun disk, no auxiliary output to record. Its radiance
// then stays as it is, and only a shading queue can leave it out (without
// the split, shade takes every ray of the bounce).
bool escapes_are_dark() {
    return !environment_shines() && !suns_shine() && !(FEATURE_AOV && params.aov != 0u);
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    uint q = pc.bounce & 1u;
    if (k >= counters[COUNTER_RAYS_0 + q]) return;
    uint path = ray_queue[q * params.pool_size + k];
    vec3 o = read_path_origin(path).xyz;
    vec3 d = read_path_direction(path);
    // The path's own bounce (path_radiance's w) seeds its alpha coverage.
    uint coverage_seed = FEATURE_ALPHA_MASK
        ? rng_coverage_seed(path_rng_key(path), read_path_radiance_bounce(path).w, 0u) : 0u;
    float time = motion_on() ? path_time(path_rng_key(path)) : 0.0;
    Hit hit = closest_hit(o, d, coverage_seed, time, BVH_MAX_ITERATIONS);
    if (hit.triangle == OVERFLOW_HIT) atomicAdd(counters[COUNTER_BVH_OVERFLOW], 1u);
    write_path_hit(path, uvec4(floatBitsToUint(hit.t), hit.triangle, floatBitsToUint(hit.b12)));
    if (SHADE_QUEUE != SHADE_QUEUE_NONE) {
        uint inst;   // the hit's instance (unused here)
        // Misses, spherical lights and overflows are basic: no BSDF.
        if (hit.triangle < LIGHT_HIT_FLAG
            && fetch_triangle_shade_queue(hit_slot(hit.triangle, inst)) == SHADE_QUEUE_FULL) {
            uint slot = queue_push(COUNTER_SHADE_FULL);
            shade_queue[params.pool_size - 1u - slot] = path;
        } else if (hit.triangle != NO_HIT || !escapes_are_dark()) {
            uint slot = queue_push(COUNTER_SHADE_BASIC);
            shade_queue[slot] = path;
        }
    }
}
