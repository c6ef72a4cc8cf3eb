//! `auto`: the back end that is fastest here. A real GPU is taken as found,
//! with the wavefront schedule. When the only Vulkan device is a CPU driver
//! (lavapipe), it and the CPU back end compete for the same cores, and which
//! one wins depends on the machine and on the kernels the scene needs. So
//! it is measured: a small render of the scene with each, alternating, and
//! the fastest in samples/s renders (lavapipe with the wavefront schedule,
//! or the one `--schedule` names). The result is cached
//! per (vkpt version and build, Vulkan device, CPU, threads, kernel variant),
//! so a machine pays for the measurement once per kind of scene and build.

use super::{Backend, RenderSettings, Schedule};
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

/// What a measurement found: samples/s of each contender (0: not run).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Measured {
    wavefront: f64,
    path_loop: f64,
    cpu: f64,
}

/// Who renders: the CPU back end, or the Vulkan device with a schedule.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Winner {
    Cpu,
    Vulkan(Schedule),
}

impl Measured {
    /// The contenders that ran, fastest first.
    fn ranked(&self) -> Vec<(Winner, f64)> {
        let mut all = vec![
            (Winner::Vulkan(Schedule::Wavefront), self.wavefront),
            (Winner::Vulkan(Schedule::PathLoop), self.path_loop),
            (Winner::Cpu, self.cpu),
        ];
        all.retain(|&(_, rate)| rate > 0.0);
        all.sort_by(|a, b| b.1.total_cmp(&a.1));
        all
    }

    fn winner(&self) -> Winner {
        self.ranked().first().map_or(Winner::Cpu, |&(w, _)| w)
    }

    fn describe(&self, device: &str, when: &str) -> String {
        let device = if device.contains("llvmpipe") {
            "lavapipe"
        } else {
            device
        };
        let name = |w: Winner| match w {
            Winner::Cpu => "the CPU back end".to_string(),
            Winner::Vulkan(Schedule::Wavefront) => format!("{device} (wavefront)"),
            Winner::Vulkan(Schedule::PathLoop) => format!("{device} (per-path loop)"),
        };
        let ranked = self.ranked();
        let Some(&(winner, best)) = ranked.first() else {
            return format!("auto: no GPU, and nothing measured ({when})");
        };
        let others: Vec<String> = ranked[1..]
            .iter()
            .map(|&(w, rate)| format!("{:.2}x that of {}", best / rate, name(w)))
            .collect();
        format!(
            "auto: no GPU, and {} ran {} in samples/s on this scene's kernels ({when})",
            name(winner),
            others.join(" and ")
        )
    }
}

/// Opens the back end `auto` picks for this scene and these settings.
pub fn choose(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    schedule: Option<Schedule>,
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
        let mut gpu = Box::new(gpu);
        gpu.schedule = schedule.unwrap_or(Schedule::Wavefront);
        return Ok(Choice {
            why: format!("auto: a GPU, {} schedule", gpu.schedule.name()),
            backend: Backend::Vulkan(gpu),
        });
    }
    let device = gpu.device_name();
    let mut gpu = Box::new(gpu);
    let key = cache_key(&device, packed, scene, settings, schedule)?;
    let path = cache_dir().map(|d| d.join(format!("auto-device-{key:016x}.txt")));
    let (measured, when) = match path.as_ref().and_then(read_cached) {
        Some(m) => (m, "cached"),
        None => {
            // The measuring render is the Vulkan device's first, where its
            // kernels are compiled: a driver that fails there leaves the
            // CPU back end, as a device that fails to open does.
            let m = match measure(&mut gpu, scene, packed, settings, schedule) {
                Ok(m) => m,
                Err(e) => {
                    return Ok(Choice {
                        backend: Backend::Cpu,
                        why: format!(
                            "auto: a measuring render failed ({e:#}); the CPU back end renders"
                        ),
                    });
                }
            };
            if let Some(p) = &path {
                // A cache that cannot be written only costs the next run a
                // measurement.
                let line = format!("{} {} {}\n", m.wavefront, m.path_loop, m.cpu);
                let _ = write_atomically(p, line.as_bytes());
            }
            (m, "measured now")
        }
    };
    let why = measured.describe(&device, when);
    let backend = match measured.winner() {
        Winner::Cpu => Backend::Cpu,
        Winner::Vulkan(schedule) => {
            gpu.schedule = schedule;
            Backend::Vulkan(gpu)
        }
    };
    Ok(Choice { backend, why })
}

/// The cache key: everything the relative speed depends on.
fn cache_key(
    device: &str,
    packed: &PackedScene,
    scene: &Scene,
    settings: &RenderSettings,
    schedule: Option<Schedule>,
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
    let schedules = schedule.map_or("both schedules", Schedule::name);
    let text = format!(
        "{} | {} | {device} | {cpu} | {} threads | {variant} | {schedules}",
        env!("CARGO_PKG_VERSION"),
        build_identity(),
        rayon::current_num_threads()
    );
    Ok(fnv1a(text.as_bytes(), FNV_OFFSET))
}

/// The running executable's size and modification time: a vkpt rebuilt
/// from newer sources (the version number need not change) may be faster
/// on one back end, so it measures again.
fn build_identity() -> String {
    std::env::current_exe()
        .and_then(std::fs::metadata)
        .map(|m| format!("{} bytes, modified {:?}", m.len(), m.modified().ok()))
        .unwrap_or_default()
}

fn read_cached(path: &PathBuf) -> Option<Measured> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut numbers = text.split_whitespace().map(|w| w.parse::<f64>().ok());
    let m = Measured {
        wavefront: numbers.next()??,
        path_loop: numbers.next()??,
        cpu: numbers.next()??,
    };
    (m.wavefront >= 0.0 && m.path_loop >= 0.0 && m.cpu > 0.0 && m.wavefront + m.path_loop > 0.0)
        .then_some(m)
}

/// Samples/s of each contender on a small render of the scene, fastest of
/// `PROBE_ROUNDS` alternating renders (a first Vulkan render compiles the
/// kernels, which a render on lavapipe would pay anyway).
fn measure(
    gpu: &mut GpuRenderer,
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    schedule: Option<Schedule>,
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
    // The per-path loop only when asked for: since lavapipe runs as one
    // device per core (`gpu::split`) the wavefront is faster on every scene
    // measured, and compiling `path_loop` on every device costs seconds.
    gpu.schedule = schedule.unwrap_or(Schedule::Wavefront);
    // A warm-up render compiles the kernels.
    gpu.render(scene, packed, &probe, &|_, _| {})?;
    let (mut vulkan, mut cpu) = (0.0f64, 0.0f64);
    for _ in 0..PROBE_ROUNDS {
        let start = Instant::now();
        gpu.render(scene, packed, &probe, &|_, _| {})?;
        vulkan = vulkan.max(samples / start.elapsed().as_secs_f64());
        let start = Instant::now();
        crate::cpu::render::render_progressive(scene, packed, &probe, &|_, _| {}, &mut RenderAll)?;
        cpu = cpu.max(samples / start.elapsed().as_secs_f64());
    }
    let looped = gpu.schedule == Schedule::PathLoop;
    Ok(Measured {
        wavefront: if looped { 0.0 } else { vulkan },
        path_loop: if looped { vulkan } else { 0.0 },
        cpu,
    })
}
