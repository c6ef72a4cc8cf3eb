//! `vkpt SCENE`: load, apply the command line's overrides, render with
//! progress and checkpoints, write the image and print the summary.

use crate::args::MotionBlur;
use crate::args::{LightArgs, RenderArgs, depth_limit};
use crate::interrupt::{INTERRUPTED, install_sigint_handler};
use crate::progress::{RenderProgress, si};
use anyhow::{Context as _, bail};
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use vkpt::film::Film;
use vkpt::image::sensor::SensorSettings;
use vkpt::image::{
    Image, PngSettings, RenderHeader, SUPPORTED_EXTENSIONS, write_image_with_header,
};
use vkpt::packed::PackedScene;
use vkpt::render::header::render_header;
use vkpt::render::motion::{Shutter, render_motion_blur};
use vkpt::render::progressive::{Progressive, StopReason, StopRules};
use vkpt::render::{Backend, RenderAll, RenderResult, RenderSettings};
use vkpt::scene::camera::find_camera;
use vkpt::scene::motion::pose_over_shutter;
use vkpt::scene::{CameraOverrides, EnvironmentMap, GltfFile, LoadOptions, Scene};

/// Samples per pixel without --spp.
const DEFAULT_SPP: u32 = 64;
/// The most samples per pixel the film counts exactly (`RenderSettings::validate`).
const MAX_SPP: u32 = 1 << 24;

/// Applies the environment options to the scene, with notes for the user.
pub(crate) fn apply_light_options(scene: &mut Scene, o: &LightArgs) -> anyhow::Result<()> {
    if o.env.is_some() && o.background.is_some() {
        bail!("--env and --background both set the environment: give one");
    }
    let default_note = |n: &String| n.contains("lit by a uniform white environment");
    if let Some(path) = &o.env {
        scene.environment_map = Some(EnvironmentMap::load(path)?);
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

fn pick_camera(scene: &Scene, wanted: Option<&str>) -> anyhow::Result<usize> {
    let Some(wanted) = wanted else { return Ok(0) };
    match find_camera(scene.cameras.iter().map(|c| c.name.as_str()), wanted) {
        Some(i) => Ok(i),
        None => {
            let names: Vec<String> = scene
                .cameras
                .iter()
                .enumerate()
                .map(|(i, c)| format!("{i}: '{}'", c.name))
                .collect();
            bail!(
                "{}: no camera '{wanted}'; cameras are {}",
                scene.source.display(),
                names.join(", ")
            )
        }
    }
}

/// How the scene file is read: the same for one image and for a sequence.
pub(crate) fn load_options(args: &RenderArgs) -> LoadOptions {
    LoadOptions {
        allow_outside_uris: args.allow_outside_uris,
        camera: args.camera.clone(),
        time: args.animation.time,
        animation: args.animation.animation.clone(),
        variant: args.variant.clone(),
        instancing: args.instancing.mode(),
    }
}

fn camera_overrides(args: &RenderArgs) -> CameraOverrides {
    let c = &args.camera_overrides;
    CameraOverrides {
        fstop: c.fstop,
        focus_distance: c.focus_distance,
        focal_length: c.focal_length,
        blades: c.blades,
        blade_rotation: c.blade_rotation,
        filter: c.filter,
        filter_radius: c.filter_radius,
        shutter: c.shutter,
        iso: c.iso,
    }
}

/// The PNG settings: the command line's exposure plus the camera's EV100
/// shift when it has a shutter time. Checkpoints use the same.
/// A pinhole camera whose shutter blurs a moving scene (`blurs`) gets no
/// exposure from it: the shutter only sets the motion-blur interval.
fn png_settings(
    args: &RenderArgs,
    scene: &Scene,
    camera: usize,
    blurs: bool,
) -> anyhow::Result<PngSettings> {
    let camera = &scene.cameras[camera];
    let mut png = PngSettings {
        exposure_ev: args.image.exposure,
        tonemap: args.image.tonemap,
    };
    if camera.shutter.is_some() && blurs && camera.lens.is_pinhole() {
        return Ok(png);
    }
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
    Ok(png)
}

/// A file name's extension in lower case ("" when it has none).
fn lowercase_extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// The output path, checked before minutes are spent rendering.
pub(crate) fn output_path(args: &RenderArgs, scene_path: &Path) -> anyhow::Result<PathBuf> {
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = scene_path.file_stem().unwrap_or_default().to_string_lossy();
        PathBuf::from(format!("{stem}.png"))
    });
    if !SUPPORTED_EXTENSIONS.contains(&lowercase_extension(&output).as_str()) {
        bail!(
            "{}: vkpt writes {} images",
            output.display(),
            SUPPORTED_EXTENSIONS.join(" or ")
        );
    }
    Ok(output)
}

