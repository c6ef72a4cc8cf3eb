// What follows a hit or a miss: one bounce of the path tracer (twin:
// src/cpu/common/integrator.rs). Emission found by the ray, next-event estimation
// (a light sample, combined with BSDF sampling by the power heuristic), the
// BSDF sample that continues the path (bsdf.glsl: Lambert, Phong, mirror,
// glTF metallic-roughness with transmission), Russian roulette; volume
// absorption (Beer-Lambert) inside closed transmissive volumes, and the
// shading frame (shading_frame.glsl). The wavefront
// kernel shade.comp and the CPU reference both call shade_path, so they
// implement the same estimator.
//
// Depth: a path of k segments (camera to light) is kept when k <= max_depth
// (Mitsuba's max_depth: 1 = emitters seen directly, 2 = direct lighting).
// `bounce` is the number of surface interactions before this hit (0 for the
// camera ray's hit).
#ifndef INTEGRATOR_GLSL
#define INTEGRATOR_GLSL

#include "bsdf.glsl"
#include "bvh.glsl"
#include "dispersion.glsl"
#include "lights.glsl"
#include "scene_fetch.glsl"
#include "shading_frame.glsl"
#include "rng.glsl"
#include "textures.glsl"

struct PathState {
    vec3 origin;
    vec3 direction;
    vec3 throughput;
    float prev_pdf;   // pdf of the BSDF sample that made this ray; 0 = no MIS (camera)
    // The product of eta^2 over the refractions so far (eta = n_t / n_o):
    // the throughput carries 1/eta^2 per refraction, which Russian roulette
    // undoes so that paths inside glass are not killed for it.
    float eta_scale;
    // KHR_materials_dispersion: the colour channel the path carries since
    // its first dispersive surface (1 red, 2 green, 3 blue), 0 before.
    uint dispersion_channel;
    // The light BVH's receiving normal at the vertex the ray left
    // (light_tree_normal_code; 0: none, as from the camera): MIS bounds with
    // the normal light sampling bounded with there.
    uint prev_normal;
};

// A path at its camera ray (twin: PathState::camera in integrator.rs).
PathState camera_path_state(vec3 origin, vec3 direction) {
    PathState s;
    s.origin = origin;
    s.direction = direction;
    s.throughput = vec3(1.0);
    s.prev_pdf = 0.0;
    s.eta_scale = 1.0;
    s.dispersion_channel = 0u;
    s.prev_normal = 0u;
    return s;
}

struct ShadeResult {
    vec3 emitted;           // radiance to add to the path now
    bool shadow;            // a shadow ray to trace; its contribution counts if unoccluded
    vec3 shadow_origin;
    vec3 shadow_direction;
    float shadow_t_max;
    vec3 shadow_contribution;
    bool next;              // the path goes on with next_state
    PathState next_state;
    // What the auxiliary outputs see here (aov.glsl), when the ray came from
    // the camera or a delta bounce (prev_pdf 0) and ends the delta chain.
    bool aov_event;
    vec3 aov_albedo;
    vec3 aov_normal;
};

// The shadow ray of light sample `ls` from `origin`: at the sampled point
// itself, stopping short of it by its error bound (gamma(7) |point|: the
// light triangle is assumed not to straddle the origin), so the ray cannot
// hit the light; along wi, unbounded, for a light at infinity.
void aim_shadow_ray(inout ShadeResult r, vec3 origin, LightSample ls) {
    r.shadow_origin = origin;
    if (ls.distance == FLT_MAX) {
        r.shadow_direction = ls.wi;
        r.shadow_t_max = FLT_MAX;
    } else {
        vec3 d = ls.point - origin;
        float len = length(d);
        r.shadow_direction = d / len;
        float short_by = dot(abs(r.shadow_direction), GAMMA7 * abs(ls.point));
        r.shadow_t_max = len * (1.0 - SHADOW_RAY_SHORTEN) - short_by;
    }
}

// What a ray that left the scene sees: the environment (unless hidden from
// camera rays) and sun disks, with MIS against light sampling.
void shade_escaped(PathState s, uint bounce, bool aov, inout ShadeResult r) {
    if (environment_shines() && !(bounce == 0u && light_params.env_hidden != 0u)) {
        vec3 le = environment_radiance(s.direction);
        float w = s.prev_pdf > 0.0 ? power_heuristic(s.prev_pdf, environment_light_pdf(s.direction)) : 1.0;
        r.emitted = s.throughput * le * w;
        // The environment as seen is the albedo of an escaped ray.
        if (aov) r.aov_albedo = min(le, vec3(1.0));
    }
    // Sun disks only where there are some: a path whose throughput became
    // infinite then keeps the radiance it had (inf * 0 would make it NaN),
    // as it does where extend ends dark escapes (escapes_are_dark).
    if (suns_shine()) {
        r.emitted += s.throughput * sun_emission(s.direction, s.prev_pdf);
    }
    r.aov_event = aov;
}

