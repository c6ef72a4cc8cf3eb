//! `vkpt bench`: speed against error. Each scene is rendered on each back
//! end at increasing spp; every step reports wall time, kernel time,
//! samples/s, rays/s and the relMSE against a converged reference, and the
//! time each back end needs to reach a relMSE is interpolated from them.
//!
//! Back ends alternate step by step, so a load change on the shared machine
//! hits them alike. Each step is an independent render from scratch at that
//! spp (its wall time is what a user waits for that image); start-up (device,
//! kernel compile, BVH build, scene upload) is reported separately.

pub mod plot;
pub mod reference;

use crate::gpu::GpuRenderer;
use crate::gpu::pipeline_cache::CacheUse;
use crate::image::compare::rel_mse;
use crate::packed::PackedScene;
use crate::packed::settings::{RenderSettings, Sampler, TextureFilter};
use crate::render::{DeviceChoice, Progress, Schedule};
use crate::scene::Scene;
use anyhow::Context as _;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to benchmark.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    pub scenes: Vec<PathBuf>,
    /// Back ends in the order they render each step. `Auto` is skipped with
    /// a note when there is no Vulkan device; other Vulkan choices must exist.
    pub devices: Vec<DeviceChoice>,
    /// Schedules each Vulkan back end runs, each a series of its own (the
    /// per-path loop's labelled `<back end>+loop`).
    pub schedules: Vec<Schedule>,
    pub width: u32,
    /// Default: width / the camera's aspect ratio.
    pub height: Option<u32>,
    pub max_depth: Option<u32>,
    /// Every back end's random numbers (the reference's too, when rendered
    /// here): independent is what Mitsuba's benchmark sampler draws.
    pub sampler: Sampler,
    /// Texture filtering of the measured renders and the reference.
    pub texture_filter: TextureFilter,
    /// Samples per pixel of each step, increasing.
    pub spp_steps: Vec<u32>,
    /// A converged image to measure against instead of the cached one.
    pub reference: Option<PathBuf>,
    pub reference_spp: u32,
    /// Receives bench.csv and one plot per scene.
    pub out_dir: PathBuf,
    /// relMSE levels whose time to reach is reported.
    pub thresholds: Vec<f64>,
    /// Renders per step and back end; the fastest is kept. Same seed, so the
    /// image (and its relMSE) is the same each time, while the machine's
    /// other load only ever adds time.
    pub repeat: u32,
    /// Seed of the measured renders; never the reference's own
    /// (`reference::REFERENCE_SEED`), whose samples they must not share.
    pub seed: u32,
    /// Light selection of the measured renders and of a reference rendered
    /// here (`Scene::light_sampler`).
    pub light_sampler: crate::scene::LightSampler,
    /// Validation layer: `None` follows `VKPT_VALIDATION`.
    pub validation: Option<bool>,
    /// Also denoise each step (Open Image Denoise, guided by the albedo and
    /// normal AOVs), reported as a series of its own, `<back end>+denoise`:
    /// wall time render plus denoiser, relMSE of the denoised image.
    pub denoise: bool,
}

impl Default for BenchConfig {
    fn default() -> Self {
        BenchConfig {
            scenes: Vec::new(),
            devices: vec![DeviceChoice::Auto, DeviceChoice::Cpu],
            schedules: vec![Schedule::Wavefront],
            width: 256,
            height: None,
            max_depth: None,
            sampler: Sampler::Sobol,
            texture_filter: TextureFilter::default(),
            spp_steps: (0..10).map(|i| 1 << i).collect(),
            reference: None,
            reference_spp: 4096,
            out_dir: PathBuf::from("vkpt-bench"),
            thresholds: vec![1e-2, 1e-3],
            repeat: 1,
            seed: 0,
            light_sampler: crate::scene::LightSampler::Auto,
            validation: None,
            denoise: false,
        }
    }
}

