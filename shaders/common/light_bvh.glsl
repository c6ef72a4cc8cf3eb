// The light BVH (twin: src/cpu/common/light_bvh.rs; host side:
// src/packed/light_bvh.rs). Needs bindings.glsl. Light sampling walks the
// tree from the root, two levels a step: a child with probability
// proportional to the summed importance of its children to the shading
// point p (of itself, for a leaf), then one of those in proportion to
// theirs (light_tree_step); the probability of a light is the
// product of its path's choices, which MIS recomputes from the light's bit
// trail (`light_trails`). Both walks are loops of at most
// LIGHT_TREE_MAX_DEPTH steps with the same arithmetic, so the pmf of a
// sampled light and the one MIS finds for it are the same float.
//
// Importance (after Conty Estevez and Kulla 2018; the idea of pbrt-v4's
// LightBounds::Importance): the node's power over the squared distance to
// its bounding sphere's centre (its radius squared inside it), times the cosine of
// the smallest angle between a direction the lights may emit into and the
// direction to p: the angle from the cone axis to p, less the cone's half
// angle theta_o and the half angle theta_b the bounds subtend at p; zero
// where that exceeds theta_e. With a receiving normal n (nonzero), times
// also cos(max(0, theta_i - theta_b)), theta_i the angle between n and the
// direction to the bounds' centre: one-sided, a node behind the surface
// gets the least factor, LIGHT_TREE_MIN_COS_I (so the normal reorders
// lights but never drops one, whatever the offset origin and the normal's
// rounding). n is the geometric normal on the side the path came from, of
// a surface that only reflects (light_tree_receiving_normal; a material
// that transmits, or is all delta lobes, gives none), as the path state
// carries it (light_tree_normal_code: octahedral, 2 x 14 bits), so
// next-event estimation at the surface and MIS where the next ray meets a
// light bound with the same f32 normal; 0 where the ray left the camera.
#ifndef LIGHT_BVH_GLSL
#define LIGHT_BVH_GLSL

#include "loop_count.glsl"
#include "features.glsl"

// LightTreeNode as 4 texels: (centre, power), (axis, cos_theta_o),
// (radius, r2, sin_theta_o, cos_theta_e), (child_or_light, flags, -, -).
LightTreeNode fetch_light_tree_node(uint i) {
    int base = int(4u * i);
    uvec4 t0 = texelFetch(light_tree_texels, base);
    uvec4 t1 = texelFetch(light_tree_texels, base + 1);
    uvec4 t2 = texelFetch(light_tree_texels, base + 2);
    uvec4 t3 = texelFetch(light_tree_texels, base + 3);
    LightTreeNode n;
    n.centre = uintBitsToFloat(t0.xyz);
    n.power = uintBitsToFloat(t0.w);
    n.axis = uintBitsToFloat(t1.xyz);
    n.cos_theta_o = uintBitsToFloat(t1.w);
    n.radius = uintBitsToFloat(t2.x);
    n.r2 = uintBitsToFloat(t2.y);
    n.sin_theta_o = uintBitsToFloat(t2.z);
    n.cos_theta_e = uintBitsToFloat(t2.w);
    n.child_or_light = t3.x;
    n.flags = t3.y;
    n._pad1 = 0u;
    n._pad2 = 0u;
    return n;
}

bool light_tree_on() {
    return FEATURE_LIGHT_TREE && light_params.tree_nodes > 0u;
}

// Importance of node n to point p with normal nrm (see the top of the
// file; nrm = 0: no normal). The node stores its bounding sphere and
// sin(theta_o), and one division (1 / d) serves every cosine and the
// falloff; a point inside the sphere gets power / r^2.
float light_tree_importance(LightTreeNode n, vec3 p, vec3 nrm) {
    vec3 dp = p - n.centre;
    float d2 = dot(dp, dp);
    if (!(d2 > n.r2)) return n.power / n.r2;
    float inv_d = 1.0 / sqrt(d2);
    float cos_w = dot(n.axis, dp) * inv_d;
    if ((n.flags & LIGHT_TREE_TWO_SIDED) != 0u) cos_w = abs(cos_w);
    float sin_w = sqrt(max(0.0, 1.0 - cos_w * cos_w));
    float cos_o = n.cos_theta_o;
    float sin_o = n.sin_theta_o;
    // cos and sin of max(0, theta_w - theta_o).
    float cos_x = 1.0;
    float sin_x = 0.0;
    if (cos_w < cos_o) {
        cos_x = cos_w * cos_o + sin_w * sin_o;
        sin_x = sin_w * cos_o - cos_w * sin_o;
    }
    // Less the half angle theta_b the bounds subtend (sin = r / d).
    float sin_b = n.radius * inv_d;
    float cos_b = sqrt(max(0.0, 1.0 - sin_b * sin_b));
    float cos_p = 1.0;
    if (cos_x < cos_b) cos_p = cos_x * cos_b + sin_x * sin_b;
    if (cos_p <= n.cos_theta_e) return 0.0;
    // The receiving side: cos of max(0, theta_i - theta_b), theta_i the
    // angle between the normal and the direction to the bounds' centre;
    // at least LIGHT_TREE_MIN_COS_I, so that no light the bound without
    // a normal keeps is lost.
    float cos_pi = 1.0;
    if (nrm != vec3(0.0)) {
        float cos_i = -dot(nrm, dp) * inv_d;
        if (cos_i < cos_b) {
            float sin_i = sqrt(max(0.0, 1.0 - cos_i * cos_i));
            cos_pi = max(cos_i * cos_b + sin_i * sin_b, LIGHT_TREE_MIN_COS_I);
        }
    }
    return n.power * cos_p * cos_pi * (inv_d * inv_d);
}

