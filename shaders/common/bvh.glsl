// BVH2 traversal (twin: src/cpu/bvh.rs). Needs bindings.glsl's params,
// bvh_nodes and tri_verts. The loops are bounded: lavapipe ends an
// invocation's loops silently after 65,535 iterations in total, so we stop at
// BVH_MAX_ITERATIONS (node visits plus triangle tests) or a full stack and
// report an overflow instead of returning a wrong answer. Pops never exceed
// pushes, so all loops together stay below 2 * BVH_MAX_ITERATIONS.
#ifndef BVH_GLSL
#define BVH_GLSL

#include "intersect.glsl"

#define NO_HIT 0xFFFFFFFFu
#define OVERFLOW_HIT 0xFFFFFFFEu

struct Hit {
    float t;
    uint triangle;   // NO_HIT on a miss, OVERFLOW_HIT when traversal gave up
    vec2 b12;        // barycentrics of vertices 1 and 2
};

// Closest hit with t in (0, t_max). any_hit: stop at the first hit found.
// Only the words traversal needs are read (lavapipe loads buffers one word
// per lane at a time, so every word counts).
Hit trace_ray(vec3 o, vec3 d, float t_max, bool any_hit) {
    Hit hit;
    hit.t = t_max;
    hit.triangle = NO_HIT;
    hit.b12 = vec2(0.0);
    RayShear shear = ray_shear(d);
    vec3 inv_d = 1.0 / d;

    uint stack_item[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    uint sp = 0u;
    uint item = params.bvh_root;
    uint work = 0u;
    while (true) {
        if ((item & BVH_LEAF_BIT) != 0u) {
            uint first = item & BVH_LEAF_FIRST_MASK;
            uint count = (item >> BVH_LEAF_COUNT_SHIFT) & BVH_LEAF_COUNT_MASK;
            work += count;
            if (work > BVH_MAX_ITERATIONS) {
                hit.triangle = OVERFLOW_HIT;
                return hit;
            }
            for (uint i = first; i < first + count; ++i) {
                float t;
                vec2 b12;
                if (intersect_triangle(o, shear, tri_verts[i].v0, tri_verts[i].v1, tri_verts[i].v2,
                                       hit.t, t, b12)) {
                    hit.t = t;
                    hit.triangle = i;
                    hit.b12 = b12;
                    if (any_hit) return hit;
                }
            }
        } else {
            work += 1u;
            if (work > BVH_MAX_ITERATIONS) {
                hit.triangle = OVERFLOW_HIT;
                return hit;
            }
            float tl = intersect_aabb(o, inv_d, bvh_nodes[item].left_min, bvh_nodes[item].left_max, hit.t);
            float tr = intersect_aabb(o, inv_d, bvh_nodes[item].right_min, bvh_nodes[item].right_max, hit.t);
            if (tl != FLT_MAX && tr != FLT_MAX) {
                if (sp == BVH_STACK_SIZE) {
                    hit.triangle = OVERFLOW_HIT;
                    return hit;
                }
                uint left = bvh_nodes[item].left;
                uint right = bvh_nodes[item].right;
                bool left_first = tl <= tr;
                stack_item[sp] = left_first ? right : left;
                stack_t[sp] = left_first ? tr : tl;
                sp++;
                item = left_first ? left : right;
                continue;
            }
            if (tl != FLT_MAX) {
                item = bvh_nodes[item].left;
                continue;
            }
            if (tr != FLT_MAX) {
                item = bvh_nodes[item].right;
                continue;
            }
        }
        // Pop the next subtree that can still hold a closer hit.
        bool found = false;
        while (sp > 0u && !found) {
            sp--;
            found = stack_t[sp] < hit.t;
            item = stack_item[sp];
        }
        if (!found) return hit;
    }
    return hit;
}

#endif
