//! `KHR_materials_dispersion` (twin: `shaders/common/dispersion.glsl`).
//!
//! The index of refraction varies with wavelength by the spec's Abbe-number
//! model. vkpt renders RGB, so dispersion is resolved at one wavelength per
//! channel (`DISPERSION_WAVELENGTH_*`): a path that reaches a dispersive
//! refracting surface picks one channel uniformly, keeps only that channel
//! of its throughput, times 3, and from then on refracts with that
//! channel's index, at this and every later dispersive surface. Each
//! channel's expectation is then the render with that channel's index (3 ×
//! 1/3), so the estimator has no bias for the three-wavelength model, and a
//! material without dispersion never takes this path. The price is colour
//! noise behind dispersive glass; the fringes are three shifted copies, not
//! a continuous spectrum.

use crate::constants::*;
use crate::packed::layout::MaterialData;
use glam::Vec3;

pub fn dispersive(m: &MaterialData) -> bool {
    m.lobes & LOBE_DISPERSION != 0
        && m.kind == MATERIAL_GLTF
        && m.transmission > 0.0
        && m.thickness > 0.0
}

/// n(λ) = n_d + (n_d − 1) / V_d · (523655 / λ² − 1.5168), V_d = 20 /
/// dispersion, λ in nm: the Cauchy fit through n_d at 587.6 nm whose
/// n_F − n_C (486.1 and 656.3 nm) is (n_d − 1) / V_d, the Abbe number's
/// definition.
pub fn dispersion_ior(ior: f32, dispersion: f32, channel: u32) -> f32 {
    let l = match channel {
        1 => DISPERSION_WAVELENGTH_R,
        2 => DISPERSION_WAVELENGTH_G,
        _ => DISPERSION_WAVELENGTH_B,
    };
    ior + (ior - 1.0) * (dispersion / 20.0) * (523655.0 / (l * l) - 1.5168)
}

/// Channel 1, 2 or 3 (red, green, blue) from a uniform number.
pub fn dispersion_pick_channel(u: f32) -> u32 {
    1 + ((u * 3.0) as u32).min(2)
}

/// 3 in the picked channel, 0 in the others.
pub fn dispersion_channel_weight(channel: u32) -> Vec3 {
    Vec3::new(
        if channel == 1 { 3.0 } else { 0.0 },
        if channel == 2 { 3.0 } else { 0.0 },
        if channel == 3 { 3.0 } else { 0.0 },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The model's index at a wavelength (the channel function with λ free).
    fn ior_at(ior: f64, dispersion: f64, l: f64) -> f64 {
        ior + (ior - 1.0) * (dispersion / 20.0) * (523655.0 / (l * l) - 1.5168)
    }

    #[test]
    fn the_model_meets_the_abbe_number_definition() {
        // n_d at the helium d line, and n_F - n_C = (n_d - 1) / V_d.
        for (ior, dispersion) in [(1.5, 1.0), (2.42, 0.5), (1.33, 3.0)] {
            let v = 20.0 / dispersion;
            assert!((ior_at(ior, dispersion, 587.56) - ior).abs() < 1e-3);
            let spread = ior_at(ior, dispersion, 486.13) - ior_at(ior, dispersion, 656.27);
            assert!(
                ((spread - (ior - 1.0) / v) / spread).abs() < 2e-3,
                "{ior} {dispersion}: {spread}"
            );
        }
        // Blue bends more than red; no dispersion is the plain index.
        assert!(dispersion_ior(1.5, 1.0, 3) > dispersion_ior(1.5, 1.0, 2));
        assert!(dispersion_ior(1.5, 1.0, 2) > dispersion_ior(1.5, 1.0, 1));
        assert_eq!(dispersion_ior(1.5, 0.0, 3), 1.5);
    }

    #[test]
    fn the_channel_weights_average_to_one() {
        let mut sum = Vec3::ZERO;
        for k in 0..3 {
            sum += dispersion_channel_weight(dispersion_pick_channel((k as f32 + 0.5) / 3.0));
        }
        assert_eq!(sum / 3.0, Vec3::ONE);
        assert_eq!(dispersion_pick_channel(0.9999999), 3);
    }
}
