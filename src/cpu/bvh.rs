//! Twin of `shaders/common/bvh.glsl`: the same bounded CWBVH traversal, in
//! the same order with the same arithmetic, so both back ends find the same
//! hit and an overflow on one back end is an overflow on the other. Where
//! no ray can overflow, the CPU visits children nearest first instead
//! (`bvh_ordered`): the same hits, in fewer steps.

use super::intersect::{ray_shear, triangle_hit};
use super::sampling::FLT_MAX;
use super::textures::alpha_test_passes;
use crate::constants::*;
use crate::packed::PackedScene;
use crate::packed::layout::CwBvhNode;
use glam::{BVec3, UVec3, Vec2, Vec3};

pub const NO_HIT: u32 = 0xFFFF_FFFF;
pub const OVERFLOW_HIT: u32 = 0xFFFF_FFFE;

#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub b12: Vec2,
}

/// Whether triangle `i`, met at `t`, is nearer than `hit`: at equal t the
/// lower index wins, so the nearest hit does not depend on the order in
/// which a traversal meets triangles (`bvh_packet` traces eight rays in
/// another order and finds the same hits).
#[inline(always)]
pub fn nearer_hit(t: f32, i: u32, hit: &Hit) -> bool {
    t < hit.t || (t == hit.t && hit.triangle != NO_HIT && i < hit.triangle)
}

/// GLSL's `bitfieldExtract(v, shift, 8)` on each component.
fn extract_byte3(v: UVec3, shift: u32) -> Vec3 {
    Vec3::new(
        ((v.x >> shift) & 0xFF) as f32,
        ((v.y >> shift) & 0xFF) as f32,
        ((v.z >> shift) & 0xFF) as f32,
    )
}

/// Hit bits of one child: byte `shift / 8` of the words of its near and far
/// grid planes (already swapped by ray direction) and of its child_meta.
/// The box test is `intersect_aabb`'s on the decoded planes `p + e * q`,
/// which enclose the child's exact bounds (`bvh::build`).
#[allow(clippy::too_many_arguments)]
pub fn child_hit_bits(
    meta4: u32,
    near4: UVec3,
    far4: UVec3,
    shift: u32,
    p: Vec3,
    e: Vec3,
    o: Vec3,
    inv_d: Vec3,
    t_max: f32,
    oct: u32,
) -> u32 {
    let near_plane = p + e * extract_byte3(near4, shift);
    let far_plane = p + e * extract_byte3(far4, shift);
    let tn = (near_plane - o) * inv_d;
    let tf = (far_plane - o) * inv_d;
    let t_enter = tn.x.max(tn.y).max(tn.z.max(0.0));
    let t_exit = tf.x.min(tf.y).min(tf.z.min(t_max)) * 1.000_000_4;
    let m = (meta4 >> shift) & 0xFF;
    let index = (m & 31) ^ if m & 0x18 == 0x18 { oct } else { 0 };
    if t_enter <= t_exit {
        (m >> 5) << index
    } else {
        0
    }
}

/// Children 4h .. 4h + 3: meta4 and the words of their planes (x, y, z).
#[allow(clippy::too_many_arguments)]
pub fn children4_hit_bits(
    meta4: u32,
    lo: UVec3,
    hi: UVec3,
    neg: BVec3,
    p: Vec3,
    e: Vec3,
    o: Vec3,
    inv_d: Vec3,
    t_max: f32,
    oct: u32,
) -> u32 {
    let near4 = UVec3::select(neg, hi, lo);
    let far4 = UVec3::select(neg, lo, hi);
    let bits = |shift| child_hit_bits(meta4, near4, far4, shift, p, e, o, inv_d, t_max, oct);
    bits(0) | bits(8) | bits(16) | bits(24)
}

