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

// Scene reads of the traversal. With BVH_TEXEL_FETCH (the renderer's
// bindings.glsl defines it) they go through uniform texel buffers, which
// lavapipe turns into vector gathers; otherwise through the storage buffers,
// whose loads lavapipe runs one lane and one word at a time.
#ifdef BVH_TEXEL_FETCH

// TriangleVerts as 3 texels: (v0, material), (v1, -), (v2, -).
void fetch_triangle(uint i, out vec3 v0, out vec3 v1, out vec3 v2) {
    v0 = uintBitsToFloat(texelFetch(tri_vert_texels, int(3u * i)).xyz);
    v1 = uintBitsToFloat(texelFetch(tri_vert_texels, int(3u * i + 1u)).xyz);
    v2 = uintBitsToFloat(texelFetch(tri_vert_texels, int(3u * i + 2u)).xyz);
}

uint fetch_triangle_material(uint i) {
    return texelFetch(tri_vert_texels, int(3u * i)).w;
}

// BvhNode as 4 texels: (left_min, left), (left_max, right), (right_min, -), (right_max, -).
void fetch_node(uint item, out vec3 lmin, out vec3 lmax, out vec3 rmin, out vec3 rmax,
                out uint left, out uint right) {
    int texel = int(4u * item);
    uvec4 n0 = texelFetch(bvh_node_texels, texel);
    uvec4 n1 = texelFetch(bvh_node_texels, texel + 1);
    lmin = uintBitsToFloat(n0.xyz);
    lmax = uintBitsToFloat(n1.xyz);
    rmin = uintBitsToFloat(texelFetch(bvh_node_texels, texel + 2).xyz);
    rmax = uintBitsToFloat(texelFetch(bvh_node_texels, texel + 3).xyz);
    left = n0.w;
    right = n1.w;
}

#else

void fetch_triangle(uint i, out vec3 v0, out vec3 v1, out vec3 v2) {
    v0 = tri_verts[i].v0;
    v1 = tri_verts[i].v1;
    v2 = tri_verts[i].v2;
}

uint fetch_triangle_material(uint i) {
    return tri_verts[i].material;
}

void fetch_node(uint item, out vec3 lmin, out vec3 lmax, out vec3 rmin, out vec3 rmax,
                out uint left, out uint right) {
    lmin = bvh_nodes[item].left_min;
    lmax = bvh_nodes[item].left_max;
    rmin = bvh_nodes[item].right_min;
    rmax = bvh_nodes[item].right_max;
    left = bvh_nodes[item].left;
    right = bvh_nodes[item].right;
}

#endif

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
                vec3 v0, v1, v2;
                fetch_triangle(i, v0, v1, v2);
                if (intersect_triangle(o, shear, v0, v1, v2, hit.t, t, b12)) {
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
            vec3 lmin, lmax, rmin, rmax;
            uint left, right;
            fetch_node(item, lmin, lmax, rmin, rmax, left, right);
            float tl = intersect_aabb(o, inv_d, lmin, lmax, hit.t);
            float tr = intersect_aabb(o, inv_d, rmin, rmax, hit.t);
            if (tl != FLT_MAX && tr != FLT_MAX) {
                if (sp == BVH_STACK_SIZE) {
                    hit.triangle = OVERFLOW_HIT;
                    return hit;
                }
                bool left_first = tl <= tr;
                stack_item[sp] = left_first ? right : left;
                stack_t[sp] = left_first ? tr : tl;
                sp++;
                item = left_first ? left : right;
                continue;
            }
            if (tl != FLT_MAX) {
                item = left;
                continue;
            }
            if (tr != FLT_MAX) {
                item = right;
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
