//! A single ray against a node's leaf triangles a register at a time
//! (`wide::WIDTH`: sixteen with AVX-512, eight with AVX2), for the order-free
//! traversal (`nearest_first`): `octant::intersect_triangles`' watertight
//! test, the same f32 operations in the same order in each lane, on blocks
//! of `WIDTH` triangles (`CpuScene::window_blocks`). Sixteen at a time,
//! a node's up to 24 leaf triangles take one or two tests instead of one
//! to three (cornell-spheres: 1.01 windows per node with leaves hit,
//! against 1.24 of eight).
//!
//! # Safety
//! As `wide`'s: only where the CPU has the width's instructions
//! (`octant::available`).

use super::cache::CpuScene;
use super::cache::triangle_blocks::WindowBlock;
use super::wide::{self, F, WIDTH};
use crate::cpu::common::bvh::{Hit, nearer_hit};
use crate::cpu::common::intersect::RayShear;
use crate::cpu::common::textures::alpha_test_passes;
use glam::{Vec2, Vec3};
use std::arch::x86_64::{_CMP_EQ_OQ, _CMP_GE_OQ, _CMP_GT_OQ, _CMP_LE_OQ, _CMP_LT_OQ, _CMP_NLE_UQ};

/// What the test needs of one ray, broadcast: its origin along its permuted
/// axes and its shear (`intersect::RayShear`), worked out once per ray.
#[derive(Clone, Copy)]
pub struct WindowRay {
    /// `RayShear::k`, each below 3 (checked by `from_parts`).
    k: [usize; 3],
    origin: [F; 3],
    shear: [F; 3],
}

impl WindowRay {
    /// The ray from `o` with shear `r`.
    ///
    /// # Safety
    /// The CPU must support AVX2 (`octant::available`).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn new(o: Vec3, r: &RayShear) -> WindowRay {
        let [kx, ky, kz] = r.k;
        // From an array: `Vec3`'s indexing is a branch per axis.
        let o = o.to_array();
        WindowRay::from_parts(r.k, [o[kx], o[ky], o[kz]], r.s.to_array())
    }

    /// The ray whose axes are `k` (each below 3, checked), its origin's
    /// components along them `origin_along` and its shear `shear`.
    ///
    /// # Safety
    /// The CPU must support AVX2 (`octant::available`).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn from_parts(k: [usize; 3], origin_along: [f32; 3], shear: [f32; 3]) -> WindowRay {
        assert!(k.iter().all(|&k| k < 3), "ray shear axes {k:?}");
        WindowRay {
            k,
            origin: [0, 1, 2].map(|a| wide::splat(origin_along[a])),
            shear: [0, 1, 2].map(|a| wide::splat(shear[a])),
        }
    }
}

/// The lanes of a window hit in front of the origin no farther than the
/// t_max they were tested at, and their distances and barycentrics.
pub struct WindowHits {
    pub candidates: u32,
    pub t: [f32; WIDTH],
    pub b1: [f32; WIDTH],
    pub b2: [f32; WIDTH],
}

/// Coordinate row `c` (3 * vertex + axis) of the block, less the origin's
/// component `o` along that axis.
///
/// # Safety
/// `c < 9`.
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn relative(block: &WindowBlock, c: usize, o: F) -> F {
    // SAFETY: c < 9 (the caller's promise).
    wide::sub(wide::load(unsafe { block.coords.get_unchecked(c) }), o)
}

/// One sheared vertex of the window's triangles (Woop et al.'s x, y, z).
#[inline]
#[target_feature(enable = "avx2")]
fn sheared_vertex(block: &WindowBlock, vertex: usize, ray: &WindowRay) -> [F; 3] {
    let [kx, ky, kz] = ray.k;
    let (o, s) = (ray.origin, ray.shear);
    // SAFETY: vertex < 3 and every k < 3 (`WindowRay::from_parts`).
    let (x, y, z) = unsafe {
        (
            relative(block, 3 * vertex + kx, o[0]),
            relative(block, 3 * vertex + ky, o[1]),
            relative(block, 3 * vertex + kz, o[2]),
        )
    };
    [
        wide::sub(x, wide::mul(s[0], z)),
        wide::sub(y, wide::mul(s[1], z)),
        wide::mul(s[2], z),
    ]
}

/// p q - r s per lane: an edge function of the sheared vertices.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) fn cross2(p: F, q: F, r: F, s: F) -> F {
    wide::sub(wide::mul(p, q), wide::mul(r, s))
}

