//! The CPU back end's lane schedule (`cpu::lanes`) traces the paths of its
//! one-path schedule: on every static bundled scene (Lambertian surfaces
//! shaded in the lanes; glass, mirrors, glTF materials, escaped rays and
//! lights other than emissive triangles by the scalar twins lane by lane),
//! with either sampler, limited and unlimited depth, auxiliary outputs and
//! a region, the same seed gives the same film bit for bit and the same ray
//! counts. Moving scenes are rendered by the one-path schedule whichever is
//! asked.

mod common;

use common::*;
use vkpt::cpu::lanes::{lanes_cover, triangle_lights_only};
use vkpt::cpu::render::{CpuSchedule, render_with};
use vkpt::image::Image;
use vkpt::image::region::Region;
use vkpt::packed::PackedScene;
use vkpt::render::{RenderAll, RenderResult, RenderSettings, Sampler};
use vkpt::scene::Scene;

fn render(
    scene: &Scene,
    packed: &PackedScene,
    s: &RenderSettings,
    schedule: CpuSchedule,
) -> RenderResult {
    render_with(scene, packed, s, &|_, _| {}, &mut RenderAll, schedule).expect("CPU render")
}

/// Every bit of the image: mean, variance and the auxiliary outputs.
fn bits(image: &Image) -> Vec<u32> {
    let variance = image.variance.as_deref().unwrap_or(&[]);
    let aov = &image.aovs;
    let albedo = aov.albedo.as_deref().unwrap_or(&[]);
    let normal = aov.normal.as_deref().unwrap_or(&[]);
    let depth = aov.depth.as_deref().unwrap_or(&[]);
    image
        .mean
        .iter()
        .chain(variance)
        .chain(albedo)
        .chain(normal)
        .flat_map(|p| p.map(f32::to_bits))
        .chain(depth.iter().map(|d| d.to_bits()))
        .collect()
}

/// Settings that reach every branch the lanes implement: bounces past
/// Russian roulette's start (unlimited depth), a depth limit ending paths
/// in the middle of the lanes, both samplers, a region, auxiliary outputs.
fn cases() -> Vec<(&'static str, RenderSettings)> {
    let base = RenderSettings {
        width: 40,
        height: 30,
        spp: 12,
        seed: 3,
        ..Default::default()
    };
    vec![
        ("sobol, unlimited depth", base.clone()),
        (
            "independent, unlimited depth",
            RenderSettings {
                sampler: Sampler::Independent,
                ..base.clone()
            },
        ),
        (
            "sobol, depth 2",
            RenderSettings {
                max_depth: Some(2),
                ..base.clone()
            },
        ),
        (
            "independent, depth 1 (emitters only)",
            RenderSettings {
                max_depth: Some(1),
                sampler: Sampler::Independent,
                ..base.clone()
            },
        ),
        (
            "sobol, auxiliary outputs",
            RenderSettings {
                aov: true,
                ..base.clone()
            },
        ),
        (
            "sobol, a region from sample 5",
            RenderSettings {
                region: Some(Region {
                    x0: 7,
                    y0: 4,
                    x1: 29,
                    y1: 21,
                }),
                first_sample: 5,
                ..base
            },
        ),
    ]
}

#[test]
fn lanes_trace_the_paths_of_the_one_path_schedule() {
    let mut covered = Vec::new();
    let mut scenes: Vec<_> = std::fs::read_dir(repo_path("scenes"))
        .expect("scenes folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "gltf"))
        .collect();
    scenes.sort();
    for path in scenes {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let (scene, packed) = load(&format!("scenes/{name}"));
        for (case, s) in cases() {
            if !lanes_cover(&packed) {
                continue;
            }
            covered.push(format!("{name}: {case}"));
            let lanes = render(&scene, &packed, &s, CpuSchedule::Lanes);
            let one = render(&scene, &packed, &s, CpuSchedule::OnePath);
            let (a, b) = (lanes.film.to_image(), one.film.to_image());
            assert_eq!(
                a.aovs.albedo.is_some(),
                s.aov,
                "{name}, {case}: auxiliary outputs recorded as asked"
            );
            let differing = bits(&a)
                .iter()
                .zip(bits(&b))
                .filter(|(x, y)| *x != y)
                .count();
            assert_eq!(differing, 0, "{name}, {case}: channels differ");
            assert_eq!(a.samples, b.samples, "{name}, {case}: sample counts");
            assert_eq!(
                (
                    lanes.extension_rays,
                    lanes.shadow_rays,
                    lanes.traversal_overflows
                ),
                (one.extension_rays, one.shadow_rays, one.traversal_overflows),
                "{name}, {case}: ray counts"
            );
            assert_eq!(lanes.nonfinite_samples, one.nonfinite_samples);
        }
    }
    println!("lanes and one path agree on {}:", covered.len());
    for c in &covered {
        println!("  {c}");
    }
    // The box is all Lambert; cornell-spheres and materials-showcase mix
    // it with glass, mirrors and glTF materials, which the lanes hand to
    // `shade_path`; env-sky and lights-showcase have an environment and
    // analytic lights, sampled by `sample_light` lane by lane.
    for scene in [
        "cornell-box.gltf",
        "cornell-spheres.gltf",
        "materials-showcase.gltf",
        "env-sky.gltf",
        "lights-showcase.gltf",
    ] {
        assert!(
            covered.iter().any(|c| c.starts_with(scene)),
            "{scene} is rendered with lanes"
        );
    }
}

/// Moving scenes take the one-path schedule. Static ones run in lanes,
/// which sample their lights in vector registers when all are untextured
/// emissive triangles and with `sample_light` lane by lane otherwise.
#[test]
fn what_the_lanes_cover() {
    let s = RenderSettings::default();
    for (name, triangles_only) in [
        ("scenes/cornell-box.gltf", true),
        ("scenes/env-sky.gltf", false),
        ("scenes/lights-showcase.gltf", false),
    ] {
        let (scene, packed) = load(name);
        let params = packed.render_params(&scene, &s, 0).expect("params");
        assert!(lanes_cover(&packed), "{name} runs in lanes");
        assert_eq!(
            triangle_lights_only(&packed, &params),
            triangles_only,
            "{name}"
        );
    }
    let (scene, _) = load("scenes/textured.gltf");
    let moving = in_motion(scene, 0.3, 0.1, glam::Vec3::X);
    let packed = PackedScene::new(&moving).expect("the moving scene packs");
    assert!(
        !lanes_cover(&packed),
        "a moving scene takes one path at a time"
    );
}
