// CWBVH traversal (twin: src/cpu/common/bvh.rs): Ylitie, Karras and Laine,
// "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"
// (HPG 2017), over CwBvhNode (types.glsl; encoding in src/layout.rs). Nodes
// and triangles are read through the uniform texel buffers bvh_node_texels
// and tri_vert_texels (bindings.glsl; scene_texel picks the part of a split
// array): lavapipe gathers texels as vectors, while its storage-buffer loads
// run one lane and one word at a time.
//
// The loops are bounded: lavapipe ends an invocation's loops silently after
// 65,535 iterations in total, so we stop at BVH_MAX_ITERATIONS (node visits
// plus triangle tests) or a full stack and report an overflow instead of
// returning a wrong answer. Pops never exceed pushes, which never exceed node
// visits, so all loops together stay below 3 * BVH_MAX_ITERATIONS + 2.
#ifndef BVH_GLSL
#define BVH_GLSL

#include "loop_count.glsl"

#include "instances.glsl"
#include "intersect.glsl"
#include "motion.glsl"
#include "textures.glsl"

#define NO_HIT 0xFFFFFFFFu
#define OVERFLOW_HIT 0xFFFFFFFEu

// TriangleVerts as 3 texels: (v0, material), (v1, -), (v2, -).
void fetch_triangle(uint i, out vec3 v0, out vec3 v1, out vec3 v2) {
    v0 = uintBitsToFloat(scene_texel(tri_vert_texels, int(3u * i)).xyz);
    v1 = uintBitsToFloat(scene_texel(tri_vert_texels, int(3u * i + 1u)).xyz);
    v2 = uintBitsToFloat(scene_texel(tri_vert_texels, int(3u * i + 2u)).xyz);
}

// The triangle's vertices where a ray at `time` (motion.glsl) meets them.
void fetch_triangle_at(uint i, float time, out vec3 v0, out vec3 v1, out vec3 v2) {
    if (motion_on()) {
        moving_triangle(i, time, v0, v1, v2);
    } else {
        fetch_triangle(i, v0, v1, v2);
    }
}

uint fetch_triangle_material(uint i) {
    return scene_texel(tri_vert_texels, int(3u * i)).w;
}

// TriangleVerts::alpha_mask (texel 1's w, which fetch_triangle reads too).
uint fetch_triangle_alpha_mask(uint i) {
    return scene_texel(tri_vert_texels, int(3u * i + 1u)).w;
}

// TriangleVerts::shade_queue (texel 2's w): SHADE_QUEUE_BASIC or _FULL.
uint fetch_triangle_shade_queue(uint i) {
    return scene_texel(tri_vert_texels, int(3u * i + 2u)).w;
}

// CwBvhNode as 5 texels: (p, e_imask), (child_base_idx, primitive_base_idx,
// child_meta), (qlo_x, qhi_x), (qlo_y, qhi_y), (qlo_z, qhi_z).
uvec4 fetch_node_texel(uint node, uint k) {
    return scene_texel(bvh_node_texels, int(5u * node + k));
}

struct Hit {
    float t;
    uint triangle;   // NO_HIT on a miss, OVERFLOW_HIT when traversal gave up
    vec2 b12;        // barycentrics of vertices 1 and 2
};

// Whether triangle i, met at t, is nearer than the hit so far: at equal t
// the lower index wins, so the nearest hit does not depend on the order in
// which a traversal meets triangles (the CPU back end traces eight rays at
// once in another order and finds the same hits: cpu/fast/packet.rs).
bool nearer_hit(float t, uint i, Hit hit) {
    return t < hit.t || (t == hit.t && hit.triangle != NO_HIT && i < hit.triangle);
}

