// Surface scattering (twin: src/cpu/common/bsdf.rs).
//
// Conventions, for every function here:
// - Directions point away from the surface: `wo` toward where the path came
//   from (the camera side), `wi` toward where it goes next (toward the light).
// - `f` is the ShadingFrame: f.n the unit shading normal on the side of
//   `wo` (shading_frame.glsl; the integrator checks that wi lies on the same
//   side of the geometric and shading normals), f.t and f.b complete it
//   (build_onb(f.n) unless the material is anisotropic), f.coat_n the
//   clearcoat's normal on wo's side; `front` says whether wo is on the front side (the
//   side the triangle's normal points to, which for a closed volume is the
//   outside).
// - `bsdf_eval` returns f * |cos theta_i|; `bsdf_pdf` the solid-angle pdf of
//   `bsdf_sample` choosing wi; `bsdf_sample` returns wi, the weight
//   f * |cos theta_i| / pdf, the pdf, and `delta`.
// - Delta lobes (mirror; smooth reflection and transmission of MATERIAL_GLTF,
//   roughness^2 below GGX_SMOOTH_ALPHA) have no density: eval and pdf cover
//   only the other lobes, and a sample from one has `delta` set and pdf 0.
//   Next-event estimation skips delta-only materials; the integrator treats
//   a delta bounce like the camera ray (prev_pdf = 0: emission found next
//   gets weight 1).
// - MATERIAL_GLTF is glTF 2.0 appendix B: mix(dielectric, metal, metallic),
//   dielectric = fresnel_mix(base = mix(diffuse, transmission,
//   transmission), layer = GGX reflection), sampled by one-sample MIS over
//   its lobes (gltf_lobe_probs; bsdf_pdf is the mixture pdf).
// - We transport radiance: a refraction from index n_o (wo's side) into n_i
//   (wi's side), eta = n_i / n_o, scales the weight by 1 / eta^2.
#ifndef BSDF_GLSL
#define BSDF_GLSL

#include "features.glsl"
#include "sampling.glsl"
#include "microfacet.glsl"
#include "anisotropy.glsl"
#include "clearcoat.glsl"
#include "sheen.glsl"

// The frame the BSDF scatters in (see the header): n the shading normal,
// (t, b, n) right-handed, coat_n the clearcoat normal.
struct ShadingFrame {
    vec3 n;
    vec3 t;
    vec3 b;
    vec3 coat_n;
};

// The frame of a material that is neither anisotropic nor coated.
ShadingFrame frame_of_normal(vec3 n) {
    ShadingFrame f;
    f.n = n;
    build_onb(n, f.t, f.b);
    f.coat_n = n;
    return f;
}
// The lobes KHR_materials_sheen and KHR_materials_diffuse_transmission add
// to the glTF model below, composed around its lobes (gltf_base_*) in the
// local frame (see the twin, src/cpu/common/bsdf.rs, for the composition
// and the sampling). The base functions they call are declared here and
// defined below. Each lobe runs only under its specialization constant and
// the material's LOBE_* bit, so a material without them takes exactly the
// base's code path.
vec3 gltf_base_eval_local(MaterialData m, float eta, vec3 wo, vec3 wi);
float gltf_base_pdf_local(MaterialData m, float eta, vec3 wo, vec3 wi);
float gltf_base_weight(MaterialData m, float c, float eta);
vec3 gltf_reflection_color(MaterialData m, float c, float eta);

bool gltf_has_sheen(MaterialData m) {
    return FEATURE_SHEEN && (m.lobes & LOBE_SHEEN) != 0u;
}

bool gltf_has_diffuse_transmission(MaterialData m) {
    return FEATURE_DIFFUSE_TRANSMISSION && (m.lobes & LOBE_DIFFUSE_TRANSMISSION) != 0u;
}

bool gltf_has_layers(MaterialData m) {
    return gltf_has_sheen(m) || gltf_has_diffuse_transmission(m);
}

float gltf_diffuse_reflected(MaterialData m) {
    return gltf_has_diffuse_transmission(m) ? 1.0 - m.diffuse_transmission : 1.0;
}

float layer_mean(vec3 c) {
    return (c.x + c.y + c.z) / 3.0;
}

