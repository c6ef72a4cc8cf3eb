// Shading's reads of the scene arrays through uniform texel buffers (host
// side: src/packed/, whose arrays the CPU reference indexes directly).
// lavapipe turns texel fetches into vector gathers, while its storage-buffer
// loads run one lane and one word at a time. Traversal's reads are in bvh.glsl.
//
// Each texel read goes into a variable or field named after the struct
// field it holds (a `return` takes its function's name), so that
// tests/suite/texel_reads.rs can check every texel and component against the Rust
// struct's offset_of!.
#ifndef SCENE_FETCH_GLSL
#define SCENE_FETCH_GLSL

#include "features.glsl"

// TriangleShading as 3 texels: (n0, light_pmf), (n1, -), (n2, -).
float fetch_light_pmf(uint i) {
    return uintBitsToFloat(scene_texel(tri_shading_texels, int(3u * i)).w);
}

// TriangleShading's vertex normals.
void fetch_triangle_normals(uint i, out vec3 n0, out vec3 n1, out vec3 n2) {
    int base = int(3u * i);
    n0 = uintBitsToFloat(scene_texel(tri_shading_texels, base).xyz);
    n1 = uintBitsToFloat(scene_texel(tri_shading_texels, base + 1).xyz);
    n2 = uintBitsToFloat(scene_texel(tri_shading_texels, base + 2).xyz);
}