/// The watertight test of the block's triangles for the lanes set in
/// `lanes`, at `t_max` (`octant::intersect_triangles`, WIDTH lanes). Lanes
/// not set are computed on whatever the block holds there and never
/// reported.
///
/// # Safety
/// The CPU must support AVX2 (`octant::available`).
#[inline]
#[target_feature(enable = "avx2")]
pub fn intersect_window(
    block: &WindowBlock,
    lanes: u32,
    ray: &WindowRay,
    t_max: f32,
) -> WindowHits {
    let [ax, ay, az] = sheared_vertex(block, 0, ray);
    let [bx, by, bz] = sheared_vertex(block, 1, ray);
    let [cx, cy, cz] = sheared_vertex(block, 2, ray);
    let u = cross2(cx, by, cy, bx);
    let v = cross2(ax, cy, ay, cx);
    let w = cross2(bx, ay, by, ax);
    let zero = wide::splat(0.0);
    let outside = wide::and(
        any_sign::<_CMP_LT_OQ>(u, v, w),
        any_sign::<_CMP_GT_OQ>(u, v, w),
    );
    let det = wide::add(wide::add(u, v), w);
    let tt = wide::add(
        wide::add(wide::mul(u, az), wide::mul(v, bz)),
        wide::mul(w, cz),
    );
    // In front of the origin (tt has det's sign), then t itself against
    // t_max, as `triangle_hit` and `nearer_hit` compute them.
    let behind = behind_origin(det, tt);
    let inv_det = wide::div(wide::splat(1.0), det);
    let t = wide::mul(tt, inv_det);
    let rejected = wide::or(
        wide::or(outside, wide::cmp::<_CMP_EQ_OQ>(det, zero)),
        wide::or(behind, wide::cmp::<_CMP_NLE_UQ>(t, wide::splat(t_max))),
    );
    let mut out = WindowHits {
        candidates: lanes & !wide::bits(rejected),
        t: [0.0; WIDTH],
        b1: [0.0; WIDTH],
        b2: [0.0; WIDTH],
    };
    if out.candidates != 0 {
        wide::store(&mut out.t, t);
        wide::store(&mut out.b1, wide::mul(v, inv_det));
        wide::store(&mut out.b2, wide::mul(w, inv_det));
    }
    out
}

/// Lanes where any of the three is below (`_CMP_LT_OQ`) or above zero.
#[inline]
#[target_feature(enable = "avx2")]
pub(super) fn any_sign<const PREDICATE: i32>(u: F, v: F, w: F) -> wide::Mask {
    let zero = wide::splat(0.0);
    wide::or(
        wide::or(
            wide::cmp::<PREDICATE>(u, zero),
            wide::cmp::<PREDICATE>(v, zero),
        ),
        wide::cmp::<PREDICATE>(w, zero),
    )
}

/// Lanes whose hit lies behind the ray's origin: tt without det's sign
/// (`octant::behind_origin` per lane, without dividing).
#[inline]
#[target_feature(enable = "avx2")]
pub(super) fn behind_origin(det: F, tt: F) -> wide::Mask {
    let zero = wide::splat(0.0);
    wide::or(
        wide::and(
            wide::cmp::<_CMP_LT_OQ>(det, zero),
            wide::cmp::<_CMP_GE_OQ>(tt, zero),
        ),
        wide::and(
            wide::cmp::<_CMP_GT_OQ>(det, zero),
            wide::cmp::<_CMP_LE_OQ>(tt, zero),
        ),
    )
}

