//! Numerical stability on the hard-case scenes of `scenes/hard/` (made by
//! `scenes/generate.py`), on both back ends. Every render here also asserts
//! (in `common`) zero non-finite samples, zero traversal overflows and no
//! validation message.

use crate::common;

use common::*;
use glam::Vec3;
use vkpt::constants::BVH_MAX_ITERATIONS;
use vkpt::cpu::common::bvh::{NO_HIT, OVERFLOW_HIT};
use vkpt::cpu::fast::cache::CpuScene;
use vkpt::cpu::traversal::trace_ray;
use vkpt::image::Image;
use vkpt::packed::PackedScene;
use vkpt::render::{RenderSettings, Sampler};
use vkpt::scene::{Camera, Material, Scene, Triangle};

const ALPHA: f64 = 0.01;

/// Independent samples: the variance-aware comparisons assume them (with
/// Sobol the per-pixel variance estimate is not valid).
fn settings(width: u32, height: u32, spp: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width,
        height,
        spp,
        max_depth: None,
        seed,
        camera: 0,
        sampler: Sampler::Independent,
        ..Default::default()
    }
}

/// Renders on the GPU when there is one, else on the CPU (different seeds
/// keep the comparison independent either way).
fn render_either(
    gpu: &mut Option<Gpu>,
    scene: &Scene,
    packed: &PackedScene,
    s: &RenderSettings,
) -> Image {
    match gpu {
        Some(g) => render_gpu(g, scene, packed, s),
        None => render_cpu(scene, packed, s),
    }
}

/// Scaled by 1e-3 (a 0.55 mm box) and by 1e4 (5.5 km), camera included,
/// the Cornell box must render the same image as the canonical one
/// (radiance does not depend on scale): variance-aware test per pixel,
/// block and image.
#[test]
fn scaled_cornell_boxes_agree_with_the_canonical_one() {
    let mut gpu = gpu_renderer("scaled_cornell_boxes_agree_with_the_canonical_one");
    let (canon, canon_packed) = load("scenes/cornell-box.gltf");
    let reference = render_cpu(&canon, &canon_packed, &settings(32, 32, 256, 7));
    for (k, name) in ["cornell-scaled-1e-3", "cornell-scaled-1e4"]
        .iter()
        .enumerate()
    {
        let (scene, packed) = load(&format!("scenes/hard/{name}.gltf"));
        let image = render_either(
            &mut gpu,
            &scene,
            &packed,
            &settings(32, 32, 256, 20 + k as u32),
        );
        assert_agree(name, &image, &reference);
    }
}

/// Far from the origin, the Cornell box renders like the untranslated one:
/// translated by 1e5, 1e6 and 1e7 m in a parent node (camera included), and
/// by 1e5 with the camera 30 m away (against the untranslated box seen from
/// 30 m). The same strict variance-aware test as every comparison (per
/// pixel, 4×4 and 16×16 block, whole image), on both back ends. It holds
/// because the loader composes transforms in f64 and stores positions
/// relative to the camera (`Scene::world_origin`), so the f32 geometry is
/// the untranslated box's to 1 ULP. (Composed in f32 and stored in world
/// space, the box at 1e5 had float steps of 0.0078 m: its light rounded
/// onto the ceiling and the image came out 40 % darker than the canonical
/// box; the former test allowed 5 % per block against that f32 geometry
/// moved to the origin.)
#[test]
fn translated_cornell_boxes_agree_with_the_untranslated_ones() {
    let mut gpu = gpu_renderer("translated_cornell_boxes_agree_with_the_untranslated_ones");
    let s = |seed| settings(48, 48, 256, seed);
    let cases = [
        ("hard/cornell-translated-1e5", "cornell-box"),
        ("hard/cornell-translated-1e6", "cornell-box"),
        ("hard/cornell-translated-1e7", "cornell-box"),
        (
            "hard/cornell-translated-1e5-camera-30m",
            "hard/cornell-camera-30m",
        ),
    ];
    for (k, (far, near)) in cases.iter().enumerate() {
        let k = k as u32;
        let (near_scene, near_packed) = load(&format!("scenes/{near}.gltf"));
        let reference = render_cpu(&near_scene, &near_packed, &s(40 + k));
        let (scene, packed) = load(&format!("scenes/{far}.gltf"));
        let name = far.trim_start_matches("hard/");
        let cpu = render_cpu(&scene, &packed, &s(50 + k));
        assert_agree(&format!("{name}-cpu"), &cpu, &reference);
        if let Some(g) = &mut gpu {
            let image = render_gpu(g, &scene, &packed, &s(60 + k));
            assert_agree(&format!("{name}-gpu"), &image, &reference);
        }
    }
}

