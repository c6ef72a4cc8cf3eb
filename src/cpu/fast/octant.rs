//! The CPU back end's traversal with AVX2: `bvh::node_hit_bits` on all
//! eight children of a CWBVH node at once, the layout's purpose (Ylitie,
//! Karras, Laine 2017), and the watertight triangle test on up to eight
//! triangles of a node's leaves at once. The same f32 operations in the same
//! order per lane (no fused multiply-add), so every value is identical to
//! the scalar twins' (tested below) and the CPU keeps tracing the kernels'
//! paths. Machines without AVX2 use the scalar tests. The node test reads
//! the children's planes already decoded from the grid (`DecodedNode`).

use super::cache::CpuScene;
use super::cache::node_planes::DecodedNode;
use super::cache::triangle_blocks::TriangleBlock;
use super::cache::triangle_soa::TriangleSoa;
use crate::cpu::common::bvh::{
    Hit, NodeStep, RaySetup, StepTests, trace_instances_with, trace_ray_with,
};
use crate::cpu::common::intersect::{RayShear, ray_shear};
use crate::cpu::common::motion::motion_segment;
use crate::cpu::common::textures::alpha_test_passes;
use crate::packed::PackedScene;
use glam::Vec3;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Whether this CPU runs the AVX2 traversal: AVX2 and the bit instructions
/// that came with it (checked once, then cached).
pub fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("popcnt")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("bmi1")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Entry and exit distances of the eight slabs of one axis. The planes'
/// distances, (plane - origin) times the inverse direction, are ordered as
/// the planes are when the direction is positive and reversed when it is
/// negative (rounding is monotonic, and the inverse direction is finite),
/// so min and max pick exactly the near and far planes' distances without
/// a branch on the ray's sign, which a new ray's first nodes mispredict.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn axis_slabs(lo: &[f32; 8], hi: &[f32; 8], o: f32, inv_d: f32) -> (__m256, __m256) {
    let (o, inv_d) = (_mm256_set1_ps(o), _mm256_set1_ps(inv_d));
    // SAFETY: each array is eight floats, 32-byte aligned (`DecodedNode`).
    let (lo, hi) = unsafe { (_mm256_load_ps(lo.as_ptr()), _mm256_load_ps(hi.as_ptr())) };
    let t_lo = _mm256_mul_ps(_mm256_sub_ps(lo, o), inv_d);
    let t_hi = _mm256_mul_ps(_mm256_sub_ps(hi, o), inv_d);
    (_mm256_min_ps(t_lo, t_hi), _mm256_max_ps(t_lo, t_hi))
}

/// `bvh::node_hit_bits`, eight children at once, on the node with its
/// planes decoded (`DecodedNode`: the same plane values).
///
/// # Safety
/// The CPU must support AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub unsafe fn node_hit_bits(n: &DecodedNode, o: Vec3, inv_d: Vec3, t_max: f32, oct: u32) -> u32 {
    let (_, hit) = child_entries(n, o, inv_d, t_max);
    slot_bits(n, hit, oct)
}

/// The slab test of the eight children: each child's entry distance, and
/// the lanes whose box the ray enters no later than it leaves it and
/// `t_max` (`bvh::child_hit_bits`' test).
///
/// # Safety
/// The CPU must support AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub fn child_entries(n: &DecodedNode, o: Vec3, inv_d: Vec3, t_max: f32) -> (__m256, __m256) {
    let (nx, fx) = axis_slabs(&n.lo[0], &n.hi[0], o.x, inv_d.x);
    let (ny, fy) = axis_slabs(&n.lo[1], &n.hi[1], o.y, inv_d.y);
    let (nz, fz) = axis_slabs(&n.lo[2], &n.hi[2], o.z, inv_d.z);
    // Without NaNs (the inverse direction is clamped finite) max and min
    // are exact and order-free: the same values as the scalar chain.
    let t_enter = _mm256_max_ps(
        _mm256_max_ps(nx, ny),
        _mm256_max_ps(nz, _mm256_setzero_ps()),
    );
    let t_exit = _mm256_mul_ps(
        _mm256_min_ps(
            _mm256_min_ps(fx, fy),
            _mm256_min_ps(fz, _mm256_set1_ps(t_max)),
        ),
        _mm256_set1_ps(1.000_000_4),
    );
    (t_enter, _mm256_cmp_ps::<_CMP_LE_OQ>(t_enter, t_exit))
}

