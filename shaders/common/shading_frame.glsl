// The one place where the shading normal is reconciled with the geometric
// normal (twin: src/cpu/shading_frame.rs, which explains the method).
#ifndef SHADING_FRAME_GLSL
#define SHADING_FRAME_GLSL

#include "bsdf.glsl"

vec3 interpolate_normal(vec3 n0, vec3 n1, vec3 n2, vec2 b12, vec3 ng) {
    vec3 n = (1.0 - b12.x - b12.y) * n0 + b12.x * n1 + b12.y * n2;
    float len = length(n);
    return len > 1e-12 ? n / len : ng;
}

// ng: unit geometric normal on wo's side; ns: shading normal on that side.
vec3 reconcile_shading_normal(vec3 ng, vec3 ns, vec3 wo) {
    if (dot(ns, ng) <= 0.0) return ng;
    vec3 r = reflect_about(wo, ns);
    float height = dot(r, ng);
    if (height >= SHADING_NORMAL_MIN_COS) return ns;
    vec3 tangent = r - height * ng;
    float len = length(tangent);
    if (len <= 1e-12) return ng;
    float c = SHADING_NORMAL_MIN_COS;
    vec3 lifted = tangent * (sqrt(1.0 - c * c) / len) + c * ng;
    vec3 h = wo + lifted;
    float hl = length(h);
    return hl <= 1e-12 ? ng : h / hl;
}

bool same_side(vec3 ng, vec3 ns, vec3 w) {
    return dot(w, ng) * dot(w, ns) > 0.0;
}

#endif
