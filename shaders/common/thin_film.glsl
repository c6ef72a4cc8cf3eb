// KHR_materials_iridescence: the thin-film interference Fresnel of Belcour
// & Barla 2017 in RGB, as the extension's specification evaluates it (twin:
// src/cpu/common/thin_film.rs, which explains the model and how it replaces the
// specular Fresnel of the glTF model). Included by bsdf.glsl.
#ifndef THIN_FILM_GLSL
#define THIN_FILM_GLSL

#include "loop_count.glsl"

#include "features.glsl"
#include "sampling.glsl"

bool gltf_iridescent(MaterialData m, float eta) {
    return FEATURE_IRIDESCENCE && (m.lobes & LOBE_IRIDESCENCE) != 0u
        && m.iridescence_thickness_max > 0.0 && eta >= 1.0;
}

float film_gauss(float v, float p, float s, float sh, float phase, float p2) {
    return v * sqrt(2.0 * PI * s) * cos(p * phase + sh) * exp(-p2 * s);
}

vec3 eval_sensitivity(float opd, vec3 shift) {
    float phase = 2.0 * PI * opd * 1.0e-9;
    float p2 = phase * phase;
    float x = film_gauss(5.4856e-13, 1.6810e+06, 4.3278e+09, shift.x, phase, p2)
        + film_gauss(9.7470e-14, 2.2399e+06, 4.5282e+09, shift.x, phase, p2);
    float y = film_gauss(4.4201e-13, 1.7953e+06, 9.3046e+09, shift.y, phase, p2);
    float z = film_gauss(5.2481e-13, 2.2084e+06, 6.6121e+09, shift.z, phase, p2);
    x = x / 1.0685e-7;
    y = y / 1.0685e-7;
    z = z / 1.0685e-7;
    return vec3(3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
                -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
                0.0556434 * x - 0.2040259 * y + 1.0572252 * z);
}

float film_schlick(float f0, float c) {
    float x = clamp(1.0 - c, 0.0, 1.0);
    float x2 = x * x;
    return f0 + (1.0 - f0) * (x2 * x2 * x);
}

float film_ior_to_f0(float t, float i) {
    float q = (t - i) / (t + i);
    return q * q;
}

vec3 thin_film_fresnel(float film_ior, float cos1, float thickness, vec3 base_f0) {
    float outside = 1.0;
    float t = clamp(thickness / 0.03, 0.0, 1.0);
    float eta2 = outside + (film_ior - outside) * (t * t * (3.0 - 2.0 * t));
    float sin2_sq = (outside / eta2) * (outside / eta2) * (1.0 - cos1 * cos1);
    float cos2_sq = 1.0 - sin2_sq;
    if (cos2_sq < 0.0) return vec3(1.0);
    float cos2 = sqrt(cos2_sq);
    float r12 = film_schlick(film_ior_to_f0(eta2, outside), cos1);
    float t121 = 1.0 - r12;
    float phi12 = eta2 < outside ? PI : 0.0;
    float phi21 = PI - phi12;
    float opd = 2.0 * eta2 * thickness * cos2;
    vec3 i, r123, phi, cm;
    for (int ch = 0; ch < 3; ch++) {
        COUNT_LOOP_ITERATION();
        float sf0 = sqrt(clamp(base_f0[ch], 0.0, 0.9999));
        float base_ior = (1.0 + sf0) / (1.0 - sf0);
        float r23 = film_schlick(film_ior_to_f0(base_ior, eta2), cos2);
        float phi23 = base_ior < eta2 ? PI : 0.0;
        r123[ch] = clamp(r12 * r23, 1e-5, 0.9999);
        float rs = t121 * t121 * r23 / (1.0 - r123[ch]);
        i[ch] = r12 + rs;
        cm[ch] = rs - t121;
        phi[ch] = phi21 + phi23;
    }
    vec3 r123_sqrt = sqrt(r123);
    for (int m = 1; m <= 2; m++) {
        COUNT_LOOP_ITERATION();
        float mf = float(m);
        cm *= r123_sqrt;
        i += cm * (2.0 * eval_sensitivity(mf * opd, mf * phi));
    }
    return clamp(i, vec3(0.0), vec3(1.0));
}

vec3 iridescent_dielectric_f0(MaterialData m, float eta) {
    float q = (eta - 1.0) / (eta + 1.0);
    return min(q * q * m.specular_color, vec3(1.0));
}

void iridescent_reflection(MaterialData m, float c, float eta, inout vec3 metal, inout vec3 dielectric) {
    if (!gltf_iridescent(m, eta)) return;
    float d = m.iridescence_thickness_max;
    vec3 fm = thin_film_fresnel(m.iridescence_ior, c, d, m.base_color);
    vec3 fd = thin_film_fresnel(m.iridescence_ior, c, d, iridescent_dielectric_f0(m, eta));
    float k = m.iridescence;
    metal = metal + (fm - metal) * k;
    dielectric = dielectric + (m.specular_factor * fd - dielectric) * k;
}

float iridescent_base_weight(MaterialData m, float c, float eta, float w) {
    if (!gltf_iridescent(m, eta)) return w;
    float d = m.iridescence_thickness_max;
    vec3 fd = thin_film_fresnel(m.iridescence_ior, c, d, iridescent_dielectric_f0(m, eta));
    return w + (1.0 - m.specular_factor * max(fd.r, max(fd.g, fd.b)) - w) * m.iridescence;
}

#endif
