//! Twin of `shaders/common/lights.glsl`: light selection, the environment
//! map's importance sampling, analytic lights (point, spot, directional,
//! spheres, suns) and the pdfs MIS needs. See the GLSL file for the model.

use super::bvh::NO_HIT;
use super::instances::{hit_slot, instance_facing, world_triangle};
use super::light_bvh::{light_tree_light_pmf, light_tree_on, light_tree_sample};
use super::sampling::{
    FLT_MAX, INV_PI, build_onb, power_heuristic, sample_uniform_sphere, sample_uniform_triangle,
    uniform_sphere_pdf,
};
use crate::constants::*;
use crate::packed::PackedScene;
use crate::packed::layout::{Emitter, Light, RenderParams};
use glam::{UVec2, Vec2, Vec3};
use std::f32::consts::PI;

pub struct LightSample {
    pub point: Vec3,
    pub normal: Vec3,
    pub wi: Vec3,
    pub distance: f32,
    pub radiance: Vec3,
    pub pdf: f32,
    pub delta: bool,
}

pub fn select_emitter(scene: &PackedScene, params: &RenderParams, u: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, params.num_emitters - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        // Selects, not a branch: u falls on either side at random.
        let above = scene.emitters[mid as usize].cdf <= u;
        lo = if above { mid + 1 } else { lo };
        hi = if above { hi } else { mid };
    }
    lo
}