/// One render of one scene on one back end.
#[derive(Clone, Debug)]
pub struct Step {
    pub backend: String,
    pub spp: u32,
    /// The render call, scene upload and film read-back included.
    pub wall_s: f64,
    /// Sum of the kernels' timestamp intervals (Vulkan only).
    pub kernel_s: Option<f64>,
    pub samples_per_s: f64,
    pub rays_per_s: f64,
    pub rel_mse: f64,
}

/// Start-up costs of one back end on one scene.
#[derive(Clone, Debug)]
pub struct StartupReport {
    pub backend: String,
    pub device_name: String,
    pub device_s: f64,
    pub pipelines_s: f64,
    pub pipeline_cache: Option<CacheUse>,
    pub upload_s: f64,
    /// Extra wall time of the first render over the same render repeated:
    /// kernels a driver compiles at first dispatch (lavapipe does).
    pub first_dispatch_s: f64,
}

/// Everything measured on one scene.
#[derive(Clone, Debug)]
pub struct SceneReport {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub bvh_build_s: f64,
    pub reference_path: PathBuf,
    /// The reference's own expected relMSE, from its variance layer (NaN
    /// when it has none): measured relMSE cannot go much below it.
    pub reference_rel_mse: f64,
    pub startup: Vec<StartupReport>,
    pub steps: Vec<Step>,
}

impl SceneReport {
    /// (seconds, relMSE) of one back end's steps, in spp order.
    pub fn curve(&self, backend: &str) -> Vec<(f64, f64)> {
        self.steps
            .iter()
            .filter(|s| s.backend == backend)
            .map(|s| (s.wall_s, s.rel_mse))
            .collect()
    }

    /// Back-end labels in the order they rendered.
    pub fn backends(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for s in &self.steps {
            if !names.contains(&s.backend) {
                names.push(s.backend.clone());
            }
        }
        names
    }
}

/// Seconds at which a curve of (seconds, relMSE) points, in render order,
/// first reaches `threshold`, interpolated linearly in log-log between the
/// two steps around the crossing (error falls as a power of time). `None`
/// when no step reaches it. When the first step already does, its time is
/// returned: an upper bound, since nothing was measured before it.
pub fn time_to_rel_mse(points: &[(f64, f64)], threshold: f64) -> Option<f64> {
    let (&(t0, r0), rest) = points.split_first()?;
    if r0 <= threshold {
        return Some(t0);
    }
    let mut prev = (t0, r0);
    for &(t, r) in rest {
        if r <= threshold {
            let (tp, rp) = prev;
            if r <= 0.0 || tp <= 0.0 || t <= 0.0 {
                return Some(t);
            }
            let f = (threshold.ln() - rp.ln()) / (r.ln() - rp.ln());
            return Some((tp.ln() + f * (t.ln() - tp.ln())).exp());
        }
        prev = (t, r);
    }
    None
}

enum Engine {
    Vulkan(Box<GpuRenderer>),
    Cpu,
}

struct Backend {
    /// Short name in tables, the CSV and the plot: lavapipe, gpu or cpu.
    label: String,
    device_name: String,
    engine: Engine,
}

fn open_backends(config: &BenchConfig, log: &mut dyn FnMut(&str)) -> anyhow::Result<Vec<Backend>> {
    let mut backends = Vec::new();
    for &choice in &config.devices {
        let Some(vulkan) = choice.vulkan() else {
            backends.push(Backend {
                label: "cpu".into(),
                device_name: format!(
                    "CPU back end ({} threads)",
                    std::thread::available_parallelism().map_or(1, |n| n.get())
                ),
                engine: Engine::Cpu,
            });
            continue;
        };
        for &schedule in &config.schedules {
            match GpuRenderer::with_validation(vulkan, config.validation) {
                Ok(mut gpu) => {
                    gpu.schedule = schedule;
                    let device_name = gpu.device_name();
                    // lavapipe reports itself as "llvmpipe (LLVM ...)".
                    let label = if device_name.contains("llvmpipe") {
                        "lavapipe"
                    } else {
                        "gpu"
                    };
                    let label = match schedule {
                        Schedule::Wavefront => label.to_string(),
                        Schedule::PathLoop => format!("{label}+loop"),
                    };
                    backends.push(Backend {
                        label,
                        device_name,
                        engine: Engine::Vulkan(Box::new(gpu)),
                    });
                }
                Err(e) if choice == DeviceChoice::Auto => {
                    log(&format!(
                        "note: no usable Vulkan device ({e:#}); benchmarking without one"
                    ));
                    break;
                }
                Err(e) => return Err(e),
            }
        }
    }
    anyhow::ensure!(!backends.is_empty(), "no back end to benchmark");
    Ok(backends)
}