/// A node's leaf triangles `group` = (primitive_base_idx, one bit per
/// triangle offset, the node's first window block) against the ray, in
/// windows of `WIDTH` from the last; the nearest hit into `hit`. Returns
/// true when `any_hit` and one was found.
///
/// # Safety
/// The CPU must support AVX2 and the bit instructions
/// (`octant::available`).
#[inline]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
#[allow(clippy::too_many_arguments)]
pub fn intersect_leaves(
    scene: &CpuScene,
    group: [u32; 3],
    blocks: &[WindowBlock],
    ray: &WindowRay,
    any_hit: bool,
    coverage_seed: u32,
    hit: &mut Hit,
) -> bool {
    const WINDOWS: u32 = 24u32.div_ceil(WIDTH as u32);
    const ALL_LANES: u32 = (1 << WIDTH) - 1;
    for w in (0..WINDOWS).rev() {
        let lanes = (group[1] >> (WIDTH as u32 * w)) & ALL_LANES;
        if lanes == 0 {
            continue;
        }
        let first = group[0] + WIDTH as u32 * w;
        let l = intersect_window(&blocks[(group[2] + w) as usize], lanes, ray, hit.t);
        let mut candidates = l.candidates;
        while candidates != 0 {
            let lane = 31 - candidates.leading_zeros();
            candidates &= !(1 << lane);
            let i = first + lane;
            let t = l.t[lane as usize];
            if !nearer_hit(t, i, hit) {
                continue;
            }
            let b12 = Vec2::new(l.b1[lane as usize], l.b2[lane as usize]);
            let tv = &scene.tri_verts[i as usize];
            if tv.alpha_mask != 0 && !alpha_test_passes(scene, tv.material, i, b12, coverage_seed) {
                continue;
            }
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
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::common::bvh::NO_HIT;
    use crate::cpu::common::intersect::{ray_shear, triangle_hit};
    use crate::cpu::common::rng::pcg_hash;
    use crate::packed::layout::TriangleVerts;

    /// Random triangles and rays, aimed at vertices and edges half the
    /// time: each lane of the window test gives exactly the scalar test's
    /// hit (`intersect::triangle_hit`, `bvh::nearer_hit`), at either width.
    #[test]
    fn window_test_equals_the_scalar_one_bit_for_bit() {
        if !super::super::octant::available() {
            println!("no AVX2 on this CPU: the window test is not used");
            return;
        }
        let state = std::cell::Cell::new(19u32);
        let unit = || {
            state.set(pcg_hash(state.get()));
            state.get() as f32 / u32::MAX as f32
        };
        let point = || Vec3::new(unit(), unit(), unit()) * 2.0 - 1.0;
        let (mut differing, mut hits) = (0, 0);
        // Twenty thousand windows of sixteen or forty thousand of eight.
        for case in 0..(320_000 / WIDTH as u32) {
            let tris: Vec<TriangleVerts> = (0..WIDTH)
                .map(|_| TriangleVerts {
                    v0: point().into(),
                    v1: point().into(),
                    v2: point().into(),
                    ..Default::default()
                })
                .collect();
            let o = point() * 3.0;
            let aimed = &tris[case as usize % WIDTH];
            let target = match case % 4 {
                0 => Vec3::from(aimed.v0),
                1 => (Vec3::from(aimed.v1) + Vec3::from(aimed.v2)) * 0.5,
                _ => point(),
            };
            let d = (target - o).normalize();
            let r = ray_shear(d);
            let t_max = if case % 3 == 0 {
                f32::MAX
            } else {
                unit() * 6.0
            };
            let lanes = pcg_hash(case) & ((1 << WIDTH) - 1);
            // The hit so far: none, or triangle 3 at t_max, so that hits at
            // exactly t_max are taken by lower indices only.
            let so_far = Hit {
                t: t_max,
                triangle: if case % 2 == 0 { NO_HIT } else { 3 },
                b12: Vec2::ZERO,
            };
            let block = WindowBlock::new(&tris, 0);
            // SAFETY: AVX2 is available (checked above).
            let l = unsafe { intersect_window(&block, lanes, &WindowRay::new(o, &r), t_max) };
            for (lane, tv) in tris.iter().enumerate() {
                if lanes & (1 << lane) == 0 {
                    continue;
                }
                let i = lane as u32;
                let scalar = triangle_hit(o, &r, tv.v0.into(), tv.v1.into(), tv.v2.into())
                    .filter(|&(t, _)| nearer_hit(t, i, &so_far));
                let window = (l.candidates & (1 << lane) != 0 && nearer_hit(l.t[lane], i, &so_far))
                    .then(|| (l.t[lane], Vec2::new(l.b1[lane], l.b2[lane])));
                let same = match (scalar, window) {
                    (None, None) => true,
                    (Some((t0, b0)), Some((t1, b1))) => {
                        t0.to_bits() == t1.to_bits()
                            && b0.x.to_bits() == b1.x.to_bits()
                            && b0.y.to_bits() == b1.y.to_bits()
                    }
                    _ => false,
                };
                differing += !same as u32;
                hits += scalar.is_some() as u32;
            }
        }
        assert_eq!(differing, 0, "lanes that differ from the scalar test");
        assert!(hits > 10_000, "only {hits} hits: the test exercises little");
    }
}
