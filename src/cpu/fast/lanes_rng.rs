//! `rng.rs`'s draws for a register of paths at once (`wide::WIDTH`: sixteen
//! with AVX-512, eight with AVX2), for the lane schedule (`lanes`):
//! Owen-scrambled Sobol and the independent hash. Integer operations only,
//! the same ones in the same order, so every number equals the scalar
//! draw's (tested below). Sobol's seeds are `rng::rng_dim_seed`'s with the
//! salt hashed where the scalar code looks it up (its table holds those
//! hashes): hashes in vector registers cost less than table loads.
//!
//! # Safety
//! As `wide`'s: only where the CPU has the width's instructions (the
//! lanes' `AVX2` flag, `octant::available`).

#[cfg(target_arch = "x86_64")]
use super::wide::{self, I, WIDTH};

#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn splat(x: u32) -> I {
    wide::splat_i(x as i32)
}

/// Each word shifted right by `s`.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn shr(a: I, s: u32) -> I {
    wide::shr_each(a, splat(s))
}

/// `rng::pcg_hash` of each word.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn pcg_hash(v: I) -> I {
    let state = wide::add_i(wide::mul_i(v, splat(747796405)), splat(2891336453));
    let shift = wide::add_i(shr(state, 28), splat(4));
    let word = wide::mul_i(
        wide::xor_i(wide::shr_each(state, shift), state),
        splat(277803737),
    );
    wide::xor_i(shr(word, 22), word)
}

/// `rng::laine_karras_permutation` of each word.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn laine_karras_permutation(x: I, seed: I) -> I {
    let x = wide::xor_i(x, wide::mul_i(x, splat(0x3d20adea)));
    let x = wide::add_i(x, seed);
    let x = wide::mul_i(x, wide::or_i(shr(seed, 16), splat(1)));
    let x = wide::xor_i(x, wide::mul_i(x, splat(0x05526c56)));
    wide::xor_i(x, wide::mul_i(x, splat(0x53a22864)))
}

/// Each 4-bit value with its bits reversed, as the low nibble and as the
/// high one.
#[cfg(all(target_arch = "x86_64", not(target_feature = "gfni")))]
const NIBBLES_REVERSED: [u8; 16] = [
    0x0, 0x8, 0x4, 0xc, 0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb, 0x7, 0xf,
];
#[cfg(all(target_arch = "x86_64", not(target_feature = "gfni")))]
const NIBBLES_REVERSED_HIGH: [u8; 16] = [
    0x00, 0x80, 0x40, 0xc0, 0x20, 0xa0, 0x60, 0xe0, 0x10, 0x90, 0x50, 0xd0, 0x30, 0xb0, 0x70, 0xf0,
];
/// Byte indices that reverse the bytes of each 32-bit word (per 16 bytes).
#[cfg(target_arch = "x86_64")]
const WORD_BYTES_REVERSED: [u8; 16] = [3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12];

/// `u32::reverse_bits` of each word: the bytes in reverse order (a byte
/// shuffle of the word's own bytes), then the bits of each byte by GFNI's
/// affine transform where the build has it.
#[cfg(all(target_arch = "x86_64", target_feature = "gfni"))]
#[inline]
#[target_feature(enable = "avx2")]
fn reverse_bits(x: I) -> I {
    wide::reverse_byte_bits(wide::shuffle_bytes(x, &WORD_BYTES_REVERSED))
}

/// `u32::reverse_bits` of each word without GFNI: the bytes in reverse
/// order, the bits of each byte reversed by two 16-entry nibble tables.
#[cfg(all(target_arch = "x86_64", not(target_feature = "gfni")))]
#[inline]
#[target_feature(enable = "avx2")]
fn reverse_bits(x: I) -> I {
    let x = wide::shuffle_bytes(x, &WORD_BYTES_REVERSED);
    let nibble = splat(0x0f0f_0f0f);
    let lo = wide::and_i(x, nibble);
    let hi = wide::and_i(shr(x, 4), nibble);
    wide::or_i(
        wide::lookup_bytes(&NIBBLES_REVERSED_HIGH, lo),
        wide::lookup_bytes(&NIBBLES_REVERSED, hi),
    )
}

/// `rng::sobol1_reversed` of each word.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn sobol1_reversed(i: I) -> I {
    let i = wide::xor_i(i, wide::and_i(shr(i, 1), splat(0x55555555)));
    let i = wide::xor_i(i, wide::and_i(shr(i, 2), splat(0x33333333)));
    let i = wide::xor_i(i, wide::and_i(shr(i, 4), splat(0x0f0f0f0f)));
    let i = wide::xor_i(i, wide::and_i(shr(i, 8), splat(0x00ff00ff)));
    wide::xor_i(i, wide::and_i(shr(i, 16), splat(0x0000ffff)))
}

/// `rng::rng_dim_seed` for each lane's hash and dimension, the salt
/// `pcg_hash(8 dim + purpose)` computed.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn dim_seed(hash: I, dim: I, purpose: u32) -> I {
    let slot = wide::add_i(wide::shl_each(dim, splat(3)), splat(purpose));
    pcg_hash(wide::xor_i(hash, pcg_hash(slot)))
}

