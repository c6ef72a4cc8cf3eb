#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
// shade: emission, light sample, BSDF sample and Russian roulette for every
// ray in this bounce's queue (shade_path in integrator.glsl).
// reads: ray queue (bounce parity), path state and hit, scene;
// writes: path state, path radiance, next ray queue, shadow queue.
#include "bindings.glsl"
#include "integrator.glsl"
#include "queues.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void main() {
    uint k = gl_GlobalInvocationID.x;
    uint q = pc.bounce & 1u;
    if (k >= counters[COUNTER_RAYS_0 + q]) return;
    uint path = ray_queue[q * params.pool_size + k];

    uint pixels = params.width * params.height;
    uint pixel = (pc.pixel_start + path) % pixels;
    uint sample_index = pc.sample_start + (pc.pixel_start + path) / pixels;
    RngKey key = rng_sampler_key(params.rng_sampler, pixel, sample_index, params.seed);

    PathState s;
    vec4 o = path_origin[path];
    s.origin = o.xyz;
    s.prev_pdf = o.w;
    s.direction = path_direction[path].xyz;
    s.throughput = path_throughput[path].xyz;
    uvec4 h = path_hit[path];
    Hit hit;
    hit.t = uintBitsToFloat(h.x);
    hit.triangle = h.y;
    hit.b12 = uintBitsToFloat(h.zw);

    ShadeResult r = shade_path(s, hit, key, pc.bounce);
    path_radiance[path].xyz += r.emitted;
    if (r.shadow) {
        uint slot = queue_push(COUNTER_SHADOW);
        shadow_origin[slot] = vec4(r.shadow_origin, r.shadow_t_max);
        shadow_direction[slot] = vec4(r.shadow_direction, uintBitsToFloat(path));
        shadow_contribution[slot] = vec4(r.shadow_contribution, 0.0);
    }
    if (r.next) {
        uint slot = queue_push(COUNTER_RAYS_0 + (q ^ 1u));
        ray_queue[(q ^ 1u) * params.pool_size + slot] = path;
        path_origin[path] = vec4(r.next_state.origin, r.next_state.prev_pdf);
        path_direction[path] = vec4(r.next_state.direction, 0.0);
        path_throughput[path] = vec4(r.next_state.throughput, 0.0);
    }
}
