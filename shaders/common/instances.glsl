// The instances of a two-level scene (twin: src/cpu/common/instances.rs;
// host side: src/packed/instances.rs). A ray enters a mesh's BVH in the
// mesh's own space (to_object); what it hits is placed in the world
// (to_world): points and tangents by the matrix, normals by its inverse
// transpose, and a mirroring instance turns its triangles' winding, so
// their front faces stay in front. Every row is ((a x + b y) + c z) + d
// with no fused multiply-add, as on the CPU.
#ifndef INSTANCES_GLSL
#define INSTANCES_GLSL

#include "features.glsl"
#include "loop_count.glsl"

// Whether the scene has two levels (FEATURE_INSTANCES compiles the code
// in; an unspecialized kernel asks the parameters).
bool two_levels() {
    return FEATURE_INSTANCES && params.num_instances > 0u;
}

// Instance k's rows of to_object (texels 3-5).
void fetch_instance_to_object(uint k, out vec4 to_object_x, out vec4 to_object_y,
                              out vec4 to_object_z) {
    int base = int(INSTANCE_TEXELS * k);
    uvec4 t3 = texelFetch(instance_texels, base + 3);
    uvec4 t4 = texelFetch(instance_texels, base + 4);
    uvec4 t5 = texelFetch(instance_texels, base + 5);
    to_object_x = uintBitsToFloat(t3.xyzw);
    to_object_y = uintBitsToFloat(t4.xyzw);
    to_object_z = uintBitsToFloat(t5.xyzw);
}

// Instance k's rows of to_world (texels 0-2).
void fetch_instance_to_world(uint k, out vec4 to_world_x, out vec4 to_world_y,
                             out vec4 to_world_z) {
    int base = int(INSTANCE_TEXELS * k);
    uvec4 t0 = texelFetch(instance_texels, base);
    uvec4 t1 = texelFetch(instance_texels, base + 1);
    uvec4 t2 = texelFetch(instance_texels, base + 2);
    to_world_x = uintBitsToFloat(t0.xyzw);
    to_world_y = uintBitsToFloat(t1.xyzw);
    to_world_z = uintBitsToFloat(t2.xyzw);
}

// Instance k's BVH root, first id, first triangle slot and flags (texel 6).
void fetch_instance_entry(uint k, out uint root, out uint id_base, out uint first_triangle,
                          out uint flags) {
    uvec4 t6 = texelFetch(instance_texels, int(INSTANCE_TEXELS * k + 6u));
    root = t6.x;
    id_base = t6.y;
    first_triangle = t6.z;
    flags = t6.w;
}

uint fetch_instance_id_base(uint k) {
    uvec4 t6 = texelFetch(instance_texels, int(INSTANCE_TEXELS * k + 6u));
    uint id_base = t6.y;
    return id_base;
}

vec3 instance_point(vec4 x, vec4 y, vec4 z, vec3 p) {
    precise float px = x.x * p.x + x.y * p.y + x.z * p.z + x.w;
    precise float py = y.x * p.x + y.y * p.y + y.z * p.z + y.w;
    precise float pz = z.x * p.x + z.y * p.y + z.z * p.z + z.w;
    return vec3(px, py, pz);
}

vec3 instance_vector(vec4 x, vec4 y, vec4 z, vec3 v) {
    precise float vx = x.x * v.x + x.y * v.y + x.z * v.z;
    precise float vy = y.x * v.x + y.y * v.y + y.z * v.z;
    precise float vz = z.x * v.x + z.y * v.y + z.z * v.z;
    return vec3(vx, vy, vz);
}

// Normal n placed by the transpose of to_object's rows, normalized.
vec3 instance_normal(vec4 x, vec4 y, vec4 z, vec3 n) {
    precise float nx = x.x * n.x + y.x * n.y + z.x * n.z;
    precise float ny = x.y * n.x + y.y * n.y + z.y * n.z;
    precise float nz = x.z * n.x + y.z * n.y + z.z * n.z;
    vec3 w = vec3(nx, ny, nz);
    float len = length(w);
    return len > 0.0 ? w / len : w;
}

