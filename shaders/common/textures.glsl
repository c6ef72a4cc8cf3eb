// Texture sampling (twin: src/cpu/common/textures.rs). Needs bindings.glsl.
// Texels live in one R32UI texel buffer (texture_texels: the sRGB decode
// table, then every image as RGBA8 words, red in the low byte, rows top to
// bottom, or for a grey image one byte per texel (TEXTURE_GREY) and for grey
// with alpha two (TEXTURE_GREY_ALPHA), which texel_rgba8 reads back as the
// same RGBA8 word; split into parts where it is large, read by scene_texel, so no
// view's size bounds the textures) and are fetched and filtered here, the same way as on the CPU:
// lavapipe has no descriptor indexing, and both back ends then sample
// identical data. Filtering is bilinear (nearest when the glTF sampler's
// magFilter says so) with the sampler's wrap mode applied to each texel
// coordinate; sRGB channels are decoded per texel, before weighting. Minified
// textures are mip-mapped (trilinear): a cone one pixel wide from the camera
// gives each hit a footprint (texture_footprint), and the level is log2 of
// the texels across it (texture_lod); a footprint under one texel reads the
// image itself, exactly as without mip levels.
#ifndef TEXTURES_GLSL
#define TEXTURES_GLSL

#include "features.glsl"
#include "rng.glsl"
#include "scene_fetch.glsl"
#include "motion.glsl"
#include "instances.glsl"

uint texel_word(uint i) {
    return scene_texel(texture_texels, int(i)).x;
}

// i mod n in [0, n) for any sign of i (GLSL's % is undefined for negatives).
int floor_mod(int i, int n) {
    int q = i >= 0 ? i / n : -((-i - 1) / n) - 1;
    return i - q * n;
}

// A texel coordinate wrapped into [0, n) by a WRAP_* mode.
int wrap_texel(int i, int n, uint mode) {
    if (mode == WRAP_CLAMP_TO_EDGE) return clamp(i, 0, n - 1);
    if (mode == WRAP_MIRRORED_REPEAT) {
        int m = floor_mod(i, 2 * n);
        return m < n ? m : 2 * n - 1 - m;
    }
    return floor_mod(i, n);
}

// An RGBA8 texel as floats; with srgb, RGB through the sRGB decode table
// (alpha is always linear).
vec4 decode_texel(uint w, bool srgb) {
    uvec4 c = uvec4(w & 0xFFu, (w >> 8u) & 0xFFu, (w >> 16u) & 0xFFu, w >> 24u);
    vec4 v = vec4(c) * INV_255;
    if (srgb) {
        v.rgb = uintBitsToFloat(uvec3(texel_word(c.r), texel_word(c.g), texel_word(c.b)));
    }
    return v;
}

// Texel i (row-major) of ti as its RGBA8 word, whatever its storage: a grey
// byte g reads as (g, g, g, 255), grey and alpha as (g, g, g, a). One word
// read for every storage: each fetch inlined here is inlined at every
// bilinear tap of every texture slot, which is what lavapipe compiles.
uint texel_rgba8(TextureInfo ti, uint i) {
    bool grey = (ti.flags & TEXTURE_GREY) != 0u;
    bool grey_alpha = (ti.flags & TEXTURE_GREY_ALPHA) != 0u;
    uint shift = grey ? 2u : (grey_alpha ? 1u : 0u);
    uint w = texel_word(ti.offset + (i >> shift));
    if (grey) {
        uint g = (w >> (8u * (i & 3u))) & 0xFFu;
        return g * 0x010101u | 0xFF000000u;
    }
    if (grey_alpha) {
        uint ga = (w >> (16u * (i & 1u))) & 0xFFFFu;
        return (ga & 0xFFu) * 0x010101u | (ga >> 8u) << 24u;
    }
    return w;
}

// Words of texel buffer `texels` texels of ti's storage take.
uint texel_storage_words(TextureInfo ti, uint texels) {
    uint per = (ti.flags & TEXTURE_GREY) != 0u ? 4u : ((ti.flags & TEXTURE_GREY_ALPHA) != 0u ? 2u : 1u);
    return (texels + per - 1u) / per;
}

// ti at mip level `level`: its first word, width and height (levels follow
// the image, each halved with odd sizes rounded up, each starting on a word).
TextureInfo texture_level(TextureInfo ti, uint level) {
    for (uint k = 0u; k < level; k++) {
        COUNT_LOOP_ITERATION();
        ti.offset += texel_storage_words(ti, ti.width * ti.height);
        ti.width = (ti.width + 1u) / 2u;
        ti.height = (ti.height + 1u) / 2u;
    }
    return ti;
}