float sheen_scaling(MaterialData m, float co, float ci) {
    if (!gltf_has_sheen(m)) return 1.0;
    float s = max(m.sheen_color.r, max(m.sheen_color.g, m.sheen_color.b));
    float r = m.sheen_roughness;
    return min(1.0 - s * sheen_energy(co, r), 1.0 - s * sheen_energy(ci, r));
}

float diffuse_weight(MaterialData m, float c, float eta) {
    return (1.0 - m.metallic) * (1.0 - m.transmission) * gltf_base_weight(m, c, eta);
}

// (sheen, diffuse transmission) lobe probabilities; the base gets the rest.
vec2 gltf_layer_probs(MaterialData m, float co, float eta) {
    float sheen = gltf_has_sheen(m) ? layer_mean(m.sheen_color) * sheen_energy(co, m.sheen_roughness) : 0.0;
    float s = sheen_scaling(m, co, co);
    float dt = gltf_has_diffuse_transmission(m)
        ? s * diffuse_weight(m, co, eta) * m.diffuse_transmission * layer_mean(m.diffuse_transmission_color)
        : 0.0;
    float under = (1.0 - m.metallic) * gltf_base_weight(m, co, eta) * layer_mean(m.base_color);
    float base = s * (under * ((1.0 - m.transmission) * gltf_diffuse_reflected(m) + m.transmission)
                      + layer_mean(gltf_reflection_color(m, co, eta)));
    float sum = sheen + dt + base;
    return sum > 0.0 ? vec2(sheen / sum, dt / sum) : vec2(0.0);
}

vec3 gltf_eval_local(MaterialData m, float eta, vec3 wo, vec3 wi) {
    vec3 f = gltf_base_eval_local(m, eta, wo, wi);
    if (!gltf_has_layers(m) || wo.z <= 0.0) return f;
    if (gltf_has_diffuse_transmission(m) && wi.z < 0.0) {
        vec3 h = normalize(wo + vec3(wi.x, wi.y, -wi.z));
        float w = diffuse_weight(m, dot(wo, h), eta) * m.diffuse_transmission * INV_PI * -wi.z;
        f += m.diffuse_transmission_color * w;
    }
    if (gltf_has_sheen(m)) {
        f *= sheen_scaling(m, wo.z, abs(wi.z));
        if (wi.z > 0.0) {
            float r = m.sheen_roughness;
            f += m.sheen_color * (sheen_eval_white(r, wo, wi) / max(sheen_albedo(wo.z, r), 1.0));
        }
    }
    return f;
}

float gltf_pdf_local(MaterialData m, float eta, vec3 wo, vec3 wi) {
    float pdf = gltf_base_pdf_local(m, eta, wo, wi);
    if (!gltf_has_layers(m) || wo.z <= 0.0) return pdf;
    vec2 p = gltf_layer_probs(m, wo.z, eta);
    pdf *= 1.0 - p.x - p.y;
    if (wi.z > 0.0) {
        pdf += p.x * cosine_hemisphere_pdf(wi.z);
    } else if (wi.z < 0.0) {
        pdf += p.y * cosine_hemisphere_pdf(-wi.z);
    }
    return pdf;
}

// True with wi set when u_lobe picks a layer lobe; otherwise u_lobe is
// rescaled to [0, 1) for the base's own choice.
bool gltf_layer_sample(MaterialData m, float co, float eta, inout float u_lobe, vec2 u, out vec3 wi) {
    wi = vec3(0.0);
    if (!gltf_has_layers(m)) return false;
    vec2 p = gltf_layer_probs(m, co, eta);
    if (u_lobe < p.x) {
        wi = sample_cosine_hemisphere(u);
        return true;
    }
    if (u_lobe < p.x + p.y) {
        wi = sample_cosine_hemisphere(u);
        wi.z = -wi.z;
        return true;
    }
    u_lobe = min((u_lobe - p.x - p.y) / (1.0 - p.x - p.y), 0.99999994);
    return false;
}

bool gltf_layer_side_ok(MaterialData m, bool layer, bool upper, float wi_z) {
    return !gltf_has_layers(m) || layer || (wi_z > 0.0) == upper;
}