/// The node's hit bits for the children hit (`child_entries`): per slot,
/// as `bvh::child_hit_bits`, meta byte m, bit index (m & 31), XOR the
/// octant for inner children (m & 0x18 == 0x18), and (m >> 5) shifted
/// there; branch-free, then OR-ed over the slots that were hit.
///
/// # Safety
/// The CPU must support AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub fn slot_bits(n: &DecodedNode, hit: __m256, oct: u32) -> u32 {
    // SAFETY: `child_meta` is 8 readable bytes; an unaligned 64-bit load.
    let meta = _mm256_cvtepu8_epi32(unsafe { _mm_loadl_epi64(n.child_meta.as_ptr().cast()) });
    let inner = _mm256_cmpeq_epi32(
        _mm256_and_si256(meta, _mm256_set1_epi32(0x18)),
        _mm256_set1_epi32(0x18),
    );
    let index = _mm256_xor_si256(
        _mm256_and_si256(meta, _mm256_set1_epi32(31)),
        _mm256_and_si256(inner, _mm256_set1_epi32(oct as i32)),
    );
    let bits = _mm256_and_si256(
        _mm256_sllv_epi32(_mm256_srli_epi32::<5>(meta), index),
        _mm256_castps_si256(hit),
    );
    let half = _mm_or_si128(
        _mm256_castsi256_si128(bits),
        _mm256_extracti128_si256::<1>(bits),
    );
    let pair = _mm_or_si128(half, _mm_shuffle_epi32::<0b01_00_11_10>(half));
    _mm_cvtsi128_si32(_mm_or_si128(pair, _mm_shuffle_epi32::<0b10_11_00_01>(pair))) as u32
}

/// The watertight test for up to eight triangles: which hit in front of
/// the origin no farther than the t_max they were tested at, and their
/// distances and barycentrics.
#[derive(Clone, Copy, Debug, Default)]
pub struct TriangleLanes {
    /// Lanes whose triangle is hit at some t in (0, t_max]: a nearer hit
    /// found since can only reject more (see `accepts`).
    pub candidates: u32,
    pub t: [f32; 8],
    pub b1: [f32; 8],
    pub b2: [f32; 8],
}

impl TriangleLanes {
    /// Lane `lane`'s hit, `triangle_hit`'s values, when triangle `i` is
    /// nearer than `hit` (`bvh::nearer_hit`).
    pub fn accepts(&self, lane: usize, i: u32, hit: &Hit) -> Option<(f32, glam::Vec2)> {
        let t = self.t[lane];
        crate::cpu::common::bvh::nearer_hit(t, i, hit)
            .then(|| (t, glam::Vec2::new(self.b1[lane], self.b2[lane])))
    }
}

/// An octet: eight of a node's leaf triangles, tested in one AVX2 register by
/// the octant-order traversal (a leaf window, `leaf_window`, is a full
/// register of them). Where their coordinates are read: a still scene's block
/// (`TriangleBlock`), or a moving scene's arrays from triangle `first` at
/// `segment` (step, weight) between two time steps.
#[derive(Clone, Copy)]
pub enum Octet<'a> {
    Still(&'a TriangleBlock),
    Moving {
        tris: &'a TriangleSoa,
        first: usize,
        segment: (u32, f32),
    },
}

/// Coordinate vector `c` (3 * vertex + axis) of the octet's eight
/// triangles; in a moving scene a + (b - a) * w per lane as `motion_lerp`
/// computes it (no fused multiply-add). A function, not a closure: closures
/// do not inherit `target_feature`, and their intrinsics become calls.
///
/// # Safety
/// `c < 9`, and for a moving octet the eight floats from the last index
/// read are inside the arrays (`TriangleSoa::len`, the same for all nine):
/// `intersect_triangles` checks that once, instead of a bounds check per
/// load (28 of the test's 131 instructions).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn load_coords(octet: Octet, c: usize) -> __m256 {
    match octet {
        Octet::Still(block) => {
            // SAFETY: c < 9 (the caller's promise); rows are 32-byte aligned.
            unsafe { _mm256_load_ps(block.coords.get_unchecked(c).as_ptr()) }
        }
        Octet::Moving {
            tris,
            first,
            segment: (step, w),
        } => {
            let coords = tris.coords(c).as_ptr();
            let at = step as usize * tris.triangles() + first;
            let next = at + tris.triangles();
            // SAFETY: next + 8 <= the array's length, and at < next.
            let a = unsafe { _mm256_loadu_ps(coords.add(at)) };
            // SAFETY: as above.
            let b = unsafe { _mm256_loadu_ps(coords.add(next)) };
            _mm256_add_ps(a, _mm256_mul_ps(_mm256_sub_ps(b, a), _mm256_set1_ps(w)))
        }
    }
}

