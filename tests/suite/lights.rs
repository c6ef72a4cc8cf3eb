//! Lights against their closed forms, on both back ends.
//!
//! Each scene is a Lambertian plane of albedo 1 (y = 0, facing +Y) seen by a
//! camera looking straight down, lit by one light, rendered with
//! `max_depth` 2 (direct light only). A pixel then shows E / pi, where E is
//! the irradiance at the plane point, averaged over the pixel's footprint
//! (the camera's box filter; the footprint is a square because the image
//! plane is parallel to the plane). The expected image integrates the closed
//! form over each footprint on a 16x16 grid and is compared with the render
//! by the variance-aware test of `vkpt::image::compare::compare`.
//!
//! Closed forms (E at a plane point; theta is the angle between the normal
//! and the direction to the light):
//! - sphere of radius r, radiance L, seen under half angle alpha while fully
//!   above the horizon (theta + alpha <= pi/2): E = pi L sin^2(alpha)
//!   cos(theta). vkpt's sphere of intensity I has L = I / (pi r^2), so
//!   E = I cos(theta) / d^2 with d the distance to the centre.
//! - point light with range: E = I window(d) cos(theta) / d^2, window =
//!   clamp(1 - (d/range)^4, 0, 1) (KHR_lights_punctual).
//! - spot light: the point light's E times clamp(cos * scale + offset, 0,
//!   1)^2, scale = 1 / (cos inner - cos outer), offset = -cos outer * scale.
//! - directional light and sun disk (fully above the horizon): E = E0
//!   cos(theta).
//! - environment map with nearest lookup: E = sum over texels above the
//!   horizon of L * dphi * (sin^2 theta1 - sin^2 theta0) / 2, exact.

use crate::common;

use common::*;
use glam::Vec3;
use std::f32::consts::PI;
use vkpt::constants::ENV_SAMPLE_UNIFORM;
use vkpt::image::Image;
use vkpt::image::compare::{compare, write_failure_evidence};
use vkpt::packed::PackedScene;
use vkpt::packed::layout::RenderParams;
use vkpt::render::RenderSettings;
use vkpt::scene::{AlphaMode, Camera, EnvironmentMap, Light, LightKind, Material, Scene};

const SIZE: u32 = 32;
/// Accuracy of the expected image (relative standard deviation): the 16x16
/// midpoint rule over a pixel, far below the renders' noise (~1e-2).
const EXPECTED_REL_STD: f32 = 3e-4;

/// A plane of albedo 1 seen from height `height`, covering [-half, half]^2.
fn plane_scene(height: f32, half: f32) -> Scene {
    Scene {
        source: "lights test plane".into(),
        triangles: horizontal_square(100.0, 0.0, 0).to_vec(),
        materials: vec![Material::lambert("albedo 1", Vec3::ONE)],
        cameras: vec![Camera {
            aspect_ratio: Some(1.0),
            ..Camera::pinhole(
                "down",
                Vec3::new(0.0, height, 0.0),
                Vec3::NEG_Y,
                Vec3::NEG_Z,
                2.0 * (half / height).atan(),
            )
        }],
        ..Default::default()
    }
}

fn light(
    kind: LightKind,
    position: Vec3,
    direction: Vec3,
    color: f32,
    range: Option<f32>,
) -> Light {
    Light {
        name: "test".into(),
        kind,
        position,
        direction: direction.normalize(),
        color: Vec3::splat(color),
        range,
    }
}

fn settings(spp: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        spp,
        max_depth: Some(2),
        seed,
        camera: 0,
        ..Default::default()
    }
}

