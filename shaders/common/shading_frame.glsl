// The one place where the shading normal is reconciled with the geometric
// normal (twin: src/cpu/common/shading_frame.rs, which explains the method).
#ifndef SHADING_FRAME_GLSL
#define SHADING_FRAME_GLSL

#include "bsdf.glsl"
#include "textures.glsl"

vec3 interpolate_normal(vec3 n0, vec3 n1, vec3 n2, vec2 b12, vec3 ng) {
    vec3 n = (1.0 - b12.x - b12.y) * n0 + b12.x * n1 + b12.y * n2;
    float len = length(n);
    return len > 1e-12 ? n / len : ng;
}

// ng: unit geometric normal on wo's side; ns: shading normal on that side.
vec3 reconcile_shading_normal(vec3 ng, vec3 ns, vec3 wo) {
    if (dot(ns, ng) <= 0.0) return ng;
    vec3 r = reflect_about(wo, ns);
    float height = dot(r, ng);
    if (height >= SHADING_NORMAL_MIN_COS) return ns;
    vec3 tangent = r - height * ng;
    float len = length(tangent);
    if (len <= 1e-12) return ng;
    float c = SHADING_NORMAL_MIN_COS;
    vec3 lifted = tangent * (sqrt(1.0 - c * c) / len) + c * ng;
    vec3 h = wo + lifted;
    float hl = length(h);
    return hl <= 1e-12 ? ng : h / hl;
}

bool same_side(vec3 ng, vec3 ns, vec3 w) {
    return dot(w, ng) * dot(w, ns) > 0.0;
}

// KHR_materials_anisotropy's direction at b12 of tri: the interpolated
// vertex tangent made orthogonal to ns, turned by anisotropy_rotation
// toward glTF's bitangent w * cross(front normal, t). Without a usable
// tangent: build_onb(ns)'s t and b (a fixed but arbitrary direction).
vec3 anisotropy_direction(MaterialData m, uint tri, uint inst, vec2 b12, float time, vec3 ns, bool front) {
    vec3 t, b;
    build_onb(ns, t, b);
    if (tri < uint(tri_texcoords.length())) {
        vec4 t4 = interpolated_tangent(tri, inst, b12, time);
        vec3 tt = t4.xyz - ns * dot(ns, t4.xyz);
        float len = length(tt);
        if (len > 1e-6) {
            t = tt / len;
            b = (t4.w < 0.0 ? -1.0 : 1.0) * cross(front ? ns : -ns, t);
        }
    }
    return cos(m.anisotropy_rotation) * t + sin(m.anisotropy_rotation) * b;
}

// The BSDF's frame (bsdf.glsl's ShadingFrame) at b12 of tri: ns the
// reconciled shading normal on wo's side, n the geometric normal on that
// side, n_vertex the interpolated vertex normal (front side, before normal
// mapping). An anisotropic material's t is its anisotropy direction; a
// coated one's coat normal is n_vertex (the spec's: the base normal map
// does not bend the coat) or its clearcoatNormalTexture, reconciled like ns.
ShadingFrame shading_frame(MaterialData m, uint tri, uint inst, vec2 b12, float time, vec3 n, vec3 n_vertex, vec3 ns,
                           bool front, vec3 wo) {
    ShadingFrame f = frame_of_normal(ns);
    if (anisotropy_active(m)) {
        f.t = anisotropy_direction(m, tri, inst, b12, time, ns, front);
        f.b = cross(ns, f.t);
    }
    if (clearcoat_active(m)) {
        vec3 nc = n_vertex;
        if (FEATURE_TEXTURES && (TEXTURE_SLOT_MASK & TEXTURE_SLOT_CLEARCOAT_NORMAL) != 0u
            && m.clearcoat_normal_texture != NO_TEXTURE) {
            nc = perturb_normal(m.clearcoat_normal_texture, m.clearcoat_normal_scale, tri, inst, b12, time, nc);
        }
        f.coat_n = reconcile_shading_normal(n, front ? nc : -nc, wo);
    }
    return f;
}

#endif