// MaterialData as 9 texels, one per 16-byte row (src/packed/layout.rs). Rows
// that only compiled-out features read are not fetched (each fetch is a
// call on lavapipe): rows 0-1 (colour, kind, emission) always, row 2 for
// Phong, rows 3-5 for glTF materials, row 6 for textures or alpha masks,
// rows 7-8 for textures, rows 9-13 for the glTF PBR extension lobes and
// rows 14-16 for their textures. A row not fetched reads as zeros and
// NO_TEXTURE.
MaterialData fetch_material(uint m) {
    int base = int(MATERIAL_TEXELS * m);
    uvec4 t0 = texelFetch(material_texels, base);
    uvec4 t1 = texelFetch(material_texels, base + 1);
    uvec4 none = uvec4(NO_TEXTURE);
    uvec4 t2 = FEATURE_PHONG ? texelFetch(material_texels, base + 2) : uvec4(0u);
    uvec4 t3 = FEATURE_GLTF_MATERIAL ? texelFetch(material_texels, base + 3) : uvec4(0u);
    uvec4 t4 = FEATURE_GLTF_MATERIAL ? texelFetch(material_texels, base + 4) : uvec4(0u);
    uvec4 t5 = FEATURE_GLTF_MATERIAL ? texelFetch(material_texels, base + 5) : uvec4(0u);
    uvec4 t6 = FEATURE_TEXTURES || FEATURE_ALPHA_MASK ? texelFetch(material_texels, base + 6)
                                                      : uvec4(0u, 0u, 0u, NO_TEXTURE);
    uvec4 t7 = FEATURE_TEXTURES ? texelFetch(material_texels, base + 7) : none;
    uvec4 t8 = FEATURE_TEXTURES ? texelFetch(material_texels, base + 8) : none;
    bool ext = FEATURE_PBR_EXTENSIONS;
    uvec4 t9 = ext ? texelFetch(material_texels, base + 9) : uvec4(0u);
    uvec4 t10 = ext ? texelFetch(material_texels, base + 10) : uvec4(0u);
    uvec4 t11 = ext ? texelFetch(material_texels, base + 11) : uvec4(0u);
    uvec4 t12 = ext ? texelFetch(material_texels, base + 12) : uvec4(0u);
    uvec4 t13 = ext ? texelFetch(material_texels, base + 13) : uvec4(0u);
    bool ext_textures = ext && FEATURE_TEXTURES;
    uvec4 t14 = ext_textures ? texelFetch(material_texels, base + 14) : none;
    uvec4 t15 = ext_textures ? texelFetch(material_texels, base + 15) : none;
    // Row 16 also holds KHR_materials_volume's thickness texture, which a
    // textured glTF material may use without any lobe.
    bool row16 = ext_textures || (FEATURE_TEXTURES && FEATURE_GLTF_MATERIAL);
    uvec4 t16 = row16 ? texelFetch(material_texels, base + 16) : none;
    MaterialData d;
    d.base_color = uintBitsToFloat(t0.xyz);
    d.kind = t0.w;
    d.emission = uintBitsToFloat(t1.xyz);
    d.double_sided = t1.w;
    d.specular = uintBitsToFloat(t2.xyz);
    d.shininess = uintBitsToFloat(t2.w);
    d.ior = uintBitsToFloat(t3.x);
    d.metallic = uintBitsToFloat(t3.y);
    d.roughness = uintBitsToFloat(t3.z);
    d.transmission = uintBitsToFloat(t3.w);
    d.specular_color = uintBitsToFloat(t4.xyz);
    d.specular_factor = uintBitsToFloat(t4.w);
    d.attenuation = uintBitsToFloat(t5.xyz);
    d.thickness = uintBitsToFloat(t5.w);
    d.alpha = uintBitsToFloat(t6.x);
    d.alpha_cutoff = uintBitsToFloat(t6.y);
    d.normal_scale = uintBitsToFloat(t6.z);
    d.base_color_texture = t6.w;
    d.metallic_roughness_texture = t7.x;
    d.normal_texture = t7.y;
    d.emissive_texture = t7.z;
    d.specular_texture = t7.w;
    d.specular_color_texture = t8.x;
    d.transmission_texture = t8.y;
    d._pad1 = 0u;
    d._pad2 = 0u;
    d.clearcoat = uintBitsToFloat(t9.x);
    d.clearcoat_roughness = uintBitsToFloat(t9.y);
    d.clearcoat_normal_scale = uintBitsToFloat(t9.z);
    d.lobes = t9.w;
    d.sheen_color = uintBitsToFloat(t10.xyz);
    d.sheen_roughness = uintBitsToFloat(t10.w);
    d.iridescence = uintBitsToFloat(t11.x);
    d.iridescence_ior = uintBitsToFloat(t11.y);
    d.iridescence_thickness_min = uintBitsToFloat(t11.z);
    d.iridescence_thickness_max = uintBitsToFloat(t11.w);
    d.diffuse_transmission_color = uintBitsToFloat(t12.xyz);
    d.diffuse_transmission = uintBitsToFloat(t12.w);
    d.anisotropy_strength = uintBitsToFloat(t13.x);
    d.anisotropy_rotation = uintBitsToFloat(t13.y);
    d.dispersion = uintBitsToFloat(t13.z);
    d._pad3 = 0u;
    d.clearcoat_texture = t14.x;
    d.clearcoat_roughness_texture = t14.y;
    d.clearcoat_normal_texture = t14.z;
    d.sheen_color_texture = t14.w;
    d.sheen_roughness_texture = t15.x;
    d.iridescence_texture = t15.y;
    d.iridescence_thickness_texture = t15.z;
    d.anisotropy_texture = t15.w;
    d.diffuse_transmission_texture = t16.x;
    d.diffuse_transmission_color_texture = t16.y;
    d.thickness_texture = t16.z;
    d._pad4 = 0u;
    return d;
}

// Emitter as 1 texel: (triangle, cdf, pmf, area).
Emitter fetch_emitter(uint i) {
    uvec4 t = scene_texel(emitter_texels, int(i));
    Emitter e;
    e.triangle = t.x;
    e.cdf = uintBitsToFloat(t.y);
    e.pmf = uintBitsToFloat(t.z);
    e.area = uintBitsToFloat(t.w);
    return e;
}

float fetch_emitter_cdf(uint i) {
    return uintBitsToFloat(scene_texel(emitter_texels, int(i)).y);
}

#endif
