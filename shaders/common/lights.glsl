// Light sampling and light pdfs (twin: src/cpu/common/lights.rs). Needs
// bindings.glsl. One light is chosen per shading point, in proportion to
// power (src/light_packing.rs): the selection number u picks the environment
// on [0, params.env_select_prob), an emissive triangle (by power) on the next
// light_params.tri_select_prob, else an analytic light by its cdf.
//
// Analytic lights (layout::Light): point and spot (KHR_lights_punctual, with
// the extension's range window and spot falloff), directional, spheres
// (sampled uniformly inside the cone they subtend) and sun disks (a cone of
// directions at infinity). Point, spot and directional lights are delta
// lights: only next-event estimation finds them (no MIS). Spheres and suns
// are found by BSDF-sampled rays too (intersect_sphere_lights, sun_emission)
// and weighted by MIS. Spheres emit from their outside only; a point inside a
// sphere gets no light from it. They absorb whatever hits them.
//
// Environment: uniform radiance params.environment, or an equirectangular
// map scaled by it (nearest texel; sampled by the piecewise-constant 2D
// distribution of luminance * sin(theta) built on the host).
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL

#include "loop_count.glsl"

#include "features.glsl"
#include "sampling.glsl"
#include "bvh.glsl"
#include "scene_fetch.glsl"
#include "textures.glsl"
#include "light_bvh.glsl"

struct LightSample {
    vec3 point;       // on the light (ignored for lights at infinity)
    vec3 normal;      // light's geometric normal, facing the shading point (0 for points)
    vec3 wi;          // unit direction from the shading point to the light
    float distance;   // FLT_MAX for lights at infinity
    vec3 radiance;    // delta lights: the irradiance-producing intensity / distance^2
    float pdf;        // solid angle (delta lights: the selection pmf), incl. selection; 0 = no sample
    bool delta;       // a delta light: no MIS
};

// Index of the emitter whose cdf interval holds u (binary search, bounded).
uint select_emitter(float u) {
    uint lo = 0u;
    uint hi = params.num_emitters - 1u;
    while (lo < hi) {
        COUNT_LOOP_ITERATION();
        uint mid = (lo + hi) / 2u;
        if (fetch_emitter_cdf(mid) <= u) lo = mid + 1u; else hi = mid;
    }
    return lo;
}

// Index of the analytic light whose cdf interval holds u.
uint select_light(float u) {
    uint lo = 0u;
    uint hi = light_params.num_lights - 1u;
    while (lo < hi) {
        COUNT_LOOP_ITERATION();
        uint mid = (lo + hi) / 2u;
        if (lights[mid].cdf <= u) lo = mid + 1u; else hi = mid;
    }
    return lo;
}

// ---- Environment ----------------------------------------------------------

// The largest i in [0, n) with env_cdf[base + i] <= u (env_cdf[base] is 0,
// so a zero-width cell is never returned).
uint env_search(uint base, uint n, float u) {
    uint lo = 0u;
    uint hi = n - 1u;
    while (lo < hi) {
        COUNT_LOOP_ITERATION();
        uint mid = (lo + hi + 1u) / 2u;
        if (env_cdf[base + mid] <= u) lo = mid; else hi = mid - 1u;
    }
    return lo;
}

