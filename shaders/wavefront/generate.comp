#version 460
#extension GL_GOOGLE_include_directive : require
// generate: camera rays for one chunk of pixel-samples.
// reads: params, push constants (chunk); writes: path state, ray queue 0, counters.
#include "bindings.glsl"
#include "camera.glsl"
#include "path_state.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i == 0u) {
        counters[COUNTER_RAYS_0] = pc.count;
        counters[COUNTER_RAYS_1] = 0u;
        counters[COUNTER_SHADOW] = 0u;
    }
    if (i >= pc.count) return;
    PathSample s = path_pixel_sample(params, pc.pixel_start, pc.sample_start, i);
    RngKey key = rng_sampler_key(params.rng_sampler, s.pixel, s.sample_index, params.seed);
    vec3 o, d;
    generate_camera_ray(params, s.pixel, key, o, d);
    write_path_origin(i, o, 0.0);
    write_path_direction(i, d, 0u, 0u);
    write_path_throughput(i, vec3(1.0), 1.0);
    write_path_radiance(i, vec3(0.0), 0u);
    ray_queue[i] = i;
}
