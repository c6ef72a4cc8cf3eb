#version 460
#extension GL_GOOGLE_include_directive : require
// shadow_queue_args: indirect dispatch size for this bounce's shadow rays.
// reads: counters (shadow queue); writes: dispatch_args[3..6], counters.
#include "bindings.glsl"

layout(local_size_x = 1) in;

void main() {
    uint n = counters[COUNTER_SHADOW];
    dispatch_args[3] = (n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    dispatch_args[4] = 1u;
    dispatch_args[5] = 1u;
    uint lo = counters[COUNTER_SHADOW_RAYS_LO];
    uint carry;
    counters[COUNTER_SHADOW_RAYS_LO] = uaddCarry(lo, n, carry);
    counters[COUNTER_SHADOW_RAYS_HI] += carry;
}