/// The image to write and what went into it.
pub(crate) struct ToWrite {
    pub image: Image,
    /// The render's estimated relMSE, before any sensor (whose image has no
    /// variance).
    rel_mse: f64,
    denoise_time: Option<Duration>,
    /// The raw mosaic in ADU, with `--sensor bayer`.
    mosaic: Option<Vec<f32>>,
}

/// The film as the image to write: the auxiliary outputs `--aov` asked for,
/// with `--sensor bayer` what the sensor makes of it (demosaiced; its
/// variance and sample counts dropped, as they no longer describe the
/// pixels), and with `--denoise` what Open Image Denoise makes of that,
/// guided by the film's albedo and normal (recorded for it), with the time
/// that took.
pub(crate) fn image_to_write(
    film: &Film,
    args: &RenderArgs,
    sensor: Option<&SensorSettings>,
) -> anyhow::Result<ToWrite> {
    let mut image = film.to_image();
    let rel_mse = image.estimated_rel_mse();
    let mut mosaic = None;
    if let Some(sensor) = sensor {
        let out = vkpt::image::sensor::simulate(image.width, image.height, &image.mean, sensor);
        image.mean = out.rgb;
        image.variance = None;
        image.samples = None;
        mosaic = Some(out.mosaic_adu);
    }
    let mut denoise_time = None;
    if args.image.denoise {
        let start = Instant::now();
        let aovs = &image.aovs;
        let denoised = vkpt::image::denoise::denoise(
            image.width,
            image.height,
            &image.mean,
            aovs.albedo.as_deref(),
            aovs.normal.as_deref(),
        )
        .context("denoising (--denoise)")?;
        image.denoised = Some(denoised);
        denoise_time = Some(start.elapsed());
    }
    let asked = |name: &str| args.image.aov.iter().any(|a| a == name);
    let aovs = &mut image.aovs;
    if !asked("albedo") {
        aovs.albedo = None;
    }
    if !asked("normal") {
        aovs.normal = None;
    }
    if !asked("depth") {
        aovs.depth = None;
    }
    Ok(ToWrite {
        image,
        rel_mse,
        denoise_time,
        mosaic,
    })
}

/// The sensor `--sensor bayer` asks for, exposed as the PNG is; None for
/// the ideal film.
fn sensor_settings(args: &RenderArgs, png: &PngSettings) -> anyhow::Result<Option<SensorSettings>> {
    let s = &args.sensor;
    if !s.is_bayer() {
        if s.raw_mosaic.is_some() {
            bail!("--raw-mosaic needs --sensor bayer");
        }
        return Ok(None);
    }
    if let Some(path) = &s.raw_mosaic
        && !SUPPORTED_EXTENSIONS.contains(&lowercase_extension(path).as_str())
    {
        bail!(
            "--raw-mosaic {}: vkpt writes .exr or .png mosaics",
            path.display()
        );
    }
    eprintln!(
        "note: --sensor bayer: the image is the demosaiced sensor image; its EXR has no variance or samples channels (not for vkpt compare or merge)"
    );
    Ok(Some(SensorSettings {
        bits: s.sensor_bits,
        noise: s.sensor_noise == "on",
        demosaic: s.demosaic,
        exposure_ev: png.exposure_ev,
        seed: args.seed as u64,
    }))
}

fn stop_rules(args: &RenderArgs) -> StopRules {
    let p = &args.progressive;
    StopRules {
        time_limit: p.time_limit.map(Duration::from_secs_f64),
        target_error: p.target_error,
        checkpoint_every: (p.checkpoint > 0.0).then(|| Duration::from_secs_f64(p.checkpoint)),
    }
}

