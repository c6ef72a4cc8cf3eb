//! A packet of rays through the BVH together, for the lane schedule
//! (`lanes`): each node is fetched once for all the rays that reach it, and
//! each child box and each triangle is tested against all the rays in one
//! vector register, a ray per lane (the packet traversal of Wald et al.
//! 2001 and Embree's packet kernels, on vkpt's CWBVH): sixteen rays with
//! AVX-512, eight with AVX2 (`wide`).
//!
//! Every lane computes what `bvh::trace_ray` computes for its ray, with the
//! same f32 operations in the same order: the slab test of
//! `bvh::node_hit_bits` (on the tight boxes of `CpuScene::tight_nodes`,
//! which hold everything the grid's boxes hold) and the watertight test of
//! `intersect::triangle_hit` on the same floats, with the same per-ray
//! shear. The packet meets the triangles in another order than a single
//! ray does and skips boxes the grid's would have opened, but the nearest
//! hit does not depend on the order (`bvh::nearer_hit`: at equal distance
//! the lower index wins), and an any-hit query asks only whether something
//! is hit. So each lane's hit is `trace_ray`'s, bit for bit
//! (`tests/suite/cpu_lanes.rs`, on every bundled scene where packets fit, with
//! thousands of rays that meet two triangles at the same distance).
//!
//! A ray left alone at a node with inner children goes on by itself
//! (`nearest_first::trace_ray_nearest_first` from that node, nearest child first
//! as a single ray goes where packets fit): a packet's tests cost as much
//! for one ray as for all. Below a node of leaves only it stays in the
//! packet, which costs less than the hand-over there.
//!
//! One difference is left: `trace_ray` gives up after `BVH_MAX_ITERATIONS`
//! node visits and triangle tests, or when its stack is full, and how soon
//! depends on the order. Packets are used only where neither can happen
//! (`order_free`: the whole BVH is smaller than the budget and shallower
//! than the stack), so no ray of those scenes ever gives up.

use super::cache::CpuScene;
#[cfg(target_arch = "x86_64")]
use super::leaf_window::{any_sign, behind_origin, cross2};
use super::wide::WIDTH;
#[cfg(target_arch = "x86_64")]
use super::wide::{self, F, I, Mask};
use crate::constants::BVH_STACK_SIZE;
use crate::cpu::common::bvh::{Hit, NO_HIT};
use crate::cpu::common::sampling::FLT_MAX;
use crate::cpu::common::textures::alpha_test_passes;
use glam::{Vec2, Vec3};
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::{_CMP_EQ_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ};
#[cfg(target_arch = "x86_64")]
use std::mem::MaybeUninit;

/// A packet's rays, a lane each (structure of arrays); lanes not set in
/// `active` are not traced and get no hit.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Rays {
    /// Per axis (x, y, z), the rays' origins and directions.
    pub origin: [[f32; WIDTH]; 3],
    pub direction: [[f32; WIDTH]; 3],
    pub t_max: [f32; WIDTH],
    /// Each ray's seed for alpha BLEND tests (`rng_coverage_seed`).
    pub coverage_seed: [u32; WIDTH],
    pub active: u32,
}

impl Default for Rays {
    fn default() -> Rays {
        Rays {
            origin: [[0.0; WIDTH]; 3],
            // Inactive lanes compute on a harmless ray (+z).
            direction: [[0.0; WIDTH], [0.0; WIDTH], [1.0; WIDTH]],
            t_max: [0.0; WIDTH],
            coverage_seed: [0; WIDTH],
            active: 0,
        }
    }
}

impl Rays {
    /// Ray `lane`, made active.
    pub fn set(&mut self, lane: usize, origin: Vec3, direction: Vec3, t_max: f32, seed: u32) {
        for axis in 0..3 {
            self.origin[axis][lane] = origin[axis];
            self.direction[axis][lane] = direction[axis];
        }
        self.t_max[lane] = t_max;
        self.coverage_seed[lane] = seed;
        self.active |= 1 << lane;
    }

