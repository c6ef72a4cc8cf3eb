// Closest hit of every ray through a compressed wide BVH8 (Ylitie, Karras
// and Laine, "Efficient Incoherent Ray Traversal on GPUs Through Compressed
// Wide BVHs", HPG 2017) in obvhs 0.4's 80-byte node encoding (obvhs
// src/cwbvh/node.rs), for benches/traversal.rs. Kernels trace_cwbvh (nodes
// and triangles from storage buffers) and trace_cwbvh_texel (from RGBA32UI
// texel buffers: CW_TEXELS defined). Triangles are tested with the
// renderer's watertight test (intersect.glsl).
//
// Node: 20 words.
//   0..2  p: origin of the node's quantization grid
//   3     e.x | e.y << 8 | e.z << 16 | imask << 24; the grid step along an
//         axis is the float with exponent bits e (2^(e - 127))
//   4     child_base: index of the first inner child node
//   5     primitive_base: index of the first triangle of the leaf children
//   6..7  child_meta, one byte per child slot: 0 empty; inner child
//         0b001_11sss (slot s + 24); leaf child: triangle count in unary in
//         the top 3 bits, offset from primitive_base in the low 5 (< 24)
//   8..19 child_min_x, child_max_x, child_min_y, child_max_y, child_min_z,
//         child_max_z: 8 bytes each, child bounds in grid steps
// A node group is (child_base, hit bits << 24 | imask): bit 24 + (s ^ oct)
// set for a hit inner child in slot s, so that findMSB picks the nearest
// first (obvhs orders the slots by octant). A triangle group is
// (primitive_base, one bit per triangle offset).
//
// Loops are bounded like bvh.glsl: at most BVH_MAX_ITERATIONS node visits plus
// triangle tests, and pops never exceed pushes, so all loops together stay far
// below lavapipe's silent 65,535-iteration limit; the node test has no loop.
#ifndef CWBVH_GLSL
#define CWBVH_GLSL

#include "bench_bindings.glsl"
#include "intersect.glsl"

#ifdef CW_TEXELS
// The node as 5 RGBA32UI texels (words 0..3, 4..7, ...), triangles as 3.
layout(set = 0, binding = 6) uniform usamplerBuffer cw_node_texels;
uvec4 cw_node_part(uint node, uint k) { return texelFetch(cw_node_texels, int(5u * node + k)); }
vec3 cw_vertex(uint tri, uint k) { return uintBitsToFloat(texelFetch(tri_vert_texels, int(3u * tri + k)).xyz); }
#else
layout(std430, set = 0, binding = 1) readonly buffer CwbvhNodes { uvec4 cw_nodes[]; };
uvec4 cw_node_part(uint node, uint k) { return cw_nodes[5u * node + k]; }
vec3 cw_vertex(uint tri, uint k) {
    return k == 0u ? tri_verts[tri].v0 : (k == 1u ? tri_verts[tri].v1 : tri_verts[tri].v2);
}
#endif

layout(local_size_x = WORKGROUP_SIZE) in;

#define NO_HIT 0xFFFFFFFFu
#define OVERFLOW_HIT 0xFFFFFFFEu
#define CW_STACK_SIZE 32u

// Hit bits of one child: its byte `shift / 8` in the words of near and far
// planes (already swapped by ray direction) and of child_meta.
uint child_hit_bits(uint meta4, uvec3 near4, uvec3 far4, int shift, vec3 scale, vec3 offset,
                    float t_max, uint oct) {
    vec3 tn = vec3(bitfieldExtract(near4, shift, 8)) * scale + offset;
    vec3 tf = vec3(bitfieldExtract(far4, shift, 8)) * scale + offset;
    float t0 = max(max(tn.x, tn.y), max(tn.z, 0.0));
    // Same conservative widening as intersect_aabb.
    float t1 = min(min(tf.x, tf.y), min(tf.z, t_max)) * 1.0000003576;
    uint m = bitfieldExtract(meta4, shift, 8);
    uint index = (m & 31u) ^ ((m & 0x18u) == 0x18u ? oct : 0u);
    return t0 <= t1 ? (m >> 5u) << index : 0u;
}

// Children 4h .. 4h + 3: meta4 and the words of their planes (x, y, z).
uint children4_hit_bits(uint meta4, uvec3 lo, uvec3 hi, bvec3 neg, vec3 scale, vec3 offset,
                        float t_max, uint oct) {
    uvec3 near4 = uvec3(neg.x ? hi.x : lo.x, neg.y ? hi.y : lo.y, neg.z ? hi.z : lo.z);
    uvec3 far4 = uvec3(neg.x ? lo.x : hi.x, neg.y ? lo.y : hi.y, neg.z ? lo.z : hi.z);
    return child_hit_bits(meta4, near4, far4, 0, scale, offset, t_max, oct)
         | child_hit_bits(meta4, near4, far4, 8, scale, offset, t_max, oct)
         | child_hit_bits(meta4, near4, far4, 16, scale, offset, t_max, oct)
         | child_hit_bits(meta4, near4, far4, 24, scale, offset, t_max, oct);
}

