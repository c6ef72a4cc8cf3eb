// Bindings of the traversal microbenchmark kernels (host: benches/traversal.rs),
// with the renderer's types (cwbvh.glsl declares the node arrays, bindings 1
// and 6).
#ifndef BENCH_BINDINGS_GLSL
#define BENCH_BINDINGS_GLSL

#include "constants.glsl"
#include "types.glsl"

layout(std140, set = 0, binding = 0) uniform ParamsBlock { RenderParams params; };
layout(std430, set = 0, binding = 2) readonly buffer TriVerts { TriangleVerts tri_verts[]; };
// Ray i: rays[2i] = (origin, t_max), rays[2i + 1] = (direction, unused).
layout(std430, set = 0, binding = 3) readonly buffer Rays { vec4 rays[]; };
// Ray i: (t bits, triangle slot or NO_HIT / OVERFLOW_HIT).
layout(std430, set = 0, binding = 4) writeonly buffer Results { uvec2 results[]; };
// Ray i: (nodes visited, triangles tested, stack pushes, 0); written only when
// bench.write_stats != 0 (kernels that can count).
layout(std430, set = 0, binding = 5) writeonly buffer Stats { uvec4 stats[]; };

// The same data as 16-byte texels (RGBA32UI), for traversals that read
// through texelFetch (lavapipe gathers texels as vectors; storage-buffer
// loads run one lane and one word at a time). Binding 6 holds the nodes,
// declared by each kernel.
layout(set = 0, binding = 7) uniform usamplerBuffer tri_vert_texels;  // 3 texels per triangle

// The rest of the renderer's scene arrays, declared only so that shared
// helpers reading them compile; traversal does not read them and the host
// binds nothing there.
layout(std430, set = 0, binding = 8) readonly buffer TriShading { TriangleShading tri_shading[]; };
layout(std430, set = 0, binding = 9) readonly buffer Materials { MaterialData materials[]; };
layout(std430, set = 0, binding = 10) readonly buffer Emitters { Emitter emitters[]; };
layout(set = 0, binding = 11) uniform usamplerBuffer tri_shading_texels;
layout(set = 0, binding = 12) uniform usamplerBuffer material_texels;
layout(set = 0, binding = 13) uniform usamplerBuffer emitter_texels;

layout(push_constant) uniform BenchPush {
    uint ray_count;
    uint write_stats;
} bench;

#endif
