#version 460
#extension GL_GOOGLE_include_directive : require
// trace_bvh2_texel: the renderer's BVH2 traversal with BVH_TEXEL_FETCH
// defined, so bvh.glsl reads nodes and triangles through texel buffers (the
// renderer's bindings.glsl chooses this).
#define BVH_TEXEL_FETCH
#include "bvh2_main.glsl"
