// Shading's reads of the scene arrays through uniform texel buffers (host
// side: src/packed.rs, whose arrays the CPU reference indexes directly).
// lavapipe turns texel fetches into vector gathers, while its storage-buffer
// loads run one lane and one word at a time. Traversal's reads are in bvh.glsl.
#ifndef SCENE_FETCH_GLSL
#define SCENE_FETCH_GLSL

// TriangleShading as 3 texels: (n0, light_pmf), (n1, -), (n2, -).
float fetch_light_pmf(uint i) {
    return uintBitsToFloat(texelFetch(tri_shading_texels, int(3u * i)).w);
}

// MaterialData as 4 texels: (base_color, kind), (emission, double_sided),
// (specular, shininess), (ior, -, -, -).
MaterialData fetch_material(uint m) {
    uvec4 t0 = texelFetch(material_texels, int(4u * m));
    uvec4 t1 = texelFetch(material_texels, int(4u * m + 1u));
    uvec4 t2 = texelFetch(material_texels, int(4u * m + 2u));
    uvec4 t3 = texelFetch(material_texels, int(4u * m + 3u));
    MaterialData d;
    d.base_color = uintBitsToFloat(t0.xyz);
    d.kind = t0.w;
    d.emission = uintBitsToFloat(t1.xyz);
    d.double_sided = t1.w;
    d.specular = uintBitsToFloat(t2.xyz);
    d.shininess = uintBitsToFloat(t2.w);
    d.ior = uintBitsToFloat(t3.x);
    d._pad1 = 0.0;
    d._pad2 = 0.0;
    d._pad3 = 0.0;
    return d;
}

// Emitter as 1 texel: (triangle, cdf, pmf, area).
Emitter fetch_emitter(uint i) {
    uvec4 t = texelFetch(emitter_texels, int(i));
    Emitter e;
    e.triangle = t.x;
    e.cdf = uintBitsToFloat(t.y);
    e.pmf = uintBitsToFloat(t.z);
    e.area = uintBitsToFloat(t.w);
    return e;
}

float fetch_emitter_cdf(uint i) {
    return uintBitsToFloat(texelFetch(emitter_texels, int(i)).y);
}

#endif
