//! The Vulkan kernels and the CPU reference implement the same estimator:
//! independent renders of the Cornell box must agree under a variance-aware
//! test (per pixel, per block and over the whole image, with Šidák and
//! Bonferroni corrections; see `vkpt::stats::compare`).
//!
//! The second test checks the comparison has the power to see a real bug:
//! a 3% albedo error on one side must be rejected.

mod common;

use common::*;
use vkpt::settings::RenderSettings;
use vkpt::stats::{compare, write_failure_evidence};

const ALPHA: f64 = 0.01;

fn settings(seed: u32) -> RenderSettings {
    RenderSettings {
        width: 48,
        height: 48,
        spp: 512,
        max_depth: None,
        seed,
        camera: 0,
    }
}

#[test]
fn cornell_box_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("cornell_box_gpu_matches_cpu") else {
        return;
    };
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let a = render_gpu(&mut gpu, &scene, &packed, &settings(1));
    let b = render_cpu(&scene, &packed, &settings(2));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("{cmp}");
    if !cmp.passed() {
        let dir = failure_dir("cornell_box_gpu_matches_cpu");
        write_failure_evidence(&dir, &a, &b, &cmp).expect("evidence written");
        panic!("GPU and CPU disagree; evidence in {}", dir.display());
    }
}

#[test]
fn comparison_rejects_a_three_percent_albedo_error() {
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let mut brighter = vkpt::packed::PackedScene::new(&scene).expect("packs");
    for m in &mut brighter.materials {
        for c in &mut m.base_color[..3] {
            *c *= 1.03;
        }
    }
    let a = render_cpu(&scene, &packed, &settings(3));
    let b = render_cpu(&scene, &brighter, &settings(4));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("{cmp}");
    assert!(!cmp.passed(), "a 3% albedo error went unnoticed");
}
