//! White furnace: a diffuse sphere of albedo 0.8 in a uniform environment of
//! radiance 1 shows exactly 0.8 (a convex object never sees itself, so every
//! path that leaves it sees the environment: 0.8 · 1), and the background
//! shows exactly 1, on both back ends, within statistical bounds.
//!
//! The same furnace with a mirror sphere of tint 0.8 shows 0.8, and with a
//! smooth glass sphere (IOR 1.5, and 0.67: an air bubble) shows exactly 1:
//! the sphere vanishes. Glass in a furnace is exact only if Fresnel
//! reflection and refraction conserve energy, radiance is scaled by 1/η²
//! across the interface, and neither the depth limit nor Russian roulette
//! cuts paths with bias (the renders use no depth limit).
//!
//! A white rough metal sphere (metallic 1, roughness 1) loses the energy
//! GGX single scattering loses: each pixel shows the directional albedo
//! E(cos θo) = ∫ D G2 / (4 cos θo) dωi (Fresnel is 1 for a white metal),
//! computed here by quadrature from the formulas (Walter et al. 2007;
//! Heitz 2014), independently of the renderer's code, and averaged over the
//! pixel's footprint on the analytic unit sphere.
//!
//! A white clear coat (KHR_materials_clearcoat, roughness 0.5) over a white
//! Lambertian base shows (1 - blend) E_base + blend E_ggx with E_base = 1,
//! by the same quadrature: never above 1, and below it by the coat's GGX
//! loss.

use crate::common;
mod furnace_layers;

use common::*;
use glam::Vec3;
use vkpt::image::Image;
use vkpt::image::compare::{compare, write_failure_evidence};
use vkpt::packed::layout::RenderParams;
use vkpt::render::{RenderSettings, Sampler};

/// Float rounding allowed in a pixel's mean (a standard deviation).
const ROUNDING: f32 = 1e-5;

/// Distance from the sphere's centre (the origin) to the ray through the
/// film point (sx, sy) in [-1, 1]^2.
fn ray_miss_distance(p: &RenderParams, sx: f32, sy: f32) -> f32 {
    let o = Vec3::from(p.cam_position);
    let d = (Vec3::from(p.cam_forward)
        + sx * p.tan_half_fov * p.aspect * Vec3::from(p.cam_right)
        + sy * p.tan_half_fov * Vec3::from(p.cam_up))
    .normalize();
    o.cross(d).length()
}

/// The analytic answer where a pixel lies wholly on the sphere (`sphere`) or
/// wholly on the background (1); pixels on the silhouette take the rendered
/// value with no variance of their own, so they test nothing.
fn expected(
    p: &RenderParams,
    rendered: &Image,
    sphere: &dyn Fn(u32, u32) -> f32,
) -> (Image, usize, usize) {
    let (w, h) = (p.width, p.height);
    let mut e = Image::new(w, h);
    // The answer is exact, but a render of it is not quite: f32 rounding
    // (1/η² then η² across a glass sphere is 0.9999999) with a variance of
    // ~1e-17 would be "rejected" at z ~ 30. A rounding allowance of 1e-5
    // (standard deviation) is far below any real noise here (~1e-2).
    e.variance = Some(vec![[ROUNDING * ROUNDING; 3]; (w * h) as usize]);
    let (mut on_sphere, mut on_background) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let corners = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)].map(|(cx, cy)| {
                let sx = 2.0 * cx as f32 / w as f32 - 1.0;
                let sy = 1.0 - 2.0 * cy as f32 / h as f32;
                ray_miss_distance(p, sx, sy)
            });
            let i = e.index(x, y);
            // The icosphere (subdivision 3) lies between radius 0.98 and 1.
            e.mean[i] = if corners.iter().all(|&d| d < 0.95) {
                on_sphere += 1;
                [sphere(x, y); 3]
            } else if corners.iter().all(|&d| d > 1.02) {
                on_background += 1;
                [1.0; 3]
            } else {
                rendered.mean[i]
            };
        }
    }
    (e, on_sphere, on_background)
}

fn check(test: &str, image: &Image, params: &RenderParams, sphere: f32) {
    check_with(test, image, params, &|_, _| sphere);
}

fn check_with(test: &str, image: &Image, params: &RenderParams, sphere: &dyn Fn(u32, u32) -> f32) {
    let (e, on_sphere, on_background) = expected(params, image, sphere);
    assert!(
        on_sphere > 500 && on_background > 500,
        "the test scene frames the sphere"
    );
    let cmp = compare(image, &e, 0.01).expect("comparable");
    println!("{test}: {on_sphere} sphere pixels, {on_background} background pixels\n{cmp}");
    if !cmp.passed() {
        let dir = failure_dir(test);
        write_failure_evidence(&dir, image, &e, &cmp).expect("evidence written");
        panic!(
            "{test}: the furnace is not as expected; evidence in {}",
            dir.display()
        );
    }
}

