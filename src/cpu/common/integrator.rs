//! Twin of `shaders/common/integrator.glsl`: one bounce of the path tracer
//! (emission, volume absorption, the shading frame, next-event estimation
//! with MIS, BSDF sampling (Lambert, Phong, mirror, glTF metallic-roughness
//! with transmission), Russian roulette). See the GLSL file for the depth convention.

use super::bsdf::{
    bsdf_albedo, bsdf_eval, bsdf_is_delta, bsdf_pdf, bsdf_sample, gltf_eta,
    gltf_has_diffuse_transmission, gltf_thin,
};
use super::bvh::{Hit, NO_HIT, OVERFLOW_HIT, triangle_at};
use super::dispersion::{
    dispersion_channel_weight, dispersion_ior, dispersion_pick_channel, dispersive,
};
use super::instances::{hit_slot, instance_error, instance_facing, world_normals, world_triangle};
use super::intersect::{offset_ray_origin, triangle_point, triangle_point_error};
use super::light_bvh::{
    light_tree_normal, light_tree_normal_code, light_tree_on, light_tree_triangle_pmf,
};
use super::lights::{
    LightSample, environment_light_pdf, environment_radiance, environment_shines, sample_light,
    sphere_emission, sun_emission, suns_shine, triangle_light_pdf,
};
use super::motion::{moving_triangle_normals, time_of_path};
use super::rng::{RngKey, rng_float, rng_float2};
use super::sampling::{FLT_MAX, power_heuristic};
use super::shading_frame::{
    interpolate_normal, reconcile_shading_normal, same_side, shading_frame,
};
use super::textures::{apply_normal_map, apply_textures, material_has_textures, texture_footprint};
use crate::constants::*;
use crate::packed::PackedScene;
use crate::packed::layout::RenderParams;
use glam::Vec3;

/// Whether the light BVH bounds with the surface's normal (one-sided): a
/// material that only reflects and has a lobe that is not delta (twin:
/// integrator.glsl).
pub fn light_tree_receiving_normal(m: &crate::packed::layout::MaterialData) -> bool {
    if bsdf_is_delta(m) {
        return false;
    }
    !(m.kind == MATERIAL_GLTF && (m.transmission > 0.0 || gltf_has_diffuse_transmission(m)))
}

#[derive(Clone, Copy, Debug)]
pub struct PathState {
    pub origin: Vec3,
    pub direction: Vec3,
    pub throughput: Vec3,
    pub prev_pdf: f32,
    /// The product of η² over the refractions so far (η = n_t / n_o): the
    /// throughput carries 1/η² per refraction, which Russian roulette undoes
    /// so that paths inside glass are not killed for it (as Mitsuba does).
    pub eta_scale: f32,
    /// `KHR_materials_dispersion`: the colour channel the path carries since
    /// its first dispersive surface (1 red, 2 green, 3 blue), 0 before.
    pub dispersion_channel: u32,
    /// The light BVH's receiving normal at the vertex the ray left
    /// (`light_tree_normal_code`; 0: none, as from the camera): MIS bounds
    /// with the normal light sampling bounded with there.
    pub prev_normal: u32,
}

