// Body of trace_bvh2 and trace_bvh2_texel: closest hit of every ray through
// the renderer's BVH2 traversal (shaders/common/bvh.glsl, included unchanged),
// for benches/traversal.rs.
#include "bench_bindings.glsl"

layout(std430, set = 0, binding = 1) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(set = 0, binding = 6) uniform usamplerBuffer bvh_node_texels;  // 4 texels per BvhNode

#include "bvh.glsl"

layout(local_size_x = WORKGROUP_SIZE) in;

void main() {
    uint ray = gl_GlobalInvocationID.x;
    if (ray >= bench.ray_count) return;
    vec4 o = rays[2u * ray];
    vec3 d = rays[2u * ray + 1u].xyz;
    Hit hit = trace_ray(o.xyz, d, o.w, false);
    results[ray] = uvec2(floatBitsToUint(hit.t), hit.triangle);
}