/// Hit bits of a node's 8 children: bits 24 + (slot ^ oct) for inner
/// children, bits `offset .. offset + count` for leaf children's triangles.
pub fn node_hit_bits(n: &CwBvhNode, o: Vec3, inv_d: Vec3, neg: BVec3, t_max: f32, oct: u32) -> u32 {
    let p = Vec3::from(n.p);
    let e = crate::packed::bvh::grid_step(n.e_imask);
    let h = |k: usize| {
        children4_hit_bits(
            n.child_meta[k],
            UVec3::new(n.qlo_x[k], n.qlo_y[k], n.qlo_z[k]),
            UVec3::new(n.qhi_x[k], n.qhi_y[k], n.qhi_z[k]),
            neg,
            p,
            e,
            o,
            inv_d,
            t_max,
            oct,
        )
    };
    h(0) | h(1)
}

/// The triangle's vertices where a ray at `time` (`motion`) meets them.
pub fn triangle_at(scene: &PackedScene, i: u32, time: f32) -> [Vec3; 3] {
    match &scene.motion {
        Some(m) => super::motion::moving_triangle(scene, m, i, time),
        None => {
            let tv = &scene.tri_verts[i as usize];
            [tv.v0.into(), tv.v1.into(), tv.v2.into()]
        }
    }
}

/// Closest hit with t in (0, t_max); any_hit: stop at the first hit found.
/// Ylitie et al.'s traversal: a node group is (child_base, hit bits << 24 |
/// imask), nearest child first (obvhs orders slots by octant); a triangle
/// group is (primitive_base, one bit per triangle offset). `coverage_seed`:
/// the ray's seed for alpha BLEND tests (`rng_coverage_seed`); `time`: the
/// ray's moment in the shutter, where moving triangles are met (`motion`;
/// the boxes enclose every step).
///
/// Where the CPU has AVX2 the whole traversal is compiled for it and tests
/// eight children or eight triangles at once (`bvh_avx2`), with the same
/// results; in a still scene that no ray can exhaust the budget of
/// (`bvh_packet::packets_fit`), nearest child first (`bvh_ordered`), again
/// with the same results.
pub fn trace_ray(
    scene: &PackedScene,
    o: Vec3,
    d: Vec3,
    t_max: f32,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
) -> Hit {
    let hit = Hit {
        t: t_max,
        triangle: NO_HIT,
        b12: Vec2::ZERO,
    };
    #[cfg(target_arch = "x86_64")]
    if super::bvh_avx2::available() {
        if super::bvh_packet::packets_fit(scene) {
            // SAFETY: the CPU has AVX2 (checked); `packets_fit`: a still
            // scene that fits the budget.
            return unsafe {
                super::bvh_ordered::trace_ray_ordered(scene, o, d, any_hit, coverage_seed, 0, hit)
            };
        }
        // SAFETY: the CPU has AVX2 (checked).
        return unsafe { trace_ray_avx2(scene, o, d, any_hit, coverage_seed, time, hit) };
    }
    trace_ray_with::<false>(scene, o, d, any_hit, coverage_seed, time, hit)
}

/// `trace_ray` compiled for AVX2, with the bit instructions every AVX2 CPU
/// has (`popcnt` for the child index, `lzcnt` and `bmi1` for the bit loops;
/// without them `count_ones` is a dozen instructions).
///
/// # Safety
/// The CPU must support them ([`super::bvh_avx2::available`]).
///
/// `hit`: t_max and `NO_HIT` (the nearest hit so far, none yet).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
#[allow(clippy::too_many_arguments)]
pub unsafe fn trace_ray_avx2(
    scene: &PackedScene,
    o: Vec3,
    d: Vec3,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
    hit: Hit,
) -> Hit {
    trace_ray_with::<true>(scene, o, d, any_hit, coverage_seed, time, hit)
}

