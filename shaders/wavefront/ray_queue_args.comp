#version 460
#extension GL_GOOGLE_include_directive : require
// ray_queue_args: indirect dispatch size for this bounce's extend and shade,
// and empty queues for what extend and shade will produce.
// reads: counters (this bounce's ray queue); writes: dispatch_args[0..3], counters.
#include "bindings.glsl"

layout(local_size_x = 1) in;

void main() {
    uint q = pc.bounce & 1u;
    uint n = counters[COUNTER_RAYS_0 + q];
    dispatch_args[0] = (n + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    dispatch_args[1] = 1u;
    dispatch_args[2] = 1u;
    counters[COUNTER_RAYS_0 + (q ^ 1u)] = 0u;
    counters[COUNTER_SHADOW] = 0u;
    counters[COUNTER_SHADE_BASIC] = 0u;
    counters[COUNTER_SHADE_FULL] = 0u;
    uint lo = counters[COUNTER_EXTENSION_RAYS_LO];
    uint carry;
    counters[COUNTER_EXTENSION_RAYS_LO] = uaddCarry(lo, n, carry);
    counters[COUNTER_EXTENSION_RAYS_HI] += carry;
}
