//! Twin of `shaders/common/rng.glsl`: wrapping arithmetic reproduces GLSL
//! `uint`. Two samplers behind one key: independent (a PCG hash per path and
//! dimension) and Owen-scrambled Sobol padded by per-dimension index
//! shuffles (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020).

use crate::constants::{
    DIM_BOUNCE_BASE, DIM_PER_BOUNCE, RNG_COVERAGE_SALT, SAMPLER_DEFAULT, SAMPLER_SOBOL,
};

pub const fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// What every random number of one path sample derives from. `hash` is the
/// path's hash (independent) or the pixel's scrambling seed (sobol).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RngKey {
    pub hash: u32,
    pub sample_index: u32,
    /// `SAMPLER_*`.
    pub kind: u32,
    /// `sample_index.reverse_bits()`, which every Sobol draw of the path
    /// starts from (CPU only: computed once per path instead of per draw).
    pub reversed_index: u32,
}

/// The key of one path sample drawn by sampler `kind` (`SAMPLER_*`).
pub fn rng_sampler_key(kind: u32, pixel: u32, sample_index: u32, seed: u32) -> RngKey {
    let hash = if kind == SAMPLER_SOBOL {
        pcg_hash(pcg_hash(pixel ^ 0x5bd1e995).wrapping_add(seed))
    } else {
        pcg_hash(pcg_hash(pcg_hash(sample_index).wrapping_add(pixel)).wrapping_add(seed))
    };
    RngKey {
        hash,
        sample_index,
        kind,
        reversed_index: sample_index.reverse_bits(),
    }
}

/// One key per path sample from the default sampler.
pub fn rng_path_key(pixel: u32, sample_index: u32, seed: u32) -> RngKey {
    rng_sampler_key(SAMPLER_DEFAULT, pixel, sample_index, seed)
}

/// A random bijection of 32-bit words in which each bit depends only on the
/// bits below it (Laine and Karras 2011; the constants of Burley 2020, sec. 3).
pub fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x05526c56);
    x ^= x.wrapping_mul(0x53a22864);
    x
}

/// Owen's nested uniform scramble of a 32-bit fixed-point fraction.
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    nested_uniform_scramble_reversed(x.reverse_bits(), seed)
}

/// `nested_uniform_scramble` of the word whose bit reversal is `reversed`.
fn nested_uniform_scramble_reversed(reversed: u32, seed: u32) -> u32 {
    laine_karras_permutation(reversed, seed).reverse_bits()
}

/// Sobol dimension 1, bit-reversed: a superset sum over bit positions (see
/// `rng.glsl`).
pub fn sobol1_reversed(mut i: u32) -> u32 {
    i ^= (i >> 1) & 0x55555555;
    i ^= (i >> 2) & 0x33333333;
    i ^= (i >> 4) & 0x0f0f0f0f;
    i ^= (i >> 8) & 0x00ff00ff;
    i ^= (i >> 16) & 0x0000ffff;
    i
}

/// Sobol dimension 2's direction numbers (primitive polynomial x^2 + x + 1,
/// m = 1, 3; Joe and Kuo), bit-reversed (a unit test derives them).
const SOBOL2_REVERSED: [u32; 32] = [
    0x1, 0x3, 0x6, 0x9, 0x17, 0x3a, 0x71, 0xa3, 0x116, 0x339, 0x677, 0x9aa, 0x1601, 0x3903, 0x7706,
    0xaa09, 0x10117, 0x3033a, 0x60671, 0x909a3, 0x171616, 0x3a3939, 0x717777, 0xa3aaaa, 0x1170001,
    0x33a0003, 0x6710006, 0x9a30009, 0x16160017, 0x3939003a, 0x77770071, 0xaaaa00a3,
];

/// Sobol dimension 2, bit-reversed like `sobol1_reversed`: the XOR of the
/// reversed direction numbers of the index's set bits.
pub fn sobol2_reversed(i: u32) -> u32 {
    SOBOL2_REVERSED
        .iter()
        .enumerate()
        .fold(0, |x, (k, &c)| x ^ (0u32.wrapping_sub((i >> k) & 1) & c))
}

