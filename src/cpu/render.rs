//! The CPU reference's driver: every thread takes whole rows and traces each
//! path to its end, calling the same `shade_path` as the shade kernel.

use super::bvh::{NO_HIT, OVERFLOW_HIT, trace_ray};
use super::camera::generate_camera_ray;
use super::integrator::{PathState, shade_path};
use super::lights::intersect_sphere_lights;
use super::rng::rng_sampler_key;
use crate::constants::LIGHT_HIT_FLAG;
use crate::film::{Film, film_add_sample};
use crate::layout::{FilmPixel, RenderParams};
use crate::packed::PackedScene;
use crate::render::{Progress, RenderResult};
use crate::scene::Scene;
use crate::settings::RenderSettings;
use glam::Vec3;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::time::Instant;

#[derive(Default)]
struct Counts {
    extension_rays: AtomicU64,
    shadow_rays: AtomicU64,
    overflows: AtomicU64,
    nonfinite: AtomicU64,
}

/// Radiance of one path sample, counting rays as the GPU does.
fn trace_path(
    scene: &PackedScene,
    params: &RenderParams,
    pixel: u32,
    sample_index: u32,
    counts: &mut [u64; 3],
) -> Vec3 {
    let key = rng_sampler_key(params.rng_sampler, pixel, sample_index, params.seed);
    let (origin, direction) = generate_camera_ray(params, pixel, key);
    let mut state = PathState {
        origin,
        direction,
        throughput: Vec3::ONE,
        prev_pdf: 0.0,
    };
    let mut radiance = Vec3::ZERO;
    let mut bounce = 0;
    loop {
        counts[0] += 1;
        let mut hit = trace_ray(scene, state.origin, state.direction, f32::MAX, false);
        if hit.triangle == OVERFLOW_HIT {
            counts[2] += 1;
        } else {
            // Spherical lights are not in the BVH: the nearer of the two wins.
            let mut t = if hit.triangle == NO_HIT {
                f32::MAX
            } else {
                hit.t
            };
            let k = intersect_sphere_lights(scene, state.origin, state.direction, &mut t);
            if k != NO_HIT {
                hit.t = t;
                hit.triangle = LIGHT_HIT_FLAG | k;
                hit.b12 = glam::Vec2::ZERO;
            }
        }
        let r = shade_path(scene, params, &state, &hit, key, bounce);
        radiance += r.emitted;
        if r.shadow {
            counts[1] += 1;
            let mut t_max = r.shadow_t_max;
            // A spherical light on the way occludes, like a triangle.
            let sphere =
                intersect_sphere_lights(scene, r.shadow_origin, r.shadow_direction, &mut t_max);
            if sphere == NO_HIT {
                let h = trace_ray(
                    scene,
                    r.shadow_origin,
                    r.shadow_direction,
                    r.shadow_t_max,
                    true,
                );
                if h.triangle == OVERFLOW_HIT {
                    counts[2] += 1;
                } else if h.triangle == NO_HIT {
                    radiance += r.shadow_contribution;
                }
            }
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
    let params = packed.render_params(scene, settings, 0)?;
    let (width, height) = (settings.width, settings.height);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let next_row = AtomicU32::new(0);
    let rows_done = AtomicU64::new(0);
    let counts = Counts::default();
    let total = settings.pixel_count() * settings.spp as u64;
    let start = Instant::now();

    let mut rows: Vec<(u32, Vec<FilmPixel>)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut done = Vec::new();
                    let mut c = [0u64; 3];
                    let mut nonfinite = 0u64;
                    loop {
                        let y = next_row.fetch_add(1, Ordering::Relaxed);
                        if y >= height {
                            break;
                        }
                        let mut row = vec![FilmPixel::default(); width as usize];
                        for (x, film_pixel) in row.iter_mut().enumerate() {
                            let pixel = y * width + x as u32;
                            for sample_index in 0..settings.spp {
                                let l = trace_path(packed, &params, pixel, sample_index, &mut c);
                                if l.is_finite() {
                                    film_add_sample(film_pixel, l.into());
                                } else {
                                    nonfinite += 1;
                                }
                            }
                        }
                        done.push((y, row));
                        let finished = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
                        progress(finished * width as u64 * settings.spp as u64, total);
                    }
                    counts.extension_rays.fetch_add(c[0], Ordering::Relaxed);
                    counts.shadow_rays.fetch_add(c[1], Ordering::Relaxed);
                    counts.overflows.fetch_add(c[2], Ordering::Relaxed);
                    counts.nonfinite.fetch_add(nonfinite, Ordering::Relaxed);
                    done
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().expect("a CPU render thread panicked"))
            .collect()
    });
    rows.sort_by_key(|(y, _)| *y);
    let film = Film {
        width,
        height,
        pixels: rows.into_iter().flat_map(|(_, row)| row).collect(),
    };
    Ok(RenderResult {
        film,
        device_name: format!("CPU reference ({threads} threads)"),
        render_time: start.elapsed(),
        extension_rays: counts.extension_rays.into_inner(),
        shadow_rays: counts.shadow_rays.into_inner(),
        traversal_overflows: counts.overflows.into_inner(),
        nonfinite_samples: counts.nonfinite.into_inner(),
        kernel_variant: None,
        kernel_times: Vec::new(),
    })
}
