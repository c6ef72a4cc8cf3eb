//! The lane schedule's light BVH walks with AVX2, on the CPU's own copy of
//! the tree (`cache::light_tree_steps`): each step's four candidates come
//! from one aligned record instead of six nodes' scattered fields, and
//! every lane's walk takes its steps together (`sample_lanes_avx2`). The
//! floats and choices are the twin's (`common::light_bvh`), to the bit:
//! `light_tree_importance_quad` and `light_tree_choose_lane` for all lanes
//! at once. Other walks (one path at a time, MIS's pmf) are the twin's.

// Loops over lane indices are the point here: each iteration is one lane.
#![allow(clippy::needless_range_loop)]

use super::cache::CpuScene;
use super::cache::light_tree_steps::{AT_LEAF, LightTreeStep, step_of};
use super::simd::{Bools, Floats, WIDTH, and, or, select, select_mask};
use crate::constants::{LIGHT_TREE_MAX_DEPTH, LIGHT_TREE_MIN_COS_I};
use crate::cpu::common::light_bvh::light_tree_sample_many;
use glam::{BVec4A, Vec3, Vec4};
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// The lane schedule's walks: `sample_lanes_avx2` where `AVX2`, the
/// twin's `light_tree_sample_many` elsewhere; the same leaves and
/// probabilities.
///
/// # Safety
/// `AVX2` only where the CPU supports AVX2.
#[inline(always)]
pub unsafe fn sample_lanes<const AVX2: bool>(
    scene: &CpuScene,
    p: &[Vec3; WIDTH],
    nrm: &[Vec3; WIDTH],
    u: &[f32; WIDTH],
    active: &[bool; WIDTH],
) -> ([u32; WIDTH], [f32; WIDTH]) {
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: the caller's.
        return unsafe { sample_lanes_avx2(scene, p, nrm, u, active) };
    }
    light_tree_sample_many(scene, p, nrm, u, active)
}

