//! Twin of `shaders/common/lights.glsl`.

use super::sampling::{
    FLT_MAX, sample_uniform_sphere, sample_uniform_triangle, uniform_sphere_pdf,
};
use crate::layout::RenderParams;
use crate::packed::PackedScene;
use glam::{Vec2, Vec3};

pub struct LightSample {
    pub point: Vec3,
    pub normal: Vec3,
    pub wi: Vec3,
    pub distance: f32,
    pub radiance: Vec3,
    pub pdf: f32,
}

pub fn select_emitter(scene: &PackedScene, params: &RenderParams, u: f32) -> u32 {
    let (mut lo, mut hi) = (0u32, params.num_emitters - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if scene.emitters[mid as usize].cdf <= u {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

pub fn sample_light(
    scene: &PackedScene,
    params: &RenderParams,
    p: Vec3,
    u_select: f32,
    u: Vec2,
) -> LightSample {
    let mut ls = LightSample {
        point: Vec3::ZERO,
        normal: Vec3::ZERO,
        wi: Vec3::Z,
        distance: FLT_MAX,
        radiance: Vec3::ZERO,
        pdf: 0.0,
    };
    let p_env = params.env_select_prob;
    if u_select < p_env {
        ls.wi = sample_uniform_sphere(u);
        ls.radiance = params.environment.into();
        ls.pdf = p_env * uniform_sphere_pdf();
        return ls;
    }
    if params.num_emitters == 0 {
        return ls;
    }
    let u_tri = ((u_select - p_env) / (1.0 - p_env)).min(0.999_999_94);
    let e = scene.emitters[select_emitter(scene, params, u_tri) as usize];
    let tv = &scene.tri_verts[e.triangle as usize];
    let (v0, v1, v2) = (Vec3::from(tv.v0), Vec3::from(tv.v1), Vec3::from(tv.v2));
    let b = sample_uniform_triangle(u);
    ls.point = (1.0 - b.x - b.y) * v0 + b.x * v1 + b.y * v2;
    let n = (v1 - v0).cross(v2 - v0).normalize();
    let to_light = ls.point - p;
    let dist2 = to_light.dot(to_light);
    ls.distance = dist2.sqrt();
    ls.wi = to_light / ls.distance;
    let cos_light = -n.dot(ls.wi);
    let m = &scene.materials[tv.material as usize];
    if !(dist2 > 0.0) || cos_light.abs() < 1e-7 || (cos_light < 0.0 && m.double_sided == 0) {
        return ls;
    }
    ls.normal = if cos_light > 0.0 { n } else { -n };
    ls.radiance = super::textures::textured_emission(scene, m, e.triangle, b);
    ls.pdf = (1.0 - p_env) * e.pmf / e.area * dist2 / cos_light.abs();
    ls
}

pub fn triangle_light_pdf(
    params: &RenderParams,
    light_pmf: f32,
    area: f32,
    dist: f32,
    cos_light: f32,
) -> f32 {
    (1.0 - params.env_select_prob) * light_pmf / area * dist * dist / cos_light.abs()
}

pub fn environment_light_pdf(params: &RenderParams) -> f32 {
    params.env_select_prob * uniform_sphere_pdf()
}