/// The expected image: E(p) / pi averaged over each pixel's footprint, or
/// the rendered value (testing nothing) where `irradiance` is `None` at some
/// point of the footprint, or where it is 0 on part of the footprint only
/// (the edge of a spot cone or of a range): there a few samples land in a
/// sliver of light, and a pixel's variance estimated from so few nonzero
/// samples is not a variance a z-test can use.
fn expected(
    p: &RenderParams,
    rendered: &Image,
    irradiance: &dyn Fn(Vec3) -> Option<f32>,
) -> (Image, usize) {
    let (w, h) = (p.width, p.height);
    let mut e = Image::new(w, h);
    let mut var = vec![[0.0f32; 3]; (w * h) as usize];
    let cam = Vec3::from(p.cam_position);
    let (right, up) = (Vec3::from(p.cam_right), Vec3::from(p.cam_up));
    let n = 16;
    let mut tested = 0;
    for y in 0..h {
        for x in 0..w {
            let mut sum = 0.0f64;
            let mut ok = true;
            let (mut zero, mut lit) = (false, false);
            for j in 0..n {
                for i in 0..n {
                    let fx = x as f32 + (i as f32 + 0.5) / n as f32;
                    let fy = y as f32 + (j as f32 + 0.5) / n as f32;
                    let sx = 2.0 * fx / w as f32 - 1.0;
                    let sy = 1.0 - 2.0 * fy / h as f32;
                    // Camera looks along -Y: the ray meets y = 0 at height * offset.
                    let point = Vec3::new(cam.x, 0.0, cam.z)
                        + cam.y
                            * (sx * p.tan_half_fov * p.aspect * right + sy * p.tan_half_fov * up);
                    match irradiance(point) {
                        Some(irr) => {
                            sum += irr as f64;
                            zero |= irr == 0.0;
                            lit |= irr > 0.0;
                        }
                        None => ok = false,
                    }
                }
            }
            let k = e.index(x, y);
            if ok && !(zero && lit) {
                let v = (sum / (n * n) as f64) as f32 / PI;
                e.mean[k] = [v; 3];
                let s = EXPECTED_REL_STD * v + 1e-7;
                var[k] = [s * s; 3];
                tested += 1;
            } else {
                e.mean[k] = rendered.mean[k];
                var[k] = [1e-14; 3];
            }
        }
    }
    e.variance = Some(var);
    (e, tested)
}

fn check(test: &str, scene: &Scene, spp: u32, irradiance: &dyn Fn(Vec3) -> Option<f32>) {
    let packed = PackedScene::new(scene).expect("packs");
    let s = settings(spp, 11);
    let params = packed.render_params(scene, &s, 0).expect("params");
    let mut images = vec![("cpu", render_cpu(scene, &packed, &s))];
    if let Some(mut gpu) = gpu_renderer(test) {
        images.push((
            "gpu",
            render_gpu(&mut gpu, scene, &packed, &settings(spp, 12)),
        ));
    }
    for (device, image) in images {
        let (e, tested) = expected(&params, &image, irradiance);
        assert!(
            tested > (SIZE * SIZE / 8) as usize,
            "{test}: only {tested} pixels tested"
        );
        let cmp = compare(&image, &e, 0.01).expect("comparable");
        println!("{test} ({device}): {tested} pixels against the closed form\n{cmp}");
        if !cmp.passed() {
            let dir = failure_dir(&format!("{test}_{device}"));
            write_failure_evidence(&dir, &image, &e, &cmp).expect("evidence written");
            panic!(
                "{test} ({device}) does not match its closed form; evidence in {}",
                dir.display()
            );
        }
    }
}

/// E from a sphere of intensity `i` at `centre`, radius `r`, while it is
/// fully above the plane's horizon at p.
fn sphere_irradiance(centre: Vec3, r: f32, i: f32) -> impl Fn(Vec3) -> Option<f32> {
    move |p: Vec3| {
        let to_c = centre - p;
        let d = to_c.length() as f64;
        let cos_theta = to_c.y as f64 / d;
        let alpha = (r as f64 / d).asin();
        let theta = cos_theta.acos();
        if theta + alpha > std::f64::consts::FRAC_PI_2 - 1e-3 {
            return None;
        }
        // pi L sin^2(alpha) cos(theta) with L = I / (pi r^2).
        let l = i as f64 / (std::f64::consts::PI * (r as f64).powi(2));
        let sin_alpha = r as f64 / d;
        Some((std::f64::consts::PI * l * sin_alpha * sin_alpha * cos_theta) as f32)
    }
}

fn sphere_test(test: &str, centre: Vec3, r: f32, i: f32, height: f32, half: f32, spp: u32) {
    let mut scene = plane_scene(height, half);
    scene.lights.push(light(
        LightKind::Sphere { radius: r },
        centre,
        Vec3::NEG_Y,
        i,
        None,
    ));
    check(test, &scene, spp, &sphere_irradiance(centre, r, i));
}

#[test]
fn sphere_light_matches_the_closed_form() {
    sphere_test(
        "sphere_light_matches_the_closed_form",
        Vec3::new(0.3, 1.5, -0.2),
        0.5,
        4.0,
        1.0,
        1.5,
        64,
    );
}

/// sin^2(alpha) = 1e-8: 1 - cos(alpha) is 0 in f32 unless formed as
/// sin^2 / (1 + cos).
#[test]
fn very_small_sphere_light_matches_the_closed_form() {
    sphere_test(
        "very_small_sphere_light_matches_the_closed_form",
        Vec3::new(0.0, 1.0, 0.0),
        1e-4,
        1.0,
        0.5,
        1.0,
        64,
    );
}

