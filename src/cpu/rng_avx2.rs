//! `rng.rs`'s draws for eight paths at once with AVX2, for the lane
//! schedule (`lanes`): Owen-scrambled Sobol and the independent hash.
//! Integer operations only, the same ones in the same order, so every
//! number equals the scalar draw's (tested below). Sobol's seeds are
//! `rng::rng_dim_seed`'s with the salt hashed where the scalar code looks
//! it up (its table holds those hashes): eight hashes in vector registers
//! cost less than eight table loads.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Eight 32-bit words.
#[cfg(target_arch = "x86_64")]
type U8 = __m256i;

#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn splat(x: u32) -> U8 {
    _mm256_set1_epi32(x as i32)
}

/// `rng::pcg_hash` of each word.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn pcg_hash(v: U8) -> U8 {
    let state = _mm256_add_epi32(_mm256_mullo_epi32(v, splat(747796405)), splat(2891336453));
    let shift = _mm256_add_epi32(_mm256_srli_epi32::<28>(state), splat(4));
    let word = _mm256_mullo_epi32(
        _mm256_xor_si256(_mm256_srlv_epi32(state, shift), state),
        splat(277803737),
    );
    _mm256_xor_si256(_mm256_srli_epi32::<22>(word), word)
}

/// `rng::laine_karras_permutation` of each word.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn laine_karras_permutation(x: U8, seed: U8) -> U8 {
    let x = _mm256_xor_si256(x, _mm256_mullo_epi32(x, splat(0x3d20adea)));
    let x = _mm256_add_epi32(x, seed);
    let x = _mm256_mullo_epi32(x, _mm256_or_si256(_mm256_srli_epi32::<16>(seed), splat(1)));
    let x = _mm256_xor_si256(x, _mm256_mullo_epi32(x, splat(0x05526c56)));
    _mm256_xor_si256(x, _mm256_mullo_epi32(x, splat(0x53a22864)))
}

/// Each 4-bit value with its bits reversed.
#[cfg(target_arch = "x86_64")]
const NIBBLES_REVERSED: [u8; 16] = [
    0x0, 0x8, 0x4, 0xc, 0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb, 0x7, 0xf,
];

/// `u32::reverse_bits` of each word: the bytes in reverse order, the bits
/// of each byte reversed by two 16-entry nibble tables.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn reverse_bits(x: U8) -> U8 {
    let byte_order = _mm256_setr_epi8(
        3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12, 3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8,
        15, 14, 13, 12,
    );
    // Nibble n reversed, as the low nibble and (shifted) as the high one;
    // the 16-bit shift cannot carry: every entry is below 0x10.
    // SAFETY: `NIBBLES_REVERSED` is 16 bytes (an unaligned load).
    let low =
        _mm256_broadcastsi128_si256(unsafe { _mm_loadu_si128(NIBBLES_REVERSED.as_ptr().cast()) });
    let high = _mm256_slli_epi16::<4>(low);
    let x = _mm256_shuffle_epi8(x, byte_order);
    let nibble = splat(0x0f0f_0f0f);
    let lo = _mm256_and_si256(x, nibble);
    let hi = _mm256_and_si256(_mm256_srli_epi32::<4>(x), nibble);
    _mm256_or_si256(_mm256_shuffle_epi8(high, lo), _mm256_shuffle_epi8(low, hi))
}

/// `rng::sobol1_reversed` of each word.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn sobol1_reversed(i: U8) -> U8 {
    let i = _mm256_xor_si256(
        i,
        _mm256_and_si256(_mm256_srli_epi32::<1>(i), splat(0x55555555)),
    );
    let i = _mm256_xor_si256(
        i,
        _mm256_and_si256(_mm256_srli_epi32::<2>(i), splat(0x33333333)),
    );
    let i = _mm256_xor_si256(
        i,
        _mm256_and_si256(_mm256_srli_epi32::<4>(i), splat(0x0f0f0f0f)),
    );
    let i = _mm256_xor_si256(
        i,
        _mm256_and_si256(_mm256_srli_epi32::<8>(i), splat(0x00ff00ff)),
    );
    _mm256_xor_si256(
        i,
        _mm256_and_si256(_mm256_srli_epi32::<16>(i), splat(0x0000ffff)),
    )
}

/// `rng::rng_dim_seed` for each lane's hash and dimension, the salt
/// `pcg_hash(8 dim + purpose)` computed.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn dim_seed(hash: U8, dim: U8, purpose: u32) -> U8 {
    let slot = _mm256_add_epi32(_mm256_slli_epi32::<3>(dim), splat(purpose));
    pcg_hash(_mm256_xor_si256(hash, pcg_hash(slot)))
}

