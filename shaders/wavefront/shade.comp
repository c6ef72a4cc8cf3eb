#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
// shade: emission, light sample, BSDF sample and Russian roulette for every
// ray in this bounce's queue (shade_path in integrator.glsl), or, with
// shading split by material, for the hits of one shading queue (SHADE_QUEUE:
// the basic one from the start of shade_queue, the full one from its end).
// reads: ray queue (bounce parity) or shading queue, path state and hit, scene;
// writes: path state, path radiance, next ray queue, shadow queue.
// The path's bounce index is its own (path_radiance's w), not the round's:
// paths parked by the per-path loop join at any bounce.
#include "bindings.glsl"
#include "integrator.glsl"
#include "queues.glsl"
#include "path_state.glsl"
#include "aov.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void main() {
    uint k = gl_GlobalInvocationID.x;
    uint q = pc.bounce & 1u;
    uint path;
    if (SHADE_QUEUE == SHADE_QUEUE_BASIC) {
        if (k >= counters[COUNTER_SHADE_BASIC]) return;
        path = shade_queue[k];
    } else if (SHADE_QUEUE == SHADE_QUEUE_FULL) {
        if (k >= counters[COUNTER_SHADE_FULL]) return;
        path = shade_queue[params.pool_size - 1u - k];
    } else {
        if (k >= counters[COUNTER_RAYS_0 + q]) return;
        path = ray_queue[q * params.pool_size + k];
    }
    uvec4 radiance = read_path_radiance_bounce(path);
    uint bounce = radiance.w;

    RngKey key = path_rng_key(path);

    PathState s;
    vec4 o = read_path_origin(path);
    s.origin = o.xyz;
    s.prev_pdf = o.w;
    s.direction = read_path_direction(path);
    vec4 throughput = read_path_throughput(path);
    s.throughput = throughput.xyz;
    s.eta_scale = throughput.w;
    s.dispersion_channel = FEATURE_DISPERSION ? read_path_dispersion_channel(path) : 0u;
    s.prev_normal = FEATURE_LIGHT_TREE ? read_path_prev_normal(path) : 0u;
    uvec4 h = read_path_hit(path);
    Hit hit;
    hit.t = uintBitsToFloat(h.x);
    hit.triangle = h.y;
    hit.b12 = uintBitsToFloat(h.zw);

    ShadeResult r = shade_path(s, hit, key, bounce);
    if (FEATURE_AOV && params.aov != 0u && (bounce == 0u || r.aov_event)) {
        AovSample a;
        if (bounce > 0u) a = aov_unpack(read_path_aov(path, 0u), read_path_aov(path, 1u));
        if (aov_after_bounce(a, bounce, hit, r)) {
            vec4 a0, a1;
            aov_pack(a, a0, a1);
            write_path_aov(path, a0, a1);
        }
    }
    write_path_radiance(path, uintBitsToFloat(radiance.xyz) + r.emitted, bounce + 1u);
    if (r.shadow) {
        uint slot = queue_push(COUNTER_SHADOW);
        write_shadow_ray(slot, r.shadow_origin, r.shadow_t_max, r.shadow_direction, path,
                         r.shadow_contribution, bounce);
    }
    if (r.next) {
        uint slot = queue_push(COUNTER_RAYS_0 + (q ^ 1u));
        ray_queue[(q ^ 1u) * params.pool_size + slot] = path;
        write_path_origin(path, r.next_state.origin, r.next_state.prev_pdf);
        write_path_direction(path, r.next_state.direction, r.next_state.dispersion_channel,
                             r.next_state.prev_normal);
        write_path_throughput(path, r.next_state.throughput, r.next_state.eta_scale);
    }
}
