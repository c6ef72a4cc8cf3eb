//! `auto`: the back end that is fastest here. A real GPU is taken as found,
//! with the wavefront schedule. When the only Vulkan device is a CPU driver
//! (lavapipe), it and the CPU back end compete for the same cores, and which
//! one wins depends on the machine and on the kernels the scene needs. So
//! it is measured: small renders of the scene at two sample counts with
//! each, alternating, give each back end's samples/s and its fixed cost per
//! render, and the one predicted to finish this render first renders
//! (lavapipe with the wavefront schedule, or the one `--schedule` names):
//! lavapipe's higher rate wins long renders, its fixed costs lose short
//! ones. The result is cached
//! per (vkpt version and build, Vulkan device, CPU, threads, kernel variant),
//! so a machine pays for the measurement once per kind of scene and build.
//!
//! A scene's size changes the rates far more than the kernel variant does
//! (a 1.3 M-triangle mesh renders 6.5x fewer samples/s than the Cornell
//! box on the CPU), so the cached rates are scaled to the scene at hand:
//! a tiny CPU render of it (`SCENE_PROBE_*`, tens of milliseconds) is
//! compared with the same render of the scene the rates were measured on,
//! and every contender's rate is scaled by that ratio (both back ends
//! trace the same BVH on the same cores); the CPU's fixed cost per render
//! (building its copies of the scene) is this scene's, from the same tiny
//! renders.

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

/// Width of the measuring renders (height from the settings' aspect).
const PROBE_WIDTH: u32 = 128;
/// Samples per pixel of the short and the long measuring render: the
/// difference of their times is the rate, what is left the fixed cost.
const PROBE_SPP: [u32; 2] = [2, 8];
/// Measuring renders per back end, alternating; the fastest counts.
const PROBE_ROUNDS: usize = 3;
/// Width and samples per pixel of the tiny CPU renders that measure what
/// this scene costs against the one the cached rates come from.
const SCENE_PROBE_WIDTH: u32 = 64;
const SCENE_PROBE_SPP: [u32; 2] = [1, 4];

/// The chosen back end and a sentence saying why.
pub struct Choice {
    pub backend: Backend,
    pub why: String,
}

/// What a measurement found: samples/s of each contender (0: not run), and
/// the seconds each back end spends per render besides its samples.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Measured {
    wavefront: f64,
    path_loop: f64,
    cpu: f64,
    vulkan_fixed: f64,
    cpu_fixed: f64,
    /// The CPU back end's samples/s on the scene probe (`scene_probe`) of
    /// the scene these rates were measured on.
    cpu_probe: f64,
}

/// Who renders: the CPU back end, or the Vulkan device with a schedule.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Winner {
    Cpu,
    Vulkan(Schedule),
}

/// Samples/s and seconds per render from the fastest short and long
/// measuring renders of `samples` samples each: the line through the two
/// (time = fixed + samples / rate); a noisy pair whose long render was not
/// slower counts as all rate.
fn fit(samples: [f64; 2], seconds: [f64; 2]) -> (f64, f64) {
    let [n0, n1] = samples;
    let [t0, t1] = seconds;
    if t1 > t0 && n1 > n0 {
        let rate = (n1 - n0) / (t1 - t0);
        let fixed = (t0 - n0 / rate).max(0.0);
        (rate, fixed)
    } else {
        (n1 / t1, 0.0)
    }
}

impl Measured {
    /// These rates scaled to a scene whose scene probe ran at `probe_rate`
    /// samples/s with `probe_fixed` seconds per render; the factor applied.
    fn for_scene(self, probe_rate: f64, probe_fixed: f64) -> (Measured, f64) {
        let factor = if self.cpu_probe > 0.0 && probe_rate > 0.0 {
            probe_rate / self.cpu_probe
        } else {
            1.0
        };
        let scaled = Measured {
            wavefront: self.wavefront * factor,
            path_loop: self.path_loop * factor,
            cpu: self.cpu * factor,
            cpu_fixed: probe_fixed,
            ..self
        };
        (scaled, factor)
    }

    /// Samples/s of `w` and its seconds per render.
    fn rate(&self, w: Winner) -> (f64, f64) {
        match w {
            Winner::Cpu => (self.cpu, self.cpu_fixed),
            Winner::Vulkan(Schedule::Wavefront) => (self.wavefront, self.vulkan_fixed),
            Winner::Vulkan(Schedule::PathLoop) => (self.path_loop, self.vulkan_fixed),
        }
    }

    /// Seconds `winner` is predicted to take for `samples` samples.
    fn predicted(&self, winner: Winner, samples: f64) -> f64 {
        let (rate, fixed) = self.rate(winner);
        fixed + samples / rate
    }