/// A unit sphere 0.02 above the plane: it fills most of the hemisphere
/// (sin^2(alpha) = 0.96 below its centre) and sinks toward the horizon
/// across the view. The camera sits between sphere and plane.
#[test]
fn very_close_sphere_light_matches_the_closed_form() {
    sphere_test(
        "very_close_sphere_light_matches_the_closed_form",
        Vec3::new(0.0, 1.02, 0.0),
        1.0,
        1.0,
        0.01,
        0.25,
        64,
    );
}

#[test]
fn point_light_with_range_matches_the_closed_form() {
    let pos = Vec3::new(0.2, 1.0, 0.0);
    let (i, range) = (2.0, 2.0);
    let mut scene = plane_scene(1.0, 2.0);
    scene
        .lights
        .push(light(LightKind::Point, pos, Vec3::NEG_Y, i, Some(range)));
    check(
        "point_light_with_range_matches_the_closed_form",
        &scene,
        16,
        &move |p| {
            let d = (pos - p).length();
            let q = d / range;
            let window = (1.0 - q.powi(4)).clamp(0.0, 1.0);
            Some(i * window * (pos.y - p.y) / d / (d * d))
        },
    );
}

#[test]
fn spot_light_falloff_matches_the_extension() {
    let pos = Vec3::new(0.0, 1.0, 0.0);
    let axis = Vec3::new(0.3, -1.0, 0.0).normalize();
    let (inner, outer) = (0.25f32, 0.6f32);
    let i = 3.0;
    let mut scene = plane_scene(1.0, 1.5);
    scene.lights.push(light(
        LightKind::Spot {
            inner_cone: inner,
            outer_cone: outer,
        },
        pos,
        axis,
        i,
        None,
    ));
    check(
        "spot_light_falloff_matches_the_extension",
        &scene,
        16,
        &move |p| {
            let to_p = p - pos;
            let d = to_p.length();
            let cd = axis.dot(to_p / d);
            // KHR_lights_punctual's recommended falloff.
            let scale = 1.0 / (inner.cos() - outer.cos()).max(0.001);
            let offset = -outer.cos() * scale;
            let a = (cd * scale + offset).clamp(0.0, 1.0);
            Some(i * a * a * (pos.y / d) / (d * d))
        },
    );
}

#[test]
fn directional_light_matches_the_closed_form() {
    let dir = Vec3::new(0.5, -1.0, 0.3).normalize();
    let e0 = 2.0;
    let mut scene = plane_scene(1.0, 1.0);
    scene
        .lights
        .push(light(LightKind::Directional, Vec3::ZERO, dir, e0, None));
    check(
        "directional_light_matches_the_closed_form",
        &scene,
        8,
        &move |_| Some(e0 * -dir.y),
    );
}

/// An alpha BLEND sheet (black, alpha 0.3) between the camera and the plane,
/// under a directional light: camera rays pass it with probability 0.7 and
/// so do the plane's shadow rays, independently, so a pixel shows
/// 0.7 * 0.7 * E0 cos(theta) / pi. (A sheet that stopped every ray, or none,
/// or the two rays deciding together, would give 0, E or 0.7 E.)
#[test]
fn alpha_blend_sheet_passes_one_minus_alpha_of_camera_and_shadow_rays() {
    let dir = Vec3::new(0.5, -1.0, 0.3).normalize();
    let (e0, alpha) = (2.0, 0.3);
    let mut scene = plane_scene(1.0, 1.0);
    scene.triangles.extend(horizontal_square(100.0, 0.5, 1));
    scene.materials.push(Material {
        alpha,
        alpha_mode: AlphaMode::Blend,
        ..Material::lambert("blend sheet", Vec3::ZERO)
    });
    scene
        .lights
        .push(light(LightKind::Directional, Vec3::ZERO, dir, e0, None));
    check(
        "alpha_blend_sheet_passes_one_minus_alpha_of_camera_and_shadow_rays",
        &scene,
        64,
        &move |_| Some((1.0 - alpha) * (1.0 - alpha) * e0 * -dir.y),
    );
}