// The instance whose ids hold hit id `id`: instances number their
// triangles' ids in order, so a binary search over id_base finds it.
uint instance_of_id(uint id) {
    uint lo = 0u;
    uint hi = params.num_instances;
    while (hi - lo > 1u) {
        COUNT_LOOP_ITERATION();
        uint mid = (lo + hi) / 2u;
        if (fetch_instance_id_base(mid) <= id) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// The triangle slot hit id `id` names, and its instance in `inst`
// (NO_INSTANCE in a one-level scene, where an id is a slot).
uint hit_slot(uint id, out uint inst) {
    inst = NO_INSTANCE;
    if (!two_levels()) return id;
    inst = instance_of_id(id);
    uint root, id_base, first_triangle, flags;
    fetch_instance_entry(inst, root, id_base, first_triangle, flags);
    return id - id_base + first_triangle;
}

// -1.0 where instance inst mirrors, else 1.0.
float instance_facing(uint inst) {
    if (inst == NO_INSTANCE) return 1.0;
    uint root, id_base, first_triangle, flags;
    fetch_instance_entry(inst, root, id_base, first_triangle, flags);
    return (flags & INSTANCE_MIRRORED) != 0u ? -1.0 : 1.0;
}

// The triangle's vertices placed by instance inst.
void world_triangle(uint inst, inout vec3 v0, inout vec3 v1, inout vec3 v2) {
    if (inst == NO_INSTANCE) return;
    vec4 x, y, z;
    fetch_instance_to_world(inst, x, y, z);
    v0 = instance_point(x, y, z, v0);
    v1 = instance_point(x, y, z, v1);
    v2 = instance_point(x, y, z, v2);
}

// |m| applied to the non-negative v, with |translation| times t added: a
// bound on what m's rows round.
vec3 abs_rows(vec4 x, vec4 y, vec4 z, vec3 v, float t) {
    precise float rx = abs(x.x) * v.x + abs(x.y) * v.y + abs(x.z) * v.z + abs(x.w) * t;
    precise float ry = abs(y.x) * v.x + abs(y.y) * v.y + abs(y.z) * v.z + abs(y.w) * t;
    precise float rz = abs(z.x) * v.x + abs(z.y) * v.y + abs(z.z) * v.z + abs(z.w) * t;
    return vec3(rx, ry, rz);
}

// What instance inst adds to the error of world point p of one of its
// surfaces: placing the hit in the world, and taking the next ray from
// near it back into the instance's space, each round (as pbrt-v4's
// transforms carry their points' error).
vec3 instance_error(uint inst, vec3 p) {
    if (inst == NO_INSTANCE) return vec3(0.0);
    vec4 mx, my, mz, wx, wy, wz;
    fetch_instance_to_world(inst, mx, my, mz);
    fetch_instance_to_object(inst, wx, wy, wz);
    vec3 back = abs_rows(wx, wy, wz, abs(p), 1.0);
    vec3 placed = abs_rows(mx, my, mz, back, 0.0);
    precise vec3 e = GAMMA7 * (2.0 * placed + abs_rows(mx, my, mz, vec3(0.0), 1.0));
    return e;
}

// Vertex normals placed by instance inst.
void world_normals(uint inst, inout vec3 n0, inout vec3 n1, inout vec3 n2) {
    if (inst == NO_INSTANCE) return;
    vec4 x, y, z;
    fetch_instance_to_object(inst, x, y, z);
    n0 = instance_normal(x, y, z, n0);
    n1 = instance_normal(x, y, z, n1);
    n2 = instance_normal(x, y, z, n2);
}

// A vertex tangent (xyz, bitangent sign w) placed by instance inst: the
// direction by the matrix, normalized; a mirror turns the bitangent.
vec4 world_tangent(uint inst, vec4 t) {
    if (inst == NO_INSTANCE) return t;
    vec4 x, y, z;
    fetch_instance_to_world(inst, x, y, z);
    vec3 v = instance_vector(x, y, z, t.xyz);
    float len = length(v);
    v = len > 0.0 ? v / len : v;
    return vec4(v, t.w * instance_facing(inst));
}

#endif
