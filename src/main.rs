//! The `vkpt` command: argument parsing, progress and the summary line.
//! Try: `vkpt scenes/cornell-box.gltf --spp 64 -o cornell.png`

use anyhow::{Context as _, anyhow, bail};
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use vkpt::cli_args::{flag_value, parse_number, split_flag};
use vkpt::image::{PngSettings, ToneMap, write_image};
use vkpt::packed::PackedScene;
use vkpt::render::progressive::{Progressive, StopReason, StopRules};
use vkpt::render::{DeviceChoice, render_progressive};
use vkpt::render::{RenderSettings, Sampler};
use vkpt::scene::{CameraOverrides, FilterKind, LoadOptions, Scene};

const HELP: &str = "\
vkpt: a physically based path tracer on Vulkan compute, checked against a CPU reference

USAGE:
    vkpt SCENE.gltf|SCENE.glb [OPTIONS]
    vkpt compare A.exr B.exr [--alpha A] [--max-rel-mse T]
    vkpt bench SCENE.gltf... [OPTIONS]   (speed against error; see vkpt bench --help)

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
        --exposure EV     PNG exposure compensation in stops: radiance is multiplied by
                          2^EV (on top of --shutter/--iso when given) [default: 0]
        --shutter T       Shutter time in seconds; with the f-number and --iso it sets the
                          PNG exposure by the EV100 convention: radiance is scaled by
                          1 / (1.2 * 2^EV100), EV100 = log2(N^2 / T) - log2(ISO / 100)
                          (needs an f-number above 0) [default: the camera's extras]
        --iso S           ISO sensitivity for --shutter [default: the camera's, else 100]
        --env FILE        Light the scene with an equirectangular environment map (.exr
                          or .hdr; row 0 is straight up (+Y), the centre faces -Z),
                          importance sampled; replaces the scene's environment
        --env-rotation DEG  Rotate the environment map about +Y [default: 0]
        --env-intensity X Scale the environment's radiance (map or uniform) [default: 1]
        --background R,G,B  A uniform environment of this radiance (the ambient light);
                          replaces the scene's environment; 0,0,0 for none
        --hide-env        Camera rays that leave the scene see black; the environment
                          still lights the scene
        --tonemap T       PNG tone map: neutral (Khronos PBR Neutral), aces, clamp
                          [default: neutral]
CAMERA (override the glTF camera's vkpt extras; lengths in scene units, metres):
        --fstop N         f-number; the aperture diameter is focal length / N. 0 = pinhole
        --focus-distance D  Distance of the plane in focus along the view axis
        --focal-length F  Focal length (0.05 = 50 mm). Sets the aperture only: the field
                          of view stays the glTF yfov [default: the extras', else from
                          yfov and a 24 mm sensor height]
        --blades N        Aperture blades: 0 = round, 3..64 = regular polygon (N-gon bokeh)
        --blade-rotation DEG  Angle of the first polygon vertex from the camera's right axis
        --filter F        Pixel filter, importance sampled (every sample has weight 1):
                          box (radius 0.5), tent (1), gaussian (1.5, sigma = radius / 3),
                          blackman-harris (2) [default: box]
        --filter-radius R Filter radius in pixels [default: per filter, above]
PROGRESSIVE RENDERING:
        --time-limit S    Stop at the last pass that ends within S seconds
        --target-error E  Stop once the estimated relative error (from the per-pixel
                          variance; with sobol usually an overestimate) is at most E,
                          e.g. 0.02. With either stopping rule and no --spp, spp is
                          unbounded (16777216)
        --checkpoint S    Write the image so far every S seconds during the render
                          (0: never) [default: 60]
OTHER:
        --timings         Print the time spent in each kernel (Vulkan devices)
        --allow-outside-uris
                          Read buffers and images that the scene's URIs place outside
                          its folder (absolute paths, '..', symbolic links leading
                          out); refused by default
    -q, --quiet           No progress bar
    -h, --help            This help
    -V, --version         Version

COMPARE:
    Tests whether two renders written by vkpt as EXR (with their variance
    layers) have the same expectation: z-tests per pixel, on 4x4 and 16x16
    blocks and on the whole image, with Sidak (within a level) and Bonferroni
    (across levels) corrections at the given family-wise alpha [default: 0.01].
    First prints error metrics of A against B (mean, bias and RMSE per
    channel, relMSE, the 16x16 block deviating most); exits 0 when they
    agree, 1 when they do not, 2 on bad input. Render them with different
    --seed. When a file has no variance layer (an EXR from another renderer)
    the z-tests cannot run: it says so and judges agreement by relMSE <=
    --max-rel-mse [default: 1e-3] alone.
    Render both with --sampler independent: the per-pixel variance assumes
    independent samples (with sobol it usually overestimates it, and the test
    loses power).

INTERRUPTING:
    Ctrl-C (SIGINT) finishes the current pass, writes the image with the
    samples every pixel has so far, and exits with status 130. A second Ctrl-C
    exits at once (the output file is renamed into place only when complete).

ENVIRONMENT:
    VKPT_VALIDATION=1     Enable the Khronos validation layer (vulkan-validationlayers)
    VKPT_KERNELS=all      Use the all-features kernels instead of kernels specialized
                          to the scene (the summary names the variant it chose)

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
    lens: CameraOverrides,
    timings: bool,
    quiet: bool,
    light: LightOptions,
    load: LoadOptions,
    spp_given: bool,
    stop: StopRules,
}

/// The environment options, applied to the loaded scene.
#[derive(Default)]
struct LightOptions {
    env: Option<PathBuf>,
    env_rotation: Option<f32>,
    env_intensity: Option<f32>,
    background: Option<glam::Vec3>,
    hide_env: bool,
}

fn parse_background(value: &str) -> anyhow::Result<glam::Vec3> {
    let parts: Vec<Option<f32>> = value
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<f32>()
                .ok()
                .filter(|x| x.is_finite() && *x >= 0.0)
        })
        .collect();
    match parts.as_slice() {
        [Some(r), Some(g), Some(b)] => Ok(glam::Vec3::new(*r, *g, *b)),
        _ => bail!("--background expects R,G,B: three non-negative numbers, got '{value}'"),
    }
}