/// `rng::rng_unit` of each word.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn unit(bits: I) -> [f32; WIDTH] {
    let f = wide::mul(wide::to_float(shr(bits, 8)), wide::splat(1.0 / 16777216.0));
    let mut out = [0f32; WIDTH];
    wide::store(&mut out, f);
    out
}

/// The lanes' keys: `RngKey::hash` and `reversed_index` per lane.
#[cfg(target_arch = "x86_64")]
pub struct KeyLanes {
    pub hash: [u32; WIDTH],
    pub reversed: [u32; WIDTH],
}

#[cfg(target_arch = "x86_64")]
impl KeyLanes {
    /// `rng::sobol_float` per lane.
    ///
    /// # Safety
    /// See the module.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn float(&self, dim: &[u32; WIDTH]) -> [f32; WIDTH] {
        let (hash, dim) = (wide::load_i(&self.hash), wide::load_i(dim));
        let i = reverse_bits(laine_karras_permutation(
            wide::load_i(&self.reversed),
            dim_seed(hash, dim, 0),
        ));
        unit(reverse_bits(laine_karras_permutation(
            i,
            dim_seed(hash, dim, 1),
        )))
    }

    /// `rng::sobol_float2` per lane.
    ///
    /// # Safety
    /// See the module.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn float2(&self, dim: &[u32; WIDTH]) -> ([f32; WIDTH], [f32; WIDTH]) {
        let (hash, dim) = (wide::load_i(&self.hash), wide::load_i(dim));
        let i = reverse_bits(laine_karras_permutation(
            wide::load_i(&self.reversed),
            dim_seed(hash, dim, 2),
        ));
        let x = reverse_bits(laine_karras_permutation(i, dim_seed(hash, dim, 3)));
        let y = reverse_bits(laine_karras_permutation(
            sobol1_reversed(i),
            dim_seed(hash, dim, 4),
        ));
        (unit(x), unit(y))
    }

    /// `rng::rng_float` of the independent sampler per lane.
    ///
    /// # Safety
    /// See the module.
    #[inline]
    #[target_feature(enable = "avx2")]
    pub fn independent_float(&self, dim: &[u32; WIDTH]) -> [f32; WIDTH] {
        unit(pcg_hash(wide::add_i(
            wide::load_i(&self.hash),
            pcg_hash(wide::load_i(dim)),
        )))
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::constants::{SAMPLER_INDEPENDENT, SAMPLER_SOBOL};
    use crate::cpu::common::rng::{rng_float, rng_sampler_key, sobol_float, sobol_float2};

    #[test]
    fn lane_draws_equal_the_scalar_ones_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            println!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        let mut checked = 0;
        for round in 0..2000u32 {
            let keys: [_; WIDTH] = std::array::from_fn(|l| {
                let pixel = round.wrapping_mul(7919) ^ (l as u32 * 104729);
                let sample = round.wrapping_mul(31) + l as u32 * (round % 5);
                rng_sampler_key(SAMPLER_SOBOL, pixel, sample, round % 3)
            });
            let lanes = KeyLanes {
                hash: keys.map(|k| k.hash),
                reversed: keys.map(|k| k.reversed_index),
            };
            // Dimensions of early and late bounces, past the salt table.
            let dim: [u32; WIDTH] = std::array::from_fn(|l| (round * 13 + l as u32 * 97) % 1200);
            // SAFETY: AVX2 is there (checked above).
            let (f, (x, y)) = unsafe { (lanes.float(&dim), lanes.float2(&dim)) };
            for l in 0..WIDTH {
                assert_eq!(f[l].to_bits(), sobol_float(keys[l], dim[l]).to_bits());
                let s = sobol_float2(keys[l], dim[l]);
                assert_eq!(
                    (x[l].to_bits(), y[l].to_bits()),
                    (s.x.to_bits(), s.y.to_bits())
                );
                checked += 1;
            }
        }
        assert_eq!(checked, 2000 * WIDTH);
    }

    #[test]
    fn lane_independent_draws_equal_the_scalar_ones_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            println!("no AVX2 on this CPU: nothing to compare");
            return;
        }
        for round in 0..2000u32 {
            let keys: [_; WIDTH] = std::array::from_fn(|l| {
                let pixel = round.wrapping_mul(7919) ^ (l as u32 * 104729);
                rng_sampler_key(SAMPLER_INDEPENDENT, pixel, round + l as u32, round % 3)
            });
            let lanes = KeyLanes {
                hash: keys.map(|k| k.hash),
                reversed: keys.map(|k| k.reversed_index),
            };
            let dim: [u32; WIDTH] = std::array::from_fn(|l| (round * 13 + l as u32 * 97) % 1200);
            // SAFETY: AVX2 is there (checked above).
            let f = unsafe { lanes.independent_float(&dim) };
            for l in 0..WIDTH {
                assert_eq!(f[l].to_bits(), rng_float(keys[l], dim[l]).to_bits());
            }
        }
    }
}