/// Rays from inside a closed mesh aimed exactly at its vertices and at
/// points of its shared edges (between triangles of one mesh and between
/// its two meshes) never escape: CPU traversal plus the watertight
/// ray/triangle test, about 3 million rays over three placements. The
/// same rays through a mesh with one triangle removed must escape (the
/// check can see a leak).
#[test]
fn rays_at_shared_edges_and_vertices_never_escape_a_closed_mesh() {
    let escapes = |name: &str, origins: usize, per_edge: usize| -> (usize, usize) {
        let (scene, packed) = load(&format!("scenes/hard/{name}.gltf"));
        let (lo, hi) = scene.bounds().expect("not empty");
        let centre = (lo + hi) * 0.5;
        let radius = (hi - lo).max_element() * 0.5;
        let mut targets: Vec<Vec3> = Vec::new();
        for t in &scene.triangles {
            for k in 0..3 {
                let (a, b) = (t.positions[k], t.positions[(k + 1) % 3]);
                targets.push(a);
                for j in 1..per_edge {
                    targets.push(a + (b - a) * (j as f32 / per_edge as f32));
                }
            }
        }
        let (mut rays, mut escaped) = (0, 0);
        let cpu_scene = CpuScene::new(&packed);
        for i in 0..origins {
            // Interior points spread through the sphere (within half its radius).
            let f = i as f32;
            let dir = Vec3::new((f * 2.399).cos(), (f * 1.7).sin(), (f * 0.913).cos());
            let o = centre + dir.normalize_or_zero() * radius * 0.5 * ((i % 7) as f32 / 7.0);
            for &target in &targets {
                let d = (target - o).normalize();
                let hit = trace_ray(&cpu_scene, o, d, f32::MAX, false, 0, 0.0);
                assert_ne!(hit.triangle, OVERFLOW_HIT, "traversal overflow in {name}");
                rays += 1;
                escaped += (hit.triangle == NO_HIT) as usize;
            }
        }
        println!("{name}: {escaped} of {rays} rays escaped");
        (rays, escaped)
    };
    let mut total = 0;
    for (name, origins) in [
        ("inside-sphere", 16),
        ("inside-sphere-translated-1e5", 4),
        ("inside-sphere-scaled-1e-3", 4),
    ] {
        let (rays, escaped) = escapes(name, origins, 32);
        assert_eq!(
            escaped, 0,
            "{name}: rays escaped through shared edges or vertices"
        );
        total += rays;
    }
    assert!(total > 2_900_000, "only {total} rays");
    let (_, escaped) = escapes("inside-sphere-with-hole", 2, 16);
    assert!(escaped > 0, "a missing triangle was not detected");
}

/// A camera inside a closed mesh lit only by the environment outside: every
/// pixel must be exactly black on both back ends (any ray or shadow ray
/// that escapes adds the environment's radiance 1). With one triangle
/// missing, light must come in.
#[test]
fn a_camera_inside_a_closed_mesh_sees_no_environment() {
    let mut gpu = gpu_renderer("a_camera_inside_a_closed_mesh_sees_no_environment");
    let s = settings(24, 24, 8, 3);
    let lit = |gpu: &mut Option<Gpu>, name: &str| -> Vec<usize> {
        let (scene, packed) = load(&format!("scenes/hard/{name}.gltf"));
        let mut images = vec![render_cpu(&scene, &packed, &s)];
        if let Some(g) = gpu {
            images.push(render_gpu(g, &scene, &packed, &s));
        }
        images
            .iter()
            .map(|im| {
                im.mean
                    .iter()
                    .filter(|p| p.iter().any(|&c| c != 0.0))
                    .count()
            })
            .collect()
    };
    for name in [
        "inside-sphere",
        "inside-sphere-translated-1e5",
        "inside-sphere-scaled-1e-3",
    ] {
        let lit_pixels = lit(&mut gpu, name);
        println!("{name}: non-black pixels (CPU, GPU): {lit_pixels:?}");
        assert!(
            lit_pixels.iter().all(|&n| n == 0),
            "{name}: light leaked in"
        );
    }
    let lit_pixels = lit(&mut gpu, "inside-sphere-with-hole");
    println!("inside-sphere-with-hole: non-black pixels (CPU, GPU): {lit_pixels:?}");
    assert!(
        lit_pixels.iter().all(|&n| n > 0),
        "the planted hole was not seen"
    );
}

