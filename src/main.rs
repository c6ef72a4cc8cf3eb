//! The `vkpt` command: argument parsing, progress and the summary line.
//! Try: `vkpt scenes/cornell-box.gltf --spp 64 -o cornell.png`

use anyhow::{Context as _, anyhow, bail};
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use vkpt::output::{PngSettings, ToneMap, write_image};
use vkpt::packed::PackedScene;
use vkpt::progressive::{Progressive, StopReason, StopRules};
use vkpt::render::{DeviceChoice, render_progressive};
use vkpt::scene::Scene;
use vkpt::settings::{RenderSettings, Sampler};

const HELP: &str = "\
vkpt: a physically based path tracer on Vulkan compute, checked against a CPU reference

USAGE:
    vkpt SCENE.gltf|SCENE.glb [OPTIONS]
    vkpt compare A.exr B.exr [--alpha A]

OPTIONS:
    -o, --output FILE     Image to write: .exr (linear RGB plus a variance layer: the
                          variance of each pixel's mean) or .png (exposed, tone-mapped,
                          sRGB). Default: the scene's name with .png
        --spp N           Samples per pixel [default: 64]
        --width N         Image width in pixels [default: 512]
        --height N        Image height [default: width / the camera's aspect ratio]
        --max-depth N     Longest path kept, counted in segments from the camera:
                          1 = emitters seen directly, 2 = direct lighting, 3 = one
                          indirect bounce, ...; -1 = no limit (Russian roulette ends
                          paths without bias) [default: -1]
        --seed N          Random seed; renders with different seeds are independent
                          [default: 0]
        --sampler S       Random numbers: sobol (Owen-scrambled Sobol, padded per
                          dimension: lower error at equal spp) or independent
                          [default: sobol]
        --camera NAME|N   Camera by name or index (in glTF node order) [default: 0]
        --device D        auto | gpu | lavapipe | cpu. auto picks the best Vulkan device
                          (discrete > integrated > virtual > CPU driver), or the CPU
                          reference when there is none; cpu is the CPU reference
                          path tracer [default: auto]
        --exposure EV     PNG exposure in stops [default: 0]
        --tonemap T       PNG tone map: neutral (Khronos PBR Neutral), aces, clamp
                          [default: neutral]
        --time-limit S    Stop at the last pass that ends within S seconds
        --target-error E  Stop once the estimated relative error (from the per-pixel
                          variance; with sobol usually an overestimate) is at most E,
                          e.g. 0.02. With either stopping rule and no --spp, spp is
                          unbounded (16777216)
        --checkpoint S    Write the image so far every S seconds during the render
                          (0: never) [default: 60]
        --timings         Print the time spent in each kernel (Vulkan devices)
    -q, --quiet           No progress bar
    -h, --help            This help
    -V, --version         Version

COMPARE:
    Tests whether two renders written by vkpt as EXR (with their variance
    layers) have the same expectation: z-tests per pixel, on 4x4 and 16x16
    blocks and on the whole image, with Sidak (within a level) and Bonferroni
    (across levels) corrections at the given family-wise alpha [default: 0.01].
    Prints the report and the relMSE of A against B; exits 0 when they agree,
    1 when they do not, 2 on bad input. Render them with different --seed and
    --sampler independent: the per-pixel variance assumes independent samples
    (with sobol it usually overestimates it, and the test loses power).

INTERRUPTING:
    Ctrl-C (SIGINT) finishes the current pass, writes the image with the
    samples every pixel has so far, and exits with status 130. A second Ctrl-C
    exits at once (the output file is renamed into place only when complete).

ENVIRONMENT:
    VKPT_VALIDATION=1     Enable the Khronos validation layer (vulkan-validationlayers)

EXAMPLE:
    vkpt scenes/cornell-box.gltf --spp 256 -o cornell.exr --device cpu
";

struct Args {
    scene: PathBuf,
    output: Option<PathBuf>,
    settings: RenderSettings,
    camera: Option<String>,
    height_given: bool,
    device: DeviceChoice,
    png: PngSettings,
    timings: bool,
    quiet: bool,
    spp_given: bool,
    stop: StopRules,
}

fn parse_number<T: std::str::FromStr>(flag: &str, value: &str) -> anyhow::Result<T> {
    value
        .parse()
        .map_err(|_| anyhow!("{flag} expects a number, got '{value}'"))
}

/// A duration in seconds: finite, not negative, and within a century.
fn parse_seconds(flag: &str, value: &str) -> anyhow::Result<f64> {
    let s: f64 = parse_number(flag, value)?;
    anyhow::ensure!(
        s.is_finite() && (0.0..=3.2e9).contains(&s),
        "{flag} expects seconds (0 or more), got {value}"
    );
    Ok(s)
}

/// The most samples per pixel the film counts exactly (`RenderSettings::validate`).
const MAX_SPP: u32 = 1 << 24;

/// Raised by the SIGINT handler; the render stops at the next pass.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_sigint(_: libc::c_int) {
    // A second Ctrl-C exits at once. Only async-signal-safe calls here: an
    // atomic swap and _exit.
    if INTERRUPTED.swap(true, Ordering::SeqCst) {
        // SAFETY: _exit is async-signal-safe.
        unsafe { libc::_exit(130) };
    }
}

