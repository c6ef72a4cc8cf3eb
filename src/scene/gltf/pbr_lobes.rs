//! The glTF PBR extensions that add or change lobes of the
//! metallic-roughness model: `KHR_materials_clearcoat`, `_sheen`,
//! `_iridescence`, `_anisotropy`, `_diffuse_transmission` and `_dispersion`,
//! read from the material's JSON (the `gltf` crate models none of them)
//! with each specification's defaults. Their textures are read by
//! `textures.rs`.

use super::json::{non_negative, rgb};
use crate::scene::PbrLobes;
use anyhow::{Result, anyhow, ensure};
use glam::Vec3;
use gltf::json::Value;

/// The lobe extensions the kernels render. An extension read here but not
/// listed is still reported as not rendered.
pub(super) const RENDERED_LOBE_EXTENSIONS: &[&str] = &[
    "KHR_materials_clearcoat",
    "KHR_materials_anisotropy",
    "KHR_materials_sheen",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_iridescence",
    "KHR_materials_dispersion",
];

/// Every extension this file reads.
const LOBE_EXTENSIONS: [&str; 6] = [
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_iridescence",
    "KHR_materials_anisotropy",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_dispersion",
];

/// The lobes of material JSON `raw` (`label` names it in errors), and the
/// rendered extensions among those it uses.
pub(super) fn read_lobes(raw: &Value, label: &str) -> Result<(PbrLobes, Vec<&'static str>)> {
    let ext = |name: &str| raw.get("extensions").and_then(|e| e.get(name));
    let mut l = PbrLobes::default();
    if let Some(c) = ext("KHR_materials_clearcoat") {
        let f = Field::new(c, label, "KHR_materials_clearcoat");
        l.clearcoat = f.unit("clearcoatFactor", 0.0)?;
        l.clearcoat_roughness = f.unit("clearcoatRoughnessFactor", 0.0)?;
        l.clearcoat_normal_scale =
            match c.get("clearcoatNormalTexture").and_then(|t| t.get("scale")) {
                None => 1.0,
                Some(s) => s
                    .as_f64()
                    .map(|s| s as f32)
                    .filter(|s| s.is_finite())
                    .ok_or_else(|| {
                        anyhow!("{label}: clearcoatNormalTexture.scale is not a number: {s}")
                    })?,
            };
    }
    if let Some(s) = ext("KHR_materials_sheen") {
        let f = Field::new(s, label, "KHR_materials_sheen");
        l.sheen_color = f.color("sheenColorFactor", Vec3::ZERO)?;
        l.sheen_roughness = f.unit("sheenRoughnessFactor", 0.0)?;
    }
    if let Some(i) = ext("KHR_materials_iridescence") {
        let f = Field::new(i, label, "KHR_materials_iridescence");
        l.iridescence = f.unit("iridescenceFactor", 0.0)?;
        l.iridescence_ior = f.positive("iridescenceIor", 1.3)?;
        l.iridescence_thickness_min = f.non_negative("iridescenceThicknessMinimum", 100.0)?;
        l.iridescence_thickness_max = f.non_negative("iridescenceThicknessMaximum", 400.0)?;
    }
    if let Some(a) = ext("KHR_materials_anisotropy") {
        let f = Field::new(a, label, "KHR_materials_anisotropy");
        l.anisotropy_strength = f.unit("anisotropyStrength", 0.0)?;
        l.anisotropy_rotation = f.number("anisotropyRotation", 0.0)?;
    }
    if let Some(d) = ext("KHR_materials_diffuse_transmission") {
        let f = Field::new(d, label, "KHR_materials_diffuse_transmission");
        l.diffuse_transmission = f.unit("diffuseTransmissionFactor", 0.0)?;
        l.diffuse_transmission_color = f.color("diffuseTransmissionColorFactor", Vec3::ONE)?;
    }
    if let Some(d) = ext("KHR_materials_dispersion") {
        l.dispersion =
            Field::new(d, label, "KHR_materials_dispersion").non_negative("dispersion", 0.0)?;
    }
    let rendered = LOBE_EXTENSIONS
        .into_iter()
        .filter(|e| ext(e).is_some() && RENDERED_LOBE_EXTENSIONS.contains(e))
        .collect();
    Ok((l, rendered))
}

/// Reads the numbers of one extension object, naming them in errors.
struct Field<'a> {
    obj: &'a Value,
    label: &'a str,
    ext: &'a str,
}

impl<'a> Field<'a> {
    fn new(obj: &'a Value, label: &'a str, ext: &'a str) -> Self {
        Field { obj, label, ext }
    }

    fn what(&self, key: &str) -> String {
        format!("{}: {} {key}", self.label, self.ext)
    }

    fn number(&self, key: &str, default: f32) -> Result<f32> {
        match self.obj.get(key) {
            None => Ok(default),
            Some(v) => v
                .as_f64()
                .map(|x| x as f32)
                .filter(|x| x.is_finite())
                .ok_or_else(|| anyhow!("{} is not a finite number: {v}", self.what(key))),
        }
    }

    fn non_negative(&self, key: &str, default: f32) -> Result<f32> {
        Ok(non_negative(self.obj.get(key), &self.what(key))?.unwrap_or(default))
    }

    fn positive(&self, key: &str, default: f32) -> Result<f32> {
        let x = self.non_negative(key, default)?;
        ensure!(x > 0.0, "{} must be above 0, found {x}", self.what(key));
        Ok(x)
    }

    fn unit(&self, key: &str, default: f32) -> Result<f32> {
        let x = self.non_negative(key, default)?;
        ensure!(
            x <= 1.0,
            "{} must be between 0 and 1, found {x}",
            self.what(key)
        );
        Ok(x)
    }

    fn color(&self, key: &str, default: Vec3) -> Result<Vec3> {
        Ok(rgb(self.obj.get(key), &self.what(key))?.unwrap_or(default))
    }
}
