//! The command line, declared with clap: `vkpt SCENE` renders, and the
//! subcommands `compare` and `bench` test and measure. Values are checked
//! here, where the flag's name is known; the library speaks in settings.

use clap::builder::{PossibleValuesParser, TypedValueParser as _};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use vkpt::image::sensor::Demosaic;
use vkpt::image::{Region, ToneMap};
use vkpt::render::{DeviceChoice, Sampler, Schedule, TextureFilter};
use vkpt::scene::FilterKind;

const AFTER_HELP: &str = "\
Interrupting:
  Ctrl-C (SIGINT) finishes the current pass, writes the image with the samples
  every pixel has so far, and exits with status 130. A second Ctrl-C exits at
  once (the output file is renamed into place only when complete).

Environment:
  VKPT_VALIDATION=1  Enable the Khronos validation layer (vulkan-validationlayers)
  VKPT_KERNELS=all   Use the all-features kernels instead of kernels specialized
                     to the scene (the summary names the variant it chose)
  VKPT_SPIRV_OPT=off Hand lavapipe the kernels and their constants instead of
                     modules specialized ahead by spirv-opt (=PATH: the program)
  VKPT_SPLIT_SHADE=off
                     Shade every hit with one kernel, not one per kind of
                     material (the summary says split-shade when split)
  VKPT_OIDN_LIB=PATH libOpenImageDenoise.so.2 for --denoise [default: the venv
                     ~/.local/share/vkpt/oidn that the README's set-up makes
                     (pip package pyoidn), then the system library path]

Exit status: 0 rendered, 1 failed (bad scene, device error, no Open Image
Denoise for --denoise), 2 bad arguments, 130 interrupted.

Example:
  vkpt scenes/cornell-box.gltf --spp 256 -o cornell.exr --device cpu";

/// vkpt: a physically based path tracer on Vulkan compute, checked against a
/// CPU reference.
///
/// Renders a glTF 2.0 scene (.gltf or .glb) to EXR or PNG. `vkpt compare`
/// tests whether two renders have the same expectation; `vkpt bench`
/// measures speed against error.
#[derive(Parser, Debug)]
#[command(
    name = "vkpt",
    version,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    after_long_help = AFTER_HELP
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub render: RenderArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Test whether two EXR renders have the same expectation.
    Compare(CompareArgs),
    /// Speed against error: render scenes at increasing spp on each back end.
    Bench(BenchArgs),
    /// Combine parts of one render (sample ranges, regions) into one image.
    Merge(MergeArgs),
}

/// A number, with the bad text in the message.
fn number<T: std::str::FromStr>(s: &str) -> Result<T, String> {
    s.trim()
        .parse()
        .map_err(|_| format!("expects a number, got '{s}'"))
}

fn at_least_one(s: &str) -> Result<u32, String> {
    let n: u32 = number(s)?;
    if n == 0 {
        return Err("must be at least 1".into());
    }
    Ok(n)
}

/// -1 (no limit) or a depth of at least 1.
fn max_depth(s: &str) -> Result<i64, String> {
    let d: i64 = number(s)?;
    if d == -1 || (1..u32::MAX as i64).contains(&d) {
        Ok(d)
    } else {
        Err(format!("must be -1 (no limit) or at least 1, got {d}"))
    }
}

/// Seconds: finite, not negative, within a century.
fn seconds(s: &str) -> Result<f64, String> {
    let v: f64 = number(s)?;
    if v.is_finite() && (0.0..=3.2e9).contains(&v) {
        Ok(v)
    } else {
        Err(format!("expects seconds (0 or more), got {s}"))
    }
}

fn positive_seconds(s: &str) -> Result<f64, String> {
    let v = seconds(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be above 0 seconds, got {v}"))
    }
}

fn relative_error(s: &str) -> Result<f64, String> {
    let e: f64 = number(s)?;
    if e.is_finite() && e > 0.0 {
        Ok(e)
    } else {
        Err(format!(
            "must be a relative error above 0 (e.g. 0.02), got {e}"
        ))
    }
}

fn positive(s: &str) -> Result<f32, String> {
    let v: f32 = number(s)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a positive number, got {v}"))
    }
}

fn non_negative(s: &str) -> Result<f32, String> {
    let v: f32 = number(s)?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("must be a non-negative number, got {v}"))
    }
}