/// A camera 1 cm above a 1 km plane (64 × 64 quads, tilted a fraction of a
/// degree), looking almost along it, in a uniform environment of 1: every
/// pixel that sees only the plane must be 0.5 (its albedo: the whole sky
/// lights it), every pixel that sees only sky 1. A black rim (rays hitting
/// the plane they leave) pulls plane pixels down, a leak through an edge
/// pushes them up. Per-pixel z-tests, Bonferroni-corrected.
#[test]
fn a_camera_skimming_a_plane_sees_no_black_rims_or_leaks() {
    let mut gpu = gpu_renderer("a_camera_skimming_a_plane_sees_no_black_rims_or_leaks");
    let (scene, packed) = load("scenes/hard/grazing-plane.gltf");
    let (w, h) = (64, 32);
    let cam = &scene.cameras[0];
    let tan_half = (cam.yfov * 0.5).tan();
    let aspect = w as f32 / h as f32;
    let right = cam.right();
    // The plane through the grid's triangles (all coplanar).
    let t0 = &scene.triangles[0];
    let n = (t0.positions[1] - t0.positions[0])
        .cross(t0.positions[2] - t0.positions[0])
        .normalize();
    let hits_plane = |x: f32, y: f32| {
        let sx = 2.0 * x / w as f32 - 1.0;
        let sy = 1.0 - 2.0 * y / h as f32;
        let d =
            (cam.forward + right * (sx * tan_half * aspect) + cam.up * (sy * tan_half)).normalize();
        let t = (t0.positions[0] - cam.position).dot(n) / d.dot(n);
        t > 0.0 && t < 400.0 // well inside the 500 m half-width
    };
    let mut expected = vec![None; (w * h) as usize];
    for y in 0..h {
        for x in 0..w {
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .map(|(dx, dy)| hits_plane(x as f32 + dx, y as f32 + dy));
            expected[(y * w + x) as usize] = if corners.iter().all(|&c| c) {
                Some(0.5f32)
            } else if corners.iter().all(|&c| !c) {
                Some(1.0)
            } else {
                None
            };
        }
    }
    let plane_pixels = expected.iter().filter(|e| **e == Some(0.5)).count();
    assert!(
        plane_pixels > 500,
        "only {plane_pixels} pixels see the plane"
    );
    let s = settings(w, h, 64, 11);
    let mut images = vec![("cpu", render_cpu(&scene, &packed, &s))];
    if let Some(g) = &mut gpu {
        images.push(("gpu", render_gpu(g, &scene, &packed, &s)));
    }
    let tests = expected.iter().filter(|e| e.is_some()).count() * 3;
    // Two-sided z threshold for alpha / tests (Bonferroni), by bisection.
    let p_each = ALPHA / tests as f64;
    let (mut lo, mut hi) = (0.0, 40.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if vkpt::image::compare::normal_two_sided_p(mid) > p_each {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let z_crit = hi;
    for (back_end, image) in &images {
        let var = image.variance.as_ref().expect("variance");
        let mut worst = (0.0f64, 0usize);
        for (i, e) in expected.iter().enumerate() {
            let Some(e) = e else { continue };
            for (mean, var) in image.mean[i].iter().zip(&var[i]) {
                let diff = (mean - e) as f64;
                let sd = (*var as f64).sqrt();
                let z = if sd > 0.0 {
                    diff / sd
                } else if diff.abs() < 1e-5 {
                    0.0
                } else {
                    f64::INFINITY
                };
                if z.abs() > worst.0.abs() {
                    worst = (z, i);
                }
            }
        }
        let (z, i) = worst;
        println!(
            "{back_end}: {plane_pixels} plane pixels; worst z {z:.2} at pixel ({}, {}) = {:?}, expected {:?} (critical |z| {z_crit:.2})",
            i as u32 % w,
            i as u32 / w,
            images.iter().find(|(b, _)| b == back_end).unwrap().1.mean[i],
            expected[i]
        );
        assert!(
            z.abs() <= z_crit,
            "{back_end}: a pixel of the grazing plane is off by z = {z:.1}"
        );
    }
}

/// A thick glass slab (total internal reflection), eight glass plates in a
/// row (chains of refractions) and a 2 mm light of radiance 2e6: finite on
/// both back ends, and the GPU agrees with the CPU reference.
#[test]
fn glass_chains_and_a_tiny_bright_light_agree_between_back_ends() {
    let Some(mut gpu) =
        gpu_renderer("glass_chains_and_a_tiny_bright_light_agree_between_back_ends")
    else {
        let (scene, packed) = load("scenes/hard/glass-and-tiny-light.gltf");
        render_cpu(&scene, &packed, &settings(24, 24, 16, 1));
        return;
    };
    let (scene, packed) = load("scenes/hard/glass-and-tiny-light.gltf");
    let a = render_gpu(&mut gpu, &scene, &packed, &settings(32, 32, 128, 40));
    let b = render_cpu(&scene, &packed, &settings(32, 32, 128, 41));
    assert_agree("glass-and-tiny-light", &a, &b);
}

/// Zero-area triangles, repeated vertices, NaN and infinite positions and
/// normals: dropped (or, for normals, replaced) at load with one counted
/// warning per kind, and the rest renders without a non-finite sample.
#[test]
fn degenerate_geometry_is_dropped_with_counted_warnings() {
    let (scene, packed) = load("scenes/hard/degenerate.gltf");
    let notes = scene.notes.join("\n");
    println!("{notes}");
    assert_eq!(scene.triangles.len(), 4, "two valid quads remain");
    for expected in [
        "warning: dropped 2 triangles with NaN, infinite or out-of-range",
        "in mesh 'mixed'",
        "warning: dropped 3 zero-area triangles",
        "warning: replaced 3 bad vertex normals (NaN, infinite or zero) by the face normal in mesh 'bad normals'",
    ] {
        assert!(
            notes.contains(expected),
            "missing {expected:?} in:\n{notes}"
        );
    }
    for t in &scene.triangles {
        assert!(t.positions.iter().chain(&t.normals).all(|v| v.is_finite()));
    }
    let s = settings(16, 16, 8, 2);
    let image = render_cpu(&scene, &packed, &s);
    assert!(image.mean.iter().flatten().all(|c| c.is_finite()));
    if let Some(mut gpu) = gpu_renderer("degenerate_geometry_is_dropped_with_counted_warnings") {
        let image = render_gpu(&mut gpu, &scene, &packed, &s);
        assert!(image.mean.iter().flatten().all(|c| c.is_finite()));
    }
}

/// Shading normals far from the geometric ones: an icosahedron with smooth
/// vertex normals (up to 37 degrees off) in a uniform environment of 1. Both
/// back ends reconcile the two normals the same way (same paths; a one-sided
/// change to `shading_frame` makes 248 pixels differ), every sphere pixel
/// stays lit and none exceeds the environment. (Naive shading normals stay
/// above 0.4 here too: this scene checks agreement and sanity, not the
/// reconciliation itself, which `shading_frame`'s unit test covers.)
#[test]
fn shading_normals_far_from_geometric_agree_between_back_ends() {
    let mut gpu = gpu_renderer("shading_normals_far_from_geometric_agree_between_back_ends");
    let (scene, packed) = load("scenes/hard/low-poly-smooth-sphere.gltf");
    let s = settings(48, 48, 64, 12);
    let cpu = render_cpu(&scene, &packed, &s);
    let mut images = vec![("cpu", cpu.clone())];
    if let Some(g) = gpu.as_mut() {
        let gpu_image = render_gpu(g, &scene, &packed, &s);
        let differ = pixels_differing(&gpu_image, &cpu, 1e-3);
        assert_eq!(differ, 0, "{differ} pixels differ between GPU and CPU");
        images.push(("gpu", gpu_image));
    }
    for (name, image) in images {
        let sphere: Vec<f32> = image
            .mean
            .iter()
            .filter(|m| (0..3).any(|c| (m[c] - 1.0).abs() > 1e-6))
            .map(|m| m[0].min(m[1]).min(m[2]))
            .collect();
        assert!(
            sphere.len() > 500,
            "{name}: only {} sphere pixels",
            sphere.len()
        );
        let darkest = sphere.iter().fold(f32::MAX, |a, &b| a.min(b));
        let brightest = image
            .mean
            .iter()
            .fold(0.0f32, |a, m| a.max(m[0]).max(m[1]).max(m[2]));
        println!(
            "{name}: {} sphere pixels, darkest {darkest:.3}, brightest {brightest:.3}",
            sphere.len()
        );
        assert!(
            darkest > 0.4,
            "{name}: a sphere pixel at {darkest} (albedo 0.8 in a uniform environment of 1): black rim"
        );
        assert!(
            brightest < 1.1,
            "{name}: a pixel at {brightest}: light leak"
        );
    }
}

/// `n` emissive triangles (radiance 2) in one plane, each 1e-6 to the right
/// of the one before, facing a camera 4 units away, under an environment of
/// 1: they overlap at one distance, so a closest-hit ray through the stack
/// must test them all, and with `n` above `BVH_MAX_ITERATIONS` the traversal
/// gives up on it.
fn triangle_stack(n: usize) -> Scene {
    let tri = |k: usize| {
        let x = k as f32 * 1e-6;
        Triangle {
            positions: [
                Vec3::new(x - 1.0, -1.0, 0.0),
                Vec3::new(x + 1.0, -1.0, 0.0),
                Vec3::new(x, 1.0, 0.0),
            ],
            normals: [Vec3::Z; 3],
            material: 0,
        }
    };
    let mut stack = Material::lambert("stack", Vec3::ZERO);
    stack.emission = Vec3::splat(2.0);
    Scene {
        source: "triangle stack".into(),
        triangles: (0..n).map(tri).collect(),
        materials: vec![stack],
        cameras: vec![Camera {
            aspect_ratio: Some(1.0),
            ..Camera::pinhole("front", Vec3::new(0.0, 0.0, 4.0), Vec3::NEG_Z, Vec3::Y, 0.6)
        }],
        environment: Some(Vec3::ONE),
        ..Default::default()
    }
}

/// A ray that needs more than `BVH_MAX_ITERATIONS` steps is counted as a
/// traversal overflow and dropped, on both back ends alike: never turned
/// into a miss (the environment, 1) or a hit found part way (the stack, 2).
/// Below the bound the same stack renders normally.
#[test]
fn a_traversal_past_its_bound_is_counted_and_dropped_never_a_wrong_hit() {
    let test = "a_traversal_past_its_bound_is_counted_and_dropped_never_a_wrong_hit";
    let s = RenderSettings {
        max_depth: Some(1),
        ..settings(16, 16, 1, 3)
    };
    let mut gpu = gpu_renderer(test);
    for (n, overflows) in [(BVH_MAX_ITERATIONS as usize + 500, true), (2000, false)] {
        let scene = triangle_stack(n);
        let packed = PackedScene::new(&scene).expect("the stack packs");
        let mut results = vec![(
            "CPU",
            vkpt::cpu::render::render(&scene, &packed, &s, &|_, _| {}).expect("CPU render"),
        )];
        if let Some(g) = gpu.as_mut() {
            let r = g
                .render(&scene, &packed, &s, &|_, _| {})
                .expect("GPU render");
            results.push(("GPU", r));
        }
        for (name, r) in &results {
            let image = r.film.to_image();
            let count = |v: f32| image.mean.iter().filter(|p| p[0] == v).count();
            let (dropped, env, stack) = (count(0.0), count(1.0), count(2.0));
            println!(
                "{n} triangles, {name}: {} overflows; pixels: {dropped} dropped, {env} environment, {stack} stack",
                r.traversal_overflows
            );
            assert_eq!(
                dropped + env + stack,
                image.mean.len(),
                "{name}: a pixel is neither"
            );
            assert!(env > 0, "{name}: the environment shows around the stack");
            if overflows {
                assert!(dropped > 0 && stack == 0, "{name}: {n} triangles");
                assert_eq!(
                    r.traversal_overflows, dropped as u64,
                    "{name}: one per dropped ray"
                );
            } else {
                assert!(dropped == 0 && stack > 0, "{name}: {n} triangles");
                assert_eq!(r.traversal_overflows, 0, "{name}");
            }
        }
        if let [(_, cpu), (_, gpu)] = &results[..] {
            assert_eq!(cpu.traversal_overflows, gpu.traversal_overflows);
            assert_eq!(cpu.film.to_image().mean, gpu.film.to_image().mean);
        }
    }
}