    /// The contenders that ran, predicted fastest for `samples` first.
    fn ranked(&self, samples: f64) -> Vec<(Winner, f64)> {
        let mut timed: Vec<(Winner, f64)> = [
            Winner::Vulkan(Schedule::Wavefront),
            Winner::Vulkan(Schedule::PathLoop),
            Winner::Cpu,
        ]
        .into_iter()
        .filter(|&w| self.rate(w).0 > 0.0)
        .map(|w| (w, self.predicted(w, samples)))
        .collect();
        timed.sort_by(|a, b| a.1.total_cmp(&b.1));
        timed
    }

    fn winner(&self, samples: f64) -> Winner {
        self.ranked(samples)
            .first()
            .map_or(Winner::Cpu, |&(w, _)| w)
    }

    fn describe(&self, device: &str, samples: f64, when: &str) -> String {
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
        let ranked = self.ranked(samples);
        let Some(&(winner, best)) = ranked.first() else {
            return format!("auto: no GPU, and nothing measured ({when})");
        };
        let others: Vec<String> = ranked[1..]
            .iter()
            .map(|&(w, t)| format!("{:.2}x faster than {}", t / best, name(w)))
            .collect();
        let details: Vec<String> = ranked
            .iter()
            .map(|&(w, t)| {
                let (rate, fixed) = self.rate(w);
                format!(
                    "{}: {:.3} Msamples/s + {:.0} ms per render, {t:.2} s",
                    name(w),
                    rate / 1e6,
                    fixed * 1e3
                )
            })
            .collect();
        format!(
            "auto: no GPU, and {} is predicted {} on this render's {:.3} Msamples ({}) ({when})",
            name(winner),
            others.join(" and "),
            samples / 1e6,
            details.join("; ")
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
                let line = format!(
                    "{} {} {} {} {} {}\n",
                    m.wavefront, m.path_loop, m.cpu, m.vulkan_fixed, m.cpu_fixed, m.cpu_probe
                );
                let _ = write_atomically(p, line.as_bytes());
            }
            (m, "measured now")
        }
    };
    // Rates measured now are this scene's; cached ones are scaled to it.
    let (measured, factor) = if when == "cached" {
        let (probe_rate, probe_fixed) = scene_probe(scene, packed, settings)?;
        measured.for_scene(probe_rate, probe_fixed)
    } else {
        (measured, 1.0)
    };
    let samples = settings.pixel_count() as f64 * settings.spp as f64;
    let when = format!("{when}; rates x{factor:.3} for this scene's cost");
    let why = measured.describe(&device, samples, &when);
    let backend = match measured.winner(samples) {
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
        vulkan_fixed: numbers.next()??,
        cpu_fixed: numbers.next()??,
        cpu_probe: numbers.next()??,
    };
    (m.wavefront >= 0.0
        && m.cpu_probe >= 0.0
        && m.path_loop >= 0.0
        && m.cpu > 0.0
        && m.wavefront + m.path_loop > 0.0
        && m.vulkan_fixed >= 0.0
        && m.cpu_fixed >= 0.0)
        .then_some(m)
}

/// Samples/s and fixed seconds per render of each contender, fitted to the
/// fastest of `PROBE_ROUNDS` alternating renders at each of `PROBE_SPP` (a
/// first Vulkan render compiles the kernels, which a render on lavapipe
/// would pay anyway).
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
    let probe = |spp| RenderSettings {
        width: PROBE_WIDTH,
        height: ((PROBE_WIDTH as f64 * aspect).round() as u32).max(1),
        spp,
        first_sample: 0,
        region: None,
        ..settings.clone()
    };
    let probes = PROBE_SPP.map(probe);
    let samples = probes
        .clone()
        .map(|p| p.pixel_count() as f64 * p.spp as f64);
    // The per-path loop only when asked for: since lavapipe runs as one
    // device per core (`gpu::split`) the wavefront is faster on every scene
    // measured, and compiling `path_loop` on every device costs seconds.
    gpu.schedule = schedule.unwrap_or(Schedule::Wavefront);
    // A warm-up render compiles the kernels.
    gpu.render(scene, packed, &probes[0], &|_, _| {})?;
    let (mut vulkan, mut cpu) = ([f64::MAX; 2], [f64::MAX; 2]);
    for _ in 0..PROBE_ROUNDS {
        for (k, p) in probes.iter().enumerate() {
            let start = Instant::now();
            gpu.render(scene, packed, p, &|_, _| {})?;
            vulkan[k] = vulkan[k].min(start.elapsed().as_secs_f64());
            let start = Instant::now();
            crate::cpu::render::render_progressive(scene, packed, p, &|_, _| {}, &mut RenderAll)?;
            cpu[k] = cpu[k].min(start.elapsed().as_secs_f64());
        }
    }
    let (vulkan_rate, vulkan_fixed) = fit(samples, vulkan);
    let (cpu_rate, cpu_fixed) = fit(samples, cpu);
    let looped = gpu.schedule == Schedule::PathLoop;
    Ok(Measured {
        wavefront: if looped { 0.0 } else { vulkan_rate },
        path_loop: if looped { vulkan_rate } else { 0.0 },
        cpu: cpu_rate,
        vulkan_fixed,
        cpu_fixed,
        cpu_probe: scene_probe(scene, packed, settings)?.0,
    })
}