fn finite(s: &str) -> Result<f32, String> {
    let v: f32 = number(s)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be a number of degrees, got {v}"))
    }
}

fn blades(s: &str) -> Result<u32, String> {
    let n: u32 = number(s)?;
    if n == 0 || (3..=64).contains(&n) {
        Ok(n)
    } else {
        Err(format!("must be 0 (a round aperture) or 3 to 64, got {n}"))
    }
}

fn rgb(s: &str) -> Result<glam::Vec3, String> {
    let parts: Vec<Option<f32>> = s
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
        _ => Err(format!(
            "expects R,G,B: three non-negative numbers, got '{s}'"
        )),
    }
}

fn alpha(s: &str) -> Result<f64, String> {
    let a: f64 = number(s)?;
    if a > 0.0 && a < 1.0 {
        Ok(a)
    } else {
        Err(format!("must be in (0, 1), got {a}"))
    }
}

/// `A..B`: sample indices A <= i < B, A < B, B at most 2^24.
fn sample_range(s: &str) -> Result<std::ops::Range<u32>, String> {
    let bad =
        || format!("expects A..B, sample indices from A up to B excluded (e.g. 0..256), got '{s}'");
    let range = vkpt::image::header::parse_range(s).ok_or_else(bad)?;
    if range.is_empty() {
        return Err(format!("'{s}' is empty: A must be below B"));
    }
    if range.end > MAX_SAMPLES {
        return Err(format!(
            "ends at {}, above the {MAX_SAMPLES} samples a film counts exactly",
            range.end
        ));
    }
    Ok(range)
}

/// `A..B`, frame numbers from A up to B excluded, non-empty.
fn frame_range(s: &str) -> Result<std::ops::Range<u32>, String> {
    let range = vkpt::image::header::parse_range(s).ok_or_else(|| {
        format!("expects A..B, frames from A up to B excluded (e.g. 0..24), got '{s}'")
    })?;
    if range.is_empty() {
        return Err(format!("'{s}' is empty: A must be below B"));
    }
    Ok(range)
}

/// A finite number of seconds (negative allowed: before the animations
/// start, the first pose holds).
fn time_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = number(s)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be a finite number of seconds, got {v}"))
    }
}

fn positive_f64(s: &str) -> Result<f64, String> {
    let v: f64 = number(s)?;
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(format!("must be above 0, got {v}"))
    }
}

/// `X0,Y0,X1,Y1`, non-empty (checked against the image size later).
fn region(s: &str) -> Result<Region, String> {
    let r = Region::parse(s).ok_or_else(|| {
        format!(
            "expects X0,Y0,X1,Y1: pixel bounds, X1 and Y1 excluded (e.g. 0,0,256,128), got '{s}'"
        )
    })?;
    if r.x0 >= r.x1 || r.y0 >= r.y1 {
        return Err(format!("'{s}' is empty: it needs X0 < X1 and Y0 < Y1"));
    }
    Ok(r)
}

/// The most samples a film counts exactly (`RenderSettings::validate`).
pub const MAX_SAMPLES: u32 = vkpt::packed::settings::MAX_SAMPLES;

fn device(s: &str) -> Result<DeviceChoice, String> {
    DeviceChoice::from_name(s.trim())
        .ok_or_else(|| format!("'{s}' is not one of {}", DeviceChoice::NAMES.join(", ")))
}

fn named<T: Clone + Send + Sync + 'static>(
    names: &'static [&'static str],
    from_name: fn(&str) -> Option<T>,
) -> impl clap::builder::TypedValueParser<Value = T> {
    PossibleValuesParser::new(names).map(move |name| {
        from_name(&name).expect("clap admits only the listed names, and each one parses")
    })
}

