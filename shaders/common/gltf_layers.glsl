// The lobes KHR_materials_sheen and KHR_materials_diffuse_transmission add
// to the glTF model of bsdf.glsl, composed around its lobes (gltf_base_*)
// in the local frame (twin: src/cpu/gltf_layers.rs, which explains the
// composition and the sampling). Included at the top of bsdf.glsl: the base
// functions it calls are declared here and defined there. Each lobe runs
// only under its specialization constant and the material's LOBE_* bit, so
// a material without them takes exactly the base's code path.
#ifndef GLTF_LAYERS_GLSL
#define GLTF_LAYERS_GLSL

#include "features.glsl"
#include "sampling.glsl"
#include "sheen.glsl"

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

#endif