/// A scrambling seed for one (pixel, dimension, purpose).
pub fn rng_dim_seed(pixel_seed: u32, dim: u32, purpose: u32) -> u32 {
    let slot = dim.wrapping_mul(8).wrapping_add(purpose);
    let salt = match DIM_SALTS.get(slot as usize) {
        Some(&salt) => salt,
        None => pcg_hash(slot),
    };
    pcg_hash(pixel_seed ^ salt)
}

const SALTED_SLOTS: usize = 8 * (DIM_BOUNCE_BASE + 64 * DIM_PER_BOUNCE) as usize;

/// `pcg_hash(8 * dim + purpose)` of the first 64 bounces' dimensions,
/// computed at compile time (CPU only: the same numbers, one hash fewer per
/// seed).
static DIM_SALTS: [u32; SALTED_SLOTS] = {
    let mut salts = [0; SALTED_SLOTS];
    let mut i = 0;
    while i < salts.len() {
        salts[i] = pcg_hash(i as u32);
        i += 1;
    }
    salts
};

/// Top 24 bits as a float in [0, 1).
pub fn rng_unit(bits: u32) -> f32 {
    (bits >> 8) as f32 * (1.0 / 16777216.0)
}

pub fn sobol_float(key: RngKey, dim: u32) -> f32 {
    let i = nested_uniform_scramble_reversed(key.reversed_index, rng_dim_seed(key.hash, dim, 0));
    rng_unit(laine_karras_permutation(i, rng_dim_seed(key.hash, dim, 1)).reverse_bits())
}

pub fn sobol_float2(key: RngKey, dim: u32) -> glam::Vec2 {
    let i = nested_uniform_scramble_reversed(key.reversed_index, rng_dim_seed(key.hash, dim, 2));
    let x = laine_karras_permutation(i, rng_dim_seed(key.hash, dim, 3)).reverse_bits();
    let y =
        laine_karras_permutation(sobol1_reversed(i), rng_dim_seed(key.hash, dim, 4)).reverse_bits();
    glam::Vec2::new(rng_unit(x), rng_unit(y))
}

/// The third coordinate of the Owen-scrambled 3D Sobol point whose first
/// two are `sobol_float2(key, dim)`: the same shuffled index, so the three
/// are stratified jointly.
pub fn sobol_float2_third(key: RngKey, dim: u32) -> f32 {
    let i = nested_uniform_scramble_reversed(key.reversed_index, rng_dim_seed(key.hash, dim, 2));
    rng_unit(
        laine_karras_permutation(sobol2_reversed(i), rng_dim_seed(key.hash, dim, 5)).reverse_bits(),
    )
}

/// Uniform in [0, 1).
pub fn rng_float(key: RngKey, dim: u32) -> f32 {
    if key.kind == SAMPLER_SOBOL {
        return sobol_float(key, dim);
    }
    rng_unit(pcg_hash(key.hash.wrapping_add(pcg_hash(dim))))
}

/// Uniform in [0, 1)^2; uses dimensions `dim` and `dim + 1`.
pub fn rng_float2(key: RngKey, dim: u32) -> glam::Vec2 {
    if key.kind == SAMPLER_SOBOL {
        return sobol_float2(key, dim);
    }
    glam::Vec2::new(rng_float(key, dim), rng_float(key, dim + 1))
}

/// The seed of one ray's stochastic alpha (BLEND) tests: the ray of
/// `purpose` (0 extension, 1 shadow) at `bounce` of the path sample `key`.
/// A hash, not a sampler dimension: the number of tests along a ray varies.
pub fn rng_coverage_seed(key: RngKey, bounce: u32, purpose: u32) -> u32 {
    let ray = bounce
        .wrapping_mul(2)
        .wrapping_add(purpose)
        .wrapping_add(RNG_COVERAGE_SALT);
    pcg_hash(key.hash ^ pcg_hash(key.sample_index ^ pcg_hash(ray)))
}

