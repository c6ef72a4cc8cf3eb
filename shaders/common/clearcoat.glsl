// KHR_materials_clearcoat: a dielectric GGX coat (IOR 1.5, its own
// roughness and normal) over the glTF material (twin: src/cpu/common/clearcoat.rs,
// which explains the model). Every function takes the coat normal `nc`
// on wo's side (shading_frame.glsl builds it) and world directions.
#ifndef CLEARCOAT_GLSL
#define CLEARCOAT_GLSL

#include "features.glsl"
#include "sampling.glsl"
#include "microfacet.glsl"

bool clearcoat_active(MaterialData m) {
    return FEATURE_CLEARCOAT && (m.lobes & LOBE_CLEARCOAT) != 0u && m.clearcoat > 0.0;
}

float clearcoat_alpha(MaterialData m) {
    return m.clearcoat_roughness * m.clearcoat_roughness;
}

// A coat whose lobe has a density (not a delta).
bool clearcoat_rough(MaterialData m) {
    return clearcoat_active(m) && clearcoat_alpha(m) >= GGX_SMOOTH_ALPHA;
}

// The spec's blend factor clearcoat * Schlick(F0, cos(wo, nc)); also the
// probability of sampling the coat.
float clearcoat_blend(MaterialData m, float co) {
    float x = clamp(1.0 - co, 0.0, 1.0);
    float x2 = x * x;
    return clamp(m.clearcoat, 0.0, 1.0) * (CLEARCOAT_F0 + (1.0 - CLEARCOAT_F0) * (x2 * x2 * x));
}

vec3 clearcoat_local(vec3 w, vec3 nc) {
    vec3 t, b;
    build_onb(nc, t, b);
    return vec3(dot(w, t), dot(w, b), dot(w, nc));
}

// The coat lobe's f * cos, Fresnel left to the blend (local to nc).
float clearcoat_spec_local(float alpha, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0 || alpha < GGX_SMOOTH_ALPHA) return 0.0;
    vec3 h = normalize(wo + wi);
    return ggx_d(h, alpha) * ggx_g2(wo, wi, alpha) / (4.0 * wo.z);
}

float clearcoat_pdf_local(float alpha, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0 || alpha < GGX_SMOOTH_ALPHA) return 0.0;
    vec3 h = normalize(wo + wi);
    return ggx_vndf_pdf(wo, h, alpha) / (4.0 * dot(wo, h));
}

// The coated material's f * cos from the base's.
vec3 clearcoat_layer_eval(MaterialData m, vec3 nc, vec3 wo, vec3 wi, vec3 base) {
    float blend = clearcoat_blend(m, dot(wo, nc));
    float spec = clearcoat_spec_local(clearcoat_alpha(m), clearcoat_local(wo, nc), clearcoat_local(wi, nc));
    return base * (1.0 - blend) + vec3(blend * spec);
}

// The coated material's pdf from the base's (the coat is picked with
// probability blend).
float clearcoat_layer_pdf(MaterialData m, vec3 nc, vec3 wo, vec3 wi, float base_pdf) {
    float blend = clearcoat_blend(m, dot(wo, nc));
    float coat = clearcoat_pdf_local(clearcoat_alpha(m), clearcoat_local(wo, nc), clearcoat_local(wi, nc));
    return base_pdf * (1.0 - blend) + blend * coat;
}

// A direction from the coat lobe (world): the mirror image of wo about nc
// for a smooth coat (a delta), else about a visible GGX normal.
vec3 clearcoat_sample_wi(MaterialData m, vec3 nc, vec3 wo, vec2 u) {
    float alpha = clearcoat_alpha(m);
    if (alpha < GGX_SMOOTH_ALPHA) return 2.0 * dot(nc, wo) * nc - wo;
    vec3 t, b;
    build_onb(nc, t, b);
    vec3 wl = vec3(dot(wo, t), dot(wo, b), dot(wo, nc));
    vec3 h = sample_ggx_vndf(wl, alpha, u);
    vec3 r = 2.0 * dot(h, wl) * h - wl;
    return normalize(r.x * t + r.y * b + r.z * nc);
}

#endif
