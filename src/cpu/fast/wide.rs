//! The ray packet's vector registers (`packet`): sixteen f32 lanes and
//! mask registers where the build targets AVX-512 (full width on Zen 5:
//! twice the rays per instruction), eight lanes and all-ones masks in an
//! AVX2 register elsewhere. The packet code is written once against these
//! few operations; each is the one IEEE instruction of its width, so a
//! lane computes the same bits at either width.
//!
//! # Safety
//! Every function here must run only where the CPU has the instructions of
//! the width the build selects (AVX2 for the packet's callers'
//! `octant::available`, which checks AVX-512 too where it is selected).

#[cfg(target_arch = "x86_64")]
pub use imp::*;

/// Lanes of one vector register: sixteen f32 where the build targets
/// AVX-512, eight elsewhere. The one width of the CPU back end's vector
/// code: a ray packet's rays, the lane schedule's paths and a leaf window's
/// triangles are each a register of `WIDTH`.
pub const WIDTH: usize = if cfg!(all(
    target_arch = "x86_64",
    target_feature = "avx512f",
    target_feature = "avx512bw",
    target_feature = "avx512vl"
)) {
    16
} else {
    8
};

/// The matrix of `gf2p8affine` that reverses the bits of a byte: the row
/// for result bit i (byte 7 - i) picks source bit 7 - i.
#[cfg(all(target_arch = "x86_64", target_feature = "gfni"))]
const BYTE_BITS_REVERSED: i64 = 0x8040_2010_0804_0201_u64 as i64;

#[cfg(all(
    target_arch = "x86_64",
    not(all(
        target_feature = "avx512f",
        target_feature = "avx512bw",
        target_feature = "avx512vl"
    ))
))]
mod imp {
    #[cfg(target_feature = "gfni")]
    use super::BYTE_BITS_REVERSED;
    use super::WIDTH;
    use std::arch::x86_64::*;