struct Measured {
    image: crate::image::Image,
    wall_s: f64,
    kernel_s: Option<f64>,
    rays: u64,
}

fn render_on(
    backend: &mut Backend,
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    progress: crate::render::Progress,
) -> anyhow::Result<Measured> {
    let start = Instant::now();
    let result = match &mut backend.engine {
        Engine::Vulkan(gpu) => gpu.render(scene, packed, settings, progress)?,
        Engine::Cpu => crate::cpu::render::render(scene, packed, settings, progress)?,
    };
    let wall_s = start.elapsed().as_secs_f64();
    let kernel_s = (!result.kernel_times.is_empty()).then(|| {
        result
            .kernel_times
            .iter()
            .map(|(_, d)| d.as_secs_f64())
            .sum()
    });
    Ok(Measured {
        image: result.film.to_image(),
        wall_s,
        kernel_s,
        rays: result.extension_rays + result.shadow_rays,
    })
}

/// Runs the benchmark, writing `bench.csv` and one plot per scene into
/// `config.out_dir`, and reporting results through `log`. `reference_progress`
/// follows the one long render a run may start unasked: the converged
/// reference, when none is given or cached.
pub fn run(
    config: &BenchConfig,
    log: &mut dyn FnMut(&str),
    reference_progress: Progress,
) -> anyhow::Result<Vec<SceneReport>> {
    anyhow::ensure!(!config.scenes.is_empty(), "no scene to benchmark");
    anyhow::ensure!(
        !config.spp_steps.is_empty() && config.spp_steps.windows(2).all(|w| w[0] < w[1]),
        "the spp steps must be increasing, got {:?}",
        config.spp_steps
    );
    anyhow::ensure!(
        config.reference.is_none() || config.scenes.len() == 1,
        "a given reference image fits one scene; benchmark one scene at a time with it"
    );
    anyhow::ensure!(
        config.seed != reference::REFERENCE_SEED,
        "--seed {} is the reference's own seed: the measured renders would share its samples; pick another",
        config.seed
    );
    let mut backends = open_backends(config, log)?;
    std::fs::create_dir_all(&config.out_dir)
        .with_context(|| format!("cannot create {}", config.out_dir.display()))?;
    let mut reports = Vec::new();
    for scene_path in &config.scenes {
        let report = bench_scene(config, scene_path, &mut backends, log, reference_progress)?;
        let stem = scene_path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into());
        let plot_path = config.out_dir.join(format!("{stem}.svg"));
        plot::plot_report(&plot_path, &report, &config.thresholds)?;
        log(&summary(&report, &config.thresholds));
        log(&format!("wrote {}", plot_path.display()));
        reports.push(report);
    }
    let csv = config.out_dir.join("bench.csv");
    crate::cache::write_atomically(&csv, to_csv(&reports).as_bytes())
        .with_context(|| format!("cannot write {}", csv.display()))?;
    log(&format!("wrote {}", csv.display()));
    Ok(reports)
}

