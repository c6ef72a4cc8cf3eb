//! Twin of `shaders/common/bvh.glsl`: the same bounded CWBVH traversal, in
//! the same order with the same arithmetic, so both back ends find the same
//! hit and an overflow on one back end is an overflow on the other. The
//! loop is written once over its step tests (`StepTests`), so the CPU
//! back end's vector tests (`cpu::fast::octant`) run the same loop.

use super::instances::{instance_point, instance_vector};
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

impl Hit {
    /// No hit yet, before `t_max`: where a traversal starts.
    pub fn none(t_max: f32) -> Hit {
        Hit {
            t: t_max,
            triangle: NO_HIT,
            b12: Vec2::ZERO,
        }
    }
}

/// Whether triangle `i`, met at `t`, is nearer than `hit`: at equal t the
/// lower index wins, so the nearest hit does not depend on the order in
/// which a traversal meets triangles (`packet` traces eight rays in
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
/// This is the kernels' traversal with their scalar tests. Which traversal
/// the CPU back end runs is `cpu::traversal`'s choice.
pub fn trace_ray(
    scene: &PackedScene,
    o: Vec3,
    d: Vec3,
    t_max: f32,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
) -> Hit {
    let hit = Hit::none(t_max);
    if !scene.instances.is_empty() {
        return trace_instances_with(
            scene,
            &|_, _| ScalarSteps,
            o,
            d,
            any_hit,
            coverage_seed,
            time,
            hit,
        );
    }
    trace_ray_with(scene, &ScalarSteps, o, d, any_hit, coverage_seed, time, hit)
}

/// A node's step: the hit bits of its children (`node_hit_bits`), where its
/// inner children and its leaf triangles start, its imask and its first
/// block of leaf triangles (`StepTests::leaf_group`'s, 0 where unused).
pub struct NodeStep {
    pub hits: u32,
    pub child_base: u32,
    pub primitive_base: u32,
    pub e_imask: u32,
    pub triangle_block: u32,
}

/// The tests `trace_ray_with` makes at each step, so that the kernels'
/// loop is written once: the scalar twins' (`ScalarSteps`), or vector tests
/// with the same results (the CPU back end's `fast::octant`).
pub trait StepTests {
    /// The ray's step at `node`, its children tested against `t_max`.
    fn node(&self, scene: &PackedScene, node: u32, ray: &RaySetup, t_max: f32) -> NodeStep;
    /// Whether `leaf_group` tests whole leaf groups.
    const GROUPS: bool;
    /// The scalar loop's result for a whole leaf group (24 bits from
    /// `group[0]`; `group[2]`: the node's first triangle block), where the
    /// work budget allows it; true when an any-hit query is done.
    /// `id_offset`: what turns a triangle slot into its hit id (the
    /// instance's, `trace_bvh_with`).
    #[allow(clippy::too_many_arguments)]
    fn leaf_group(
        &self,
        scene: &PackedScene,
        group: [u32; 3],
        any_hit: bool,
        coverage_seed: u32,
        id_offset: u32,
        hit: &mut Hit,
    ) -> bool;
}

/// What every step of one ray's traversal reads: its origin, its inverse
/// direction clamped to finite values, their signs and its octant.
pub struct RaySetup {
    pub o: Vec3,
    pub inv_d: Vec3,
    pub neg: BVec3,
    /// obvhs' ray_get_octant_inv4: a bit per positive axis (x 4, y 2, z 1).
    pub oct: u32,
}

impl RaySetup {
    pub fn new(o: Vec3, d: Vec3) -> RaySetup {
        // A zero direction component gives an infinite inverse, and 0 * inf
        // = NaN in the slab test: clamp to the largest finite float, same
        // sign.
        let inv_d = (Vec3::ONE / d).clamp(Vec3::splat(-FLT_MAX), Vec3::splat(FLT_MAX));
        let neg = inv_d.cmplt(Vec3::ZERO);
        let oct =
            (if neg.x { 0 } else { 4 }) | (if neg.y { 0 } else { 2 }) | (if neg.z { 0 } else { 1 });
        RaySetup { o, inv_d, neg, oct }
    }
}

