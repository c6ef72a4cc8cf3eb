//! How `vkpt compare` judges images without variance layers (another
//! renderer's EXRs), with the noise estimated from the images
//! (`vkpt::image::estimated_noise`), measured on vkpt renders of the Cornell
//! box with their variance layers dropped (CPU back end, default Sobol
//! sampler, about 5 minutes on 2 cores):
//!
//!     cargo run --release --example compare_without_variance
//!
//! 1. Planted perturbations of a 256-spp 256×256 render, judged against a
//!    1024-spp render (a nearly converged reference, as a Mitsuba user would
//!    compare with) and against another 256-spp render; beside each, the
//!    former criterion (relMSE ≤ 1e-3 alone).
//! 2. False rejections: `VKPT_PAIRS` (default 50) pairs of independent
//!    64×64 renders at 64 spp, each compared at α = 0.01.

use vkpt::image::Image;
use vkpt::image::compare::Comparison;
use vkpt::image::compare::rel_mse;
use vkpt::image::estimated_noise::compare_estimating_noise;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::Scene;

const ALPHA: f64 = 0.01;

fn render(scene: &Scene, packed: &PackedScene, size: u32, spp: u32, seed: u32) -> Image {
    let settings = RenderSettings {
        width: size,
        height: size,
        spp,
        seed,
        ..Default::default()
    };
    let result = vkpt::cpu::render::render(scene, packed, &settings, &|_, _| {})
        .expect("the CPU back end renders the Cornell box");
    let mut image = result.film.to_image();
    image.variance = None;
    image.samples = None;
    image
}

/// `image` with the pixels of the rectangle [x0, x1) × [y0, y1), channels
/// `channels`, scaled by `gain`.
fn scaled(
    image: &Image,
    (x0, y0, x1, y1): (u32, u32, u32, u32),
    channels: &[usize],
    gain: f32,
) -> Image {
    let mut out = image.clone();
    for y in y0..y1 {
        for x in x0..x1 {
            let i = out.index(x, y);
            for &c in channels {
                out.mean[i][c] *= gain;
            }
        }
    }
    out
}

/// One line: the verdict, the level and z of the most significant finding.
fn verdict(cmp: &Comparison) -> String {
    let worst = cmp
        .worst
        .map(|w| {
            let level = if w.block >= cmp.width.max(cmp.height) {
                "image".to_string()
            } else {
                format!("{0}x{0}", w.block)
            };
            format!("worst {level} t {:+.1}", w.z)
        })
        .unwrap_or_default();
    let rejected: Vec<String> = cmp
        .levels
        .iter()
        .filter(|l| l.rejections > 0)
        .map(|l| format!("{} {}", l.rejections, l.name()))
        .collect();
    if cmp.passed() {
        format!("agree     ({worst})")
    } else {
        format!("REJECTED  ({}; {worst})", rejected.join(", "))
    }
}

fn main() -> anyhow::Result<()> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.gltf");
    let scene = Scene::load(&path)?;
    let packed = PackedScene::new(&scene)?;

    println!("rendering 256x256: a and b at 256 spp, the reference at 1024 spp ...");
    let a = render(&scene, &packed, 256, 256, 1);
    let b = render(&scene, &packed, 256, 256, 2);
    let reference = render(&scene, &packed, 256, 1024, 3);
    let full = (0, 0, 256, 256);
    let rgb = [0, 1, 2];
    let cases: Vec<(&str, Image)> = vec![
        ("unperturbed", a.clone()),
        ("whole image 0.5 % darker", scaled(&a, full, &rgb, 0.995)),
        ("whole image 1 % darker", scaled(&a, full, &rgb, 0.99)),
        ("whole image 3 % darker", scaled(&a, full, &rgb, 0.97)),
        ("red channel 1 % brighter", scaled(&a, full, &[0], 1.01)),
        (
            "16x16 block on the back wall +5 %",
            scaled(&a, (120, 60, 136, 76), &rgb, 1.05),
        ),
        (
            "16x16 block on the floor +5 %",
            scaled(&a, (100, 210, 116, 226), &rgb, 1.05),
        ),
        (
            "16x16 block on the red wall +5 %",
            scaled(&a, (20, 100, 36, 116), &rgb, 1.05),
        ),
        (
            "16x16 block on the back wall +2 %",
            scaled(&a, (120, 60, 136, 76), &rgb, 1.02),
        ),
        (
            "16x16 block on the back wall +10 %",
            scaled(&a, (120, 60, 136, 76), &rgb, 1.10),
        ),
        (
            "4x4 block on the back wall +20 %",
            scaled(&a, (124, 64, 128, 68), &rgb, 1.2),
        ),
        (
            "one pixel on the back wall x2",
            scaled(&a, (128, 64, 129, 65), &rgb, 2.0),
        ),
    ];
    for (against, other) in [
        ("1024-spp reference", &reference),
        ("another 256-spp render", &b),
    ] {
        println!("\nagainst the {against} (alpha {ALPHA}):");
        println!(
            "{:<36} {:<60} relMSE <= 1e-3 alone",
            "perturbation of a", "estimated noise"
        );
        for (name, image) in &cases {
            let cmp = compare_estimating_noise(image, other, ALPHA)?;
            let r = rel_mse(image, other);
            let old = if r <= 1e-3 { "agree" } else { "REJECTED" };
            println!("{name:<36} {:<60} {old} ({r:.2e})", verdict(&cmp));
        }
    }
    let cmp = compare_estimating_noise(&a, &reference, ALPHA)?;
    println!("\nthe unperturbed comparison in full:\n{cmp}");

    let pairs: u32 = std::env::var("VKPT_PAIRS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(50);
    println!("\nfalse rejections: {pairs} pairs of independent 64x64 renders at 64 spp ...");
    let mut rejected = 0;
    let mut smallest = f64::INFINITY;
    for k in 0..pairs {
        let x = render(&scene, &packed, 64, 64, 100 + 2 * k);
        let y = render(&scene, &packed, 64, 64, 101 + 2 * k);
        let cmp = compare_estimating_noise(&x, &y, ALPHA)?;
        if let Some(w) = cmp.worst {
            smallest = smallest.min(w.p / w.alpha);
        }
        if !cmp.passed() {
            rejected += 1;
            println!("pair {k} rejected:\n{cmp}");
        }
    }
    println!(
        "{rejected} of {pairs} pairs rejected at alpha {ALPHA} (expected at most {:.1}); \
         smallest p / threshold {smallest:.2}",
        ALPHA * pairs as f64
    );
    Ok(())
}
