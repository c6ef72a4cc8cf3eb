// KHR_materials_sheen: the Charlie microfiber lobe (Estevez & Kulla 2017)
// with their fitted visibility, and its directional-albedo table (twin:
// src/cpu/common/sheen.rs, which explains both). The table is the binding
// sheen_albedo_table, uploaded from src/packed/sheen_table.rs: both back ends
// read the same bits. (A GLSL const array indexed at run time was tried
// first: lavapipe ran the furnace test for over 25 minutes without ending.)
#ifndef SHEEN_GLSL
#define SHEEN_GLSL

#include "sampling.glsl"

float sheen_alpha(float r) {
    r = max(r, SHEEN_MIN_ROUGHNESS);
    return r * r;
}

float charlie_d(float cos_h, float alpha) {
    float inv = 1.0 / alpha;
    float sin2 = max(1.0 - cos_h * cos_h, 0.0);
    return (2.0 + inv) * pow(sin2, 0.5 * inv) * (0.5 * INV_PI);
}

float sheen_lerp(float a, float b, float w) {
    return a + (b - a) * w;
}

float sheen_l(float x, float alpha) {
    float w = (1.0 - alpha) * (1.0 - alpha);
    float a = sheen_lerp(21.5473, 25.3245, w);
    float b = sheen_lerp(3.82987, 3.32435, w);
    float c = sheen_lerp(0.19823, 0.16801, w);
    float d = sheen_lerp(-1.97760, -1.27393, w);
    float e = sheen_lerp(-4.32054, -4.85967, w);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

float sheen_lambda(float c, float alpha) {
    if (c < 0.5) return exp(sheen_l(c, alpha));
    return exp(2.0 * sheen_l(0.5, alpha) - sheen_l(1.0 - c, alpha));
}

// f_sheen * cos(theta_i) for a white sheen colour (local frame).
float sheen_eval_white(float roughness, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
    float alpha = sheen_alpha(roughness);
    vec3 h = normalize(wo + wi);
    float g = 1.0 + sheen_lambda(wo.z, alpha) + sheen_lambda(wi.z, alpha);
    return charlie_d(h.z, alpha) / (4.0 * wo.z * g);
}

float sheen_albedo(float mu, float r) {
    float last = float(SHEEN_TABLE_SIZE - 1u);
    float x = sqrt(clamp(mu, 0.0, 1.0)) * last;
    float y = clamp(r, 0.0, 1.0) * last;
    uint i = min(uint(x), SHEEN_TABLE_SIZE - 2u);
    uint j = min(uint(y), SHEEN_TABLE_SIZE - 2u);
    float fx = x - float(i);
    float fy = y - float(j);
    uint k = j * SHEEN_TABLE_SIZE + i;
    float lo = sheen_albedo_table[k] * (1.0 - fx) + sheen_albedo_table[k + 1u] * fx;
    float hi = sheen_albedo_table[k + SHEEN_TABLE_SIZE] * (1.0 - fx) + sheen_albedo_table[k + SHEEN_TABLE_SIZE + 1u] * fx;
    return lo * (1.0 - fy) + hi * fy;
}

float sheen_energy(float mu, float r) {
    return min(sheen_albedo(mu, r), 1.0);
}

#endif