/// The image and its paths, as rendering and `vkpt bench` both take them.
#[derive(Args, Debug)]
pub struct FrameArgs {
    /// Image width in pixels [default: 512; 256 for vkpt bench]
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub width: Option<u32>,
    /// Image height [default: width / the camera's aspect ratio]
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub height: Option<u32>,
    /// Longest path kept, counted in segments from the camera: 1 = emitters
    /// seen directly, 2 = direct lighting, 3 = one indirect bounce, ...;
    /// -1 = no limit (Russian roulette ends paths without bias).
    #[arg(long, value_name = "N", default_value_t = -1, allow_negative_numbers = true,
          value_parser = max_depth)]
    pub max_depth: i64,
    /// Random numbers: sobol (Owen-scrambled Sobol, padded per dimension:
    /// lower error at equal spp) or independent (Mitsuba's default sampler
    /// draws independent numbers).
    #[arg(long, value_name = "S", default_value = "sobol",
          value_parser = named(&Sampler::NAMES, Sampler::from_name))]
    pub sampler: Sampler,
    /// Texture filtering of minified textures: mip (trilinear between the
    /// mip levels a pixel's footprint spans, found from a cone through the
    /// pixel; less noise and aliasing at few samples per pixel) or bilinear
    /// (the full-resolution image only: what many samples per pixel
    /// average to without the mip levels' blur).
    #[arg(long, value_name = "F", default_value = "mip",
          value_parser = named(&TextureFilter::NAMES, TextureFilter::from_name))]
    pub texture_filter: TextureFilter,
}

/// Rendering one scene.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// The scene: a glTF 2.0 file (.gltf or .glb).
    #[arg(value_name = "SCENE")]
    pub scene: Option<PathBuf>,

    /// Image to write: .exr (linear RGB plus a variance layer: the variance
    /// of each pixel's mean) or .png (exposed, tone-mapped, sRGB). Written to a
    /// temporary name and renamed, never half-written [default: the scene's
    /// name with .png]
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Samples per pixel [default: 64, or unbounded with --time-limit or
    /// --target-error]
    #[arg(long, value_name = "N", value_parser = at_least_one)]
    pub spp: Option<u32>,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Random seed; renders with different seeds are independent.
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = number::<u32>)]
    pub seed: u32,
    /// Camera by name or index (in glTF node order) [default: 0]
    #[arg(long, value_name = "NAME|N")]
    pub camera: Option<String>,
    /// Material variant (KHR_materials_variants) by name or index
    /// [default: the file's default materials]
    #[arg(long, value_name = "NAME|N")]
    pub variant: Option<String>,
    /// auto | on | off: keep a mesh that the file places more than once
    /// (several nodes, or EXT_mesh_gpu_instancing) once, and trace it
    /// through a two-level BVH. auto does where the copies would add over
    /// 100,000 triangles; off copies every placement (one level).
    #[arg(long, value_name = "M", value_enum, default_value_t = Instancing::Auto)]
    pub instancing: Instancing,
    /// auto | power | bvh: how each shading point picks the light it
    /// samples. power: in proportion to each light's power; bvh: by a
    /// light BVH, in proportion to a bound on each light's contribution
    /// there (power over distance squared, within its cone of emission).
    /// auto takes bvh for scenes with 8 emitters or more (emissive
    /// triangles, spheres, point and spot lights) that do not move during
    /// the shutter.
    #[arg(long, value_name = "S", value_enum, default_value_t = LightSamplerArg::Auto)]
    pub light_sampler: LightSamplerArg,
    /// auto | gpu | lavapipe | cpu. auto takes a GPU when there is one;
    /// without one it races lavapipe (a Vulkan driver on the CPU) against the
    /// CPU back end on a small render of the scene, once per machine and kind
    /// of scene (cached), and renders with the faster; cpu is the CPU back
    /// end (no Vulkan). lavapipe runs as one device per core
    /// (VKPT_LAVAPIPE_DEVICES=N sets how many).
    #[arg(long, value_name = "D", default_value = "auto", value_parser = device)]
    pub device: DeviceChoice,
    /// How a Vulkan device traces paths: wavefront (a kernel per stage of a
    /// bounce, paths queued between them: what a GPU needs) or loop (one
    /// kernel runs each path to its end, with its state in registers). Both
    /// trace the same paths and give the same pixels. [default: wavefront]
    #[arg(long, value_name = "S", value_parser = named(&Schedule::NAMES, Schedule::from_name))]
    pub schedule: Option<Schedule>,

    #[command(flatten)]
    pub light: LightArgs,
    #[command(flatten)]
    pub image: ImageArgs,
    #[command(flatten)]
    pub sensor: SensorArgs,
    #[command(flatten)]
    pub camera_overrides: CameraArgs,
    #[command(flatten)]
    pub progressive: ProgressiveArgs,
    #[command(flatten)]
    pub split: SplitArgs,
    #[command(flatten)]
    pub animation: AnimationArgs,

    /// Print the time spent in each kernel (Vulkan devices).
    #[arg(long, help_heading = "Other")]
    pub timings: bool,
    /// Read buffers and images that the scene's URIs place outside its folder
    /// (absolute paths, '..', symbolic links leading out); refused by default.
    #[arg(long, help_heading = "Other")]
    pub allow_outside_uris: bool,
    /// No progress bar.
    #[arg(short, long, help_heading = "Other")]
    pub quiet: bool,
}

