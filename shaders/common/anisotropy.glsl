// KHR_materials_anisotropy: the anisotropic GGX distribution (twin:
// src/cpu/common/anisotropy.rs, which names the sources). Local frame: +x the
// anisotropy direction (ShadingFrame.t), +z the shading normal; alpha =
// (alpha_t, alpha_b). The mf_* functions are what the glTF lobes call: an
// isotropic alpha (x == y) goes to microfacet.glsl's functions unchanged.
#ifndef ANISOTROPY_GLSL
#define ANISOTROPY_GLSL

#include "features.glsl"
#include "sampling.glsl"
#include "microfacet.glsl"

bool anisotropy_active(MaterialData m) {
    return FEATURE_ANISOTROPY && (m.lobes & LOBE_ANISOTROPY) != 0u;
}

// (alpha_t, alpha_b) from alpha = roughness^2: alpha_t = mix(alpha, 1,
// strength^2), alpha_b = alpha, kept at least GGX_SMOOTH_ALPHA where
// alpha_t makes the lobe rough.
vec2 anisotropy_alpha(MaterialData m, float alpha) {
    if (!anisotropy_active(m)) return vec2(alpha);
    float s = clamp(m.anisotropy_strength, 0.0, 1.0);
    float at = alpha + (1.0 - alpha) * (s * s);
    if (!(s > 0.0) || at < GGX_SMOOTH_ALPHA) return vec2(alpha);
    return vec2(at, max(alpha, GGX_SMOOTH_ALPHA));
}

float ggx_d_aniso(vec3 h, vec2 a) {
    if (h.z <= 0.0) return 0.0;
    float x = h.x / a.x;
    float y = h.y / a.y;
    float d = x * x + y * y + h.z * h.z;
    return INV_PI / (a.x * a.y * d * d);
}

float ggx_lambda_aniso(vec3 w, vec2 a) {
    float z2 = max(w.z * w.z, 1e-20);
    float t2 = (a.x * a.x * w.x * w.x + a.y * a.y * w.y * w.y) / z2;
    return 0.5 * (sqrt(1.0 + t2) - 1.0);
}

float ggx_g1_aniso(vec3 w, vec2 a) {
    return 1.0 / (1.0 + ggx_lambda_aniso(w, a));
}

float mf_d(vec3 h, vec2 a) {
    if (FEATURE_ANISOTROPY && a.x != a.y) return ggx_d_aniso(h, a);
    return ggx_d(h, a.x);
}

float mf_g2(vec3 wo, vec3 wi, vec2 a) {
    if (FEATURE_ANISOTROPY && a.x != a.y) return 1.0 / (1.0 + ggx_lambda_aniso(wo, a) + ggx_lambda_aniso(wi, a));
    return ggx_g2(wo, wi, a.x);
}

float mf_vndf_pdf(vec3 wo, vec3 h, vec2 a) {
    if (FEATURE_ANISOTROPY && a.x != a.y) {
        float woh = dot(wo, h);
        if (wo.z <= 0.0 || woh <= 0.0) return 0.0;
        return ggx_g1_aniso(wo, a) * woh * ggx_d_aniso(h, a) / wo.z;
    }
    return ggx_vndf_pdf(wo, h, a.x);
}

// One sampler for both: the isotropic one is a.x == a.y.
vec3 mf_sample_vndf(vec3 wo, vec2 a, vec2 u) {
    return sample_ggx_vndf_aniso(wo, a, u);
}

#endif
