//! Throughput of both back ends on the bundled Cornell box, measured side by
//! side in one run (the machines are shared and noisy: runs alternate between
//! back ends and the median is reported).
//!
//!     cargo bench --bench render
//!     VKPT_BENCH_RUNS=7 VKPT_BENCH_SPP=64 cargo bench --bench render
//!
//! Unlimited depth (Russian roulette), as a user renders by default. The
//! first Vulkan render is a warm-up: lavapipe compiles kernels at their first
//! dispatch.

mod common;

use common::{env_or, median};
use std::path::Path;
use vkpt::gpu::GpuRenderer;
use vkpt::gpu::context::VulkanDevice;
use vkpt::packed::PackedScene;
use vkpt::render::RenderResult;
use vkpt::render::RenderSettings;
use vkpt::scene::Scene;

struct Row {
    samples_per_s: Vec<f64>,
    rays_per_s: Vec<f64>,
    rel_error: Vec<f64>,
}

impl Row {
    fn new() -> Row {
        Row {
            samples_per_s: vec![],
            rays_per_s: vec![],
            rel_error: vec![],
        }
    }

    fn add(&mut self, r: &RenderResult, samples: f64) {
        let s = r.render_time.as_secs_f64();
        self.samples_per_s.push(samples / s);
        self.rays_per_s
            .push((r.extension_rays + r.shadow_rays) as f64 / s);
        self.rel_error.push(r.film.to_image().estimated_rel_error());
    }
}

fn main() {
    // `cargo bench` passes --bench; `cargo test --benches` would pass nothing useful.
    let runs = env_or("VKPT_BENCH_RUNS", 5);
    let spp = env_or("VKPT_BENCH_SPP", 32);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.gltf");
    let scene = Scene::load(&path).expect("the bundled Cornell box loads");
    let packed = PackedScene::new(&scene).expect("packs");
    let mut gpu = match GpuRenderer::new(VulkanDevice::Best) {
        Ok(g) => Some(g),
        Err(e) => {
            println!("no Vulkan device ({e:#}); benchmarking the CPU reference only");
            None
        }
    };
    let device = gpu.as_ref().map(|g| g.device_name()).unwrap_or_default();
    println!("Cornell box, {spp} spp, unlimited depth, median of {runs} runs");
    println!(
        "{:<10} {:<34} {:>14} {:>12} {:>10}",
        "size", "back end", "Msamples/s", "Mrays/s", "rel. err"
    );
    for size in [256u32, 512] {
        let settings = RenderSettings {
            width: size,
            height: size,
            spp,
            ..Default::default()
        };
        let samples = settings.pixel_count() as f64 * spp as f64;
        let (mut g_row, mut c_row) = (Row::new(), Row::new());
        if let Some(g) = gpu.as_mut() {
            let warm = RenderSettings {
                spp: 1,
                ..settings.clone()
            };
            g.render(&scene, &packed, &warm, &|_, _| {})
                .expect("warm-up render");
        }
        let mut cpu_name = String::new();
        for _ in 0..runs {
            if let Some(g) = gpu.as_mut() {
                let r = g
                    .render(&scene, &packed, &settings, &|_, _| {})
                    .expect("GPU render");
                g_row.add(&r, samples);
            }
            let r = vkpt::cpu::render::render(&scene, &packed, &settings, &|_, _| {})
                .expect("CPU render");
            cpu_name = r.device_name.clone();
            c_row.add(&r, samples);
        }
        for (name, row) in [(device.as_str(), &g_row), (cpu_name.as_str(), &c_row)] {
            if row.samples_per_s.is_empty() {
                continue;
            }
            println!(
                "{:<10} {:<34} {:>14.3} {:>12.2} {:>9.2}%",
                format!("{size}x{size}"),
                name.chars().take(34).collect::<String>(),
                median(row.samples_per_s.clone()) / 1e6,
                median(row.rays_per_s.clone()) / 1e6,
                100.0 * median(row.rel_error.clone()),
            );
        }
        if !g_row.samples_per_s.is_empty() {
            let ratios: Vec<f64> = g_row
                .samples_per_s
                .iter()
                .zip(&c_row.samples_per_s)
                .map(|(g, c)| g / c)
                .collect();
            println!(
                "{:<10} Vulkan / CPU reference throughput: {:.2}x (median of per-run ratios)",
                "",
                median(ratios)
            );
        }
    }
}