/// Applies the environment options to the scene, with notes for the user.
fn apply_light_options(scene: &mut Scene, o: &LightOptions) -> anyhow::Result<()> {
    if o.env.is_some() && o.background.is_some() {
        bail!("--env and --background both set the environment: give one");
    }
    let default_note = |n: &String| n.contains("lit by a uniform white environment");
    if let Some(path) = &o.env {
        scene.environment_map = Some(vkpt::scene::EnvironmentMap::load(path)?);
        scene.environment = Some(glam::Vec3::ONE);
        scene.notes.retain(|n| !default_note(n));
    }
    if let Some(rgb) = o.background {
        scene.environment_map = None;
        scene.environment = Some(rgb);
        scene.notes.retain(|n| !default_note(n));
    }
    if let Some(x) = o.env_intensity {
        match scene.environment {
            Some(env) => scene.environment = Some(env * x),
            None => scene.notes.push(
                "--env-intensity ignored: the scene has no environment (give --env or --background)"
                    .to_string(),
            ),
        }
    }
    if let Some(deg) = o.env_rotation {
        if scene.environment_map.is_none() {
            scene
                .notes
                .push("--env-rotation ignored: the scene has no environment map".to_string());
        }
        scene.environment_rotation = deg;
    }
    if o.hide_env {
        scene.environment_hidden = true;
    }
    Ok(())
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
        lens: CameraOverrides::default(),
        timings: false,
        quiet: false,
        light: LightOptions::default(),
        load: LoadOptions::default(),
        spp_given: false,
        stop: StopRules {
            checkpoint_every: Some(Duration::from_secs(60)),
            ..Default::default()
        },
    };
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let (flag, inline) = split_flag(arg);
        let mut value = || flag_value(flag, &inline, &mut it, "--help");
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
            "--env" => a.light.env = Some(PathBuf::from(value()?)),
            "--env-rotation" => {
                let v: f32 = parse_number(flag, &value()?)?;
                anyhow::ensure!(
                    v.is_finite(),
                    "--env-rotation must be a finite number of degrees"
                );
                a.light.env_rotation = Some(v);
            }
            "--env-intensity" => {
                let v: f32 = parse_number(flag, &value()?)?;
                anyhow::ensure!(
                    v.is_finite() && v >= 0.0,
                    "--env-intensity must be a non-negative number, got {v}"
                );
                a.light.env_intensity = Some(v);
            }
            "--background" => a.light.background = Some(parse_background(&value()?)?),
            "--hide-env" => a.light.hide_env = true,
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
            "--fstop" => a.lens.fstop = Some(parse_number(flag, &value()?)?),
            "--focus-distance" => a.lens.focus_distance = Some(parse_number(flag, &value()?)?),
            "--focal-length" => a.lens.focal_length = Some(parse_number(flag, &value()?)?),
            "--blades" => a.lens.blades = Some(parse_number(flag, &value()?)?),
            "--blade-rotation" => a.lens.blade_rotation = Some(parse_number(flag, &value()?)?),
            "--filter" => {
                let v = value()?;
                a.lens.filter = Some(FilterKind::from_name(&v).ok_or_else(|| {
                    anyhow!(
                        "--filter must be one of {}, got '{v}'",
                        FilterKind::NAMES.join(", ")
                    )
                })?);
            }
            "--filter-radius" => a.lens.filter_radius = Some(parse_number(flag, &value()?)?),
            "--shutter" => a.lens.shutter = Some(parse_number(flag, &value()?)?),
            "--iso" => a.lens.iso = Some(parse_number(flag, &value()?)?),
            "--timings" => a.timings = true,
            "--allow-outside-uris" => a.load.allow_outside_uris = true,
            "-q" | "--quiet" => a.quiet = true,
            f if f.starts_with('-') && f.len() > 1 => bail!("unknown option '{f}' (see --help)"),
            _ if scene.is_none() => scene = Some(PathBuf::from(arg)),
            _ => bail!("unexpected argument '{arg}': vkpt renders one scene at a time"),
        }
    }
    a.scene = scene.ok_or_else(|| anyhow!("no scene given\n\n{HELP}"))?;
    // Bad lens values are usage errors, found before the scene is loaded.
    a.lens.validate()?;
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
    let mut scene = Scene::load_with(&args.scene, &args.load)?;
    apply_light_options(&mut scene, &args.light)?;
    let load_time = load_start.elapsed();
    for note in &scene.notes {
        eprintln!("note: {note}");
    }
    let mut settings = args.settings.clone();
    settings.camera = pick_camera(&scene, args.camera.as_deref())?;
    let camera = &mut scene.cameras[settings.camera];
    let camera_notes = args
        .lens
        .apply(camera)
        .with_context(|| format!("{}", args.scene.display()))?;
    for note in &camera_notes {
        eprintln!("note: {note}");
    }
    let mut png = args.png;
    if let Some(shutter) = camera.shutter {
        anyhow::ensure!(
            !camera.lens.is_pinhole(),
            "camera '{}': exposure from a shutter time needs an f-number above 0 (--fstop)",
            camera.name
        );
        let iso = camera.iso.unwrap_or_else(|| {
            eprintln!("note: no ISO given: exposure for ISO 100");
            100.0
        });
        let fstop = camera.lens.fstop;
        png.exposure_ev += vkpt::image::tonemap::exposure_from_camera(fstop, shutter, iso);
        eprintln!(
            "note: exposure EV100 {:.2} (f/{fstop}, {shutter} s, ISO {iso}): radiance scaled by 2^{:.2}",
            vkpt::image::tonemap::ev100(fstop, shutter, iso),
            png.exposure_ev
        );
    } else if camera.iso.is_some() {
        bail!(
            "camera '{}': an ISO without a shutter time does not set an exposure (give --shutter)",
            camera.name
        );
    }
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
    if !vkpt::image::SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
        bail!(
            "{}: vkpt writes {} images",
            output.display(),
            vkpt::image::SUPPORTED_EXTENSIONS.join(" or ")
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
        DeviceChoice::Auto => {
            match vkpt::gpu::GpuRenderer::new(vkpt::gpu::context::VulkanDevice::Best) {
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
            }
        }
        device => render_progressive(&scene, &packed, &settings, device, &progress, &mut control)?,
    };
    let reason = control.reason();
    if bar.tty && bar.enabled && reason != StopReason::Finished {
        eprintln!();
    }
    let image = result.film.to_image();
    write_image(&output, &image, &png).with_context(|| format!("writing {}", output.display()))?;

    let secs = result.render_time.as_secs_f64().max(1e-9);
    let samples = settings.pixel_count() as f64 * result.spp as f64;
    let rays = (result.extension_rays + result.shadow_rays) as f64;
    println!(
        "device: {} | scene: {} triangles, {} emitters, {} lights{} | load {:.0} ms, BVH {:.1} ms",
        result.device_name,
        packed.tri_verts.len(),
        packed.emitters.len(),
        packed.light_params.num_lights,
        if packed.light_params.env_width > 0 {
            ", environment map"
        } else if packed.has_environment() {
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
    if let Some(variant) = &result.kernel_variant {
        println!("kernels specialized to: {variant}");
    }
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
    let mut max_rel_mse = 1e-3;
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
            "--max-rel-mse" => {
                let v = it
                    .next()
                    .ok_or_else(|| anyhow!("--max-rel-mse needs a value"))?;
                max_rel_mse = parse_number("--max-rel-mse", v)?;
                anyhow::ensure!(
                    max_rel_mse >= 0.0,
                    "--max-rel-mse must be at least 0, got {max_rel_mse}"
                );
            }
            f if f.starts_with('-') => bail!("unknown option '{f}' for compare (see --help)"),
            f => files.push(PathBuf::from(f)),
        }
    }
    let [a, b] = files.as_slice() else {
        bail!(
            "compare needs two EXR files: vkpt compare A.exr B.exr [--alpha A] [--max-rel-mse T]"
        );
    };
    let image_a = vkpt::image::read_exr(a)?;
    let image_b = vkpt::image::read_exr(b)?;
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
    let metrics = vkpt::image::metrics::error_metrics(&image_a, &image_b)?;
    println!(
        "relMSE of {} against {}: {:.3e}",
        a.display(),
        b.display(),
        metrics.rel_mse
    );
    println!("{metrics}");
    let missing: Vec<String> = [(a, &image_a), (b, &image_b)]
        .iter()
        .filter(|(_, image)| image.variance.is_none())
        .map(|(path, _)| path.display().to_string())
        .collect();
    if !missing.is_empty() {
        let agree = metrics.rel_mse <= max_rel_mse;
        println!(
            "no variance layer in {} (an EXR not written by vkpt?): the per-pixel z-test \
             cannot run, so agreement is judged by relMSE alone: {:.3e} {} {max_rel_mse:.1e} \
             (--max-rel-mse): {}",
            missing.join(" and "),
            metrics.rel_mse,
            if agree { "<=" } else { ">" },
            if agree { "agree" } else { "DIFFERENT" }
        );
        return Ok(agree);
    }
    let comparison = vkpt::image::compare::compare(&image_a, &image_b, alpha)?;
    println!("{comparison}");
    Ok(comparison.passed())
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().is_some_and(|a| a == "bench") {
        std::process::exit(vkpt::bench::cli::main(&args[1..]));
    }
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