/// The render settings, PNG exposure and sensor for `scene` (its camera
/// takes the command line's overrides, with notes when `say`); `file` and
/// `time` tell whether the camera's shutter blurs motion.
pub(crate) fn frame_settings(
    args: &RenderArgs,
    scene: &mut Scene,
    (file, time): (&GltfFile, f64),
    open_ended: bool,
    say: bool,
) -> anyhow::Result<(RenderSettings, PngSettings, Option<SensorSettings>)> {
    let scene_path = scene.source.clone();
    let (first_sample, spp) = match &args.split.samples {
        Some(range) => (range.start, range.len() as u32),
        None => (
            0,
            args.spp
                .unwrap_or(if open_ended { MAX_SPP } else { DEFAULT_SPP }),
        ),
    };
    let mut settings = RenderSettings {
        width: args.frame.width.unwrap_or(512),
        height: args.frame.height.unwrap_or(0),
        spp,
        first_sample,
        region: args.split.region,
        max_depth: depth_limit(args.frame.max_depth),
        seed: args.seed,
        sampler: args.frame.sampler,
        texture_filter: args.frame.texture_filter,
        camera: pick_camera(scene, args.camera.as_deref())?,
        // The denoiser is guided by albedo and normal.
        aov: !args.image.aov.is_empty() || args.image.denoise,
    };
    let camera = &mut scene.cameras[settings.camera];
    for note in camera_overrides(args)
        .apply(camera)
        .with_context(|| format!("{}", scene_path.display()))?
    {
        if say {
            eprintln!("note: {note}");
        }
    }
    let blurs = scene.cameras[settings.camera]
        .shutter
        .is_some_and(|s| file.moves_during(time, time + s as f64));
    let png = png_settings(args, scene, settings.camera, blurs)?;
    let sensor = sensor_settings(args, &png)?;
    if args.frame.height.is_none() {
        let aspect = scene.cameras[settings.camera].aspect_ratio.unwrap_or(1.0);
        settings.height = ((settings.width as f32 / aspect).round() as u32).max(1);
    }
    settings.validate()?;
    Ok((settings, png, sensor))
}

/// The shutter to blur over: the camera's (`--shutter` or its `shutter`
/// extra), opening at `time`, when something moves while it is open.
pub(crate) fn motion_shutter(
    file: &GltfFile,
    scene: &Scene,
    settings: &RenderSettings,
    time: f64,
) -> Option<Shutter> {
    let duration = scene.cameras[settings.camera].shutter? as f64;
    (duration > 0.0 && file.moves_during(time, time + duration)).then_some(Shutter {
        open: time,
        duration,
    })
}

/// The scene posed over `shutter` for the kernels, each path at its own
/// time (`scene::motion`), or the reason they cannot follow its motion
/// (then [`render_blurred`] takes host time steps). Prints what it chose.
pub(crate) fn scene_in_motion(
    args: &RenderArgs,
    file: &GltfFile,
    shutter: Shutter,
) -> anyhow::Result<Result<Scene, String>> {
    if args.animation.motion_blur == MotionBlur::TimeSteps {
        return Ok(Err("--motion-blur time-steps".to_string()));
    }
    // Light options set the environment, which does not move: only the
    // first pose needs them (they may load a map).
    let mut pose = |time: f64, origin: Option<DVec3>| -> anyhow::Result<Scene> {
        let mut scene = file.at_from_in_one_level(time, origin)?;
        if origin.is_none() {
            apply_light_options(&mut scene, &args.light)?;
        }
        frame_settings(args, &mut scene, (file, shutter.open), false, false)?;
        Ok(scene)
    };
    let moving = pose_over_shutter(&mut pose, shutter.open, shutter.duration)?;
    let close = (shutter.open + shutter.duration) as f32;
    match (&moving, args.quiet) {
        (Ok(scene), false) => {
            let m = scene.motion.as_ref().expect("a scene in motion");
            println!(
                "motion blur: shutter {}..{close} s, every path at its own time, {} time steps (linear between them, within {:.1e} of the scene's size or radians of the true motion)",
                shutter.open as f32,
                m.steps.len(),
                m.deviation
            );
        }
        (Err(reason), _) if args.animation.motion_blur == MotionBlur::PerPath => eprintln!(
            "note: {reason}: motion blur over {}..{close} s by time steps on the host instead of a time per path",
            shutter.open as f32
        ),
        _ => {}
    }
    Ok(moving)
}