fn bench_scene(
    config: &BenchConfig,
    scene_path: &Path,
    backends: &mut [Backend],
    log: &mut dyn FnMut(&str),
    reference_progress: Progress,
) -> anyhow::Result<SceneReport> {
    let mut scene = Scene::load(scene_path)?;
    scene.light_sampler = config.light_sampler;
    for note in &scene.notes {
        log(&crate::scene::note_line(note));
    }
    let packed = PackedScene::new(&scene)?;
    let height = config.height.unwrap_or_else(|| {
        let aspect = scene
            .cameras
            .first()
            .and_then(|c| c.aspect_ratio)
            .unwrap_or(1.0);
        ((config.width as f32 / aspect).round() as u32).max(1)
    });
    let base = RenderSettings {
        width: config.width,
        height,
        max_depth: config.max_depth,
        sampler: config.sampler,
        texture_filter: config.texture_filter,
        seed: config.seed,
        ..Default::default()
    };
    base.validate()?;
    let name = scene_path.display().to_string();

    // Warm-up: the first render pays for kernels compiled at first dispatch.
    let warm = RenderSettings {
        spp: 1,
        ..base.clone()
    };
    let mut startup = Vec::new();
    let compiled = |b: &Backend| match &b.engine {
        Engine::Vulkan(g) => g.startup.pipelines.as_secs_f64(),
        Engine::Cpu => 0.0,
    };
    for b in backends.iter_mut() {
        let compiled_before = compiled(b);
        let first = render_on(b, &scene, &packed, &warm, &|_, _| {})?.wall_s;
        // Pipelines are made at the first render; the rest of its extra
        // time is what the driver compiles at first dispatch.
        let compile_s = compiled(b) - compiled_before;
        let again = render_on(b, &scene, &packed, &warm, &|_, _| {})?.wall_s;
        let (device_s, cache, upload_s) = match &b.engine {
            Engine::Vulkan(g) => (
                g.startup.device.as_secs_f64(),
                Some(g.startup.pipeline_cache),
                g.last_upload_time.as_secs_f64(),
            ),
            Engine::Cpu => (0.0, None, 0.0),
        };
        startup.push(StartupReport {
            backend: b.label.clone(),
            device_name: b.device_name.clone(),
            device_s,
            // This scene's: the back ends (and kernels compiled for earlier
            // scenes) are shared by every scene of the run.
            pipelines_s: compile_s,
            pipeline_cache: cache,
            upload_s,
            first_dispatch_s: (first - again - compile_s).max(0.0),
        });
    }

    // The reference: given, cached, or rendered now on the first back end.
    let (reference, reference_path) = match &config.reference {
        Some(path) => (
            reference::load(path, base.width, base.height)?,
            path.clone(),
        ),
        None => {
            let settings = RenderSettings {
                spp: config.reference_spp,
                seed: reference::REFERENCE_SEED,
                ..base.clone()
            };
            let path = reference::cache_path(scene_path, &settings)?;
            if path.exists() {
                log(&format!("reference: {} (cached)", path.display()));
                (reference::load(&path, base.width, base.height)?, path)
            } else {
                let backend = &mut backends[0];
                log(&format!(
                    "reference: rendering {name} at {} spp on {} (once; cached in {})",
                    settings.spp,
                    backend.device_name,
                    path.display()
                ));
                let m = render_on(backend, &scene, &packed, &settings, reference_progress)?;
                log(&format!("reference: done in {:.1} s", m.wall_s));
                reference::store(&path, &m.image)?;
                (m.image, path)
            }
        }
    };
    let reference_rel_mse = reference.estimated_rel_mse();
    if let Some(&lowest) = config
        .thresholds
        .iter()
        .min_by(|a, b| a.total_cmp(b))
        .filter(|&&t| reference_rel_mse > t / 10.0)
    {
        log(&format!(
            "note: the reference's own relMSE ({reference_rel_mse:.1e}) is above a tenth of \
             {lowest:.0e}: the time to reach {lowest:.0e} is overstated; raise BenchConfig::reference_spp"
        ));
    }

    log(&format!("sampler: {}", base.sampler.name()));
    let mut steps = Vec::new();
    let pixels = base.pixel_count() as f64;
    for &spp in &config.spp_steps {
        let settings = RenderSettings {
            spp,
            // The denoiser is guided by albedo and normal.
            aov: config.denoise,
            ..base.clone()
        };
        // Back ends take turns within each repetition, so load hits them alike.
        let mut best: Vec<Option<Measured>> = backends.iter().map(|_| None).collect();
        for _ in 0..config.repeat.max(1) {
            for (b, kept) in backends.iter_mut().zip(best.iter_mut()) {
                let m = render_on(b, &scene, &packed, &settings, &|_, _| {})?;
                if kept.as_ref().is_none_or(|k| m.wall_s < k.wall_s) {
                    *kept = Some(m);
                }
            }
        }
        for (b, m) in backends.iter().zip(best) {
            let m = m.expect("at least one repetition");
            let step = Step {
                backend: b.label.clone(),
                spp,
                wall_s: m.wall_s,
                kernel_s: m.kernel_s,
                samples_per_s: pixels * spp as f64 / m.wall_s.max(1e-9),
                rays_per_s: m.rays as f64 / m.wall_s.max(1e-9),
                rel_mse: rel_mse(&m.image, &reference),
            };
            let denoised = config
                .denoise
                .then(|| denoised_step(&step, &m, &reference, pixels))
                .transpose()?;
            for step in std::iter::once(step).chain(denoised) {
                log(&format!(
                    "{:<13} {:>6} spp {:>8.3} s  {:>7.3} Msamples/s  {:>7.2} Mrays/s  relMSE {:.3e}",
                    step.backend,
                    spp,
                    step.wall_s,
                    step.samples_per_s / 1e6,
                    step.rays_per_s / 1e6,
                    step.rel_mse
                ));
                steps.push(step);
            }
        }
    }
    Ok(SceneReport {
        scene: name,
        width: base.width,
        height: base.height,
        bvh_build_s: packed.bvh_build_time.as_secs_f64(),
        reference_path,
        reference_rel_mse,
        startup,
        steps,
    })
}

