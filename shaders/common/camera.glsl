// Primary rays (twin: src/cpu/camera.rs). A pinhole with a box pixel filter:
// each sample lands uniformly inside its pixel.
#ifndef CAMERA_GLSL
#define CAMERA_GLSL

#include "types.glsl"
#include "rng.glsl"

void generate_camera_ray(RenderParams p, uint pixel, RngKey key, out vec3 origin, out vec3 direction) {
    vec2 u = rng_float2(key, DIM_CAMERA_JITTER);
    float x = float(pixel % p.width) + u.x;
    float y = float(pixel / p.width) + u.y;
    float sx = 2.0 * x / float(p.width) - 1.0;
    float sy = 1.0 - 2.0 * y / float(p.height);
    origin = p.cam_position;
    direction = normalize(p.cam_forward + (sx * p.tan_half_fov * p.aspect) * p.cam_right
                          + (sy * p.tan_half_fov) * p.cam_up);
}

#endif