/// The kernels' scalar tests.
pub struct ScalarSteps;

impl StepTests for ScalarSteps {
    #[inline(always)]
    fn node(&self, scene: &PackedScene, node: u32, ray: &RaySetup, t_max: f32) -> NodeStep {
        let n = &scene.nodes[node as usize];
        NodeStep {
            hits: node_hit_bits(n, ray.o, ray.inv_d, ray.neg, t_max, ray.oct),
            child_base: n.child_base_idx,
            primitive_base: n.primitive_base_idx,
            e_imask: n.e_imask,
            triangle_block: 0,
        }
    }
    const GROUPS: bool = false;
    fn leaf_group(
        &self,
        _: &PackedScene,
        _: [u32; 3],
        _: bool,
        _: u32,
        _: u32,
        _: &mut Hit,
    ) -> bool {
        unreachable!("the scalar steps test triangles one at a time")
    }
}

/// The traversal with the step tests `tests`. `hit`: t_max and `NO_HIT`
/// (the nearest hit so far, none yet). A one-level scene's whole BVH; a
/// two-level scene's go through `trace_instances_with`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn trace_ray_with<T: StepTests>(
    scene: &PackedScene,
    tests: &T,
    o: Vec3,
    d: Vec3,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
    mut hit: Hit,
) -> Hit {
    let mut work = 0u32;
    trace_bvh_with(
        scene,
        tests,
        [0, 0],
        o,
        d,
        any_hit,
        coverage_seed,
        time,
        &mut hit,
        &mut work,
    );
    hit
}

/// The BVH from node `root[0]` (the scene's, or a mesh's with the ray in
/// the mesh's space), a triangle in slot s reporting id `s + root[1]`;
/// `work` counts on from the caller's. True when the query is done: an
/// any-hit query found one, or the traversal gave up (`OVERFLOW_HIT`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn trace_bvh_with<T: StepTests>(
    scene: &PackedScene,
    tests: &T,
    root: [u32; 2],
    o: Vec3,
    d: Vec3,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
    hit: &mut Hit,
    work: &mut u32,
) -> bool {
    let [root, id_offset] = root;
    let shear = ray_shear(d);
    let ray = RaySetup::new(o, d);
    let oct = ray.oct;

    // Node groups put aside, uninitialized: an entry is read only after it
    // is written, and zeroing 256 bytes per ray cost about 1 % of a render.
    let mut stack =
        [const { std::mem::MaybeUninit::<[u32; 2]>::uninit() }; BVH_STACK_SIZE as usize];
    let mut sp = 0usize;
    let mut node_group = [root, 0x8000_0000];
    // primitive_base, one bit per triangle offset, and the node's first
    // block of triangles (`StepTests::leaf_group`).
    let mut tri_group = [0u32, 0, 0];
    loop {
        if T::GROUPS && tri_group[1] != 0 && *work + tri_group[1].count_ones() <= BVH_MAX_ITERATIONS
        {
            *work += tri_group[1].count_ones();
            if tests.leaf_group(scene, tri_group, any_hit, coverage_seed, id_offset, hit) {
                return true;
            }
            tri_group[1] = 0;
        }
        while tri_group[1] != 0 {
            let b = 31 - tri_group[1].leading_zeros();
            tri_group[1] &= !(1 << b);
            *work += 1;
            if *work > BVH_MAX_ITERATIONS {
                hit.triangle = OVERFLOW_HIT;
                return true;
            }
            let i = tri_group[0] + b;
            let id = i.wrapping_add(id_offset);
            let tv = &scene.tri_verts[i as usize];
            let [v0, v1, v2] = triangle_at(scene, i, time);
            // A MASK or BLEND triangle is hit only where its alpha test passes.
            if let Some((t, b12)) = triangle_hit(o, &shear, v0, v1, v2).filter(|&(t, b12)| {
                nearer_hit(t, id, hit)
                    && (tv.alpha_mask == 0
                        || alpha_test_passes(scene, tv.material, i, b12, coverage_seed))
            }) {
                *hit = Hit {
                    t,
                    triangle: id,
                    b12,
                };
                if any_hit {
                    return true;
                }
            }
        }
        if node_group[1] & 0xFF00_0000 != 0 {
            let b = 31 - node_group[1].leading_zeros();
            node_group[1] &= !(1 << b);
            if node_group[1] & 0xFF00_0000 != 0 {
                if sp == BVH_STACK_SIZE as usize {
                    hit.triangle = OVERFLOW_HIT;
                    return true;
                }
                stack[sp].write(node_group);
                sp += 1;
            }
            *work += 1;
            if *work > BVH_MAX_ITERATIONS {
                hit.triangle = OVERFLOW_HIT;
                return true;
            }
            // Inner children are stored in slot order from child_base: the
            // node's index is the number of inner slots before its own.
            let slot = (b - 24) ^ oct;
            let node = node_group[0] + (node_group[1] & ((1 << slot) - 1)).count_ones();
            let step = tests.node(scene, node, &ray, hit.t);
            node_group = [
                step.child_base,
                (step.hits & 0xFF00_0000) | (step.e_imask >> 24),
            ];
            tri_group = [
                step.primitive_base,
                step.hits & 0x00FF_FFFF,
                step.triangle_block,
            ];
        } else {
            if sp == 0 {
                return false;
            }
            sp -= 1;
            // SAFETY: entries below sp were written (pushes write, pops lower).
            node_group = unsafe { stack[sp].assume_init() };
        }
    }
}

