// Light sampling (twin: src/cpu/lights.rs). Needs bindings.glsl. One light
// is chosen per shading point: the environment with probability
// params.env_select_prob, else an emissive triangle by power.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL

#include "sampling.glsl"
#include "bvh.glsl"
#include "scene_fetch.glsl"
#include "textures.glsl"

struct LightSample {
    vec3 point;       // on the light (ignored for the environment)
    vec3 normal;      // light's geometric normal, facing the shading point
    vec3 wi;          // unit direction from the shading point to the light
    float distance;   // FLT_MAX for the environment
    vec3 radiance;
    float pdf;        // solid angle, including the selection probability; 0 = no sample
};

// Index of the emitter whose cdf interval holds u (binary search, bounded).
uint select_emitter(float u) {
    uint lo = 0u;
    uint hi = params.num_emitters - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (fetch_emitter_cdf(mid) <= u) lo = mid + 1u; else hi = mid;
    }
    return lo;
}

LightSample sample_light(vec3 p, float u_select, vec2 u) {
    LightSample ls;
    ls.pdf = 0.0;
    ls.radiance = vec3(0.0);
    ls.point = vec3(0.0);
    ls.normal = vec3(0.0);
    ls.distance = FLT_MAX;
    ls.wi = vec3(0.0, 0.0, 1.0);
    float p_env = params.env_select_prob;
    if (u_select < p_env) {
        ls.wi = sample_uniform_sphere(u);
        ls.radiance = params.environment;
        ls.pdf = p_env * uniform_sphere_pdf();
        return ls;
    }
    if (params.num_emitters == 0u) return ls;
    float u_tri = min((u_select - p_env) / (1.0 - p_env), 0.99999994);
    Emitter e = fetch_emitter(select_emitter(u_tri));
    vec3 v0, v1, v2;
    fetch_triangle(e.triangle, v0, v1, v2);
    vec2 b = sample_uniform_triangle(u);
    ls.point = (1.0 - b.x - b.y) * v0 + b.x * v1 + b.y * v2;
    vec3 n = normalize(cross(v1 - v0, v2 - v0));
    vec3 to_light = ls.point - p;
    float dist2 = dot(to_light, to_light);
    ls.distance = sqrt(dist2);
    ls.wi = to_light / ls.distance;
    float cos_light = -dot(n, ls.wi);
    MaterialData m = fetch_material(fetch_triangle_material(e.triangle));
    if (!(dist2 > 0.0) || abs(cos_light) < 1e-7 || (cos_light < 0.0 && m.double_sided == 0u)) return ls;
    ls.normal = cos_light > 0.0 ? n : -n;
    ls.radiance = textured_emission(m, e.triangle, b);
    ls.pdf = (1.0 - p_env) * e.pmf / e.area * dist2 / abs(cos_light);
    return ls;
}

// Solid-angle pdf with which sample_light would have produced a hit on an
// emissive triangle at distance `dist` seen under cosine `cos_light`.
float triangle_light_pdf(float light_pmf, float area, float dist, float cos_light) {
    return (1.0 - params.env_select_prob) * light_pmf / area * dist * dist / abs(cos_light);
}

float environment_light_pdf() {
    return params.env_select_prob * uniform_sphere_pdf();
}

#endif
