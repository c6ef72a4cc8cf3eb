// BVH2 traversal (twin: src/cpu/bvh.rs). Needs bindings.glsl's bvh_nodes and
// tri_verts. The loop is bounded: lavapipe ends an invocation's loops
// silently after 65,535 iterations in total, so we stop at
// BVH_MAX_ITERATIONS (node visits plus triangle tests) or a full stack and
// report an overflow instead of returning a wrong answer.
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
Hit trace_ray(vec3 o, vec3 d, float t_max, bool any_hit) {
    Hit hit;
    hit.t = t_max;
    hit.triangle = NO_HIT;
    hit.b12 = vec2(0.0);
    RayShear shear = ray_shear(d);
    vec3 inv_d = 1.0 / d;

    BvhNode root = bvh_nodes[0];
    if (intersect_aabb(o, inv_d, root.min, root.max, t_max) == FLT_MAX) return hit;

    uint stack_node[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    uint sp = 0u;
    uint node = 0u;
    uint work = 0u;
    while (true) {
        BvhNode n = bvh_nodes[node];
        work += 1u + n.count;
        if (work > BVH_MAX_ITERATIONS) {
            hit.triangle = OVERFLOW_HIT;
            return hit;
        }
        bool descend = false;
        if (n.count > 0u) {
            for (uint i = n.first; i < n.first + n.count; ++i) {
                TriangleVerts tv = tri_verts[i];
                float t;
                vec2 b12;
                if (intersect_triangle(o, shear, tv.v0, tv.v1, tv.v2, hit.t, t, b12)) {
                    hit.t = t;
                    hit.triangle = i;
                    hit.b12 = b12;
                    if (any_hit) return hit;
                }
            }
        } else {
            BvhNode left = bvh_nodes[n.first];
            BvhNode right = bvh_nodes[n.first + 1u];
            float tl = intersect_aabb(o, inv_d, left.min, left.max, hit.t);
            float tr = intersect_aabb(o, inv_d, right.min, right.max, hit.t);
            if (tl != FLT_MAX || tr != FLT_MAX) {
                descend = true;
                if (tl != FLT_MAX && tr != FLT_MAX) {
                    if (sp == BVH_STACK_SIZE) {
                        hit.triangle = OVERFLOW_HIT;
                        return hit;
                    }
                    bool left_first = tl <= tr;
                    stack_node[sp] = left_first ? n.first + 1u : n.first;
                    stack_t[sp] = left_first ? tr : tl;
                    sp++;
                    node = left_first ? n.first : n.first + 1u;
                } else {
                    node = tl != FLT_MAX ? n.first : n.first + 1u;
                }
            }
        }
        if (!descend) {
            // Pop the next subtree that can still hold a closer hit.
            bool found = false;
            while (sp > 0u && !found) {
                sp--;
                found = stack_t[sp] < hit.t;
                node = stack_node[sp];
            }
            if (!found) return hit;
        }
    }
    return hit;
}

#endif
