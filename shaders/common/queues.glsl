// Queue helpers (host side: src/gpu/wavefront.rs). A queue is an array with
// an atomic counter in `counters`. Pushes are aggregated per subgroup: one
// atomic per subgroup instead of one per invocation (on lavapipe every
// atomic is a serialized read-modify-write per lane). Kernels that push
// enable GL_KHR_shader_subgroup_ballot before including this file.
#ifndef QUEUES_GLSL
#define QUEUES_GLSL

// Reserves one slot in the queue counted by counters[counter] for every
// active invocation that calls it, and returns this invocation's slot.
uint queue_push(uint counter) {
    uvec4 lanes = subgroupBallot(true);
    uint count = subgroupBallotBitCount(lanes);
    uint rank = subgroupBallotExclusiveBitCount(lanes);
    uint base = 0u;
    if (subgroupElect()) base = atomicAdd(counters[counter], count);
    return subgroupBroadcastFirst(base) + rank;
}

#endif
