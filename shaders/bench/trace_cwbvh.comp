#version 460
#extension GL_GOOGLE_include_directive : require
// trace_cwbvh: CWBVH8 closest hit, nodes and triangles read from storage
// buffers (see cwbvh.glsl).
#include "cwbvh.glsl"
