// Surface scattering (twin: src/cpu/bsdf.rs).
//
// Conventions, for every function here:
// - Directions point away from the surface: `wo` toward where the path came
//   from (the camera side), `wi` toward where it goes next (toward the light).
// - `n` is the unit geometric normal on the side of `wo`; `front` says
//   whether that is the front side (the side the triangle's normal points
//   to, which for a closed dielectric is the outside).
// - `bsdf_eval` returns f * |cos theta_i|; `bsdf_pdf` the solid-angle pdf of
//   `bsdf_sample` choosing wi; `bsdf_sample` returns wi, the weight
//   f * |cos theta_i| / pdf, the pdf, and `delta`.
// - Delta lobes (mirror, smooth dielectric) have no density: eval and pdf
//   are 0 for them, and a sample from one has `delta` set and pdf 0. Next-event
//   estimation skips delta-only materials; the integrator treats a delta
//   bounce like the camera ray (prev_pdf = 0: emission found next gets
//   weight 1).
// - We transport radiance: a refraction from index n_o (wo's side) into n_i
//   (wi's side), eta = n_i / n_o, scales the weight by 1 / eta^2.
// Lambert is unchanged from the original lambert_* functions, which
// bsdf_* call for MATERIAL_LAMBERT (same random numbers, same results).
#ifndef BSDF_GLSL
#define BSDF_GLSL

#include "sampling.glsl"

struct BsdfSample {
    vec3 wi;
    vec3 weight;
    float pdf;
    bool delta;
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
    s.delta = false;
    return s;
}

vec3 reflect_about(vec3 wo, vec3 n) {
    return 2.0 * dot(n, wo) * n - wo;
}

// Exact unpolarized Fresnel reflectance of a smooth dielectric interface,
// light arriving from the side of index n_o at cos_i > 0 to the side of
// index n_t, eta = n_t / n_o. Returns 1 beyond the critical angle (total
// internal reflection); `cos_t` receives the refracted cosine.
float fresnel_dielectric(float cos_i, float eta, out float cos_t) {
    float sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) {
        cos_t = 0.0;
        return 1.0;
    }
    cos_t = sqrt(1.0 - sin2_t);
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Phong: probability of sampling the specular lobe (lobes by their weights).
float phong_specular_prob(MaterialData m) {
    float d = m.base_color.r + m.base_color.g + m.base_color.b;
    float s = m.specular.r + m.specular.g + m.specular.b;
    return d + s > 0.0 ? s / (d + s) : 0.0;
}

// Normalized cos^n lobe around the mirror direction r over the sphere.
float phong_lobe_pdf(float shininess, float cos_alpha) {
    return cos_alpha > 0.0 ? (shininess + 1.0) * (0.5 * INV_PI) * pow(cos_alpha, shininess) : 0.0;
}

vec3 sample_phong_lobe(vec3 r, float shininess, vec2 u) {
    float c = pow(u.x, 1.0 / (shininess + 1.0));
    float s = sqrt(max(0.0, 1.0 - c * c));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    build_onb(r, t, b);
    return normalize(s * cos(phi) * t + s * sin(phi) * b + c * r);
}

vec3 phong_eval(MaterialData m, vec3 n, vec3 wo, vec3 wi) {
    float cos_i = dot(n, wi);
    if (cos_i <= 0.0) return vec3(0.0);
    float cos_alpha = dot(reflect_about(wo, n), wi);
    float lobe = cos_alpha > 0.0 ? (m.shininess + 2.0) * (0.5 * INV_PI) * pow(cos_alpha, m.shininess) : 0.0;
    return (m.base_color * INV_PI + m.specular * lobe) * cos_i;
}

float phong_pdf(MaterialData m, vec3 n, vec3 wo, vec3 wi) {
    float ps = phong_specular_prob(m);
    float cos_alpha = dot(reflect_about(wo, n), wi);
    return (1.0 - ps) * cosine_hemisphere_pdf(dot(n, wi)) + ps * phong_lobe_pdf(m.shininess, cos_alpha);
}

bool bsdf_is_delta(MaterialData m) {
    return m.kind == MATERIAL_MIRROR || m.kind == MATERIAL_DIELECTRIC;
}

vec3 bsdf_eval(MaterialData m, vec3 n, bool front, vec3 wo, vec3 wi) {
    if (m.kind == MATERIAL_LAMBERT) return lambert_eval(m.base_color, n, wi);
    if (m.kind == MATERIAL_PHONG) return phong_eval(m, n, wo, wi);
    return vec3(0.0);
}

float bsdf_pdf(MaterialData m, vec3 n, bool front, vec3 wo, vec3 wi) {
    if (m.kind == MATERIAL_LAMBERT) return lambert_pdf(n, wi);
    if (m.kind == MATERIAL_PHONG) return phong_pdf(m, n, wo, wi);
    return 0.0;
}

BsdfSample bsdf_sample(MaterialData m, vec3 n, bool front, vec3 wo, float u_lobe, vec2 u) {
    if (m.kind == MATERIAL_LAMBERT) return lambert_sample(m.base_color, n, u);
    BsdfSample s;
    s.weight = vec3(0.0);
    s.pdf = 0.0;
    s.delta = false;
    if (m.kind == MATERIAL_PHONG) {
        if (u_lobe < phong_specular_prob(m)) {
            s.wi = sample_phong_lobe(reflect_about(wo, n), m.shininess, u);
        } else {
            s.wi = lambert_sample(m.base_color, n, u).wi;
        }
        s.pdf = phong_pdf(m, n, wo, s.wi);
        if (s.pdf > 0.0) s.weight = phong_eval(m, n, wo, s.wi) / s.pdf;
        return s;
    }
    s.delta = true;
    if (m.kind == MATERIAL_MIRROR) {
        s.wi = reflect_about(wo, n);
        s.weight = m.base_color;
        return s;
    }
    // MATERIAL_DIELECTRIC: reflect with probability F, else refract.
    float eta = front ? m.ior : 1.0 / m.ior;
    float cos_i = dot(n, wo);
    float cos_t;
    float f = fresnel_dielectric(cos_i, eta, cos_t);
    if (u_lobe < f) {
        s.wi = reflect_about(wo, n);
        s.weight = vec3(1.0);
    } else {
        s.wi = normalize(-wo / eta + (cos_i / eta - cos_t) * n);
        s.weight = m.base_color / (eta * eta);
    }
    return s;
}

#endif