/// Uniform in [0, 1): the coverage test of `triangle` by the ray of `ray_seed`.
pub fn rng_coverage(ray_seed: u32, triangle: u32) -> f32 {
    rng_unit(pcg_hash(ray_seed ^ pcg_hash(triangle)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direction numbers from the recurrence m_k = 2 m_(k-1) ^ 4 m_(k-2) ^
    /// m_(k-2) (x^2 + x + 1), m_1 = 1, m_2 = 3; the first 2^m points of
    /// dimensions 0 and 2 are then a (1, m, 2)-net: every elementary box of
    /// area 2^(1-m) holds exactly two of them.
    #[test]
    fn sobol_dimension_2_is_the_joe_kuo_sequence() {
        let mut m = vec![0u64, 1, 3];
        for k in 3..=32 {
            m.push((2 * m[k - 1]) ^ (4 * m[k - 2]) ^ m[k - 2]);
        }
        for k in 1..=32 {
            let v = ((m[k] << (32 - k)) & 0xffff_ffff) as u32;
            assert_eq!(
                SOBOL2_REVERSED[k - 1],
                v.reverse_bits(),
                "direction number {k}"
            );
        }
        let n = 256u32;
        for a in 0..=7 {
            let b = 7 - a;
            let mut boxes = std::collections::HashMap::new();
            for i in 0..n {
                let x = i.reverse_bits() >> (32 - a.max(1)) >> (a == 0) as u32;
                let y = sobol2_reversed(i).reverse_bits() >> (32 - b.max(1)) >> (b == 0) as u32;
                *boxes.entry((x, y)).or_insert(0) += 1;
            }
            assert!(boxes.values().all(|&c| c == 2), "boxes 2^-{a} x 2^-{b}");
        }
    }

    use crate::constants::SAMPLER_INDEPENDENT;

    const SAMPLERS: [u32; 2] = [SAMPLER_INDEPENDENT, SAMPLER_SOBOL];

    #[test]
    fn rng_float_is_in_unit_interval_and_uniform() {
        for sampler in SAMPLERS {
            let mut bins = [0u32; 16];
            for i in 0..160_000u32 {
                let u = rng_float(rng_sampler_key(sampler, i % 977, i / 977, 7), i % 13);
                assert!((0.0..1.0).contains(&u));
                bins[(u * 16.0) as usize] += 1;
            }
            // Chi-square with 15 degrees of freedom; 37.7 is the 0.001 quantile.
            let chi2: f64 = bins
                .iter()
                .map(|&b| (b as f64 - 10_000.0).powi(2) / 10_000.0)
                .sum();
            assert!(chi2 < 37.7, "sampler {sampler}: chi2 = {chi2}");
        }
    }

    #[test]
    fn different_seeds_give_different_streams() {
        for sampler in SAMPLERS {
            let same = (0..1000)
                .filter(|&d| {
                    rng_float(rng_sampler_key(sampler, 5, 3, 0), d)
                        == rng_float(rng_sampler_key(sampler, 5, 3, 1), d)
                })
                .count();
            assert!(same < 5, "sampler {sampler}: {same} equal draws");
        }
    }

    /// The generator matrix of Sobol dimension 1 from its direction numbers
    /// (primitive polynomial x + 1, m_1 = 1: v_{k+1} = v_k ^ (v_k >> 1)),
    /// against the five-step superset sum.
    #[test]
    fn sobol1_matches_its_direction_numbers() {
        let mut v = [0u32; 32];
        v[0] = 1 << 31;
        for k in 1..32 {
            v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        }
        let direct = |i: u32| (0..32).filter(|k| i >> k & 1 == 1).fold(0, |x, k| x ^ v[k]);
        let mut state = 12345u32;
        for i in (0..4096).chain((0..4096).map(|_| {
            state = pcg_hash(state);
            state
        })) {
            assert_eq!(sobol1_reversed(i).reverse_bits(), direct(i), "index {i}");
        }
    }

    /// Owen scrambling needs each output bit to depend only on the input bits
    /// above it (as a fraction), and to be a bijection.
    #[test]
    fn nested_uniform_scramble_keeps_prefixes() {
        let mut state = 99u32;
        for _ in 0..2000 {
            state = pcg_hash(state);
            let (x, seed) = (state, pcg_hash(state ^ 7));
            let bit = pcg_hash(state ^ 3) % 32;
            let flipped = x ^ (1 << bit);
            let (a, b) = (
                nested_uniform_scramble(x, seed),
                nested_uniform_scramble(flipped, seed),
            );
            // Bits above the flipped one agree; the flipped bit itself differs.
            let above = !((2u64 << bit) - 1) as u32;
            assert_eq!(a & above, b & above);
            assert_ne!(a >> bit & 1, b >> bit & 1);
        }
    }

    /// Number of samples of `points` in each cell of a `nx` by `ny` grid.
    fn cell_counts(points: &[(f32, f32)], nx: usize, ny: usize) -> Vec<u32> {
        let mut cells = vec![0u32; nx * ny];
        for &(x, y) in points {
            cells[(y * ny as f32) as usize * nx + (x * nx as f32) as usize] += 1;
        }
        cells
    }

    /// The first 2^k samples of a pixel are stratified in every dimension:
    /// one point in each of the 2^k intervals of every 1D draw, and a
    /// (0, k, 2)-net in every 2D draw (one point in each elementary interval
    /// 2^-a by 2^-(k-a)), for several pixels, seeds and dimensions.
    #[test]
    fn sobol_projections_are_stratified() {
        for (pixel, seed) in [(0u32, 0u32), (17, 0), (4095, 3), (123_456, 99)] {
            for dim in [0u32, 1, 8, 9, 11, 13, 40, 1000] {
                for k in 0..=8u32 {
                    let n = 1usize << k;
                    let key = |s: usize| rng_sampler_key(SAMPLER_SOBOL, pixel, s as u32, seed);
                    let xs: Vec<(f32, f32)> =
                        (0..n).map(|s| (rng_float(key(s), dim), 0.0)).collect();
                    let counts = cell_counts(&xs, n, 1);
                    assert!(
                        counts.iter().all(|&c| c == 1),
                        "1D dim {dim}, pixel {pixel}, seed {seed}, {n} samples: {counts:?}"
                    );
                    let ps: Vec<(f32, f32)> = (0..n)
                        .map(|s| {
                            let u = rng_float2(key(s), dim);
                            (u.x, u.y)
                        })
                        .collect();
                    for a in 0..=k {
                        let counts = cell_counts(&ps, 1 << a, 1 << (k - a));
                        assert!(
                            counts.iter().all(|&c| c == 1),
                            "2D dim {dim}, pixel {pixel}, seed {seed}, {n} samples, \
                             {}x{} cells: {counts:?}",
                            1 << a,
                            1 << (k - a)
                        );
                    }
                }
            }
        }
    }

    /// Across pixels (independent scramblings) every 1D and 2D draw is
    /// uniform, and different dimensions are uncorrelated: chi-square over a
    /// 16x16 grid of (dimension d, dimension d') pairs for 1D draws, and of
    /// the two coordinates of 2D draws.
    #[test]
    fn sobol_dimensions_are_uniform_and_independent_across_pixels() {
        // Chi-square with 255 degrees of freedom; 330.5 is the 0.001 quantile.
        let chi2 = |counts: &[u32], expected: f64| -> f64 {
            counts
                .iter()
                .map(|&c| (c as f64 - expected).powi(2) / expected)
                .sum()
        };
        let pixels = 25_600u32;
        for sample_index in [0u32, 1, 7, 64] {
            for (d0, d1) in [(0u32, 1u32), (8, 9), (9, 11), (13, 21)] {
                let key = |p| rng_sampler_key(SAMPLER_SOBOL, p, sample_index, 5);
                let pairs: Vec<(f32, f32)> = (0..pixels)
                    .map(|p| (rng_float(key(p), d0), rng_float(key(p), d1)))
                    .collect();
                let c = chi2(&cell_counts(&pairs, 16, 16), pixels as f64 / 256.0);
                assert!(
                    c < 330.5,
                    "1D dims {d0}, {d1}, sample {sample_index}: chi2 {c}"
                );
                let pairs: Vec<(f32, f32)> = (0..pixels)
                    .map(|p| {
                        let u = rng_float2(key(p), d0);
                        (u.x, u.y)
                    })
                    .collect();
                let c = chi2(&cell_counts(&pairs, 16, 16), pixels as f64 / 256.0);
                assert!(c < 330.5, "2D dim {d0}, sample {sample_index}: chi2 {c}");
                let pairs: Vec<(f32, f32)> = (0..pixels)
                    .map(|p| (rng_float2(key(p), d0).y, rng_float2(key(p), d1).x))
                    .collect();
                let c = chi2(&cell_counts(&pairs, 16, 16), pixels as f64 / 256.0);
                assert!(
                    c < 330.5,
                    "2D dims {d0}.y, {d1}.x, sample {sample_index}: chi2 {c}"
                );
            }
        }
    }
}
