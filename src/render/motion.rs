//! Motion blur over the shutter, by time-stratified sample ranges: the
//! samples of a render are split into `steps` consecutive ranges, and range
//! k is rendered with the scene posed on the host at
//!
//!   t_k = open + duration · (k + ξ_k) / steps,   ξ_k uniform in [0, 1)
//!
//! (ξ_k a hash of the seed and k). Every sample's time is then uniform over
//! the shutter, one per stratum, so each pixel's mean is an unbiased,
//! time-stratified estimate of the radiance averaged over the exposure.
//! Whatever the host poses moves: rigid nodes, cameras, lights, emitters
//! (next-event estimation samples them where they are at t_k), skinned and
//! morphed meshes. The kernels are today's, untouched (a scene without
//! motion renders exactly as before, at the same speed), and both back
//! ends render the same sample indices at the same times, so CPU and GPU
//! agree as for any still scene. The price: one pose, BVH build and upload
//! per step (the GPU keeps its buffers and re-uploads only what changed),
//! and at low spp all pixels share the few times (ghost copies, not
//! independent noise), which converges as the steps grow.

use super::{RenderResult, RenderSettings};
use crate::cpu::common::rng::pcg_hash;
use crate::packed::PackedScene;
use crate::scene::Scene;
use std::time::Duration;

/// The most time steps (BVH builds) one render makes.
pub const MAX_TIME_STEPS: u32 = 64;

/// The exposure: it opens at `open` and lasts `duration` seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shutter {
    pub open: f64,
    pub duration: f64,
}

/// How many time steps a render of `spp` samples takes: the largest
/// divisor of `spp` up to [`MAX_TIME_STEPS`], so every step has as many
/// samples (the mean weighs the strata equally).
pub fn time_steps(spp: u32) -> u32 {
    (1..=MAX_TIME_STEPS.min(spp).max(1))
        .rev()
        .find(|d| spp.is_multiple_of(*d))
        .unwrap_or(1)
}

/// The time of step `k` of `steps` (see the module doc).
pub fn step_time(shutter: Shutter, seed: u32, k: u32, steps: u32) -> f64 {
    let bits = pcg_hash(pcg_hash(k ^ 0x6d6f_7469) ^ seed.wrapping_mul(0x9e37_79b9));
    let xi = (bits >> 8) as f64 / 16_777_216.0;
    shutter.open + shutter.duration * (k as f64 + xi) / steps as f64
}

/// What a motion-blurred render measured besides the film.
#[derive(Clone, Copy, Debug, Default)]
pub struct MotionStats {
    pub steps: u32,
    /// Posing the scene on the host (node walk), all steps.
    pub pose_time: Duration,
    /// Building the BVHs (packing), all steps.
    pub bvh_time: Duration,
}

/// Renders `settings` (its samples split over [`time_steps`]) with the
/// scene `pose(time, origin)` returns for each step's time, measured from
/// the origin of the pose at the opening (`scene::motion::pose_over_shutter`
/// says why), through `render` (a back end rendering a sample range); the
/// films are merged.
pub fn render_motion_blur(
    shutter: Shutter,
    settings: &RenderSettings,
    pose: &mut dyn FnMut(f64, Option<glam::DVec3>) -> anyhow::Result<Scene>,
    render: &mut dyn FnMut(&Scene, &PackedScene, &RenderSettings) -> anyhow::Result<RenderResult>,
) -> anyhow::Result<(RenderResult, MotionStats)> {
    let steps = time_steps(settings.spp);
    let per_step = settings.spp / steps;
    let mut stats = MotionStats {
        steps,
        ..MotionStats::default()
    };
    let mut total: Option<RenderResult> = None;
    // A camera vkpt framed on the scene holds still where the shutter opens,
    // as under per-path time (`scene::motion`).
    let start = std::time::Instant::now();
    let opening = pose(shutter.open, None)?;
    stats.pose_time += start.elapsed();
    for k in 0..steps {
        let time = step_time(shutter, settings.seed, k, steps);
        let start = std::time::Instant::now();
        let mut scene = pose(time, Some(opening.world_origin))?;
        for (c, held) in scene.cameras.iter_mut().zip(&opening.cameras) {
            if held.framed_automatically {
                *c = held.clone();
            }
        }
        stats.pose_time += start.elapsed();
        let packed = PackedScene::new(&scene)?;
        stats.bvh_time += packed.bvh_build_time;
        let part = RenderSettings {
            first_sample: settings.first_sample + k * per_step,
            spp: per_step,
            ..settings.clone()
        };
        let result = render(&scene, &packed, &part)?;
        match &mut total {
            None => total = Some(result),
            Some(t) => {
                t.film.merge(&result.film);
                t.spp += result.spp;
                t.render_time += result.render_time;
                t.extension_rays += result.extension_rays;
                t.shadow_rays += result.shadow_rays;
                t.traversal_overflows += result.traversal_overflows;
                t.nonfinite_samples += result.nonfinite_samples;
            }
        }
    }
    let total = total.ok_or_else(|| anyhow::anyhow!("no samples to render"))?;
    Ok((total, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_divide_the_samples() {
        assert_eq!(time_steps(1), 1);
        assert_eq!(time_steps(64), 64);
        assert_eq!(time_steps(256), 64);
        assert_eq!(time_steps(100), 50);
        assert_eq!(time_steps(67), 1);
    }

    #[test]
    fn step_times_are_one_per_stratum_of_the_shutter() {
        let s = Shutter {
            open: 2.0,
            duration: 0.5,
        };
        for k in 0..16 {
            let t = step_time(s, 7, k, 16);
            let lo = 2.0 + 0.5 * k as f64 / 16.0;
            assert!(t >= lo && t < lo + 0.5 / 16.0, "step {k}: {t}");
        }
    }
}
