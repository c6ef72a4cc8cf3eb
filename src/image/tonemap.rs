//! From linear radiance to display values: exposure (EV100 from shutter,
//! ISO and f-number), tone maps and the sRGB transfer function.

/// How linear radiance becomes display values before sRGB encoding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneMap {
    /// Khronos PBR Neutral: leaves colours below ~0.76 nearly untouched (so
    /// base colours stay recognisable) and compresses highlights towards white.
    #[default]
    PbrNeutral,
    /// Krzysztof Narkowicz's 2015 single-curve fit of the ACES filmic RRT+ODT,
    /// applied per channel as published, without his 0.6 pre-exposure (use
    /// `exposure_ev` for that).
    AcesFilmic,
    /// Clamp to [0, 1]: what you see is the radiance, cut at 1.
    Clamp,
}

impl ToneMap {
    /// Names accepted by `from_name`, for command-line help.
    pub const NAMES: &'static [&'static str] = &["neutral", "aces", "clamp"];

    /// Parses a command-line name, case-insensitively.
    pub fn from_name(name: &str) -> Option<Self> {
        match name.to_ascii_lowercase().as_str() {
            "neutral" | "pbr-neutral" | "pbrneutral" => Some(ToneMap::PbrNeutral),
            "aces" | "aces-filmic" => Some(ToneMap::AcesFilmic),
            "clamp" => Some(ToneMap::Clamp),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ToneMap::PbrNeutral => "neutral",
            ToneMap::AcesFilmic => "aces",
            ToneMap::Clamp => "clamp",
        }
    }

    /// Maps linear (exposed) radiance to display-linear values in [0, 1].
    pub fn apply(self, rgb: [f32; 3]) -> [f32; 3] {
        let out = match self {
            ToneMap::PbrNeutral => pbr_neutral(rgb),
            ToneMap::AcesFilmic => rgb.map(aces_narkowicz),
            ToneMap::Clamp => rgb,
        };
        out.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) })
    }
}

/// Khronos PBR Neutral tone mapper, as in the Khronos reference GLSL
/// (KhronosGroup/ToneMapping, PBR_Neutral).
pub fn pbr_neutral(rgb: [f32; 3]) -> [f32; 3] {
    const START_COMPRESSION: f32 = 0.8 - 0.04;
    const DESATURATION: f32 = 0.15;
    let [mut r, mut g, mut b] = rgb;
    let x = r.min(g).min(b);
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    r -= offset;
    g -= offset;
    b -= offset;
    let peak = r.max(g).max(b);
    if peak < START_COMPRESSION {
        return [r, g, b];
    }
    let d = 1.0 - START_COMPRESSION;
    let new_peak = 1.0 - d * d / (peak + d - START_COMPRESSION);
    let scale = new_peak / peak;
    r *= scale;
    g *= scale;
    b *= scale;
    let t = 1.0 - 1.0 / (DESATURATION * (peak - new_peak) + 1.0);
    let mix = |c: f32| c * (1.0 - t) + new_peak * t;
    [mix(r), mix(g), mix(b)]
}

