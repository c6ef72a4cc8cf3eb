// Surface scattering (twin: src/cpu/bsdf.rs). Conventions: directions point
// away from the surface; `n` is the unit normal on the side of `wo`;
// `bsdf_eval` returns f * |cos theta_i|; `bsdf_sample` returns the weight
// f * |cos theta_i| / pdf and the solid-angle pdf.
#ifndef BSDF_GLSL
#define BSDF_GLSL

#include "sampling.glsl"

struct BsdfSample {
    vec3 wi;
    vec3 weight;
    float pdf;
};

vec3 lambert_eval(vec3 albedo, vec3 n, vec3 wi) {
    return albedo * (INV_PI * max(dot(n, wi), 0.0));
}

float lambert_pdf(vec3 n, vec3 wi) {
    return cosine_hemisphere_pdf(dot(n, wi));
}

BsdfSample lambert_sample(vec3 albedo, vec3 n, vec2 u) {
    vec3 t, b;
    build_onb(n, t, b);
    vec3 l = sample_cosine_hemisphere(u);
    BsdfSample s;
    s.wi = normalize(l.x * t + l.y * b + l.z * n);
    s.pdf = cosine_hemisphere_pdf(l.z);
    s.weight = s.pdf > 0.0 ? albedo : vec3(0.0);
    return s;
}

#endif
