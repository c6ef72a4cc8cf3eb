#version 460
#extension GL_GOOGLE_include_directive : require
// generate: camera rays for one chunk of pixel-samples.
// reads: params, push constants (chunk); writes: path state, ray queue 0, counters.
#include "bindings.glsl"
#include "camera.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i == 0u) {
        counters[COUNTER_RAYS_0] = pc.count;
        counters[COUNTER_RAYS_1] = 0u;
        counters[COUNTER_SHADOW] = 0u;
    }
    if (i >= pc.count) return;
    uint pixels = params.width * params.height;
    uint pixel = (pc.pixel_start + i) % pixels;
    uint sample_index = pc.sample_start + (pc.pixel_start + i) / pixels;
    RngKey key = rng_sampler_key(params.rng_sampler, pixel, sample_index, params.seed);
    vec3 o, d;
    generate_camera_ray(params, pixel, key, o, d);
    path_origin[i] = vec4(o, 0.0);
    path_direction[i] = vec4(d, 0.0);
    path_throughput[i] = vec4(1.0);
    path_radiance[i] = vec4(0.0);
    ray_queue[i] = i;
}
