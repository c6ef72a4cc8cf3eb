#version 460
#extension GL_GOOGLE_include_directive : require
// trace_cwbvh_texel: CWBVH8 closest hit, nodes and triangles read from
// RGBA32UI texel buffers (see cwbvh.glsl).
#define CW_TEXELS
#include "cwbvh.glsl"
