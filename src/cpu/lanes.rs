//! The CPU back end's lane schedule: eight paths side by side, each stage
//! of a bounce one loop over the lanes, so that the compiler runs the
//! arithmetic in vector registers (AVX2 where the CPU has it). This is the
//! schedule Mitsuba's LLVM variants and Cycles' CPU kernels get their speed
//! from; here it is a schedule only. Every lane calls the same scalar
//! functions as `integrator::shade_path`, in the same order, so each path's
//! radiance is bit for bit the scalar driver's (tested below), and the CPU
//! keeps tracing the kernels' paths.
//!
//! It covers the scenes most renders are: static Lambertian triangles lit
//! by emissive triangles, no textures, no environment, no analytic lights,
//! no auxiliary outputs ([`lanes_cover`]). Other scenes take the scalar
//! driver (`render::trace_path`). A lane whose path ends takes the next path
//! of the row at once, so the lanes stay full; radiance goes to the path's
//! own slot and the film adds the row's samples in the scalar order.

use super::bsdf::{lambert_eval, lambert_pdf, lambert_sample};
use super::bvh::{Hit, NO_HIT, OVERFLOW_HIT};
use super::camera::generate_camera_ray;
use super::dispersion::dispersive;
use super::integrator::PathState;
use super::intersect::{offset_ray_origin, triangle_point, triangle_point_error};
use super::lights::{environment_shines, select_emitter, suns_shine};
use super::rng::{
    RngKey, rng_coverage_seed, rng_float, rng_float2, rng_sampler_key, sobol_float, sobol_float2,
};
use super::rng_avx2::SobolLanes;
use super::sampling::{build_onb, power_heuristic, sample_uniform_triangle};
use super::shading_frame::{interpolate_normal, reconcile_shading_normal, same_side};
use super::textures::{alpha_coverage, material_has_textures};
use super::trace::{closest_hit, shadow_blocker};
use crate::constants::*;
use crate::packed::PackedScene;
use crate::packed::layout::RenderParams;
use glam::{Vec2, Vec3};

/// Paths side by side: one AVX2 register of f32.
const LANES: usize = 8;

/// Whether the lane schedule renders this scene: only the features its
/// shading stages implement (see the module comment). Everything else in
/// `shade_path` is then dead for every path, so skipping it changes nothing.
pub fn lanes_cover(scene: &PackedScene, params: &RenderParams) -> bool {
    scene.motion.is_none()
        && params.aov == 0
        && !environment_shines(params)
        && !(params.env_select_prob > 0.0)
        && !suns_shine(scene)
        && scene.light_params.num_spheres == 0
        && scene.light_params.num_lights == 0
        && scene.materials.iter().all(|m| {
            m.kind == MATERIAL_LAMBERT
                && !material_has_textures(m)
                && m.normal_texture == NO_TEXTURE
                && !(m.thickness > 0.0)
                && !dispersive(m)
                && m.lobes == 0
        })
}

/// One lane's path between bounces.
#[derive(Clone, Copy)]
struct Lane {
    /// The path's slot in the row's results.
    item: usize,
    key: RngKey,
    bounce: u32,
    state: PathState,
    radiance: Vec3,
}

/// What the shading stages hand back per lane: `shade_path`'s result for
/// the features covered.
#[derive(Clone, Copy, Default)]
struct LaneShade {
    emitted: Vec3,
    shadow: bool,
    shadow_origin: Vec3,
    shadow_direction: Vec3,
    shadow_t_max: f32,
    shadow_contribution: Vec3,
    next: bool,
    next_origin: Vec3,
    next_direction: Vec3,
    next_throughput: Vec3,
    next_pdf: f32,
}

