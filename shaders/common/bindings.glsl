// The one descriptor set every wavefront kernel shares (host side:
// src/gpu/wavefront.rs, `Binding`). Kernels use the bindings they need.
#ifndef BINDINGS_GLSL
#define BINDINGS_GLSL

#extension GL_ARB_gpu_shader_int64 : require

#include "constants.glsl"
#include "types.glsl"

layout(std140, set = 0, binding = 0) uniform ParamsBlock { RenderParams params; };
// Scene (read only).
layout(std430, set = 0, binding = 1) readonly buffer BvhNodes { CwBvhNode bvh_nodes[]; };
layout(std430, set = 0, binding = 2) readonly buffer TriVerts { TriangleVerts tri_verts[]; };
layout(std430, set = 0, binding = 3) readonly buffer TriShading { TriangleShading tri_shading[]; };
layout(std430, set = 0, binding = 4) readonly buffer Materials { MaterialData materials[]; };
layout(std430, set = 0, binding = 5) readonly buffer Emitters { Emitter emitters[]; };
// Path state, structure of arrays indexed by path slot, and the shadow
// rays. Kernels write them here as pairs of 64-bit words (lavapipe stores
// one word per lane at a time, so 64-bit words halve the stores) and read
// them through the texel views at bindings 30..37; path_state.glsl has the
// accessors. Each element is 16 bytes, as commented.
layout(std430, set = 0, binding = 6) buffer PathOrigin { u64vec2 path_origin[]; };        // xyz, w = previous BSDF pdf (0: no MIS)
layout(std430, set = 0, binding = 7) buffer PathDirection { u64vec2 path_direction[]; };  // xyz
layout(std430, set = 0, binding = 8) buffer PathHit { u64vec2 path_hit[]; };             // t bits, triangle, b1 bits, b2 bits
layout(std430, set = 0, binding = 9) buffer PathThroughput { u64vec2 path_throughput[]; };
layout(std430, set = 0, binding = 10) buffer PathRadiance { u64vec2 path_radiance[]; };
// Queues: two ray queues (by bounce parity) of path slots, and shadow rays.
layout(std430, set = 0, binding = 11) buffer RayQueues { uint ray_queue[]; };          // 2 * pool size
layout(std430, set = 0, binding = 12) buffer ShadowOrigin { u64vec2 shadow_origin[]; };   // xyz, w = t_max
layout(std430, set = 0, binding = 13) buffer ShadowDirection { u64vec2 shadow_direction[]; }; // xyz, w = path slot bits
layout(std430, set = 0, binding = 14) buffer ShadowContribution { u64vec2 shadow_contribution[]; };
layout(std430, set = 0, binding = 15) buffer Counters { uint counters[]; };
layout(std430, set = 0, binding = 16) buffer DispatchArgs { uint dispatch_args[]; };   // 2 x (x, y, z)
layout(std430, set = 0, binding = 17) buffer Film { FilmPixel film[]; };

// The read-only scene arrays again, as 16-byte texels (RGBA32UI), read by
// scene_fetch.glsl: lavapipe gathers texels as vectors, while its
// storage-buffer loads run one lane at a time.
layout(set = 0, binding = 18) uniform usamplerBuffer bvh_node_texels;
layout(set = 0, binding = 19) uniform usamplerBuffer tri_vert_texels;
layout(set = 0, binding = 20) uniform usamplerBuffer tri_shading_texels;
layout(set = 0, binding = 21) uniform usamplerBuffer material_texels;
layout(set = 0, binding = 22) uniform usamplerBuffer emitter_texels;
#define BVH_TEXEL_FETCH

// Textures (textures.glsl): the texture table, the texels (one RGBA8 texel
// per R32UI element, after the sRGB decode table) and each triangle's
// texture coordinates and tangents. Dummies of 16 bytes in untextured scenes.
layout(std430, set = 0, binding = 23) readonly buffer Textures { TextureInfo textures[]; };
layout(set = 0, binding = 24) uniform usamplerBuffer texture_texels;
layout(std430, set = 0, binding = 25) readonly buffer TriTexcoords { TriangleTexcoords tri_texcoords[]; };
// Lights and the environment map (host side: src/packed.rs, PackedLights).
layout(std430, set = 0, binding = 26) readonly buffer LightParamsBlock { LightParams light_params; };
layout(std430, set = 0, binding = 27) readonly buffer Lights { Light lights[]; };
// Environment map distribution: marginal cdf over rows (env_height + 1
// floats), then each row's conditional cdf (env_width + 1 floats per row).
layout(std430, set = 0, binding = 28) readonly buffer EnvCdf { float env_cdf[]; };
layout(std430, set = 0, binding = 29) readonly buffer EnvRadiance { vec4 env_radiance[]; };  // rgb, row-major, row 0 at +Y

// Bindings 6..10 and 12..14 again, as RGBA32UI texels, for reading.
layout(set = 0, binding = 30) uniform usamplerBuffer path_origin_texels;
layout(set = 0, binding = 31) uniform usamplerBuffer path_direction_texels;
layout(set = 0, binding = 32) uniform usamplerBuffer path_hit_texels;
layout(set = 0, binding = 33) uniform usamplerBuffer path_throughput_texels;
layout(set = 0, binding = 34) uniform usamplerBuffer path_radiance_texels;
layout(set = 0, binding = 35) uniform usamplerBuffer shadow_origin_texels;
layout(set = 0, binding = 36) uniform usamplerBuffer shadow_direction_texels;
layout(set = 0, binding = 37) uniform usamplerBuffer shadow_contribution_texels;

layout(push_constant) uniform Push { PushConstants pc; };

#endif