    pub fn origin(&self, lane: usize) -> Vec3 {
        Vec3::new(
            self.origin[0][lane],
            self.origin[1][lane],
            self.origin[2][lane],
        )
    }

    pub fn direction(&self, lane: usize) -> Vec3 {
        Vec3::new(
            self.direction[0][lane],
            self.direction[1][lane],
            self.direction[2][lane],
        )
    }
}

/// A node still to visit: its index, the rays that reach it and their
/// distances to its box (to drop those that found a nearer hit since).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Pending {
    t_enter: F,
    node: u32,
    rays: u32,
}

/// The packet's rays, a lane each, as the tests need them.
#[cfg(target_arch = "x86_64")]
struct Lanes {
    origin: [F; 3],
    inv_d: [F; 3],
    /// The lanes whose inverse direction is negative, per axis.
    negative: [Mask; 3],
    /// The watertight test's axes (`RayShear::k`): each lane's k.x, k.y
    /// and k.z (0, 1 or 2), and its origin's components along them.
    axis: [I; 3],
    origin_along: [F; 3],
    shear: [F; 3],
}

/// Each active lane's nearest hit (closest hit) or some hit (`any_hit`),
/// exactly `bvh::trace_ray`'s for a still scene where `order_free`.
///
/// # Safety
/// The CPU must support AVX2 and the bit instructions
/// ([`super::octant::available`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
pub unsafe fn trace_rays(scene: &CpuScene, rays: &Rays, any_hit: bool) -> [Hit; WIDTH] {
    let lanes = ray_lanes(rays);
    let mut best = Best {
        t: wide::load(&rays.t_max),
        triangle: wide::splat_i(NO_HIT as i32),
        b1: wide::splat(0.0),
        b2: wide::splat(0.0),
    };
    traverse(scene, &lanes, rays, any_hit, &mut best);

    let (t, triangle, b1, b2) = best.lanes();
    std::array::from_fn(|l| Hit {
        t: t[l],
        triangle: triangle[l],
        b12: Vec2::new(b1[l], b2[l]),
    })
}

/// What the tests need of the rays: `bvh::trace_ray`'s clamped inverse
/// direction and octant, and `intersect::ray_shear`'s axes and shear, for
/// the packet's rays in vector registers (divisions are exact, so each lane's
/// values are the scalar code's).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn ray_lanes(rays: &Rays) -> Lanes {
    let o = [
        wide::load(&rays.origin[0]),
        wide::load(&rays.origin[1]),
        wide::load(&rays.origin[2]),
    ];
    let d = [
        wide::load(&rays.direction[0]),
        wide::load(&rays.direction[1]),
        wide::load(&rays.direction[2]),
    ];
    let one = wide::splat(1.0);
    let zero = wide::splat(0.0);
    let inv_d = d.map(|d| {
        // Vec3::clamp is max, then min.
        let inv = wide::div(one, d);
        wide::min(wide::max(inv, wide::splat(-FLT_MAX)), wide::splat(FLT_MAX))
    });
    let negative = inv_d.map(|i| wide::cmp::<_CMP_LT_OQ>(i, zero));
    // ray_shear: kz the largest |d| component, x before y before z on
    // ties as its comparisons decide; kx, ky the next two, swapped when
    // d[kz] < 0.
    let abs = [wide::abs(d[0]), wide::abs(d[1]), wide::abs(d[2])];
    let x_over_y = wide::cmp::<_CMP_GT_OQ>(abs[0], abs[1]);
    let z_is_x = wide::and(x_over_y, wide::cmp::<_CMP_GT_OQ>(abs[0], abs[2]));
    let z_is_y = wide::and_not(x_over_y, wide::cmp::<_CMP_GT_OQ>(abs[1], abs[2]));
    let dz = pick(d, z_is_x, z_is_y);
    let swap = wide::cmp::<_CMP_LT_OQ>(dz, zero);
    let z_is_z = wide::not(wide::or(z_is_x, z_is_y));
    // Before the swap: kz x gives (y, z), kz y gives (z, x), kz z (x, y).
    let (first_is_x, first_is_y) = (z_is_z, z_is_x);
    let (second_is_x, second_is_y) = (z_is_y, z_is_z);
    let choose = |m: Mask, a: Mask, b: Mask| wide::or(wide::and(m, a), wide::and_not(m, b));
    let kx_is_x = choose(swap, second_is_x, first_is_x);
    let kx_is_y = choose(swap, second_is_y, first_is_y);
    let ky_is_x = choose(swap, first_is_x, second_is_x);
    let ky_is_y = choose(swap, first_is_y, second_is_y);
    let dx = pick(d, kx_is_x, kx_is_y);
    let dy = pick(d, ky_is_x, ky_is_y);
    Lanes {
        origin: o,
        inv_d,
        negative,
        axis: [(kx_is_x, kx_is_y), (ky_is_x, ky_is_y), (z_is_x, z_is_y)]
            .map(|(is_x, is_y)| wide::axis_index(is_x, is_y)),
        origin_along: [
            pick(o, kx_is_x, kx_is_y),
            pick(o, ky_is_x, ky_is_y),
            pick(o, z_is_x, z_is_y),
        ],
        shear: [wide::div(dx, dz), wide::div(dy, dz), wide::div(one, dz)],
    }
}