vec4 fetch_texel(TextureInfo ti, int x, int y, bool srgb) {
    return decode_texel(texel_rgba8(ti, uint(y) * ti.width + uint(x)), srgb);
}

// The mip level (fractional) at which texture ti is sampled for a hit whose
// footprint is texture_footprint's: log2 of texels per footprint width. 0
// (the image itself) without mip levels or footprint.
float texture_lod(TextureInfo ti, vec3 footprint) {
    if (ti.levels <= 1u || !(footprint.x > NO_FOOTPRINT)) return 0.0;
    float uv = (ti.flags & TEXTURE_TEXCOORD_1) != 0u ? footprint.z : footprint.y;
    // KHR_texture_transform scales texture-space areas by its determinant.
    float det = abs(ti.transform_s.x * ti.transform_t.y - ti.transform_s.y * ti.transform_t.x);
    return footprint.x + uv + 0.5 * log2(float(ti.width) * float(ti.height) * det);
}

// One level ti (texture_level) at texture-space point st: nearest or
// bilinear with the sampler's wrap modes.
vec4 sample_level(TextureInfo ti, vec2 st, bool srgb) {
    int w = int(ti.width);
    int h = int(ti.height);
    float x = clamp(st.x * float(w), -TEXEL_COORD_LIMIT, TEXEL_COORD_LIMIT);
    float y = clamp(st.y * float(h), -TEXEL_COORD_LIMIT, TEXEL_COORD_LIMIT);
    uint wrap_s = ti.flags & 3u;
    uint wrap_t = (ti.flags >> TEXTURE_WRAP_T_SHIFT) & 3u;
    if ((ti.flags & TEXTURE_NEAREST) != 0u) {
        return fetch_texel(ti, wrap_texel(int(floor(x)), w, wrap_s),
                           wrap_texel(int(floor(y)), h, wrap_t), srgb);
    }
    // Bilinear between the four texel centres around (x, y).
    x -= 0.5;
    y -= 0.5;
    float x0 = floor(x);
    float y0 = floor(y);
    float fx = x - x0;
    float fy = y - y0;
    int xa = wrap_texel(int(x0), w, wrap_s);
    int xb = wrap_texel(int(x0) + 1, w, wrap_s);
    int ya = wrap_texel(int(y0), h, wrap_t);
    int yb = wrap_texel(int(y0) + 1, h, wrap_t);
    vec4 top = mix(fetch_texel(ti, xa, ya, srgb), fetch_texel(ti, xb, ya, srgb), fx);
    vec4 bottom = mix(fetch_texel(ti, xa, yb, srgb), fetch_texel(ti, xb, yb, srgb), fx);
    return mix(top, bottom, fy);
}

// Texture row ti's texture-space point for texture coordinates uv0 / uv1:
// the row picks the set and applies its KHR_texture_transform.
vec2 texture_st(TextureInfo ti, vec2 uv0, vec2 uv1) {
    vec3 uvh = vec3((ti.flags & TEXTURE_TEXCOORD_1) != 0u ? uv1 : uv0, 1.0);
    return vec2(dot(ti.transform_s, uvh), dot(ti.transform_t, uvh));
}

// Texture table row t at texture coordinates uv0 / uv1, the image itself
// (no mip level): emission, normal maps and alpha tests.
vec4 texture_sample_image(uint t, vec2 uv0, vec2 uv1, bool srgb) {
    TextureInfo ti = textures[t];
    return sample_level(ti, texture_st(ti, uv0, uv1), srgb);
}

// Texture table row t at texture coordinates uv0 / uv1, trilinear between
// the mip levels `footprint` (texture_footprint; NO_FOOTPRINT in x for the
// image itself) spans. The one or two levels are read by one sample_level
// in a loop, not two calls: lavapipe inlines every call at every texture
// slot, and an unspecialized shade kernel then grew past what Mesa
// compiles in reasonable memory.
vec4 texture_sample(uint t, vec2 uv0, vec2 uv1, bool srgb, vec3 footprint) {
    TextureInfo ti = textures[t];
    vec2 st = texture_st(ti, uv0, uv1);
    float lod = texture_lod(ti, footprint);
    // Only where it pays: a footprint under one texel reads the image
    // itself; at or past the top level, that level alone.
    float top = float(ti.levels - 1u);
    float k = !(lod > 0.0) ? 0.0 : min(floor(lod), top);
    uint count = (lod > 0.0 && lod < top) ? 2u : 1u;
    TextureInfo level = texture_level(ti, uint(k));
    vec4 fine = vec4(0.0);
    vec4 coarse = vec4(0.0);
    for (uint i = 0u; i < count; i++) {
        COUNT_LOOP_ITERATION();
        vec4 c = sample_level(level, st, srgb);
        if (i == 0u) fine = c; else coarse = c;
        level = texture_level(level, 1u);
    }
    return count == 1u ? fine : mix(fine, coarse, lod - k);
}