/// Traces the paths `paths` (pixel, sample index) with eight lanes and
/// writes each one's radiance to its slot of `radiance`; counts rays as
/// `render::trace_path` does (extension, shadow, overflows).
pub fn trace_paths(
    scene: &PackedScene,
    params: &RenderParams,
    paths: &[(u32, u32)],
    radiance: &mut [Vec3],
    counts: &mut [u64; 3],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked).
        unsafe { trace_paths_avx2(scene, params, paths, radiance, counts) };
        return;
    }
    trace_paths_with::<false>(scene, params, paths, radiance, counts);
}

/// `trace_paths` compiled for AVX2.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn trace_paths_avx2(
    scene: &PackedScene,
    params: &RenderParams,
    paths: &[(u32, u32)],
    radiance: &mut [Vec3],
    counts: &mut [u64; 3],
) {
    trace_paths_with::<true>(scene, params, paths, radiance, counts);
}

/// The schedule; `AVX2`: draw Sobol numbers with `rng_avx2` (only so
/// from `trace_paths_avx2`).
#[inline(always)]
fn trace_paths_with<const AVX2: bool>(
    scene: &PackedScene,
    params: &RenderParams,
    paths: &[(u32, u32)],
    radiance: &mut [Vec3],
    counts: &mut [u64; 3],
) {
    let mut lanes: [Option<Lane>; LANES] = [None; LANES];
    let mut next_path = 0usize;
    let mut hits = [Hit {
        t: 0.0,
        triangle: NO_HIT,
        b12: Vec2::ZERO,
    }; LANES];
    loop {
        // Lanes whose paths ended take the next paths: the camera ray.
        for lane in lanes.iter_mut().filter(|l| l.is_none()) {
            let Some(&(pixel, sample_index)) = paths.get(next_path) else {
                break;
            };
            let key = rng_sampler_key(params.rng_sampler, pixel, sample_index, params.seed);
            let (origin, direction) = generate_camera_ray(scene, params, pixel, key);
            *lane = Some(Lane {
                item: next_path,
                key,
                bounce: 0,
                state: PathState::camera(origin, direction),
                radiance: Vec3::ZERO,
            });
            next_path += 1;
        }
        if lanes.iter().all(Option::is_none) {
            return;
        }
        // Extension rays, one lane at a time (no time: the scene is static).
        for (lane, hit) in lanes.iter().zip(hits.iter_mut()) {
            if let Some(l) = lane {
                counts[0] += 1;
                let seed = rng_coverage_seed(l.key, l.bounce, 0);
                *hit = closest_hit(scene, l.state.origin, l.state.direction, seed, 0.0);
                if hit.triangle == OVERFLOW_HIT {
                    counts[2] += 1;
                }
            }
        }
        let shade = shade_lanes::<AVX2>(scene, params, &lanes, &hits);
        for (lane, r) in lanes.iter_mut().zip(shade.iter()) {
            let Some(l) = lane else { continue };
            l.radiance += r.emitted;
            if r.shadow {
                counts[1] += 1;
                let seed = rng_coverage_seed(l.key, l.bounce, 1);
                match shadow_blocker(
                    scene,
                    r.shadow_origin,
                    r.shadow_direction,
                    r.shadow_t_max,
                    seed,
                    0.0,
                ) {
                    OVERFLOW_HIT => counts[2] += 1,
                    NO_HIT => l.radiance += r.shadow_contribution,
                    _ => {}
                }
            }
            if r.next {
                l.state.origin = r.next_origin;
                l.state.direction = r.next_direction;
                l.state.throughput = r.next_throughput;
                l.state.prev_pdf = r.next_pdf;
                l.bounce += 1;
            } else {
                radiance[l.item] = l.radiance;
                *lane = None;
            }
        }
    }
}