fn settings() -> RenderSettings {
    RenderSettings {
        width: 64,
        height: 64,
        spp: 64,
        max_depth: None,
        seed: 11,
        camera: 0,
        // The variance-aware check assumes a pixel's samples are independent.
        sampler: Sampler::Independent,
        ..Default::default()
    }
}

/// The render's camera parameters with the camera placed in the file's
/// coordinates, where the sphere is centred on the origin (the loader
/// stores positions relative to the camera, `Scene::world_origin`).
fn file_params(
    scene: &vkpt::scene::Scene,
    packed: &vkpt::packed::PackedScene,
    settings: &RenderSettings,
) -> RenderParams {
    let mut params = packed.render_params(scene, settings, 0).unwrap();
    params.cam_position = scene
        .world_position(params.cam_position.into())
        .as_vec3()
        .into();
    params
}

fn furnace_cpu(test: &str, path: &str, sphere: f32, settings: &RenderSettings) {
    let (scene, packed) = load(path);
    let params = file_params(&scene, &packed, settings);
    let image = render_cpu(&scene, &packed, settings);
    check(test, &image, &params, sphere);
}

fn furnace_gpu(test: &str, path: &str, sphere: f32, settings: &RenderSettings) {
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, packed) = load(path);
    let params = file_params(&scene, &packed, settings);
    let image = render_gpu(&mut gpu, &scene, &packed, settings);
    check(test, &image, &params, sphere);
}

#[test]
fn white_furnace_cpu() {
    furnace_cpu(
        "white_furnace_cpu",
        "scenes/white-furnace.gltf",
        0.8,
        &settings(),
    );
}

#[test]
fn white_furnace_gpu() {
    furnace_gpu(
        "white_furnace_gpu",
        "scenes/white-furnace.gltf",
        0.8,
        &settings(),
    );
}

#[test]
fn mirror_furnace_cpu() {
    let path = "scenes/furnace-mirror-0.8.gltf";
    furnace_cpu("mirror_furnace_cpu", path, 0.8, &settings());
}

#[test]
fn mirror_furnace_gpu() {
    let path = "scenes/furnace-mirror-0.8.gltf";
    furnace_gpu("mirror_furnace_gpu", path, 0.8, &settings());
}

#[test]
fn glass_furnace_ior_1_5_cpu() {
    let path = "scenes/furnace-glass-1.5.gltf";
    furnace_cpu("glass_furnace_ior_1_5_cpu", path, 1.0, &settings());
}

#[test]
fn glass_furnace_ior_1_5_gpu() {
    let path = "scenes/furnace-glass-1.5.gltf";
    furnace_gpu("glass_furnace_ior_1_5_gpu", path, 1.0, &settings());
}

#[test]
fn glass_furnace_ior_0_67_cpu() {
    let path = "scenes/furnace-glass-0.67.gltf";
    furnace_cpu("glass_furnace_ior_0_67_cpu", path, 1.0, &settings());
}

#[test]
fn glass_furnace_ior_0_67_gpu() {
    let path = "scenes/furnace-glass-0.67.gltf";
    furnace_gpu("glass_furnace_ior_0_67_gpu", path, 1.0, &settings());
}

/// GGX directional albedo of a white metal (F = 1) for roughness α at
/// cos θo = `mu`: ∫ D(h) G2(ωo, ωi) / (4 cos θo) dωi over the upper
/// hemisphere, midpoint rule in (cos θi, φi), f64.
fn ggx_albedo(mu: f64, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let lambda = |c: f64| {
        let c2 = c * c;
        0.5 * ((1.0 + a2 * (1.0 - c2) / c2).sqrt() - 1.0)
    };
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let (nc, np) = (400, 400);
    let mut sum = 0.0;
    for i in 0..nc {
        let c = (i as f64 + 0.5) / nc as f64;
        let s = (1.0 - c * c).sqrt();
        // Symmetric in φ: integrate over [0, π] and double.
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::PI;
            let wi = [s * phi.cos(), s * phi.sin(), c];
            let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
            let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            let hz = h[2] / len;
            let d = a2 / (std::f64::consts::PI * (hz * hz * (a2 - 1.0) + 1.0).powi(2));
            let g2 = 1.0 / (1.0 + lambda(mu) + lambda(c));
            sum += d * g2 / (4.0 * mu);
        }
    }
    sum * (1.0 / nc as f64) * (2.0 * std::f64::consts::PI / np as f64)
}

/// Per-pixel expected value of the rough metal furnace: E(cos θo) averaged
/// over an 8 x 8 grid of points in the pixel, on the analytic unit sphere
/// (the test mesh is a subdivision-5 icosphere with vertex normals).
fn rough_metal_expected(p: &RenderParams) -> impl Fn(u32, u32) -> f32 + use<> {
    let e = tabulate(&|mu| ggx_albedo(mu.max(1e-3), 1.0));
    println!(
        "GGX roughness 1 white-metal albedo by quadrature: E(1) = {:.4}, E(0.5) = {:.4}, E(0.2) = {:.4}",
        e(1.0),
        e(0.5),
        e(0.2)
    );
    sphere_pixels(p, e)
}