// Hit bits of one child: byte `shift / 8` of the words of its near and far
// grid planes (already swapped by ray direction) and of its child_meta. The
// box test is intersect_aabb's on the decoded planes p + e * q (e * q is
// exact), which enclose the child's exact bounds (src/bvh.rs checks it), so
// rounding never culls a child the ray touches.
uint child_hit_bits(uint meta4, uvec3 near4, uvec3 far4, int shift, vec3 p, vec3 e, vec3 o,
                    vec3 inv_d, float t_max, uint oct) {
    vec3 near_plane = p + e * vec3(bitfieldExtract(near4, shift, 8));
    vec3 far_plane = p + e * vec3(bitfieldExtract(far4, shift, 8));
    vec3 tn = (near_plane - o) * inv_d;
    vec3 tf = (far_plane - o) * inv_d;
    float t_enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float t_exit = min(min(tf.x, tf.y), min(tf.z, t_max)) * 1.0000003576;
    uint m = bitfieldExtract(meta4, shift, 8);
    uint index = (m & 31u) ^ ((m & 0x18u) == 0x18u ? oct : 0u);
    return t_enter <= t_exit ? (m >> 5u) << index : 0u;
}

// Children 4h .. 4h + 3: meta4 and the words of their planes (x, y, z).
uint children4_hit_bits(uint meta4, uvec3 lo, uvec3 hi, bvec3 neg, vec3 p, vec3 e, vec3 o,
                        vec3 inv_d, float t_max, uint oct) {
    uvec3 near4 = uvec3(neg.x ? hi.x : lo.x, neg.y ? hi.y : lo.y, neg.z ? hi.z : lo.z);
    uvec3 far4 = uvec3(neg.x ? lo.x : hi.x, neg.y ? lo.y : hi.y, neg.z ? lo.z : hi.z);
    return child_hit_bits(meta4, near4, far4, 0, p, e, o, inv_d, t_max, oct)
         | child_hit_bits(meta4, near4, far4, 8, p, e, o, inv_d, t_max, oct)
         | child_hit_bits(meta4, near4, far4, 16, p, e, o, inv_d, t_max, oct)
         | child_hit_bits(meta4, near4, far4, 24, p, e, o, inv_d, t_max, oct);
}

// One node's step (twin: `ScalarSteps::node`): its children the ray meets
// before t_max, as the next node group (child_base, hit bits << 24 |
// imask) and leaf group (primitive_base, one bit per leaf primitive:
// triangles in a mesh's BVH, instances in the top level).
void node_step(uint node, vec3 o, vec3 inv_d, bvec3 neg, uint oct, float t_max,
               out uvec2 node_group, out uvec2 leaf_group) {
    // The node's fields, each named as in CwBvhNode (tests/suite/texel_reads.rs
    // checks every texel and component against src/packed/layout.rs).
    uvec4 n0 = fetch_node_texel(node, 0u);
    uvec4 n1 = fetch_node_texel(node, 1u);
    uvec4 n2 = fetch_node_texel(node, 2u);
    uvec4 n3 = fetch_node_texel(node, 3u);
    uvec4 n4 = fetch_node_texel(node, 4u);
    vec3 p = uintBitsToFloat(n0.xyz);
    uint e_imask = n0.w;
    uint child_base_idx = n1.x;
    uint primitive_base_idx = n1.y;
    uvec2 child_meta = n1.zw;
    uvec2 qlo_x = n2.xy;
    uvec2 qhi_x = n2.zw;
    uvec2 qlo_y = n3.xy;
    uvec2 qhi_y = n3.zw;
    uvec2 qlo_z = n4.xy;
    uvec2 qhi_z = n4.zw;
    vec3 e = uintBitsToFloat(uvec3(e_imask & 0xFFu, (e_imask >> 8u) & 0xFFu,
                                   (e_imask >> 16u) & 0xFFu) << 23u);
    // Word 0 of each byte array holds children 0-3, word 1 children 4-7.
    uint hits = children4_hit_bits(child_meta.x, uvec3(qlo_x.x, qlo_y.x, qlo_z.x),
                                   uvec3(qhi_x.x, qhi_y.x, qhi_z.x), neg, p, e, o, inv_d, t_max, oct)
              | children4_hit_bits(child_meta.y, uvec3(qlo_x.y, qlo_y.y, qlo_z.y),
                                   uvec3(qhi_x.y, qhi_y.y, qhi_z.y), neg, p, e, o, inv_d, t_max, oct);
    node_group = uvec2(child_base_idx, (hits & 0xFF000000u) | (e_imask >> 24u));
    leaf_group = uvec2(primitive_base_idx, hits & 0x00FFFFFFu);
}

