// Reads and writes of the path state and shadow rays (bindings.glsl), GPU
// only: the CPU reference keeps a path in local variables. lavapipe runs a
// storage-buffer load or store as a loop over the lanes, one word at a time,
// but gathers texels as vectors: so state is read through texel views and
// written as 64-bit words, half as many stores as 32-bit ones. A kernel
// reads a slot before it writes it, and later kernels see the writes after
// the barrier between dispatches.
#ifndef PATH_STATE_GLSL
#define PATH_STATE_GLSL

#include "rng.glsl"
#include "camera.glsl"

u64vec2 pack_words(uvec4 v) {
    return u64vec2(packUint2x32(v.xy), packUint2x32(v.zw));
}

u64vec2 pack_words(vec4 v) {
    return pack_words(floatBitsToUint(v));
}

vec4 read_path_origin(uint path) { return uintBitsToFloat(texelFetch(path_origin_texels, int(path))); }
// Direction xyz, w = the dispersion channel (bits 0-1) and the light BVH's
// prev_normal code shifted by 2 (PathState).
vec3 read_path_direction(uint path) { return uintBitsToFloat(texelFetch(path_direction_texels, int(path)).xyz); }
uint read_path_dispersion_channel(uint path) { return texelFetch(path_direction_texels, int(path)).w & 3u; }
uint read_path_prev_normal(uint path) { return texelFetch(path_direction_texels, int(path)).w >> 2u; }
uvec4 read_path_hit(uint path) { return texelFetch(path_hit_texels, int(path)); }
// Throughput rgb, w = eta_scale (PathState).
vec4 read_path_throughput(uint path) { return uintBitsToFloat(texelFetch(path_throughput_texels, int(path))); }
vec3 read_path_radiance(uint path) { return uintBitsToFloat(texelFetch(path_radiance_texels, int(path)).xyz); }
// Radiance rgb, w = the bounce index of the path's next extension ray: paths
// the per-path loop parks join the wavefront at their own bounce.
uvec4 read_path_radiance_bounce(uint path) { return texelFetch(path_radiance_texels, int(path)); }
vec4 read_shadow_origin(uint k) { return uintBitsToFloat(texelFetch(shadow_origin_texels, int(k))); }
vec4 read_shadow_direction(uint k) { return uintBitsToFloat(texelFetch(shadow_direction_texels, int(k))); }
uvec4 read_shadow_contribution_bounce(uint k) { return texelFetch(shadow_contribution_texels, int(k)); }

void write_path_origin(uint path, vec3 o, float prev_pdf) { path_origin[path] = pack_words(vec4(o, prev_pdf)); }
void write_path_direction(uint path, vec3 d, uint dispersion_channel, uint prev_normal) {
    path_direction[path] = pack_words(uvec4(floatBitsToUint(d), dispersion_channel | (prev_normal << 2u)));
}
void write_path_hit(uint path, uvec4 h) { path_hit[path] = pack_words(h); }
void write_path_throughput(uint path, vec3 t, float eta_scale) { path_throughput[path] = pack_words(vec4(t, eta_scale)); }
void write_path_radiance(uint path, vec3 l, uint bounce) {
    path_radiance[path] = pack_words(uvec4(floatBitsToUint(l), bounce));
}
// The auxiliary outputs (aov.glsl), two vec4 per path; plain storage
// access: they are read and written only at the camera ray's hit and along
// delta chains.
vec4 read_path_aov(uint path, uint k) { return path_aov[2u * path + k]; }
void write_path_aov(uint path, vec4 a, vec4 b) {
    path_aov[2u * path] = a;
    path_aov[2u * path + 1u] = b;
}
// The shadow ray of `path` at `bounce` (contribution's w: its coverage seed
// needs the bounce, which the path's own state has moved past).
void write_shadow_ray(uint k, vec3 o, float t_max, vec3 d, uint path, vec3 contribution,
                      uint bounce) {
    shadow_origin[k] = pack_words(vec4(o, t_max));
    shadow_direction[k] = pack_words(vec4(d, uintBitsToFloat(path)));
    shadow_contribution[k] = pack_words(uvec4(floatBitsToUint(contribution), bounce));
}

// The random-number key of the path sample in pool slot `path` (pc, params:
// bindings.glsl): slot k of a chunk is path k of path_pixel_sample.
RngKey path_rng_key(uint path) {
    PathSample s = path_pixel_sample(params, pc.pixel_start, pc.sample_start, path);
    return rng_sampler_key(params.rng_sampler, s.pixel, s.sample_index, params.seed);
}

#endif