/// `raw` denoised (guided by its albedo and normal): a step of the series
/// `<back end>+denoise`, whose wall time adds the denoiser's.
fn denoised_step(
    raw: &Step,
    m: &Measured,
    reference: &crate::image::Image,
    pixels: f64,
) -> anyhow::Result<Step> {
    let image = &m.image;
    let start = Instant::now();
    let denoised = crate::image::denoise::denoise(
        image.width,
        image.height,
        &image.mean,
        image.aovs.albedo.as_deref(),
        image.aovs.normal.as_deref(),
    )?;
    let wall_s = raw.wall_s + start.elapsed().as_secs_f64();
    let denoised = crate::image::Image {
        mean: denoised,
        ..image.clone()
    };
    Ok(Step {
        backend: format!("{}+denoise", raw.backend),
        wall_s,
        samples_per_s: pixels * raw.spp as f64 / wall_s.max(1e-9),
        rays_per_s: m.rays as f64 / wall_s.max(1e-9),
        rel_mse: rel_mse(&denoised, reference),
        ..raw.clone()
    })
}

/// The CSV: one row per step, with a header naming the columns.
pub fn to_csv(reports: &[SceneReport]) -> String {
    let mut s = String::from(
        "scene,backend,width,height,spp,wall_s,kernel_s,samples_per_s,rays_per_s,rel_mse\n",
    );
    for r in reports {
        for st in &r.steps {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{:.6},{},{:.1},{:.1},{:.6e}",
                r.scene.replace(',', "_"),
                st.backend,
                r.width,
                r.height,
                st.spp,
                st.wall_s,
                st.kernel_s.map(|k| format!("{k:.6}")).unwrap_or_default(),
                st.samples_per_s,
                st.rays_per_s,
                st.rel_mse
            );
        }
    }
    s
}

fn format_seconds(t: Option<f64>) -> String {
    match t {
        None => "not reached".into(),
        Some(t) if t < 1.0 => format!("{:.1} ms", t * 1e3),
        Some(t) => format!("{t:.2} s"),
    }
}