/// Animation: the instant rendered, or a sequence of frames.
#[derive(Args, Debug, Default)]
#[command(next_help_heading = "Animation")]
pub struct AnimationArgs {
    /// The instant to render, in seconds: every animation that plays is
    /// sampled there (before its first keyframe it holds its first pose,
    /// after its last its last one; no looping). A file without animations
    /// looks the same at every time. With --frames: the time of frame 0.
    #[arg(long, value_name = "T", default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = time_seconds)]
    pub time: f64,
    /// The animation that plays, by name or index [default: all of them,
    /// as glTF viewers play them]
    #[arg(long, value_name = "NAME|N")]
    pub animation: Option<String>,
    /// Render frames A to B-1 (frame n at --time + n / --fps) into the
    /// files -o names with a %04d-style pattern (e.g. out_%04d.png),
    /// keeping the device, pipelines and kernels between frames.
    #[arg(long, value_name = "A..B", value_parser = frame_range)]
    pub frames: Option<std::ops::Range<u32>>,
    /// Frames per second of --frames.
    #[arg(long, value_name = "F", default_value_t = 24.0, value_parser = positive_f64)]
    pub fps: f64,
    /// How a shutter blurs motion: per-path (every path at its own time in
    /// the kernels, the scene interpolated between time steps; falls back to
    /// time-steps, with a note saying why, where lights move, a lens or the
    /// triangles change, linear steps cannot follow the motion, or the steps
    /// exceed the buffer budget) or time-steps (sample ranges rendered with the
    /// scene posed on the host at stratified times: exact poses, but at low
    /// spp ghost copies instead of noise, and all of --spp at once).
    #[arg(long, value_name = "M", value_enum, default_value_t = MotionBlur::PerPath)]
    pub motion_blur: MotionBlur,
}

/// `--instancing`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Instancing {
    #[default]
    Auto,
    On,
    Off,
}

impl Instancing {
    pub fn mode(self) -> vkpt::scene::InstancingMode {
        match self {
            Instancing::Auto => vkpt::scene::InstancingMode::Auto,
            Instancing::On => vkpt::scene::InstancingMode::On,
            Instancing::Off => vkpt::scene::InstancingMode::Off,
        }
    }
}

/// `--light-sampler`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum LightSamplerArg {
    #[default]
    Auto,
    Power,
    Bvh,
}

impl LightSamplerArg {
    pub fn mode(self) -> vkpt::scene::LightSampler {
        match self {
            LightSamplerArg::Auto => vkpt::scene::LightSampler::Auto,
            LightSamplerArg::Power => vkpt::scene::LightSampler::Power,
            LightSamplerArg::Bvh => vkpt::scene::LightSampler::Bvh,
        }
    }
}

/// `--motion-blur`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum MotionBlur {
    #[default]
    PerPath,
    TimeSteps,
}

/// Lighting: the environment.
#[derive(Args, Debug, Default)]
#[command(next_help_heading = "Lighting")]
pub struct LightArgs {
    /// Light the scene with an equirectangular environment map (.exr or .hdr;
    /// row 0 is straight up (+Y), the centre faces -Z), importance sampled;
    /// replaces the scene's environment.
    #[arg(long, value_name = "FILE")]
    pub env: Option<PathBuf>,
    /// Rotate the environment map about +Y, in degrees [default: 0]
    #[arg(long, value_name = "DEG", allow_negative_numbers = true, value_parser = finite)]
    pub env_rotation: Option<f32>,
    /// Scale the environment's radiance (map or uniform) [default: 1]
    #[arg(long, value_name = "X", allow_negative_numbers = true, value_parser = non_negative)]
    pub env_intensity: Option<f32>,
    /// A uniform environment of this radiance (the ambient light); replaces
    /// the scene's environment; 0,0,0 for none.
    #[arg(long, value_name = "R,G,B", allow_hyphen_values = true, value_parser = rgb)]
    pub background: Option<glam::Vec3>,
    /// Camera rays that leave the scene see black; the environment still
    /// lights the scene.
    #[arg(long)]
    pub hide_env: bool,
}