// Closest hit with t in (0, t_max); any_hit: stop at the first hit found.
// coverage_seed: the ray's seed for alpha BLEND tests (rng_coverage_seed).
// max_work: give up (OVERFLOW_HIT) after this much work (node visits plus
// triangle tests, at most BVH_MAX_ITERATIONS: the loops then run at most
// 3 * max_work + 5 times). time: the ray's moment in the shutter, where
// moving triangles are met (motion.glsl; the boxes enclose every step). GPU only: the per-path loop lowers it to stay
// within lavapipe's loop limit; the CPU twin always allows BVH_MAX_ITERATIONS.
// A node group is (child_base, hit bits << 24 | imask): bit 24 + (s ^ oct)
// is set for a hit inner child in slot s, so that findMSB picks the nearest
// first (obvhs orders the slots by octant). A triangle group is
// (primitive_base, one bit per triangle offset).
//
// trace_bvh is that loop over one BVH from node `root` (the scene's, or a
// mesh's with the ray in the mesh's space), a triangle in slot s reporting
// id s + id_offset, counting on from the caller's `work`; it returns true
// when the query is done (an any-hit query found one, or it gave up).
bool trace_bvh(uint root, uint id_offset, vec3 o, vec3 d, bool any_hit, uint coverage_seed,
               float time, uint max_work, inout Hit hit, inout uint work) {
    RayShear shear = ray_shear(d);
    // A zero direction component gives an infinite inverse, and 0 * inf =
    // NaN in the slab test: clamp to the largest finite float, same sign.
    vec3 inv_d = clamp(1.0 / d, vec3(-FLT_MAX), vec3(FLT_MAX));
    bvec3 neg = lessThan(inv_d, vec3(0.0));
    // obvhs' ray_get_octant_inv4: a bit per positive axis (x 4, y 2, z 1).
    uint oct = (neg.x ? 0u : 4u) | (neg.y ? 0u : 2u) | (neg.z ? 0u : 1u);

    uint stack_base[BVH_STACK_SIZE];
    uint stack_mask[BVH_STACK_SIZE];
    uint sp = 0u;
    uvec2 node_group = uvec2(root, 0x80000000u);
    uvec2 tri_group = uvec2(0u);
    while (true) {
        COUNT_LOOP_ITERATION();
        while (tri_group.y != 0u) {
            COUNT_LOOP_ITERATION();
            uint b = uint(findMSB(tri_group.y));
            tri_group.y &= ~(1u << b);
            work++;
            if (work > max_work) {
                hit.triangle = OVERFLOW_HIT;
                return true;
            }
            uint i = tri_group.x + b;
            uint id = i + id_offset;
            float t;
            vec2 b12;
            vec3 v0, v1, v2;
            fetch_triangle_at(i, time, v0, v1, v2);
            // A MASK or BLEND triangle is hit only where its alpha test passes.
            if (intersect_triangle(o, shear, v0, v1, v2, t, b12) && nearer_hit(t, id, hit)
                && (!FEATURE_ALPHA_MASK || fetch_triangle_alpha_mask(i) == 0u
                    || alpha_test_passes(fetch_triangle_material(i), i, b12, coverage_seed))) {
                hit.t = t;
                hit.triangle = id;
                hit.b12 = b12;
                if (any_hit) return true;
            }
        }
        if ((node_group.y & 0xFF000000u) != 0u) {
            uint b = uint(findMSB(node_group.y));
            node_group.y &= ~(1u << b);
            if ((node_group.y & 0xFF000000u) != 0u) {
                if (sp == BVH_STACK_SIZE) {
                    hit.triangle = OVERFLOW_HIT;
                    return true;
                }
                stack_base[sp] = node_group.x;
                stack_mask[sp] = node_group.y;
                sp++;
            }
            work++;
            if (work > max_work) {
                hit.triangle = OVERFLOW_HIT;
                return true;
            }
            // Inner children are stored in slot order from child_base: the
            // node's index is the number of inner slots before its own.
            uint slot = (b - 24u) ^ oct;
            uint node = node_group.x + uint(bitCount(node_group.y & ((1u << slot) - 1u)));
            node_step(node, o, inv_d, neg, oct, hit.t, node_group, tri_group);
        } else {
            if (sp == 0u) return false;
            sp--;
            node_group = uvec2(stack_base[sp], stack_mask[sp]);
        }
    }
    return false;
}


