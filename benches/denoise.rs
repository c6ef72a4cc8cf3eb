//! What denoising buys: relMSE against a converged reference, raw and
//! denoised with Open Image Denoise (`vkpt --denoise`), at several spp, and
//! the denoiser's time.
//!
//!     cargo bench --bench denoise
//!     VKPT_BENCH_SIZE=128 VKPT_BENCH_SPPS=4,16 cargo bench --bench denoise
//!     VKPT_BENCH_SCENE=scenes/cornell-spheres.gltf cargo bench --bench denoise
//!
//! Renders run on the CPU back end (it traces the same paths as the Vulkan
//! kernels), with Sobol sampling and seed 0 as `vkpt` does by default. The
//! reference (default 2048 spp, seed `REFERENCE_SEED`) is cached where `vkpt
//! bench` caches its references. The denoiser's time is the median of 3
//! calls after a warm-up call (library loading), each making its own device
//! and filters as `vkpt --denoise` does. Two denoised columns: the beauty
//! alone, and guided by the render's albedo and normal AOVs (prefiltered),
//! as `vkpt --denoise` runs it.

mod common;

use common::{env_or, median};
use std::path::PathBuf;
use std::time::Instant;
use vkpt::bench::reference;
use vkpt::image::Image;
use vkpt::image::compare::rel_mse;
use vkpt::image::denoise::{available, denoise, library_description};
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::Scene;

fn render(scene: &Scene, packed: &PackedScene, settings: &RenderSettings) -> Image {
    vkpt::cpu::render::render(scene, packed, settings, &|_, _| {})
        .expect("CPU render")
        .film
        .to_image()
}

fn main() {
    if let Err(e) = available() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
    let size: u32 = env_or("VKPT_BENCH_SIZE", 256);
    let ref_spp: u32 = env_or("VKPT_BENCH_REF_SPP", 2048);
    let spps: Vec<u32> = std::env::var("VKPT_BENCH_SPPS")
        .ok()
        .and_then(|v| v.split(',').map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![4, 16, 64]);
    let scene_path = std::env::var("VKPT_BENCH_SCENE").map_or_else(
        |_| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.gltf"),
        PathBuf::from,
    );
    let scene = Scene::load(&scene_path).expect("the scene loads");
    let packed = PackedScene::new(&scene).expect("packs");
    let base = RenderSettings {
        width: size,
        height: size,
        aov: true,
        ..Default::default()
    };

    let ref_settings = RenderSettings {
        spp: ref_spp,
        seed: reference::REFERENCE_SEED,
        aov: false,
        ..base.clone()
    };
    let path = reference::cache_path(&scene_path, &ref_settings).expect("a cache directory");
    let reference = if path.exists() {
        println!("reference: {} (cached)", path.display());
        reference::load(&path, size, size).expect("the cached reference reads")
    } else {
        println!("reference: rendering {ref_spp} spp on the CPU back end...");
        let start = Instant::now();
        let image = render(&scene, &packed, &ref_settings);
        println!(
            "reference: done in {:.1} s, cached in {}",
            start.elapsed().as_secs_f64(),
            path.display()
        );
        reference::store(&path, &image).expect("the reference is cached");
        image
    };
    println!(
        "{}, {size}x{size}, reference {ref_spp} spp (its own estimated relMSE {:.1e}, an \
         overestimate with Sobol); {}",
        scene_path.display(),
        reference.estimated_rel_mse(),
        library_description().unwrap_or_default()
    );
    println!(
        "{:>5} {:>12} {:>12} {:>8} {:>12} {:>8} {:>11}",
        "spp", "raw relMSE", "beauty only", "raw/den.", "with AOVs", "raw/den.", "denoise ms"
    );
    let mut warmed = false;
    for &spp in &spps {
        let image = render(
            &scene,
            &packed,
            &RenderSettings {
                spp,
                ..base.clone()
            },
        );
        let (albedo, normal) = (image.aovs.albedo.as_deref(), image.aovs.normal.as_deref());
        let run = |guided: bool| {
            let start = Instant::now();
            let (a, n) = if guided {
                (albedo, normal)
            } else {
                (None, None)
            };
            let out = denoise(size, size, &image.mean, a, n).expect("denoising");
            (out, start.elapsed().as_secs_f64())
        };
        if !warmed {
            run(true);
            warmed = true;
        }
        let runs: Vec<(Vec<[f32; 3]>, f64)> = (0..3).map(|_| run(true)).collect();
        let time = median(runs.iter().map(|r| r.1).collect());
        let relmse_of = |mean: Vec<[f32; 3]>| {
            rel_mse(
                &Image {
                    mean,
                    ..image.clone()
                },
                &reference,
            )
        };
        let raw = rel_mse(&image, &reference);
        let beauty = relmse_of(run(false).0);
        let guided = relmse_of(runs[0].0.clone());
        println!(
            "{spp:>5} {raw:>12.3e} {beauty:>12.3e} {:>8.2} {guided:>12.3e} {:>8.2} {:>11.1}",
            raw / beauty,
            raw / guided,
            time * 1e3
        );
    }
}