/// The PNG's exposure and tone map; denoising.
#[derive(Args, Debug)]
#[command(next_help_heading = "Image")]
pub struct ImageArgs {
    /// PNG exposure compensation in stops: radiance is multiplied by 2^EV (on
    /// top of --shutter/--iso when given).
    #[arg(long, value_name = "EV", default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = number::<f32>)]
    pub exposure: f32,
    /// PNG tone map: neutral (Khronos PBR Neutral), aces, clamp.
    #[arg(long, value_name = "T", default_value = "neutral",
          value_parser = named(ToneMap::NAMES, ToneMap::from_name))]
    pub tonemap: ToneMap,
    /// Auxiliary outputs, added to the EXR as layers (any of, comma-separated):
    /// albedo (albedo.R/G/B: the reflectance of the first surface that is not
    /// a mirror or smooth glass, textures applied), normal (normal.X/Y/Z: its
    /// world-space shading normal), depth (depth.Z: distance along the camera
    /// ray; +inf where no sample hits anything). Each the mean over the
    /// pixel's samples; rays escaping on the way see the environment (albedo:
    /// its radiance up to 1, normal 0).
    #[arg(long, value_name = "LIST", value_delimiter = ',',
          value_parser = PossibleValuesParser::new(AOV_NAMES))]
    pub aov: Vec<String>,
    /// Denoise with Intel Open Image Denoise 2.x (its HDR "RT" filter, guided
    /// by the render's albedo and normal, recorded for it), the final image
    /// and every checkpoint. The EXR keeps the raw render in R, G,
    /// B (with its variance) and adds the denoised image as denoised.R/G/B;
    /// the PNG shows the denoised image. A denoised image is biased: compare,
    /// merge and measure raw renders. Needs libOpenImageDenoise.so.2 (see
    /// VKPT_OIDN_LIB below), checked before rendering.
    #[arg(long)]
    pub denoise: bool,
}

/// The camera sensor the finished image passes through (`vkpt::image::sensor`).
#[derive(Args, Debug)]
#[command(next_help_heading = "Sensor")]
pub struct SensorArgs {
    /// ideal: RGB film, every pixel sees every colour (the render as it is).
    /// bayer: the linear image is sampled through an RGGB colour filter
    /// array (R at even x and y, B at odd x and y, G elsewhere), exposed to
    /// electrons (exposure as the PNG's: an exposed value of 1 fills the
    /// 10,000 e- well, mid-grey fills 18%), given Poisson shot noise and
    /// 3 e- RMS read noise, clipped at full well, quantised to --sensor-bits,
    /// scaled back to radiance and demosaiced. The EXR then holds the
    /// demosaiced image without its variance and samples channels: it is
    /// not for vkpt compare or merge.
    #[arg(long, value_name = "S", default_value = "ideal",
          value_parser = PossibleValuesParser::new(["ideal", "bayer"]))]
    pub sensor: String,
    /// ADC bit depth of --sensor bayer (1 to 16): full well is 2^N - 1 ADU.
    #[arg(long, value_name = "N", default_value_t = vkpt::image::sensor::DEFAULT_BITS,
          value_parser = clap::value_parser!(u32).range(1..=16))]
    pub sensor_bits: u32,
    /// on: shot and read noise, seeded from --seed (the same render and seed
    /// give the same noise); off: a noiseless mosaic, still clipped and
    /// quantised.
    #[arg(long, value_name = "on|off", default_value = "on",
          value_parser = PossibleValuesParser::new(["on", "off"]))]
    pub sensor_noise: String,
    /// Demosaicing of --sensor bayer: bilinear (average of the nearest
    /// photosites of each missing colour) or mhc (Malvar, He and Cutler
    /// 2004: bilinear corrected by the photosite's own colour's Laplacian,
    /// 5x5 filters, sharper edges). Borders are mirrored.
    #[arg(long, value_name = "M", default_value = "mhc",
          value_parser = named(Demosaic::NAMES, Demosaic::from_name))]
    pub demosaic: Demosaic,
    /// Also write the raw mosaic of --sensor bayer, one value per photosite:
    /// .exr (one f32 channel Y, in ADU) or .png (16-bit grey, linear,
    /// ADU * 65535 / (2^N - 1)).
    #[arg(long, value_name = "FILE")]
    pub raw_mosaic: Option<PathBuf>,
}

