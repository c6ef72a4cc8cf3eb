// The isotropic GGX (Trowbridge-Reitz) microfacet distribution in a local
// frame whose +z is the shading normal (twin: src/cpu/common/microfacet.rs, which
// names the sources). `alpha` is the perceptual roughness squared.
#ifndef MICROFACET_GLSL
#define MICROFACET_GLSL

#include "sampling.glsl"

float ggx_d(vec3 h, float alpha) {
    if (h.z <= 0.0) return 0.0;
    float a2 = alpha * alpha;
    float d = h.z * h.z * (a2 - 1.0) + 1.0;
    return a2 * INV_PI / (d * d);
}

// Smith lambda: (-1 + sqrt(1 + alpha^2 tan^2 theta)) / 2.
float ggx_lambda(vec3 w, float alpha) {
    float z2 = max(w.z * w.z, 1e-20);
    float tan2 = max(1.0 - z2, 0.0) / z2;
    return 0.5 * (sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

float ggx_g1(vec3 w, float alpha) {
    return 1.0 / (1.0 + ggx_lambda(w, alpha));
}

// Height-correlated masking-shadowing.
float ggx_g2(vec3 wo, vec3 wi, float alpha) {
    return 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

// Visible-normal sampling (Heitz 2018), wo.z > 0, for roughness a = (αx,
// αy): stretch to the hemisphere configuration, sample the projected disk,
// unstretch. The isotropic distribution is a.x == a.y.
vec3 sample_ggx_vndf_aniso(vec3 wo, vec2 a, vec2 u) {
    vec3 vh = normalize(vec3(a.x * wo.x, a.y * wo.y, wo.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = len2 > 0.0 ? vec3(-vh.y, vh.x, 0.0) / sqrt(len2) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float s = 0.5 * (1.0 + vh.z);
    float p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    return normalize(vec3(a.x * nh.x, a.y * nh.y, max(nh.z, 0.0)));
}

vec3 sample_ggx_vndf(vec3 wo, float alpha, vec2 u) {
    return sample_ggx_vndf_aniso(wo, vec2(alpha), u);
}

float ggx_vndf_pdf(vec3 wo, vec3 h, float alpha) {
    float woh = dot(wo, h);
    if (wo.z <= 0.0 || woh <= 0.0) return 0.0;
    return ggx_g1(wo, alpha) * woh * ggx_d(h, alpha) / wo.z;
}

#endif