/// Each lane's hit so far (t_max and no triangle at first).
#[cfg(target_arch = "x86_64")]
struct Best {
    t: F,
    triangle: I,
    b1: F,
    b2: F,
}

#[cfg(target_arch = "x86_64")]
impl Best {
    /// t, triangle and barycentrics, lane by lane.
    #[inline]
    #[target_feature(enable = "avx2")]
    #[allow(clippy::type_complexity)]
    fn lanes(&self) -> ([f32; WIDTH], [u32; WIDTH], [f32; WIDTH], [f32; WIDTH]) {
        let mut t = [0f32; WIDTH];
        let mut triangle = [0u32; WIDTH];
        let (mut b1, mut b2) = ([0f32; WIDTH], [0f32; WIDTH]);
        wide::store(&mut t, self.t);
        wide::store_i(&mut triangle, self.triangle);
        wide::store(&mut b1, self.b1);
        wide::store(&mut b2, self.b2);
        (t, triangle, b1, b2)
    }
}

/// The traversal: nodes from a stack, nearest first for the lowest active
/// lane's octant (any order finds the same hits; this one finds them
/// soonest); a node's leaf triangles are tested when the node is visited.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
fn traverse(scene: &CpuScene, lanes: &Lanes, rays: &Rays, any_hit: bool, best: &mut Best) {
    let nodes = scene.tight_nodes();
    // A node pushes at most its eight children, and `order_free` bounds
    // the depth by BVH_STACK_SIZE.
    const STACK: usize = 8 * BVH_STACK_SIZE as usize;
    // Uninitialized: zeroing 16 KiB per packet would cost more than most
    // traversals; an entry is read only after it is written.
    let mut stack = [const { MaybeUninit::<Pending>::uninit() }; STACK];
    stack[0].write(Pending {
        t_enter: wide::splat(0.0),
        node: 0,
        rays: rays.active,
    });
    let mut sp = 1usize;
    let mut alive = rays.active;
    let widen = wide::splat(1.000_000_4);
    while sp > 0 {
        sp -= 1;
        // SAFETY: entries below sp were written (pushes write, pops lower).
        let entry = unsafe { stack[sp].assume_init() };
        // Rays that have since found a hit nearer than the box drop out,
        // with the node test's own comparison.
        let near_enough = wide::cmp::<_CMP_LE_OQ>(entry.t_enter, wide::mul(best.t, widen));
        let reach = entry.rays & alive & wide::bits(near_enough);
        if reach == 0 {
            continue;
        }
        let n = &nodes[entry.node as usize];
        let imask = n.e_imask >> 24;
        // Too few rays left to share the node's tests: each goes on alone,
        // where a subtree lies below (inner children). Below a node of
        // leaves only, the packet's own tests cost less than handing the
        // ray over (the Cornell box: +3 %).
        if reach.count_ones() <= ALONE && imask != 0 {
            alive &= !alone(scene, entry.node, reach, rays, lanes, any_hit, best);
            if alive == 0 {
                return;
            }
            continue;
        }
        let leader = reach.trailing_zeros() as usize;
        // obvhs' octant bits of the leading ray: a bit per positive axis.
        let oct = (0..3).fold(0u32, |acc, axis| {
            acc | (((lanes_negative_bit(lanes, axis, leader)) ^ 1) << (2 - axis))
        });
        let mut child_rays = [0u32; 8];
        let mut child_enter = [wide::splat(0.0); 8];
        for slot in 0..8 {
            let meta = (n.child_meta[slot / 4] >> (8 * (slot % 4))) & 0xFF;
            if meta == 0 {
                continue;
            }
            let (t_enter, hit) = child_box(n, slot, lanes, best.t);
            child_rays[slot] = reach & wide::bits(hit);
            child_enter[slot] = t_enter;
        }
        // Leaves first, nearest first; then the inner children pushed so
        // that the nearest is popped first (the slot order is by octant:
        // trace_ray takes the highest slot ^ oct first).
        for j in (0..8u32).rev() {
            let slot = (j ^ oct) as usize;
            let rays_here = child_rays[slot] & alive;
            if rays_here == 0 || imask & (1 << slot) != 0 {
                continue;
            }
            let meta = (n.child_meta[slot / 4] >> (8 * (slot % 4))) & 0xFF;
            let first = n.primitive_base_idx + (meta & 31);
            let mut here = wide::from_bits(rays_here);
            for i in first..first + (meta >> 5).count_ones() {
                let h = triangle_hits(scene, i, lanes);
                let done = take(scene, i, &h, rays, here, any_hit, best);
                // Only an any-hit query ends lanes, and rarely: a
                // predictable branch.
                if done != 0 {
                    alive &= !done;
                    if alive == 0 {
                        return;
                    }
                    here = wide::from_bits(rays_here & alive);
                }
            }
        }
        for j in 0..8u32 {
            let slot = (j ^ oct) as usize;
            if child_rays[slot] == 0 || imask & (1 << slot) == 0 {
                continue;
            }
            let node = n.child_base_idx + (imask & ((1 << slot) - 1)).count_ones();
            stack[sp].write(Pending {
                t_enter: child_enter[slot],
                node,
                rays: child_rays[slot],
            });
            sp += 1;
        }
    }
}