impl SensorArgs {
    pub fn is_bayer(&self) -> bool {
        self.sensor == "bayer"
    }
}

/// The names `--aov` takes.
pub const AOV_NAMES: [&str; 3] = ["albedo", "normal", "depth"];

/// Overrides of the glTF camera's vkpt extras (lengths in scene units).
#[derive(Args, Debug, Default)]
#[command(
    next_help_heading = "Camera (overrides the glTF camera's vkpt extras; lengths in scene units, metres)"
)]
pub struct CameraArgs {
    /// f-number; the aperture diameter is focal length / N. 0 = pinhole.
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = non_negative)]
    pub fstop: Option<f32>,
    /// Distance of the plane in focus along the view axis.
    #[arg(long, value_name = "D", allow_negative_numbers = true, value_parser = positive)]
    pub focus_distance: Option<f32>,
    /// Focal length (0.05 = 50 mm). Sets the aperture only: the field of view
    /// stays the glTF yfov [default: the extras', else from yfov and a 24 mm
    /// sensor height]
    #[arg(long, value_name = "F", allow_negative_numbers = true, value_parser = positive)]
    pub focal_length: Option<f32>,
    /// Aperture blades: 0 = round, 3..64 = regular polygon (N-gon bokeh).
    #[arg(long, value_name = "N", value_parser = blades)]
    pub blades: Option<u32>,
    /// Angle of the first polygon vertex from the camera's right axis, in
    /// degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true, value_parser = finite)]
    pub blade_rotation: Option<f32>,
    /// Pixel filter, importance sampled (every sample has weight 1): box
    /// (radius 0.5), tent (1), gaussian (1.5, sigma = radius / 3),
    /// blackman-harris (2) [default: box]
    #[arg(long, value_name = "F", value_parser = named(&FilterKind::NAMES, FilterKind::from_name))]
    pub filter: Option<FilterKind>,
    /// Filter radius in pixels [default: per filter, above]
    #[arg(long, value_name = "R", allow_negative_numbers = true, value_parser = positive)]
    pub filter_radius: Option<f32>,
    /// Shutter time in seconds, opening at --time: whatever the animations
    /// move while it is open is motion-blurred, every path at its own time.
    /// With the f-number and --iso it also sets the PNG exposure by the EV100
    /// convention: radiance is scaled by 1 / (1.2 * 2^EV100), EV100 =
    /// log2(N^2 / T) - log2(ISO / 100) (needs an f-number above 0) [default:
    /// the camera's extras]
    #[arg(long, value_name = "T", allow_negative_numbers = true, value_parser = positive)]
    pub shutter: Option<f32>,
    /// ISO sensitivity for --shutter [default: the camera's, else 100]
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = positive)]
    pub iso: Option<f32>,
}

/// When to stop and when to write the image so far.
#[derive(Args, Debug)]
#[command(next_help_heading = "Progressive rendering")]
pub struct ProgressiveArgs {
    /// Stop at the last pass that ends within S seconds.
    #[arg(long, value_name = "S", allow_negative_numbers = true, value_parser = positive_seconds)]
    pub time_limit: Option<f64>,
    /// Stop once the estimated relative error (from the per-pixel variance;
    /// with sobol usually an overestimate) is at most E, e.g. 0.02. With
    /// either stopping rule and no --spp, spp is unbounded (16777216).
    #[arg(long, value_name = "E", allow_negative_numbers = true, value_parser = relative_error)]
    pub target_error: Option<f64>,
    /// Write the image so far every S seconds during the render (0: never).
    #[arg(long, value_name = "S", default_value_t = 60.0, allow_negative_numbers = true,
          value_parser = seconds)]
    pub checkpoint: f64,
}

