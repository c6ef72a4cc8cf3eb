// Motion over the shutter (twin: src/cpu/common/motion.rs; representation and
// buffer layout: src/scene/motion.rs, src/packed/motion.rs). Every path has
// its own time, a fraction of the shutter (path_time), and sees the camera and the triangles where they are
// then: linear between the two time steps around it. Still scenes compile
// all of it out (FEATURE_MOTION) or skip it (motion_steps 0).
#ifndef MOTION_GLSL
#define MOTION_GLSL

#include "features.glsl"
#include "rng.glsl"

bool motion_on() {
    return FEATURE_MOTION && params.motion_steps > 1u;
}

// The path's moment in the shutter, in [0, 1). Under Sobol, the third
// coordinate of the pixel jitter's point: a moving edge is an integrand of
// position and time together, which then are stratified jointly.
float path_time(RngKey key) {
    if (FEATURE_SOBOL && key.kind == SAMPLER_SOBOL) return sobol_float2_third(key, DIM_CAMERA_JITTER);
    return rng_float(key, DIM_CAMERA_TIME);
}

// The time steps around `time`: step k and k + 1, at weight w of the way.
struct MotionSegment {
    uint step;
    float w;
};

MotionSegment motion_segment(float time) {
    float f = time * float(params.motion_steps - 1u);
    MotionSegment s;
    s.step = min(uint(f), params.motion_steps - 2u);
    s.w = f - float(s.step);
    return s;
}

// precise: no fused multiply-add, as on the CPU (scene/motion.rs's
// motion_lerp).
vec3 motion_lerp(vec3 a, vec3 b, float w) {
    precise vec3 d = b - a;
    precise vec3 r = a + d * w;
    return r;
}

vec4 motion_lerp4(vec4 a, vec4 b, float w) {
    precise vec4 d = b - a;
    precise vec4 r = a + d * w;
    return r;
}

vec3 motion_texel(uint i) {
    return uintBitsToFloat(texelFetch(motion_texels, int(i)).xyz);
}

vec4 motion_texel4(uint i) {
    return uintBitsToFloat(texelFetch(motion_texels, int(i)));
}

// Three consecutive vec3 records (a triangle's vertices, normals) of the
// section starting at `section`, at `time`.
void motion_triangle_record(uint section, uint tri, float time, out vec3 a, out vec3 b, out vec3 c) {
    MotionSegment s = motion_segment(time);
    uint t = params.num_triangles;
    uint i = section + 3u * (s.step * t + tri);
    uint j = i + 3u * t;
    a = motion_lerp(motion_texel(i), motion_texel(j), s.w);
    b = motion_lerp(motion_texel(i + 1u), motion_texel(j + 1u), s.w);
    c = motion_lerp(motion_texel(i + 2u), motion_texel(j + 2u), s.w);
}

// The triangle's vertices at `time`.
void moving_triangle(uint tri, float time, out vec3 v0, out vec3 v1, out vec3 v2) {
    motion_triangle_record(params.motion_vertex_base, tri, time, v0, v1, v2);
}

// Its vertex normals at `time` (interpolate_normal normalizes their blend).
void moving_triangle_normals(uint tri, float time, out vec3 n0, out vec3 n1, out vec3 n2) {
    uint section = params.motion_vertex_base + 3u * params.motion_steps * params.num_triangles;
    motion_triangle_record(section, tri, time, n0, n1, n2);
}

// Its vertex tangents (xyz, bitangent sign w) at `time`: textured scenes only.
void moving_triangle_tangents(uint tri, float time, out vec4 t0, out vec4 t1, out vec4 t2) {
    MotionSegment s = motion_segment(time);
    uint t = params.num_triangles;
    uint section = params.motion_vertex_base + 6u * params.motion_steps * t;
    uint i = section + 3u * (s.step * t + tri);
    uint j = i + 3u * t;
    t0 = motion_lerp4(motion_texel4(i), motion_texel4(j), s.w);
    t1 = motion_lerp4(motion_texel4(i + 1u), motion_texel4(j + 1u), s.w);
    t2 = motion_lerp4(motion_texel4(i + 2u), motion_texel4(j + 2u), s.w);
}

// The render camera's frame at `time`: position linear, axes normalized
// after linear interpolation.
void moving_camera(float time, out vec3 position, out vec3 right, out vec3 up, out vec3 forward) {
    MotionSegment s = motion_segment(time);
    uint i = params.motion_camera_base + 4u * s.step;
    position = motion_lerp(motion_texel(i), motion_texel(i + 4u), s.w);
    right = normalize(motion_lerp(motion_texel(i + 1u), motion_texel(i + 5u), s.w));
    up = normalize(motion_lerp(motion_texel(i + 2u), motion_texel(i + 6u), s.w));
    forward = normalize(motion_lerp(motion_texel(i + 3u), motion_texel(i + 7u), s.w));
}

#endif