// A two-level scene's traversal: the top level (node 0 on) over the
// instances; at each instance it meets, the ray is taken into the mesh's
// space and the mesh's BVH traversed (trace_bvh), under one work budget
// (an instance entered counts as a step). Twin: trace_instances_with.
void trace_instances(vec3 o, vec3 d, bool any_hit, uint coverage_seed, float time, uint max_work,
                     inout Hit hit) {
    vec3 inv_d = clamp(1.0 / d, vec3(-FLT_MAX), vec3(FLT_MAX));
    bvec3 neg = lessThan(inv_d, vec3(0.0));
    uint oct = (neg.x ? 0u : 4u) | (neg.y ? 0u : 2u) | (neg.z ? 0u : 1u);
    uint stack_base[BVH_STACK_SIZE];
    uint stack_mask[BVH_STACK_SIZE];
    uint sp = 0u;
    uvec2 node_group = uvec2(0u, 0x80000000u);
    uvec2 instance_group = uvec2(0u);
    uint work = 0u;
    while (true) {
        COUNT_LOOP_ITERATION();
        while (instance_group.y != 0u) {
            COUNT_LOOP_ITERATION();
            uint b = uint(findMSB(instance_group.y));
            instance_group.y &= ~(1u << b);
            work++;
            if (work > max_work) {
                hit.triangle = OVERFLOW_HIT;
                return;
            }
            uint k = instance_group.x + b;
            vec4 x, y, z;
            fetch_instance_to_object(k, x, y, z);
            uint root, id_base, first_triangle, flags;
            fetch_instance_entry(k, root, id_base, first_triangle, flags);
            vec3 oo = instance_point(x, y, z, o);
            vec3 od = instance_vector(x, y, z, d);
            if (trace_bvh(root, id_base - first_triangle, oo, od, any_hit, coverage_seed, time,
                          max_work, hit, work)) {
                return;
            }
        }
        if ((node_group.y & 0xFF000000u) != 0u) {
            uint b = uint(findMSB(node_group.y));
            node_group.y &= ~(1u << b);
            if ((node_group.y & 0xFF000000u) != 0u) {
                if (sp == BVH_STACK_SIZE) {
                    hit.triangle = OVERFLOW_HIT;
                    return;
                }
                stack_base[sp] = node_group.x;
                stack_mask[sp] = node_group.y;
                sp++;
            }
            work++;
            if (work > max_work) {
                hit.triangle = OVERFLOW_HIT;
                return;
            }
            uint slot = (b - 24u) ^ oct;
            uint node = node_group.x + uint(bitCount(node_group.y & ((1u << slot) - 1u)));
            node_step(node, o, inv_d, neg, oct, hit.t, node_group, instance_group);
        } else {
            if (sp == 0u) return;
            sp--;
            node_group = uvec2(stack_base[sp], stack_mask[sp]);
        }
    }
}

// Closest hit with t in (0, t_max) (any_hit: the first found), through
// one level or two.
Hit trace_ray_bounded(vec3 o, vec3 d, float t_max, bool any_hit, uint coverage_seed, float time,
                      uint max_work) {
    Hit hit;
    hit.t = t_max;
    hit.triangle = NO_HIT;
    hit.b12 = vec2(0.0);
    if (two_levels()) {
        trace_instances(o, d, any_hit, coverage_seed, time, max_work, hit);
    } else {
        uint work = 0u;
        trace_bvh(0u, 0u, o, d, any_hit, coverage_seed, time, max_work, hit, work);
    }
    return hit;
}

Hit trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, uint coverage_seed, float time) {
    return trace_ray_bounded(o, d, t_max, any_hit, coverage_seed, time, BVH_MAX_ITERATIONS);
}

#endif