/// Narkowicz's ACES filmic fit: x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14).
/// Inputs are capped at 1e4, where the curve is long past 1, so that huge
/// values do not overflow to inf / inf.
pub fn aces_narkowicz(x: f32) -> f32 {
    let x = x.min(1e4);
    (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
}

/// The exact piecewise sRGB encoding (IEC 61966-2-1) of a value in [0, 1].
pub fn srgb_oetf(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// How `write_image` turns radiance into an 8-bit PNG.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PngSettings {
    /// Exposure in stops: radiance is multiplied by 2^exposure_ev.
    pub exposure_ev: f32,
    pub tonemap: ToneMap,
}

impl Default for PngSettings {
    fn default() -> Self {
        PngSettings {
            exposure_ev: 0.0,
            tonemap: ToneMap::PbrNeutral,
        }
    }
}

/// The exposure value at ISO 100 of a camera setting: EV100 =
/// log2(N^2 / t) - log2(S / 100) for f-number N, shutter time t in seconds
/// and ISO sensitivity S (the photographic convention; "sunny 16", f/16 at
/// 1/100 s and ISO 100, is EV100 14.6).
pub fn ev100(fstop: f32, shutter: f32, iso: f32) -> f32 {
    (fstop * fstop / shutter).log2() - (iso / 100.0).log2()
}

/// PNG exposure in stops for a camera setting: radiance (taken as
/// luminance in cd/m^2) is scaled by 1 / (1.2 * 2^EV100), the
/// saturation-based sensitivity convention (the factor 1.2 = 78 / (100 *
/// 0.65): ISO 12232's saturation constant 78 with a lens transmittance and
/// vignetting factor of 0.65; Lagarde and de Rousiers, "Moving Frostbite to
/// PBR", 2014, section 5.1). Radiance of 1.2 * 2^EV100 maps to 1.
pub fn exposure_from_camera(fstop: f32, shutter: f32, iso: f32) -> f32 {
    -ev100(fstop, shutter, iso) - 1.2f32.log2()
}

/// One pixel through exposure, tone map and sRGB encoding. NaN becomes 0 and
/// infinity becomes very bright, so nothing here can panic or poison a
/// neighbour; the renderer is what should prevent non-finite pixels.
pub fn encode_srgb8(rgb: [f32; 3], settings: &PngSettings) -> [u8; 3] {
    let scale = settings.exposure_ev.exp2();
    let exposed = rgb.map(|v| {
        let v = v * scale;
        if v.is_nan() { 0.0 } else { v.clamp(0.0, 1e20) }
    });
    settings
        .tonemap
        .apply(exposed)
        .map(|v| (srgb_oetf(v) * 255.0).round().clamp(0.0, 255.0) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_exposure_from_camera_follows_ev100() {
        // Sunny 16: f/16, 1/100 s, ISO 100 is EV100 log2(25600) = 14.64.
        assert!((ev100(16.0, 0.01, 100.0) - 14.644).abs() < 1e-3);
        // One stop more light for each of: half the f-number squared, twice
        // the time, twice the ISO.
        let base = exposure_from_camera(8.0, 0.01, 100.0);
        assert!((exposure_from_camera(8.0, 0.02, 100.0) - base - 1.0).abs() < 1e-5);
        assert!((exposure_from_camera(8.0, 0.01, 200.0) - base - 1.0).abs() < 1e-5);
        assert!((exposure_from_camera(8.0 / 2f32.sqrt(), 0.01, 100.0) - base - 1.0).abs() < 1e-5);
        // A luminance of 1.2 * 2^EV100 is exposed to exactly 1.
        let ev = ev100(2.8, 1.0 / 60.0, 400.0);
        let l = 1.2 * ev.exp2();
        assert!((l * exposure_from_camera(2.8, 1.0 / 60.0, 400.0).exp2() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn output_tonemap_values() {
        // Below the compression start PBR Neutral only subtracts the 0.04 offset.
        let out = pbr_neutral([0.5, 0.3, 0.2]);
        for (o, e) in out.iter().zip([0.46, 0.26, 0.16]) {
            assert!((o - e).abs() < 1e-6);
        }
        // Near black the offset is x - 6.25 x^2 (continuous at 0.08), so a grey
        // x maps to 6.25 x^2.
        let out = pbr_neutral([0.04, 0.04, 0.04]);
        assert!((out[0] - 6.25 * 0.0016).abs() < 1e-7);
        assert!((pbr_neutral([0.08; 3])[0] - 0.04).abs() < 1e-6);
        // Highlights compress monotonically towards 1.
        let mut last = 0.0;
        for i in 0..200 {
            let v = ToneMap::PbrNeutral.apply([0.01 * 1.1f32.powi(i); 3])[0];
            assert!(v >= last && v <= 1.0);
            last = v;
        }
        assert!(last > 0.999);
        // Saturated highlights desaturate towards white.
        let hot = pbr_neutral([10.0, 1.0, 0.5]);
        assert!(hot[1] > 0.5 && hot[0] <= 1.0);
        // ACES fit: f(0) = 0, f(1) = 2.54 / 3.16.
        assert_eq!(aces_narkowicz(0.0), 0.0);
        assert!((aces_narkowicz(1.0) - 2.54 / 3.16).abs() < 1e-6);
        assert_eq!(ToneMap::from_name("ACES"), Some(ToneMap::AcesFilmic));
        assert_eq!(ToneMap::from_name("neutral"), Some(ToneMap::PbrNeutral));
        assert_eq!(ToneMap::from_name("clamp"), Some(ToneMap::Clamp));
        assert_eq!(ToneMap::from_name("reinhard"), None);
        assert_eq!(ToneMap::default(), ToneMap::PbrNeutral);
        for name in ToneMap::NAMES {
            assert_eq!(ToneMap::from_name(name).unwrap().name(), *name);
        }
    }
}