void main() {
    uint ray = gl_GlobalInvocationID.x;
    if (ray >= bench.ray_count) return;
    vec4 o4 = rays[2u * ray];
    vec3 o = o4.xyz;
    vec3 d = rays[2u * ray + 1u].xyz;

    float hit_t = o4.w;
    uint hit_tri = NO_HIT;
    RayShear shear = ray_shear(d);
    // A zero direction component would give 0 * inf = NaN in the quantized
    // slab test (grid coordinate 0): use a tiny one for the boxes only.
    vec3 d_box = vec3(abs(d.x) < 1e-30 ? (d.x < 0.0 ? -1e-30 : 1e-30) : d.x,
                      abs(d.y) < 1e-30 ? (d.y < 0.0 ? -1e-30 : 1e-30) : d.y,
                      abs(d.z) < 1e-30 ? (d.z < 0.0 ? -1e-30 : 1e-30) : d.z);
    vec3 inv_d = 1.0 / d_box;
    bvec3 neg = lessThan(d, vec3(0.0));
    // obvhs' ray_get_octant_inv4: a bit per positive axis (x 4, y 2, z 1).
    uint oct = (neg.x ? 0u : 4u) | (neg.y ? 0u : 2u) | (neg.z ? 0u : 1u);

    uint stack_base[CW_STACK_SIZE];
    uint stack_mask[CW_STACK_SIZE];
    uint sp = 0u;
    uvec2 node_group = uvec2(0u, 0x80000000u);  // the root, node 0
    uvec2 tri_group = uvec2(0u);
    uint work = 0u;
    uint nodes = 0u;
    uint tris = 0u;
    uint pushes = 0u;
    bool overflow = false;
    while (true) {
        while (tri_group.y != 0u) {
            uint b = uint(findMSB(tri_group.y));
            tri_group.y &= ~(1u << b);
            work++;
            tris++;
            if (work > BVH_MAX_ITERATIONS) {
                overflow = true;
                break;
            }
            uint i = tri_group.x + b;
            float t;
            vec2 b12;
            if (intersect_triangle(o, shear, cw_vertex(i, 0u), cw_vertex(i, 1u), cw_vertex(i, 2u),
                                   t, b12)
                && (t < hit_t || (t == hit_t && hit_tri != NO_HIT && i < hit_tri))) {
                hit_t = t;
                hit_tri = i;
            }
        }
        if (overflow) break;
        if ((node_group.y & 0xFF000000u) != 0u) {
            uint b = uint(findMSB(node_group.y));
            node_group.y &= ~(1u << b);
            if ((node_group.y & 0xFF000000u) != 0u) {
                if (sp == CW_STACK_SIZE) {
                    overflow = true;
                    break;
                }
                stack_base[sp] = node_group.x;
                stack_mask[sp] = node_group.y;
                sp++;
                pushes++;
            }
            work++;
            nodes++;
            if (work > BVH_MAX_ITERATIONS) {
                overflow = true;
                break;
            }
            // Inner children are stored in slot order from child_base: the
            // node's index is the number of inner slots before its own.
            uint slot = (b - 24u) ^ oct;
            uint node = node_group.x + uint(bitCount(node_group.y & ((1u << slot) - 1u)));
            uvec4 n0 = cw_node_part(node, 0u);  // p, e | imask << 24
            uvec4 n1 = cw_node_part(node, 1u);  // child_base, primitive_base, child_meta
            uvec4 n2 = cw_node_part(node, 2u);  // child_min_x, child_max_x
            uvec4 n3 = cw_node_part(node, 3u);  // child_min_y, child_max_y
            uvec4 n4 = cw_node_part(node, 4u);  // child_min_z, child_max_z
            vec3 p = uintBitsToFloat(n0.xyz);
            uint w3 = n0.w;
            vec3 e = uintBitsToFloat(uvec3(w3 & 0xFFu, (w3 >> 8u) & 0xFFu, (w3 >> 16u) & 0xFFu) << 23u);
            vec3 scale = e * inv_d;
            vec3 offset = (p - o) * inv_d;
            uint hits = children4_hit_bits(n1.z, uvec3(n2.x, n3.x, n4.x), uvec3(n2.z, n3.z, n4.z),
                                           neg, scale, offset, hit_t, oct)
                      | children4_hit_bits(n1.w, uvec3(n2.y, n3.y, n4.y), uvec3(n2.w, n3.w, n4.w),
                                           neg, scale, offset, hit_t, oct);
            node_group = uvec2(n1.x, (hits & 0xFF000000u) | (w3 >> 24u));
            tri_group = uvec2(n1.y, hits & 0x00FFFFFFu);
        } else {
            if (sp == 0u) break;
            sp--;
            node_group = uvec2(stack_base[sp], stack_mask[sp]);
        }
    }
    results[ray] = uvec2(floatBitsToUint(hit_t), overflow ? OVERFLOW_HIT : hit_tri);
    if (bench.write_stats != 0u) stats[ray] = uvec4(nodes, tris, pushes, 0u);
}

#endif