/// A function of cos θ tabulated at 257 points, linear between them.
pub(crate) fn tabulate(f: &dyn Fn(f64) -> f64) -> impl Fn(f64) -> f64 + use<> {
    const N: usize = 256;
    let t: Vec<f64> = (0..=N).map(|i| f(i as f64 / N as f64)).collect();
    move |mu: f64| {
        let x = mu.clamp(0.0, 1.0) * N as f64;
        let i = (x as usize).min(N - 1);
        let f = x - i as f64;
        t[i] * (1.0 - f) + t[i + 1] * f
    }
}

/// Per-pixel expected value of a sphere whose directional albedo is `a`
/// (cos θo), averaged over 8 x 8 points of the pixel on the analytic unit
/// sphere (the scenes' icosphere meshes are subdivided enough that the
/// analytic sphere stands for them).
pub(crate) fn sphere_pixels<A: Fn(f64) -> f64>(
    p: &RenderParams,
    a: A,
) -> impl Fn(u32, u32) -> f32 + use<A> {
    let p = *p;
    move |x, y| {
        let o = Vec3::from(p.cam_position);
        let mut sum = 0.0;
        for j in 0..8 {
            for i in 0..8 {
                let px = x as f32 + (i as f32 + 0.5) / 8.0;
                let py = y as f32 + (j as f32 + 0.5) / 8.0;
                let sx = 2.0 * px / p.width as f32 - 1.0;
                let sy = 1.0 - 2.0 * py / p.height as f32;
                let d = (Vec3::from(p.cam_forward)
                    + sx * p.tan_half_fov * p.aspect * Vec3::from(p.cam_right)
                    + sy * p.tan_half_fov * Vec3::from(p.cam_up))
                .normalize();
                let b = o.dot(d);
                let t = -b - (b * b - o.dot(o) + 1.0).max(0.0).sqrt();
                let n = (o + t * d).normalize();
                sum += a((-d).dot(n) as f64);
            }
        }
        (sum / 64.0) as f32
    }
}

/// Renders the furnace scene at `path` on one back end and checks every
/// pixel against `expected` (the scene's albedo model).
fn sphere_furnace<E: Fn(u32, u32) -> f32>(
    test: &str,
    path: &str,
    gpu: bool,
    expected: fn(&RenderParams) -> E,
) {
    let settings = settings();
    let (scene, packed) = load(path);
    let params = file_params(&scene, &packed, &settings);
    let image = if gpu {
        let Some(mut gpu) = gpu_renderer(test) else {
            return;
        };
        render_gpu(&mut gpu, &scene, &packed, &settings)
    } else {
        render_cpu(&scene, &packed, &settings)
    };
    check_with(test, &image, &params, &expected(&params));
}

fn rough_metal_furnace(test: &str, gpu: bool) {
    sphere_furnace(
        test,
        "scenes/furnace-rough-metal.gltf",
        gpu,
        rough_metal_expected,
    );
}

#[test]
fn rough_metal_furnace_cpu() {
    rough_metal_furnace("rough_metal_furnace_cpu", false);
}

#[test]
fn rough_metal_furnace_gpu() {
    rough_metal_furnace("rough_metal_furnace_gpu", true);
}

/// Per-pixel expected value of the clearcoat furnace: a white Lambertian
/// base (albedo 1) under a white coat (factor 1, roughness 0.5) reflects
/// (1 - blend) + blend · E(cos θo), blend = Schlick's Fresnel of F0 0.04 at
/// cos θo and E the bare GGX lobe's albedo (`ggx_albedo`, quadrature), as
/// `KHR_materials_clearcoat` composes them; averaged over the pixel like
/// `rough_metal_expected`.
fn clearcoat_expected(p: &RenderParams) -> impl Fn(u32, u32) -> f32 + use<> {
    let model = |mu: f64| {
        let mu = mu.max(1e-3);
        let blend = 0.04 + 0.96 * (1.0 - mu).powi(5);
        (1.0 - blend) + blend * ggx_albedo(mu, 0.25)
    };
    assert!(
        (0..=256).all(|i| model(i as f64 / 256.0) <= 1.0),
        "the model creates energy"
    );
    let e = tabulate(&model);
    println!(
        "white coat (roughness 0.5) over white diffuse, by quadrature: E(1) = {:.4}, E(0.5) = {:.4}, E(0.2) = {:.4}",
        e(1.0),
        e(0.5),
        e(0.2)
    );
    sphere_pixels(p, e)
}

fn clearcoat_furnace(test: &str, gpu: bool) {
    sphere_furnace(
        test,
        "scenes/furnace-clearcoat.gltf",
        gpu,
        clearcoat_expected,
    );
}

#[test]
fn clearcoat_furnace_cpu() {
    clearcoat_furnace("clearcoat_furnace_cpu", false);
}

#[test]
fn clearcoat_furnace_gpu() {
    clearcoat_furnace("clearcoat_furnace_gpu", true);
}
