//! Which BVH traversal a CPU ray takes: the one place that decides. Every
//! traversal finds the same hit as the kernels' for every ray it is given
//! (the tests in `tests/suite/cpu_lanes.rs` compare them bit for bit); they
//! differ in speed and in the rays they can take.
//!
//! | traversal | where | runs when | why |
//! |---|---|---|---|
//! | the kernels' loop, scalar tests | `common::bvh::trace_ray` | the CPU lacks AVX2 | the twin itself |
//! | the kernels' loop, AVX2 tests | `fast::octant` | AVX2, and the scene moves or some ray could exhaust the work budget or the stack (`order_free` is false) | the same order and work as the kernels, so a ray that overflows there overflows here |
//! | nearest child first, leaf windows | `fast::nearest_first`, `fast::leaf_window` | AVX2, a still scene where no ray can exhaust the budget | the same hits in fewer steps: tight boxes, children in entry order, a node's leaf triangles a register at a time |
//! | packets | `fast::packet` | the lane schedule's rays, where `packets_run` | a register of rays shares each node fetch and test; a thinned-out packet hands its rays to nearest-first |
//! | two levels, scalar or AVX2 tests in the meshes | `common::bvh::trace_instances_with`, through `fast::octant::trace_ray_octant` | a scene with instances (`PackedScene::instances`) | the kernels' order over the instances, each mesh's BVH entered in its own space |
//!
//! Packets run where nearest-first may (`order_free`) and where they pay:
//! eight rays wide (AVX2) up to `PACKETS_MAX_TRIANGLES`, sixteen wide
//! (AVX-512) on any scene (measured: docs/design-record.md).

use super::common::bvh::{Hit, NO_HIT, OVERFLOW_HIT};
use super::common::integrator::ShadeResult;
use super::common::trace::{nearest_with_sphere_lights, sphere_light_blocker};
use super::fast::cache::CpuScene;
use super::fast::packet::Rays;
use super::fast::wide::WIDTH;
use crate::constants::{BVH_MAX_ITERATIONS, BVH_STACK_SIZE};
use crate::packed::PackedScene;
use glam::Vec3;

/// Whether this CPU has the vector instructions the fast traversals are
/// compiled for: AVX2 and the bit instructions that came with it, and
/// AVX-512 where the build selects sixteen lanes (checked once, cached).
pub fn vector_traversals() -> bool {
    super::fast::octant::available()
}

/// Whether no single ray can exhaust the traversal's work budget or its
/// stack in this scene (nodes plus triangles within `BVH_MAX_ITERATIONS`,
/// depth below `BVH_STACK_SIZE`), in a still scene, on a CPU with the
/// vector instructions: then any order finds the kernels' hits. Decided
/// once per scene.
pub fn order_free(scene: &CpuScene) -> bool {
    scene.order_free(|scene| {
        scene.motion.is_none()
            && scene.instances.is_empty()
            && vector_traversals()
            && !scene.nodes.is_empty()
            && scene.nodes.len() + scene.tri_verts.len() <= BVH_MAX_ITERATIONS as usize
            && bvh_depth(scene) < BVH_STACK_SIZE as usize
    })
}

/// The largest scene traced in packets: eight rays wide, between the
/// measured 1,308 and 4,178 triangles (faster at 32 to 1,308 triangles: 0
/// to +13 %; slower at 4,178 to 12,832: -4 to -8 %); sixteen wide, any
/// that fits (-2 % to -14 % CPU time on every bundled scene).
pub const PACKETS_MAX_TRIANGLES: Option<usize> = if WIDTH == 16 { None } else { Some(2048) };

/// Whether the lane schedule traces its rays a packet at a time here.
pub fn packets_run(scene: &CpuScene) -> bool {
    // The size first: it is free, the fit walks the BVH.
    PACKETS_MAX_TRIANGLES.is_none_or(|max| scene.tri_verts.len() <= max) && order_free(scene)
}

/// Levels of inner nodes from the root down (the root alone: 1).
fn bvh_depth(scene: &PackedScene) -> usize {
    let mut deepest = 0;
    let mut pending = vec![(0usize, 1usize)];
    while let Some((node, depth)) = pending.pop() {
        deepest = deepest.max(depth);
        let n = &scene.nodes[node];
        let imask = n.e_imask >> 24;
        for k in 0..imask.count_ones() as usize {
            pending.push((n.child_base_idx as usize + k, depth + 1));
        }
    }
    deepest
}