// Whether the light BVH bounds with the surface's normal (one-sided): a
// material that only reflects and has a lobe that is not delta (twin:
// integrator.rs).
bool light_tree_receiving_normal(MaterialData m) {
    if (bsdf_is_delta(m)) return false;
    return !(m.kind == MATERIAL_GLTF && (m.transmission > 0.0 || gltf_has_diffuse_transmission(m)));
}

ShadeResult shade_path(PathState s, Hit hit, RngKey key, uint bounce) {
    ShadeResult r;
    r.emitted = vec3(0.0);
    r.shadow = false;
    r.next = false;
    r.shadow_origin = vec3(0.0);
    r.shadow_direction = vec3(0.0);
    r.shadow_t_max = 0.0;
    r.shadow_contribution = vec3(0.0);
    r.next_state = s;
    r.aov_event = false;
    r.aov_albedo = vec3(0.0);
    r.aov_normal = vec3(0.0);
    bool aov = FEATURE_AOV && params.aov != 0u && s.prev_pdf == 0.0;

    if (hit.triangle == OVERFLOW_HIT) return r;   // counted by the caller
    if (hit.triangle == NO_HIT) {
        shade_escaped(s, bounce, aov, r);
        return r;
    }
    if ((hit.triangle & LIGHT_HIT_FLAG) != 0u) {   // a spherical light: it absorbs
        vec3 o_normal = light_tree_normal(s.prev_normal);
        r.emitted = s.throughput * sphere_emission(hit.triangle & ~LIGHT_HIT_FLAG, s.origin, o_normal, s.direction, hit.t, s.prev_pdf);
        if (aov) r.aov_albedo = min(sphere_emission(hit.triangle & ~LIGHT_HIT_FLAG, s.origin, o_normal, s.direction, hit.t, 0.0), vec3(1.0));
        r.aov_event = aov;
        return r;
    }

    float time = motion_on() ? path_time(key) : 0.0;   // the path's moment in the shutter
    // The triangle's slot and the instance that places it (instances.glsl).
    uint inst;
    uint tri = hit_slot(hit.triangle, inst);
    vec3 v0, v1, v2;
    fetch_triangle_at(tri, time, v0, v1, v2);
    world_triangle(inst, v0, v1, v2);
    vec3 p = triangle_point(hit.b12, v0, v1, v2);
    vec3 p_error = triangle_point_error(hit.b12, v0, v1, v2, p);
    if (inst != NO_INSTANCE) p_error += instance_error(inst, p);
    vec3 ng_raw = cross(v1 - v0, v2 - v0) * instance_facing(inst);
    float area = 0.5 * length(ng_raw);
    vec3 ng = ng_raw / (2.0 * area);
    float cos_o = dot(s.direction, ng);
    bool front = cos_o < 0.0;
    MaterialData m = fetch_material(fetch_triangle_material(tri));
    if (FEATURE_TEXTURES && material_has_textures(m)) {
        m = apply_textures(m, tri, hit.b12, texture_footprint(tri, v0, v1, v2, p));
    }

    // Beer-Lambert: a ray reaching the back face of a closed volume
    // (thickness > 0) travelled hit.t inside it.
    if (FEATURE_GLTF_MATERIAL && !front && m.thickness > 0.0) s.throughput *= exp(-m.attenuation * hit.t);

    // Emission found by this ray.
    if (max(m.emission.r, max(m.emission.g, m.emission.b)) > 0.0 && (front || m.double_sided != 0u)) {
        float w = 1.0;
        if (s.prev_pdf > 0.0) {
            float light_pdf;
            if (light_tree_on()) {
                // The light BVH's choice at the point the ray left from,
                // with its normal.
                light_pdf = light_tree_triangle_pmf(hit.triangle, s.origin, light_tree_normal(s.prev_normal)) / area * hit.t * hit.t / abs(cos_o);
            } else {
                // Per unit area in a two-level scene (packed::instanced_emitters).
                float light_pmf = fetch_light_pmf(tri);
                if (inst != NO_INSTANCE) light_pmf *= area;
                light_pdf = triangle_light_pdf(light_pmf, area, hit.t, cos_o);
            }
            w = power_heuristic(s.prev_pdf, light_pdf);
        }
        r.emitted = s.throughput * m.emission * w;
    }

    // Dispersion (dispersion.glsl): from here on the path keeps one channel.
    if (dispersive(m)) {
        if (s.dispersion_channel == 0u) {
            uint d = DIM_BOUNCE_BASE + DIM_PER_BOUNCE * bounce + DIM_DISPERSION_CHANNEL;
            s.dispersion_channel = dispersion_pick_channel(rng_float(key, d));
            s.throughput *= dispersion_channel_weight(s.dispersion_channel);
        }
        m.ior = dispersion_ior(m.ior, m.dispersion, s.dispersion_channel);
    }

    vec3 n = front ? ng : -ng;   // scatter on the side the ray came from
    vec3 wo = -s.direction;
    // Shading normal: interpolated vertex normals on wo's side, reconciled
    // with the geometric normal (shading_frame.glsl).
    vec3 sn0, sn1, sn2;
    if (motion_on()) {
        moving_triangle_normals(tri, time, sn0, sn1, sn2);
    } else {
        fetch_triangle_normals(tri, sn0, sn1, sn2);
        world_normals(inst, sn0, sn1, sn2);
    }
    vec3 n_vertex = interpolate_normal(sn0, sn1, sn2, hit.b12, ng);
    vec3 ns = n_vertex;
    if (FEATURE_TEXTURES && (TEXTURE_SLOT_MASK & TEXTURE_SLOT_NORMAL) != 0u && m.normal_texture != NO_TEXTURE) {
        ns = apply_normal_map(m, tri, inst, hit.b12, time, ns);
    }
    ns = front ? ns : -ns;
    ns = reconcile_shading_normal(n, ns, wo);
    ShadingFrame frame = shading_frame(m, tri, inst, hit.b12, time, n, n_vertex, ns, front, wo);
    // The first surface that is not a mirror or smooth glass ends the chain.
    if (aov && !bsdf_is_delta(m)) {
        r.aov_event = true;
        r.aov_albedo = bsdf_albedo(m);
        r.aov_normal = ns;
    }

    // A path may add a segment only while it stays within max_depth.
    if (bounce + 1u >= params.max_depth || bounce + 1u >= MAX_BOUNCES_HARD) return r;
    uint dim = DIM_BOUNCE_BASE + DIM_PER_BOUNCE * bounce;
    vec3 origin = offset_ray_origin(p, p_error, n);

    // Next-event estimation (not for delta-only materials: a light sample
    // never lies on a delta lobe). Delta lights get no MIS weight.
    // The light BVH bounds cos theta_i with n as the path state carries it
    // (the same f32 normal where MIS meets the path's next ray), where the
    // surface only reflects.
    uint n_code = light_tree_on() && light_tree_receiving_normal(m) ? light_tree_normal_code(n) : 0u;
    if (!bsdf_is_delta(m)) {
        LightSample ls = sample_light(p, origin, light_tree_normal(n_code), rng_float(key, dim + DIM_LIGHT_SELECT),
                                      rng_float2(key, dim + DIM_LIGHT_SAMPLE), time);
        if (ls.pdf > 0.0 && same_side(n, ns, ls.wi)) {
            vec3 f = bsdf_eval(m, frame, front, wo, ls.wi);
            float w = ls.delta ? 1.0 : power_heuristic(ls.pdf, bsdf_pdf(m, frame, front, wo, ls.wi));
            r.shadow_contribution = s.throughput * f * ls.radiance * (w / ls.pdf);
            // From the side the light is on (transmission reaches through).
            aim_shadow_ray(r, offset_ray_origin(p, p_error, dot(ls.wi, n) > 0.0 ? n : -n), ls);
            r.shadow = max(r.shadow_contribution.r, max(r.shadow_contribution.g, r.shadow_contribution.b)) > 0.0;
        }
    }

    // BSDF sampling continues the path.
    BsdfSample bs = bsdf_sample(m, frame, front, wo, rng_float(key, dim + DIM_BSDF_LOBE),
                                rng_float2(key, dim + DIM_BSDF_SAMPLE));
    if ((!bs.delta && !(bs.pdf > 0.0)) || !same_side(n, ns, bs.wi)) return r;
    vec3 throughput = s.throughput * bs.weight;
    // A refracted ray leaves from the other side of the surface.
    bool crossed = dot(bs.wi, n) < 0.0;
    if (crossed) origin = offset_ray_origin(p, p_error, -n);
    float eta_scale = s.eta_scale;
    if (FEATURE_GLTF_MATERIAL && crossed && m.kind == MATERIAL_GLTF && !gltf_thin(m)) {
        float eta = gltf_eta(m, front);
        eta_scale *= eta * eta;
    }

    // Russian roulette.
    if (bounce >= RR_START_BOUNCE) {
        float q = min(max(throughput.r, max(throughput.g, throughput.b)) * eta_scale, RR_MAX_CONTINUE);
        if (rng_float(key, dim + DIM_RUSSIAN_ROULETTE) >= q) return r;
        throughput /= q;
    }
    if (!(max(throughput.r, max(throughput.g, throughput.b)) > 0.0)) return r;

    r.next = true;
    r.next_state.origin = origin;
    r.next_state.direction = bs.wi;
    r.next_state.throughput = throughput;
    r.next_state.prev_pdf = bs.delta ? 0.0 : bs.pdf;   // a delta bounce: no MIS, like the camera ray
    r.next_state.eta_scale = eta_scale;
    r.next_state.dispersion_channel = s.dispersion_channel;
    r.next_state.prev_normal = n_code;
    return r;
}

#endif