/// One sheared vertex of eight triangles (Woop et al.'s x, y and z):
/// (vertex - origin) along the ray's permuted axes, then sheared.
///
/// # Safety
/// `vertex < 3`, and the range as for `load_coords`.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn sheared_vertex(octet: Octet, vertex: usize, ray: &RayLanes) -> [__m256; 3] {
    let [kx, ky, kz] = ray.k;
    let (o, s) = (ray.origin, ray.shear);
    // SAFETY: 3 * vertex + k < 9, and the range (the caller's promise).
    let x = _mm256_sub_ps(unsafe { load_coords(octet, 3 * vertex + kx) }, o[0]);
    // SAFETY: as above.
    let y = _mm256_sub_ps(unsafe { load_coords(octet, 3 * vertex + ky) }, o[1]);
    // SAFETY: as above.
    let z = _mm256_sub_ps(unsafe { load_coords(octet, 3 * vertex + kz) }, o[2]);
    [
        _mm256_sub_ps(x, _mm256_mul_ps(s[0], z)),
        _mm256_sub_ps(y, _mm256_mul_ps(s[1], z)),
        _mm256_mul_ps(s[2], z),
    ]
}

#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn cross2(p: __m256, q: __m256, r: __m256, s: __m256) -> __m256 {
    _mm256_sub_ps(_mm256_mul_ps(p, q), _mm256_mul_ps(r, s))
}

/// Lanes where any of the three is below (`BELOW`) or above zero.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn any_sign<const PREDICATE: i32>(u: __m256, v: __m256, w: __m256) -> __m256 {
    let zero = _mm256_setzero_ps();
    _mm256_or_ps(
        _mm256_or_ps(
            _mm256_cmp_ps::<PREDICATE>(u, zero),
            _mm256_cmp_ps::<PREDICATE>(v, zero),
        ),
        _mm256_cmp_ps::<PREDICATE>(w, zero),
    )
}

/// Lanes whose hit lies behind the ray's origin: tt without det's sign
/// (`intersect::triangle_hit`'s test, without dividing).
///
/// # Safety
/// The CPU must support AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub fn behind_origin(det: __m256, tt: __m256) -> __m256 {
    let zero = _mm256_setzero_ps();
    _mm256_or_ps(
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_LT_OQ>(det, zero),
            _mm256_cmp_ps::<_CMP_GE_OQ>(tt, zero),
        ),
        _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OQ>(det, zero),
            _mm256_cmp_ps::<_CMP_LE_OQ>(tt, zero),
        ),
    )
}

/// What the watertight test needs of one ray, in vector registers: the
/// origin along the ray's permuted axes and the shear, each broadcast, and
/// the axes themselves. Worked out once per ray rather than per octet of
/// triangles.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub struct RayLanes {
    /// `RayShear::k`, each below 3 (checked by `from_parts`).
    k: [usize; 3],
    origin: [__m256; 3],
    shear: [__m256; 3],
}

#[cfg(target_arch = "x86_64")]
impl RayLanes {
    /// The ray from `o` with shear `r`.
    ///
    /// # Safety
    /// The CPU must support AVX2 ([`available`]).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn new(o: Vec3, r: &RayShear) -> RayLanes {
        let [kx, ky, kz] = r.k;
        // From an array: `Vec3`'s indexing is a branch per axis.
        let o = o.to_array();
        RayLanes::from_parts(r.k, [o[kx], o[ky], o[kz]], r.s.to_array())
    }

    /// The ray whose axes are `k` (each below 3, checked), its origin's
    /// components along them `origin_along` and its shear `shear`.
    ///
    /// # Safety
    /// The CPU must support AVX2 ([`available`]).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn from_parts(k: [usize; 3], origin_along: [f32; 3], shear: [f32; 3]) -> RayLanes {
        assert!(k.iter().all(|&k| k < 3), "ray shear axes {k:?}");
        RayLanes {
            k,
            origin: origin_along.map(|c| _mm256_set1_ps(c)),
            shear: shear.map(|c| _mm256_set1_ps(c)),
        }
    }
}

