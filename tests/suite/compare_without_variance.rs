//! `vkpt compare` on images without variance layers (another renderer's
//! EXRs), where the noise is estimated from the images
//! (`image::estimated_noise`). The inputs are vkpt renders on the CPU back
//! end with their variance layers dropped, as Mitsuba, Cycles or pbrt would
//! write them, rendered with the default (Sobol) sampler: the estimate
//! needs no particular sampler, only pixels whose noise is independent.

use crate::common;

use common::*;
use vkpt::image::Image;
use vkpt::image::estimated_noise::compare_estimating_noise;
use vkpt::render::RenderSettings;

const ALPHA: f64 = 0.01;

/// A render of the Cornell box as another renderer would hand it over:
/// mean only.
fn plain_render(size: u32, spp: u32, seed: u32) -> Image {
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let settings = RenderSettings {
        width: size,
        height: size,
        spp,
        seed,
        ..Default::default()
    };
    let mut image = render_cpu(&scene, &packed, &settings);
    image.variance = None;
    image.samples = None;
    image
}

/// Two independent renders of one scene agree: at most a couple of false
/// rejections in 60 pairs at α = 0.01 (the expected count is at most
/// 0.6; 3 or more would happen by chance with probability 2 %). Fixed
/// seeds, so the outcome is the same on every run.
#[test]
fn independent_renders_without_variance_are_accepted() {
    let pairs = 60u32;
    let mut rejected = Vec::new();
    let mut worst_p_ratio = f64::INFINITY;
    for k in 0..pairs {
        let a = plain_render(32, 64, 1000 + 2 * k);
        let b = plain_render(32, 64, 1001 + 2 * k);
        let cmp = compare_estimating_noise(&a, &b, ALPHA).expect("comparable");
        if k == 0 {
            println!("{cmp}");
        }
        if let Some(w) = cmp.worst {
            worst_p_ratio = worst_p_ratio.min(w.p / w.alpha);
        }
        if !cmp.passed() {
            rejected.push(format!("pair {k}: {cmp}"));
        }
    }
    println!(
        "{} of {pairs} pairs rejected at alpha {ALPHA}; smallest p / threshold {worst_p_ratio:.3}",
        rejected.len()
    );
    assert!(rejected.len() <= 2, "{}", rejected.join("\n"));
}

/// Planted biases on a 128×128 render at 128 spp, compared with another
/// seed's render, both without variance: the image 1 % darker and one
/// 16×16 block 5 % brighter are rejected; the unperturbed pair is not.
#[test]
fn a_one_percent_bias_and_a_five_percent_block_are_rejected_without_variance() {
    let a = plain_render(128, 128, 7);
    let b = plain_render(128, 128, 8);
    let cmp = compare_estimating_noise(&a, &b, ALPHA).expect("comparable");
    println!("unperturbed:\n{cmp}");
    assert!(cmp.passed(), "two seeds of one scene disagree:\n{cmp}");

    let mut darker = a.clone();
    for p in &mut darker.mean {
        p.iter_mut().for_each(|c| *c *= 0.99);
    }
    let cmp = compare_estimating_noise(&darker, &b, ALPHA).expect("comparable");
    println!("1 % darker:\n{cmp}");
    let whole = cmp.levels.iter().find(|l| l.whole_image).expect("whole");
    assert!(
        !cmp.passed() && whole.rejections > 0,
        "a 1 % bias was accepted:\n{cmp}"
    );

    // A block of the back wall and the tall box (not aligned to the 16×16
    // grid, so it straddles four tested blocks).
    let mut block = a.clone();
    for y in 40..56 {
        for x in 72..88 {
            let i = block.index(x, y);
            block.mean[i].iter_mut().for_each(|c| *c *= 1.05);
        }
    }
    let cmp = compare_estimating_noise(&block, &b, ALPHA).expect("comparable");
    println!("16x16 block 5 % brighter at (72, 40):\n{cmp}");
    assert!(!cmp.passed(), "a block 5 % off was accepted:\n{cmp}");
}
