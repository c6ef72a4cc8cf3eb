#version 460
#extension GL_GOOGLE_include_directive : require
// accumulate: adds the chunk's finished paths to the film. One invocation
// owns one pixel and visits that pixel's paths in sample order, so there are
// no float atomics and the result is deterministic.
// reads: path radiance, path AOVs; writes: film, AOV film, non-finite counter.
#include "bindings.glsl"
#include "camera.glsl"
#include "path_state.glsl"
#include "aov.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void film_add_sample(inout FilmPixel f, vec3 x) {
    float n = f.mean.w + 1.0;
    vec3 delta = x - f.mean.xyz;
    f.mean.xyz += delta / n;
    f.m2.xyz += delta * (x - f.mean.xyz);
    f.mean.w = n;
}

// Running means of one pixel's auxiliary outputs (twin: aov_add_sample in
// src/film/mod.rs); depth over the samples that hit something.
void aov_add_sample(inout AovPixel f, AovSample s) {
    float n = f.albedo.w + 1.0;
    f.albedo.xyz += (s.albedo - f.albedo.xyz) / n;
    f.normal.xyz += (s.normal - f.normal.xyz) / n;
    f.albedo.w = n;
    if (!isinf(s.depth)) {
        float h = f.depth.y + 1.0;
        f.depth.x += (s.depth - f.depth.x) / h;
        f.depth.y = h;
    }
}

void main() {
    uint pixel = gl_GlobalInvocationID.x;   // a film pixel
    uint pixels = film_pixel_count(params);
    if (pixel >= pixels) return;
    // Paths of this pixel sit at slots i = pixel + j * pixels - pixel_start
    // (the inverse of path_pixel_sample's film_pixel).
    uint j = pixel >= pc.pixel_start ? 0u : (pc.pixel_start - pixel + pixels - 1u) / pixels;
    uint i = pixel + j * pixels - pc.pixel_start;
    if (i >= pc.count) return;
    FilmPixel f = film[pixel];
    bool aov = FEATURE_AOV && params.aov != 0u;
    AovPixel fa;
    if (aov) fa = film_aov[pixel];
    uint nonfinite = 0u;
    for (; i < pc.count; i += pixels) {
        vec3 x = read_path_radiance(i);
        if (any(isnan(x)) || any(isinf(x))) {
            nonfinite++;
        } else {
            film_add_sample(f, x);
        }
        if (aov) aov_add_sample(fa, aov_unpack(read_path_aov(i, 0u), read_path_aov(i, 1u)));
    }
    film[pixel] = f;
    if (aov) film_aov[pixel] = fa;
    if (nonfinite > 0u) atomicAdd(counters[COUNTER_NONFINITE], nonfinite);
}