/// The watertight test (`intersect::triangle_hit`) of the octet's eight
/// triangles for the lanes set in `lanes`, at `t_max`.
///
/// Lanes not set in `lanes` are computed on whatever the octet holds
/// there (other triangles, padding) and never reported.
///
/// # Safety
/// The CPU must support AVX2 ([`available`]).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
pub unsafe fn intersect_triangles(
    octet: Octet,
    lanes: u32,
    ray: &RayLanes,
    t_max: f32,
) -> TriangleLanes {
    // One check for all nine loads of each vertex: the last eight floats
    // read lie inside every coordinate array (they are equally long).
    if let Octet::Moving {
        tris,
        first,
        segment,
    } = octet
    {
        let last = (segment.0 as usize + 1) * tris.triangles() + first;
        assert!(
            last + 8 <= tris.len(),
            "triangle octet {first} outside the coordinate arrays"
        );
    }
    // SAFETY: vertex < 3, every k < 3 (`RayLanes::from_parts`) and the range
    // (checked above).
    let [ax, ay, az] = unsafe { sheared_vertex(octet, 0, ray) };
    // SAFETY: as above.
    let [bx, by, bz] = unsafe { sheared_vertex(octet, 1, ray) };
    // SAFETY: as above.
    let [cx, cy, cz] = unsafe { sheared_vertex(octet, 2, ray) };
    let u = cross2(cx, by, cy, bx);
    let v = cross2(ax, cy, ay, cx);
    let w = cross2(bx, ay, by, ax);
    let zero = _mm256_setzero_ps();
    let outside = _mm256_and_ps(
        any_sign::<_CMP_LT_OQ>(u, v, w),
        any_sign::<_CMP_GT_OQ>(u, v, w),
    );
    let det = _mm256_add_ps(_mm256_add_ps(u, v), w);
    let tt = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(u, az), _mm256_mul_ps(v, bz)),
        _mm256_mul_ps(w, cz),
    );
    // In front of the origin (tt has det's sign), then t itself against
    // t_max, as `triangle_hit` and `nearer_hit` compute them.
    let behind = behind_origin(det, tt);
    let inv_det = _mm256_div_ps(_mm256_set1_ps(1.0), det);
    let t = _mm256_mul_ps(tt, inv_det);
    let rejected = _mm256_or_ps(
        _mm256_or_ps(outside, _mm256_cmp_ps::<_CMP_EQ_OQ>(det, zero)),
        _mm256_or_ps(
            behind,
            _mm256_cmp_ps::<_CMP_NLE_UQ>(t, _mm256_set1_ps(t_max)),
        ),
    );
    let mut out = TriangleLanes {
        candidates: lanes & !(_mm256_movemask_ps(rejected) as u32),
        ..Default::default()
    };
    if out.candidates != 0 {
        // SAFETY: each array holds eight floats.
        unsafe {
            _mm256_storeu_ps(out.t.as_mut_ptr(), t);
            _mm256_storeu_ps(out.b1.as_mut_ptr(), _mm256_mul_ps(v, inv_det));
            _mm256_storeu_ps(out.b2.as_mut_ptr(), _mm256_mul_ps(w, inv_det));
        }
    }
    out
}