// The octahedral map's fold of the lower hemisphere onto the square's
// corners (its own inverse): both ways of the normal's code.
vec2 light_tree_octahedral_fold(float x, float y) {
    return vec2((1.0 - abs(y)) * (x >= 0.0 ? 1.0 : -1.0), (1.0 - abs(x)) * (y >= 0.0 ? 1.0 : -1.0));
}

// The receiving normal as the path state carries it (PathState's
// prev_normal): octahedral, 14 bits an axis, bit 0 set; 0: none. Next-event
// estimation bounds with light_tree_normal(light_tree_normal_code(n)), the
// vector MIS decodes where the path's next ray meets a light.
uint light_tree_normal_code(vec3 n) {
    float l1 = abs(n.x) + abs(n.y) + abs(n.z);
    float x = n.x / l1;
    float y = n.y / l1;
    if (n.z < 0.0) {
        vec2 f = light_tree_octahedral_fold(x, y);
        x = f.x;
        y = f.y;
    }
    uint qx = min(uint(max(x * 8192.0 + 8192.0, 0.0)), 16383u);
    uint qy = min(uint(max(y * 8192.0 + 8192.0, 0.0)), 16383u);
    return 1u | (qx << 1u) | (qy << 15u);
}

vec3 light_tree_normal(uint code) {
    if (code == 0u) return vec3(0.0);
    // The cell's centre: (q + 0.5) / 8192 - 1, in exact steps.
    float x = float((code >> 1u) & 16383u) * 0.0001220703125 - 0.99993896484375;
    float y = float((code >> 15u) & 16383u) * 0.0001220703125 - 0.99993896484375;
    float z = 1.0 - abs(x) - abs(y);
    if (z < 0.0) {
        vec2 f = light_tree_octahedral_fold(x, y);
        x = f.x;
        y = f.y;
    }
    vec3 v = vec3(x, y, z);
    return v / sqrt(dot(v, v));
}

// One side of a step of the walk: child x (node i) of the step's node,
// its two children and their importances to p, or, where x is a leaf, x
// itself and a second of no importance.
void light_tree_lanes(uint i, vec3 p, vec3 nrm, out uvec2 idx, out vec2 q) {
    LightTreeNode x = fetch_light_tree_node(i);
    if ((x.flags & LIGHT_TREE_LEAF) != 0u) {
        idx = uvec2(i);
        q = vec2(light_tree_importance(x, p, nrm), 0.0);
    } else {
        idx = uvec2(x.child_or_light, x.child_or_light + 1u);
        q = vec2(light_tree_importance(fetch_light_tree_node(idx.x), p, nrm),
                 light_tree_importance(fetch_light_tree_node(idx.y), p, nrm));
    }
}

// Whether u falls in the first of two choices of probability q, and u
// rescaled to [0, 1) within the one it falls in; or, by_trail, whether the
// trail's next bit is 0 (the trail then shifted).
bool light_tree_choose(bool by_trail, inout float u, inout uint trail, float q) {
    if (by_trail) {
        bool first = (trail & 1u) == 0u;
        trail >>= 1u;
        return first;
    }
    if (u < q) {
        u = min(u / q, 0.99999994);
        return true;
    }
    u = min((u - q) / (1.0 - q), 0.99999994);
    return false;
}