// TriangleTexcoords as 6 texels: (uv0_01), (uv0_2_uv1_0), (uv1_12), then
// tangent0..2; the first three, the vertices' texture coordinates.
void fetch_triangle_texcoords(uint tri, out vec4 uv0_01, out vec4 uv0_2_uv1_0, out vec4 uv1_12) {
    int base = int(6u * tri);
    uv0_01 = uintBitsToFloat(scene_texel(tri_texcoord_texels, base).xyzw);
    uv0_2_uv1_0 = uintBitsToFloat(scene_texel(tri_texcoord_texels, base + 1).xyzw);
    uv1_12 = uintBitsToFloat(scene_texel(tri_texcoord_texels, base + 2).xyzw);
}

// Twice the areas of triangle tri's texture-coordinate triangles, sets 0
// and 1 (TriangleTexcoords' first three texels).
vec2 triangle_uv_areas(uint tri) {
    vec4 uv0_01, uv0_2_uv1_0, uv1_12;
    fetch_triangle_texcoords(tri, uv0_01, uv0_2_uv1_0, uv1_12);
    vec2 a = uv0_01.zw - uv0_01.xy;
    vec2 b = uv0_2_uv1_0.xy - uv0_01.xy;
    vec2 c = uv1_12.xy - uv0_2_uv1_0.zw;
    vec2 d = uv1_12.zw - uv0_2_uv1_0.zw;
    return vec2(abs(a.x * b.y - a.y * b.x), abs(c.x * d.y - c.y * d.x));
}

// The texture footprint of a hit at p on world triangle v0 v1 v2 (slot tri),
// for texture_lod: a cone from the camera one pixel wide
// (params.texture_spread), its width at p over |cos| of the view direction
// and the surface, as a log2 less half the log2 of the triangle's world
// area (x), and half the log2 of its texture-coordinate areas (y, z). The
// same cone serves every bounce, its width at p measured from the camera
// (as pbrt-v4's Approximate_dp_dxy does after the first hit): exact at the
// camera hit of a pinhole, and after a bounce no wider than the path's own
// cone, which only grows along the path except behind a focusing (concave)
// mirror. NO_FOOTPRINT when mip-mapping is off.
vec3 texture_footprint(uint tri, vec3 v0, vec3 v1, vec3 v2, vec3 p) {
    vec3 ng_raw = cross(v1 - v0, v2 - v0);
    float world = length(ng_raw);
    if (!(params.texture_spread > 0.0) || !(world > 0.0)) return vec3(NO_FOOTPRINT, 0.0, 0.0);
    bool ortho = params.projection == PROJECTION_ORTHOGRAPHIC;
    vec3 to_p = p - params.cam_position;
    float dist = length(to_p);
    vec3 view = ortho ? params.cam_forward : to_p / dist;
    float cos_v = max(abs(dot(view, ng_raw) / world), FOOTPRINT_MIN_COS);
    float width = params.texture_spread * (ortho ? 1.0 : dist);
    vec2 uv = triangle_uv_areas(tri);
    return vec3(log2(width / cos_v) - 0.5 * log2(world), 0.5 * log2(uv.x), 0.5 * log2(uv.y));
}

// Texture coordinates (sets 0 and 1) at barycentrics b12 of triangle tri.
void fetch_triangle_uvs(uint tri, vec2 b12, out vec2 uv0, out vec2 uv1) {
    vec4 uv0_01, uv0_2_uv1_0, uv1_12;
    fetch_triangle_texcoords(tri, uv0_01, uv0_2_uv1_0, uv1_12);
    float b0 = 1.0 - b12.x - b12.y;
    uv0 = b0 * uv0_01.xy + b12.x * uv0_01.zw + b12.y * uv0_2_uv1_0.xy;
    uv1 = b0 * uv0_2_uv1_0.zw + b12.x * uv1_12.xy + b12.y * uv1_12.zw;
}

