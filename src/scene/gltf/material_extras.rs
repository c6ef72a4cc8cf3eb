//! The vkpt material extras (`extras.vkpt`: `phong`, `mirror` or
//! `dielectric`, documented in docs/gltf-support.md, "vkpt extras"): a
//! scattering model chosen in place of glTF's own. The `gltf` crate leaves `extras` as raw JSON, so
//! they are read here from the file's JSON.

use super::json::{non_negative, rgb};
use super::materials::check_ior;
use crate::scene::{Material, MaterialKind};
use anyhow::{Result, anyhow, ensure};
use glam::Vec3;
use gltf::json::Value;

/// The models a material's `extras.vkpt` may name, with their keys.
const MODELS: [(&str, &[&str]); 3] = [
    ("phong", &["kd", "ks", "n"]),
    ("mirror", &["tint"]),
    ("dielectric", &["ior", "tint"]),
];

/// Applies the model the material's vkpt extras name, if any (returns
/// whether one was). `m` is the material's JSON; keys that are not
/// understood become notes, malformed values errors naming the material.
pub(super) fn apply(
    m: &Value,
    label: &str,
    material: &mut Material,
    notes: &mut Vec<String>,
) -> Result<bool> {
    let name = material.name.clone();
    let Some(vkpt) = m.get("extras").and_then(|e| e.get("vkpt")) else {
        return Ok(false);
    };
    let obj = vkpt
        .as_object()
        .ok_or_else(|| anyhow!("{label}: extras \"vkpt\" must be an object, found {vkpt}"))?;
    let models: Vec<&String> = obj
        .keys()
        .filter(|k| MODELS.iter().any(|(model, _)| model == k))
        .collect();
    ensure!(
        models.len() <= 1,
        "{label}: extras vkpt names more than one material model ({models:?})"
    );
    for key in obj.keys() {
        if !models.contains(&key) {
            notes.push(format!(
                "material '{name}': extras vkpt.{key} is not understood: ignored"
            ));
        }
    }
    let Some(model) = models.first() else {
        return Ok(false);
    };
    let p = &obj[model.as_str()];
    ensure!(
        p.is_object(),
        "{label}: extras vkpt.{model} must be an object, found {p}"
    );
    let known = MODELS
        .iter()
        .find(|(m, _)| m == model)
        .map_or(&[][..], |(_, keys)| *keys);
    for key in p.as_object().into_iter().flat_map(|o| o.keys()) {
        if !known.contains(&key.as_str()) {
            notes.push(format!(
                "material '{name}': extras vkpt.{model}.{key} is not understood: ignored"
            ));
        }
    }
    let what = |k: &str| format!("{label}: extras vkpt.{model}.{k}");
    match model.as_str() {
        "phong" => phong(p, &what, material, notes)?,
        "mirror" => {
            material.kind = MaterialKind::Mirror;
            material.base_color = rgb(p.get("tint"), &what("tint"))?.unwrap_or(material.base_color);
        }
        _ => {
            // Smooth clear glass: the glTF model's closed volume.
            material.kind = MaterialKind::Gltf;
            let ior = non_negative(p.get("ior"), &what("ior"))?.unwrap_or(1.5);
            material.ior = check_ior(ior, &what("ior"))?;
            material.base_color = rgb(p.get("tint"), &what("tint"))?.unwrap_or(material.base_color);
            material.metallic = 0.0;
            material.roughness = 0.0;
            material.transmission = 1.0;
            material.thickness = 1.0;
            material.specular_factor = 1.0;
            material.specular_color = Vec3::ONE;
        }
    }
    Ok(true)
}

/// `phong`: kd (default base colour), ks and n; kd + ks above 1 in a
/// channel is scaled down to 1 with a warning.
fn phong(
    p: &Value,
    what: &dyn Fn(&str) -> String,
    material: &mut Material,
    notes: &mut Vec<String>,
) -> Result<()> {
    let name = &material.name;
    let kd = rgb(p.get("kd"), &what("kd"))?.unwrap_or(material.base_color);
    let ks = rgb(p.get("ks"), &what("ks"))?.ok_or_else(|| anyhow!("{} is missing", what("ks")))?;
    let n =
        non_negative(p.get("n"), &what("n"))?.ok_or_else(|| anyhow!("{} is missing", what("n")))?;
    let sum = kd + ks;
    let (mut kd, mut ks) = (kd, ks);
    if sum.max_element() > 1.0 {
        let s = Vec3::select(sum.cmpgt(Vec3::ONE), Vec3::ONE / sum, Vec3::ONE);
        kd *= s;
        ks *= s;
        notes.push(format!(
            "warning: material '{name}': Phong kd + ks = {sum} is above 1 (it would create energy): \
             scaled down to kd {kd}, ks {ks}"
        ));
    }
    material.kind = MaterialKind::Phong;
    material.base_color = kd;
    material.specular = ks;
    material.shininess = n;
    Ok(())
}