/// Ctrl-C finishes the current pass and writes the image (see `HELP`).
fn install_sigint_handler() {
    let handler: extern "C" fn(libc::c_int) = on_sigint;
    // SAFETY: the handler only touches an atomic and calls _exit.
    unsafe { libc::signal(libc::SIGINT, handler as libc::sighandler_t) };
}

fn parse_args(args: &[String]) -> anyhow::Result<Option<Args>> {
    let mut scene = None;
    let mut a = Args {
        scene: PathBuf::new(),
        output: None,
        settings: RenderSettings::default(),
        camera: None,
        height_given: false,
        device: DeviceChoice::Auto,
        png: PngSettings::default(),
        timings: false,
        quiet: false,
        spp_given: false,
        stop: StopRules {
            checkpoint_every: Some(Duration::from_secs(60)),
            ..Default::default()
        },
    };
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let (flag, inline) = match arg.split_once('=') {
            Some((f, v)) if f.starts_with("--") => (f, Some(v.to_string())),
            _ => (arg.as_str(), None),
        };
        let mut value = || -> anyhow::Result<String> {
            inline
                .clone()
                .or_else(|| it.next().cloned())
                .ok_or_else(|| anyhow!("{flag} needs a value (see --help)"))
        };
        match flag {
            "-h" | "--help" => {
                print!("{HELP}");
                return Ok(None);
            }
            "-V" | "--version" => {
                println!("vkpt {}", env!("CARGO_PKG_VERSION"));
                return Ok(None);
            }
            "-o" | "--output" => a.output = Some(PathBuf::from(value()?)),
            "--spp" => {
                a.settings.spp = parse_number(flag, &value()?)?;
                a.spp_given = true;
            }
            "--time-limit" => {
                let s = parse_seconds(flag, &value()?)?;
                anyhow::ensure!(s > 0.0, "--time-limit must be above 0 seconds, got {s}");
                a.stop.time_limit = Some(Duration::from_secs_f64(s));
            }
            "--target-error" => {
                let e: f64 = parse_number(flag, &value()?)?;
                anyhow::ensure!(
                    e.is_finite() && e > 0.0,
                    "--target-error must be a relative error above 0 (e.g. 0.02), got {e}"
                );
                a.stop.target_error = Some(e);
            }
            "--checkpoint" => {
                let s = parse_seconds(flag, &value()?)?;
                a.stop.checkpoint_every = (s > 0.0).then(|| Duration::from_secs_f64(s));
            }
            "--width" => a.settings.width = parse_number(flag, &value()?)?,
            "--height" => {
                a.settings.height = parse_number(flag, &value()?)?;
                a.height_given = true;
            }
            "--max-depth" => {
                let d: i64 = parse_number(flag, &value()?)?;
                a.settings.max_depth = match d {
                    -1 => None,
                    d if d >= 1 && d < u32::MAX as i64 => Some(d as u32),
                    _ => bail!("--max-depth must be -1 (no limit) or at least 1, got {d}"),
                };
            }
            "--seed" => a.settings.seed = parse_number(flag, &value()?)?,
            "--camera" => a.camera = Some(value()?),
            "--sampler" => {
                let v = value()?;
                a.settings.sampler = Sampler::from_name(&v).ok_or_else(|| {
                    anyhow!(
                        "--sampler must be one of {}, got '{v}'",
                        Sampler::NAMES.join(", ")
                    )
                })?;
            }
            "--device" => {
                let v = value()?;
                a.device = DeviceChoice::from_name(&v).ok_or_else(|| {
                    anyhow!("--device must be auto, gpu, lavapipe or cpu, got '{v}'")
                })?;
            }
            "--exposure" => a.png.exposure_ev = parse_number(flag, &value()?)?,
            "--tonemap" => {
                let v = value()?;
                a.png.tonemap = ToneMap::from_name(&v).ok_or_else(|| {
                    anyhow!(
                        "--tonemap must be one of {}, got '{v}'",
                        ToneMap::NAMES.join(", ")
                    )
                })?;
            }
            "--timings" => a.timings = true,
            "-q" | "--quiet" => a.quiet = true,
            f if f.starts_with('-') && f.len() > 1 => bail!("unknown option '{f}' (see --help)"),
            _ if scene.is_none() => scene = Some(PathBuf::from(arg)),
            _ => bail!("unexpected argument '{arg}': vkpt renders one scene at a time"),
        }
    }
    a.scene = scene.ok_or_else(|| anyhow!("no scene given\n\n{HELP}"))?;
    if !a.spp_given && (a.stop.time_limit.is_some() || a.stop.target_error.is_some()) {
        a.settings.spp = MAX_SPP;
    }
    Ok(Some(a))
}

