// KHR_materials_dispersion (twin: src/cpu/common/dispersion.rs, which explains the
// estimator): a path that meets a dispersive refracting surface continues
// in one colour channel, picked uniformly and weighted by 3, and sees the
// index of refraction of that channel's wavelength from then on.
#ifndef DISPERSION_GLSL
#define DISPERSION_GLSL

#include "features.glsl"

bool dispersive(MaterialData m) {
    return FEATURE_DISPERSION && (m.lobes & LOBE_DISPERSION) != 0u && m.kind == MATERIAL_GLTF
        && m.transmission > 0.0 && m.thickness > 0.0;
}

// The spec's Abbe-number model: n(l) = n_d + (n_d - 1) / V_d
// (523655 / l^2 - 1.5168), V_d = 20 / dispersion, l in nm.
float dispersion_ior(float ior, float dispersion, uint channel) {
    float l = channel == 1u ? DISPERSION_WAVELENGTH_R
            : channel == 2u ? DISPERSION_WAVELENGTH_G : DISPERSION_WAVELENGTH_B;
    return ior + (ior - 1.0) * (dispersion / 20.0) * (523655.0 / (l * l) - 1.5168);
}

// Channel 1, 2 or 3 (red, green, blue) from a uniform number.
uint dispersion_pick_channel(float u) {
    return 1u + min(uint(u * 3.0), 2u);
}

// 3 in the picked channel, 0 in the others.
vec3 dispersion_channel_weight(uint channel) {
    return vec3(channel == 1u ? 3.0 : 0.0, channel == 2u ? 3.0 : 0.0, channel == 3u ? 3.0 : 0.0);
}

#endif