/// An emissive alpha BLEND quad (alpha 0.3, above the camera) lights the
/// plane as an opaque quad of 0.3 times its emission does: light samples on
/// it are weighted by alpha, BSDF-sampled rays meet it with probability
/// alpha. Variance-aware comparison of the two renders, on each back end.
#[test]
fn alpha_blend_emitter_lights_as_alpha_times_its_emission() {
    let test = "alpha_blend_emitter_lights_as_alpha_times_its_emission";
    let with_lamp = |lamp: Material| {
        let mut scene = plane_scene(1.0, 1.0);
        // Facing up, double-sided (below): the side facing the plane emits.
        scene.triangles.extend(horizontal_square(0.5, 1.5, 1));
        scene.materials.push(Material {
            double_sided: true,
            ..lamp
        });
        let packed = PackedScene::new(&scene).expect("packs");
        (scene, packed)
    };
    let (blend, blend_packed) = with_lamp(Material {
        alpha: 0.3,
        alpha_mode: AlphaMode::Blend,
        emission: Vec3::splat(5.0),
        ..Material::lambert("blend lamp", Vec3::ZERO)
    });
    let (opaque, opaque_packed) = with_lamp(Material {
        emission: Vec3::splat(1.5),
        ..Material::lambert("lamp", Vec3::ZERO)
    });
    let mut pairs = vec![(
        "cpu",
        render_cpu(&blend, &blend_packed, &settings(64, 21)),
        render_cpu(&opaque, &opaque_packed, &settings(64, 22)),
    )];
    if let Some(mut gpu) = gpu_renderer(test) {
        pairs.push((
            "gpu",
            render_gpu(&mut gpu, &blend, &blend_packed, &settings(64, 23)),
            render_gpu(&mut gpu, &opaque, &opaque_packed, &settings(64, 24)),
        ));
    }
    for (device, a, b) in pairs {
        assert_agree(&format!("{test}_{device}"), &a, &b);
    }
}

/// Sun disks, 0.1 rad and the real sun's 0.0093 rad: E = E0 cos(theta).
#[test]
fn sun_disk_matches_the_closed_form() {
    for (name, diameter) in [("sun_disk_wide", 0.1f32), ("sun_disk_real", 0.0093)] {
        let dir = Vec3::new(-0.4, -1.0, 0.2).normalize();
        let e0 = 3.0;
        let mut scene = plane_scene(1.0, 1.0);
        scene.lights.push(light(
            LightKind::Sun {
                angular_diameter: diameter,
            },
            Vec3::ZERO,
            dir,
            e0,
            None,
        ));
        check(name, &scene, 32, &move |_| Some(e0 * -dir.y));
    }
}

/// The bundled sky, its irradiance on an upward plane summed texel by texel.
fn sky() -> EnvironmentMap {
    EnvironmentMap::load(&repo_path("scenes/env/sky-with-sun.exr")).expect("bundled sky loads")
}

fn sky_irradiance(map: &EnvironmentMap) -> f32 {
    let (w, h) = (map.width as usize, map.height as usize);
    let mut e = 0.0f64;
    for y in 0..h {
        let t0 = std::f64::consts::PI * y as f64 / h as f64;
        let t1 = std::f64::consts::PI * (y + 1) as f64 / h as f64;
        if t1 > std::f64::consts::FRAC_PI_2 + 1e-9 {
            break; // rows below the horizon (h is even: a row boundary lies on it)
        }
        let band = 0.5 * (t1.sin().powi(2) - t0.sin().powi(2));
        for x in 0..w {
            let lum = map.texels[y * w + x].x as f64; // red channel
            e += lum * band * 2.0 * std::f64::consts::PI / w as f64;
        }
    }
    e as f32
}

fn sky_scene(rotation: f32) -> Scene {
    let mut scene = plane_scene(1.0, 1.0);
    scene.environment_map = Some(sky());
    scene.environment = Some(Vec3::ONE);
    scene.environment_rotation = rotation;
    scene
}