/// Renders `settings` blurred over `shutter` (`render::motion`): the scene
/// posed at each step's time with the command line's overrides; prints
/// what the steps cost.
pub(crate) fn render_blurred(
    args: &RenderArgs,
    file: &GltfFile,
    backend: &mut Backend,
    settings: &RenderSettings,
    shutter: Shutter,
) -> anyhow::Result<RenderResult> {
    // Every step is rendered: each gets the light options.
    let mut pose = |time: f64, origin: Option<DVec3>| -> anyhow::Result<Scene> {
        let mut scene = file.at_from(time, origin)?;
        apply_light_options(&mut scene, &args.light)?;
        frame_settings(args, &mut scene, (file, shutter.open), false, false)?;
        Ok(scene)
    };
    let mut render = |scene: &Scene, packed: &PackedScene, part: &RenderSettings| {
        backend.render_progressive(scene, packed, part, &|_, _| {}, &mut RenderAll)
    };
    let (result, stats) = render_motion_blur(shutter, settings, &mut pose, &mut render)?;
    if !args.quiet {
        println!(
            "motion blur: shutter {}..{} s in {} time steps of {} spp; posing {:.1} ms, BVH builds {:.1} ms ({:.2} ms per step)",
            shutter.open as f32,
            (shutter.open + shutter.duration) as f32,
            stats.steps,
            settings.spp / stats.steps,
            stats.pose_time.as_secs_f64() * 1e3,
            stats.bvh_time.as_secs_f64() * 1e3,
            stats.bvh_time.as_secs_f64() * 1e3 / stats.steps as f64
        );
    }
    Ok(result)
}