/// One part of a render split over processes or machines (vkpt merge
/// joins the parts).
#[derive(Args, Debug, Default)]
#[command(next_help_heading = "Splitting a render (vkpt merge joins the parts; write .exr)")]
pub struct SplitArgs {
    /// Render only sample indices A <= i < B of every pixel: the very
    /// samples a render of 0..B takes, so parts with disjoint ranges merge
    /// into it exactly. Also resumes a stopped render (its EXR says where
    /// it stopped). Replaces --spp.
    #[arg(long, value_name = "A..B", value_parser = sample_range, conflicts_with = "spp")]
    pub samples: Option<std::ops::Range<u32>>,
    /// Render only this rectangle of the image, in pixels (X1, Y1 excluded,
    /// y = 0 at the top), with the full image's camera: the EXR holds the
    /// rectangle in place (its data window).
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = region)]
    pub region: Option<Region>,
}

/// `vkpt merge PART.exr... -o OUT.exr`.
#[derive(Args, Debug)]
#[command(long_about = "\
Combines parts of one render into the image a single render would have made:
parts with disjoint sample ranges (--samples) are averaged weighted by their
sample counts, with the variance of all samples; parts with disjoint regions
(--region) are put in place. Parts may be both.

The parts' headers must agree on the scene's content, image size, seed,
sampler, filter, depth, camera and vkpt version; sample ranges may not overlap
or leave gaps, and regions may not overlap and must cover the image (unless
--allow-holes). Anything else is refused with one line, and nothing is
written. The output is written to a temporary name and renamed.")]
pub struct MergeArgs {
    /// The parts (EXR files written by vkpt).
    #[arg(required = true, value_name = "PART.exr")]
    pub parts: Vec<PathBuf>,
    /// The merged image (.exr).
    #[arg(short, long, value_name = "OUT.exr")]
    pub output: PathBuf,
    /// Leave pixels no part covers black (no samples) instead of refusing.
    #[arg(long)]
    pub allow_holes: bool,
    /// Refuse unless the parts hold exactly these samples (A..B), so a
    /// missing last part is noticed.
    #[arg(long, value_name = "A..B", value_parser = sample_range)]
    pub samples: Option<std::ops::Range<u32>>,
}

/// `vkpt compare A.exr B.exr`.
#[derive(Args, Debug)]
#[command(long_about = "\
Tests whether two renders have the same expectation: z-tests per pixel, on 4x4
and 16x16 blocks and on the whole image, with Sidak (within a level) and
Bonferroni (across levels) corrections at the given family-wise alpha.

First prints error metrics of A against B (mean, bias and RMSE per channel,
relMSE, the 16x16 block deviating most); exits 0 when they agree, 1 when they
do not, 2 on bad input. Render them with different --seed.

When a file has no variance layer (an EXR from another renderer) the noise is
estimated from the images: a - b has expectation 0 in every pixel when they
agree, so its spread within 4x4 cells measures the noise (Student t, with the
correlation between neighbouring pixels' noise measured and allowed for); the
4x4, 16x16 and whole-image levels are tested, single pixels are not. The
output names the noise model used. This needs no particular sampler, only
pixels whose noise is (nearly) independent beyond 2 pixels.

With variance layers, render both with --sampler independent: the per-pixel
variance assumes independent samples (with sobol it usually overestimates
it, and the test loses power).")]
pub struct CompareArgs {
    /// The first render (EXR).
    pub a: PathBuf,
    /// The second render (EXR).
    pub b: PathBuf,
    /// Family-wise significance level of the z-tests.
    #[arg(long, default_value_t = 0.01, value_parser = alpha)]
    pub alpha: f64,
    /// Also require relMSE of A against B at most T (an extra criterion,
    /// on top of the statistical test).
    #[arg(long, value_name = "T", allow_negative_numbers = true, value_parser = non_negative_f64)]
    pub max_rel_mse: Option<f64>,
    /// Instead of the statistical test, require the same numbers: every
    /// channel of every pixel within R * (1 + |b|) and the same sample
    /// counts. For a merged render against one render of the same samples
    /// (float rounding only: 1e-5 is ample).
    #[arg(long, value_name = "R", allow_negative_numbers = true, value_parser = non_negative_f64)]
    pub tolerance: Option<f64>,
}

fn non_negative_f64(s: &str) -> Result<f64, String> {
    let v: f64 = number(s)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("must be at least 0, got {v}"))
    }
}