/// `shade_path` for the lanes, restricted to the covered features: every
/// quantity is computed for all eight lanes in one loop (lanes without a
/// triangle hit compute on triangle 0 and are masked at the end).
#[inline(always)]
fn shade_lanes<const AVX2: bool>(
    scene: &PackedScene,
    params: &RenderParams,
    lanes: &[Option<Lane>; LANES],
    hits: &[Hit; LANES],
) -> [LaneShade; LANES] {
    let mut out = [LaneShade::default(); LANES];

    // Gather: the hit triangle, its material and the lane's path. Escaped
    // rays see nothing in covered scenes; overflows end the path.
    let mut shading = [false; LANES];
    let mut s = [PathState::camera(Vec3::ZERO, Vec3::Z); LANES];
    let mut key = [RngKey {
        hash: 0,
        sample_index: 0,
        kind: params.rng_sampler,
        reversed_index: 0,
    }; LANES];
    let mut bounce = [0u32; LANES];
    let mut t = [0f32; LANES];
    let mut b12 = [Vec2::ZERO; LANES];
    let mut v = [[Vec3::ZERO; 3]; LANES];
    let mut sn = [[Vec3::ZERO; 3]; LANES];
    let mut light_pmf = [0f32; LANES];
    let mut albedo = [Vec3::ZERO; LANES];
    let mut emission = [Vec3::ZERO; LANES];
    let mut double_sided = [false; LANES];
    for l in 0..LANES {
        let (Some(lane), hit) = (&lanes[l], &hits[l]) else {
            continue;
        };
        let tri = hit.triangle;
        if tri == NO_HIT || tri == OVERFLOW_HIT || tri & LIGHT_HIT_FLAG != 0 {
            continue;
        }
        shading[l] = true;
        s[l] = lane.state;
        key[l] = lane.key;
        bounce[l] = lane.bounce;
        t[l] = hit.t;
        b12[l] = hit.b12;
        let tv = &scene.tri_verts[tri as usize];
        v[l] = [tv.v0.into(), tv.v1.into(), tv.v2.into()];
        let sh = &scene.tri_shading[tri as usize];
        sn[l] = [sh.n0.into(), sh.n1.into(), sh.n2.into()];
        light_pmf[l] = sh.light_pmf;
        let m = &scene.materials[tv.material as usize];
        albedo[l] = Vec3::from(m.base_color);
        emission[l] = Vec3::from(m.emission);
        double_sided[l] = m.double_sided != 0;
    }

    // The surface: the point, its normals and the shading frame.
    let mut p = [Vec3::ZERO; LANES];
    let mut p_error = [Vec3::ZERO; LANES];
    let mut n = [Vec3::ZERO; LANES];
    let mut ns = [Vec3::ZERO; LANES];
    let mut frame_t = [Vec3::ZERO; LANES];
    let mut frame_b = [Vec3::ZERO; LANES];
    let tri_select_prob = scene.light_params.tri_select_prob;
    for l in 0..LANES {
        let [v0, v1, v2] = v[l];
        p[l] = triangle_point(b12[l], v0, v1, v2);
        p_error[l] = triangle_point_error(b12[l], v0, v1, v2, p[l]);
        let ng_raw = (v1 - v0).cross(v2 - v0);
        let area = 0.5 * ng_raw.length();
        let ng = ng_raw / (2.0 * area);
        let cos_o = s[l].direction.dot(ng);
        let front = cos_o < 0.0;
        if emission[l].max_element() > 0.0 && (front || double_sided[l]) {
            let mut w = 1.0;
            if s[l].prev_pdf > 0.0 {
                // triangle_light_pdf
                let light_pdf = tri_select_prob * light_pmf[l] / area * t[l] * t[l] / cos_o.abs();
                w = power_heuristic(s[l].prev_pdf, light_pdf);
            }
            out[l].emitted = s[l].throughput * emission[l] * w;
        }
        n[l] = if front { ng } else { -ng };
        let wo = -s[l].direction;
        let [sn0, sn1, sn2] = sn[l];
        let n_vertex = interpolate_normal(sn0, sn1, sn2, b12[l], ng);
        let ns_side = if front { n_vertex } else { -n_vertex };
        ns[l] = reconcile_shading_normal(n[l], ns_side, wo);
        (frame_t[l], frame_b[l]) = build_onb(ns[l]);
    }

    // A path may add a segment only while it stays within max_depth.
    let mut grows = [false; LANES];
    for l in 0..LANES {
        grows[l] =
            shading[l] && bounce[l] + 1 < params.max_depth && bounce[l] + 1 < MAX_BOUNCES_HARD;
    }
    if !grows.iter().any(|&g| g) {
        mask_to(&mut out, &shading);
        return out;
    }

    // The bounce's random numbers (the BSDF lobe's is not drawn: Lambert
    // has one lobe, and a draw changes nothing else).
    let mut u_select = [0f32; LANES];
    let mut u_light = [Vec2::ZERO; LANES];
    let mut u_bsdf = [Vec2::ZERO; LANES];
    let mut u_rr = [0f32; LANES];
    if params.rng_sampler == SAMPLER_SOBOL {
        let dim: [u32; LANES] =
            std::array::from_fn(|l| DIM_BOUNCE_BASE + DIM_PER_BOUNCE * bounce[l]);
        let at = |offset: u32| dim.map(|d| d + offset);
        let sobol = SobolLanes {
            hash: key.map(|k| k.hash),
            reversed: key.map(|k| k.reversed_index),
        };
        if AVX2 {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `AVX2` only where the CPU has it (`trace_paths`).
            unsafe {
                u_select = sobol.float(&at(DIM_LIGHT_SELECT));
                let (x, y) = sobol.float2(&at(DIM_LIGHT_SAMPLE));
                u_light = std::array::from_fn(|l| Vec2::new(x[l], y[l]));
                let (x, y) = sobol.float2(&at(DIM_BSDF_SAMPLE));
                u_bsdf = std::array::from_fn(|l| Vec2::new(x[l], y[l]));
                u_rr = sobol.float(&at(DIM_RUSSIAN_ROULETTE));
            }
        } else {
            for l in 0..LANES {
                u_select[l] = sobol_float(key[l], dim[l] + DIM_LIGHT_SELECT);
                u_light[l] = sobol_float2(key[l], dim[l] + DIM_LIGHT_SAMPLE);
                u_bsdf[l] = sobol_float2(key[l], dim[l] + DIM_BSDF_SAMPLE);
                u_rr[l] = sobol_float(key[l], dim[l] + DIM_RUSSIAN_ROULETTE);
            }
        }
    } else {
        for l in 0..LANES {
            let dim = DIM_BOUNCE_BASE + DIM_PER_BOUNCE * bounce[l];
            u_select[l] = rng_float(key[l], dim + DIM_LIGHT_SELECT);
            u_light[l] = rng_float2(key[l], dim + DIM_LIGHT_SAMPLE);
            u_bsdf[l] = rng_float2(key[l], dim + DIM_BSDF_SAMPLE);
            u_rr[l] = rng_float(key[l], dim + DIM_RUSSIAN_ROULETTE);
        }
    }

    // Rays leave from the side they go to.
    let mut origin_front = [Vec3::ZERO; LANES];
    let mut origin_back = [Vec3::ZERO; LANES];
    for l in 0..LANES {
        origin_front[l] = offset_ray_origin(p[l], p_error[l], n[l]);
        origin_back[l] = offset_ray_origin(p[l], p_error[l], -n[l]);
    }

    // Light selection (`sample_light`'s triangle branch: covered scenes
    // have no environment and no analytic lights).
    let p_env = params.env_select_prob;
    let mut picked = [false; LANES];
    let mut e_v = [[Vec3::ZERO; 3]; LANES];
    let mut e_pmf = [0f32; LANES];
    let mut e_area = [1f32; LANES];
    let mut e_radiance = [Vec3::ZERO; LANES];
    let mut e_double_sided = [false; LANES];
    for l in 0..LANES {
        if !grows[l] || !(u_select[l] < p_env + tri_select_prob) || params.num_emitters == 0 {
            continue;
        }
        picked[l] = true;
        let u_tri = ((u_select[l] - p_env) / tri_select_prob).min(0.999_999_94);
        let e = scene.emitters[select_emitter(scene, params, u_tri) as usize];
        let tv = &scene.tri_verts[e.triangle as usize];
        e_v[l] = [tv.v0.into(), tv.v1.into(), tv.v2.into()];
        e_pmf[l] = e.pmf;
        e_area[l] = e.area;
        let m = &scene.materials[tv.material as usize];
        e_radiance[l] = Vec3::from(m.emission) * alpha_coverage(m.alpha, m.alpha_cutoff);
        e_double_sided[l] = m.double_sided != 0;
    }

    // The light sample and next-event estimation (Lambert: f and pdf
    // about the shading normal).
    for l in 0..LANES {
        let [v0, v1, v2] = e_v[l];
        let b = sample_uniform_triangle(u_light[l]);
        let point = (1.0 - b.x - b.y) * v0 + b.x * v1 + b.y * v2;
        let en = (v1 - v0).cross(v2 - v0).normalize();
        let to_light = point - p[l];
        let dist2 = to_light.dot(to_light);
        let distance = dist2.sqrt();
        let wi = to_light / distance;
        let cos_light = -en.dot(wi);
        // sample_light's test as written there (NaNs included).
        let unlit = !picked[l]
            || !(dist2 > 0.0)
            || cos_light.abs() < 1e-7
            || (cos_light < 0.0 && !e_double_sided[l]);
        let pdf = tri_select_prob * e_pmf[l] / e_area[l] * dist2 / cos_light.abs();
        if !unlit && pdf > 0.0 && same_side(n[l], ns[l], wi) {
            let f = lambert_eval(albedo[l], ns[l], wi);
            let w = power_heuristic(pdf, lambert_pdf(ns[l], wi));
            let c = s[l].throughput * f * e_radiance[l] * (w / pdf);
            out[l].shadow_contribution = c;
            // aim_shadow_ray, at the sampled point.
            let origin = if wi.dot(n[l]) > 0.0 {
                origin_front[l]
            } else {
                origin_back[l]
            };
            let d = point - origin;
            let len = d.length();
            let dir = d / len;
            let short_by = dir.abs().dot(GAMMA7 * point.abs());
            out[l].shadow_origin = origin;
            out[l].shadow_direction = dir;
            out[l].shadow_t_max = len * (1.0 - SHADOW_RAY_SHORTEN) - short_by;
            out[l].shadow = c.max_element() > 0.0;
        }
    }

    // The BSDF sample, Russian roulette and the next segment.
    for l in 0..LANES {
        if !grows[l] {
            continue;
        }
        let frame = super::bsdf::ShadingFrame {
            n: ns[l],
            t: frame_t[l],
            b: frame_b[l],
            coat_n: ns[l],
        };
        let bs = lambert_sample(albedo[l], &frame, u_bsdf[l]);
        if !(bs.pdf > 0.0) || !same_side(n[l], ns[l], bs.wi) {
            continue;
        }
        let mut throughput = s[l].throughput * bs.weight;
        let crossed = bs.wi.dot(n[l]) < 0.0;
        let origin = if crossed {
            origin_back[l]
        } else {
            origin_front[l]
        };
        if bounce[l] >= RR_START_BOUNCE {
            let q = (throughput.max_element() * s[l].eta_scale).min(RR_MAX_CONTINUE);
            if u_rr[l] >= q {
                continue;
            }
            throughput /= q;
        }
        if !(throughput.max_element() > 0.0) {
            continue;
        }
        out[l].next = true;
        out[l].next_origin = origin;
        out[l].next_direction = bs.wi;
        out[l].next_throughput = throughput;
        out[l].next_pdf = bs.pdf;
    }
    mask_to(&mut out, &shading);
    out
}

/// Clears the results of lanes that did not shade a surface.
fn mask_to(out: &mut [LaneShade; LANES], shading: &[bool; LANES]) {
    for (o, &s) in out.iter_mut().zip(shading) {
        if !s {
            *o = LaneShade::default();
        }
    }
}