/// `sample_many` with AVX2, every lane's walk a step at a time together:
/// the importances of two lanes' four candidates fill one 256-bit
/// register (`importance_pair`), and the choices are made for all lanes at
/// once with selects, so that no lane's coin flip is a branch that stalls
/// the others. The same float operations in the same order as the twin's
/// `light_tree_importance_quad` and `light_tree_choose_lane`, so the same
/// leaves and the same bits (`tests/suite/light_bvh.rs`).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub unsafe fn sample_lanes_avx2(
    scene: &CpuScene,
    p: &[Vec3; WIDTH],
    nrm: &[Vec3; WIDTH],
    u: &[f32; WIDTH],
    active: &[bool; WIDTH],
) -> ([u32; WIDTH], [f32; WIDTH]) {
    let steps = scene.light_tree_steps();
    let root_step = step_of(&scene.light_tree.nodes[0]);
    let mut node = [0u32; WIDTH];
    let mut step = [AT_LEAF; WIDTH];
    let mut pmf = Floats::splat(0.0);
    for l in 0..WIDTH {
        if active[l] {
            step[l] = root_step;
            pmf.0[l] = 1.0;
        }
    }
    let mut u = Floats(*u);
    let pairs = pair_points(p, nrm);
    let (zero, one) = (Floats::splat(0.0), Floats::splat(1.0));
    let below_one = Floats::splat(0.999_999_94);
    for _ in 0..LIGHT_TREE_MAX_DEPTH {
        let walking: Bools = std::array::from_fn(|l| step[l] != AT_LEAF);
        if !walking.contains(&true) {
            break;
        }
        // Lanes that do not walk read step 0 and keep their state.
        let rec: [&LightTreeStep; WIDTH] =
            std::array::from_fn(|l| &steps[if walking[l] { step[l] as usize } else { 0 }]);
        let mut q = [0.0f32; 4 * WIDTH];
        for k in 0..WIDTH / 2 {
            let imp = unsafe { importance_pair(rec[2 * k], rec[2 * k + 1], &pairs[k]) };
            unsafe { _mm256_storeu_ps(q.as_mut_ptr().add(8 * k), imp) };
        }
        let slot = |j: usize| Floats(std::array::from_fn(|l| q[4 * l + j]));
        let (q0, q1, q2, q3) = (slot(0), slot(1), slot(2), slot(3));
        let leaf_a: Bools = std::array::from_fn(|l| !rec[l].counts.test(1));
        let leaf_b: Bools = std::array::from_fn(|l| !rec[l].counts.test(3));
        // light_tree_choose_lane, both sides of each choice.
        let ia = q0 + q1;
        let ib = q2 + q3;
        let total = ia + ib;
        let reached = total.gt(zero);
        let pa = ia / total;
        let pb = ib / total;
        let first = u.lt(pa);
        u = select(
            first,
            (u / pa).min(below_one),
            ((u - pa) / (one - pa)).min(below_one),
        );
        let side_pmf = select(first, pa, pb);
        let leaf_side = select_mask(first, leaf_a, leaf_b);
        let i0 = select(first, q0, q2);
        let i1 = select(first, q1, q3);
        let t = i0 + i1;
        let p0 = i0 / t;
        let p1 = i1 / t;
        let first2 = u.lt(p0);
        let u2 = select(
            first2,
            (u / p0).min(below_one),
            ((u - p0) / (one - p0)).min(below_one),
        );
        let step_pmf = select(leaf_side, side_pmf, side_pmf * select(first2, p0, p1));
        u = select(leaf_side, u, u2);
        let ok = and(reached, or(leaf_side, t.gt(zero)));
        let taken = and(walking, ok);
        pmf = select(taken, pmf * step_pmf, select(walking, zero, pmf));
        for l in 0..WIDTH {
            if !walking[l] {
                continue;
            }
            if !ok[l] {
                step[l] = AT_LEAF;
                continue;
            }
            let c = 2 * usize::from(!first[l]) + usize::from(!leaf_side[l] && !first2[l]);
            node[l] = rec[l].node[c];
            step[l] = rec[l].next[c];
        }
    }
    for l in 0..WIDTH {
        if step[l] != AT_LEAF {
            pmf.0[l] = 0.0;
        }
    }
    (node, pmf.0)
}