/// The CPU back end's samples/s on this scene and its fixed seconds per
/// render (building its copies of the scene): a first tiny render builds
/// them, then renders at `SCENE_PROBE_SPP` on the same copies (the
/// fastest of two each) give the rate without them, so that a big scene's
/// seconds of copying are not read as a slow rate.
fn scene_probe(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
) -> anyhow::Result<(f64, f64)> {
    use crate::cpu::render::{CpuSchedule, render_on};
    let aspect = settings.height as f64 / settings.width.max(1) as f64;
    let probes = SCENE_PROBE_SPP.map(|spp| RenderSettings {
        width: SCENE_PROBE_WIDTH,
        height: ((SCENE_PROBE_WIDTH as f64 * aspect).round() as u32).max(1),
        spp,
        first_sample: 0,
        region: None,
        ..settings.clone()
    });
    let samples = probes
        .clone()
        .map(|p| p.pixel_count() as f64 * p.spp as f64);
    let cpu_scene = crate::cpu::fast::cache::CpuScene::new(packed);
    let render = |p: &RenderSettings| -> anyhow::Result<f64> {
        let start = Instant::now();
        render_on(
            scene,
            &cpu_scene,
            p,
            &|_, _| {},
            &mut RenderAll,
            CpuSchedule::Lanes,
        )?;
        Ok(start.elapsed().as_secs_f64())
    };
    let first = render(&probes[0])?;
    let mut seconds = [f64::MAX; 2];
    for _ in 0..2 {
        for (k, p) in probes.iter().enumerate() {
            seconds[k] = seconds[k].min(render(p)?);
        }
    }
    let (rate, fixed) = fit(samples, seconds);
    Ok((rate, fixed + (first - seconds[0]).max(0.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_splits_time_into_rate_and_fixed_cost() {
        // 0.5 s per render plus 1 M samples/s.
        let (rate, fixed) = fit([1e5, 4e5], [0.6, 0.9]);
        assert!((rate - 1e6).abs() < 1.0 && (fixed - 0.5).abs() < 1e-9);
        // A long render no slower than the short one: all rate.
        assert_eq!(fit([1e5, 4e5], [0.5, 0.5]), (8e5, 0.0));
    }

    #[test]
    fn fixed_costs_lose_short_renders_and_rates_win_long_ones() {
        let m = Measured {
            wavefront: 2e6,
            path_loop: 0.0,
            cpu: 1e6,
            vulkan_fixed: 1.0,
            cpu_fixed: 0.0,
            cpu_probe: 1e6,
        };
        assert_eq!(m.winner(1e5), Winner::Cpu);
        assert_eq!(m.winner(1e7), Winner::Vulkan(Schedule::Wavefront));
        // Break-even at 2e6 samples: 1 s + 1 s against 2 s.
        assert!((m.predicted(Winner::Cpu, 2e6) - 2.0).abs() < 1e-12);
        assert!((m.predicted(Winner::Vulkan(Schedule::Wavefront), 2e6) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_scene_four_times_as_costly_renders_four_times_slower() {
        let m = Measured {
            wavefront: 2e6,
            path_loop: 0.0,
            cpu: 1e6,
            vulkan_fixed: 1.0,
            cpu_fixed: 0.1,
            cpu_probe: 8e5,
        };
        let (scaled, factor) = m.for_scene(2e5, 0.3);
        assert_eq!(factor, 0.25);
        assert_eq!((scaled.cpu, scaled.wavefront), (2.5e5, 5e5));
        // Its own fixed cost (the CPU's copies of a bigger scene).
        assert_eq!((scaled.cpu_fixed, scaled.vulkan_fixed), (0.3, 1.0));
        // A smaller scene does not keep a bigger one's.
        assert_eq!(m.for_scene(8e5, 0.01).0.cpu_fixed, 0.01);
        assert!((scaled.predicted(Winner::Cpu, 1e6) - 4.3).abs() < 1e-12);
        // The scene the rates were measured on keeps them.
        assert_eq!(m.for_scene(8e5, 0.1).0, m);
    }
}