float gltf_layer_delta_scale(MaterialData m, float co, float eta, float ci) {
    if (!gltf_has_layers(m)) return 1.0;
    vec2 p = gltf_layer_probs(m, co, eta);
    return sheen_scaling(m, co, abs(ci)) / (1.0 - p.x - p.y);
}

#include "thin_film.glsl"

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

// Cosine-weighted in frame f (for a Lambertian surface frame_of_normal's,
// so no second basis is built).
BsdfSample lambert_sample(vec3 albedo, ShadingFrame f, vec2 u) {
    vec3 l = sample_cosine_hemisphere(u);
    BsdfSample s;
    s.wi = normalize(l.x * f.t + l.y * f.b + l.z * f.n);
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

// Schlick's approximation (glTF's metal Fresnel).
vec3 fresnel_schlick(vec3 f0, float c) {
    float x = clamp(1.0 - c, 0.0, 1.0);
    float x2 = x * x;
    return f0 + (vec3(1.0) - f0) * (x2 * x2 * x);
}

// The dielectric specular layer's reflectance: exact Fresnel with
// KHR_materials_specular's colour on F0 (see src/cpu/common/bsdf.rs).
vec3 specular_fresnel(MaterialData m, float c, float eta) {
    float cos_t;
    float f = fresnel_dielectric(c, eta, cos_t);
    float q = (eta - 1.0) / (eta + 1.0);
    float f0 = q * q;
    vec3 f0c = min(f0 * m.specular_color, vec3(1.0));
    float rise = f0 < 1.0 ? max((f - f0) / (1.0 - f0), 0.0) : 1.0;
    return f0c + (vec3(1.0) - f0c) * rise;
}

float gltf_eta(MaterialData m, bool front) {
    return (m.thickness > 0.0 && !front) ? 1.0 / m.ior : m.ior;
}

bool gltf_thin(MaterialData m) {
    return m.thickness <= 0.0 || abs(m.ior - 1.0) < 1e-4;
}

float gltf_alpha(MaterialData m) {
    return m.roughness * m.roughness;
}

// (alpha_t, alpha_b): equal unless anisotropic (anisotropy.glsl).
vec2 gltf_alpha2(MaterialData m) {
    return anisotropy_alpha(m, gltf_alpha(m));
}

bool gltf_smooth(MaterialData m) {
    return gltf_alpha2(m).x < GGX_SMOOTH_ALPHA;
}

vec3 gltf_reflection_color(MaterialData m, float c, float eta) {
    vec3 metal = fresnel_schlick(m.base_color, c);
    vec3 dielectric = m.specular_factor * specular_fresnel(m, c, eta);
    iridescent_reflection(m, c, eta, metal, dielectric);
    return m.metallic * metal + (1.0 - m.metallic) * dielectric;
}

float gltf_base_weight(MaterialData m, float c, float eta) {
    vec3 fr = specular_fresnel(m, c, eta);
    return iridescent_base_weight(m, c, eta, 1.0 - m.specular_factor * max(fr.r, max(fr.g, fr.b)));
}

float mean3(vec3 c) {
    return (c.x + c.y + c.z) / 3.0;
}

// Lobe probabilities (diffuse, reflection, transmission).
vec3 gltf_lobe_probs(MaterialData m, float co, float eta) {
    float base = (1.0 - m.metallic) * gltf_base_weight(m, co, eta) * mean3(m.base_color);
    float d = (1.0 - m.transmission) * base;
    d *= gltf_diffuse_reflected(m);
    float r = mean3(gltf_reflection_color(m, co, eta));
    float t = m.transmission * base;
    float sum = d + r + t;
    return sum > 0.0 ? vec3(d / sum, r / sum, t / sum) : vec3(0.0);
}

// Refracted direction of wo about h for relative index eta; false under TIR.
bool refract_about(vec3 wo, vec3 h, float eta, out vec3 wi) {
    float c = dot(wo, h);
    float cos_t;
    float f = fresnel_dielectric(c, eta, cos_t);
    wi = vec3(0.0);
    if (f >= 1.0) return false;
    wi = normalize(-wo / eta + (c / eta - cos_t) * h);
    return true;
}

bool refraction_half(vec3 wo, vec3 wi, float eta, out vec3 h) {
    h = wo + eta * wi;
    if (dot(h, h) < 1e-12) return false;
    h = normalize(h.z < 0.0 ? -h : h);
    return dot(wo, h) > 0.0 && dot(wi, h) < 0.0;
}

vec3 mirror_z(vec3 w) {
    return vec3(w.x, w.y, -w.z);
}

vec3 gltf_base_eval_local(MaterialData m, float eta, vec3 wo, vec3 wi) {
    float co = wo.z;
    if (co <= 0.0) return vec3(0.0);
    vec2 alpha = gltf_alpha2(m);
    bool smooth_surface = alpha.x < GGX_SMOOTH_ALPHA;
    if (wi.z > 0.0) {
        vec3 h = normalize(wo + wi);
        float c = dot(wo, h);
        float diffuse = (1.0 - m.metallic) * (1.0 - m.transmission) * gltf_base_weight(m, c, eta);
        diffuse *= gltf_diffuse_reflected(m);
        vec3 f = m.base_color * (diffuse * INV_PI * wi.z);
        if (!smooth_surface) {
            float g = mf_d(h, alpha) * mf_g2(wo, wi, alpha) / (4.0 * co);
            f += gltf_reflection_color(m, c, eta) * g;
        }
        return f;
    }
    if (wi.z == 0.0 || smooth_surface || m.transmission <= 0.0 || m.metallic >= 1.0) return vec3(0.0);
    float weight = (1.0 - m.metallic) * m.transmission;
    if (gltf_thin(m)) {
        vec3 r = mirror_z(wi);
        vec3 h = normalize(wo + r);
        float g = mf_d(h, alpha) * mf_g2(wo, r, alpha) / (4.0 * co);
        return m.base_color * (weight * gltf_base_weight(m, dot(wo, h), eta) * g);
    }
    vec3 h;
    if (!refraction_half(wo, wi, eta, h)) return vec3(0.0);
    float woh = dot(wo, h);
    float wih = dot(wi, h);
    float denom = eta * wih + woh;
    float g = mf_d(h, alpha) * mf_g2(wo, wi, alpha) * woh * (-wih) / (co * denom * denom);
    return m.base_color * (weight * gltf_base_weight(m, woh, eta) * g);
}

float gltf_base_pdf_local(MaterialData m, float eta, vec3 wo, vec3 wi) {
    float co = wo.z;
    if (co <= 0.0) return 0.0;
    vec3 p = gltf_lobe_probs(m, co, eta);
    vec2 alpha = gltf_alpha2(m);
    bool smooth_surface = alpha.x < GGX_SMOOTH_ALPHA;
    if (wi.z > 0.0) {
        float pdf = p.x * cosine_hemisphere_pdf(wi.z);
        if (!smooth_surface) {
            vec3 h = normalize(wo + wi);
            pdf += p.y * mf_vndf_pdf(wo, h, alpha) / (4.0 * dot(wo, h));
        }
        return pdf;
    }
    if (wi.z == 0.0 || smooth_surface || p.z <= 0.0) return 0.0;
    if (gltf_thin(m)) {
        vec3 h = normalize(wo + mirror_z(wi));
        return p.z * mf_vndf_pdf(wo, h, alpha) / (4.0 * dot(wo, h));
    }
    vec3 h;
    if (!refraction_half(wo, wi, eta, h)) return 0.0;
    float denom = eta * dot(wi, h) + dot(wo, h);
    return p.z * mf_vndf_pdf(wo, h, alpha) * eta * eta * (-dot(wi, h)) / (denom * denom);
}

vec3 to_local(vec3 w, vec3 t, vec3 b, vec3 n) {
    return vec3(dot(w, t), dot(w, b), dot(w, n));
}

vec3 gltf_eval(MaterialData m, ShadingFrame f, bool front, vec3 wo, vec3 wi) {
    vec3 v = gltf_eval_local(m, gltf_eta(m, front), to_local(wo, f.t, f.b, f.n), to_local(wi, f.t, f.b, f.n));
    if (clearcoat_active(m)) v = clearcoat_layer_eval(m, f.coat_n, wo, wi, v);
    return v;
}

float gltf_pdf(MaterialData m, ShadingFrame f, bool front, vec3 wo, vec3 wi) {
    float p = gltf_pdf_local(m, gltf_eta(m, front), to_local(wo, f.t, f.b, f.n), to_local(wi, f.t, f.b, f.n));
    if (clearcoat_active(m)) p = clearcoat_layer_pdf(m, f.coat_n, wo, wi, p);
    return p;
}

// A coated material's non-delta sample: the mixture pdf and eval / pdf.
BsdfSample gltf_coated_weight(MaterialData m, ShadingFrame f, bool front, vec3 wo, BsdfSample s) {
    s.pdf = gltf_pdf(m, f, front, wo, s.wi);
    s.weight = s.pdf > 0.0 ? gltf_eval(m, f, front, wo, s.wi) / s.pdf : vec3(0.0);
    s.pdf = max(s.pdf, 0.0);
    return s;
}

BsdfSample gltf_sample(MaterialData m, ShadingFrame f, bool front, vec3 wo_world, float u_lobe, vec2 u) {
    BsdfSample s;
    s.wi = vec3(0.0);
    s.weight = vec3(0.0);
    s.pdf = 0.0;
    s.delta = false;
    // The coat first, with probability blend (clearcoat.glsl); the rest of
    // u_lobe picks among the base's lobes. A smooth coat's weight is
    // blend / blend; the base's delta weights are unchanged ((1 - blend) /
    // (1 - blend)).
    bool coated = clearcoat_active(m);
    if (coated) {
        float blend = clearcoat_blend(m, dot(wo_world, f.coat_n));
        if (u_lobe < blend) {
            vec3 wi = clearcoat_sample_wi(m, f.coat_n, wo_world, u);
            if (clearcoat_rough(m)) {
                // A failed draw (below the coat) stays failed: the base
                // may have density there, the coat's draw does not.
                if (dot(wi, f.coat_n) <= 0.0) return s;
                s.wi = wi;
                return gltf_coated_weight(m, f, front, wo_world, s);
            }
            s.wi = wi;
            s.delta = true;
            s.weight = vec3(1.0);
            return s;
        }
        u_lobe = (u_lobe - blend) / (1.0 - blend);
    }
    vec3 t = f.t;
    vec3 b = f.b;
    vec3 n = f.n;
    vec3 wo = to_local(wo_world, t, b, n);
    float co = wo.z;
    if (co <= 0.0) return s;
    float eta = gltf_eta(m, front);
    vec3 p = gltf_lobe_probs(m, co, eta);
    vec2 alpha = gltf_alpha2(m);
    bool smooth_surface = alpha.x < GGX_SMOOTH_ALPHA;
    vec3 wi;
    bool layer = gltf_layer_sample(m, co, eta, u_lobe, u, wi);
    if (layer) {
        // A sheen or diffuse transmission direction (the layers above).
    } else if (u_lobe < p.x) {
        wi = sample_cosine_hemisphere(u);
    } else if (u_lobe < p.x + p.y) {
        if (smooth_surface) {
            s.delta = true;
            s.weight = gltf_reflection_color(m, co, eta) / p.y;
            wi = mirror_z(-wo);
        } else {
            wi = reflect_about(wo, mf_sample_vndf(wo, alpha, u));
        }
    } else if (p.z > 0.0) {
        bool thin = gltf_thin(m);
        if (smooth_surface) {
            if (thin) {
                wi = -wo;
            } else if (!refract_about(wo, vec3(0.0, 0.0, 1.0), eta, wi)) {
                return s;
            }
            float scale = thin ? 1.0 : 1.0 / (eta * eta);
            s.delta = true;
            s.weight = m.base_color
                * ((1.0 - m.metallic) * m.transmission * gltf_base_weight(m, co, eta) * scale / p.z);
        } else {
            vec3 h = mf_sample_vndf(wo, alpha, u);
            if (thin) {
                wi = mirror_z(reflect_about(wo, h));
            } else if (!refract_about(wo, h, eta, wi)) {
                return s;
            }
        }
    } else {
        return s;
    }
    if (!gltf_layer_side_ok(m, layer, u_lobe < p.x + p.y, wi.z)) return s;
    s.wi = normalize(wi.x * t + wi.y * b + wi.z * n);
    if (s.delta) s.weight *= gltf_layer_delta_scale(m, co, eta, wi.z);
    if (s.delta) return s;
    if (coated) {
        // Likewise a base draw where the base has no density.
        if (!(gltf_pdf_local(m, eta, wo, wi) > 0.0)) {
            s.wi = vec3(0.0);
            return s;
        }
        return gltf_coated_weight(m, f, front, wo_world, s);
    }
    s.pdf = gltf_pdf_local(m, eta, wo, wi);
    if (s.pdf > 0.0) {
        s.weight = gltf_eval_local(m, eta, wo, wi) / s.pdf;
    } else {
        s.pdf = 0.0;
    }
    return s;
}

// Only delta lobes: next-event estimation has nothing to evaluate.
// The albedo AOV (aov.glsl): the colour the surface reflects, textures
// applied. Lambert and glTF: the base colour (a metal's is its F0); Phong:
// diffuse plus specular colour, at most 1.
vec3 bsdf_albedo(MaterialData m) {
    if (FEATURE_PHONG && m.kind == MATERIAL_PHONG) return min(m.base_color + m.specular, vec3(1.0));
    return m.base_color;
}

// A rough coat over a delta-only base has a density.
bool bsdf_is_delta(MaterialData m) {
    return m.kind == MATERIAL_MIRROR
        || (FEATURE_GLTF_MATERIAL && m.kind == MATERIAL_GLTF && gltf_smooth(m) && (1.0 - m.metallic) * (1.0 - m.transmission) <= 0.0
            && !clearcoat_rough(m)
            && !gltf_has_sheen(m));
}

vec3 bsdf_eval(MaterialData m, ShadingFrame f, bool front, vec3 wo, vec3 wi) {
    vec3 n = f.n;
    if (m.kind == MATERIAL_LAMBERT) return lambert_eval(m.base_color, n, wi);
    if (FEATURE_PHONG && m.kind == MATERIAL_PHONG) return phong_eval(m, n, wo, wi);
    if (FEATURE_GLTF_MATERIAL && m.kind == MATERIAL_GLTF) return gltf_eval(m, f, front, wo, wi);
    return vec3(0.0);
}

float bsdf_pdf(MaterialData m, ShadingFrame f, bool front, vec3 wo, vec3 wi) {
    vec3 n = f.n;
    if (m.kind == MATERIAL_LAMBERT) return lambert_pdf(n, wi);
    if (FEATURE_PHONG && m.kind == MATERIAL_PHONG) return phong_pdf(m, n, wo, wi);
    if (FEATURE_GLTF_MATERIAL && m.kind == MATERIAL_GLTF) return gltf_pdf(m, f, front, wo, wi);
    return 0.0;
}

BsdfSample bsdf_sample(MaterialData m, ShadingFrame f, bool front, vec3 wo, float u_lobe, vec2 u) {
    vec3 n = f.n;
    if (m.kind == MATERIAL_LAMBERT) return lambert_sample(m.base_color, f, u);
    if (FEATURE_GLTF_MATERIAL && m.kind == MATERIAL_GLTF) return gltf_sample(m, f, front, wo, u_lobe, u);
    BsdfSample s;
    s.weight = vec3(0.0);
    s.pdf = 0.0;
    s.delta = false;
    if (FEATURE_PHONG && m.kind == MATERIAL_PHONG) {
        if (u_lobe < phong_specular_prob(m)) {
            s.wi = sample_phong_lobe(reflect_about(wo, n), m.shininess, u);
        } else {
            s.wi = lambert_sample(m.base_color, f, u).wi;
        }
        s.pdf = phong_pdf(m, n, wo, s.wi);
        if (s.pdf > 0.0) s.weight = phong_eval(m, n, wo, s.wi) / s.pdf;
        return s;
    }
    // MATERIAL_MIRROR: perfect reflection tinted by the base colour.
    s.wi = reflect_about(wo, n);
    s.delta = m.kind == MATERIAL_MIRROR;
    if (s.delta) s.weight = m.base_color;
    return s;
}

#endif