// World direction of map coordinates (u, v) in [0, 1]^2.
vec3 env_direction(float u, float v) {
    float theta = PI * v;
    float phi = 2.0 * PI * (u - 0.5);
    float st = sin(theta);
    vec3 d = vec3(st * sin(phi), cos(theta), -st * cos(phi));
    float c = light_params.env_rot_cos;
    float s = light_params.env_rot_sin;
    return vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

// Texel (x, y) that world direction d falls in.
uvec2 env_texel_of(vec3 d) {
    float c = light_params.env_rot_cos;
    float s = light_params.env_rot_sin;
    vec3 m = vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    float v = acos(clamp(m.y, -1.0, 1.0)) * INV_PI;
    float u = atan(m.x, -m.z) * (0.5 * INV_PI) + 0.5;
    uint w = light_params.env_width;
    uint h = light_params.env_height;
    return uvec2(min(uint(u * float(w)), w - 1u), min(uint(v * float(h)), h - 1u));
}

// Probability density (solid angle) of importance sampling texel t whose
// direction has sin(theta) = sin_theta.
float env_texel_pdf(uvec2 t, float sin_theta) {
    uint w = light_params.env_width;
    uint h = light_params.env_height;
    uint row = h + 1u + t.y * (w + 1u);
    float p_row = env_cdf[t.y + 1u] - env_cdf[t.y];
    float p_col = env_cdf[row + t.x + 1u] - env_cdf[row + t.x];
    if (!(sin_theta > 0.0)) return 0.0;
    return (p_row * float(h)) * (p_col * float(w)) / (2.0 * PI * PI * sin_theta);
}

// Environment radiance arriving from direction d.
vec3 environment_radiance(vec3 d) {
    if (!FEATURE_ENVIRONMENT_MAP || light_params.env_width == 0u) return params.environment;
    uvec2 t = env_texel_of(d);
    return params.environment * env_radiance[t.y * light_params.env_width + t.x].xyz;
}

// Solid-angle pdf of sampling direction d given that the environment is chosen.
float environment_direction_pdf(vec3 d) {
    if (!FEATURE_ENVIRONMENT_MAP || light_params.env_width == 0u
        || light_params.env_sampling == ENV_SAMPLE_UNIFORM)
        return uniform_sphere_pdf();
    uvec2 t = env_texel_of(d);
    float c = light_params.env_rot_cos;
    float s = light_params.env_rot_sin;
    vec2 mxz = vec2(c * d.x - s * d.z, s * d.x + c * d.z);
    return env_texel_pdf(t, length(mxz));
}

void sample_environment(vec2 u, inout LightSample ls) {
    ls.distance = FLT_MAX;
    if (!FEATURE_ENVIRONMENT_MAP || light_params.env_width == 0u
        || light_params.env_sampling == ENV_SAMPLE_UNIFORM) {
        ls.wi = sample_uniform_sphere(u);
        ls.radiance = environment_radiance(ls.wi);
        ls.pdf = uniform_sphere_pdf();
        return;
    }
    uint w = light_params.env_width;
    uint h = light_params.env_height;
    uint y = env_search(0u, h, u.y);
    float r0 = env_cdf[y];
    float dv = (u.y - r0) / (env_cdf[y + 1u] - r0);
    uint row = h + 1u + y * (w + 1u);
    uint x = env_search(row, w, u.x);
    float c0 = env_cdf[row + x];
    float du = (u.x - c0) / (env_cdf[row + x + 1u] - c0);
    float v = (float(y) + dv) / float(h);
    ls.wi = env_direction((float(x) + du) / float(w), v);
    ls.radiance = params.environment * env_radiance[y * w + x].xyz;
    ls.pdf = env_texel_pdf(uvec2(x, y), sin(PI * v));
}

// ---- Analytic lights -------------------------------------------------------

// KHR_lights_punctual's range window: max(min(1 - (d/range)^4, 1), 0).
float range_window(float range, float dist) {
    if (!(range > 0.0)) return 1.0;
    float q = dist / range;
    float q2 = q * q;
    return clamp(1.0 - q2 * q2, 0.0, 1.0);
}

// KHR_lights_punctual's spot falloff for cos of the angle from the axis.
float spot_falloff(Light l, float cos_axis) {
    float a = clamp(cos_axis * l.spot_scale + l.spot_offset, 0.0, 1.0);
    return a * a;
}

// Direction inside the cone of half angle theta_max around unit axis w,
// uniform in solid angle; 1 - cos(theta_max) = one_minus_cos_max. sin^2
// theta is formed as (1 - cos)(1 + cos), exact for tiny cones.
vec3 sample_cone(vec3 w, float one_minus_cos_max, vec2 u, out float cos_theta, out float sin2_theta) {
    float omc = u.x * one_minus_cos_max;
    cos_theta = 1.0 - omc;
    sin2_theta = omc * (2.0 - omc);
    float sin_theta = sqrt(max(0.0, sin2_theta));
    float phi = 2.0 * PI * u.y;
    vec3 t, b;
    build_onb(w, t, b);
    return sin_theta * cos(phi) * t + sin_theta * sin(phi) * b + cos_theta * w;
}

float cone_pdf(float one_minus_cos_max) {
    return 1.0 / (2.0 * PI * one_minus_cos_max);
}

// 1 - cos of the half angle a sphere of radius r subtends at distance^2
// dc2 > r^2, as sin^2 / (1 + cos) (no cancellation for small spheres).
float sphere_one_minus_cos_max(float r, float dc2) {
    float sin2 = min(r * r / dc2, 1.0);
    return sin2 / (1.0 + sqrt(max(0.0, 1.0 - sin2)));
}

// Solid-angle pdf (without selection) of sampling sphere light l from p; 0 inside.
float sphere_cone_pdf(Light l, vec3 p) {
    vec3 pc = l.position - p;
    float dc2 = dot(pc, pc);
    if (!(dc2 > l.radius * l.radius)) return 0.0;
    return cone_pdf(sphere_one_minus_cos_max(l.radius, dc2));
}

void sample_sphere_light(Light l, vec3 p, vec2 u, inout LightSample ls) {
    vec3 pc = l.position - p;
    float dc2 = dot(pc, pc);
    float r = l.radius;
    if (!(dc2 > r * r)) return;   // inside: the sphere emits outward only
    float dc = sqrt(dc2);
    vec3 w = pc / dc;
    float sin2_max = min(r * r / dc2, 1.0);
    float omc_max = sphere_one_minus_cos_max(r, dc2);
    float cos_theta, sin2_theta;
    sample_cone(w, omc_max, u, cos_theta, sin2_theta);   // for cos and sin^2 theta
    // The point the direction meets on the near side, by its angle alpha at
    // the centre: cos alpha = sin^2 theta / sin theta_max + cos theta
    // sqrt(1 - sin^2 theta / sin^2 theta_max) (pbrt-v4, Sphere::Sample).
    float sin_max = sqrt(sin2_max);
    float ratio = min(sin2_theta / sin2_max, 1.0);
    float cos_alpha = sin2_theta / sin_max + cos_theta * sqrt(max(0.0, 1.0 - ratio));
    cos_alpha = clamp(cos_alpha, -1.0, 1.0);
    float sin_alpha = sqrt(max(0.0, 1.0 - cos_alpha * cos_alpha));
    // The point's azimuth is dir's (sample_cone's frame), taken from the
    // frame itself: dir minus its w component cancels badly for small cones.
    vec3 t, b;
    build_onb(w, t, b);
    float phi = 2.0 * PI * u.y;
    vec3 side = cos(phi) * t + sin(phi) * b;
    vec3 n = -cos_alpha * w + sin_alpha * side;
    ls.point = l.position + r * n;
    vec3 to_light = ls.point - p;
    ls.distance = length(to_light);
    if (!(ls.distance > 0.0)) return;
    ls.wi = to_light / ls.distance;
    ls.normal = n;
    ls.radiance = l.emission;
    ls.pdf = cone_pdf(omc_max);
}

// Samples analytic light l from p; pdf without the selection pmf.
void sample_analytic_light(Light l, vec3 p, vec2 u, inout LightSample ls) {
    if (l.kind == LIGHT_SPHERE) {
        sample_sphere_light(l, p, u, ls);
        return;
    }
    if (l.kind == LIGHT_SUN) {
        float cos_theta, sin2_theta;
        ls.wi = sample_cone(-l.direction, l.one_minus_cos_max, u, cos_theta, sin2_theta);
        ls.distance = FLT_MAX;
        ls.radiance = l.emission;
        ls.pdf = cone_pdf(l.one_minus_cos_max);
        return;
    }
    ls.delta = true;
    if (l.kind == LIGHT_DIRECTIONAL) {
        ls.wi = -l.direction;
        ls.distance = FLT_MAX;
        ls.radiance = l.emission;
        ls.pdf = 1.0;
        return;
    }
    // Point and spot.
    vec3 to_light = l.position - p;
    float dist2 = dot(to_light, to_light);
    if (!(dist2 > 0.0)) return;
    float dist = sqrt(dist2);
    ls.point = l.position;
    ls.normal = vec3(0.0);
    ls.distance = dist;
    ls.wi = to_light / dist;
    float a = range_window(l.range, dist) / dist2;
    if (l.kind == LIGHT_SPOT) a *= spot_falloff(l, dot(l.direction, -ls.wi));
    ls.radiance = l.emission * a;
    ls.pdf = a > 0.0 ? 1.0 : 0.0;
}

// ---- Selection ---------------------------------------------------------------

// Samples a point of emitter e for p. By power (per_area): select_pmf is
// tri_select_prob, times e.pmf / area, or in a two-level scene times the
// triangle's light_pmf (per unit area). By the light BVH (!per_area):
// select_pmf is the probability of choosing e, spread over the area of the
// triangle as placed, which shade_path finds too.
void sample_emitter(Emitter e, vec3 p, vec2 u, float time, float select_pmf, bool per_area,
                    inout LightSample ls) {
    // The emitter's slot, and the instance that places it (instances.glsl).
    uint inst;
    uint tri = hit_slot(e.triangle, inst);
    vec3 v0, v1, v2;
    fetch_triangle_at(tri, time, v0, v1, v2);
    world_triangle(inst, v0, v1, v2);
    // A moving triangle's area is the one at `time`, as shade_path
    // computes it where a ray finds the emitter; it may be 0 then. The
    // light BVH takes the area shade_path finds too.
    float area = e.area;
    if (motion_on() || !per_area) {
        area = 0.5 * length(cross(v1 - v0, v2 - v0));
        if (!(area > 0.0)) return;
    }
    vec2 b = sample_uniform_triangle(u);
    ls.point = (1.0 - b.x - b.y) * v0 + b.x * v1 + b.y * v2;
    vec3 n = normalize(cross(v1 - v0, v2 - v0) * instance_facing(inst));
    vec3 to_light = ls.point - p;
    float dist2 = dot(to_light, to_light);
    ls.distance = sqrt(dist2);
    ls.wi = to_light / ls.distance;
    float cos_light = -dot(n, ls.wi);
    MaterialData m = fetch_material(fetch_triangle_material(tri));
    if (!(dist2 > 0.0) || abs(cos_light) < 1e-7 || (cos_light < 0.0 && m.double_sided == 0u)) return;
    ls.normal = cos_light > 0.0 ? n : -n;
    ls.radiance = textured_emission(m, tri, b);
    if (!per_area) {
        ls.pdf = select_pmf / area * dist2 / abs(cos_light);
    } else if (inst == NO_INSTANCE) {
        ls.pdf = select_pmf * e.pmf / area * dist2 / abs(cos_light);
    } else {
        // The emitter's probability per unit area (instanced_emitters).
        ls.pdf = select_pmf * fetch_light_pmf(tri) * dist2 / abs(cos_light);
    }
}

// A light for point p (the shading point), chosen by power or, with the
// light BVH, by its importance to `p_tree`: the point the path's next rays
// leave from (offset_ray_origin toward the surface normal), which is
// where MIS finds the path again when a BSDF-sampled ray meets the light;
// `n_tree`: the normal there as the path state carries it
// (light_tree_normal), 0 for none.
LightSample sample_light(vec3 p, vec3 p_tree, vec3 n_tree, float u_select, vec2 u, float time) {
    LightSample ls;
    ls.pdf = 0.0;
    ls.radiance = vec3(0.0);
    ls.point = vec3(0.0);
    ls.normal = vec3(0.0);
    ls.distance = FLT_MAX;
    ls.wi = vec3(0.0, 0.0, 1.0);
    ls.delta = false;
    float p_env = params.env_select_prob;
    float p_tri = light_params.tri_select_prob;
    if (u_select < p_env) {
        sample_environment(u, ls);
        ls.pdf *= p_env;
        return ls;
    }
    if (u_select < p_env + p_tri) {
        float u_tri = min((u_select - p_env) / p_tri, 0.99999994);
        if (light_tree_on()) {
            float pmf;
            LightTreeNode leaf = light_tree_sample(p_tree, n_tree, u_tri, pmf);
            if (!(pmf > 0.0)) return ls;
            if ((leaf.flags & LIGHT_TREE_ANALYTIC) != 0u) {
                sample_analytic_light(lights[leaf.child_or_light], p, u, ls);
                ls.pdf *= p_tri * pmf;
            } else {
                sample_emitter(fetch_emitter(leaf.child_or_light), p, u, time, p_tri * pmf, false, ls);
            }
            return ls;
        }
        if (params.num_emitters == 0u) return ls;
        sample_emitter(fetch_emitter(select_emitter(u_tri)), p, u, time, p_tri, true, ls);
        return ls;
    }
    if (!FEATURE_ANALYTIC_LIGHTS || light_params.num_lights == 0u) return ls;
    float u_light = min((u_select - p_env - p_tri) / (1.0 - p_env - p_tri), 0.99999994);
    Light l = lights[select_light(u_light)];
    if (!(l.pmf > 0.0)) return ls;
    sample_analytic_light(l, p, u, ls);
    ls.pdf *= l.pmf;
    return ls;
}

// Solid-angle pdf with which sample_light would have produced a hit on an
// emissive triangle at distance `dist` seen under cosine `cos_light`.
float triangle_light_pdf(float light_pmf, float area, float dist, float cos_light) {
    return light_params.tri_select_prob * light_pmf / area * dist * dist / abs(cos_light);
}

// Solid-angle pdf with which sample_light would have produced direction d
// toward the environment.
float environment_light_pdf(vec3 d) {
    return params.env_select_prob * environment_direction_pdf(d);
}

// ---- Rays meeting spheres and suns ------------------------------------------

// Nearest t in (0, t_max) where the ray meets sphere light k, or t_max.
float intersect_sphere(Light l, vec3 o, vec3 d, float t_max) {
    vec3 oc = o - l.position;
    float b = dot(oc, d);
    vec3 f = oc - b * d;   // centre to the ray's closest point (stable for small spheres)
    float disc = l.radius * l.radius - dot(f, f);
    if (disc < 0.0) return t_max;
    float q = sqrt(disc);
    float t0 = -b - q;
    float t1 = -b + q;
    if (t0 > 0.0 && t0 < t_max) return t0;
    if (t1 > 0.0 && t1 < t_max) return t1;
    return t_max;
}

// The nearest spherical light the ray meets before t_max (updates t_max), or
// NO_HIT. Spheres are lights only: they are not in the BVH.
uint intersect_sphere_lights(vec3 o, vec3 d, inout float t_max) {
    uint found = NO_HIT;
    if (!FEATURE_ANALYTIC_LIGHTS) return found;
    for (uint k = 0u; k < light_params.num_spheres; k++) {
        COUNT_LOOP_ITERATION();
        float t = intersect_sphere(lights[k], o, d, t_max);
        if (t < t_max) {
            t_max = t;
            found = k;
        }
    }
    return found;
}

// Radiance from sphere light k seen along ray (o, d) at distance t, with the
// MIS weight against light sampling when prev_pdf > 0 (0: camera or delta);
// o_normal: the normal at o (light_tree_normal of the path's prev_normal).
vec3 sphere_emission(uint k, vec3 o, vec3 o_normal, vec3 d, float t, float prev_pdf) {
    Light l = lights[k];
    vec3 n = (o + t * d - l.position);
    if (dot(n, d) >= 0.0) return vec3(0.0);   // from inside: dark
    float w = 1.0;
    if (prev_pdf > 0.0) {
        float pmf = light_tree_on() ? light_tree_light_pmf(k, o, o_normal) : l.pmf;
        w = power_heuristic(prev_pdf, pmf * sphere_cone_pdf(l, o));
    }
    return l.emission * w;
}

// What a ray leaving the scene can meet (twin: lights.rs): the environment,
// uniform or a map scaled by params.environment, and sun disks.
bool environment_shines() {
    return max(params.environment.r, max(params.environment.g, params.environment.b)) > 0.0;
}

bool suns_shine() {
    return FEATURE_ANALYTIC_LIGHTS && light_params.num_suns > 0u;
}

// Radiance from sun disks in direction d, MIS-weighted as above.
vec3 sun_emission(vec3 d, float prev_pdf) {
    vec3 sum = vec3(0.0);
    if (!FEATURE_ANALYTIC_LIGHTS) return sum;
    uint first = light_params.num_spheres;
    for (uint k = first; k < first + light_params.num_suns; k++) {
        COUNT_LOOP_ITERATION();
        Light l = lights[k];
        vec3 e = d + l.direction;   // d - (direction toward the sun)
        if (0.5 * dot(e, e) > l.one_minus_cos_max) continue;
        float w = 1.0;
        if (prev_pdf > 0.0) w = power_heuristic(prev_pdf, l.pmf * cone_pdf(l.one_minus_cos_max));
        sum += l.emission * w;
    }
    return sum;
}

#endif