fn pick_camera(scene: &Scene, wanted: Option<&str>) -> anyhow::Result<usize> {
    let names = || {
        scene
            .cameras
            .iter()
            .enumerate()
            .map(|(i, c)| format!("{i}: '{}'", c.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let Some(wanted) = wanted else { return Ok(0) };
    if let Some(i) = scene.cameras.iter().position(|c| c.name == wanted) {
        return Ok(i);
    }
    match wanted.parse::<usize>() {
        Ok(i) if i < scene.cameras.len() => Ok(i),
        _ => bail!(
            "{}: no camera '{wanted}'; cameras are {}",
            scene.source.display(),
            names()
        ),
    }
}

/// A one-line progress bar on a terminal; a few plain lines elsewhere.
struct ProgressBar {
    start: Instant,
    tty: bool,
    last: Mutex<(Instant, u64)>,
    enabled: bool,
}

impl ProgressBar {
    fn update(&self, done: u64, total: u64) {
        if !self.enabled || total == 0 {
            return;
        }
        let mut last = self.last.lock().expect("progress lock");
        let now = Instant::now();
        let quarter = |n: u64| n * 4 / total;
        let due = if self.tty {
            now.duration_since(last.0).as_millis() >= 100 || done == total
        } else {
            quarter(done) > quarter(last.1)
        };
        if !due {
            return;
        }
        *last = (now, done);
        let fraction = done as f64 / total as f64;
        let elapsed = self.start.elapsed().as_secs_f64();
        let eta = if fraction > 0.0 {
            elapsed / fraction - elapsed
        } else {
            0.0
        };
        let width = 30;
        let filled = (fraction * width as f64) as usize;
        let bar: String = "#".repeat(filled) + &" ".repeat(width - filled);
        let line = format!(
            "[{bar}] {:5.1}%  {elapsed:6.1} s elapsed, {eta:6.1} s left",
            fraction * 100.0
        );
        let mut err = std::io::stderr().lock();
        if self.tty {
            let _ = write!(err, "\r{line}");
            if done == total {
                let _ = writeln!(err);
            }
        } else {
            let _ = writeln!(err, "{line}");
        }
    }
}

fn si(x: f64) -> String {
    match x {
        x if x >= 1e9 => format!("{:.2} G", x / 1e9),
        x if x >= 1e6 => format!("{:.2} M", x / 1e6),
        x if x >= 1e3 => format!("{:.2} k", x / 1e3),
        x => format!("{x:.0} "),
    }
}

/// Renders and writes the image; the exit status (0, or 130 when interrupted).
fn run(args: Args) -> anyhow::Result<i32> {
    let load_start = Instant::now();
    let scene = Scene::load(&args.scene)?;
    let load_time = load_start.elapsed();
    for note in &scene.notes {
        eprintln!("note: {note}");
    }
    let mut settings = args.settings.clone();
    settings.camera = pick_camera(&scene, args.camera.as_deref())?;
    if !args.height_given {
        let aspect = scene.cameras[settings.camera].aspect_ratio.unwrap_or(1.0);
        settings.height = ((settings.width as f32 / aspect).round() as u32).max(1);
    }
    settings.validate()?;
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = args.scene.file_stem().unwrap_or_default().to_string_lossy();
        PathBuf::from(format!("{stem}.png"))
    });
    // Fail on a bad output name before spending minutes rendering.
    let ext = output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    if !vkpt::output::SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
        bail!(
            "{}: vkpt writes {} images",
            output.display(),
            vkpt::output::SUPPORTED_EXTENSIONS.join(" or ")
        );
    }

    let packed = PackedScene::new(&scene)?;
    let tty = std::io::stderr().is_terminal();
    let bar = ProgressBar {
        start: Instant::now(),
        tty,
        last: Mutex::new((Instant::now(), 0)),
        enabled: !args.quiet,
    };
    let progress = |d, t| bar.update(d, t);
    let quiet = args.quiet;
    let mut checkpoint = |film: &vkpt::film::Film, spp: u32| -> anyhow::Result<()> {
        write_image(&output, &film.to_image(), &args.png)
            .with_context(|| format!("writing a checkpoint to {}", output.display()))?;
        if !quiet {
            eprintln!("\ncheckpoint: wrote {} at {spp} spp", output.display());
        }
        Ok(())
    };
    install_sigint_handler();
    let mut control = Progressive::new(args.stop.clone(), &INTERRUPTED, &mut checkpoint);
    let result = match args.device {
        // auto: the best Vulkan device, else the CPU reference (and say so).
        DeviceChoice::Auto => match vkpt::gpu::GpuRenderer::new(DeviceChoice::Auto) {
            Ok(mut gpu) => {
                gpu.render_progressive(&scene, &packed, &settings, &progress, &mut control)?
            }
            Err(e) => {
                eprintln!(
                    "note: no usable Vulkan device ({e:#}); rendering with the CPU reference"
                );
                render_progressive(
                    &scene,
                    &packed,
                    &settings,
                    DeviceChoice::Cpu,
                    &progress,
                    &mut control,
                )?
            }
        },
        device => render_progressive(&scene, &packed, &settings, device, &progress, &mut control)?,
    };
    let reason = control.reason();
    if bar.tty && bar.enabled && reason != StopReason::Finished {
        eprintln!();
    }
    let image = result.film.to_image();
    write_image(&output, &image, &args.png)
        .with_context(|| format!("writing {}", output.display()))?;

    let secs = result.render_time.as_secs_f64().max(1e-9);
    let samples = settings.pixel_count() as f64 * result.spp as f64;
    let rays = (result.extension_rays + result.shadow_rays) as f64;
    println!(
        "device: {} | scene: {} triangles, {} emitters{} | load {:.0} ms, BVH {:.1} ms",
        result.device_name,
        packed.tri_verts.len(),
        packed.emitters.len(),
        if packed.has_environment() {
            ", environment"
        } else {
            ""
        },
        load_time.as_secs_f64() * 1e3,
        packed.bvh_build_time.as_secs_f64() * 1e3,
    );
    println!(
        "rendered {}x{} at {} spp in {:.2} s: {}samples/s, {}rays/s ({}extension + {}shadow rays), \
         est. relative error {:.2}% (relMSE {:.2e})",
        settings.width,
        settings.height,
        result.spp,
        secs,
        si(samples / secs),
        si(rays / secs),
        si(result.extension_rays as f64),
        si(result.shadow_rays as f64),
        image.estimated_rel_error() * 100.0,
        image.estimated_rel_mse(),
    );
    if args.timings && !result.kernel_times.is_empty() {
        let total: f64 = result
            .kernel_times
            .iter()
            .map(|(_, d)| d.as_secs_f64())
            .sum();
        println!("kernel times (timestamps):");
        for (name, d) in &result.kernel_times {
            println!(
                "  {name:<18} {:9.1} ms {:5.1}%",
                d.as_secs_f64() * 1e3,
                100.0 * d.as_secs_f64() / total.max(1e-12)
            );
        }
    }
    if result.traversal_overflows > 0 {
        eprintln!(
            "warning: {} rays exceeded the BVH traversal bound and were dropped; the image is \
             darker than it should be where they were",
            result.traversal_overflows
        );
    }
    if result.nonfinite_samples > 0 {
        eprintln!(
            "warning: {} non-finite samples (NaN or infinity) were dropped",
            result.nonfinite_samples
        );
    }
    let asked = if args.spp_given || settings.spp != MAX_SPP {
        format!(" of the {} asked for", settings.spp)
    } else {
        String::new()
    };
    match reason {
        StopReason::Finished => {}
        StopReason::TimeLimit => println!(
            "stopped at the time limit of {:.1} s after {} spp{asked}",
            args.stop.time_limit.unwrap_or_default().as_secs_f64(),
            result.spp
        ),
        StopReason::TargetError(e) => println!(
            "stopped at {} spp{asked}: estimated relative error {:.2}% reached the target {:.2}%",
            result.spp,
            e * 100.0,
            args.stop.target_error.unwrap_or_default() * 100.0
        ),
        StopReason::Interrupted => println!(
            "interrupted (Ctrl-C) after {} spp{asked}; the image has every sample so far",
            result.spp
        ),
    }
    println!("wrote {}", output.display());
    Ok(if reason == StopReason::Interrupted {
        130
    } else {
        0
    })
}

