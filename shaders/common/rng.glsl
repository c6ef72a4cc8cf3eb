// Stateless random numbers indexed by (pixel, sample, dimension, seed): the
// same function on both back ends (twin: src/cpu/common/rng.rs), so any sample can be
// replayed on its own. Two samplers behind one key (RngKey):
// - independent: a hash of (path, dimension). Hash: PCG-RXS-M-XS (Jarzynski
//   and Olano, JCGT 2020).
// - sobol: Owen-scrambled Sobol points, padded to any number of dimensions by
//   shuffling the sample index per dimension (Burley, "Practical Hash-based
//   Owen Scrambling", JCGT 2020). rng_float draws from the 1D sequence
//   (van der Corput), rng_float2 from the 2D one (Sobol dimensions 0 and 1),
//   so the first 2^k samples of a pixel are stratified in every 1D and every
//   2D draw; each (pixel, dimension, seed) gets its own scrambling.
// Every step is loop-free: lavapipe ends an invocation's loops after 65,535
// iterations in total, and the traversal needs them.
#ifndef RNG_GLSL
#define RNG_GLSL

#include "constants.glsl"
#include "features.glsl"

uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// What every random number of one path sample derives from. `hash` is the
// path's hash (independent) or the pixel's scrambling seed (sobol).
struct RngKey {
    uint hash;
    uint sample_index;
    uint kind;              // SAMPLER_*
};

// The key of one path sample drawn by sampler `kind` (SAMPLER_*).
RngKey rng_sampler_key(uint kind, uint pixel, uint sample_index, uint seed) {
    RngKey k;
    k.hash = kind == SAMPLER_SOBOL ? pcg_hash(pcg_hash(pixel ^ 0x5bd1e995u) + seed)
                                      : pcg_hash(pcg_hash(pcg_hash(sample_index) + pixel) + seed);
    k.sample_index = sample_index;
    k.kind = kind;
    return k;
}

// One key per path sample from the default sampler; every dimension of that
// sample derives from it.
RngKey rng_path_key(uint pixel, uint sample_index, uint seed) {
    return rng_sampler_key(SAMPLER_DEFAULT, pixel, sample_index, seed);
}

// A random bijection of 32-bit words in which each bit depends only on the
// bits below it (Laine and Karras 2011; the constants of Burley 2020, sec. 3).
uint laine_karras_permutation(uint x, uint seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16u) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

// Owen's nested uniform scramble of a 32-bit fixed-point fraction: each bit
// is flipped by a hash of the bits above it.
uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(laine_karras_permutation(bitfieldReverse(x), seed));
}

// Sobol dimension 1 (generator: the Pascal matrix mod 2), bit-reversed: bit j
// of the result is the parity of the index bits at positions k that contain
// j as a bit subset (Lucas: C(k, j) is odd iff j is a subset of k), a
// superset sum computed in five steps.
uint sobol1_reversed(uint i) {
    i ^= (i >> 1u) & 0x55555555u;
    i ^= (i >> 2u) & 0x33333333u;
    i ^= (i >> 4u) & 0x0f0f0f0fu;
    i ^= (i >> 8u) & 0x00ff00ffu;
    i ^= (i >> 16u) & 0x0000ffffu;
    return i;
}

// Sobol dimension 2 (primitive polynomial x^2 + x + 1, direction numbers
// m = 1, 3; Joe and Kuo), bit-reversed like sobol1_reversed: the XOR of the
// reversed direction numbers of the index's set bits, written out (no loop).
uint sobol2_reversed(uint i) {
    uint x = 0u;
    x ^= (0u - ((i >> 0u) & 1u)) & 0x1u;
    x ^= (0u - ((i >> 1u) & 1u)) & 0x3u;
    x ^= (0u - ((i >> 2u) & 1u)) & 0x6u;
    x ^= (0u - ((i >> 3u) & 1u)) & 0x9u;
    x ^= (0u - ((i >> 4u) & 1u)) & 0x17u;
    x ^= (0u - ((i >> 5u) & 1u)) & 0x3au;
    x ^= (0u - ((i >> 6u) & 1u)) & 0x71u;
    x ^= (0u - ((i >> 7u) & 1u)) & 0xa3u;
    x ^= (0u - ((i >> 8u) & 1u)) & 0x116u;
    x ^= (0u - ((i >> 9u) & 1u)) & 0x339u;
    x ^= (0u - ((i >> 10u) & 1u)) & 0x677u;
    x ^= (0u - ((i >> 11u) & 1u)) & 0x9aau;
    x ^= (0u - ((i >> 12u) & 1u)) & 0x1601u;
    x ^= (0u - ((i >> 13u) & 1u)) & 0x3903u;
    x ^= (0u - ((i >> 14u) & 1u)) & 0x7706u;
    x ^= (0u - ((i >> 15u) & 1u)) & 0xaa09u;
    x ^= (0u - ((i >> 16u) & 1u)) & 0x10117u;
    x ^= (0u - ((i >> 17u) & 1u)) & 0x3033au;
    x ^= (0u - ((i >> 18u) & 1u)) & 0x60671u;
    x ^= (0u - ((i >> 19u) & 1u)) & 0x909a3u;
    x ^= (0u - ((i >> 20u) & 1u)) & 0x171616u;
    x ^= (0u - ((i >> 21u) & 1u)) & 0x3a3939u;
    x ^= (0u - ((i >> 22u) & 1u)) & 0x717777u;
    x ^= (0u - ((i >> 23u) & 1u)) & 0xa3aaaau;
    x ^= (0u - ((i >> 24u) & 1u)) & 0x1170001u;
    x ^= (0u - ((i >> 25u) & 1u)) & 0x33a0003u;
    x ^= (0u - ((i >> 26u) & 1u)) & 0x6710006u;
    x ^= (0u - ((i >> 27u) & 1u)) & 0x9a30009u;
    x ^= (0u - ((i >> 28u) & 1u)) & 0x16160017u;
    x ^= (0u - ((i >> 29u) & 1u)) & 0x3939003au;
    x ^= (0u - ((i >> 30u) & 1u)) & 0x77770071u;
    x ^= (0u - ((i >> 31u) & 1u)) & 0xaaaa00a3u;
    return x;
}