// One step of the walk at interior node n, two levels at once: a child
// (a, b: nodes c and c + 1, c = n.child_or_light) in proportion to the sum
// of its lanes' importances (light_tree_lanes: its own children's, or its
// own for a leaf), then, unless that child is a leaf, one of its children
// in proportion to its own. The CPU twin computes the four lanes in one
// SIMD register. Sets the node reached and the step's probability q;
// false where no light reaches p.
bool light_tree_step(LightTreeNode n, vec3 p, vec3 nrm, bool by_trail, inout float u, inout uint trail, out uint next, out float q) {
    uint c = n.child_or_light;
    uvec2 ia_idx, ib_idx;
    vec2 qa, qb;
    light_tree_lanes(c, p, nrm, ia_idx, qa);
    light_tree_lanes(c + 1u, p, nrm, ib_idx, qb);
    float ia = qa.x + qa.y;
    float ib = qb.x + qb.y;
    float total = ia + ib;
    next = 0u;
    q = 0.0;
    if (!(total > 0.0)) return false;
    float pa = ia / total;
    float pb = ib / total;
    bool first = light_tree_choose(by_trail, u, trail, pa);
    q = first ? pa : pb;
    uint child = first ? c : c + 1u;
    if ((fetch_light_tree_node(child).flags & LIGHT_TREE_LEAF) != 0u) {
        next = child;
        return true;
    }
    vec2 qx = first ? qa : qb;
    uvec2 idx = first ? ia_idx : ib_idx;
    float t = qx.x + qx.y;
    if (!(t > 0.0)) return false;
    float p0 = qx.x / t;
    float p1 = qx.y / t;
    bool first2 = light_tree_choose(by_trail, u, trail, p0);
    q *= first2 ? p0 : p1;
    next = first2 ? idx.x : idx.y;
    return true;
}

// Walks from the root to a leaf, choosing by importance to p with u in
// [0, 1) (rescaled at each choice). Returns the leaf node and its
// probability `pmf`; pmf 0: no light reaches p.
LightTreeNode light_tree_sample(vec3 p, vec3 nrm, float u, out float pmf) {
    LightTreeNode n = fetch_light_tree_node(0u);
    pmf = 1.0;
    uint trail = 0u;
    for (uint depth = 0u; depth < LIGHT_TREE_MAX_DEPTH; depth++) {
        COUNT_LOOP_ITERATION();
        if ((n.flags & LIGHT_TREE_LEAF) != 0u) return n;
        uint next;
        float q;
        if (!light_tree_step(n, p, nrm, false, u, trail, next, q)) break;
        pmf *= q;
        n = fetch_light_tree_node(next);
    }
    if ((n.flags & LIGHT_TREE_LEAF) == 0u) pmf = 0.0;
    return n;
}

// The probability that light_tree_sample at p picks the leaf that `trail`
// leads to (bit k: the child taken at depth k).
float light_tree_pmf(uint trail, vec3 p, vec3 nrm) {
    LightTreeNode n = fetch_light_tree_node(0u);
    float pmf = 1.0;
    float u = 0.0;
    for (uint depth = 0u; depth < LIGHT_TREE_MAX_DEPTH; depth++) {
        COUNT_LOOP_ITERATION();
        if ((n.flags & LIGHT_TREE_LEAF) != 0u) return pmf;
        uint next;
        float q;
        if (!light_tree_step(n, p, nrm, true, u, trail, next, q)) return 0.0;
        pmf *= q;
        n = fetch_light_tree_node(next);
    }
    return (n.flags & LIGHT_TREE_LEAF) != 0u ? pmf : 0.0;
}

// The emitters row of emissive triangle `id` (a hit's triangle id: slot, or
// (instance, triangle) pair), by binary search: rows are sorted by id.
uint light_tree_emitter_row(uint id) {
    uint lo = 0u;
    uint hi = params.num_emitters - 1u;
    while (lo < hi) {
        COUNT_LOOP_ITERATION();
        uint mid = (lo + hi) / 2u;
        if (fetch_emitter(mid).triangle < id) lo = mid + 1u; else hi = mid;
    }
    return lo;
}

// The probability that light sampling picks emissive triangle `id` from p.
float light_tree_triangle_pmf(uint id, vec3 p, vec3 nrm) {
    if (params.num_emitters == 0u) return 0.0;
    uint row = light_tree_emitter_row(id);
    if (fetch_emitter(row).triangle != id) return 0.0;
    return light_params.tri_select_prob * light_tree_pmf(light_trails[row], p, nrm);
}

// The probability that light sampling picks analytic light k from p.
float light_tree_light_pmf(uint k, vec3 p, vec3 nrm) {
    return light_params.tri_select_prob * light_tree_pmf(light_trails[params.num_emitters + k], p, nrm);
}

#endif
