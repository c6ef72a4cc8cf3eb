//! The per-path loop schedule (`shaders/path_loop/path_loop.comp`) traces the
//! same paths as the wavefront kernels: the same seed gives the same pixels,
//! bit for bit, and so do the paths the loop parks for the wavefront to
//! finish (lavapipe's loop limit). A loop budget lowered far below
//! `PATH_LOOP_BUDGET` makes many paths park after a few bounces, which the
//! test sees happen; one too small for any bounce makes the wavefront trace it
//! all. lavapipe as several single-threaded devices, each tracing its share
//! of every pass's samples, traces the paths one device traces.

use crate::common;

use common::*;
use std::sync::Mutex;
use vkpt::constants::PATH_LOOP_BUDGET;
use vkpt::film::Film;
use vkpt::gpu::{GpuRenderer, Schedule};
use vkpt::image::Image;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::render::{PassControl, RenderResult};
use vkpt::scene::Scene;

/// Scenes whose paths take the estimator's every branch: long glass paths,
/// textures and alpha coverage (seeded by bounce), spherical lights, an
/// environment, layered lobes, a thin lens and a filter sampled by
/// bisection. The test also renders textured.gltf in motion.
const SCENES: [&str; 7] = [
    "scenes/cornell-box.gltf",
    "scenes/cornell-spheres.gltf",
    "scenes/textured.gltf",
    "scenes/lights-showcase.gltf",
    "scenes/env-sky.gltf",
    "scenes/coat-grid.gltf",
    "scenes/depth-of-field.gltf",
];

/// A budget that leaves a subgroup room for one or two bounces per lane:
/// longer paths are parked after bounces in the loop.
const SMALL_BUDGET: u32 = 4000;

fn settings(aov: bool) -> RenderSettings {
    RenderSettings {
        width: 32,
        height: 24,
        spp: 8,
        seed: 5,
        aov,
        ..Default::default()
    }
}

fn bits(v: &[[f32; 3]]) -> Vec<[u32; 3]> {
    v.iter().map(|p| p.map(f32::to_bits)).collect()
}

/// Pixels where the two renders differ in any bit of mean, variance, sample
/// count or auxiliary output.
/// The image and the paths parked. (The validation layer's messages are
/// checked when `Gpu` drops.)
fn render(
    gpu: &mut GpuRenderer,
    scene: &Scene,
    packed: &PackedScene,
    s: &RenderSettings,
) -> (Image, u64) {
    let r = gpu
        .render(scene, packed, s, &|_, _| {})
        .expect("GPU render succeeds");
    assert_eq!(r.traversal_overflows, 0, "BVH traversal overflowed");
    assert_eq!(r.nonfinite_samples, 0, "non-finite samples");
    (r.film.to_image(), r.paths_parked)
}

fn differing_pixels(a: &Image, b: &Image) -> usize {
    let (ma, mb) = (bits(&a.mean), bits(&b.mean));
    let (va, vb) = (
        bits(a.variance.as_deref().unwrap_or(&[])),
        bits(b.variance.as_deref().unwrap_or(&[])),
    );
    let mut n = (0..ma.len())
        .filter(|&i| ma[i] != mb[i] || va.get(i) != vb.get(i))
        .count();
    if a.samples != b.samples || a.aovs != b.aovs {
        n += 1;
    }
    n
}

#[test]
fn the_per_path_loop_gives_the_wavefronts_pixels() {
    let Some(mut gpu) = gpu_renderer("schedules") else {
        return;
    };
    // And a moving scene: every path at its own time (motion.glsl).
    let scenes = SCENES.iter().map(|p| (*p, false));
    for (i, (path, moving)) in scenes.chain([("scenes/textured.gltf", true)]).enumerate() {
        let (mut scene, mut packed) = load(path);
        if moving {
            scene = in_motion(scene, 0.3, 1.2, glam::Vec3::new(0.05, 0.0, 0.02));
            packed = PackedScene::new(&scene).expect("packs");
        }
        // AOVs on in every other scene: the loop keeps them in registers.
        let s = settings(i % 2 == 0);
        gpu.schedule = Schedule::Wavefront;
        let (wavefront, parked) = render(&mut gpu, &scene, &packed, &s);
        assert_eq!(parked, 0);

        gpu.schedule = Schedule::PathLoop;
        gpu.loop_budget = PATH_LOOP_BUDGET;
        let (looped, parked_default) = render(&mut gpu, &scene, &packed, &s);

        gpu.loop_budget = SMALL_BUDGET;
        let (parking, parked_small) = render(&mut gpu, &scene, &packed, &s);

        // Too small for one bounce: the wavefront traces every chunk.
        gpu.loop_budget = 500;
        let (fallen_back, parked) = render(&mut gpu, &scene, &packed, &s);
        assert_eq!(parked, 0);
        gpu.loop_budget = PATH_LOOP_BUDGET;

        let paths = s.pixel_count() * s.spp as u64;
        println!(
            "{path}: paths parked {parked_default} of {paths} (budget {PATH_LOOP_BUDGET}), \
             {parked_small} (budget {SMALL_BUDGET})"
        );
        assert!(
            parked_small * 20 > paths,
            "{path}: a budget of {SMALL_BUDGET} parked only {parked_small} of {paths} paths"
        );
        assert_eq!(
            differing_pixels(&looped, &wavefront),
            0,
            "{path}: the per-path loop changes the image"
        );
        assert_eq!(
            differing_pixels(&parking, &wavefront),
            0,
            "{path}: paths parked by the per-path loop end differently"
        );
        assert_eq!(
            differing_pixels(&fallen_back, &wavefront),
            0,
            "{path}: the fallback to the wavefront changes the image"
        );
    }
}