// TriangleTexcoords' vertex tangents (xyz, bitangent sign w).
void fetch_triangle_tangents(uint tri, out vec4 tangent0, out vec4 tangent1, out vec4 tangent2) {
    int base = int(6u * tri);
    tangent0 = uintBitsToFloat(scene_texel(tri_texcoord_texels, base + 3).xyzw);
    tangent1 = uintBitsToFloat(scene_texel(tri_texcoord_texels, base + 4).xyzw);
    tangent2 = uintBitsToFloat(scene_texel(tri_texcoord_texels, base + 5).xyzw);
}

bool material_has_textures(MaterialData m) {
    return m.base_color_texture != NO_TEXTURE || m.metallic_roughness_texture != NO_TEXTURE
        || m.normal_texture != NO_TEXTURE || m.emissive_texture != NO_TEXTURE
        || m.specular_texture != NO_TEXTURE || m.specular_color_texture != NO_TEXTURE
        || m.transmission_texture != NO_TEXTURE
        || (FEATURE_CLEARCOAT && (m.clearcoat_texture != NO_TEXTURE || m.clearcoat_roughness_texture != NO_TEXTURE))
        || (FEATURE_ANISOTROPY && m.anisotropy_texture != NO_TEXTURE)
        || m.sheen_color_texture != NO_TEXTURE || m.sheen_roughness_texture != NO_TEXTURE
        || m.iridescence_texture != NO_TEXTURE || m.iridescence_thickness_texture != NO_TEXTURE
        || m.diffuse_transmission_texture != NO_TEXTURE
        || m.diffuse_transmission_color_texture != NO_TEXTURE || m.thickness_texture != NO_TEXTURE;
}