/// The BVH's hit of one ray (`bvh::trace_ray`'s, by the traversal the table
/// above picks): the closest hit with t in (0, t_max), or with `any_hit`
/// the first found.
pub fn trace_ray(
    scene: &CpuScene,
    o: Vec3,
    d: Vec3,
    t_max: f32,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
) -> Hit {
    let hit = Hit::none(t_max);
    #[cfg(target_arch = "x86_64")]
    if vector_traversals() {
        if order_free(scene) {
            // SAFETY: the CPU has the instructions (checked); `order_free`:
            // a still scene that fits the budget.
            return unsafe {
                super::fast::nearest_first::trace_ray_nearest_first(
                    scene,
                    o,
                    d,
                    any_hit,
                    coverage_seed,
                    0,
                    hit,
                )
            };
        }
        // SAFETY: the CPU has the instructions (checked).
        return unsafe {
            super::fast::octant::trace_ray_octant(scene, o, d, any_hit, coverage_seed, time, hit)
        };
    }
    super::common::bvh::trace_ray(scene, o, d, t_max, any_hit, coverage_seed, time)
}

/// The hits of a packet of rays, each exactly `trace_ray`'s.
///
/// # Safety
/// Only where `packets_run(scene)`.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
pub unsafe fn trace_packet(scene: &CpuScene, rays: &Rays, any_hit: bool) -> [Hit; WIDTH] {
    // SAFETY: the caller's promise (`packets_run` checks the instructions).
    unsafe { super::fast::packet::trace_rays(scene, rays, any_hit) }
}

/// The nearest of the BVH's hit and the spherical lights' (`LIGHT_HIT_FLAG |
/// k`); `OVERFLOW_HIT` when traversal gave up (`trace.glsl`'s
/// `closest_hit`, with this module's choice of traversal).
pub fn closest_hit(scene: &CpuScene, o: Vec3, d: Vec3, coverage_seed: u32, time: f32) -> Hit {
    let hit = trace_ray(scene, o, d, f32::MAX, false, coverage_seed, time);
    nearest_with_sphere_lights(scene, o, d, hit)
}

/// What blocks a shadow ray: `NO_HIT` when nothing does, `OVERFLOW_HIT` when
/// traversal gave up, anything else when a triangle or a spherical light
/// does (`trace.glsl`'s `shadow_blocker`).
pub fn shadow_blocker(
    scene: &CpuScene,
    o: Vec3,
    d: Vec3,
    t_max: f32,
    coverage_seed: u32,
    time: f32,
) -> u32 {
    if let Some(blocker) = sphere_light_blocker(scene, o, d, t_max) {
        return blocker;
    }
    trace_ray(scene, o, d, t_max, true, coverage_seed, time).triangle
}

/// The extension ray of a path, counted as the GPU counts rays (`counts`:
/// extension, shadow, traversal overflows). `seed`: the ray's seed for
/// alpha tests, `rng_coverage_seed(key, bounce, 0)` (the lanes pass 0 where
/// no triangle is alpha-tested, and skip its three hashes).
pub fn extension_hit(
    scene: &CpuScene,
    origin: Vec3,
    direction: Vec3,
    seed: u32,
    time: f32,
    counts: &mut [u64; 3],
) -> Hit {
    counts[0] += 1;
    let hit = closest_hit(scene, origin, direction, seed, time);
    if hit.triangle == OVERFLOW_HIT {
        counts[2] += 1;
    }
    hit
}

/// The shadow ray `r` asks for, if any, counted: its contribution when
/// nothing blocks it. `seed`: the ray's seed for alpha tests,
/// `rng_coverage_seed(key, bounce, 1)` (or 0, as for `extension_hit`).
pub fn shadow_ray_reaches(
    scene: &CpuScene,
    r: &ShadeResult,
    seed: u32,
    time: f32,
    counts: &mut [u64; 3],
) -> Option<Vec3> {
    let reaches = r.shadow
        && shadow_ray_unblocked(
            scene,
            (r.shadow_origin, r.shadow_direction, r.shadow_t_max),
            seed,
            time,
            counts,
        );
    reaches.then_some(r.shadow_contribution)
}

/// Whether nothing blocks the shadow ray (origin, direction, t_max),
/// counted (a shadow ray, and an overflow, which counts as blocked).
pub fn shadow_ray_unblocked(
    scene: &CpuScene,
    (origin, direction, t_max): (Vec3, Vec3, f32),
    seed: u32,
    time: f32,
    counts: &mut [u64; 3],
) -> bool {
    counts[1] += 1;
    match shadow_blocker(scene, origin, direction, t_max, seed, time) {
        OVERFLOW_HIT => {
            counts[2] += 1;
            false
        }
        blocker => blocker == NO_HIT,
    }
}