/// Kernels are compiled by the first render that needs them, not with the
/// renderer: `--device auto` makes a renderer to measure or to leave unused
/// when its cached choice is the CPU back end, and lavapipe takes seconds
/// per kernel. The wavefront never compiles the per-path loop; the loop
/// schedule adds it beside the wavefront kernels it parks paths with.
#[test]
fn kernels_are_compiled_by_the_render_that_needs_them() {
    let Some(mut gpu) = gpu_renderer("lazy kernels") else {
        return;
    };
    assert_eq!(gpu.compiled_kernels(), Vec::<&str>::new());
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let s = RenderSettings {
        spp: 1,
        ..settings(false)
    };
    gpu.schedule = Schedule::Wavefront;
    render(&mut gpu, &scene, &packed, &s);
    let wavefront = gpu.compiled_kernels();
    assert!(wavefront.contains(&"shade"), "{wavefront:?}");
    assert!(!wavefront.contains(&"path_loop"), "{wavefront:?}");
    // The same render again compiles nothing.
    let compiled = gpu.startup.pipelines;
    render(&mut gpu, &scene, &packed, &s);
    assert_eq!(gpu.startup.pipelines, compiled, "kernels compiled again");
    if !gpu.supports_path_loop() {
        println!("no subgroup arithmetic: the loop schedule does not run here");
        return;
    }
    gpu.schedule = Schedule::PathLoop;
    render(&mut gpu, &scene, &packed, &s);
    let looped = gpu.compiled_kernels();
    assert!(looped.contains(&"path_loop"), "{looped:?}");
    assert_eq!(looped.len(), wavefront.len() + 1, "{looped:?}");
}

/// Records the samples per pixel after each pass.
struct Passes(Vec<u32>);

impl PassControl for Passes {
    fn after_pass(
        &mut self,
        spp: u32,
        film: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool> {
        let f = film()?;
        assert!(
            f.pixels.iter().all(|p| p.mean[3] == spp as f32),
            "pass {spp}: sample counts"
        );
        self.0.push(spp);
        Ok(true)
    }
}

/// The render, its passes and its progress reports.
fn render_passes(
    gpu: &mut GpuRenderer,
    scene: &Scene,
    packed: &PackedScene,
    s: &RenderSettings,
) -> (RenderResult, Vec<u32>, Vec<(u64, u64)>) {
    let reports = Mutex::new(Vec::new());
    let mut passes = Passes(Vec::new());
    let r = gpu
        .render_progressive(
            scene,
            packed,
            s,
            &|done, total| reports.lock().expect("unpoisoned").push((done, total)),
            &mut passes,
        )
        .expect("GPU render succeeds");
    let reports = reports.into_inner().expect("unpoisoned");
    (r, passes.0, reports)
}

/// lavapipe as three devices of one thread (`vkpt::gpu::split`): every
/// pass is split into contiguous sample ranges, one per device, and the
/// films are merged. The paths are those one device traces: the same rays,
/// and the same pixels up to the rounding of merging running means. At
/// 384x384 a pool holds one sample per pixel, so passes are 3 samples (one
/// per device) and the last, of 1 sample, leaves two devices idle.
#[test]
fn lavapipe_devices_split_the_samples_of_every_pass() {
    let Some(mut one) = gpu_renderer_with_devices("lavapipe devices", 1) else {
        return;
    };
    if !one.is_cpu_device() {
        println!("lavapipe devices: a GPU renders as one device");
        return;
    }
    let Some(mut three) = gpu_renderer_with_devices("lavapipe devices", 3) else {
        return;
    };
    assert_eq!((one.device_count(), three.device_count()), (1, 3));
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let s = RenderSettings {
        width: 384,
        height: 384,
        spp: 7,
        seed: 11,
        ..Default::default()
    };
    let (single, _, _) = render_passes(&mut one, &scene, &packed, &s);
    let (split, passes, reports) = render_passes(&mut three, &scene, &packed, &s);
    assert_eq!(passes, vec![3, 6], "passes of the split render");
    let total = s.pixel_count() * s.spp as u64;
    assert_eq!(reports.first(), Some(&(0, total)), "progress starts at 0");
    assert_eq!(
        reports.last(),
        Some(&(total, total)),
        "progress ends at the total"
    );
    assert!(
        reports.windows(2).all(|w| w[0].0 <= w[1].0),
        "progress goes back"
    );
    assert_eq!(split.spp, s.spp);
    assert_eq!(
        (split.extension_rays, split.shadow_rays),
        (single.extension_rays, single.shadow_rays),
        "the devices traced other rays than one device"
    );
    let (a, b) = (split.film.to_image(), single.film.to_image());
    assert_eq!(a.samples, b.samples, "sample counts");
    let differing = pixels_differing(&a, &b, 1e-5);
    assert_eq!(
        differing, 0,
        "{differing} pixels differ from one device's render"
    );
}