// The material at barycentrics b12 of triangle tri: every factor with a
// texture multiplied by it, as glTF defines (base colour and alpha by
// baseColor (sRGB), roughness by G and metallic by B of metallicRoughness,
// emission by emissive (sRGB), specular_factor by the specular texture's A,
// specular_color by specularColor (sRGB), transmission by R), for the
// slots set in `slots` (TEXTURE_SLOT_*).
// footprint (texture_footprint) picks the mip levels of every slot but the
// emission, which is read at full resolution: a light sample reads it
// there too, and MIS weighs the two as estimates of one integrand.
MaterialData apply_texture_slots(MaterialData m, uint tri, vec2 b12, uint slots, vec3 footprint) {
    if (!FEATURE_TEXTURES || !material_has_textures(m)) return m;
    vec2 uv0, uv1;
    fetch_triangle_uvs(tri, b12, uv0, uv1);
    if ((slots & TEXTURE_SLOT_BASE_COLOR) != 0u && m.base_color_texture != NO_TEXTURE) {
        vec4 c = texture_sample(m.base_color_texture, uv0, uv1, true, footprint);
        m.base_color *= c.rgb;
        m.alpha *= c.a;
    }
    if ((slots & TEXTURE_SLOT_METALLIC_ROUGHNESS) != 0u && m.metallic_roughness_texture != NO_TEXTURE) {
        vec4 c = texture_sample(m.metallic_roughness_texture, uv0, uv1, false, footprint);
        m.roughness *= c.g;
        m.metallic *= c.b;
    }
    if ((slots & TEXTURE_SLOT_EMISSIVE) != 0u && m.emissive_texture != NO_TEXTURE) {
        m.emission *= texture_sample_image(m.emissive_texture, uv0, uv1, true).rgb;
    }
    if ((slots & TEXTURE_SLOT_SPECULAR) != 0u && m.specular_texture != NO_TEXTURE) {
        m.specular_factor *= texture_sample(m.specular_texture, uv0, uv1, false, footprint).a;
    }
    if ((slots & TEXTURE_SLOT_SPECULAR_COLOR) != 0u && m.specular_color_texture != NO_TEXTURE) {
        m.specular_color *= texture_sample(m.specular_color_texture, uv0, uv1, true, footprint).rgb;
    }
    if ((slots & TEXTURE_SLOT_TRANSMISSION) != 0u && m.transmission_texture != NO_TEXTURE) {
        m.transmission *= texture_sample(m.transmission_texture, uv0, uv1, false, footprint).r;
    }
    // KHR_materials_clearcoat: factor by R, roughness by G.
    if (FEATURE_CLEARCOAT && (slots & TEXTURE_SLOT_CLEARCOAT) != 0u && m.clearcoat_texture != NO_TEXTURE) {
        m.clearcoat *= texture_sample(m.clearcoat_texture, uv0, uv1, false, footprint).r;
    }
    if (FEATURE_CLEARCOAT && (slots & TEXTURE_SLOT_CLEARCOAT_ROUGHNESS) != 0u && m.clearcoat_roughness_texture != NO_TEXTURE) {
        m.clearcoat_roughness *= texture_sample(m.clearcoat_roughness_texture, uv0, uv1, false, footprint).g;
    }
    // KHR_materials_anisotropy: strength by B; RG a direction in [-1, 1]^2
    // in tangent space, which turns the rotation by its angle.
    if (FEATURE_ANISOTROPY && (slots & TEXTURE_SLOT_ANISOTROPY) != 0u && m.anisotropy_texture != NO_TEXTURE) {
        vec3 c = texture_sample(m.anisotropy_texture, uv0, uv1, false, footprint).rgb;
        m.anisotropy_strength *= c.b;
        vec2 d = c.rg * 2.0 - 1.0;
        if (dot(d, d) > 0.0) m.anisotropy_rotation += atan(d.y, d.x);
    }
    // KHR_materials_sheen, _iridescence, _diffuse_transmission and the
    // volume's thickness (src/cpu/common/textures.rs says how each applies).
    if ((slots & TEXTURE_SLOT_SHEEN_COLOR) != 0u && m.sheen_color_texture != NO_TEXTURE) {
        m.sheen_color *= texture_sample(m.sheen_color_texture, uv0, uv1, true, footprint).rgb;
    }
    if ((slots & TEXTURE_SLOT_SHEEN_ROUGHNESS) != 0u && m.sheen_roughness_texture != NO_TEXTURE) {
        m.sheen_roughness *= texture_sample(m.sheen_roughness_texture, uv0, uv1, false, footprint).a;
    }
    if ((slots & TEXTURE_SLOT_IRIDESCENCE) != 0u && m.iridescence_texture != NO_TEXTURE) {
        m.iridescence *= texture_sample(m.iridescence_texture, uv0, uv1, false, footprint).r;
    }
    if ((slots & TEXTURE_SLOT_IRIDESCENCE_THICKNESS) != 0u && m.iridescence_thickness_texture != NO_TEXTURE) {
        float g = texture_sample(m.iridescence_thickness_texture, uv0, uv1, false, footprint).g;
        m.iridescence_thickness_max = m.iridescence_thickness_min
            + (m.iridescence_thickness_max - m.iridescence_thickness_min) * g;
    }
    if ((slots & TEXTURE_SLOT_DIFFUSE_TRANSMISSION) != 0u && m.diffuse_transmission_texture != NO_TEXTURE) {
        m.diffuse_transmission *= texture_sample(m.diffuse_transmission_texture, uv0, uv1, false, footprint).a;
    }
    if ((slots & TEXTURE_SLOT_DIFFUSE_TRANSMISSION_COLOR) != 0u && m.diffuse_transmission_color_texture != NO_TEXTURE) {
        m.diffuse_transmission_color *= texture_sample(m.diffuse_transmission_color_texture, uv0, uv1, true, footprint).rgb;
    }
    if ((slots & TEXTURE_SLOT_THICKNESS) != 0u && m.thickness_texture != NO_TEXTURE) {
        m.thickness *= texture_sample(m.thickness_texture, uv0, uv1, false, footprint).g;
    }
    return m;
}

// apply_textures for the slots the scene fills (TEXTURE_SLOT_MASK).
MaterialData apply_textures(MaterialData m, uint tri, vec2 b12, vec3 footprint) {
    return apply_texture_slots(m, tri, b12, TEXTURE_SLOT_MASK, footprint);
}

// The fraction of rays that meet a surface of this alpha and alpha_cutoff
// (MaterialData): MASK 0 or 1 by the cutoff, BLEND alpha, opaque 1.
float alpha_coverage(float alpha, float cutoff) {
    if (cutoff == ALPHA_BLEND) return clamp(alpha, 0.0, 1.0);
    return alpha >= cutoff ? 1.0 : 0.0;
}

