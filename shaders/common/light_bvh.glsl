// The light BVH (twin: src/cpu/common/light_bvh.rs; host side:
// src/packed/light_bvh.rs). Needs bindings.glsl. Light sampling walks the
// tree from the root, taking each child with probability proportional to
// its importance to the shading point p; the probability of a light is the
// product of its path's choices, which MIS recomputes from the light's bit
// trail (`light_trails`). Both walks are loops of at most
// LIGHT_TREE_MAX_DEPTH steps with the same arithmetic, so the pmf of a
// sampled light and the one MIS finds for it are the same float.
//
// Importance (after Conty Estevez and Kulla 2018; the idea of pbrt-v4's
// LightBounds::Importance): the node's power over the squared distance to
// its bounds' centre (at least their radius, squared), times the cosine of
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

// LightTreeNode as 4 texels: (lo, power), (hi, cos_theta_o),
// (axis, cos_theta_e), (child_or_light, flags, -, -).
LightTreeNode fetch_light_tree_node(uint i) {
    int base = int(4u * i);
    uvec4 t0 = texelFetch(light_tree_texels, base);
    uvec4 t1 = texelFetch(light_tree_texels, base + 1);
    uvec4 t2 = texelFetch(light_tree_texels, base + 2);
    uvec4 t3 = texelFetch(light_tree_texels, base + 3);
    LightTreeNode n;
    n.lo = uintBitsToFloat(t0.xyz);
    n.power = uintBitsToFloat(t0.w);
    n.hi = uintBitsToFloat(t1.xyz);
    n.cos_theta_o = uintBitsToFloat(t1.w);
    n.axis = uintBitsToFloat(t2.xyz);
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
// file; nrm = 0: no normal).
float light_tree_importance(LightTreeNode n, vec3 p, vec3 nrm) {
    vec3 dp = p - 0.5 * (n.lo + n.hi);
    float d2 = dot(dp, dp);
    vec3 ext = n.hi - n.lo;
    float r2 = 0.25 * dot(ext, ext);
    float cos_p = 1.0;
    float cos_pi = 1.0;
    if (d2 > r2) {
        float d = sqrt(d2);
        float cos_w = dot(n.axis, dp) / d;
        if ((n.flags & LIGHT_TREE_TWO_SIDED) != 0u) cos_w = abs(cos_w);
        float sin_w = sqrt(max(0.0, 1.0 - cos_w * cos_w));
        float cos_o = n.cos_theta_o;
        float sin_o = sqrt(max(0.0, 1.0 - cos_o * cos_o));
        // cos and sin of max(0, theta_w - theta_o).
        float cos_x = 1.0;
        float sin_x = 0.0;
        if (cos_w < cos_o) {
            cos_x = cos_w * cos_o + sin_w * sin_o;
            sin_x = sin_w * cos_o - cos_w * sin_o;
        }
        // Less the half angle theta_b the bounds subtend (sin^2 = r^2 / d^2).
        float sin2_b = r2 / d2;
        float cos_b = sqrt(max(0.0, 1.0 - sin2_b));
        float sin_b = sqrt(sin2_b);
        if (cos_x < cos_b) cos_p = cos_x * cos_b + sin_x * sin_b;
        if (cos_p <= n.cos_theta_e) return 0.0;
        // The receiving side: cos of max(0, theta_i - theta_b), theta_i the
        // angle between the normal and the direction to the bounds' centre;
        // at least LIGHT_TREE_MIN_COS_I, so that no light the bound without
        // a normal keeps is lost.
        if (nrm != vec3(0.0)) {
            float cos_i = -dot(nrm, dp) / d;
            if (cos_i < cos_b) {
                float sin_i = sqrt(max(0.0, 1.0 - cos_i * cos_i));
                cos_pi = max(cos_i * cos_b + sin_i * sin_b, LIGHT_TREE_MIN_COS_I);
            }
        }
    }
    return n.power * cos_p * cos_pi / max(d2, r2);
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

// One step of the walk: n's children a and b and the probabilities of
// taking each at p, in proportion to importance; (0, 0) where neither
// reaches p.
vec2 light_tree_children(LightTreeNode n, vec3 p, vec3 nrm, out LightTreeNode a, out LightTreeNode b) {
    a = fetch_light_tree_node(n.child_or_light);
    b = fetch_light_tree_node(n.child_or_light + 1u);
    float ia = light_tree_importance(a, p, nrm);
    float ib = light_tree_importance(b, p, nrm);
    float total = ia + ib;
    if (!(total > 0.0)) return vec2(0.0);
    return vec2(ia / total, ib / total);
}

// Walks from the root to a leaf, choosing by importance to p with u in
// [0, 1) (rescaled at each level). Returns the leaf node and its
// probability `pmf`; pmf 0: no light reaches p.
LightTreeNode light_tree_sample(vec3 p, vec3 nrm, float u, out float pmf) {
    LightTreeNode n = fetch_light_tree_node(0u);
    pmf = 1.0;
    for (uint depth = 0u; depth < LIGHT_TREE_MAX_DEPTH; depth++) {
        COUNT_LOOP_ITERATION();
        if ((n.flags & LIGHT_TREE_LEAF) != 0u) return n;
        LightTreeNode a, b;
        vec2 q = light_tree_children(n, p, nrm, a, b);
        if (!(q.x + q.y > 0.0)) break;
        if (u < q.x) {
            u = min(u / q.x, 0.99999994);
            pmf *= q.x;
            n = a;
        } else {
            u = min((u - q.x) / (1.0 - q.x), 0.99999994);
            pmf *= q.y;
            n = b;
        }
    }
    if ((n.flags & LIGHT_TREE_LEAF) == 0u) pmf = 0.0;
    return n;
}

// The probability that light_tree_sample at p picks the leaf that `trail`
// leads to (bit k: the child taken at depth k).
float light_tree_pmf(uint trail, vec3 p, vec3 nrm) {
    LightTreeNode n = fetch_light_tree_node(0u);
    float pmf = 1.0;
    for (uint depth = 0u; depth < LIGHT_TREE_MAX_DEPTH; depth++) {
        COUNT_LOOP_ITERATION();
        if ((n.flags & LIGHT_TREE_LEAF) != 0u) return pmf;
        LightTreeNode a, b;
        vec2 q = light_tree_children(n, p, nrm, a, b);
        if (!(q.x + q.y > 0.0)) return 0.0;
        if ((trail & 1u) == 0u) {
            pmf *= q.x;
            n = a;
        } else {
            pmf *= q.y;
            n = b;
        }
        trail >>= 1u;
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