/// Mean of the red channel over all pixels, and its standard error from the
/// spread of the pixel means (every pixel has the same expectation here,
/// and pixels are independent). Robust where per-pixel variance estimates
/// are not: uniform sampling finds the sun in few of a pixel's samples.
fn pooled_red(image: &Image) -> (f64, f64) {
    let n = image.mean.len() as f64;
    let mean = image.mean.iter().map(|p| p[0] as f64).sum::<f64>() / n;
    let var = image
        .mean
        .iter()
        .map(|p| (p[0] as f64 - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Importance sampling and uniform sampling of the environment both match
/// the exact irradiance, and each other; importance sampling has far lower
/// variance with the small bright sun. Every pixel sees the same irradiance,
/// so besides the per-pixel test (importance sampling) the pixels are
/// pooled: a z-test of the image mean against the exact value, with the
/// standard error from the spread across pixels.
#[test]
fn environment_map_importance_and_uniform_sampling_agree() {
    let map = sky();
    let e = sky_irradiance(&map);
    let exact = e as f64 / std::f64::consts::PI;
    let scene = sky_scene(73.0);
    let mut packed = PackedScene::new(&scene).expect("packs");
    let (spp_is, spp_uniform) = (256u32, 1024u32);
    let s = settings(spp_is, 21);
    let params = packed.render_params(&scene, &s, 0).expect("params");
    let importance = render_cpu(&scene, &packed, &s);
    packed.light_params.env_sampling = ENV_SAMPLE_UNIFORM;
    let uniform = render_cpu(&scene, &packed, &settings(spp_uniform, 22));

    let (m_is, se_is) = pooled_red(&importance);
    let (m_u, se_u) = pooled_red(&uniform);
    // Per-sample variance = variance of a pixel mean times its sample count.
    let var_is = se_is * se_is * importance.mean.len() as f64 * spp_is as f64;
    let var_u = se_u * se_u * uniform.mean.len() as f64 * spp_uniform as f64;
    let ratio = var_u / var_is;
    println!(
        "environment, red channel: exact {exact:.5}; importance {m_is:.5} +- {se_is:.5}; \
         uniform {m_u:.5} +- {se_u:.5}"
    );
    println!("environment: per-sample variance, uniform / importance sampling = {ratio:.0}");
    for (name, m, se) in [("importance", m_is, se_is), ("uniform", m_u, se_u)] {
        let z = (m - exact) / se;
        assert!(
            z.abs() < 4.0,
            "{name} sampling misses the exact irradiance: z = {z:.2}"
        );
    }
    let z = (m_is - m_u) / (se_is * se_is + se_u * se_u).sqrt();
    assert!(
        z.abs() < 4.0,
        "importance and uniform sampling disagree: z = {z:.2}"
    );
    assert!(
        ratio > 10.0,
        "importance sampling is not better: ratio {ratio}"
    );

    // Per pixel, importance sampling only (its variance estimates hold).
    let (mut exp, tested) = expected(&params, &importance, &|_| Some(e));
    // Only the red channel has the closed form above.
    for (k, m) in exp.mean.iter_mut().enumerate() {
        m[1] = importance.mean[k][1];
        m[2] = importance.mean[k][2];
    }
    let cmp = compare(&importance, &exp, 0.01).expect("comparable");
    println!("environment, importance sampling: {tested} pixels\n{cmp}");
    assert!(
        cmp.passed(),
        "importance sampling misses the exact irradiance"
    );
}

/// The same on the GPU, and with the same seed it draws the same directions
/// as the CPU (the distribution's binary searches are written alike).
#[test]
fn environment_map_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("environment_map_gpu_matches_cpu") else {
        return;
    };
    let scene = sky_scene(-40.0);
    let packed = PackedScene::new(&scene).expect("packs");
    let e = sky_irradiance(&sky());
    let s = settings(64, 31);
    let params = packed.render_params(&scene, &s, 0).expect("params");
    let a = render_gpu(&mut gpu, &scene, &packed, &s);
    let b = render_cpu(&scene, &packed, &s);
    let differing = pixels_differing(&a, &b, 1e-4);
    println!(
        "environment, same seed: {differing} of {} pixels differ",
        a.mean.len()
    );
    assert!(differing * 100 < a.mean.len(), "{differing} pixels differ");
    let (mut exp, _) = expected(&params, &a, &|_| Some(e));
    for (k, m) in exp.mean.iter_mut().enumerate() {
        m[1] = a.mean[k][1];
        m[2] = a.mean[k][2];
    }
    let cmp = compare(&a, &exp, 0.01).expect("comparable");
    println!("{cmp}");
    assert!(cmp.passed(), "the GPU misses the exact irradiance");
}

/// Map directions and texels invert each other under rotation, and the
/// environment pdf integrates to 1 over the sphere.
#[test]
fn environment_directions_and_pdf_are_consistent() {
    use vkpt::cpu::common::lights::{env_direction, env_texel_of, environment_direction_pdf};
    let scene = sky_scene(33.0);
    let packed = PackedScene::new(&scene).expect("packs");
    let (w, h) = (
        packed.light_params.env_width,
        packed.light_params.env_height,
    );
    for y in 0..h {
        for x in (0..w).step_by(7) {
            let d = env_direction(
                &packed,
                (x as f32 + 0.5) / w as f32,
                (y as f32 + 0.5) / h as f32,
            );
            let t = env_texel_of(&packed, d);
            assert_eq!(
                (t.x, t.y),
                (x, y),
                "texel of the direction of texel ({x}, {y})"
            );
        }
    }
    // Monte Carlo over uniform directions: E[pdf / (1 / 4 pi)] = 1.
    let n = 200_000;
    let mut sum = 0.0f64;
    for k in 0..n {
        let u = vkpt::cpu::common::sampling::sample_uniform_sphere(glam::Vec2::new(
            (k as f32 + 0.5) / n as f32,
            ((k as f64 * 0.618_033_988_75).fract()) as f32,
        ));
        sum += environment_direction_pdf(&packed, u) as f64 * 4.0 * std::f64::consts::PI;
    }
    let integral = sum / n as f64;
    println!("integral of the environment pdf: {integral:.4}");
    assert!(
        (integral - 1.0).abs() < 0.02,
        "pdf integrates to {integral}"
    );
}

/// Every light kind in one scene (lights-showcase.gltf) and the sky
/// (env-sky.gltf): with the same seed both back ends trace the same paths,
/// and independent renders agree statistically.
#[test]
fn every_light_kind_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("every_light_kind_gpu_matches_cpu") else {
        return;
    };
    for path in ["scenes/lights-showcase.gltf", "scenes/env-sky.gltf"] {
        let (scene, packed) = load(path);
        let s = |spp, seed| RenderSettings {
            width: 36,
            height: 24,
            spp,
            max_depth: None,
            seed,
            camera: 0,
            ..Default::default()
        };
        let a = render_gpu(&mut gpu, &scene, &packed, &s(8, 7));
        let b = render_cpu(&scene, &packed, &s(8, 7));
        let differing = pixels_differing(&a, &b, 1e-4);
        println!(
            "{path}, same seed: {differing} of {} pixels differ",
            a.mean.len()
        );
        assert!(
            differing * 100 < a.mean.len(),
            "{path}: {differing} pixels differ"
        );

        let a = render_gpu(&mut gpu, &scene, &packed, &s(256, 1));
        let b = render_cpu(&scene, &packed, &s(256, 2));
        let cmp = compare(&a, &b, 0.01).expect("comparable");
        println!("{path}:\n{cmp}");
        if !cmp.passed() {
            let dir = failure_dir("every_light_kind_gpu_matches_cpu");
            write_failure_evidence(&dir, &a, &b, &cmp).expect("evidence written");
            panic!(
                "{path}: GPU and CPU disagree; evidence in {}",
                dir.display()
            );
        }
    }
}

fn write_gltf(test: &str, lights: &str, nodes: &str) -> std::path::PathBuf {
    let dir = common::output_dir("lights");
    let path = dir.join(format!("{test}.gltf"));
    let text = format!(
        r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {{"KHR_lights_punctual": {{"lights": [{lights}]}}}},
            "scene": 0, "scenes": [{{"nodes": [0]}}],
            "buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}}],
            "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
            "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                            "min": [0, 0, 0], "max": [1, 1, 0]}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
            "nodes": [{{"children": [1], "mesh": 0}}, {nodes}]}}"#
    );
    std::fs::write(&path, text).expect("write glTF");
    path
}