/// The kernels' traversal (`bvh::trace_ray_with`, octant order, the same
/// work budget and overflow) with this file's tests: eight children or
/// eight leaf triangles at once, the node test on decoded planes. Compiled
/// for AVX2 with the bit instructions every AVX2 CPU has (`popcnt` for the
/// child index, `lzcnt` and `bmi1` for the bit loops; without them
/// `count_ones` is a dozen instructions).
///
/// # Safety
/// The CPU must support them ([`available`]).
///
/// `hit`: t_max and `NO_HIT` (the nearest hit so far, none yet). A
/// two-level scene's rays take `bvh::trace_instances_with`, these tests in
/// its meshes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
#[allow(clippy::too_many_arguments)]
pub unsafe fn trace_ray_octant(
    scene: &CpuScene,
    o: Vec3,
    d: Vec3,
    any_hit: bool,
    coverage_seed: u32,
    time: f32,
    hit: Hit,
) -> Hit {
    let nodes = scene.decoded_nodes();
    // A still scene's triangles in blocks (a moving one's in arrays).
    let blocks = if scene.motion.is_none() {
        scene.triangle_blocks()
    } else {
        &[]
    };
    let triangles = scene.motion.as_ref().map(|_| scene.triangle_soa());
    // A moving scene's time steps around the ray's time (`motion`).
    let segment = scene.motion.as_ref().map(|m| motion_segment(m, time));
    let steps_for = |o: Vec3, d: Vec3| OctantSteps {
        nodes,
        blocks,
        triangles,
        ray: RayLanes::new(o, &ray_shear(d)),
        segment,
    };
    if scene.instances.is_empty() {
        trace_ray_with(
            scene,
            &steps_for(o, d),
            o,
            d,
            any_hit,
            coverage_seed,
            time,
            hit,
        )
    } else {
        // Two levels: these tests in each mesh the ray enters.
        trace_instances_with(scene, &steps_for, o, d, any_hit, coverage_seed, time, hit)
    }
}

/// Asks the caches for the nodes of the inner children that a node's test
/// hit (`hits`' top byte), every line of each: on a big mesh the first
/// load of a node was a third of this traversal's time, and all but the
/// nearest of those children wait on the stack while the node's leaf
/// triangles and the nearer subtrees are tested.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn prefetch_children(nodes: &[DecodedNode], n: &DecodedNode, hits: u32, oct: u32) {
    let imask = n.e_imask >> 24;
    let mut inner = hits >> 24;
    while inner != 0 {
        let slot = inner.trailing_zeros() ^ oct;
        inner &= inner - 1;
        let child = (n.child_base_idx + (imask & ((1 << slot) - 1)).count_ones()) as usize;
        if let Some(c) = nodes.get(child) {
            let first = (c as *const DecodedNode).cast::<i8>();
            // SAFETY: every address lies inside the node (224 bytes, on
            // four or five lines); prefetches never fault.
            unsafe {
                for byte in [0, 64, 128, 192, 223] {
                    _mm_prefetch::<_MM_HINT_T0>(first.add(byte));
                }
            }
        }
    }
}

/// The AVX2 step tests of one ray.
#[cfg(target_arch = "x86_64")]
struct OctantSteps<'a> {
    nodes: &'a [DecodedNode],
    blocks: &'a [TriangleBlock],
    triangles: Option<&'a TriangleSoa>,
    ray: RayLanes,
    segment: Option<(u32, f32)>,
}

