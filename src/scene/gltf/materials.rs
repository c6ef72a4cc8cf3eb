//! glTF materials as [`Material`]s: base colour, emission, alpha mode and
//! the metallic-roughness model with `KHR_materials_specular`,
//! `_transmission`, `_ior` and `_volume`, unless the vkpt material extras
//! pick another model (`material_extras.rs`). What is not rendered is
//! gathered into one note per kind.

use super::data::{array, name_suffix};
use super::extensions::UnrenderedMaterialExtensions;
use super::json::{f32_array, non_negative, rgb};
use super::material_extras;
use super::notes::{Grouped, list};
use super::textures::{RENDERED_TEXTURE_SLOTS, TextureLoader, texture_slots};
use crate::scene::{AlphaMode, Material, MaterialKind};
use anyhow::{Context, Result, anyhow, bail, ensure};
use glam::Vec3;
use gltf::json::Value;

/// The name notes use for material `i`: its own, else `material #i`.
pub(super) fn material_name(m: &Value, i: usize) -> String {
    m.get("name")
        .and_then(Value::as_str)
        .map(str::to_string)
        .unwrap_or_else(|| format!("material #{i}"))
}

pub(super) fn positive_ior(v: Option<&Value>, what: &str) -> Result<f32> {
    let ior = non_negative(v, what)?.unwrap_or(1.5);
    ensure!(ior > 0.0, "{what} must be above 0, found {ior}");
    Ok(ior)
}

/// What was not rendered as the file asks, over all materials: each kind
/// becomes one note listing the materials.
#[derive(Default)]
struct MaterialNotes {
    /// Texture slot -> materials using it.
    unrendered_slots: Grouped,
    extensions: UnrenderedMaterialExtensions,
    /// Materials whose emission needs an emissive texture that cannot be used.
    emissive_textured: Vec<String>,
    blended: Vec<String>,
}

impl MaterialNotes {
    fn finish(self, notes: &mut Vec<String>) {
        if !self.unrendered_slots.0.is_empty() {
            let parts: Vec<String> = self
                .unrendered_slots
                .0
                .iter()
                .map(|(slot, mats)| format!("{slot} on {}", list(mats)))
                .collect();
            notes.push(format!(
                "these textures are not rendered yet (the materials' factors are used): {}",
                parts.join("; ")
            ));
        }
        self.extensions.notes(notes);
        if !self.emissive_textured.is_empty() {
            notes.push(format!(
                "emission set to 0 on {} {}: its emission comes from an emissiveTexture that cannot be used",
                materials(self.emissive_textured.len()),
                list(&self.emissive_textured)
            ));
        }
        if !self.blended.is_empty() {
            notes.push(format!(
                "alphaMode BLEND on {} {} is rendered as coverage: a ray meets the surface with probability alpha",
                materials(self.blended.len()),
                list(&self.blended)
            ));
        }
    }
}

fn materials(n: usize) -> &'static str {
    if n == 1 { "material" } else { "materials" }
}

/// Every material of the file, in file order; their textures are decoded
/// through `textures`.
pub(super) fn load_materials(
    json: &Value,
    textures: &mut TextureLoader,
    notes: &mut Vec<String>,
) -> Result<Vec<Material>> {
    let mut seen = MaterialNotes::default();
    let mut out = Vec::new();
    for (i, m) in array(json, "materials").iter().enumerate() {
        out.push(load_material(m, i, textures, &mut seen, notes)?);
    }
    seen.finish(notes);
    Ok(out)
}

