//! `auto`: the back end that is fastest here. A real GPU is taken as found.
//! When the only Vulkan device is a CPU driver (lavapipe), it and the CPU
//! back end compete for the same cores, and which one wins depends on the
//! machine and on the kernels the scene needs, so it is measured: a small
//! render of the scene on each, alternating, and the faster one in samples/s
//! renders. The result is cached per (vkpt version, Vulkan device, CPU,
//! threads, kernel variant), so a machine pays for the measurement once per
//! kind of scene.

use super::{Backend, RenderSettings};
use crate::cache::{FNV_OFFSET, cache_dir, fnv1a, write_atomically};
use crate::film::passes::RenderAll;
use crate::gpu::GpuRenderer;
use crate::gpu::context::VulkanDevice;
use crate::packed::PackedScene;
use crate::packed::features::KernelFeatures;
use crate::scene::Scene;
use std::path::PathBuf;
use std::time::Instant;

/// Width of the measuring render (height from the settings' aspect): big
/// enough that neither back end is measured mostly on its fixed costs.
const PROBE_WIDTH: u32 = 128;
/// Samples per pixel of each measuring render.
const PROBE_SPP: u32 = 4;
/// Measuring renders per back end, alternating; the fastest counts.
const PROBE_ROUNDS: usize = 3;

/// The chosen back end and a sentence saying why.
pub struct Choice {
    pub backend: Backend,
    pub why: String,
}

/// What a measurement found: samples/s of each back end.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Measured {
    vulkan: f64,
    cpu: f64,
}

impl Measured {
    fn cpu_wins(&self) -> bool {
        self.cpu > self.vulkan
    }

    fn describe(&self, device: &str, when: &str) -> String {
        let device = if device.contains("llvmpipe") {
            "lavapipe"
        } else {
            device
        };
        let (winner, loser, ratio) = if self.cpu_wins() {
            ("the CPU back end", device, self.cpu / self.vulkan)
        } else {
            (device, "the CPU back end", self.vulkan / self.cpu)
        };
        format!(
            "auto: no GPU, and {winner} ran {ratio:.2}x the samples/s of {loser} on this \
             scene's kernels ({when})"
        )
    }
}

/// Opens the back end `auto` picks for this scene and these settings.
pub fn choose(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
) -> anyhow::Result<Choice> {
    let gpu = match GpuRenderer::new(VulkanDevice::Best) {
        Ok(gpu) => gpu,
        Err(e) => {
            return Ok(Choice {
                backend: Backend::Cpu,
                why: format!("auto: no usable Vulkan device ({e:#})"),
            });
        }
    };
    if !gpu.is_cpu_device() {
        return Ok(Choice {
            backend: Backend::Vulkan(Box::new(gpu)),
            why: "auto: a GPU".into(),
        });
    }
    let device = gpu.device_name();
    let mut gpu = Box::new(gpu);
    let key = cache_key(&device, packed, scene, settings)?;
    let path = cache_dir().map(|d| d.join(format!("auto-device-{key:016x}.txt")));
    let (measured, when) = match path.as_ref().and_then(read_cached) {
        Some(m) => (m, "cached"),
        None => {
            let m = measure(&mut gpu, scene, packed, settings)?;
            if let Some(p) = &path {
                // A cache that cannot be written only costs the next run a
                // measurement.
                let _ = write_atomically(p, format!("{} {}\n", m.vulkan, m.cpu).as_bytes());
            }
            (m, "measured now")
        }
    };
    let why = measured.describe(&device, when);
    let backend = if measured.cpu_wins() {
        Backend::Cpu
    } else {
        Backend::Vulkan(gpu)
    };
    Ok(Choice { backend, why })
}

/// The cache key: everything the relative speed depends on.
fn cache_key(
    device: &str,
    packed: &PackedScene,
    scene: &Scene,
    settings: &RenderSettings,
) -> anyhow::Result<u64> {
    let params = packed.render_params(scene, settings, 0)?;
    let variant = KernelFeatures::of(packed, &params).describe();
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .map(str::to_string)
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let text = format!(
        "{} | {device} | {cpu} | {} threads | {variant}",
        env!("CARGO_PKG_VERSION"),
        rayon::current_num_threads()
    );
    Ok(fnv1a(text.as_bytes(), FNV_OFFSET))
}

fn read_cached(path: &PathBuf) -> Option<Measured> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut numbers = text.split_whitespace().map(|w| w.parse::<f64>().ok());
    let (vulkan, cpu) = (numbers.next()??, numbers.next()??);
    (vulkan > 0.0 && cpu > 0.0).then_some(Measured { vulkan, cpu })
}

/// Samples/s of each back end on a small render of the scene, fastest of
/// `PROBE_ROUNDS` alternating renders (the first Vulkan render also compiles
/// the kernels, which a render on lavapipe would pay anyway).
fn measure(
    gpu: &mut GpuRenderer,
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
) -> anyhow::Result<Measured> {
    let aspect = settings.height as f64 / settings.width.max(1) as f64;
    // The whole (small) image from sample 0: a region or sample range of
    // the real render says nothing about speed.
    let probe = RenderSettings {
        width: PROBE_WIDTH,
        height: ((PROBE_WIDTH as f64 * aspect).round() as u32).max(1),
        spp: PROBE_SPP,
        first_sample: 0,
        region: None,
        ..settings.clone()
    };
    let samples = probe.pixel_count() as f64 * PROBE_SPP as f64;
    gpu.render(scene, packed, &probe, &|_, _| {})?;
    let mut best = Measured {
        vulkan: 0.0,
        cpu: 0.0,
    };
    for _ in 0..PROBE_ROUNDS {
        let start = Instant::now();
        gpu.render(scene, packed, &probe, &|_, _| {})?;
        best.vulkan = best.vulkan.max(samples / start.elapsed().as_secs_f64());
        let start = Instant::now();
        crate::cpu::render::render_progressive(scene, packed, &probe, &|_, _| {}, &mut RenderAll)?;
        best.cpu = best.cpu.max(samples / start.elapsed().as_secs_f64());
    }
    Ok(best)
}
