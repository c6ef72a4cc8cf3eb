//! The camera on both back ends: depth of field with a six-blade aperture,
//! the orthographic camera and every pixel filter, on
//! `scenes/depth-of-field.gltf`.
//!
//! Same seed: `camera.glsl` and `src/cpu/common/camera.rs` draw the lens and filter
//! samples from the same random-number dimensions, so the two back ends
//! trace the same paths (pixels agree up to float rounding). Different
//! seeds: the variance-aware comparison of `tests/suite/gpu_vs_cpu.rs`.

use crate::common;

use common::*;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{FilterKind, PixelFilter, Scene};

const SCENE: &str = "scenes/depth-of-field.gltf";
const MAIN: usize = 0;
const ORTHO: usize = 1;

fn settings(camera: usize, width: u32, height: u32, spp: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        spp,
        max_depth: None,
        seed,
        camera,
        ..Default::default()
    }
}

fn with_filter(scene: &Scene, kind: FilterKind) -> Scene {
    let mut s = scene.clone();
    s.cameras[MAIN].filter = PixelFilter {
        kind,
        radius: kind.default_radius(),
    };
    s
}

/// Every camera variant: the lens with the box filter, the orthographic
/// camera, and the lens with each other filter.
fn variants(scene: &Scene) -> Vec<(String, Scene, usize)> {
    let mut v = vec![
        ("six-blade lens, box".to_string(), scene.clone(), MAIN),
        ("orthographic".to_string(), scene.clone(), ORTHO),
    ];
    for kind in [
        FilterKind::Tent,
        FilterKind::Gaussian,
        FilterKind::BlackmanHarris,
    ] {
        v.push((
            format!("six-blade lens, {kind:?}"),
            with_filter(scene, kind),
            MAIN,
        ));
    }
    v
}

#[test]
fn camera_same_seed_traces_the_same_paths() {
    let test = "camera_same_seed_traces_the_same_paths";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, _) = load(SCENE);
    let mut failures = Vec::new();
    for (name, scene, camera) in variants(&scene) {
        let packed = PackedScene::new(&scene).expect("packs");
        let s = settings(camera, 48, 32, 4, 7);
        let a = render_gpu(&mut gpu, &scene, &packed, &s);
        let b = render_cpu(&scene, &packed, &s);
        let differing = pixels_differing(&a, &b, 1e-3);
        println!(
            "{name}: {differing} of {} pixels differ by more than 1e-3",
            a.mean.len()
        );
        if differing * 100 > a.mean.len() {
            failures.push(format!("{name}: {differing} pixels differ"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Scales the bright spots (2 cm squares) up six times about their
/// centres: a camera ray then hits a spot's bokeh often enough for the
/// comparison to see the bokeh's size and shape.
fn bigger_spots(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    let spot =
        |t: &vkpt::scene::Triangle| s.materials[t.material as usize].name.starts_with("spot");
    let flags: Vec<bool> = s.triangles.iter().map(spot).collect();
    let mut i = 0;
    while i + 1 < s.triangles.len() {
        if flags[i] && flags[i + 1] {
            // Each quad is two triangles [q0, q1, q2], [q0, q2, q3]: its
            // centre is the middle of the diagonal q0 q2.
            let [q0, _, q2] = s.triangles[i].positions;
            let centre = 0.5 * (q0 + q2);
            for t in &mut s.triangles[i..i + 2] {
                for p in &mut t.positions {
                    *p = centre + 6.0 * (*p - centre);
                }
            }
            i += 2;
        } else {
            i += 1;
        }
    }
    s
}

/// Depth of field (85 mm f/1.2, six blades, Blackman-Harris filter):
/// independent renders agree under the variance-aware test. Emitters only
/// (max depth 1) with the spots made larger, so the image is the bokeh of
/// the bright spots and the test's power goes to the camera rather than to
/// light transport.
#[test]
fn depth_of_field_gpu_matches_cpu() {
    let test = "depth_of_field_gpu_matches_cpu";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, _) = load(SCENE);
    let scene = bigger_spots(&with_filter(&scene, FilterKind::BlackmanHarris));
    let packed = PackedScene::new(&scene).expect("packs");
    let s = |seed| RenderSettings {
        max_depth: Some(1),
        ..settings(MAIN, 96, 64, 128, seed)
    };
    let a = render_gpu(&mut gpu, &scene, &packed, &s(1));
    let b = render_cpu(&scene, &packed, &s(2));
    assert_agree(test, &a, &b);
}

/// The orthographic camera: independent renders agree.
#[test]
fn orthographic_gpu_matches_cpu() {
    let test = "orthographic_gpu_matches_cpu";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, packed) = load(SCENE);
    let a = render_gpu(&mut gpu, &scene, &packed, &settings(ORTHO, 36, 24, 128, 3));
    let b = render_cpu(&scene, &packed, &settings(ORTHO, 36, 24, 128, 4));
    assert_agree(test, &a, &b);
}