#[cfg(target_arch = "x86_64")]
impl StepTests for OctantSteps<'_> {
    #[inline(always)]
    fn node(&self, _: &PackedScene, node: u32, ray: &RaySetup, t_max: f32) -> NodeStep {
        let n = &self.nodes[node as usize];
        // SAFETY: built only by `trace_ray_octant`, whose caller promised
        // AVX2.
        let hits = unsafe { node_hit_bits(n, ray.o, ray.inv_d, t_max, ray.oct) };
        prefetch_children(self.nodes, n, hits, ray.oct);
        NodeStep {
            hits,
            child_base: n.child_base_idx,
            primitive_base: n.primitive_base_idx,
            e_imask: n.e_imask,
            triangle_block: n.triangle_block,
        }
    }

    const GROUPS: bool = true;

    /// Eight triangles at a time: the AVX2 test finds the lanes that can
    /// hit at the current t_max, then those are accepted in the scalar
    /// loop's order (highest bit first) with its exact checks at the t_max
    /// of that moment.
    #[inline(always)]
    fn leaf_group(
        &self,
        scene: &PackedScene,
        group: [u32; 3],
        any_hit: bool,
        coverage_seed: u32,
        id_offset: u32,
        hit: &mut Hit,
    ) -> bool {
        for w in (0..3).rev() {
            let lanes = (group[1] >> (8 * w)) & 0xFF;
            if lanes == 0 {
                continue;
            }
            let first = group[0] + 8 * w;
            let octet = match (self.segment, self.triangles) {
                (Some(segment), Some(tris)) => Octet::Moving {
                    tris,
                    first: first as usize,
                    segment,
                },
                _ => Octet::Still(&self.blocks[(group[2] + w) as usize]),
            };
            // SAFETY: AVX2 (`trace_ray_octant`'s caller's promise); set bits
            // are leaf triangles.
            let l = unsafe { intersect_triangles(octet, lanes, &self.ray, hit.t) };
            let mut candidates = l.candidates;
            while candidates != 0 {
                let lane = 31 - candidates.leading_zeros();
                candidates &= !(1 << lane);
                let i = first + lane;
                let id = i.wrapping_add(id_offset);
                let tv = &scene.tri_verts[i as usize];
                if let Some((t, b12)) = l.accepts(lane as usize, id, hit).filter(|&(_, b12)| {
                    tv.alpha_mask == 0
                        || alpha_test_passes(scene, tv.material, i, b12, coverage_seed)
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
        }
        false
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::cpu::common::rng::pcg_hash;
    use crate::packed::layout::CwBvhNode;

    /// Random nodes and rays, grazing and axis-parallel ones included: the
    /// AVX2 test returns exactly the scalar test's bits.
    #[test]
    fn avx2_node_test_equals_the_scalar_one_bit_for_bit() {
        if !available() {
            println!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        let state = std::cell::Cell::new(1u32);
        let next = || {
            state.set(pcg_hash(state.get()));
            state.get()
        };
        let unit = || next() as f32 / u32::MAX as f32;
        let (mut differing, mut hits) = (0, 0);
        for case in 0..200_000 {
            // Per child: a box of random grid planes, lo <= hi, on each axis.
            let mut planes = [[[0u32; 2]; 2]; 3];
            for axis in &mut planes {
                for k in 0..8 {
                    let lo = next() & 0xFF;
                    let hi = (lo + (next() & 0x7F)).min(255);
                    axis[0][k / 4] |= lo << (8 * (k % 4));
                    axis[1][k / 4] |= hi << (8 * (k % 4));
                }
            }
            let node = CwBvhNode {
                p: [unit() * 4.0 - 2.0, unit() * 4.0 - 2.0, unit() * 4.0 - 2.0],
                // Exponents 118..125: grid steps of 2^-9 .. 2^-2.
                e_imask: (118 + case % 8)
                    | (118 + (case / 8) % 8) << 8
                    | (118 + (case / 64) % 8) << 16
                    | (next() & 0xFF) << 24,
                child_base_idx: 0,
                primitive_base_idx: 0,
                child_meta: [next(), next()],
                qlo_x: planes[0][0],
                qhi_x: planes[0][1],
                qlo_y: planes[1][0],
                qhi_y: planes[1][1],
                qlo_z: planes[2][0],
                qhi_z: planes[2][1],
            };
            let o = Vec3::new(unit(), unit(), unit()) * 6.0 - 3.0;
            // Aimed at a random point of the node's grid, so most rays hit
            // some children; every other ray at a corner of a child's box,
            // where entry and exit distances are equal up to rounding.
            let e = crate::packed::bvh::grid_step(node.e_imask);
            let byte = |w: [u32; 2], k: usize| ((w[k / 4] >> (8 * (k % 4))) & 0xFF) as f32;
            let k = (next() % 8) as usize;
            let grid = if case % 2 == 0 {
                Vec3::new(unit(), unit(), unit()) * 255.0
            } else {
                let pick = |lo, hi| {
                    if next() % 2 == 0 {
                        byte(lo, k)
                    } else {
                        byte(hi, k)
                    }
                };
                Vec3::new(
                    pick(node.qlo_x, node.qhi_x),
                    pick(node.qlo_y, node.qhi_y),
                    pick(node.qlo_z, node.qhi_z),
                )
            };
            let target = Vec3::from(node.p) + e * grid;
            let mut d = (target - o).normalize();
            if case % 5 == 0 {
                d[(case / 5 % 3) as usize] = 0.0;
            }
            let inv_d = (Vec3::ONE / d).clamp(
                Vec3::splat(-crate::cpu::common::sampling::FLT_MAX),
                Vec3::splat(crate::cpu::common::sampling::FLT_MAX),
            );
            let neg = inv_d.cmplt(Vec3::ZERO);
            let oct = (if neg.x { 0 } else { 4 })
                | (if neg.y { 0 } else { 2 })
                | (if neg.z { 0 } else { 1 });
            let t_max = if case % 3 == 0 {
                f32::MAX
            } else {
                unit() * 5.0
            };
            let scalar = crate::cpu::common::bvh::node_hit_bits(&node, o, inv_d, neg, t_max, oct);
            // SAFETY: AVX2 is available (checked above).
            let simd = unsafe { node_hit_bits(&DecodedNode::new(&node), o, inv_d, t_max, oct) };
            differing += (scalar != simd) as u32;
            hits += (scalar != 0) as u32;
        }
        assert_eq!(differing, 0, "nodes whose hit bits differ");
        assert!(
            hits > 10_000,
            "only {hits} nodes hit: the test exercises little"
        );
    }

    /// Random triangles and rays (many grazing edges and vertices): each
    /// lane's candidate flag and distance checks give exactly the scalar
    /// test's hit, t and barycentrics.
    #[test]
    fn avx2_triangle_test_equals_the_scalar_one_bit_for_bit() {
        if !available() {
            println!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        use crate::cpu::common::bvh::{Hit, NO_HIT, nearer_hit};
        use crate::cpu::common::intersect::{ray_shear, triangle_hit};
        use crate::packed::layout::TriangleVerts;
        let state = std::cell::Cell::new(7u32);
        let unit = || {
            state.set(pcg_hash(state.get()));
            state.get() as f32 / u32::MAX as f32
        };
        let point = || Vec3::new(unit(), unit(), unit()) * 2.0 - 1.0;
        let (mut differing, mut hits) = (0, 0);
        for case in 0..40_000u32 {
            let tris: Vec<TriangleVerts> = (0..8)
                .map(|_| TriangleVerts {
                    v0: point().into(),
                    v1: point().into(),
                    v2: point().into(),
                    ..Default::default()
                })
                .collect();
            let o = point() * 3.0;
            // Aimed at a vertex or an edge of one triangle every other time.
            let t = &tris[(case % 8) as usize];
            let target = match case % 4 {
                0 => Vec3::from(t.v0),
                1 => (Vec3::from(t.v1) + Vec3::from(t.v2)) * 0.5,
                _ => point(),
            };
            let d = (target - o).normalize();
            let r = ray_shear(d);
            let t_max = if case % 3 == 0 {
                f32::MAX
            } else {
                unit() * 6.0
            };
            let lanes = pcg_hash(case) & 0xFF;
            // The hit so far: none, or triangle 3 at t_max, so that hits at
            // exactly t_max are taken by lower indices only.
            let so_far = Hit {
                t: t_max,
                triangle: if case % 2 == 0 { NO_HIT } else { 3 },
                b12: glam::Vec2::ZERO,
            };
            // SAFETY: AVX2 is available; the lanes name the 8 triangles.
            // A still scene's block, and a moving scene's arrays (at weight
            // 0 of a step to the zero padding: the same coordinates).
            let block = TriangleBlock::new(&tris, 0);
            let soa = TriangleSoa::new(&tris);
            let moving = Octet::Moving {
                tris: &soa,
                first: 0,
                segment: (0, 0.0),
            };
            let ray = unsafe { RayLanes::new(o, &r) };
            let l = unsafe { intersect_triangles(Octet::Still(&block), lanes, &ray, t_max) };
            let lm = unsafe { intersect_triangles(moving, lanes, &ray, t_max) };
            differing += (l.candidates != lm.candidates
                || (0..8).any(|k| {
                    l.candidates & (1 << k) != 0
                        && (l.t[k].to_bits(), l.b1[k].to_bits(), l.b2[k].to_bits())
                            != (lm.t[k].to_bits(), lm.b1[k].to_bits(), lm.b2[k].to_bits())
                })) as u32;
            for (lane, tv) in tris.iter().enumerate() {
                if lanes & (1 << lane) == 0 {
                    continue;
                }
                let i = lane as u32;
                let scalar = triangle_hit(o, &r, tv.v0.into(), tv.v1.into(), tv.v2.into())
                    .filter(|&(t, _)| nearer_hit(t, i, &so_far));
                let simd = (l.candidates & (1 << lane) != 0)
                    .then(|| l.accepts(lane, i, &so_far))
                    .flatten();
                let same = match (scalar, simd) {
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