/// `rng::rng_unit` of each word.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn unit(bits: U8) -> [f32; 8] {
    let f = _mm256_mul_ps(
        _mm256_cvtepi32_ps(_mm256_srli_epi32::<8>(bits)),
        _mm256_set1_ps(1.0 / 16777216.0),
    );
    let mut out = [0f32; 8];
    // SAFETY: `out` holds eight floats (an unaligned store).
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), f) };
    out
}

#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn load(words: &[u32; 8]) -> U8 {
    // SAFETY: eight words (an unaligned load).
    unsafe { _mm256_loadu_si256(words.as_ptr().cast()) }
}

/// Eight paths' keys: `RngKey::hash` and `reversed_index` per lane.
pub struct KeyLanes {
    pub hash: [u32; 8],
    pub reversed: [u32; 8],
}

impl KeyLanes {
    /// `rng::sobol_float(key_l, dim_l)` of each lane.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn float(&self, dim: &[u32; 8]) -> [f32; 8] {
        let (hash, dim) = (load(&self.hash), load(dim));
        let i = reverse_bits(laine_karras_permutation(
            load(&self.reversed),
            dim_seed(hash, dim, 0),
        ));
        unit(reverse_bits(laine_karras_permutation(
            i,
            dim_seed(hash, dim, 1),
        )))
    }

    /// `rng::sobol_float2(key_l, dim_l)` of each lane, as x and y.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn float2(&self, dim: &[u32; 8]) -> ([f32; 8], [f32; 8]) {
        let (hash, dim) = (load(&self.hash), load(dim));
        let i = reverse_bits(laine_karras_permutation(
            load(&self.reversed),
            dim_seed(hash, dim, 2),
        ));
        let x = reverse_bits(laine_karras_permutation(i, dim_seed(hash, dim, 3)));
        let y = reverse_bits(laine_karras_permutation(
            sobol1_reversed(i),
            dim_seed(hash, dim, 4),
        ));
        (unit(x), unit(y))
    }

    /// `rng::rng_float(key_l, dim_l)` of each lane's independent key.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn independent_float(&self, dim: &[u32; 8]) -> [f32; 8] {
        unit(pcg_hash(_mm256_add_epi32(
            load(&self.hash),
            pcg_hash(load(dim)),
        )))
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::constants::{SAMPLER_INDEPENDENT, SAMPLER_SOBOL};
    use crate::cpu::rng::{rng_float, rng_sampler_key, sobol_float, sobol_float2};

    #[test]
    fn eight_lane_draws_equal_the_scalar_ones_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            println!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        let mut checked = 0;
        for round in 0..2000u32 {
            let keys: [_; 8] = std::array::from_fn(|l| {
                let pixel = round.wrapping_mul(7919) ^ (l as u32 * 104729);
                let sample = round.wrapping_mul(31) + l as u32 * (round % 5);
                rng_sampler_key(SAMPLER_SOBOL, pixel, sample, round % 3)
            });
            let lanes = KeyLanes {
                hash: keys.map(|k| k.hash),
                reversed: keys.map(|k| k.reversed_index),
            };
            // Dimensions of early and late bounces, past the salt table.
            let dim: [u32; 8] = std::array::from_fn(|l| (round * 13 + l as u32 * 97) % 1200);
            // SAFETY: AVX2 is there (checked above).
            let (f, (x, y)) = unsafe { (lanes.float(&dim), lanes.float2(&dim)) };
            for l in 0..8 {
                assert_eq!(f[l].to_bits(), sobol_float(keys[l], dim[l]).to_bits());
                let s = sobol_float2(keys[l], dim[l]);
                assert_eq!(
                    (x[l].to_bits(), y[l].to_bits()),
                    (s.x.to_bits(), s.y.to_bits())
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 16000);
    }

    #[test]
    fn eight_lane_independent_draws_equal_the_scalar_ones_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            println!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        for round in 0..2000u32 {
            let keys: [_; 8] = std::array::from_fn(|l| {
                let pixel = round.wrapping_mul(7919) ^ (l as u32 * 104729);
                rng_sampler_key(SAMPLER_INDEPENDENT, pixel, round + l as u32, round % 3)
            });
            let lanes = KeyLanes {
                hash: keys.map(|k| k.hash),
                reversed: keys.map(|k| k.reversed_index),
            };
            let dim: [u32; 8] = std::array::from_fn(|l| (round * 13 + l as u32 * 97) % 1200);
            // SAFETY: AVX2 is there (checked above).
            let f = unsafe { lanes.independent_float(&dim) };
            for l in 0..8 {
                assert_eq!(f[l].to_bits(), rng_float(keys[l], dim[l]).to_bits());
            }
        }
    }
}