// Radiance a light sample at b12 of emissive triangle tri receives from
// material m: the emission with its texture, times the fraction of rays
// that meet the surface there (a BSDF-sampled ray meets it that often).
vec3 textured_emission(MaterialData m, uint tri, vec2 b12) {
    // Only the emission and the alpha matter here, both read at full
    // resolution (apply_texture_slots says why for the emission); the
    // other slots' fetches would cost lavapipe as much, unused.
    if (FEATURE_TEXTURES && material_has_textures(m)) {
        vec2 uv0, uv1;
        fetch_triangle_uvs(tri, b12, uv0, uv1);
        if ((TEXTURE_SLOT_MASK & TEXTURE_SLOT_BASE_COLOR) != 0u && m.base_color_texture != NO_TEXTURE) {
            m.alpha *= texture_sample_image(m.base_color_texture, uv0, uv1, true).a;
        }
        if ((TEXTURE_SLOT_MASK & TEXTURE_SLOT_EMISSIVE) != 0u && m.emissive_texture != NO_TEXTURE) {
            m.emission *= texture_sample_image(m.emissive_texture, uv0, uv1, true).rgb;
        }
    }
    if (!FEATURE_ALPHA_MASK) return m.emission;
    return m.emission * alpha_coverage(m.alpha, m.alpha_cutoff);
}

// Alpha MASK and BLEND: whether a hit at b12 on triangle tri (material
// index mi, not opaque) is kept, with alpha = alpha factor × baseColor
// texture's A: MASK where alpha reaches the cutoff, BLEND with probability
// alpha (the ray's random number for this triangle from coverage_seed).
// Reads only MaterialData's row 6 (alpha, alpha_cutoff, normal_scale,
// base_color_texture; see src/packed/layout.rs).
bool alpha_test_passes(uint mi, uint tri, vec2 b12, uint coverage_seed) {
    uvec4 row6 = texelFetch(material_texels, int(MATERIAL_TEXELS * mi + 6u));
    float alpha = uintBitsToFloat(row6.x);
    float alpha_cutoff = uintBitsToFloat(row6.y);
    uint base_color_texture = row6.w;
    if ((TEXTURE_SLOT_MASK & TEXTURE_SLOT_BASE_COLOR) != 0u && base_color_texture != NO_TEXTURE) {
        vec2 uv0, uv1;
        fetch_triangle_uvs(tri, b12, uv0, uv1);
        alpha *= texture_sample_image(base_color_texture, uv0, uv1, false).a;
    }
    return alpha_cutoff == ALPHA_BLEND ? alpha > rng_coverage(coverage_seed, tri)
                                       : alpha >= alpha_cutoff;
}

// The vertex tangents (xyz, bitangent sign w) blended at b12, with the
// triangle where it is at `time` (motion.glsl), placed by instance inst.
vec4 interpolated_tangent(uint tri, uint inst, vec2 b12, float time) {
    vec4 t0, t1, t2;
    fetch_triangle_tangents(tri, t0, t1, t2);
    if (motion_on()) moving_triangle_tangents(tri, time, t0, t1, t2);
    t0 = world_tangent(inst, t0);
    t1 = world_tangent(inst, t1);
    t2 = world_tangent(inst, t2);
    float b0 = 1.0 - b12.x - b12.y;
    return b0 * t0 + b12.x * t1 + b12.y * t2;
}

// A normal map's (texture `tex`) perturbation of the unit shading normal ns
// at b12: tangent space from the interpolated
// vertex tangents, Gram-Schmidt against ns, bitangent w · cross(ns, t) as
// glTF defines; the map's XY scaled by normal_scale. Returns ns when the
// tangent frame is degenerate.
vec3 perturb_normal(uint tex, float normal_scale, uint tri, uint inst, vec2 b12, float time, vec3 ns) {
    if (!FEATURE_TEXTURES) return ns;
    vec4 t4 = interpolated_tangent(tri, inst, b12, time);
    vec3 t = t4.xyz - ns * dot(ns, t4.xyz);
    float len = length(t);
    if (!(len > 1e-6)) return ns;
    t /= len;
    vec3 b = (t4.w < 0.0 ? -1.0 : 1.0) * cross(ns, t);
    vec2 uv0, uv1;
    fetch_triangle_uvs(tri, b12, uv0, uv1);
    vec3 c = texture_sample_image(tex, uv0, uv1, false).rgb * 2.0 - 1.0;
    c.xy *= normal_scale;
    vec3 n = c.x * t + c.y * b + c.z * ns;
    float n_len = length(n);
    return n_len > 0.0 ? n / n_len : ns;
}

// The base normal map; perturb_normal also serves KHR_materials_clearcoat's
// clearcoatNormalTexture with its own scale.
vec3 apply_normal_map(MaterialData m, uint tri, uint inst, vec2 b12, float time, vec3 ns) {
    return perturb_normal(m.normal_texture, m.normal_scale, tri, inst, b12, time, ns);
}

#endif
