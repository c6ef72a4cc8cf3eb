// Ray/primitive tests (twin: src/cpu/common/intersect.rs).
#ifndef INTERSECT_GLSL
#define INTERSECT_GLSL

#include "sampling.glsl"

// Component k of v, by selects: dynamic vector indexing becomes per-lane
// memory traffic on SIMD CPU drivers such as lavapipe.
float component(vec3 v, int k) {
    return k == 0 ? v.x : (k == 1 ? v.y : v.z);
}

// Per-ray setup of the watertight ray/triangle test (Woop, Benthin and Wald,
// JCGT 2013): a shear that maps the ray onto +z, so that the three edge
// functions are evaluated identically for triangles that share an edge.
struct RayShear {
    ivec3 k;   // kx, ky, kz
    vec3 s;    // Sx, Sy, Sz
};

RayShear ray_shear(vec3 d) {
    vec3 a = abs(d);
    int kz = (a.x > a.y) ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2);
    int kx = kz == 2 ? 0 : kz + 1;
    int ky = kx == 2 ? 0 : kx + 1;
    if (component(d, kz) < 0.0) {
        int tmp = kx;
        kx = ky;
        ky = tmp;
    }
    RayShear r;
    r.k = ivec3(kx, ky, kz);
    float dz = component(d, kz);
    r.s = vec3(component(d, kx) / dz, component(d, ky) / dz, 1.0 / dz);
    return r;
}

// Returns true on a hit in front of the origin (t > 0, at any distance); t
// and barycentrics (b1, b2) of vertices 1 and 2. Points on an edge count as
// inside, so a ray through a shared edge hits at least one of the two
// triangles. Whether the hit is the nearest is `nearer_hit`'s (bvh.glsl)
// question, asked of t itself: comparing tt with t_max * det instead can
// round the other way, and the answer would then depend on the order in
// which a traversal meets triangles at equal distance.
bool intersect_triangle(vec3 o, RayShear r, vec3 v0, vec3 v1, vec3 v2, out float t,
                        out vec2 b12) {
    vec3 a = v0 - o;
    vec3 b = v1 - o;
    vec3 c = v2 - o;
    float az = component(a, r.k.z);
    float bz = component(b, r.k.z);
    float cz = component(c, r.k.z);
    float ax = component(a, r.k.x) - r.s.x * az;
    float ay = component(a, r.k.y) - r.s.y * az;
    float bx = component(b, r.k.x) - r.s.x * bz;
    float by = component(b, r.k.y) - r.s.y * bz;
    float cx = component(c, r.k.x) - r.s.x * cz;
    float cy = component(c, r.k.y) - r.s.y * cz;
    // precise: no fused multiply-add here. A triangle and its neighbour
    // evaluate a shared edge with its operands in other roles; contracted
    // into an FMA the two results could round differently and open a crack
    // (the CPU twin never fuses).
    precise float u = cx * by - cy * bx;
    precise float v = ax * cy - ay * cx;
    precise float w = bx * ay - by * ax;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return false;
    float det = u + v + w;
    if (det == 0.0) return false;
    float tt = u * (r.s.z * az) + v * (r.s.z * bz) + w * (r.s.z * cz);
    // In front of the origin: tt has det's sign (t > 0 without dividing).
    if (det < 0.0 && tt >= 0.0) return false;
    if (det > 0.0 && tt <= 0.0) return false;
    float inv_det = 1.0 / det;
    t = tt * inv_det;
    b12 = vec2(v, w) * inv_det;
    return true;
}

// Slab test. Returns the entry distance, or FLT_MAX on a miss. The exit
// distance is enlarged by 1 + 2*gamma(3) so that rounding never culls a box
// the ray touches (pbrt-v4, Bounds3::IntersectP).
float intersect_aabb(vec3 o, vec3 inv_d, vec3 lo, vec3 hi, float t_max) {
    vec3 t0 = (lo - o) * inv_d;
    vec3 t1 = (hi - o) * inv_d;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    float t_enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float t_exit = min(min(tf.x, tf.y), min(tf.z, t_max)) * 1.0000003576;
    return t_enter <= t_exit ? t_enter : FLT_MAX;
}

// The point with barycentrics b12 of vertices 1 and 2, computed from the
// edges: for a small triangle far from the origin the edges are exact
// (Sterbenz), so only the last addition rounds at the coordinates' scale.
vec3 triangle_point(vec2 b12, vec3 v0, vec3 v1, vec3 v2) {
    return v0 + (b12.x * (v1 - v0) + b12.y * (v2 - v0));
}

// Error bound (per component) of triangle_point: gamma(1) |p| for the last
// addition, gamma(4) (|b1 e1| + |b2 e2|) for the edges, products and sum
// (error analysis as in pbrt-v4, Triangle::InteractionFromIntersection;
// GAMMA7 is used for the second term), and at least OFFSET_EDGE_FRACTION of
// the largest edge component, which covers the rounding of the watertight
// test itself.
vec3 triangle_point_error(vec2 b12, vec3 v0, vec3 v1, vec3 v2, vec3 p) {
    vec3 e1 = v1 - v0;
    vec3 e2 = v2 - v0;
    vec3 e = max(abs(e1), abs(e2));
    float floor_e = OFFSET_EDGE_FRACTION * max(e.x, max(e.y, e.z));
    vec3 bound = GAMMA1 * abs(p) + GAMMA7 * (abs(b12.x * e1) + abs(b12.y * e2));
    return max(bound, vec3(floor_e));
}

// The float after x away from zero in the direction of sign s (s != 0).
float next_float_toward(float x, float s) {
    if (s == 0.0) return x;
    if (x == 0.0) return s > 0.0 ? uintBitsToFloat(1u) : -uintBitsToFloat(1u);
    uint bits = floatBitsToUint(x);
    return uintBitsToFloat((x > 0.0) == (s > 0.0) ? bits + 1u : bits - 1u);
}

// One component of offset_ray_origin: p + o, one float further when
// rounding took back part of o.
float offset_component(float p, float o) {
    // precise: the compiler may otherwise fold (p + o) - p into o and
    // never see the rounding (seen on lavapipe: rays escaped at 1e5).
    precise float po = p + o;
    precise float moved = po - p;
    return abs(moved) < abs(o) ? next_float_toward(po, o) : po;
}

// Moves p, known to within p_error per component, off its surface along n
// (pointing to the side the new ray leaves on) by the bound's projection on
// n (pbrt-v4, OffsetRayOrigin), stepping a component one float further only
// where rounding shortened its offset. Scale-invariant: the offset follows
// the coordinates' own precision, never a fixed epsilon.
vec3 offset_ray_origin(vec3 p, vec3 p_error, vec3 n) {
    float d = dot(abs(n), p_error);
    vec3 o = d * n;
    return vec3(offset_component(p.x, o.x), offset_component(p.y, o.y),
                offset_component(p.z, o.z));
}

#endif
