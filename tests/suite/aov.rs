//! Auxiliary outputs (`--aov`): albedo, normal and depth against closed
//! forms on both back ends, and GPU = CPU on a scene with mirrors, glass,
//! textures and an environment.

use crate::common;

use common::{gpu_renderer, horizontal_square, load};
use glam::Vec3;
use vkpt::image::{Aovs, Image};
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{Camera, Material, MaterialKind, Scene, Triangle};

const SIZE: u32 = 16;

/// A camera at height `height` looking along `forward` (down or up), 40°.
fn scene(triangles: Vec<Triangle>, materials: Vec<Material>, height: f32, forward: Vec3) -> Scene {
    Scene {
        source: "aov test".into(),
        triangles,
        materials,
        cameras: vec![Camera {
            aspect_ratio: Some(1.0),
            ..Camera::pinhole(
                "camera",
                Vec3::new(0.0, height, 0.0),
                forward,
                Vec3::NEG_Z,
                40f32.to_radians(),
            )
        }],
        environment: Some(Vec3::new(0.25, 0.5, 2.0)),
        ..Default::default()
    }
}

fn settings(spp: u32) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        spp,
        seed: 5,
        aov: true,
        ..Default::default()
    }
}

/// The image of `scene` on each back end the machine has.
fn render_both(test: &str, scene: &Scene, settings: &RenderSettings) -> Vec<(&'static str, Image)> {
    let packed = PackedScene::new(scene).expect("packs");
    let mut out = vec![("cpu", common::render_cpu(scene, &packed, settings))];
    if let Some(mut gpu) = gpu_renderer(test) {
        out.push((
            "gpu",
            common::render_gpu(&mut gpu, scene, &packed, settings),
        ));
    }
    out
}

fn layers(image: &Image) -> (&[[f32; 3]], &[[f32; 3]], &[f32]) {
    let Aovs {
        albedo,
        normal,
        depth,
    } = &image.aovs;
    (
        albedo.as_deref().expect("albedo layer"),
        normal.as_deref().expect("normal layer"),
        depth.as_deref().expect("depth layer"),
    )
}

fn assert_close3(what: &str, got: [f32; 3], want: Vec3, tolerance: f32) {
    let close = (0..3).all(|c| (got[c] - want[c]).abs() <= tolerance);
    assert!(close, "{what}: {got:?}, expected {want}");
}

/// The mean over a pixel's footprint of the distance along camera rays to
/// the plane at distance `height` straight ahead: height / cos, sampled
/// finely over the pixel (the box filter's footprint).
fn expected_depth(x: u32, y: u32, height: f32) -> f32 {
    let tan = (20f32).to_radians().tan();
    let n = 32;
    let mut sum = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let sx = ((x as f32 + (i as f32 + 0.5) / n as f32) / SIZE as f32 * 2.0 - 1.0) * tan;
            let sy = ((y as f32 + (j as f32 + 0.5) / n as f32) / SIZE as f32 * 2.0 - 1.0) * tan;
            sum += (height * (1.0 + sx * sx + sy * sy).sqrt()) as f64;
        }
    }
    (sum / (n * n) as f64) as f32
}

#[test]
fn a_lambert_floor_shows_its_colour_its_normal_and_its_distance() {
    let test = "a_lambert_floor_shows_its_colour_its_normal_and_its_distance";
    let colour = Vec3::new(0.8, 0.5, 0.2);
    let floor = scene(
        horizontal_square(100.0, 0.0, 0).to_vec(),
        vec![Material::lambert("floor", colour)],
        2.0,
        Vec3::NEG_Y,
    );
    for (backend, image) in render_both(test, &floor, &settings(16)) {
        let (albedo, normal, depth) = layers(&image);
        for y in 0..SIZE {
            for x in 0..SIZE {
                let i = image.index(x, y);
                let at = format!("{backend} pixel ({x}, {y})");
                assert_close3(&format!("{at} albedo"), albedo[i], colour, 1e-6);
                assert_close3(&format!("{at} normal"), normal[i], Vec3::Y, 1e-6);
                let want = expected_depth(x, y, 2.0);
                assert!(
                    (depth[i] - want).abs() <= 2e-3 * want,
                    "{at} depth: {}, expected {want}",
                    depth[i]
                );
            }
        }
    }
}