/// `vkpt compare A.exr B.exr [--alpha A]`: Ok(true) when the renders agree.
fn compare_command(args: &[String]) -> anyhow::Result<bool> {
    let mut files = Vec::new();
    let mut alpha = 0.01;
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "--alpha" => {
                let v = it.next().ok_or_else(|| anyhow!("--alpha needs a value"))?;
                alpha = parse_number("--alpha", v)?;
                anyhow::ensure!(
                    alpha > 0.0 && alpha < 1.0,
                    "--alpha must be in (0, 1), got {alpha}"
                );
            }
            f if f.starts_with('-') => bail!("unknown option '{f}' for compare (see --help)"),
            f => files.push(PathBuf::from(f)),
        }
    }
    let [a, b] = files.as_slice() else {
        bail!("compare needs two EXR files: vkpt compare A.exr B.exr [--alpha A]");
    };
    let image_a = vkpt::output::read_exr(a)?;
    let image_b = vkpt::output::read_exr(b)?;
    anyhow::ensure!(
        (image_a.width, image_a.height) == (image_b.width, image_b.height),
        "{} is {}x{} but {} is {}x{}",
        a.display(),
        image_a.width,
        image_a.height,
        b.display(),
        image_b.width,
        image_b.height
    );
    println!(
        "relMSE of {} against {}: {:.3e}",
        a.display(),
        b.display(),
        vkpt::stats::rel_mse(&image_a, &image_b)
    );
    for (path, image) in [(a, &image_a), (b, &image_b)] {
        anyhow::ensure!(
            image.variance.is_some(),
            "{} has no variance layer, so agreement cannot be tested; write renders as .exr with vkpt",
            path.display()
        );
    }
    let comparison = vkpt::stats::compare(&image_a, &image_b, alpha)?;
    println!("{comparison}");
    Ok(comparison.passed())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|a| a == "compare") {
        let code = match compare_command(&args[1..]) {
            Ok(true) => 0,
            Ok(false) => 1,
            Err(e) => {
                eprintln!("error: {e:#}");
                2
            }
        };
        std::process::exit(code);
    }
    let code = match parse_args(&args) {
        Ok(None) => 0,
        Ok(Some(a)) => match run(a) {
            Ok(code) => code,
            Err(e) => {
                eprintln!("error: {e:#}");
                1
            }
        },
        Err(e) => {
            eprintln!("error: {e:#}");
            2
        }
    };
    std::process::exit(code);
}
