// Optional kernel features as specialization constants (host side:
// src/features.rs). The host turns off what a scene does not use and the
// driver compiles the guarded code out; the default (true) keeps
// everything, so a kernel is correct for any scene without specialization.
#ifndef FEATURES_GLSL
#define FEATURES_GLSL

#include "constants.glsl"

layout(constant_id = SPEC_TEXTURES) const bool FEATURE_TEXTURES = true;
layout(constant_id = SPEC_ALPHA_MASK) const bool FEATURE_ALPHA_MASK = true;
layout(constant_id = SPEC_PHONG) const bool FEATURE_PHONG = true;
layout(constant_id = SPEC_GLTF_MATERIAL) const bool FEATURE_GLTF_MATERIAL = true;
layout(constant_id = SPEC_ANALYTIC_LIGHTS) const bool FEATURE_ANALYTIC_LIGHTS = true;
layout(constant_id = SPEC_ENVIRONMENT_MAP) const bool FEATURE_ENVIRONMENT_MAP = true;
layout(constant_id = SPEC_THIN_LENS) const bool FEATURE_THIN_LENS = true;
layout(constant_id = SPEC_FILTER_BISECTION) const bool FEATURE_FILTER_BISECTION = true;
layout(constant_id = SPEC_SOBOL) const bool FEATURE_SOBOL = true;
layout(constant_id = SPEC_AOV) const bool FEATURE_AOV = true;
layout(constant_id = SPEC_CLEARCOAT) const bool FEATURE_CLEARCOAT = true;
layout(constant_id = SPEC_SHEEN) const bool FEATURE_SHEEN = true;
layout(constant_id = SPEC_IRIDESCENCE) const bool FEATURE_IRIDESCENCE = true;
layout(constant_id = SPEC_ANISOTROPY) const bool FEATURE_ANISOTROPY = true;
layout(constant_id = SPEC_DIFFUSE_TRANSMISSION) const bool FEATURE_DIFFUSE_TRANSMISSION = true;
layout(constant_id = SPEC_DISPERSION) const bool FEATURE_DISPERSION = true;
layout(constant_id = SPEC_MOTION) const bool FEATURE_MOTION = true;
layout(constant_id = SPEC_INSTANCES) const bool FEATURE_INSTANCES = true;
layout(constant_id = SPEC_LIGHT_TREE) const bool FEATURE_LIGHT_TREE = true;
// The texture slots (TEXTURE_SLOT_*) any material of the scene fills: lavapipe
// executes every branch of a kernel for every invocation, masked, so a slot
// compiled in costs its texture fetches on every hit whether used or not.
layout(constant_id = SPEC_TEXTURE_SLOTS) const uint TEXTURE_SLOT_MASK = TEXTURE_SLOTS_ALL;
// Which hits this shade kernel takes (SHADE_QUEUE_*); in extend, nonzero:
// sort hits into the basic and full shading queues. The default, one shade
// kernel for every hit, is right for any scene.
layout(constant_id = SPEC_SHADE_QUEUE) const uint SHADE_QUEUE = SHADE_QUEUE_NONE;
// log2 of the texels per part of the split scene arrays (bindings.glsl's
// scene_texel; src/packed/bindings.rs), or 0: each array is one part.
layout(constant_id = SPEC_SCENE_VIEW_SHIFT) const uint SCENE_VIEW_SHIFT = 0u;
// Any glTF PBR extension lobe: MaterialData rows 9-16 are fetched.
const bool FEATURE_PBR_EXTENSIONS = FEATURE_CLEARCOAT || FEATURE_SHEEN || FEATURE_IRIDESCENCE
    || FEATURE_ANISOTROPY || FEATURE_DIFFUSE_TRANSMISSION || FEATURE_DISPERSION;

#endif
