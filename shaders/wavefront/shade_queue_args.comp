#version 460
#extension GL_GOOGLE_include_directive : require
// shade_queue_args: indirect dispatch sizes of shade_basic and shade when
// shading is split by material (the shading queues extend filled).
// reads: counters (shading queues); writes: dispatch_args[6..12].
#include "bindings.glsl"

layout(local_size_x = 1) in;

void main() {
    uint basic = counters[COUNTER_SHADE_BASIC];
    uint full = counters[COUNTER_SHADE_FULL];
    dispatch_args[6] = (basic + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    dispatch_args[7] = 1u;
    dispatch_args[8] = 1u;
    dispatch_args[9] = (full + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    dispatch_args[10] = 1u;
    dispatch_args[11] = 1u;
}