/// Start-up costs and the time each back end needs to reach each threshold.
pub fn summary(r: &SceneReport, thresholds: &[f64]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} at {}x{}: reference {} (its own relMSE {})",
        r.scene,
        r.width,
        r.height,
        r.reference_path.display(),
        if r.reference_rel_mse.is_nan() {
            "unknown: no variance layer".to_string()
        } else {
            format!("{:.1e}", r.reference_rel_mse)
        }
    );
    let _ = writeln!(s, "  BVH build {:.1} ms", r.bvh_build_s * 1e3);
    for st in &r.startup {
        if let Some(cache) = st.pipeline_cache {
            let cache = match cache {
                CacheUse::Off => "no pipeline cache".to_string(),
                CacheUse::Miss => "pipeline cache empty".to_string(),
                CacheUse::Loaded(n) if n <= crate::gpu::pipeline_cache::HEADER_BYTES => {
                    "pipeline cache loaded: a bare header, the driver stores nothing in it".into()
                }
                CacheUse::Loaded(n) => format!("pipeline cache loaded, {n} bytes"),
            };
            let _ = writeln!(
                s,
                "  {} ({}): device {:.1} ms, kernel compile {:.1} ms ({cache}) + {:.1} ms at first \
                 dispatch, scene upload {:.1} ms",
                st.backend,
                st.device_name,
                st.device_s * 1e3,
                st.pipelines_s * 1e3,
                st.first_dispatch_s * 1e3,
                st.upload_s * 1e3
            );
        } else {
            let _ = writeln!(
                s,
                "  {} ({}): no start-up beyond the BVH",
                st.backend, st.device_name
            );
        }
    }
    for &t in thresholds {
        let times: Vec<String> = r
            .backends()
            .iter()
            .map(|b| format!("{b} {}", format_seconds(time_to_rel_mse(&r.curve(b), t))))
            .collect();
        let _ = writeln!(s, "  time to relMSE {t:.0e}: {}", times.join(", "));
    }
    s.trim_end().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bench_time_to_rel_mse_interpolates_log_log() {
        // relMSE = 0.1 / t: reaches 1e-2 at t = 10 exactly; steps at 1, 100.
        let curve = [(1.0, 0.1), (100.0, 0.001)];
        let t = time_to_rel_mse(&curve, 1e-2).unwrap();
        assert!((t - 10.0).abs() < 1e-9, "{t}");
        // The first crossing counts, even if noise goes back up after it.
        let noisy = [
            (1.0, 0.1),
            (2.0, 0.05),
            (4.0, 0.009),
            (8.0, 0.011),
            (16.0, 0.004),
        ];
        let t = time_to_rel_mse(&noisy, 1e-2).unwrap();
        assert!(t > 2.0 && t < 4.0, "{t}");
        // Never reached; an empty curve; met at the first step.
        assert_eq!(time_to_rel_mse(&curve, 1e-4), None);
        assert_eq!(time_to_rel_mse(&[], 1e-2), None);
        assert_eq!(time_to_rel_mse(&curve, 0.5), Some(1.0));
        // A step with zero error is reached at its own time.
        assert_eq!(time_to_rel_mse(&[(1.0, 0.1), (3.0, 0.0)], 1e-2), Some(3.0));
    }

    #[test]
    fn bench_csv_has_one_row_per_step() {
        let report = SceneReport {
            scene: "a,b.gltf".into(),
            width: 4,
            height: 2,
            bvh_build_s: 0.0,
            reference_path: PathBuf::new(),
            reference_rel_mse: 0.0,
            startup: vec![],
            steps: vec![Step {
                backend: "cpu".into(),
                spp: 8,
                wall_s: 0.5,
                kernel_s: None,
                samples_per_s: 128.0,
                rays_per_s: 256.0,
                rel_mse: 0.25,
            }],
        };
        let csv = to_csv(&[report]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 2);
        assert_eq!(
            lines[1],
            "a_b.gltf,cpu,4,2,8,0.500000,,128.0,256.0,2.500000e-1"
        );
    }
}