/// KHR_lights_punctual as the extension defines it: colour times intensity,
/// spot defaults (inner 0, outer pi/4), the node's position and -Z, and
/// vkpt's extras turning a point into a sphere and a directional light into
/// a sun disk; malformed lights are errors naming the light.
#[test]
fn punctual_lights_load_from_gltf() {
    let lights = r#"
        {"type": "point", "color": [1, 0.5, 0.25], "intensity": 2, "range": 5},
        {"type": "spot", "name": "lamp"},
        {"type": "directional", "intensity": 3},
        {"type": "point", "extras": {"vkpt": {"radius": 0.1}}},
        {"type": "directional", "extras": {"vkpt": {"angular_diameter": 0.01}}}"#;
    // Node 1 is translated by (1, 2, 3) and turned -90 degrees about X
    // (its -Z points down); each light hangs on a child of it.
    let nodes = r#"{"translation": [1, 2, 3], "rotation": [-0.70710678, 0, 0, 0.70710678],
        "children": [2, 3, 4, 5, 6]},
        {"extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"extensions": {"KHR_lights_punctual": {"light": 2}}},
        {"extensions": {"KHR_lights_punctual": {"light": 3}}},
        {"extensions": {"KHR_lights_punctual": {"light": 4}}}"#;
    let scene = Scene::load(&write_gltf("punctual", lights, nodes)).expect("loads");
    assert_eq!(scene.lights.len(), 5);
    for l in &scene.lights {
        // Positions are stored relative to the world origin.
        let placed = scene.world_position(l.position);
        assert!(
            placed.distance(glam::DVec3::new(1.0, 2.0, 3.0)) < 1e-5,
            "{l:?}"
        );
        assert!(l.direction.distance(Vec3::NEG_Y) < 1e-5, "{l:?}");
    }
    assert_eq!(scene.lights[0].kind, LightKind::Point);
    assert_eq!(scene.lights[0].color, Vec3::new(2.0, 1.0, 0.5));
    assert_eq!(scene.lights[0].range, Some(5.0));
    assert_eq!(
        scene.lights[1].kind,
        LightKind::Spot {
            inner_cone: 0.0,
            outer_cone: std::f32::consts::FRAC_PI_4
        }
    );
    assert_eq!(scene.lights[1].name, "lamp");
    assert_eq!(scene.lights[2].kind, LightKind::Directional);
    assert_eq!(scene.lights[2].color, Vec3::splat(3.0));
    assert_eq!(scene.lights[3].kind, LightKind::Sphere { radius: 0.1 });
    assert_eq!(
        scene.lights[4].kind,
        LightKind::Sun {
            angular_diameter: 0.01
        }
    );

    let path = write_gltf(
        "inapplicable",
        r#"{"type": "spot", "extras": {"vkpt": {"radius": 0.1, "colour": 1}}}"#,
        r#"{"extensions": {"KHR_lights_punctual": {"light": 0}}}"#,
    );
    let scene = Scene::load(&path).expect("loads");
    for key in ["vkpt.radius", "vkpt.colour"] {
        assert!(
            scene
                .notes
                .iter()
                .any(|n| n.contains(key) && n.contains("ignored")),
            "no note for {key}: {:?}",
            scene.notes
        );
    }

    for (bad, needle) in [
        (
            r#"{"type": "spot", "spot": {"innerConeAngle": 0.5, "outerConeAngle": 0.4}}"#,
            "innerConeAngle < outerConeAngle",
        ),
        (r#"{"type": "area"}"#, "unknown light type"),
        (
            r#"{"type": "point", "intensity": -1}"#,
            "intensity must be non-negative",
        ),
        (r#"{"type": "point", "range": 0}"#, "range must be above 0"),
        (
            r#"{"type": "point", "extras": {"vkpt": {"radius": "big"}}}"#,
            "vkpt.radius",
        ),
    ] {
        let path = write_gltf(
            "bad",
            bad,
            r#"{"extensions": {"KHR_lights_punctual": {"light": 0}}}"#,
        );
        let err = format!("{:#}", Scene::load(&path).expect_err(bad));
        assert!(err.contains("KHR_lights_punctual light #0"), "{err}");
        assert!(err.contains(needle), "{bad}: {err}");
    }
    let path = write_gltf(
        "missing",
        r#"{"type": "point"}"#,
        r#"{"extensions": {"KHR_lights_punctual": {"light": 3}}}"#,
    );
    let err = format!("{:#}", Scene::load(&path).expect_err("light #3"));
    assert!(err.contains("light #3 does not exist"), "{err}");
}

/// A hidden environment is black to camera rays only: with the same seed,
/// pixels that see the sky turn black and pixels that see the lit plane
/// stay exactly as they were. Loaded from the scene extras of env-sky.gltf.
#[test]
fn hidden_environment_still_lights_the_scene() {
    let (scene, _) = load("scenes/env-sky.gltf");
    assert!(
        scene.environment_map.is_some(),
        "env-sky.gltf names its map"
    );
    let mut scene = sky_scene(0.0);
    scene.cameras[0] = Camera {
        aspect_ratio: Some(1.0),
        ..Camera::pinhole(
            "horizon",
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::NEG_Z,
            Vec3::Y,
            1.0,
        )
    };
    let s = settings(4, 5);
    let shown = render_cpu(&scene, &PackedScene::new(&scene).expect("packs"), &s);
    scene.environment_hidden = true;
    let hidden = render_cpu(&scene, &PackedScene::new(&scene).expect("packs"), &s);
    let (mut sky_pixels, mut plane_pixels, mut horizon_pixels) = (0, 0, 0);
    for (a, b) in shown.mean.iter().zip(&hidden.mean) {
        if a == b {
            plane_pixels += 1;
        } else if *b == [0.0; 3] {
            assert!(a[0] > 0.0, "a sky pixel was black before hiding");
            sky_pixels += 1;
        } else {
            // Some of the pixel's samples see the sky, the rest the plane.
            assert!((0..3).all(|c| b[c] < a[c]), "{a:?} -> {b:?}");
            horizon_pixels += 1;
        }
    }
    println!(
        "{sky_pixels} sky pixels black, {plane_pixels} plane pixels unchanged, \
         {horizon_pixels} on the horizon darker"
    );
    assert!(sky_pixels > 300 && plane_pixels > 300 && horizon_pixels <= 2 * SIZE as usize);
}

/// Radiance .hdr maps load like EXR ones (row 0 at the top); a map with a
/// NaN or negative texel is an error naming the file and the pixel.
#[test]
fn environment_maps_load_from_hdr_and_reject_bad_texels() {
    let dir = common::output_dir("lights");
    let path = dir.join("tiny.hdr");
    let img = image::Rgb32FImage::from_fn(4, 2, |x, y| {
        image::Rgb([x as f32 + 1.0, 2.0 * y as f32 + 0.5, 0.25])
    });
    img.save(&path).expect("writes .hdr");
    let map = EnvironmentMap::load(&path).expect("loads .hdr");
    assert_eq!((map.width, map.height), (4, 2));
    for y in 0..2 {
        for x in 0..4 {
            let want = Vec3::from(img.get_pixel(x, y).0);
            let got = map.texels[(y * 4 + x) as usize];
            // RGBE keeps 8 bits of mantissa per channel.
            assert!(
                (got - want).abs().max_element() < 0.02 * want.max_element(),
                "({x}, {y}): {got} vs {want}"
            );
        }
    }

    let path = dir.join("nan.exr");
    exr::prelude::write_rgb_file(&path, 4, 2, |x, y| {
        if (x, y) == (2, 1) {
            (f32::NAN, 0.0, 0.0)
        } else {
            (1.0f32, 1.0f32, 1.0f32)
        }
    })
    .expect("writes .exr");
    let err = format!("{:#}", EnvironmentMap::load(&path).expect_err("NaN texel"));
    assert!(
        err.contains("nan.exr") && err.contains("pixel (2, 1)"),
        "{err}"
    );
}

/// Sphere sampling from near, far and inside: from outside every sample lies
/// on the sphere's near side (facing the point), the pdf is finite and
/// positive and equals 1 / (2 pi (1 - cos theta_max)); from inside there is
/// no sample (the sphere emits outward only) and the pdf is 0.
#[test]
fn sphere_sampling_is_safe_near_far_and_inside() {
    use vkpt::cpu::common::lights::{LightSample, sample_sphere_light, sphere_cone_pdf};
    let r = 0.5f32;
    let l = vkpt::packed::layout::Light {
        position: [1.0, 2.0, 3.0],
        kind: vkpt::constants::LIGHT_SPHERE,
        radius: r,
        emission: [1.0; 3],
        ..Default::default()
    };
    let centre = Vec3::from(l.position);
    let dir = Vec3::new(0.3, -0.8, 0.52).normalize();
    for distance_in_radii in [0.5f32, 0.999, 1.0001, 1.01, 2.0, 1e2, 1e4, 1e6] {
        let p = centre + dir * (r * distance_in_radii);
        let inside = distance_in_radii <= 1.0;
        for k in 0..64 {
            let u = glam::Vec2::new((k as f32 + 0.5) / 64.0, ((k * 37 % 64) as f32 + 0.5) / 64.0);
            let mut ls = LightSample {
                point: Vec3::ZERO,
                normal: Vec3::ZERO,
                wi: Vec3::Z,
                distance: f32::MAX,
                radiance: Vec3::ZERO,
                pdf: 0.0,
                delta: false,
            };
            sample_sphere_light(&l, p, u, &mut ls);
            if inside {
                assert_eq!(
                    ls.pdf, 0.0,
                    "a sample from inside at {distance_in_radii} radii"
                );
                continue;
            }
            let d = distance_in_radii as f64;
            let omc = 1.0 - (1.0 - 1.0 / (d * d)).sqrt();
            let want = 1.0 / (2.0 * std::f64::consts::PI * omc);
            let rel = (ls.pdf as f64 - want).abs() / want;
            assert!(
                ls.pdf.is_finite() && rel < 1e-3,
                "pdf {} vs {want} at {d} radii",
                ls.pdf
            );
            let on = (ls.point - centre).length() / r;
            assert!(
                (on - 1.0).abs() < 1e-3,
                "sample {on} radii from the centre at {d} radii"
            );
            assert!(
                ls.normal.dot(-ls.wi) > -1e-3,
                "sample on the far side at {d} radii"
            );
            assert!(ls.wi.is_finite() && ls.distance.is_finite());
        }
        assert_eq!(
            sphere_cone_pdf(&l, p) == 0.0,
            inside,
            "{distance_in_radii} radii"
        );
    }
}