// A scrambling seed for one (pixel, dimension, purpose).
uint rng_dim_seed(uint pixel_seed, uint dim, uint purpose) {
    return pcg_hash(pixel_seed ^ pcg_hash(dim * 8u + purpose));
}

// Top 24 bits as a float in [0, 1).
float rng_unit(uint bits) {
    return float(bits >> 8u) * (1.0 / 16777216.0);
}

// Owen-scrambled van der Corput point of a shuffled index: the scramble of
// reverse(i) is reverse(laine_karras_permutation(i)).
float sobol_float(RngKey key, uint dim) {
    uint i = nested_uniform_scramble(key.sample_index, rng_dim_seed(key.hash, dim, 0u));
    return rng_unit(bitfieldReverse(laine_karras_permutation(i, rng_dim_seed(key.hash, dim, 1u))));
}

vec2 sobol_float2(RngKey key, uint dim) {
    uint i = nested_uniform_scramble(key.sample_index, rng_dim_seed(key.hash, dim, 2u));
    uint x = bitfieldReverse(laine_karras_permutation(i, rng_dim_seed(key.hash, dim, 3u)));
    uint y = bitfieldReverse(laine_karras_permutation(sobol1_reversed(i),
                                                      rng_dim_seed(key.hash, dim, 4u)));
    return vec2(rng_unit(x), rng_unit(y));
}

// The third coordinate of the Owen-scrambled 3D Sobol point whose first two
// are sobol_float2(key, dim): the same shuffled index, so the three are
// stratified jointly (dimensions 0 and 2 of Sobol form a (1, 2)-sequence).
float sobol_float2_third(RngKey key, uint dim) {
    uint i = nested_uniform_scramble(key.sample_index, rng_dim_seed(key.hash, dim, 2u));
    return rng_unit(bitfieldReverse(laine_karras_permutation(sobol2_reversed(i),
                                                             rng_dim_seed(key.hash, dim, 5u))));
}

// Uniform in [0, 1).
float rng_float(RngKey key, uint dim) {
    if (FEATURE_SOBOL && key.kind == SAMPLER_SOBOL) return sobol_float(key, dim);
    return rng_unit(pcg_hash(key.hash + pcg_hash(dim)));
}

// Uniform in [0, 1)^2; uses dimensions dim and dim + 1.
vec2 rng_float2(RngKey key, uint dim) {
    if (FEATURE_SOBOL && key.kind == SAMPLER_SOBOL) return sobol_float2(key, dim);
    return vec2(rng_float(key, dim), rng_float(key, dim + 1u));
}

// The seed of one ray's stochastic alpha (BLEND) tests: the ray of
// `purpose` (0 extension, 1 shadow) at `bounce` of the path sample `key`.
// A hash, not a sampler dimension: the number of tests along a ray varies.
uint rng_coverage_seed(RngKey key, uint bounce, uint purpose) {
    return pcg_hash(key.hash ^ pcg_hash(key.sample_index
                                        ^ pcg_hash(bounce * 2u + purpose + RNG_COVERAGE_SALT)));
}

// Uniform in [0, 1): the coverage test of `triangle` by the ray of `ray_seed`.
float rng_coverage(uint ray_seed, uint triangle) {
    return rng_unit(pcg_hash(ray_seed ^ pcg_hash(triangle)));
}

#endif