/// A two-level scene's traversal: the top level (node 0 on, the scalar
/// node tests) over the instances; at each instance it meets, the ray is
/// taken into the mesh's space and its BVH traversed with the step tests
/// `steps_for` makes for that ray (`trace_bvh_with`), under one work
/// budget. The same order as the kernels' `trace_instances`, so the same
/// hit and the same overflows.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn trace_instances_with<T: StepTests, F: Fn(Vec3, Vec3) -> T>(
    scene: &PackedScene,
    steps_for: &F,
    o: Vec3,
    d: Vec3,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
    mut hit: Hit,
) -> Hit {
    let ray = RaySetup::new(o, d);
    let oct = ray.oct;
    let mut stack = [[0u32; 2]; BVH_STACK_SIZE as usize];
    let mut sp = 0usize;
    let mut node_group = [0u32, 0x8000_0000];
    let mut instance_group = [0u32, 0];
    let mut work = 0u32;
    loop {
        while instance_group[1] != 0 {
            let b = 31 - instance_group[1].leading_zeros();
            instance_group[1] &= !(1 << b);
            work += 1;
            if work > BVH_MAX_ITERATIONS {
                hit.triangle = OVERFLOW_HIT;
                return hit;
            }
            let inst = &scene.instances[(instance_group[0] + b) as usize];
            let to_object = inst.to_object();
            let oo = instance_point(&to_object, o);
            let od = instance_vector(&to_object, d);
            let tests = steps_for(oo, od);
            let root = [inst.root, inst.id_base.wrapping_sub(inst.first_triangle)];
            if trace_bvh_with(
                scene,
                &tests,
                root,
                oo,
                od,
                any_hit,
                coverage_seed,
                time,
                &mut hit,
                &mut work,
            ) {
                return hit;
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
                stack[sp] = node_group;
                sp += 1;
            }
            work += 1;
            if work > BVH_MAX_ITERATIONS {
                hit.triangle = OVERFLOW_HIT;
                return hit;
            }
            let slot = (b - 24) ^ oct;
            let node = node_group[0] + (node_group[1] & ((1 << slot) - 1)).count_ones();
            let step = ScalarSteps.node(scene, node, &ray, hit.t);
            node_group = [
                step.child_base,
                (step.hits & 0xFF00_0000) | (step.e_imask >> 24),
            ];
            instance_group = [step.primitive_base, step.hits & 0x00FF_FFFF];
        } else {
            if sp == 0 {
                return hit;
            }
            sp -= 1;
            node_group = stack[sp];
        }
    }
}