/// The traversal; `SIMD`: use the AVX2 tests (only called so from
/// `trace_ray_avx2`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn trace_ray_with<const SIMD: bool>(
    scene: &PackedScene,
    o: Vec3,
    d: Vec3,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
    mut hit: Hit,
) -> Hit {
    let shear = ray_shear(d);
    // A zero direction component gives an infinite inverse, and 0 * inf =
    // NaN in the slab test: clamp to the largest finite float, same sign.
    let inv_d = (Vec3::ONE / d).clamp(Vec3::splat(-FLT_MAX), Vec3::splat(FLT_MAX));
    let neg = inv_d.cmplt(Vec3::ZERO);
    // obvhs' ray_get_octant_inv4: a bit per positive axis (x 4, y 2, z 1).
    let oct =
        (if neg.x { 0 } else { 4 }) | (if neg.y { 0 } else { 2 }) | (if neg.z { 0 } else { 1 });

    // Node groups put aside, uninitialized: an entry is read only after it
    // is written, and zeroing 256 bytes per ray cost about 1 % of a render.
    let mut stack =
        [const { std::mem::MaybeUninit::<[u32; 2]>::uninit() }; BVH_STACK_SIZE as usize];
    let mut sp = 0usize;
    let mut node_group = [0u32, 0x8000_0000]; // the root is node 0
    // primitive_base, one bit per triangle offset, and the node's first
    // block of triangles (`triangle_blocks`).
    let mut tri_group = [0u32, 0, 0];
    let mut work = 0u32;
    // The AVX2 node test reads the nodes with their planes decoded.
    let decoded_nodes = if SIMD { scene.decoded_nodes() } else { &[] };
    // And a still scene's triangles in blocks (a moving one's in arrays).
    let triangle_blocks = if SIMD && scene.motion.is_none() {
        scene.triangle_blocks()
    } else {
        &[]
    };
    // The triangle test's per-ray values, once.
    #[cfg(target_arch = "x86_64")]
    let ray_lanes = if SIMD {
        // SAFETY: `SIMD` only where the CPU has AVX2.
        Some(unsafe { super::bvh_avx2::RayLanes::new(o, &shear) })
    } else {
        None
    };
    // A moving scene's time steps around the ray's time (`motion`).
    let segment = scene
        .motion
        .as_ref()
        .map(|m| super::motion::motion_segment(m, time));
    loop {
        #[cfg(target_arch = "x86_64")]
        if SIMD && tri_group[1] != 0 && work + tri_group[1].count_ones() <= BVH_MAX_ITERATIONS {
            work += tri_group[1].count_ones();
            // SAFETY: `SIMD` only where the CPU has AVX2.
            if unsafe {
                intersect_group_avx2(
                    scene,
                    tri_group,
                    triangle_blocks,
                    ray_lanes.as_ref().expect("set where SIMD"),
                    segment,
                    any_hit,
                    coverage_seed,
                    &mut hit,
                )
            } {
                return hit;
            }
            tri_group[1] = 0;
        }
        while tri_group[1] != 0 {
            let b = 31 - tri_group[1].leading_zeros();
            tri_group[1] &= !(1 << b);
            work += 1;
            if work > BVH_MAX_ITERATIONS {
                hit.triangle = OVERFLOW_HIT;
                return hit;
            }
            let i = tri_group[0] + b;
            let tv = &scene.tri_verts[i as usize];
            let [v0, v1, v2] = triangle_at(scene, i, time);
            // A MASK or BLEND triangle is hit only where its alpha test passes.
            if let Some((t, b12)) = triangle_hit(o, &shear, v0, v1, v2).filter(|&(t, b12)| {
                nearer_hit(t, i, &hit)
                    && (tv.alpha_mask == 0
                        || alpha_test_passes(scene, tv.material, i, b12, coverage_seed))
            }) {
                hit = Hit {
                    t,
                    triangle: i,
                    b12,
                };
                if any_hit {
                    return hit;
                }
            }
        }
        if node_group[1] & 0xFF00_0000 != 0 {
            let b = 31 - node_group[1].leading_zeros();
            node_group[1] &= !(1 << b);
            if node_group[1] & 0xFF00_0000 != 0 {
                if sp == BVH_STACK_SIZE as usize {
                    hit.triangle = OVERFLOW_HIT;
                    return hit;
                }
                stack[sp].write(node_group);
                sp += 1;
            }
            work += 1;
            if work > BVH_MAX_ITERATIONS {
                hit.triangle = OVERFLOW_HIT;
                return hit;
            }
            // Inner children are stored in slot order from child_base: the
            // node's index is the number of inner slots before its own.
            let slot = (b - 24) ^ oct;
            let node = node_group[0] + (node_group[1] & ((1 << slot) - 1)).count_ones();
            let (hits, (child_base, primitive_base), e_imask, triangle_block) = if SIMD {
                let n = &decoded_nodes[node as usize];
                let hits = {
                    // SAFETY: `SIMD` is true only where the CPU has AVX2.
                    #[cfg(target_arch = "x86_64")]
                    unsafe {
                        super::bvh_avx2::node_hit_bits(n, o, inv_d, hit.t, oct)
                    }
                    #[cfg(not(target_arch = "x86_64"))]
                    unreachable!("the AVX2 node test exists only on x86_64")
                };
                let base = (n.child_base_idx, n.primitive_base_idx);
                (hits, base, n.e_imask, n.triangle_block)
            } else {
                let n = &scene.nodes[node as usize];
                let hits = node_hit_bits(n, o, inv_d, neg, hit.t, oct);
                (hits, (n.child_base_idx, n.primitive_base_idx), n.e_imask, 0)
            };
            node_group = [child_base, (hits & 0xFF00_0000) | (e_imask >> 24)];
            tri_group = [primitive_base, hits & 0x00FF_FFFF, triangle_block];
        } else {
            if sp == 0 {
                return hit;
            }
            sp -= 1;
            // SAFETY: entries below sp were written (pushes write, pops lower).
            node_group = unsafe { stack[sp].assume_init() };
        }
    }
}

