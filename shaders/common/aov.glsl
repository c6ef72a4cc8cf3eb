// Auxiliary outputs (AOVs) of one path sample (twin: src/cpu/common/aov.rs), for
// denoisers and compositing: the depth of the camera ray's hit, and the
// albedo and shading normal of the first surface that is not a mirror or
// smooth glass (through delta bounces the path is followed to the first
// rough surface, as Open Image Denoise asks). A path that escapes on that
// chain sees the environment: albedo its radiance (at most 1), normal 0.
// Depth is the distance along the camera ray, +inf when it meets nothing.
#ifndef AOV_GLSL
#define AOV_GLSL

#include "integrator.glsl"

struct AovSample {
    vec3 albedo;
    float depth;
    vec3 normal;
    bool open;      // no surface has ended the delta chain yet
};

// Updates `a` after shading `hit` at `bounce` (r: shade_path's result).
// Returns whether `a` changed. At bounce 0 it starts over, so `a` may hold
// anything then.
bool aov_after_bounce(inout AovSample a, uint bounce, Hit hit, ShadeResult r) {
    bool changed = false;
    if (bounce == 0u) {
        bool missed = hit.triangle == NO_HIT || hit.triangle == OVERFLOW_HIT;
        a.depth = missed ? uintBitsToFloat(0x7F800000u) : hit.t;
        a.albedo = vec3(0.0);
        a.normal = vec3(0.0);
        a.open = true;
        changed = true;
    }
    if (a.open && r.aov_event) {
        a.albedo = r.aov_albedo;
        a.normal = r.aov_normal;
        a.open = false;
        changed = true;
    }
    return changed;
}

// The two vec4 a path's AOVs are stored as (path_state.glsl).
AovSample aov_unpack(vec4 a, vec4 b) {
    AovSample s;
    s.albedo = a.xyz;
    s.depth = a.w;
    s.normal = b.xyz;
    s.open = b.w != 0.0;
    return s;
}

void aov_pack(AovSample s, out vec4 a, out vec4 b) {
    a = vec4(s.albedo, s.depth);
    b = vec4(s.normal, s.open ? 1.0 : 0.0);
}

#endif