/// Two lanes' shading points and normals for `importance_pair`: each
/// coordinate four times for the first lane, then four for the second;
/// `has_normal` all ones in a half whose lane has a normal.
#[cfg(target_arch = "x86_64")]
struct PairPoints {
    p: [__m256; 3],
    n: [__m256; 3],
    has_normal: __m256,
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn pair_points(p: &[Vec3; WIDTH], nrm: &[Vec3; WIDTH]) -> [PairPoints; WIDTH / 2] {
    let two = |a: f32, b: f32| _mm256_set_ps(b, b, b, b, a, a, a, a);
    std::array::from_fn(|k| {
        let (a, b) = (2 * k, 2 * k + 1);
        let has = |l: usize| {
            if nrm[l] != Vec3::ZERO {
                f32::from_bits(!0)
            } else {
                0.0
            }
        };
        PairPoints {
            p: [
                two(p[a].x, p[b].x),
                two(p[a].y, p[b].y),
                two(p[a].z, p[b].z),
            ],
            n: [
                two(nrm[a].x, nrm[b].x),
                two(nrm[a].y, nrm[b].y),
                two(nrm[a].z, nrm[b].z),
            ],
            has_normal: two(has(a), has(b)),
        }
    })
}

/// `light_tree_importance_quad` of two steps' quads at once, `a`'s four
/// candidates in the low half and `b`'s in the high half, those that do
/// not count (`LightTreeStep::counts`) zero: glam's SSE operations at
/// twice the width, so the same floats.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn importance_pair(a: &LightTreeStep, b: &LightTreeStep, at: &PairPoints) -> __m256 {
    let two = |x: &Vec4, y: &Vec4| {
        _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(__m128::from(*x)), __m128::from(*y))
    };
    let mask = |x: BVec4A, y: BVec4A| {
        _mm256_insertf128_ps::<1>(_mm256_castps128_ps256(__m128::from(x)), __m128::from(y))
    };
    let (qa, qb) = (&a.quad, &b.quad);
    let zero = _mm256_setzero_ps();
    let one = _mm256_set1_ps(1.0);
    let (add, sub, mul) = (_mm256_add_ps, _mm256_sub_ps, _mm256_mul_ps);
    let sel = |m: __m256, x: __m256, y: __m256| _mm256_blendv_ps(y, x, m);
    let dpx = sub(at.p[0], two(&qa.centre[0], &qb.centre[0]));
    let dpy = sub(at.p[1], two(&qa.centre[1], &qb.centre[1]));
    let dpz = sub(at.p[2], two(&qa.centre[2], &qb.centre[2]));
    let d2 = add(add(mul(dpx, dpx), mul(dpy, dpy)), mul(dpz, dpz));
    let inv_d = _mm256_div_ps(one, _mm256_sqrt_ps(d2));
    let (ax, ay, az) = (
        two(&qa.axis[0], &qb.axis[0]),
        two(&qa.axis[1], &qb.axis[1]),
        two(&qa.axis[2], &qb.axis[2]),
    );
    let mut cos_w = mul(add(add(mul(ax, dpx), mul(ay, dpy)), mul(az, dpz)), inv_d);
    let abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff));
    cos_w = sel(
        mask(qa.two_sided, qb.two_sided),
        _mm256_and_ps(cos_w, abs_mask),
        cos_w,
    );
    let sin_w = _mm256_sqrt_ps(_mm256_max_ps(sub(one, mul(cos_w, cos_w)), zero));
    let cos_o = two(&qa.cos_theta_o, &qb.cos_theta_o);
    let sin_o = two(&qa.sin_theta_o, &qb.sin_theta_o);
    let narrower = _mm256_cmp_ps::<_CMP_LT_OS>(cos_w, cos_o);
    let cos_x = sel(narrower, add(mul(cos_w, cos_o), mul(sin_w, sin_o)), one);
    let sin_x = sel(narrower, sub(mul(sin_w, cos_o), mul(cos_w, sin_o)), zero);
    let sin_b = mul(two(&qa.radius, &qb.radius), inv_d);
    let cos_b = _mm256_sqrt_ps(_mm256_max_ps(sub(one, mul(sin_b, sin_b)), zero));
    let cos_p = sel(
        _mm256_cmp_ps::<_CMP_LT_OS>(cos_x, cos_b),
        add(mul(cos_x, cos_b), mul(sin_x, sin_b)),
        one,
    );
    let dark = _mm256_cmp_ps::<_CMP_LE_OS>(cos_p, two(&qa.cos_theta_e, &qb.cos_theta_e));
    let [nx, ny, nz] = at.n;
    let cos_i = mul(
        _mm256_xor_ps(
            _mm256_set1_ps(-0.0),
            add(add(mul(nx, dpx), mul(ny, dpy)), mul(nz, dpz)),
        ),
        inv_d,
    );
    let sin_i = _mm256_sqrt_ps(_mm256_max_ps(sub(one, mul(cos_i, cos_i)), zero));
    let bounded = _mm256_max_ps(
        add(mul(cos_i, cos_b), mul(sin_i, sin_b)),
        _mm256_set1_ps(LIGHT_TREE_MIN_COS_I),
    );
    let cos_pi = sel(
        at.has_normal,
        sel(_mm256_cmp_ps::<_CMP_LT_OS>(cos_i, cos_b), bounded, one),
        one,
    );
    let power = two(&qa.power, &qb.power);
    let r2 = two(&qa.r2, &qb.r2);
    let lit = sel(
        dark,
        zero,
        mul(mul(mul(power, cos_p), cos_pi), mul(inv_d, inv_d)),
    );
    let imp = sel(
        _mm256_cmp_ps::<_CMP_GT_OS>(d2, r2),
        lit,
        _mm256_div_ps(power, r2),
    );
    sel(mask(a.counts, b.counts), imp, zero)
}
