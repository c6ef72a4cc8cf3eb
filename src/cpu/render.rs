//! The CPU back end's driver: in passes of whole samples per pixel,
//! rayon's threads take whole rows and trace each path to its end, calling
//! the same `shade_path` as the shade kernel; in static scenes
//! (`lanes::lanes_cover`) a row's paths run a register side by side (the
//! lane schedule, `fast::lanes`), with the same pixels.

use super::common::aov::{AovSample, aov_after_bounce};
use super::common::camera::{generate_camera_ray, path_pixel_sample};
use super::common::integrator::{PathState, shade_path};
use super::common::motion::time_of_path;
use super::common::rng::{rng_coverage_seed, rng_sampler_key};
use super::fast::cache::CpuScene;
use super::fast::lanes::{LaneOptions, PathBatch, lanes_cover, trace_paths};
use super::traversal::{extension_hit, shadow_ray_reaches};
use crate::film::passes::{PassControl, Progress, RenderAll, RenderResult, pass_spp};
use crate::film::{Film, aov_add_sample, film_add_sample};
use crate::packed::PackedScene;
use crate::packed::layout::AovPixel;
use crate::packed::layout::RenderParams;
use crate::packed::settings::RenderSettings;
use crate::scene::Scene;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Radiance of one path sample, counting rays as the GPU does, and its
/// auxiliary outputs when `params.aov` asks for them.
fn trace_path(
    scene: &CpuScene,
    params: &RenderParams,
    pixel: u32,
    sample_index: u32,
    counts: &mut [u64; 3],
    aov: &mut AovSample,
) -> Vec3 {
    let key = rng_sampler_key(params.rng_sampler, pixel, sample_index, params.seed);
    let (origin, direction) = generate_camera_ray(scene, params, pixel, key);
    let time = time_of_path(scene, key);
    let mut state = PathState::camera(origin, direction);
    let mut radiance = Vec3::ZERO;
    let mut bounce = 0;
    loop {
        let seed = rng_coverage_seed(key, bounce, 0);
        let hit = extension_hit(scene, state.origin, state.direction, seed, time, counts);
        let r = shade_path(scene, params, &state, &hit, key, bounce);
        if params.aov != 0 {
            aov_after_bounce(aov, bounce, &hit, &r);
        }
        radiance += r.emitted;
        let seed = rng_coverage_seed(key, bounce, 1);
        if let Some(c) = shadow_ray_reaches(scene, &r, seed, time, counts) {
            radiance += c;
        }
        if !r.next {
            return radiance;
        }
        state = r.next_state;
        bounce += 1;
    }
}

pub fn render(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    progress: Progress,
) -> anyhow::Result<RenderResult> {
    render_progressive(scene, packed, settings, progress, &mut RenderAll)
}

/// The back end's name in summaries and headers.
pub fn device_name() -> String {
    format!("CPU back end ({} threads)", rayon::current_num_threads())
}

/// Paths of the first pass: enough that starting the threads costs nothing.
const PASS_PATHS: u64 = 1 << 14;

/// Passes shorter than this double (where the control allows it), so they
/// settle between 50 and 100 ms: each pass ends with the threads finishing
/// their last rows and meeting, and at 1 spp per pass (16 ms) the 256x256
/// Cornell box lost about 3 % to those ends.
const PASS_GROW_BELOW: Duration = Duration::from_millis(50);

/// Renders in passes of whole samples per pixel (`PassControl`); within a
/// pass every thread takes whole rows.
pub fn render_progressive(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    progress: Progress,
    control: &mut dyn PassControl,
) -> anyhow::Result<RenderResult> {
    render_with(
        scene,
        packed,
        settings,
        progress,
        control,
        CpuSchedule::Lanes,
    )
}

/// How the CPU back end runs its paths: both give the same bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CpuSchedule {
    /// A register of paths side by side (`lanes`) where the scene allows
    /// it, their rays traced in packets where that pays (`LaneOptions`).
    Lanes,
    /// One path at a time, always (`trace_path`).
    OnePath,
}

/// `render_progressive` with the schedule chosen (tests compare the two).
pub fn render_with(
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    progress: Progress,
    control: &mut dyn PassControl,
    schedule: CpuSchedule,
) -> anyhow::Result<RenderResult> {
    // The CPU's own copies of the scene, built as the traversals ask.
    render_on(
        scene,
        &CpuScene::new(packed),
        settings,
        progress,
        control,
        schedule,
    )
}