impl PathState {
    /// A path at its camera ray (twin: camera_path_state in integrator.glsl).
    pub fn camera(origin: Vec3, direction: Vec3) -> PathState {
        PathState {
            origin,
            direction,
            throughput: Vec3::ONE,
            prev_pdf: 0.0,
            eta_scale: 1.0,
            dispersion_channel: 0,
            prev_normal: 0,
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct ShadeResult {
    pub emitted: Vec3,
    pub shadow: bool,
    pub shadow_origin: Vec3,
    pub shadow_direction: Vec3,
    pub shadow_t_max: f32,
    pub shadow_contribution: Vec3,
    pub next: bool,
    pub next_state: PathState,
    /// What the auxiliary outputs see here (`aov.rs`), when the ray came
    /// from the camera or a delta bounce (prev_pdf 0) and ends the delta chain.
    pub aov_event: bool,
    pub aov_albedo: Vec3,
    pub aov_normal: Vec3,
}

impl ShadeResult {
    /// Nothing emitted, no shadow ray, the path ends (state `s` kept).
    pub fn ends(s: &PathState) -> ShadeResult {
        ShadeResult {
            emitted: Vec3::ZERO,
            shadow: false,
            shadow_origin: Vec3::ZERO,
            shadow_direction: Vec3::ZERO,
            shadow_t_max: 0.0,
            shadow_contribution: Vec3::ZERO,
            next: false,
            next_state: *s,
            aov_event: false,
            aov_albedo: Vec3::ZERO,
            aov_normal: Vec3::ZERO,
        }
    }
}

/// The shadow ray of light sample `ls` from `origin`: at the sampled point
/// itself, stopping short of it by its error bound (gamma(7) |point|), so
/// it cannot hit the light; along `wi`, unbounded, for a light at infinity.
fn aim_shadow_ray(r: &mut ShadeResult, origin: Vec3, ls: &LightSample) {
    r.shadow_origin = origin;
    if ls.distance == FLT_MAX {
        r.shadow_direction = ls.wi;
        r.shadow_t_max = FLT_MAX;
    } else {
        let d = ls.point - origin;
        let len = d.length();
        r.shadow_direction = d / len;
        let short_by = r.shadow_direction.abs().dot(GAMMA7 * ls.point.abs());
        r.shadow_t_max = len * (1.0 - SHADOW_RAY_SHORTEN) - short_by;
    }
}

/// What a ray that left the scene sees: the environment (unless hidden
/// from camera rays) and sun disks, with MIS against light sampling.
fn shade_escaped(
    scene: &PackedScene,
    params: &RenderParams,
    s: &PathState,
    bounce: u32,
    aov: bool,
    r: &mut ShadeResult,
) {
    if environment_shines(params) && !(bounce == 0 && scene.light_params.env_hidden != 0) {
        let le = environment_radiance(scene, params, s.direction);
        let w = if s.prev_pdf > 0.0 {
            power_heuristic(
                s.prev_pdf,
                environment_light_pdf(scene, params, s.direction),
            )
        } else {
            1.0
        };
        r.emitted = s.throughput * le * w;
        // The environment as seen is the albedo of an escaped ray.
        if aov {
            r.aov_albedo = le.min(Vec3::ONE);
        }
    }
    // Sun disks only where there are some (see integrator.glsl).
    if suns_shine(scene) {
        r.emitted += s.throughput * sun_emission(scene, s.direction, s.prev_pdf);
    }
    r.aov_event = aov;
}

pub fn shade_path(
    scene: &PackedScene,
    params: &RenderParams,
    s: &PathState,
    hit: &Hit,
    key: RngKey,
    bounce: u32,
) -> ShadeResult {
    let mut r = ShadeResult::ends(s);
    let aov = params.aov != 0 && s.prev_pdf == 0.0;

    if hit.triangle == OVERFLOW_HIT {
        return r;
    }
    if hit.triangle == NO_HIT {
        shade_escaped(scene, params, s, bounce, aov, &mut r);
        return r;
    }
    if hit.triangle & LIGHT_HIT_FLAG != 0 {
        let k = hit.triangle & !LIGHT_HIT_FLAG;
        let o_normal = light_tree_normal(s.prev_normal);
        let emission = |prev_pdf: f32| {
            sphere_emission(
                scene,
                params,
                k,
                s.origin,
                o_normal,
                s.direction,
                hit.t,
                prev_pdf,
            )
        };
        r.emitted = s.throughput * emission(s.prev_pdf);
        if aov {
            r.aov_albedo = emission(0.0).min(Vec3::ONE);
        }
        r.aov_event = aov;
        return r;
    }

    let time = time_of_path(scene, key); // the path's moment in the shutter
    // The triangle's slot and the instance that places it (instances.rs).
    let (tri, inst) = hit_slot(scene, hit.triangle);
    let tv = &scene.tri_verts[tri as usize];
    let [v0, v1, v2] = world_triangle(scene, inst, triangle_at(scene, tri, time));
    let p = triangle_point(hit.b12, v0, v1, v2);
    let mut p_error = triangle_point_error(hit.b12, v0, v1, v2, p);
    if inst != NO_INSTANCE {
        p_error += instance_error(scene, inst, p);
    }
    let ng_raw = (v1 - v0).cross(v2 - v0) * instance_facing(scene, inst);
    let area = 0.5 * ng_raw.length();
    let ng = ng_raw / (2.0 * area);
    let cos_o = s.direction.dot(ng);
    let front = cos_o < 0.0;
    let untextured = &scene.materials[tv.material as usize];
    let textured;
    let m = if material_has_textures(untextured) {
        let footprint = texture_footprint(scene, params, tri, [v0, v1, v2], p);
        textured = apply_textures(scene, untextured, tri, hit.b12, footprint);
        &textured
    } else {
        untextured
    };
    let emission = Vec3::from(m.emission);

    // Beer–Lambert: a ray reaching the back face of a closed volume
    // (thickness > 0) travelled `t` inside it.
    let mut s = *s;
    if !front && m.thickness > 0.0 {
        let a = Vec3::from(m.attenuation) * -hit.t;
        s.throughput *= Vec3::new(a.x.exp(), a.y.exp(), a.z.exp());
    }

    if emission.max_element() > 0.0 && (front || m.double_sided != 0) {
        let mut w = 1.0;
        if s.prev_pdf > 0.0 {
            let light_pdf = if light_tree_on(scene) {
                // The light BVH's choice at the point the ray left from,
                // with its normal.
                let o_normal = light_tree_normal(s.prev_normal);
                light_tree_triangle_pmf(scene, params, hit.triangle, s.origin, o_normal) / area
                    * hit.t
                    * hit.t
                    / cos_o.abs()
            } else {
                // Per unit area in a two-level scene (packed::instanced_emitters).
                let mut light_pmf = scene.tri_shading[tri as usize].light_pmf;
                if inst != NO_INSTANCE {
                    light_pmf *= area;
                }
                triangle_light_pdf(scene, light_pmf, area, hit.t, cos_o)
            };
            w = power_heuristic(s.prev_pdf, light_pdf);
        }
        r.emitted = s.throughput * emission * w;
    }

    // Dispersion (dispersion.rs): from here on the path keeps one channel.
    let dispersed;
    let m = if dispersive(m) {
        if s.dispersion_channel == 0 {
            let d = DIM_BOUNCE_BASE + DIM_PER_BOUNCE * bounce + DIM_DISPERSION_CHANNEL;
            s.dispersion_channel = dispersion_pick_channel(rng_float(key, d));
            s.throughput *= dispersion_channel_weight(s.dispersion_channel);
        }
        let mut d = *m;
        d.ior = dispersion_ior(m.ior, m.dispersion, s.dispersion_channel);
        dispersed = d;
        &dispersed
    } else {
        m
    };

    let n = if front { ng } else { -ng };
    let wo = -s.direction;
    // Shading normal: interpolated vertex normals on wo's side, reconciled
    // with the geometric normal (shading_frame.rs).
    let [sn0, sn1, sn2] = match &scene.motion {
        Some(motion) => moving_triangle_normals(scene, motion, tri, time),
        None => {
            let sh = &scene.tri_shading[tri as usize];
            world_normals(scene, inst, [sh.n0.into(), sh.n1.into(), sh.n2.into()])
        }
    };
    let n_vertex = interpolate_normal(sn0, sn1, sn2, hit.b12, ng);
    let ns = if m.normal_texture != NO_TEXTURE {
        apply_normal_map(scene, m, tri, inst, hit.b12, time, n_vertex)
    } else {
        n_vertex
    };
    let ns = if front { ns } else { -ns };
    let ns = reconcile_shading_normal(n, ns, wo);
    let frame = shading_frame(
        scene, m, tri, inst, hit.b12, time, n, n_vertex, ns, front, wo,
    );
    // The first surface that is not a mirror or smooth glass ends the chain.
    if aov && !bsdf_is_delta(m) {
        r.aov_event = true;
        r.aov_albedo = bsdf_albedo(m);
        r.aov_normal = ns;
    }

    // A path may add a segment only while it stays within max_depth.
    if bounce + 1 >= params.max_depth || bounce + 1 >= MAX_BOUNCES_HARD {
        return r;
    }
    let dim = DIM_BOUNCE_BASE + DIM_PER_BOUNCE * bounce;
    // Rays leave from the side they go to; most go to n's side.
    let origin_front = offset_ray_origin(p, p_error, n);
    let origin_toward = |d: Vec3| {
        if d.dot(n) > 0.0 {
            origin_front
        } else {
            offset_ray_origin(p, p_error, -n)
        }
    };

    // The light BVH bounds cos theta_i with n as the path state carries it
    // (the same f32 normal where MIS meets the path's next ray), where the
    // surface only reflects.
    let n_code = if light_tree_on(scene) && light_tree_receiving_normal(m) {
        light_tree_normal_code(n)
    } else {
        0
    };
    if !bsdf_is_delta(m) {
        let ls = sample_light(
            scene,
            params,
            p,
            origin_front,
            light_tree_normal(n_code),
            rng_float(key, dim + DIM_LIGHT_SELECT),
            rng_float2(key, dim + DIM_LIGHT_SAMPLE),
            time,
        );
        if ls.pdf > 0.0 && same_side(n, ns, ls.wi) {
            let f = bsdf_eval(m, &frame, front, wo, ls.wi);
            let w = if ls.delta {
                1.0
            } else {
                power_heuristic(ls.pdf, bsdf_pdf(m, &frame, front, wo, ls.wi))
            };
            r.shadow_contribution = s.throughput * f * ls.radiance * (w / ls.pdf);
            // From the side the light is on (transmission reaches through).
            aim_shadow_ray(&mut r, origin_toward(ls.wi), &ls);
            r.shadow = r.shadow_contribution.max_element() > 0.0;
        }
    }

    let bs = bsdf_sample(
        m,
        &frame,
        front,
        wo,
        rng_float(key, dim + DIM_BSDF_LOBE),
        rng_float2(key, dim + DIM_BSDF_SAMPLE),
    );
    if (!bs.delta && !(bs.pdf > 0.0)) || !same_side(n, ns, bs.wi) {
        return r;
    }
    let mut throughput = s.throughput * bs.weight;
    // A refracted ray leaves from the other side of the surface.
    let crossed = bs.wi.dot(n) < 0.0;
    let origin = if crossed {
        offset_ray_origin(p, p_error, -n)
    } else {
        origin_front
    };
    let mut eta_scale = s.eta_scale;
    if crossed && m.kind == MATERIAL_GLTF && !gltf_thin(m) {
        let eta = gltf_eta(m, front);
        eta_scale *= eta * eta;
    }

    if bounce >= RR_START_BOUNCE {
        let q = (throughput.max_element() * eta_scale).min(RR_MAX_CONTINUE);
        if rng_float(key, dim + DIM_RUSSIAN_ROULETTE) >= q {
            return r;
        }
        throughput /= q;
    }
    if !(throughput.max_element() > 0.0) {
        return r;
    }

    r.next = true;
    r.next_state = PathState {
        origin,
        direction: bs.wi,
        throughput,
        // A delta bounce: no MIS, like the camera ray.
        prev_pdf: if bs.delta { 0.0 } else { bs.pdf },
        eta_scale,
        dispersion_channel: s.dispersion_channel,
        prev_normal: n_code,
    };
    r
}