    pub type F = __m256;
    pub type I = __m256i;
    /// All ones in a lane where the condition holds.
    pub type Mask = __m256;

    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn splat(x: f32) -> F {
        _mm256_set1_ps(x)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn splat_i(x: i32) -> I {
        _mm256_set1_epi32(x)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn add(a: F, b: F) -> F {
        _mm256_add_ps(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn sub(a: F, b: F) -> F {
        _mm256_sub_ps(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn mul(a: F, b: F) -> F {
        _mm256_mul_ps(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn div(a: F, b: F) -> F {
        _mm256_div_ps(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn min(a: F, b: F) -> F {
        _mm256_min_ps(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn max(a: F, b: F) -> F {
        _mm256_max_ps(a, b)
    }
    /// |a|: the sign bit cleared.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn abs(a: F) -> F {
        _mm256_andnot_ps(_mm256_set1_ps(-0.0), a)
    }
    /// The comparison `P` (`_CMP_*`) per lane.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn cmp<const P: i32>(a: F, b: F) -> Mask {
        _mm256_cmp_ps::<P>(a, b)
    }
    /// a > b as signed integers.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn gt_i(a: I, b: I) -> Mask {
        _mm256_castsi256_ps(_mm256_cmpgt_epi32(a, b))
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn and(a: Mask, b: Mask) -> Mask {
        _mm256_and_ps(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn or(a: Mask, b: Mask) -> Mask {
        _mm256_or_ps(a, b)
    }
    /// Where `b` holds and `a` does not.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn and_not(a: Mask, b: Mask) -> Mask {
        _mm256_andnot_ps(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn not(a: Mask) -> Mask {
        _mm256_xor_ps(a, _mm256_castsi256_ps(_mm256_set1_epi32(-1)))
    }
    /// Bit l set where lane l holds.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn bits(m: Mask) -> u32 {
        _mm256_movemask_ps(m) as u32
    }
    /// The lanes whose bit is set.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn from_bits(bits: u32) -> Mask {
        {
            let lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let set = _mm256_and_si256(_mm256_set1_epi32(bits as i32), lane_bits);
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(set, lane_bits))
        }
    }
    /// `m ? a : b` per lane.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn blend(m: Mask, a: F, b: F) -> F {
        _mm256_blendv_ps(b, a, m)
    }
    /// `m ? a : b` per lane, of integers.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn blend_i(m: Mask, a: I, b: I) -> I {
        {
            _mm256_castps_si256(_mm256_blendv_ps(
                _mm256_castsi256_ps(b),
                _mm256_castsi256_ps(a),
                m,
            ))
        }
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn load(a: &[f32; WIDTH]) -> F {
        // SAFETY: see the module; WIDTH floats, an unaligned load.
        unsafe { _mm256_loadu_ps(a.as_ptr()) }
    }
    /// Lane `l` (below WIDTH) of `v`, from the register (a permute), not
    /// through memory: a scalar read of a vector just stored waits for it.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn lane(v: F, l: usize) -> f32 {
        _mm256_cvtss_f32(_mm256_permutevar8x32_ps(v, _mm256_set1_epi32(l as i32)))
    }
    /// Lane `l` (below WIDTH) of `v`, as `lane`.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn lane_i(v: I, l: usize) -> u32 {
        _mm256_cvtsi256_si32(_mm256_permutevar8x32_epi32(v, _mm256_set1_epi32(l as i32))) as u32
    }
    /// `v` with lane `l` (below WIDTH) set to `x`.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn with_lane(v: F, l: usize, x: f32) -> F {
        blend(from_bits(1 << l), _mm256_set1_ps(x), v)
    }
    /// `v` with lane `l` (below WIDTH) set to `x`.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn with_lane_i(v: I, l: usize, x: u32) -> I {
        blend_i(from_bits(1 << l), _mm256_set1_epi32(x as i32), v)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn store(a: &mut [f32; WIDTH], v: F) {
        // SAFETY: as for `load`.
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), v) }
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn load_i(a: &[u32; WIDTH]) -> I {
        // SAFETY: as for `load`.
        unsafe { _mm256_loadu_si256(a.as_ptr().cast()) }
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn store_i(a: &mut [u32; WIDTH], v: I) {
        // SAFETY: as for `load`.
        unsafe { _mm256_storeu_si256(a.as_mut_ptr().cast(), v) }
    }
    /// The lane's axis (0, 1 or 2) from exclusive masks "is x", "is y".
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn axis_index(is_x: Mask, is_y: Mask) -> I {
        // 2 + 2 (is x) + (is y), the masks being -1 where set.
        {
            _mm256_add_epi32(
                _mm256_add_epi32(
                    _mm256_set1_epi32(2),
                    _mm256_slli_epi32::<1>(_mm256_castps_si256(is_x)),
                ),
                _mm256_castps_si256(is_y),
            )
        }
    }
    /// Each lane's component `axis[lane]` (below 3) of the vector at `p`.
    ///
    /// # Safety
    /// Four floats from `p` are readable.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub unsafe fn gather_axis(p: *const f32, axis: I) -> F {
        // SAFETY: the caller's promise; the upper half is never indexed.
        unsafe {
            let xyz = _mm256_castps128_ps256(_mm_loadu_ps(p));
            _mm256_permutevar8x32_ps(xyz, axis)
        }
    }

    // Used by `simd` where the build targets AVX2 and BMI2.
    #[cfg_attr(
        not(all(target_feature = "avx2", target_feature = "bmi2")),
        allow(dead_code)
    )]
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn sqrt(a: F) -> F {
        _mm256_sqrt_ps(a)
    }
    /// A mask's lanes as bools (`simd::Bools`).
    // Used by `simd` where the build targets AVX2 and BMI2.
    #[cfg_attr(
        not(all(target_feature = "avx2", target_feature = "bmi2")),
        allow(dead_code)
    )]
    #[inline]
    #[target_feature(enable = "avx2,bmi2")]
    pub fn to_bools(m: Mask) -> [bool; WIDTH] {
        // Bit l to the low bit of byte l: a word of 0 and 1 bytes.
        let bytes = _pdep_u64(_mm256_movemask_ps(m) as u32 as u64, 0x0101_0101_0101_0101);
        // SAFETY: every byte is 0 or 1, a valid bool.
        unsafe { std::mem::transmute::<u64, [bool; WIDTH]>(bytes) }
    }
    /// Bools as a mask (the sign bit of each lane).
    // Used by `simd` where the build targets AVX2 and BMI2.
    #[cfg_attr(
        not(all(target_feature = "avx2", target_feature = "bmi2")),
        allow(dead_code)
    )]
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn from_bools(b: [bool; WIDTH]) -> Mask {
        // SAFETY: eight bools are eight bytes.
        let bytes = unsafe { std::mem::transmute::<[bool; WIDTH], u64>(b) };
        let ones = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(bytes as i64));
        _mm256_castsi256_ps(_mm256_slli_epi32::<31>(ones))
    }
    // Integer lanes, for the random numbers (`lanes_rng`).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn add_i(a: I, b: I) -> I {
        _mm256_add_epi32(a, b)
    }
    /// The low 32 bits of each product.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn mul_i(a: I, b: I) -> I {
        _mm256_mullo_epi32(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn xor_i(a: I, b: I) -> I {
        _mm256_xor_si256(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn and_i(a: I, b: I) -> I {
        _mm256_and_si256(a, b)
    }
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn or_i(a: I, b: I) -> I {
        _mm256_or_si256(a, b)
    }
    /// Each word shifted right by its own count (below 32).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn shr_each(a: I, counts: I) -> I {
        _mm256_srlv_epi32(a, counts)
    }
    /// Each word shifted left by its own count (below 32).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn shl_each(a: I, counts: I) -> I {
        _mm256_sllv_epi32(a, counts)
    }
    /// Byte `idx` (low four bits) of `table`'s 16 bytes, per byte.
    #[cfg(not(target_feature = "gfni"))]
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn lookup_bytes(table: &[u8; 16], idx: I) -> I {
        // SAFETY: 16 bytes (an unaligned load).
        let t = _mm256_broadcastsi128_si256(unsafe { _mm_loadu_si128(table.as_ptr().cast()) });
        _mm256_shuffle_epi8(t, idx)
    }
    /// `x`'s bytes picked per 16 bytes by `order` (`_mm256_shuffle_epi8`).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn shuffle_bytes(x: I, order: &[u8; 16]) -> I {
        // SAFETY: 16 bytes (an unaligned load).
        let o = _mm256_broadcastsi128_si256(unsafe { _mm_loadu_si128(order.as_ptr().cast()) });
        _mm256_shuffle_epi8(x, o)
    }
    /// Each byte's bits in reverse order (GFNI's affine transform by the
    /// bit-reversal matrix: one instruction for two nibble lookups).
    #[cfg(target_feature = "gfni")]
    #[inline]
    #[target_feature(enable = "avx2,gfni")]
    pub fn reverse_byte_bits(x: I) -> I {
        _mm256_gf2p8affine_epi64_epi8::<0>(x, _mm256_set1_epi64x(BYTE_BITS_REVERSED))
    }
    /// Each word as f32 (signed).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn to_float(a: I) -> F {
        _mm256_cvtepi32_ps(a)
    }
    /// `table`'s lane `idx[l]` in each lane l (each index's low three bits).
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn permute(table: F, idx: I) -> F {
        _mm256_permutevar8x32_ps(table, idx)
    }
}