/// Rays that reach a node with inner children no more than this many, they
/// traverse its subtree one at a time: a packet's tests cost about as much
/// for one ray as for all. Measured: one of eight; three of sixteen
/// (cornell-spheres -6 % against one, the Cornell box level).
const ALONE: u32 = if WIDTH == 16 { 3 } else { 1 };

/// `bvh::trace_ray` through the subtree of `node` for each lane in `reach`,
/// from the lane's hit so far. Returns the lanes that found a hit when
/// `any_hit` (they are done), else 0. Each ray goes on with the packet's
/// values for it (inverse direction, axes, origin along them and shear:
/// the single ray's own, by the same operations), not worked out again.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
fn alone(
    scene: &CpuScene,
    node: u32,
    reach: u32,
    rays: &Rays,
    lanes: &Lanes,
    any_hit: bool,
    best: &mut Best,
) -> u32 {
    // Each lane's values straight from the registers: stored to arrays
    // and read back a float at a time, the reads wait for the stores.
    let mut done = 0;
    let mut left = reach;
    while left != 0 {
        let l = left.trailing_zeros() as usize;
        left &= left - 1;
        let so_far = Hit {
            t: wide::lane(best.t, l),
            triangle: wide::lane_i(best.triangle, l),
            b12: Vec2::new(wide::lane(best.b1, l), wide::lane(best.b2, l)),
        };
        let ray = super::leaf_window::WindowRay::from_parts(
            lanes.axis.map(|k| wide::lane_i(k, l) as usize),
            lanes.origin_along.map(|c| wide::lane(c, l)),
            lanes.shear.map(|c| wide::lane(c, l)),
        );
        let [x, y, z] = lanes.inv_d.map(|c| wide::lane(c, l));
        // SAFETY: AVX2 and the bit instructions (this function's own).
        let hit = unsafe {
            super::nearest_first::trace_ray_nearest_first_with(
                scene,
                rays.origin(l),
                Vec3::new(x, y, z),
                &ray,
                any_hit,
                rays.coverage_seed[l],
                node,
                so_far,
            )
        };
        best.t = wide::with_lane(best.t, l, hit.t);
        best.triangle = wide::with_lane_i(best.triangle, l, hit.triangle);
        best.b1 = wide::with_lane(best.b1, l, hit.b12.x);
        best.b2 = wide::with_lane(best.b2, l, hit.b12.y);
        if any_hit && hit.triangle != NO_HIT {
            done |= 1 << l;
        }
    }
    done
}

