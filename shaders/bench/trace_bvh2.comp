#version 460
#extension GL_GOOGLE_include_directive : require
// trace_bvh2: the renderer's BVH2 traversal, storage-buffer fetches.
#include "bvh2_main.glsl"
