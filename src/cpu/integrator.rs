//! Twin of `shaders/common/integrator.glsl`: one bounce of the path tracer
//! (emission, next-event estimation with MIS, BSDF sampling (Lambert, Phong,
//! mirror, smooth dielectric), Russian roulette). See the GLSL file for the depth convention.

use super::bsdf::{bsdf_eval, bsdf_is_delta, bsdf_pdf, bsdf_sample};
use super::bvh::{Hit, NO_HIT, OVERFLOW_HIT};
use super::intersect::{offset_ray_origin, triangle_point, triangle_point_error};
use super::lights::{environment_light_pdf, sample_light, triangle_light_pdf};
use super::rng::{rng_float, rng_float2};
use super::sampling::{FLT_MAX, power_heuristic};
use crate::constants::*;
use crate::layout::RenderParams;
use crate::packed::PackedScene;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct PathState {
    pub origin: Vec3,
    pub direction: Vec3,
    pub throughput: Vec3,
    pub prev_pdf: f32,
}

pub struct ShadeResult {
    pub emitted: Vec3,
    pub shadow: bool,
    pub shadow_origin: Vec3,
    pub shadow_direction: Vec3,
    pub shadow_t_max: f32,
    pub shadow_contribution: Vec3,
    pub next: bool,
    pub next_state: PathState,
}

pub fn shade_path(
    scene: &PackedScene,
    params: &RenderParams,
    s: &PathState,
    hit: &Hit,
    key: u32,
    bounce: u32,
) -> ShadeResult {
    let mut r = ShadeResult {
        emitted: Vec3::ZERO,
        shadow: false,
        shadow_origin: Vec3::ZERO,
        shadow_direction: Vec3::ZERO,
        shadow_t_max: 0.0,
        shadow_contribution: Vec3::ZERO,
        next: false,
        next_state: *s,
    };

    if hit.triangle == OVERFLOW_HIT {
        return r;
    }
    if hit.triangle == NO_HIT {
        let le = Vec3::from(params.environment);
        if le.max_element() > 0.0 {
            let w = if s.prev_pdf > 0.0 {
                power_heuristic(s.prev_pdf, environment_light_pdf(params))
            } else {
                1.0
            };
            r.emitted = s.throughput * le * w;
        }
        return r;
    }

    let tv = &scene.tri_verts[hit.triangle as usize];
    let (v0, v1, v2) = (Vec3::from(tv.v0), Vec3::from(tv.v1), Vec3::from(tv.v2));
    let p = triangle_point(hit.b12, v0, v1, v2);
    let p_error = triangle_point_error(hit.b12, v0, v1, v2, p);
    let ng_raw = (v1 - v0).cross(v2 - v0);
    let area = 0.5 * ng_raw.length();
    let ng = ng_raw / (2.0 * area);
    let cos_o = s.direction.dot(ng);
    let front = cos_o < 0.0;
    let m = &scene.materials[tv.material as usize];
    let emission = Vec3::from(m.emission);

    if emission.max_element() > 0.0 && (front || m.double_sided != 0) {
        let mut w = 1.0;
        if s.prev_pdf > 0.0 {
            let light_pmf = scene.tri_shading[hit.triangle as usize].light_pmf;
            let light_pdf = triangle_light_pdf(params, light_pmf, area, hit.t, cos_o);
            w = power_heuristic(s.prev_pdf, light_pdf);
        }
        r.emitted = s.throughput * emission * w;
    }

    if bounce + 1 >= params.max_depth || bounce + 1 >= MAX_BOUNCES_HARD {
        return r;
    }

    let n = if front { ng } else { -ng };
    let wo = -s.direction;
    let dim = DIM_BOUNCE_BASE + DIM_PER_BOUNCE * bounce;
    let mut origin = offset_ray_origin(p, p_error, n);

    if !bsdf_is_delta(m) {
        let ls = sample_light(
            scene,
            params,
            p,
            rng_float(key, dim + DIM_LIGHT_SELECT),
            rng_float2(key, dim + DIM_LIGHT_SAMPLE),
        );
        if ls.pdf > 0.0 && n.dot(ls.wi) > 0.0 {
            let f = bsdf_eval(m, n, front, wo, ls.wi);
            let w = power_heuristic(ls.pdf, bsdf_pdf(m, n, front, wo, ls.wi));
            r.shadow_contribution = s.throughput * f * ls.radiance * (w / ls.pdf);
            r.shadow_origin = origin;
            if ls.distance == FLT_MAX {
                r.shadow_direction = ls.wi;
                r.shadow_t_max = FLT_MAX;
            } else {
                // Aim at the sampled point, stop short by its error bound.
                let d = ls.point - origin;
                let len = d.length();
                r.shadow_direction = d / len;
                let short_by = r.shadow_direction.abs().dot(GAMMA7 * ls.point.abs());
                r.shadow_t_max = len * (1.0 - SHADOW_RAY_SHORTEN) - short_by;
            }
            r.shadow = r.shadow_contribution.max_element() > 0.0;
        }
    }

    let bs = bsdf_sample(
        m,
        n,
        front,
        wo,
        rng_float(key, dim + DIM_BSDF_LOBE),
        rng_float2(key, dim + DIM_BSDF_SAMPLE),
    );
    if !bs.delta && !(bs.pdf > 0.0) {
        return r;
    }
    let mut throughput = s.throughput * bs.weight;
    // A refracted ray leaves from the other side of the surface.
    if bs.wi.dot(n) < 0.0 {
        origin = offset_ray_origin(p, p_error, -n);
    }

    if bounce >= RR_START_BOUNCE {
        let q = throughput.max_element().min(RR_MAX_CONTINUE);
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
    };
    r
}