#[cfg(all(
    target_arch = "x86_64",
    target_feature = "avx512f",
    target_feature = "avx512bw",
    target_feature = "avx512vl"
))]
mod imp {
    #[cfg(target_feature = "gfni")]
    use super::BYTE_BITS_REVERSED;
    use super::WIDTH;
    use std::arch::x86_64::*;

    pub type F = __m512;
    pub type I = __m512i;
    /// A mask register: bit l for lane l.
    pub type Mask = __mmask16;

    #[inline(always)]
    pub fn splat(x: f32) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_set1_ps(x) }
    }
    #[inline(always)]
    pub fn splat_i(x: i32) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_set1_epi32(x) }
    }
    #[inline(always)]
    pub fn add(a: F, b: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_add_ps(a, b) }
    }
    #[inline(always)]
    pub fn sub(a: F, b: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_sub_ps(a, b) }
    }
    #[inline(always)]
    pub fn mul(a: F, b: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_mul_ps(a, b) }
    }
    #[inline(always)]
    pub fn div(a: F, b: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_div_ps(a, b) }
    }
    #[inline(always)]
    pub fn min(a: F, b: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_min_ps(a, b) }
    }
    #[inline(always)]
    pub fn max(a: F, b: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_max_ps(a, b) }
    }
    /// |a|: the sign bit cleared.
    #[inline(always)]
    pub fn abs(a: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_abs_ps(a) }
    }
    /// The comparison `P` (`_CMP_*`) per lane.
    #[inline(always)]
    pub fn cmp<const P: i32>(a: F, b: F) -> Mask {
        // SAFETY: see the module.
        unsafe { _mm512_cmp_ps_mask::<P>(a, b) }
    }
    /// a > b as signed integers.
    #[inline(always)]
    pub fn gt_i(a: I, b: I) -> Mask {
        // SAFETY: see the module.
        unsafe { _mm512_cmpgt_epi32_mask(a, b) }
    }
    #[inline(always)]
    pub fn and(a: Mask, b: Mask) -> Mask {
        a & b
    }
    #[inline(always)]
    pub fn or(a: Mask, b: Mask) -> Mask {
        a | b
    }
    /// Where `b` holds and `a` does not.
    #[inline(always)]
    pub fn and_not(a: Mask, b: Mask) -> Mask {
        !a & b
    }
    #[inline(always)]
    pub fn not(a: Mask) -> Mask {
        !a
    }
    /// Bit l set where lane l holds.
    #[inline(always)]
    pub fn bits(m: Mask) -> u32 {
        u32::from(m)
    }
    /// The lanes whose bit is set.
    #[inline(always)]
    pub fn from_bits(bits: u32) -> Mask {
        bits as Mask
    }
    /// `m ? a : b` per lane.
    #[inline(always)]
    pub fn blend(m: Mask, a: F, b: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_mask_blend_ps(m, b, a) }
    }
    /// `m ? a : b` per lane, of integers.
    #[inline(always)]
    pub fn blend_i(m: Mask, a: I, b: I) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_mask_blend_epi32(m, b, a) }
    }
    #[inline(always)]
    pub fn load(a: &[f32; WIDTH]) -> F {
        // SAFETY: see the module; WIDTH floats, an unaligned load.
        unsafe { _mm512_loadu_ps(a.as_ptr()) }
    }
    /// Lane `l` (below WIDTH) of `v`, from the register (a permute), not
    /// through memory: a scalar read of a vector just stored waits for it.
    #[inline(always)]
    pub fn lane(v: F, l: usize) -> f32 {
        // SAFETY: see the module.
        unsafe { _mm512_cvtss_f32(_mm512_permutexvar_ps(_mm512_set1_epi32(l as i32), v)) }
    }
    /// Lane `l` (below WIDTH) of `v`, as `lane`.
    #[inline(always)]
    pub fn lane_i(v: I, l: usize) -> u32 {
        // SAFETY: see the module.
        unsafe {
            _mm512_cvtsi512_si32(_mm512_permutexvar_epi32(_mm512_set1_epi32(l as i32), v)) as u32
        }
    }
    /// `v` with lane `l` (below WIDTH) set to `x`.
    #[inline(always)]
    pub fn with_lane(v: F, l: usize, x: f32) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_mask_mov_ps(v, 1 << l, _mm512_set1_ps(x)) }
    }
    /// `v` with lane `l` (below WIDTH) set to `x`.
    #[inline(always)]
    pub fn with_lane_i(v: I, l: usize, x: u32) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_mask_mov_epi32(v, 1 << l, _mm512_set1_epi32(x as i32)) }
    }
    #[inline(always)]
    pub fn store(a: &mut [f32; WIDTH], v: F) {
        // SAFETY: as for `load`.
        unsafe { _mm512_storeu_ps(a.as_mut_ptr(), v) }
    }
    #[inline(always)]
    pub fn load_i(a: &[u32; WIDTH]) -> I {
        // SAFETY: as for `load`.
        unsafe { _mm512_loadu_si512(a.as_ptr().cast()) }
    }
    #[inline(always)]
    pub fn store_i(a: &mut [u32; WIDTH], v: I) {
        // SAFETY: as for `load`.
        unsafe { _mm512_storeu_si512(a.as_mut_ptr().cast(), v) }
    }
    /// The lane's axis (0, 1 or 2) from exclusive masks "is x", "is y".
    #[inline(always)]
    pub fn axis_index(is_x: Mask, is_y: Mask) -> I {
        // SAFETY: see the module.
        unsafe {
            let y_or_z = _mm512_mask_mov_epi32(_mm512_set1_epi32(2), is_y, _mm512_set1_epi32(1));
            _mm512_mask_mov_epi32(y_or_z, is_x, _mm512_setzero_si512())
        }
    }
    /// Each lane's component `axis[lane]` (below 3) of the vector at `p`.
    ///
    /// # Safety
    /// Four floats from `p` are readable.
    #[inline(always)]
    pub unsafe fn gather_axis(p: *const f32, axis: I) -> F {
        // SAFETY: the caller's promise; only lanes 0 to 2 are indexed.
        unsafe {
            let xyz = _mm512_castps128_ps512(_mm_loadu_ps(p));
            _mm512_permutexvar_ps(axis, xyz)
        }
    }

    #[inline(always)]
    pub fn sqrt(a: F) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_sqrt_ps(a) }
    }
    /// A mask's lanes as bools (`simd::Bools`).
    #[inline(always)]
    pub fn to_bools(m: Mask) -> [bool; WIDTH] {
        // SAFETY: AVX-512BW and VL; sixteen bytes, each 0 or 1: valid bools.
        unsafe {
            std::mem::transmute::<__m128i, [bool; WIDTH]>(_mm_maskz_mov_epi8(m, _mm_set1_epi8(1)))
        }
    }
    /// Bools as a mask.
    #[inline(always)]
    pub fn from_bools(b: [bool; WIDTH]) -> Mask {
        // SAFETY: sixteen bools are sixteen bytes; AVX-512BW and VL.
        unsafe {
            let bytes = std::mem::transmute::<[bool; WIDTH], __m128i>(b);
            _mm_test_epi8_mask(bytes, bytes)
        }
    }
    // Integer lanes, for the random numbers (`lanes_rng`).
    #[inline(always)]
    pub fn add_i(a: I, b: I) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_add_epi32(a, b) }
    }
    /// The low 32 bits of each product.
    #[inline(always)]
    pub fn mul_i(a: I, b: I) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_mullo_epi32(a, b) }
    }
    #[inline(always)]
    pub fn xor_i(a: I, b: I) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_xor_si512(a, b) }
    }
    #[inline(always)]
    pub fn and_i(a: I, b: I) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_and_si512(a, b) }
    }
    #[inline(always)]
    pub fn or_i(a: I, b: I) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_or_si512(a, b) }
    }
    /// Each word shifted right by its own count (below 32).
    #[inline(always)]
    pub fn shr_each(a: I, counts: I) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_srlv_epi32(a, counts) }
    }
    /// Each word shifted left by its own count (below 32).
    #[inline(always)]
    pub fn shl_each(a: I, counts: I) -> I {
        // SAFETY: see the module.
        unsafe { _mm512_sllv_epi32(a, counts) }
    }
    /// Byte `idx` (low four bits) of `table`'s 16 bytes, per byte.
    #[cfg(not(target_feature = "gfni"))]
    #[inline(always)]
    pub fn lookup_bytes(table: &[u8; 16], idx: I) -> I {
        // SAFETY: 16 bytes (an unaligned load); AVX-512BW.
        unsafe {
            let t = _mm512_broadcast_i32x4(_mm_loadu_si128(table.as_ptr().cast()));
            _mm512_shuffle_epi8(t, idx)
        }
    }
    /// `x`'s bytes picked per 16 bytes by `order` (`_mm512_shuffle_epi8`).
    #[inline(always)]
    pub fn shuffle_bytes(x: I, order: &[u8; 16]) -> I {
        // SAFETY: 16 bytes (an unaligned load); AVX-512BW.
        unsafe {
            let o = _mm512_broadcast_i32x4(_mm_loadu_si128(order.as_ptr().cast()));
            _mm512_shuffle_epi8(x, o)
        }
    }
    /// Each byte's bits in reverse order (GFNI's affine transform by the
    /// bit-reversal matrix: one instruction for two nibble lookups).
    #[cfg(target_feature = "gfni")]
    #[inline(always)]
    pub fn reverse_byte_bits(x: I) -> I {
        // SAFETY: see the module; GFNI is in the build's target features.
        unsafe { _mm512_gf2p8affine_epi64_epi8::<0>(x, _mm512_set1_epi64(BYTE_BITS_REVERSED)) }
    }
    /// Each word as f32 (signed).
    #[inline(always)]
    pub fn to_float(a: I) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_cvtepi32_ps(a) }
    }
    /// `table`'s lane `idx[l]` in each lane l (each index's low four bits).
    #[inline(always)]
    pub fn permute(table: F, idx: I) -> F {
        // SAFETY: see the module.
        unsafe { _mm512_permutexvar_ps(idx, table) }
    }
}