/// `vkpt bench SCENE...`.
#[derive(Args, Debug)]
#[command(long_about = "\
Renders each scene on each back end at increasing spp (back ends alternate
step by step) and reports, per step, wall time, kernel time (timestamps),
samples/s, rays/s and the relMSE against a converged reference: the mean over
pixels and channels of (x - ref)^2 / (ref^2 + 0.01). Then prints start-up
costs (device, kernel compile, BVH build, scene upload) and the time each back
end needs to reach relMSE 1e-2 and 1e-3 (log-log interpolation between steps).
Writes DIR/bench.csv and a log-log plot DIR/<scene>.svg.")]
pub struct BenchArgs {
    /// Scenes to benchmark (glTF).
    #[arg(required = true, value_name = "SCENE")]
    pub scenes: Vec<PathBuf>,
    /// Back ends, comma-separated: auto, gpu, lavapipe, cpu (auto is skipped
    /// without Vulkan).
    #[arg(long, value_name = "LIST", value_delimiter = ',', default_value = "auto,cpu",
          value_parser = device)]
    pub device: Vec<DeviceChoice>,
    /// Schedules each Vulkan back end runs, comma-separated: wavefront, loop
    /// (the per-path loop, a series of its own: lavapipe+loop).
    #[arg(long, value_name = "LIST", value_delimiter = ',', default_value = "wavefront",
          value_parser = named(&Schedule::NAMES, Schedule::from_name))]
    pub schedule: Vec<Schedule>,
    /// spp of each step, comma-separated and increasing [default:
    /// 1,2,4,...,512]
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_parser = at_least_one)]
    pub spp: Vec<u32>,
    #[command(flatten)]
    pub frame: FrameArgs,
    /// Converged EXR to measure against (one scene only). Default: rendered
    /// once at --reference-spp on the first back end and cached under
    /// $XDG_CACHE_HOME/vkpt (or ~/.cache/vkpt, or $VKPT_CACHE_DIR).
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of a reference rendered here.
    #[arg(long, value_name = "N", default_value_t = 4096, value_parser = at_least_one)]
    pub reference_spp: u32,
    /// Render each step N times (back ends taking turns) and keep the
    /// fastest: on a shared machine other load only adds time.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = at_least_one)]
    pub repeat: u32,
    /// Random seed of the measured renders (not the reference's): renders
    /// with different seeds are independent, so several seeds show how much
    /// a step's relMSE varies (rare bright paths make it heavy-tailed).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u32,
    /// Also denoise every step with Open Image Denoise (guided by albedo and
    /// normal), reported as a series of its own, BACKEND+denoise: wall time
    /// of render plus denoiser, relMSE of the denoised image (biased).
    #[arg(long)]
    pub denoise: bool,
    /// auto | power | bvh: light selection of the measured renders (see
    /// `vkpt render --light-sampler`); the reference is the same image
    /// whichever is chosen.
    #[arg(long, value_name = "S", value_enum, default_value_t = LightSamplerArg::Auto)]
    pub light_sampler: LightSamplerArg,
    /// Folder for bench.csv and the plots.
    #[arg(short, long, value_name = "DIR", default_value = "vkpt-bench")]
    pub output: PathBuf,
}

/// `None` for -1.
pub fn depth_limit(d: i64) -> Option<u32> {
    u32::try_from(d).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_command_line_is_well_formed() {
        Cli::command().debug_assert();
    }

    #[test]
    fn a_scene_renders_and_subcommands_dispatch() {
        let cli = Cli::try_parse_from(["vkpt", "a.gltf", "--spp", "8", "--max-depth", "-1"])
            .expect("parses");
        assert!(cli.command.is_none());
        assert_eq!(cli.render.spp, Some(8));
        assert_eq!(depth_limit(cli.render.frame.max_depth), None);
        let cli = Cli::try_parse_from(["vkpt", "compare", "a.exr", "b.exr"]).expect("parses");
        assert!(matches!(cli.command, Some(Command::Compare(_))));
        let err = Cli::try_parse_from(["vkpt", "a.gltf", "--spp", "many"]).unwrap_err();
        assert!(
            err.to_string().contains("expects a number, got 'many'"),
            "{err}"
        );
    }
}