/// The scalar triangle loop's result for a whole group (24 bits from
/// `group[0]`; `group[2]`: the node's first block in `blocks`), eight
/// triangles at a time: the AVX2 test finds the lanes that can hit at the
/// current t_max, then those are accepted in the scalar loop's order
/// (highest bit first) with its exact checks at the t_max of that moment.
/// Returns true when an any-hit query is done.
///
/// # Safety
/// The CPU must support them ([`super::bvh_avx2::available`]).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
#[allow(clippy::too_many_arguments)]
pub(super) unsafe fn intersect_group_avx2(
    scene: &PackedScene,
    group: [u32; 3],
    blocks: &[crate::packed::triangle_blocks::TriangleBlock],
    ray: &super::bvh_avx2::RayLanes,
    segment: Option<(u32, f32)>,
    any_hit: bool,
    coverage_seed: u32,
    hit: &mut Hit,
) -> bool {
    for w in (0..3).rev() {
        let lanes = (group[1] >> (8 * w)) & 0xFF;
        if lanes == 0 {
            continue;
        }
        let first = group[0] + 8 * w;
        let window = match segment {
            Some(segment) => super::bvh_avx2::Window::Moving {
                tris: scene.triangle_soa(),
                first: first as usize,
                segment,
            },
            None => super::bvh_avx2::Window::Still(&blocks[(group[2] + w) as usize]),
        };
        // SAFETY: AVX2 (the caller's promise); set bits are leaf triangles.
        let l = unsafe { super::bvh_avx2::intersect_triangles(window, lanes, ray, hit.t) };
        let mut candidates = l.candidates;
        while candidates != 0 {
            let lane = 31 - candidates.leading_zeros();
            candidates &= !(1 << lane);
            let i = first + lane;
            let tv = &scene.tri_verts[i as usize];
            if let Some((t, b12)) = l.accepts(lane as usize, i, hit).filter(|&(_, b12)| {
                tv.alpha_mask == 0 || alpha_test_passes(scene, tv.material, i, b12, coverage_seed)
            }) {
                *hit = Hit {
                    t,
                    triangle: i,
                    b12,
                };
                if any_hit {
                    return true;
                }
            }
        }
    }
    false
}
