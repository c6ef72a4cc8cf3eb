//! What specializing the kernels to a scene buys (src/features.rs): the
//! same renders with the scene's kernel variant and with the all-features
//! kernels, alternating run by run on one renderer, median of per-run
//! throughput ratios.
//!
//!     cargo bench --bench specialization
//!     VKPT_BENCH_RUNS=7 VKPT_BENCH_SPP=32 VKPT_BENCH_SIZE=256 cargo bench --bench specialization
//!
//! Every variant is warmed up first: lavapipe compiles kernels at their
//! first dispatch, and that start-up cost is not what is measured here.

mod common;

use common::{env_or, median};
use std::path::Path;
use vkpt::gpu::GpuRenderer;
use vkpt::gpu::context::VulkanDevice;
use vkpt::packed::PackedScene;
use vkpt::packed::features::KernelFeatures;
use vkpt::render::RenderSettings;
use vkpt::scene::Scene;

fn main() {
    let runs = env_or("VKPT_BENCH_RUNS", 5);
    let spp = env_or("VKPT_BENCH_SPP", 16);
    let size = env_or("VKPT_BENCH_SIZE", 256);
    let mut gpu = match GpuRenderer::new(VulkanDevice::Best) {
        Ok(g) => g,
        Err(e) => {
            println!("no Vulkan device ({e:#}): nothing to measure");
            return;
        }
    };
    println!(
        "{} | {size}x{size}, {spp} spp, unlimited depth, median of {runs} alternating runs",
        gpu.device_name()
    );
    println!(
        "{:<28} {:<44} {:>11} {:>11} {:>8}",
        "scene", "specialized to", "Ms/s spec.", "Ms/s all", "ratio"
    );
    for name in [
        "cornell-box",
        "textured",
        "materials-showcase",
        "lights-showcase",
    ] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.gltf"));
        let scene = Scene::load(&path).expect("bundled scene loads");
        let packed = PackedScene::new(&scene).expect("packs");
        let settings = RenderSettings {
            width: size,
            height: size,
            spp,
            ..Default::default()
        };
        let params = packed
            .render_params(&scene, &settings, 1 << 18)
            .expect("params");
        let variant = KernelFeatures::of(&packed, &params).describe();
        let samples = settings.pixel_count() as f64 * spp as f64;
        let mut rate = |all: bool, s: &RenderSettings| {
            gpu.all_features = all;
            let r = gpu.render(&scene, &packed, s, &|_, _| {}).expect("renders");
            samples / r.render_time.as_secs_f64() * (s.spp as f64 / spp as f64)
        };
        let warm = RenderSettings {
            spp: 1,
            ..settings.clone()
        };
        rate(true, &warm);
        rate(false, &warm);
        let (mut spec, mut all, mut ratios) = (vec![], vec![], vec![]);
        for run in 0..runs {
            // Alternate which goes first, so drift in machine load cancels.
            let (s, a) = if run % 2 == 0 {
                let s = rate(false, &settings);
                (s, rate(true, &settings))
            } else {
                let a = rate(true, &settings);
                (rate(false, &settings), a)
            };
            spec.push(s / 1e6);
            all.push(a / 1e6);
            ratios.push(s / a);
        }
        println!(
            "{:<28} {:<44} {:>11.3} {:>11.3} {:>7.3}x",
            name,
            variant,
            median(spec),
            median(all),
            median(ratios)
        );
    }
}