/// `render_with` on a `CpuScene` whose copies earlier renders may have
/// built (`--device auto` times renders of a scene without them).
pub fn render_on(
    scene: &Scene,
    packed: &CpuScene,
    settings: &RenderSettings,
    progress: Progress,
    control: &mut dyn PassControl,
    schedule: CpuSchedule,
) -> anyhow::Result<RenderResult> {
    let params = packed.render_params(scene, settings, 0)?;
    let lanes = schedule == CpuSchedule::Lanes && lanes_cover(packed);
    let lane_options = LaneOptions::for_scene(packed, &params);
    // The film covers the region; rows are the region's.
    let region = settings.film_region();
    let width = region.width();
    // Extension rays, shadow rays, traversal overflows, non-finite samples.
    let mut counts = [0u64; 4];
    let pixels = settings.pixel_count();
    let total = pixels * settings.spp as u64;
    let mut pass = pass_spp(pixels, PASS_PATHS);
    progress(0, total);
    let start = Instant::now();
    let mut film = if params.aov != 0 {
        Film::with_aov(width, region.height())
    } else {
        Film::new(width, region.height())
    };
    let mut spp = 0u32;

    while spp < settings.spp {
        let pass_start = Instant::now();
        let samples = spp..(spp + pass).min(settings.spp);
        let rows_done = AtomicU64::new(0);
        let done_before = pixels * spp as u64;
        let row_samples = width as u64 * samples.len() as u64;
        let aov_film = &film.aov;
        // Per row: extension rays, shadow rays, overflows, non-finite
        // samples, and the row's auxiliary outputs (when recorded).
        // A row per job (`with_max_len(1)`): rayon otherwise splits a pass
        // into a few runs of rows that cannot be split further once begun,
        // and a thread that ended its runs waited for the other's to end
        // (3 % of the Cornell box's core time).
        let rows: Vec<([u64; 4], Vec<AovPixel>)> = film
            .pixels
            .par_chunks_mut(width as usize)
            .with_max_len(1)
            .enumerate()
            .map(|(y, row)| {
                let mut rays = [0u64; 3];
                let mut nonfinite = 0;
                let w = width as usize;
                let mut aov_row = aov_film.get(y * w..(y + 1) * w).unwrap_or(&[]).to_vec();
                // The row's paths, pixel by pixel, each pixel's samples in order.
                let pixel_of = |x: usize| y as u32 * width + x as u32;
                // A pixel's samples differ only in their index, which
                // grows with the sample (`path_pixel_sample`'s divisions
                // once per pixel; plain loops: a flat_map was 1.5 % of
                // cornell-spheres).
                let mut paths: Vec<(u32, u32)> = Vec::with_capacity(w * samples.len());
                for x in 0..w {
                    let first = path_pixel_sample(&params, pixel_of(x), samples.start, 0);
                    for s in 0..samples.len() as u32 {
                        paths.push((first.pixel, first.sample_index + s));
                    }
                }
                let mut radiance = vec![Vec3::ZERO; paths.len()];
                let aov_paths = if aov_row.is_empty() { 0 } else { paths.len() };
                let mut aovs = vec![AovSample::default(); aov_paths];
                if lanes {
                    let mut batch = PathBatch {
                        paths: &paths,
                        radiance: &mut radiance,
                        aovs: &mut aovs,
                        counts: &mut rays,
                    };
                    trace_paths(packed, &params, &lane_options, &mut batch);
                } else {
                    for (i, &(pixel, sample_index)) in paths.iter().enumerate() {
                        let mut aov = AovSample::default();
                        radiance[i] =
                            trace_path(packed, &params, pixel, sample_index, &mut rays, &mut aov);
                        if let Some(a) = aovs.get_mut(i) {
                            *a = aov;
                        }
                    }
                }
                // The film adds each pixel's samples in order.
                let per_pixel = samples.len();
                for (x, (film_pixel, l)) in
                    row.iter_mut().zip(radiance.chunks(per_pixel)).enumerate()
                {
                    for l in l {
                        if l.is_finite() {
                            film_add_sample(film_pixel, (*l).into());
                        } else {
                            nonfinite += 1;
                        }
                    }
                    if let Some(a) = aov_row.get_mut(x) {
                        for s in &aovs[x * per_pixel..(x + 1) * per_pixel] {
                            aov_add_sample(a, s.albedo.into(), s.normal.into(), s.depth);
                        }
                    }
                }
                let finished = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
                progress(done_before + finished * row_samples, total);
                ([rays[0], rays[1], rays[2], nonfinite], aov_row)
            })
            .collect();
        for (y, (row_counts, aov_row)) in rows.into_iter().enumerate() {
            for (sum, n) in counts.iter_mut().zip(row_counts) {
                *sum += n;
            }
            let w = width as usize;
            if !aov_row.is_empty() {
                film.aov[y * w..(y + 1) * w].copy_from_slice(&aov_row);
            }
        }
        spp = samples.end;
        if control.passes_may_grow() && pass_start.elapsed() < PASS_GROW_BELOW {
            pass = pass.saturating_mul(2);
        }
        if spp < settings.spp && !control.after_pass(spp, &mut || Ok(film.clone()))? {
            break;
        }
    }
    Ok(RenderResult {
        film,
        spp,
        // Which schedule traced the paths (the same pixels either way).
        device_name: if lanes {
            format!(
                "CPU back end ({} threads, {} paths side by side{})",
                rayon::current_num_threads(),
                super::fast::wide::WIDTH,
                if lane_options.packets() {
                    ", their rays in packets"
                } else {
                    ""
                }
            )
        } else {
            device_name()
        },
        render_time: start.elapsed(),
        extension_rays: counts[0],
        shadow_rays: counts[1],
        traversal_overflows: counts[2],
        nonfinite_samples: counts[3],
        paths_parked: 0,
        kernel_variant: None,
        kernel_times: Vec::new(),
    })
}