fn load_material(
    m: &Value,
    i: usize,
    textures: &mut TextureLoader,
    seen: &mut MaterialNotes,
    notes: &mut Vec<String>,
) -> Result<Material> {
    let name = material_name(m, i);
    let label = format!("material #{i}{}", name_suffix(m));
    let spec_gloss = m
        .get("extensions")
        .and_then(|e| e.get("KHR_materials_pbrSpecularGlossiness"));
    let (base_color, alpha) = base_color(m, spec_gloss, &label)?;
    let emissive = emissive(m, &label)?;
    let textures = textures.material_textures(m, &name, notes);
    let mut emission = emissive;
    if m.get("emissiveTexture").is_some() && textures.emissive.is_none() && emission != Vec3::ZERO {
        // The factor only scales the texture; without the texture the
        // whole surface would glow at full strength, which is worse than
        // not glowing.
        emission = Vec3::ZERO;
        seen.emissive_textured.push(name.clone());
    }
    ensure!(
        emission.min_element() >= 0.0 && emission.is_finite(),
        "{label}: emission {emission} is negative or not finite"
    );
    let double_sided = m
        .get("doubleSided")
        .and_then(Value::as_bool)
        .unwrap_or(false);
    let alpha_mode = alpha_mode(m, &label)?;
    if alpha_mode == AlphaMode::Blend {
        seen.blended.push(name.clone());
    }
    let normal_scale = match m.get("normalTexture").and_then(|t| t.get("scale")) {
        None => 1.0,
        Some(v) => v
            .as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite())
            .ok_or_else(|| anyhow!("{label}: normalTexture.scale is not a number: {v}"))?,
    };
    let mut material = Material {
        base_color,
        emission,
        double_sided,
        alpha,
        alpha_mode,
        normal_scale,
        textures,
        ..Material::lambert(&name, base_color)
    };
    let rendered =
        if material_extras::apply(m, &label, &mut material, notes)? || spec_gloss.is_some() {
            Vec::new()
        } else {
            metallic_roughness(m, &label, &mut material)?
        };

    let mut slots = Vec::new();
    texture_slots(m, &mut slots);
    for (slot, _) in &slots {
        if !RENDERED_TEXTURE_SLOTS.contains(&slot.as_str()) {
            seen.unrendered_slots.add(slot.clone(), name.clone());
        }
    }
    seen.extensions.add(m, &name, &rendered);
    Ok(material)
}

/// baseColorFactor (else `KHR_materials_pbrSpecularGlossiness`'
/// diffuseFactor, which is not rendered otherwise) as colour and alpha.
fn base_color(m: &Value, spec_gloss: Option<&Value>, label: &str) -> Result<(Vec3, f32)> {
    let pbr = m.get("pbrMetallicRoughness");
    let base = f32_array::<4>(
        pbr.and_then(|p| p.get("baseColorFactor")),
        "baseColorFactor",
    )
    .with_context(|| label.to_string())?;
    let diffuse = f32_array::<4>(
        spec_gloss.and_then(|s| s.get("diffuseFactor")),
        "diffuseFactor",
    )
    .with_context(|| label.to_string())?;
    let base_color = match (base, diffuse) {
        (Some(b), _) => Vec3::new(b[0], b[1], b[2]),
        (None, Some(d)) => Vec3::new(d[0], d[1], d[2]),
        (None, None) => Vec3::ONE,
    };
    ensure!(
        base_color.min_element() >= 0.0,
        "{label}: baseColorFactor has a negative component"
    );
    Ok((base_color, base.or(diffuse).map_or(1.0, |c| c[3])))
}

/// emissiveFactor times `KHR_materials_emissive_strength`.
fn emissive(m: &Value, label: &str) -> Result<Vec3> {
    let emissive = f32_array::<3>(m.get("emissiveFactor"), "emissiveFactor")
        .with_context(|| label.to_string())?
        .map(Vec3::from)
        .unwrap_or(Vec3::ZERO);
    let strength = match m
        .get("extensions")
        .and_then(|e| e.get("KHR_materials_emissive_strength"))
        .and_then(|e| e.get("emissiveStrength"))
    {
        None => 1.0,
        Some(v) => v
            .as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite() && *f >= 0.0)
            .ok_or_else(|| {
                anyhow!("{label}: emissiveStrength is not a non-negative number: {v}")
            })?,
    };
    Ok(emissive * strength)
}

fn alpha_mode(m: &Value, label: &str) -> Result<AlphaMode> {
    Ok(match m.get("alphaMode") {
        None => AlphaMode::Opaque,
        Some(mode) => match mode.as_str() {
            Some("OPAQUE") => AlphaMode::Opaque,
            Some("MASK") => AlphaMode::Mask {
                cutoff: non_negative(m.get("alphaCutoff"), &format!("{label}: alphaCutoff"))?
                    .unwrap_or(0.5),
            },
            Some("BLEND") => AlphaMode::Blend,
            _ => bail!("{label}: alphaMode must be OPAQUE, MASK or BLEND, found {mode}"),
        },
    })
}

