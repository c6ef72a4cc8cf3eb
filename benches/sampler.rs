//! Error at equal spp of the two samplers (`--sampler independent|sobol`) on
//! every bundled scene: relMSE against a converged reference, averaged over
//! independent seeds, at several spp.
//!
//!     cargo bench --bench sampler
//!     VKPT_BENCH_SIZE=64 VKPT_BENCH_REF_SPP=8192 VKPT_BENCH_SEEDS=16 cargo bench --bench sampler
//!     VKPT_BENCH_SCENES=furnace-glass cargo bench --bench sampler
//!     VKPT_BENCH_SCENES=env-sky VKPT_BENCH_SEEDS=128 VKPT_BENCH_SPPS=16,64 cargo bench --bench sampler
//!
//! Each figure is the mean over seeds with its standard error, and the
//! ratio's error to first order: the glass furnaces' error is heavy-tailed
//! (rare long internal-reflection paths), so they need 16 or more seeds.
//!
//! The reference is rendered with the independent sampler, whose per-pixel
//! variance estimate is valid, and its own expected relMSE (from that
//! variance) is subtracted from every figure, so what is printed estimates
//! the error against the true image. Renders run on the CPU reference, which
//! traces the same paths as the Vulkan kernels (tests/suite/gpu_vs_cpu.rs).

mod common;

use common::env_or;
use std::path::Path;
use vkpt::image::Image;
use vkpt::image::compare::rel_mse;
use vkpt::packed::PackedScene;
use vkpt::render::{RenderSettings, Sampler};
use vkpt::scene::Scene;

fn render(scene: &Scene, packed: &PackedScene, settings: &RenderSettings) -> Image {
    vkpt::cpu::render::render(scene, packed, settings, &|_, _| {})
        .expect("CPU render")
        .film
        .to_image()
}

/// Mean relMSE over seeds less the reference's own, and the standard error
/// of that mean.
fn mean_and_error(errors: &[f64], ref_error: f64) -> (f64, f64) {
    let n = errors.len() as f64;
    let mean = errors.iter().sum::<f64>() / n;
    let var = errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean - ref_error, (var / n).sqrt())
}

fn main() {
    let size: u32 = env_or("VKPT_BENCH_SIZE", 48);
    let ref_spp: u32 = env_or("VKPT_BENCH_REF_SPP", 4096);
    let seeds: u32 = env_or("VKPT_BENCH_SEEDS", 8);
    // Comma-separated, e.g. VKPT_BENCH_SPPS=16,64.
    let spps: Vec<u32> = std::env::var("VKPT_BENCH_SPPS")
        .ok()
        .and_then(|v| v.split(',').map(|x| x.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![4, 16, 64, 256]);
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
        "(± the standard error over seeds: on scenes with rare bright paths, such as the glass \
         furnaces, the error is heavy-tailed and a few seeds decide little)"
    );
    println!(
        "{:<28} {:>5} {:>12} {:>8} {:>12} {:>8} {:>9} {:>6}",
        "scene", "spp", "independent", "±", "sobol", "±", "ind/sobol", "±"
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
        for &spp in &spps {
            let mut row = Vec::new();
            for sampler in [Sampler::Independent, Sampler::Sobol] {
                let errors: Vec<f64> = (0..seeds)
                    .map(|seed| {
                        let s = RenderSettings {
                            spp,
                            seed,
                            sampler,
                            ..base.clone()
                        };
                        rel_mse(&render(&scene, &packed, &s), &reference)
                    })
                    .collect();
                row.push(mean_and_error(&errors, ref_error));
            }
            let (ind, sobol) = (row[0], row[1]);
            // The ratio's relative standard error, to first order.
            let ratio = ind.0 / sobol.0;
            let rel = ((ind.1 / ind.0).powi(2) + (sobol.1 / sobol.0).powi(2)).sqrt();
            println!(
                "{name:<28} {spp:>5} {:>12.3e} {:>8.1e} {:>12.3e} {:>8.1e} {ratio:>9.2} {:>6.2}",
                ind.0,
                ind.1,
                sobol.0,
                sobol.1,
                ratio * rel
            );
        }
        println!("{name:<28} reference's own estimated relMSE {ref_error:.2e}");
    }
}
