#version 460
#extension GL_GOOGLE_include_directive : require
// trace_bvh2_texel: the renderer's BVH2 traversal with texel fetches
// defined (BVH_TEXEL_FETCH, renamed SCENE_TEXEL_FETCH with scene_fetch.glsl),
// so bvh.glsl reads nodes and triangles through texel buffers, as the
// renderer's bindings.glsl chooses.
#define BVH_TEXEL_FETCH
#define SCENE_TEXEL_FETCH
#include "bvh2_main.glsl"