fn unit_interval(v: Option<&Value>, what: &str, default: f32) -> Result<f32> {
    let x = non_negative(v, what)?.unwrap_or(default);
    ensure!(x <= 1.0, "{what} must be between 0 and 1, found {x}");
    Ok(x)
}

/// glTF metallic-roughness with `KHR_materials_specular`, `_transmission`,
/// `_ior` and `_volume` (MaterialKind::Gltf); returns the material
/// extensions it rendered. Two parameter cases get their exact, cheaper
/// kinds: metallic 1 with roughness 0 (and no metallic-roughness texture)
/// is the tinted mirror, and a non-metal without transmission whose
/// specularFactor is 0 is Lambertian.
fn metallic_roughness(
    m: &Value,
    label: &str,
    material: &mut Material,
) -> Result<Vec<&'static str>> {
    let ext = |e: &str| m.get("extensions").and_then(|x| x.get(e));
    let pbr = m.get("pbrMetallicRoughness");
    let get = |key: &str| pbr.and_then(|p| p.get(key));
    let what = |key: &str| format!("{label}: {key}");
    material.metallic = unit_interval(get("metallicFactor"), &what("metallicFactor"), 1.0)?;
    material.roughness = unit_interval(get("roughnessFactor"), &what("roughnessFactor"), 1.0)?;

    let transmission = ext("KHR_materials_transmission");
    material.transmission = unit_interval(
        transmission.and_then(|t| t.get("transmissionFactor")),
        &what("KHR_materials_transmission transmissionFactor"),
        0.0,
    )?;
    material.ior = positive_ior(
        ext("KHR_materials_ior").and_then(|i| i.get("ior")),
        &what("KHR_materials_ior ior"),
    )?;
    let specular = ext("KHR_materials_specular");
    material.specular_factor = unit_interval(
        specular.and_then(|s| s.get("specularFactor")),
        &what("KHR_materials_specular specularFactor"),
        1.0,
    )?;
    material.specular_color = rgb(
        specular.and_then(|s| s.get("specularColorFactor")),
        &what("KHR_materials_specular specularColorFactor"),
    )?
    .unwrap_or(Vec3::ONE);
    volume(ext("KHR_materials_volume"), label, material)?;

    let mr_texture = pbr.is_some_and(|p| p.get("metallicRoughnessTexture").is_some());
    material.kind = if material.metallic == 1.0
        && material.roughness == 0.0
        && material.transmission == 0.0
        && !mr_texture
    {
        MaterialKind::Mirror
    } else if material.metallic == 0.0
        && material.transmission == 0.0
        && material.specular_factor == 0.0
    {
        MaterialKind::Lambert
    } else {
        MaterialKind::Gltf
    };
    Ok(vec![
        "KHR_materials_transmission",
        "KHR_materials_ior",
        "KHR_materials_volume",
        "KHR_materials_specular",
    ])
}

/// `KHR_materials_volume`: thickness and the absorption coefficient.
fn volume(volume: Option<&Value>, label: &str, material: &mut Material) -> Result<()> {
    let what = |key: &str| format!("{label}: {key}");
    material.thickness = non_negative(
        volume.and_then(|v| v.get("thicknessFactor")),
        &what("KHR_materials_volume thicknessFactor"),
    )?
    .unwrap_or(0.0);
    let distance = non_negative(
        volume.and_then(|v| v.get("attenuationDistance")),
        &what("KHR_materials_volume attenuationDistance"),
    )?;
    let color = rgb(
        volume.and_then(|v| v.get("attenuationColor")),
        &what("KHR_materials_volume attenuationColor"),
    )?
    .unwrap_or(Vec3::ONE);
    ensure!(
        color.max_element() <= 1.0,
        "{label}: KHR_materials_volume attenuationColor must be at most 1, found {color}"
    );
    // Beer–Lambert: attenuationColor is what remains after
    // attenuationDistance, so the coefficient is -ln(color) / distance.
    material.attenuation = match distance {
        Some(d) if d > 0.0 => {
            let c = color.max(Vec3::splat(1e-6));
            Vec3::new(-c.x.ln(), -c.y.ln(), -c.z.ln()) / d
        }
        _ => Vec3::ZERO,
    };
    Ok(())
}
