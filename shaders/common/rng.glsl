// Stateless random numbers indexed by (pixel, sample, dimension, seed): the
// same function on both back ends (twin: src/cpu/rng.rs), so any sample can be
// replayed on its own. Hash: PCG-RXS-M-XS (Jarzynski and Olano, JCGT 2020).
#ifndef RNG_GLSL
#define RNG_GLSL

uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// One key per path sample; every dimension of that sample derives from it.
uint rng_path_key(uint pixel, uint sample_index, uint seed) {
    return pcg_hash(pcg_hash(pcg_hash(sample_index) + pixel) + seed);
}

// Uniform in [0, 1): the top 24 bits of the hash.
float rng_float(uint key, uint dim) {
    return float(pcg_hash(key + pcg_hash(dim)) >> 8u) * (1.0 / 16777216.0);
}

vec2 rng_float2(uint key, uint dim) {
    return vec2(rng_float(key, dim), rng_float(key, dim + 1u));
}

#endif