pub fn select_light(scene: &PackedScene, u: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, scene.light_params.num_lights - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if scene.lights[mid as usize].cdf <= u {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

// ---- Environment ----------------------------------------------------------

pub fn env_search(scene: &PackedScene, base: u32, n: u32, u: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, n - 1);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if scene.env_cdf[(base + mid) as usize] <= u {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    lo
}

pub fn env_direction(scene: &PackedScene, u: f32, v: f32) -> Vec3 {
    let theta = PI * v;
    let phi = 2.0 * PI * (u - 0.5);
    let st = theta.sin();
    let d = Vec3::new(st * phi.sin(), theta.cos(), -st * phi.cos());
    let (c, s) = (
        scene.light_params.env_rot_cos,
        scene.light_params.env_rot_sin,
    );
    Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
}

pub fn env_texel_of(scene: &PackedScene, d: Vec3) -> UVec2 {
    let lp = &scene.light_params;
    let (c, s) = (lp.env_rot_cos, lp.env_rot_sin);
    let m = Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    let v = m.y.clamp(-1.0, 1.0).acos() * INV_PI;
    let u = m.x.atan2(-m.z) * (0.5 * INV_PI) + 0.5;
    let (w, h) = (lp.env_width, lp.env_height);
    UVec2::new(
        ((u * w as f32) as u32).min(w - 1),
        ((v * h as f32) as u32).min(h - 1),
    )
}

pub fn env_texel_pdf(scene: &PackedScene, t: UVec2, sin_theta: f32) -> f32 {
    let (w, h) = (scene.light_params.env_width, scene.light_params.env_height);
    let cdf = &scene.env_cdf;
    let row = (h + 1 + t.y * (w + 1)) as usize;
    let p_row = cdf[t.y as usize + 1] - cdf[t.y as usize];
    let p_col = cdf[row + t.x as usize + 1] - cdf[row + t.x as usize];
    if !(sin_theta > 0.0) {
        return 0.0;
    }
    (p_row * h as f32) * (p_col * w as f32) / (2.0 * PI * PI * sin_theta)
}

pub fn environment_radiance(scene: &PackedScene, params: &RenderParams, d: Vec3) -> Vec3 {
    let env = Vec3::from(params.environment);
    if scene.light_params.env_width == 0 {
        return env;
    }
    let t = env_texel_of(scene, d);
    let texel = scene.env_radiance[(t.y * scene.light_params.env_width + t.x) as usize];
    env * Vec3::new(texel[0], texel[1], texel[2])
}

pub fn environment_direction_pdf(scene: &PackedScene, d: Vec3) -> f32 {
    let lp = &scene.light_params;
    if lp.env_width == 0 || lp.env_sampling == ENV_SAMPLE_UNIFORM {
        return uniform_sphere_pdf();
    }
    let t = env_texel_of(scene, d);
    let (c, s) = (lp.env_rot_cos, lp.env_rot_sin);
    let mxz = Vec2::new(c * d.x - s * d.z, s * d.x + c * d.z);
    env_texel_pdf(scene, t, mxz.length())
}

pub fn sample_environment(
    scene: &PackedScene,
    params: &RenderParams,
    u: Vec2,
    ls: &mut LightSample,
) {
    let lp = &scene.light_params;
    ls.distance = FLT_MAX;
    if lp.env_width == 0 || lp.env_sampling == ENV_SAMPLE_UNIFORM {
        ls.wi = sample_uniform_sphere(u);
        ls.radiance = environment_radiance(scene, params, ls.wi);
        ls.pdf = uniform_sphere_pdf();
        return;
    }
    let (w, h) = (lp.env_width, lp.env_height);
    let cdf = &scene.env_cdf;
    let y = env_search(scene, 0, h, u.y);
    let r0 = cdf[y as usize];
    let dv = (u.y - r0) / (cdf[y as usize + 1] - r0);
    let row = h + 1 + y * (w + 1);
    let x = env_search(scene, row, w, u.x);
    let c0 = cdf[(row + x) as usize];
    let du = (u.x - c0) / (cdf[(row + x) as usize + 1] - c0);
    let v = (y as f32 + dv) / h as f32;
    ls.wi = env_direction(scene, (x as f32 + du) / w as f32, v);
    let texel = scene.env_radiance[(y * w + x) as usize];
    ls.radiance = Vec3::from(params.environment) * Vec3::new(texel[0], texel[1], texel[2]);
    ls.pdf = env_texel_pdf(scene, UVec2::new(x, y), (PI * v).sin());
}

// ---- Analytic lights -------------------------------------------------------

pub fn range_window(range: f32, dist: f32) -> f32 {
    if !(range > 0.0) {
        return 1.0;
    }
    let q = dist / range;
    let q2 = q * q;
    (1.0 - q2 * q2).clamp(0.0, 1.0)
}

pub fn spot_falloff(l: &Light, cos_axis: f32) -> f32 {
    let a = (cos_axis * l.spot_scale + l.spot_offset).clamp(0.0, 1.0);
    a * a
}

/// Returns (direction, cos_theta, sin2_theta).
pub fn sample_cone(w: Vec3, one_minus_cos_max: f32, u: Vec2) -> (Vec3, f32, f32) {
    let omc = u.x * one_minus_cos_max;
    let cos_theta = 1.0 - omc;
    let sin2_theta = omc * (2.0 - omc);
    let sin_theta = sin2_theta.max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let (t, b) = build_onb(w);
    (
        sin_theta * phi.cos() * t + sin_theta * phi.sin() * b + cos_theta * w,
        cos_theta,
        sin2_theta,
    )
}

pub fn cone_pdf(one_minus_cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * one_minus_cos_max)
}

pub fn sphere_one_minus_cos_max(r: f32, dc2: f32) -> f32 {
    let sin2 = (r * r / dc2).min(1.0);
    sin2 / (1.0 + (1.0 - sin2).max(0.0).sqrt())
}

pub fn sphere_cone_pdf(l: &Light, p: Vec3) -> f32 {
    let pc = Vec3::from(l.position) - p;
    let dc2 = pc.dot(pc);
    if !(dc2 > l.radius * l.radius) {
        return 0.0;
    }
    cone_pdf(sphere_one_minus_cos_max(l.radius, dc2))
}

pub fn sample_sphere_light(l: &Light, p: Vec3, u: Vec2, ls: &mut LightSample) {
    let centre = Vec3::from(l.position);
    let pc = centre - p;
    let dc2 = pc.dot(pc);
    let r = l.radius;
    if !(dc2 > r * r) {
        return;
    }
    let dc = dc2.sqrt();
    let w = pc / dc;
    let sin2_max = (r * r / dc2).min(1.0);
    let omc_max = sphere_one_minus_cos_max(r, dc2);
    let (_, cos_theta, sin2_theta) = sample_cone(w, omc_max, u);
    let sin_max = sin2_max.sqrt();
    let ratio = (sin2_theta / sin2_max).min(1.0);
    let cos_alpha =
        (sin2_theta / sin_max + cos_theta * (1.0 - ratio).max(0.0).sqrt()).clamp(-1.0, 1.0);
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    // The point's azimuth is dir's (sample_cone's frame), taken from the
    // frame itself: dir minus its w component cancels badly for small cones.
    let (t, b) = build_onb(w);
    let phi = 2.0 * PI * u.y;
    let side = phi.cos() * t + phi.sin() * b;
    let n = -cos_alpha * w + sin_alpha * side;
    ls.point = centre + r * n;
    let to_light = ls.point - p;
    ls.distance = to_light.length();
    if !(ls.distance > 0.0) {
        return;
    }
    ls.wi = to_light / ls.distance;
    ls.normal = n;
    ls.radiance = l.emission.into();
    ls.pdf = cone_pdf(omc_max);
}

pub fn sample_analytic_light(l: &Light, p: Vec3, u: Vec2, ls: &mut LightSample) {
    let direction = Vec3::from(l.direction);
    if l.kind == LIGHT_SPHERE {
        sample_sphere_light(l, p, u, ls);
        return;
    }
    if l.kind == LIGHT_SUN {
        ls.wi = sample_cone(-direction, l.one_minus_cos_max, u).0;
        ls.distance = FLT_MAX;
        ls.radiance = l.emission.into();
        ls.pdf = cone_pdf(l.one_minus_cos_max);
        return;
    }
    ls.delta = true;
    if l.kind == LIGHT_DIRECTIONAL {
        ls.wi = -direction;
        ls.distance = FLT_MAX;
        ls.radiance = l.emission.into();
        ls.pdf = 1.0;
        return;
    }
    let to_light = Vec3::from(l.position) - p;
    let dist2 = to_light.dot(to_light);
    if !(dist2 > 0.0) {
        return;
    }
    let dist = dist2.sqrt();
    ls.point = l.position.into();
    ls.normal = Vec3::ZERO;
    ls.distance = dist;
    ls.wi = to_light / dist;
    let mut a = range_window(l.range, dist) / dist2;
    if l.kind == LIGHT_SPOT {
        a *= spot_falloff(l, direction.dot(-ls.wi));
    }
    ls.radiance = Vec3::from(l.emission) * a;
    ls.pdf = if a > 0.0 { 1.0 } else { 0.0 };
}

// ---- Selection ---------------------------------------------------------------

/// Samples a point of emitter `e` for `p` (see `sample_emitter` in
/// lights.glsl for `select_pmf` and `per_area`).
#[allow(clippy::too_many_arguments)]
pub fn sample_emitter(
    scene: &PackedScene,
    e: &Emitter,
    p: Vec3,
    u: Vec2,
    time: f32,
    select_pmf: f32,
    per_area: bool,
    ls: &mut LightSample,
) {
    // The emitter's slot, and the instance that places it (instances.rs).
    let (tri, inst) = hit_slot(scene, e.triangle);
    let tv = &scene.tri_verts[tri as usize];
    let [v0, v1, v2] = world_triangle(scene, inst, super::bvh::triangle_at(scene, tri, time));
    // A moving triangle's area is the one at `time`, as shade_path
    // computes it where a ray finds the emitter; it may be 0 then. The
    // light BVH takes the area shade_path finds too.
    let mut area = e.area;
    if scene.motion.is_some() || !per_area {
        area = 0.5 * (v1 - v0).cross(v2 - v0).length();
        if !(area > 0.0) {
            return;
        }
    }
    let b = sample_uniform_triangle(u);
    ls.point = (1.0 - b.x - b.y) * v0 + b.x * v1 + b.y * v2;
    let n = ((v1 - v0).cross(v2 - v0) * instance_facing(scene, inst)).normalize();
    let to_light = ls.point - p;
    let dist2 = to_light.dot(to_light);
    ls.distance = dist2.sqrt();
    ls.wi = to_light / ls.distance;
    let cos_light = -n.dot(ls.wi);
    let m = &scene.materials[tv.material as usize];
    if !(dist2 > 0.0) || cos_light.abs() < 1e-7 || (cos_light < 0.0 && m.double_sided == 0) {
        return;
    }
    ls.normal = if cos_light > 0.0 { n } else { -n };
    ls.radiance = super::textures::textured_emission(scene, m, tri, b);
    ls.pdf = if !per_area {
        select_pmf / area * dist2 / cos_light.abs()
    } else if inst == NO_INSTANCE {
        select_pmf * e.pmf / area * dist2 / cos_light.abs()
    } else {
        // The emitter's probability per unit area (instanced_emitters).
        select_pmf * scene.tri_shading[tri as usize].light_pmf * dist2 / cos_light.abs()
    };
}

/// A light for `p`, chosen by power or by its importance to `p_tree` with
/// normal `n_tree` (see `sample_light` in lights.glsl).
#[allow(clippy::too_many_arguments)]
pub fn sample_light(
    scene: &PackedScene,
    params: &RenderParams,
    p: Vec3,
    p_tree: Vec3,
    n_tree: Vec3,
    u_select: f32,
    u: Vec2,
    time: f32,
) -> LightSample {
    let mut ls = LightSample {
        point: Vec3::ZERO,
        normal: Vec3::ZERO,
        wi: Vec3::Z,
        distance: FLT_MAX,
        radiance: Vec3::ZERO,
        pdf: 0.0,
        delta: false,
    };
    let p_env = params.env_select_prob;
    let p_tri = scene.light_params.tri_select_prob;
    if u_select < p_env {
        sample_environment(scene, params, u, &mut ls);
        ls.pdf *= p_env;
        return ls;
    }
    if u_select < p_env + p_tri {
        let u_tri = ((u_select - p_env) / p_tri).min(0.999_999_94);
        if light_tree_on(scene) {
            let (leaf, pmf) = light_tree_sample(scene, p_tree, n_tree, u_tri);
            if !(pmf > 0.0) {
                return ls;
            }
            if leaf.flags & LIGHT_TREE_ANALYTIC != 0 {
                sample_analytic_light(&scene.lights[leaf.child_or_light as usize], p, u, &mut ls);
                ls.pdf *= p_tri * pmf;
            } else {
                let e = &scene.emitters[leaf.child_or_light as usize];
                sample_emitter(scene, e, p, u, time, p_tri * pmf, false, &mut ls);
            }
            return ls;
        }
        if params.num_emitters == 0 {
            return ls;
        }
        let e = &scene.emitters[select_emitter(scene, params, u_tri) as usize];
        sample_emitter(scene, e, p, u, time, p_tri, true, &mut ls);
        return ls;
    }
    if scene.light_params.num_lights == 0 {
        return ls;
    }
    let u_light = ((u_select - p_env - p_tri) / (1.0 - p_env - p_tri)).min(0.999_999_94);
    let l = &scene.lights[select_light(scene, u_light) as usize];
    if !(l.pmf > 0.0) {
        return ls;
    }
    sample_analytic_light(l, p, u, &mut ls);
    ls.pdf *= l.pmf;
    ls
}

pub fn triangle_light_pdf(
    scene: &PackedScene,
    light_pmf: f32,
    area: f32,
    dist: f32,
    cos_light: f32,
) -> f32 {
    scene.light_params.tri_select_prob * light_pmf / area * dist * dist / cos_light.abs()
}

pub fn environment_light_pdf(scene: &PackedScene, params: &RenderParams, d: Vec3) -> f32 {
    params.env_select_prob * environment_direction_pdf(scene, d)
}

// ---- Rays meeting spheres and suns ------------------------------------------

pub fn intersect_sphere(l: &Light, o: Vec3, d: Vec3, t_max: f32) -> f32 {
    let oc = o - Vec3::from(l.position);
    let b = oc.dot(d);
    let f = oc - b * d;
    let disc = l.radius * l.radius - f.dot(f);
    if disc < 0.0 {
        return t_max;
    }
    let q = disc.sqrt();
    let (t0, t1) = (-b - q, -b + q);
    if t0 > 0.0 && t0 < t_max {
        return t0;
    }
    if t1 > 0.0 && t1 < t_max {
        return t1;
    }
    t_max
}

#[inline]
pub fn intersect_sphere_lights(scene: &PackedScene, o: Vec3, d: Vec3, t_max: &mut f32) -> u32 {
    let mut found = NO_HIT;
    for k in 0..scene.light_params.num_spheres {
        let t = intersect_sphere(&scene.lights[k as usize], o, d, *t_max);
        if t < *t_max {
            *t_max = t;
            found = k;
        }
    }
    found
}

/// Radiance from sphere light `k` seen along the ray (`o`, `d`) at distance
/// `t`, MIS-weighted when `prev_pdf` > 0 (`o_normal`: the normal at `o`,
/// `light_tree_normal` of the path's `prev_normal`).
#[allow(clippy::too_many_arguments)]
pub fn sphere_emission(
    scene: &PackedScene,
    params: &RenderParams,
    k: u32,
    o: Vec3,
    o_normal: Vec3,
    d: Vec3,
    t: f32,
    prev_pdf: f32,
) -> Vec3 {
    let l = &scene.lights[k as usize];
    let n = o + t * d - Vec3::from(l.position);
    if n.dot(d) >= 0.0 {
        return Vec3::ZERO;
    }
    let mut w = 1.0;
    if prev_pdf > 0.0 {
        let pmf = if light_tree_on(scene) {
            light_tree_light_pmf(scene, params, k, o, o_normal)
        } else {
            l.pmf
        };
        w = power_heuristic(prev_pdf, pmf * sphere_cone_pdf(l, o));
    }
    Vec3::from(l.emission) * w
}

/// What a ray leaving the scene can meet (twin: lights.glsl): the
/// environment, uniform or a map scaled by `params.environment`, and sun
/// disks.
pub fn environment_shines(params: &RenderParams) -> bool {
    Vec3::from(params.environment).max_element() > 0.0
}

pub fn suns_shine(scene: &PackedScene) -> bool {
    scene.light_params.num_suns > 0
}

pub fn sun_emission(scene: &PackedScene, d: Vec3, prev_pdf: f32) -> Vec3 {
    let mut sum = Vec3::ZERO;
    let first = scene.light_params.num_spheres;
    for k in first..first + scene.light_params.num_suns {
        let l = &scene.lights[k as usize];
        let e = d + Vec3::from(l.direction);
        if 0.5 * e.dot(e) > l.one_minus_cos_max {
            continue;
        }
        let mut w = 1.0;
        if prev_pdf > 0.0 {
            w = power_heuristic(prev_pdf, l.pmf * cone_pdf(l.one_minus_cos_max));
        }
        sum += Vec3::from(l.emission) * w;
    }
    sum
}
