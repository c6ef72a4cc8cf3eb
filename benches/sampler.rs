//! Error at equal spp of the two samplers (`--sampler independent|sobol`) on
//! every bundled scene: relMSE against a converged reference, averaged over
//! independent seeds, at several spp.
//!
//!     cargo bench --bench sampler
//!     VKPT_BENCH_SIZE=64 VKPT_BENCH_REF_SPP=8192 VKPT_BENCH_SEEDS=4 cargo bench --bench sampler
//!     VKPT_BENCH_SCENES=furnace-glass cargo bench --bench sampler
//!
//! The reference is rendered with the independent sampler, whose per-pixel
//! variance estimate is valid, and its own expected relMSE (from that
//! variance) is subtracted from every figure, so what is printed estimates
//! the error against the true image. Renders run on the CPU reference, which
//! traces the same paths as the Vulkan kernels (tests/gpu_vs_cpu.rs).

mod common;

use common::env_or;
use std::path::Path;
use vkpt::film::Image;
use vkpt::packed::PackedScene;
use vkpt::scene::Scene;
use vkpt::settings::{RenderSettings, Sampler};
use vkpt::stats::rel_mse;

fn render(scene: &Scene, packed: &PackedScene, settings: &RenderSettings) -> Image {
    vkpt::cpu::render::render(scene, packed, settings, &|_, _| {})
        .expect("CPU render")
        .film
        .to_image()
}

fn main() {
    let size: u32 = env_or("VKPT_BENCH_SIZE", 48);
    let ref_spp: u32 = env_or("VKPT_BENCH_REF_SPP", 4096);
    let seeds: u32 = env_or("VKPT_BENCH_SEEDS", 4);
    let spps = [4u32, 16, 64, 256];
    // Only scenes whose path contains this text.
    let only = std::env::var("VKPT_BENCH_SCENES").unwrap_or_default();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut scenes: Vec<_> = std::fs::read_dir(&dir)
        .expect("scenes/ is readable")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "gltf"))
        .filter(|p| p.to_string_lossy().contains(&only))
        .collect();
    scenes.sort();
    println!(
        "relMSE at equal spp, {size}x{size}, mean of {seeds} seeds, reference {ref_spp} spp \
         (its own estimated relMSE subtracted)"
    );
    println!(
        "{:<28} {:>5} {:>12} {:>12} {:>9}",
        "scene", "spp", "independent", "sobol", "ind/sobol"
    );
    for path in scenes {
        let scene = Scene::load(&path).expect("bundled scene loads");
        let packed = PackedScene::new(&scene).expect("packs");
        let base = RenderSettings {
            width: size,
            height: size,
            ..Default::default()
        };
        let reference = render(
            &scene,
            &packed,
            &RenderSettings {
                spp: ref_spp,
                seed: 1_000_000,
                sampler: Sampler::Independent,
                ..base.clone()
            },
        );
        let ref_error = reference.estimated_rel_mse();
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        for spp in spps {
            let mut row = Vec::new();
            for sampler in [Sampler::Independent, Sampler::Sobol] {
                let mut sum = 0.0;
                for seed in 0..seeds {
                    let s = RenderSettings {
                        spp,
                        seed,
                        sampler,
                        ..base.clone()
                    };
                    sum += rel_mse(&render(&scene, &packed, &s), &reference);
                }
                row.push(sum / seeds as f64 - ref_error);
            }
            println!(
                "{name:<28} {spp:>5} {:>12.3e} {:>12.3e} {:>9.2}",
                row[0],
                row[1],
                row[0] / row[1]
            );
        }
        println!("{name:<28} reference's own estimated relMSE {ref_error:.2e}");
    }
}