/// Renders and writes the image; the exit status (0, or 130 when interrupted).
pub fn run(args: RenderArgs) -> anyhow::Result<i32> {
    let Some(scene_path) = args.scene.clone() else {
        bail!("no scene given: vkpt SCENE.gltf [OPTIONS] (see vkpt --help)");
    };
    if args.image.denoise {
        // Before the scene loads and minutes go into rendering.
        vkpt::image::denoise::available().map_err(anyhow::Error::msg)?;
    }
    if let Some(frames) = args.animation.frames.clone() {
        return crate::sequence_command::run(&args, &scene_path, frames);
    }
    let load_start = Instant::now();
    let load = load_options(&args);
    let file = Scene::open_file(&scene_path, &load)?;
    let mut scene = file.at(load.time)?;
    apply_light_options(&mut scene, &args.light)?;
    let load_time = load_start.elapsed();
    for note in &scene.notes {
        eprintln!("{}", vkpt::scene::note_line(note));
    }
    let stop = stop_rules(&args);
    let open_ended = args.spp.is_none()
        && args.split.samples.is_none()
        && (stop.time_limit.is_some() || stop.target_error.is_some());
    let (settings, png, sensor) = frame_settings(
        &args,
        &mut scene,
        (&file, args.animation.time),
        open_ended,
        true,
    )?;
    let output = output_path(&args, &scene_path)?;
    note_what_png_loses(&args, &output);

    // Motion blur: a time per path in the kernels where they can follow the
    // motion, else time steps on the host.
    let mut blur_on_host = None;
    if let Some(shutter) = motion_shutter(&file, &scene, &settings, args.animation.time) {
        match scene_in_motion(&args, &file, shutter)? {
            Ok(moving) => scene = moving,
            Err(_) => blur_on_host = Some(shutter),
        }
    }
    scene.light_sampler = args.light_sampler.mode();
    // The file's buffers are read again only to pose the scene at other
    // times (motion blur on the host): freed before the BVH build otherwise,
    // and the scene's triangles once they are packed (docs/performance.md,
    // "Memory per triangle").
    let blur_on_host = blur_on_host.map(|shutter| (shutter, file));
    let packed = PackedScene::from_scene(&mut scene)?;
    let (mut backend, why) = Backend::open(args.device, args.schedule, &scene, &packed, &settings)?;
    // What the EXR holds; the back end's name and the samples are filled in
    // when they are known.
    let header = render_header(&scene, &packed, &settings, 0, "")?;
    let header_at = |spp: u32, backend: &str| RenderHeader {
        samples: settings.first_sample..settings.first_sample + spp,
        backend: backend.to_string(),
        ..header.clone()
    };
    let backend_name = backend.name();
    let progress = RenderProgress::new(settings.pixel_count(), open_ended, !args.quiet);
    let mut checkpoint = |film: &Film, spp: u32| -> anyhow::Result<()> {
        let h = header_at(spp, &backend_name);
        let image = image_to_write(film, &args, sensor.as_ref())?.image;
        write_image_with_header(&output, &image, &png, Some(&h))
            .with_context(|| format!("writing a checkpoint to {}", output.display()))?;
        if !args.quiet {
            progress.println(&format!(
                "checkpoint: wrote {} at {spp} spp",
                output.display()
            ));
        }
        Ok(())
    };
    install_sigint_handler();
    let (result, reason) = match blur_on_host {
        Some((shutter, file)) => {
            if open_ended || args.split.samples.is_some() {
                bail!(
                    "motion blur by host time steps renders all of --spp: it does not take --time-limit, --target-error or --samples"
                );
            }
            let result = render_blurred(&args, &file, &mut backend, &settings, shutter)?;
            (result, StopReason::Finished)
        }
        None => {
            let mut control = Progressive::new(stop.clone(), &INTERRUPTED, &mut checkpoint);
            let result = backend.render_progressive(
                &scene,
                &packed,
                &settings,
                &|done, total| progress.update(done, total),
                &mut control,
            )?;
            (result, control.reason())
        }
    };
    progress.finish();
    let written = image_to_write(&result.film, &args, sensor.as_ref())?;
    let h = header_at(result.spp, &result.device_name);
    write_image_with_header(&output, &written.image, &png, Some(&h))
        .with_context(|| format!("writing {}", output.display()))?;
    if let (Some(path), Some(mosaic), Some(sensor)) =
        (&args.sensor.raw_mosaic, &written.mosaic, &sensor)
    {
        let image = &written.image;
        vkpt::image::write_mosaic(
            path,
            image.width,
            image.height,
            mosaic,
            sensor.max_adu() as f32,
        )
        .with_context(|| format!("writing the raw mosaic {}", path.display()))?;
        println!("wrote the raw mosaic {}", path.display());
    }

    let summary = Summary {
        settings: &settings,
        packed: &packed,
        result: &result,
        rel_mse: written.rel_mse,
        load_time,
        why: &why,
    };
    summary.print(args.timings);
    if let Some(t) = written.denoise_time {
        println!(
            "denoised in {:.2} s with {}",
            t.as_secs_f64(),
            vkpt::image::denoise::library_description()
                .unwrap_or_else(|| "Open Image Denoise".to_string())
        );
    }
    let asked = if args.spp.is_some() || settings.spp != MAX_SPP {
        format!(" of the {} asked for", settings.spp)
    } else {
        String::new()
    };
    // A render stopped early is a part: say how to finish it.
    let samples = settings.samples();
    let done = settings.first_sample + result.spp;
    if reason != StopReason::Finished && done < samples.end && settings.spp != MAX_SPP {
        println!(
            "to finish it: render --samples {done}..{} with the same settings and join the \
             two with vkpt merge",
            samples.end
        );
    }
    match reason {
        StopReason::Finished => {}
        StopReason::TimeLimit => println!(
            "stopped at the time limit of {:.1} s after {} spp{asked}",
            stop.time_limit.unwrap_or_default().as_secs_f64(),
            result.spp
        ),
        StopReason::TargetError(e) => println!(
            "stopped at {} spp{asked}: estimated relative error {:.2}% reached the target {:.2}%",
            result.spp,
            e * 100.0,
            stop.target_error.unwrap_or_default() * 100.0
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

/// ", textures 12.3 MiB": the texels the kernels read (RGBA8 a word each,
/// grey a byte, grey with alpha two bytes; and the sRGB table), where the
/// scene has textures.
fn texture_memory(packed: &PackedScene) -> String {
    let t = &packed.textures;
    if t.textures.is_empty() {
        return String::new();
    }
    let bytes = std::mem::size_of_val(t.texels.as_slice());
    format!(", textures {:.1} MiB", bytes as f64 / (1024.0 * 1024.0))
}

/// What the summary lines report.
struct Summary<'a> {
    settings: &'a RenderSettings,
    packed: &'a PackedScene,
    result: &'a RenderResult,
    /// The render's estimated relMSE (before any sensor).
    rel_mse: f64,
    load_time: Duration,
    why: &'a str,
}

impl Summary<'_> {
    fn print(&self, timings: bool) {
        let (settings, packed, result) = (self.settings, self.packed, self.result);
        let secs = result.render_time.as_secs_f64().max(1e-9);
        let samples = settings.pixel_count() as f64 * result.spp as f64;
        let rays = (result.extension_rays + result.shadow_rays) as f64;
        println!(
            "device: {}, {} | scene: {} triangles, {} emitters, {} lights{}{} | load {:.0} ms, BVH {:.1} ms, scene memory {:.1} MiB",
            result.device_name,
            self.why,
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
            texture_memory(packed),
            self.load_time.as_secs_f64() * 1e3,
            packed.bvh_build_time.as_secs_f64() * 1e3,
            packed.memory_bytes() as f64 / (1024.0 * 1024.0),
        );
        if let Some(i) = &packed.instancing {
            println!(
                "instancing: {} instances of {} meshes place {} triangles, {} stored once | BVHs: meshes {:.1} ms, top level {:.1} ms",
                i.instances,
                i.meshes,
                i.placed_triangles,
                i.unique_triangles,
                i.bottom_build_time.as_secs_f64() * 1e3,
                i.top_build_time.as_secs_f64() * 1e3,
            );
        }
        let region = settings.film_region();
        let what = if region.is_full(settings.width, settings.height) {
            format!("{}x{}", settings.width, settings.height)
        } else {
            format!(
                "region {region} ({}x{}) of {}x{}",
                region.width(),
                region.height(),
                settings.width,
                settings.height
            )
        };
        let spp = if settings.first_sample > 0 {
            format!(
                "samples {}..{}",
                settings.first_sample,
                settings.first_sample + result.spp
            )
        } else {
            format!("{} spp", result.spp)
        };
        println!(
            "rendered {what} at {spp} in {:.2} s: {}samples/s, {}rays/s ({}extension + {}shadow rays), \
             est. relative error {:.2}% (relMSE {:.2e})",
            secs,
            si(samples / secs),
            si(rays / secs),
            si(result.extension_rays as f64),
            si(result.shadow_rays as f64),
            self.rel_mse.sqrt() * 100.0,
            self.rel_mse,
        );
        if let Some(variant) = &result.kernel_variant {
            println!("kernels specialized to: {variant}");
        }
        if timings && !result.kernel_times.is_empty() {
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
            if result.paths_parked > 0 {
                println!(
                    "per-path loop: {} of {} paths parked for the wavefront kernels ({:.3}%)",
                    result.paths_parked,
                    samples as u64,
                    100.0 * result.paths_parked as f64 / samples.max(1.0)
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
    }
}

/// Notes what a PNG output cannot hold of what was asked for.
pub(crate) fn note_what_png_loses(args: &RenderArgs, output: &Path) {
    if output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
    {
        return;
    }
    if args.split.samples.is_some() || args.split.region.is_some() {
        eprintln!(
            "note: {} is a PNG: vkpt merge needs the EXR's samples and header to join parts",
            output.display()
        );
    }
    if !args.image.aov.is_empty() {
        eprintln!(
            "note: {} is a PNG: the --aov layers are written to EXR files only",
            output.display()
        );
    }
}