/// 1 where lane `lane`'s inverse direction along `axis` is negative.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn lanes_negative_bit(lanes: &Lanes, axis: usize, lane: usize) -> u32 {
    (wide::bits(lanes.negative[axis]) >> lane) & 1
}

/// `bvh::child_hit_bits`' slab test of child `slot` for every lane, at each
/// lane's nearest hit so far: (the entry distances, the lanes that hit).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn child_box(
    n: &super::cache::node_planes::DecodedNode,
    slot: usize,
    lanes: &Lanes,
    t_max: F,
) -> (F, Mask) {
    let slabs = |axis: usize| {
        let lo = wide::splat(n.lo[axis][slot]);
        let hi = wide::splat(n.hi[axis][slot]);
        let near = wide::blend(lanes.negative[axis], hi, lo);
        let far = wide::blend(lanes.negative[axis], lo, hi);
        let o = lanes.origin[axis];
        let inv_d = lanes.inv_d[axis];
        (
            wide::mul(wide::sub(near, o), inv_d),
            wide::mul(wide::sub(far, o), inv_d),
        )
    };
    let (nx, fx) = slabs(0);
    let (ny, fy) = slabs(1);
    let (nz, fz) = slabs(2);
    // Without NaNs (the inverse direction is clamped finite) max and min
    // are exact and order-free: the same values as the scalar chain.
    let t_enter = wide::max(wide::max(nx, ny), wide::max(nz, wide::splat(0.0)));
    let t_exit = wide::mul(
        wide::min(wide::min(fx, fy), wide::min(fz, t_max)),
        wide::splat(1.000_000_4),
    );
    (t_enter, wide::cmp::<_CMP_LE_OQ>(t_enter, t_exit))
}

/// Component k of a vertex for each lane: x, y or z as the lane's axis
/// masks say.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn pick(c: [F; 3], is_x: Mask, is_y: Mask) -> F {
    wide::blend(is_x, c[0], wide::blend(is_y, c[1], c[2]))
}

/// `intersect::triangle_hit` of one triangle for every lane: t and the
/// barycentrics, and the lanes hit in front of their origin.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct TriangleHits {
    t: F,
    b1: F,
    b2: F,
    hit: Mask,
}

