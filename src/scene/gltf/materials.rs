//! glTF materials as [`Material`]s, read through the `gltf` crate's typed
//! material (base colour, emission, alpha mode, and the metallic-roughness
//! model with `KHR_materials_specular`, `_transmission`, `_ior` and
//! `_volume`) unless the vkpt material extras pick another model
//! (`material_extras.rs`). What is not rendered is gathered into one note
//! per kind.

use super::document::Gltf;
use super::extensions::UnrenderedMaterialExtensions;
use super::json::{color, f32_array, finite, non_negative_f32};
use super::material_extras;
use super::notes::{Grouped, list, name_suffix};
use super::pbr_lobes::read_lobes;
use super::spec_gloss::{self, SpecGloss};
use super::textures::{RENDERED_TEXTURE_SLOTS, TextureLoader, texture_slots};
use crate::scene::{AlphaMode, Material, MaterialKind};
use anyhow::{Context, Result, bail, ensure};
use glam::Vec3;
use gltf::json::Value;

/// The name notes use for material `i`: its own, else `material #i`.
pub(super) fn material_name(name: Option<&str>, i: usize) -> String {
    name.map(str::to_string)
        .unwrap_or_else(|| format!("material #{i}"))
}

/// An index of refraction: finite and above 0 (below 1 is allowed: an air
/// bubble in water).
pub(super) fn check_ior(ior: f32, what: &str) -> Result<f32> {
    let ior = non_negative_f32(ior, what)?;
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
    unlit: Vec<String>,
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
        if !self.unlit.is_empty() {
            notes.push(format!(
                "KHR_materials_unlit on {} {}: the base colour is emitted as is (seen unshaded, and lighting the scene like any emitter of that radiance)",
                materials(self.unlit.len()),
                list(&self.unlit)
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
/// A specular-glossiness material (by index) waiting for its images.
pub(super) type ToConvert = (usize, SpecGloss);

/// Specular-glossiness materials come back beside them, to be converted once
/// their images are decoded (`spec_gloss::apply`).
pub(super) fn load_materials(
    gltf: &Gltf,
    textures: &mut TextureLoader,
    notes: &mut Vec<String>,
) -> Result<(Vec<Material>, Vec<ToConvert>)> {
    let mut seen = MaterialNotes::default();
    let mut out = Vec::new();
    let mut spec_gloss = Vec::new();
    for (i, m) in gltf.doc.materials().enumerate() {
        let (material, sg) = load_material(gltf, &m, i, textures, &mut seen, notes)?;
        out.push(material);
        spec_gloss.extend(sg.map(|sg| (i, sg)));
    }
    seen.finish(notes);
    Ok((out, spec_gloss))
}

fn load_material(
    gltf: &Gltf,
    m: &gltf::Material,
    i: usize,
    loader: &mut TextureLoader,
    seen: &mut MaterialNotes,
    notes: &mut Vec<String>,
) -> Result<(Material, Option<SpecGloss>)> {
    let raw = gltf.raw("materials", i);
    let name = material_name(m.name(), i);
    let label = format!("material #{i}{}", name_suffix(m.name()));
    // Converted to metallic-roughness (spec_gloss.rs) once images are decoded.
    let spec_gloss = raw
        .get("extensions")
        .and_then(|e| e.get("KHR_materials_pbrSpecularGlossiness"));
    let (base_color, alpha) = base_color(m, raw, spec_gloss, &label)?;
    let emissive = emissive(m, &label)?;
    let textures = loader.material_textures(m, raw, &name, notes);
    let mut emission = emissive;
    if m.emissive_texture().is_some() && textures.emissive.is_none() && emission != Vec3::ZERO {
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
    let alpha_mode = alpha_mode(m, &label)?;
    if alpha_mode == AlphaMode::Blend {
        seen.blended.push(name.clone());
    }
    let normal_scale = match m.normal_texture().map(|t| t.scale()) {
        None => 1.0,
        Some(s) if s.is_finite() => s,
        Some(s) => bail!("{label}: normalTexture.scale is not a number: {s}"),
    };
    let mut material = Material {
        base_color,
        emission,
        double_sided: m.double_sided(),
        alpha,
        alpha_mode,
        normal_scale,
        textures,
        ..Material::lambert(&name, base_color)
    };
    let mut converted = None;
    let mut rendered = if material_extras::apply(raw, &label, &mut material, notes)? {
        Vec::new()
    } else if let Some(ext) = spec_gloss {
        let mut sg = spec_gloss::read(ext, &label)?;
        sg.diffuse_texture =
            loader.json_texture(ext.get("diffuseTexture"), &name, "diffuseTexture", notes);
        sg.specular_glossiness_texture = loader.json_texture(
            ext.get("specularGlossinessTexture"),
            &name,
            "specularGlossinessTexture",
            notes,
        );
        converted = Some(sg);
        vec!["KHR_materials_pbrSpecularGlossiness"]
    } else {
        metallic_roughness(gltf, m, i, &label, &mut material)?
    };
    if raw
        .get("extensions")
        .and_then(|e| e.get("KHR_materials_unlit"))
        .is_some()
    {
        make_unlit(&mut material);
        seen.unlit.push(name.clone());
        rendered.push("KHR_materials_unlit");
    }

    let mut slots = Vec::new();
    texture_slots(raw, &mut slots);
    for (slot, _) in &slots {
        if !RENDERED_TEXTURE_SLOTS.contains(&slot.as_str()) {
            seen.unrendered_slots.add(slot.clone(), name.clone());
        }
    }
    seen.extensions.add(raw, &name, &rendered);
    Ok((material, converted))
}

/// `KHR_materials_unlit`: the surface shows its base colour (factor times
/// texture) whatever the light, which in a path tracer is emission of that
/// radiance with nothing scattered. The base colour texture stays in its
/// slot for alpha; its colour now scales the emission.
fn make_unlit(material: &mut Material) {
    material.unlit = true;
    material.kind = MaterialKind::Lambert;
    material.emission = material.base_color;
    material.textures.emissive = material.textures.base_color;
    material.base_color = Vec3::ZERO;
}

/// baseColorFactor (else `KHR_materials_pbrSpecularGlossiness`'
/// diffuseFactor) as colour and alpha. Whether baseColorFactor was given
/// at all is read from the JSON: the crate fills in its default.
fn base_color(
    m: &gltf::Material,
    raw: &Value,
    spec_gloss: Option<&Value>,
    label: &str,
) -> Result<(Vec3, f32)> {
    let given = raw
        .get("pbrMetallicRoughness")
        .and_then(|p| p.get("baseColorFactor"))
        .is_some();
    let base = match given {
        true => Some(
            finite(
                m.pbr_metallic_roughness().base_color_factor(),
                "baseColorFactor",
            )
            .with_context(|| label.to_string())?,
        ),
        false => None,
    };
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
fn emissive(m: &gltf::Material, label: &str) -> Result<Vec3> {
    let emissive = Vec3::from(
        finite(m.emissive_factor(), "emissiveFactor").with_context(|| label.to_string())?,
    );
    let strength = match m.emissive_strength() {
        None => 1.0,
        Some(s) if s.is_finite() && s >= 0.0 => s,
        Some(s) => bail!("{label}: emissiveStrength is not a non-negative number: {s}"),
    };
    Ok(emissive * strength)
}

fn alpha_mode(m: &gltf::Material, label: &str) -> Result<AlphaMode> {
    use gltf::material::AlphaMode as Gltf;
    Ok(match m.alpha_mode() {
        Gltf::Opaque => AlphaMode::Opaque,
        Gltf::Mask => AlphaMode::Mask {
            cutoff: match m.alpha_cutoff() {
                None => 0.5,
                Some(c) => non_negative_f32(c, &format!("{label}: alphaCutoff"))?,
            },
        },
        Gltf::Blend => AlphaMode::Blend,
    })
}

fn unit_interval(x: f32, what: &str) -> Result<f32> {
    let x = non_negative_f32(x, what)?;
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
    gltf: &Gltf,
    m: &gltf::Material,
    i: usize,
    label: &str,
    material: &mut Material,
) -> Result<Vec<&'static str>> {
    let what = |key: &str| format!("{label}: {key}");
    let pbr = m.pbr_metallic_roughness();
    material.metallic = unit_interval(pbr.metallic_factor(), &what("metallicFactor"))?;
    material.roughness = unit_interval(pbr.roughness_factor(), &what("roughnessFactor"))?;
    material.transmission = unit_interval(
        m.transmission().map_or(0.0, |t| t.transmission_factor()),
        &what("KHR_materials_transmission transmissionFactor"),
    )?;
    material.ior = check_ior(m.ior().unwrap_or(1.5), &what("KHR_materials_ior ior"))?;
    let specular = m.specular();
    material.specular_factor = unit_interval(
        specular.as_ref().map_or(1.0, |s| s.specular_factor()),
        &what("KHR_materials_specular specularFactor"),
    )?;
    material.specular_color = match &specular {
        Some(s) => color(
            s.specular_color_factor(),
            &what("KHR_materials_specular specularColorFactor"),
        )?,
        None => Vec3::ONE,
    };
    volume(gltf, m, i, label, material)?;
    let (lobes, rendered_lobes) = read_lobes(gltf.raw("materials", i), label)?;
    material.lobes = lobes;

    let mr_texture = pbr.metallic_roughness_texture().is_some();
    material.kind = if material.lobes.mask() != 0 {
        MaterialKind::Gltf
    } else if material.metallic == 1.0
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
    let mut rendered = vec![
        "KHR_materials_transmission",
        "KHR_materials_ior",
        "KHR_materials_volume",
        "KHR_materials_specular",
    ];
    rendered.extend(rendered_lobes);
    Ok(rendered)
}

/// `KHR_materials_volume`: thickness and the absorption coefficient.
fn volume(
    gltf: &Gltf,
    m: &gltf::Material,
    i: usize,
    label: &str,
    material: &mut Material,
) -> Result<()> {
    let what = |key: &str| format!("{label}: KHR_materials_volume {key}");
    let Some(volume) = m.volume() else {
        material.thickness = 0.0;
        material.attenuation = Vec3::ZERO;
        return Ok(());
    };
    material.thickness = non_negative_f32(volume.thickness_factor(), &what("thicknessFactor"))?;
    // The crate gives an absent attenuationDistance as infinity; whether
    // the file gives one is read from the JSON.
    let given = gltf
        .raw("materials", i)
        .get("extensions")
        .and_then(|e| e.get("KHR_materials_volume"))
        .and_then(|v| v.get("attenuationDistance"))
        .is_some();
    let distance = match given {
        true => Some(non_negative_f32(
            volume.attenuation_distance(),
            &what("attenuationDistance"),
        )?),
        false => None,
    };
    let color = color(volume.attenuation_color(), &what("attenuationColor"))?;
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
