//! A single ray through the BVH nearest child first, for the CPU back end
//! where that finds `bvh::trace_ray`'s hit bit for bit: each node's inner
//! children that the ray enters are visited in the order of their entry
//! distances (Embree's and pbrt's order), and a child put aside is dropped
//! without being fetched once a hit nearer than its entry is found.
//!
//! `bvh::trace_ray` walks node groups in the order of the ray's octant
//! (Ylitie et al. 2017), an order the GPU can follow without sorting. It
//! is an approximation of near to far: on the tessellated spheres of
//! cornell-spheres a ray meets boxes behind its hit that the exact order
//! would never open.
//!
//! The hit does not depend on the order (`bvh::nearer_hit`), and an
//! any-hit query asks only whether something is hit, so the result is
//! `trace_ray`'s wherever neither can give up: `trace_ray` stops after
//! `BVH_MAX_ITERATIONS` node visits and triangle tests, or on a full stack,
//! and how soon depends on the order. So this traversal runs only where
//! that cannot happen (`traversal::order_free`: the whole BVH is smaller
//! than the budget and shallower than the stack); here each node is opened
//! at most once and each triangle tested at most once.
//!
//! For the same reason it tests each child's exact bounds
//! (`CpuScene::tight_nodes`) rather than the grid's looser planes that
//! the kernels decode: fewer boxes opened, the same hits.

use super::cache::CpuScene;
use super::cache::node_planes::DecodedNode;
#[cfg(target_arch = "x86_64")]
use super::leaf_window::{WindowRay, intersect_leaves};
use super::octant::{child_entries, slot_bits};
use crate::constants::BVH_STACK_SIZE;
use crate::cpu::common::bvh::Hit;
use crate::cpu::common::intersect::ray_shear;
use crate::cpu::common::sampling::FLT_MAX;
use glam::Vec3;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Children put aside: at most seven per level of a BVH shallower than
/// `BVH_STACK_SIZE` (`order_free`).
const ORDERED_STACK_SIZE: usize = 8 * BVH_STACK_SIZE as usize;

/// What the ray meets at one node: its leaf triangles' bits (as
/// `bvh::node_hit_bits` sets them), the inner children it enters (bit k for
/// child k) and every child's entry distance.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn node_entries(
    n: &DecodedNode,
    o: Vec3,
    inv_d: Vec3,
    t_max: f32,
    t_enter_out: &mut [f32; 8],
) -> (u32, u32) {
    let (t_enter, hit) = child_entries(n, o, inv_d, t_max);
    // SAFETY: eight floats.
    unsafe { _mm256_storeu_ps(t_enter_out.as_mut_ptr(), t_enter) };
    // Octant 0 leaves inner children's bits at 24 + k, above the leaves'.
    let leaves = slot_bits(n, hit, 0) & 0x00FF_FFFF;
    let inner = _mm256_movemask_ps(hit) as u32 & (n.e_imask >> 24);
    (leaves, inner)
}

/// `bvh::trace_ray`'s hit for a still scene where
/// `traversal::order_free`, nearest child first. `start` and `hit`: the
/// subtree of node `start` with `hit` the nearest hit so far (the root and
/// t_max with `NO_HIT` for a whole query); `packet` hands a ray over
/// to it where the packet has thinned out.
///
/// # Safety
/// The CPU must support AVX2 and the bit instructions
/// ([`super::octant::available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
pub unsafe fn trace_ray_nearest_first(
    scene: &CpuScene,
    o: Vec3,
    d: Vec3,
    any_hit: bool,
    coverage_seed: u32,
    start: u32,
    hit: Hit,
) -> Hit {
    let ray = WindowRay::new(o, &ray_shear(d));
    let inv_d = (Vec3::ONE / d).clamp(Vec3::splat(-FLT_MAX), Vec3::splat(FLT_MAX));
    // SAFETY: the caller's promise.
    unsafe {
        trace_ray_nearest_first_with(scene, o, inv_d, &ray, any_hit, coverage_seed, start, hit)
    }
}

/// `trace_ray_nearest_first` with the ray's set-up done: `inv_d` its clamped
/// inverse direction and `ray` its triangle test's values (a packet hands
/// a ray over with its own, the same values).
///
/// # Safety
/// As for [`trace_ray_nearest_first`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
#[allow(clippy::too_many_arguments)]
pub unsafe fn trace_ray_nearest_first_with(
    scene: &CpuScene,
    o: Vec3,
    inv_d: Vec3,
    ray: &WindowRay,
    any_hit: bool,
    coverage_seed: u32,
    start: u32,
    mut hit: Hit,
) -> Hit {
    let nodes = scene.tight_nodes();
    let blocks = scene.window_blocks();
    let mut stack = [const { std::mem::MaybeUninit::<(u32, f32)>::uninit() }; ORDERED_STACK_SIZE];
    let mut sp = 0usize;
    let mut node = start;
    let mut t_enter = [0f32; 8];
    loop {
        let n = &nodes[node as usize];
        let (tri_bits, mut inner) = node_entries(n, o, inv_d, hit.t, &mut t_enter);
        if tri_bits != 0 {
            let group = [n.primitive_base_idx, tri_bits, n.triangle_block];
            if intersect_leaves(scene, group, blocks, ray, any_hit, coverage_seed, &mut hit) {
                return hit;
            }
        }
        // Inner children are stored in slot order from child_base.
        let imask = n.e_imask >> 24;
        let child = |k: u32| n.child_base_idx + (imask & ((1 << k) - 1)).count_ones();
        let entered = inner.count_ones();
        if entered == 1 {
            node = child(inner.trailing_zeros());
            continue;
        }
        if entered > 1 {
            // Push them all, then sort the pushed run far to near by
            // insertion (at most eight), and take the nearest off the top.
            let first = sp;
            while inner != 0 {
                let k = inner.trailing_zeros();
                inner &= inner - 1;
                let entry = (child(k), t_enter[k as usize]);
                let mut at = sp;
                // SAFETY: entries first..sp were written just now.
                while at > first && unsafe { stack[at - 1].assume_init().1 } < entry.1 {
                    stack[at] = stack[at - 1];
                    at -= 1;
                }
                stack[at].write(entry);
                sp += 1;
            }
        }
        // The nearest child put aside whose box still begins before the
        // hit (the node test's own bound at the current t_max).
        loop {
            if sp == 0 {
                return hit;
            }
            sp -= 1;
            // SAFETY: entries below sp were written (pushes write, pops lower).
            let (next, t) = unsafe { stack[sp].assume_init() };
            if t <= hit.t * 1.000_000_4 {
                node = next;
                break;
            }
        }
    }
}