/// `intersect::triangle_hit` of triangle `i` for every lane, with the
/// lane's own axes and shear.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn triangle_hits(scene: &CpuScene, i: u32, lanes: &Lanes) -> TriangleHits {
    let tv = &scene.tri_verts[i as usize];
    // (vertex - origin) along the lane's axes kx, ky, kz: the vertex's
    // component picked per lane by a permute of (x, y, z, and the u32 that
    // follows it in `TriangleVerts`, never picked), minus the origin's.
    let relative = |vertex: usize| {
        // SAFETY: `TriangleVerts` is repr(C), each vertex three f32 and a
        // u32: four floats from the vertex's x lie inside the struct.
        let p = unsafe { std::ptr::from_ref(tv).cast::<f32>().add(4 * vertex) };
        // SAFETY: as above.
        [0, 1, 2].map(|k| {
            wide::sub(
                unsafe { wide::gather_axis(p, lanes.axis[k]) },
                lanes.origin_along[k],
            )
        })
    };
    let [a, b, c] = [relative(0), relative(1), relative(2)];
    let [sx, sy, sz] = lanes.shear;
    let sheared = |p: [F; 3]| {
        (
            wide::sub(p[0], wide::mul(sx, p[2])),
            wide::sub(p[1], wide::mul(sy, p[2])),
        )
    };
    let ((ax, ay), (bx, by), (cx, cy)) = (sheared(a), sheared(b), sheared(c));
    let u = cross2(cx, by, cy, bx);
    let v = cross2(ax, cy, ay, cx);
    let w = cross2(bx, ay, by, ax);
    let zero = wide::splat(0.0);
    let below = any_sign::<_CMP_LT_OQ>(u, v, w);
    let above = any_sign::<_CMP_GT_OQ>(u, v, w);
    let det = wide::add(wide::add(u, v), w);
    let tt = wide::add(
        wide::add(
            wide::mul(u, wide::mul(sz, a[2])),
            wide::mul(v, wide::mul(sz, b[2])),
        ),
        wide::mul(w, wide::mul(sz, c[2])),
    );
    let missed = wide::or(
        wide::or(wide::and(below, above), wide::cmp::<_CMP_EQ_OQ>(det, zero)),
        behind_origin(det, tt),
    );
    let inv_det = wide::div(wide::splat(1.0), det);
    TriangleHits {
        t: wide::mul(tt, inv_det),
        b1: wide::mul(v, inv_det),
        b2: wide::mul(w, inv_det),
        hit: wide::not(missed),
    }
}

/// Triangle `i`'s hits taken by the lanes of `here` (all ones in each)
/// where `bvh::nearer_hit` (and its alpha test) says so. Returns the lanes
/// that took it when `any_hit` (they are done), else 0.
///
/// Without an alpha test the hits are blended in whether or not a lane
/// takes one: a branch on "some lane took it" mispredicted about as often
/// as not, and the blend of no lane changes nothing.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn take(
    scene: &CpuScene,
    i: u32,
    h: &TriangleHits,
    rays: &Rays,
    here: Mask,
    any_hit: bool,
    best: &mut Best,
) -> u32 {
    // nearer_hit: t < best, or the same t and a lower index than a hit
    // (no hit is NO_HIT, -1 as a signed lane: never above i).
    let index = wide::splat_i(i as i32);
    let lower_index = wide::gt_i(best.triangle, index);
    let nearer = wide::or(
        wide::cmp::<_CMP_LT_OQ>(h.t, best.t),
        wide::and(wide::cmp::<_CMP_EQ_OQ>(h.t, best.t), lower_index),
    );
    let mut mask = wide::and(wide::and(h.hit, nearer), here);
    // A MASK or BLEND triangle is hit only where its alpha test passes.
    let tv = &scene.tri_verts[i as usize];
    if tv.alpha_mask != 0 {
        let mut taken = wide::bits(mask);
        if taken == 0 {
            return 0;
        }
        let (mut u1, mut u2) = ([0f32; WIDTH], [0f32; WIDTH]);
        wide::store(&mut u1, h.b1);
        wide::store(&mut u2, h.b2);
        for l in 0..WIDTH {
            if taken & (1 << l) != 0
                && !alpha_test_passes(
                    scene,
                    tv.material,
                    i,
                    Vec2::new(u1[l], u2[l]),
                    rays.coverage_seed[l],
                )
            {
                taken &= !(1 << l);
            }
        }
        mask = wide::from_bits(taken);
    }
    best.t = wide::blend(mask, h.t, best.t);
    best.b1 = wide::blend(mask, h.b1, best.b1);
    best.b2 = wide::blend(mask, h.b2, best.b2);
    best.triangle = wide::blend_i(mask, index, best.triangle);
    if any_hit { wide::bits(mask) } else { 0 }
}