#[test]
fn a_mirror_is_seen_through_to_the_first_rough_surface() {
    let test = "a_mirror_is_seen_through_to_the_first_rough_surface";
    // A mirror floor under the camera, a rough ceiling above it: camera rays
    // meet the mirror at distance 2, their reflections the ceiling's underside.
    let ceiling = Vec3::new(0.3, 0.6, 0.9);
    let mut triangles = horizontal_square(100.0, 0.0, 0).to_vec();
    triangles.extend(horizontal_square(100.0, 3.0, 1));
    let mirror = Material {
        kind: MaterialKind::Mirror,
        ..Material::lambert("mirror", Vec3::splat(0.9))
    };
    let room = scene(
        triangles,
        vec![mirror, Material::lambert("ceiling", ceiling)],
        2.0,
        Vec3::NEG_Y,
    );
    for (backend, image) in render_both(test, &room, &settings(16)) {
        let (albedo, normal, depth) = layers(&image);
        for i in 0..albedo.len() {
            let at = format!("{backend} pixel {i}");
            assert_close3(&format!("{at} albedo"), albedo[i], ceiling, 1e-6);
            assert_close3(&format!("{at} normal"), normal[i], Vec3::NEG_Y, 1e-6);
        }
        let centre = image.index(SIZE / 2, SIZE / 2);
        let want = expected_depth(SIZE / 2, SIZE / 2, 2.0);
        assert!(
            (depth[centre] - want).abs() <= 2e-3 * want,
            "{backend} depth at the centre: {}, expected {want} (the mirror's distance)",
            depth[centre]
        );
    }
}

#[test]
fn rays_that_meet_nothing_see_the_environment() {
    let test = "rays_that_meet_nothing_see_the_environment";
    // The camera looks up, away from the floor: every ray escapes.
    let sky = scene(
        horizontal_square(100.0, 0.0, 0).to_vec(),
        vec![Material::lambert("floor", Vec3::ONE)],
        2.0,
        Vec3::Y,
    );
    for (backend, image) in render_both(test, &sky, &settings(4)) {
        let (albedo, normal, depth) = layers(&image);
        for i in 0..albedo.len() {
            let at = format!("{backend} pixel {i}");
            // The environment (0.25, 0.5, 2.0) as seen, at most 1.
            assert_close3(
                &format!("{at} albedo"),
                albedo[i],
                Vec3::new(0.25, 0.5, 1.0),
                0.0,
            );
            assert_close3(&format!("{at} normal"), normal[i], Vec3::ZERO, 0.0);
            assert!(depth[i] == f32::INFINITY, "{at} depth {}", depth[i]);
        }
    }
}

#[test]
fn gpu_and_cpu_record_the_same_aovs() {
    let test = "gpu_and_cpu_record_the_same_aovs";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    // Mirrors, glass, Phong and glTF materials under an environment.
    for file in ["scenes/materials-showcase.gltf", "scenes/textured.gltf"] {
        let (scene, packed) = load(file);
        let s = RenderSettings {
            width: 48,
            height: 36,
            ..settings(8)
        };
        let cpu = common::render_cpu(&scene, &packed, &s);
        let gpu = common::render_gpu(&mut gpu, &scene, &packed, &s);
        let (ca, cn, cd) = layers(&cpu);
        let (ga, gn, gd) = layers(&gpu);
        // The same paths: the same numbers, but for the rare path that
        // float rounding sends another way.
        let differs = |a: [f32; 3], b: [f32; 3]| (0..3).any(|c| (a[c] - b[c]).abs() > 1e-4);
        let albedo = ca.iter().zip(ga).filter(|(a, b)| differs(**a, **b)).count();
        let normal = cn.iter().zip(gn).filter(|(a, b)| differs(**a, **b)).count();
        let depth = cd
            .iter()
            .zip(gd)
            .filter(|(a, b)| !(a == b || (*a - *b).abs() <= 1e-4 * a.abs()))
            .count();
        println!("{file}: pixels differing: albedo {albedo}, normal {normal}, depth {depth}");
        let allowed = ca.len() / 100;
        assert!(
            albedo <= allowed && normal <= allowed && depth <= allowed,
            "{file}: GPU and CPU AOVs differ in more than 1% of {} pixels: albedo {albedo}, \
             normal {normal}, depth {depth}",
            ca.len()
        );
        let nonzero = ca.iter().filter(|a| a.iter().any(|c| *c > 0.0)).count();
        assert!(nonzero > ca.len() / 2, "{file}: albedo mostly black");
    }
}

#[test]
fn without_aov_the_film_records_none() {
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let s = RenderSettings {
        aov: false,
        ..settings(2)
    };
    let image = common::render_cpu(&scene, &packed, &s);
    assert!(image.aovs.is_empty());
}
