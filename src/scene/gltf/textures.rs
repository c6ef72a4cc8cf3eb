//! glTF textures: the texture references of a material (texture, sampler,
//! texture coordinate set, `KHR_texture_transform`), which slots vkpt
//! renders, and what it says about those it cannot use. The images they
//! read are decoded by `images.rs`.

use super::document::Gltf;
use super::images::{ImageLoader, texture_source};
use super::notes::plural;
use crate::scene::texture::{MaterialTextures, TextureImage, TextureRef, Wrap};
use gltf::json::Value;
use gltf::texture::{MagFilter, WrappingMode};
use std::collections::BTreeMap;

/// Texture extensions whose images vkpt cannot decode (used only when the
/// texture has no other source).
const UNDECODABLE_SOURCES: [&str; 2] = ["EXT_texture_avif", "MSFT_texture_dds"];

/// Texture extensions that name an image vkpt decodes (`images.rs`).
const DECODED_SOURCES: [&str; 2] = ["EXT_texture_webp", "KHR_texture_basisu"];

/// Image formats by preference, where a texture offers several: lossless
/// first, a GPU block format (transcoded from a lossy codec) last.
const PREFERENCE: [&str; 4] = ["PNG", "WebP", "JPEG", "KTX2"];

/// The format of glTF image `i` from its mimeType or its uri's extension
/// (without reading it), or "JPEG" (a lossy rank) when neither says.
fn image_format(gltf: &Gltf, i: usize) -> &'static str {
    let img = gltf.raw("images", i);
    let mime = img.get("mimeType").and_then(Value::as_str).unwrap_or("");
    let uri = img
        .get("uri")
        .and_then(Value::as_str)
        .unwrap_or("")
        .to_ascii_lowercase();
    let data = |m: &str| uri.starts_with(&format!("data:{m}"));
    if mime == "image/png" || uri.ends_with(".png") || data("image/png") {
        "PNG"
    } else if mime == "image/webp" || uri.ends_with(".webp") || data("image/webp") {
        "WebP"
    } else if mime == "image/ktx2" || uri.ends_with(".ktx2") || data("image/ktx2") {
        "KTX2"
    } else {
        "JPEG"
    }
}

/// Texture slots that are rendered (or, for occlusion, deliberately left
/// to the path tracer).
pub(super) const RENDERED_TEXTURE_SLOTS: &[&str] = &[
    "baseColorTexture",
    "metallicRoughnessTexture",
    "normalTexture",
    "occlusionTexture",
    "emissiveTexture",
    "specularTexture",
    "specularColorTexture",
    "transmissionTexture",
    "diffuseTexture",
    "specularGlossinessTexture",
    "clearcoatTexture",
    "clearcoatRoughnessTexture",
    "clearcoatNormalTexture",
    "anisotropyTexture",
    "sheenColorTexture",
    "sheenRoughnessTexture",
    "diffuseTransmissionTexture",
    "diffuseTransmissionColorTexture",
    "thicknessTexture",
    "iridescenceTexture",
    "iridescenceThicknessTexture",
];

/// Every texture reference in a material: (slot name such as
/// "baseColorTexture", texture index). Extension slots are found too.
pub(super) fn texture_slots(v: &Value, out: &mut Vec<(String, Option<u64>)>) {
    if let Value::Object(map) = v {
        for (k, child) in map {
            if k.ends_with("Texture") && child.is_object() {
                out.push((k.clone(), child.get("index").and_then(Value::as_u64)));
            }
            texture_slots(child, out);
        }
    }
}

/// Resolves materials' texture references, decoding their images through
/// an [`ImageLoader`], and remembers what it could not use.
pub(super) struct TextureLoader<'a> {
    gltf: &'a Gltf,
    images: ImageLoader<'a>,
    /// (texture extension, texture index) that could not be used.
    skipped_extensions: BTreeMap<String, Vec<String>>,
    /// Occlusion textures seen (ignored: a path tracer computes occlusion).
    occlusion: Vec<String>,
    /// Textures offering more than one image: texture index -> the format
    /// used and those passed over.
    choices: BTreeMap<usize, (&'static str, Vec<&'static str>)>,
    /// Texture references left unused, by why: "material 'm' (slot)".
    unused_slots: BTreeMap<String, Vec<String>>,
}

/// A material's reference to a texture: the crate's `texture::Info` or
/// `NormalTexture`, which share no trait.
struct Slot<'a, 'b> {
    texture: gltf::Texture<'a>,
    tex_coord: u32,
    /// `KHR_texture_transform`, as JSON: the crate models it on
    /// textureInfo but not on normalTexture (which TextureTransformMultiTest
    /// transforms), and vkpt has always used a malformed one untransformed
    /// with a note rather than refusing the file.
    transform: Option<&'b Value>,
}

impl<'a, 'b> Slot<'a, 'b> {
    fn info(info: &'b gltf::texture::Info<'a>) -> Self {
        Slot {
            texture: info.texture(),
            tex_coord: info.tex_coord(),
            transform: info.extension_value("KHR_texture_transform"),
        }
    }

    fn normal(info: &'b gltf::material::NormalTexture<'a>) -> Self {
        Slot {
            texture: info.texture(),
            tex_coord: info.tex_coord(),
            transform: info.extension_value("KHR_texture_transform"),
        }
    }
}

impl<'a, 'b> Slot<'a, 'b> {
    /// A textureInfo the crate does not model (an extension's), from JSON;
    /// `None` when its index names no texture (validation reports that).
    fn json(gltf: &'a Gltf, info: &'b Value) -> Option<Self> {
        let index = info.get("index")?.as_u64()? as usize;
        Some(Slot {
            texture: gltf.doc.textures().nth(index)?,
            tex_coord: info.get("texCoord").and_then(Value::as_u64).unwrap_or(0) as u32,
            transform: info
                .get("extensions")
                .and_then(|e| e.get("KHR_texture_transform")),
        })
    }
}

/// The JSON textureInfo `key` of material extension `ext`.
fn extension_texture<'v>(raw: &'v Value, ext: &str, key: &str) -> Option<&'v Value> {
    raw.get("extensions")?.get(ext)?.get(key)
}

impl<'a> TextureLoader<'a> {
    pub fn new(gltf: &'a Gltf, images: ImageLoader<'a>) -> Self {
        TextureLoader {
            gltf,
            images,
            skipped_extensions: BTreeMap::new(),
            occlusion: Vec::new(),
            choices: BTreeMap::new(),
            unused_slots: BTreeMap::new(),
        }
    }

    /// The texture slots of material `m` (named `name`). A slot whose
    /// texture cannot be used is left empty (the factor alone), with a note.
    pub fn material_textures(
        &mut self,
        m: &gltf::Material,
        raw: &Value,
        name: &str,
        notes: &mut Vec<String>,
    ) -> MaterialTextures {
        let pbr = m.pbr_metallic_roughness();
        let specular = m.specular();
        let base_color = pbr.base_color_texture();
        let metallic_roughness = pbr.metallic_roughness_texture();
        let normal = m.normal_texture();
        let emissive = m.emissive_texture();
        let specular_factor = specular.as_ref().and_then(|s| s.specular_texture());
        let specular_color = specular.as_ref().and_then(|s| s.specular_color_texture());
        let transmission = m.transmission().and_then(|t| t.transmission_texture());
        let mut read = |slot: Option<Slot>, what: &str| {
            slot.and_then(|slot| self.texture_ref(slot, name, what, notes))
        };
        let textures = MaterialTextures {
            base_color: read(base_color.as_ref().map(Slot::info), "baseColorTexture"),
            metallic_roughness: read(
                metallic_roughness.as_ref().map(Slot::info),
                "metallicRoughnessTexture",
            ),
            normal: read(normal.as_ref().map(Slot::normal), "normalTexture"),
            emissive: read(emissive.as_ref().map(Slot::info), "emissiveTexture"),
            specular: read(specular_factor.as_ref().map(Slot::info), "specularTexture"),
            specular_color: read(
                specular_color.as_ref().map(Slot::info),
                "specularColorTexture",
            ),
            transmission: read(transmission.as_ref().map(Slot::info), "transmissionTexture"),
            ..MaterialTextures::default()
        };
        let gltf = self.gltf;
        let mut ext = |e: &str, key: &str| {
            extension_texture(raw, e, key)
                .and_then(|v| Slot::json(gltf, v))
                .and_then(|slot| self.texture_ref(slot, name, key, notes))
        };
        let clearcoat = "KHR_materials_clearcoat";
        let sheen = "KHR_materials_sheen";
        let iridescence = "KHR_materials_iridescence";
        let diffuse_transmission = "KHR_materials_diffuse_transmission";
        let textures = MaterialTextures {
            clearcoat: ext(clearcoat, "clearcoatTexture"),
            clearcoat_roughness: ext(clearcoat, "clearcoatRoughnessTexture"),
            clearcoat_normal: ext(clearcoat, "clearcoatNormalTexture"),
            sheen_color: ext(sheen, "sheenColorTexture"),
            sheen_roughness: ext(sheen, "sheenRoughnessTexture"),
            iridescence: ext(iridescence, "iridescenceTexture"),
            iridescence_thickness: ext(iridescence, "iridescenceThicknessTexture"),
            anisotropy: ext("KHR_materials_anisotropy", "anisotropyTexture"),
            diffuse_transmission: ext(diffuse_transmission, "diffuseTransmissionTexture"),
            diffuse_transmission_color: ext(
                diffuse_transmission,
                "diffuseTransmissionColorTexture",
            ),
            thickness: ext("KHR_materials_volume", "thicknessTexture"),
            ..textures
        };
        if m.occlusion_texture().is_some() {
            self.occlusion.push(name.to_string());
        }
        textures
    }

    /// A textureInfo read from JSON (an extension the crate does not
    /// model), or `None` (with a note when it cannot be used).
    pub fn json_texture(
        &mut self,
        info: Option<&Value>,
        material: &str,
        what: &str,
        notes: &mut Vec<String>,
    ) -> Option<TextureRef> {
        let gltf = self.gltf;
        info.and_then(|v| Slot::json(gltf, v))
            .and_then(|slot| self.texture_ref(slot, material, what, notes))
    }

    /// A texture reference as a `TextureRef`, or `None` with a note.
    fn texture_ref(
        &mut self,
        slot: Slot,
        material: &str,
        what: &str,
        notes: &mut Vec<String>,
    ) -> Option<TextureRef> {
        let who = format!("material '{material}' ({what})");
        let texture = &slot.texture;
        let ti = texture.index();
        let mut texcoord = slot.tex_coord as u64;
        if let Some(t) = slot
            .transform
            .and_then(|t| t.get("texCoord"))
            .and_then(Value::as_u64)
        {
            texcoord = t;
        }
        if texcoord > 1 {
            self.unused_slots
                .entry(format!(
                    "TEXCOORD_{texcoord} is not supported (only sets 0 and 1): the texture is ignored"
                ))
                .or_default()
                .push(who);
            return None;
        }
        let matrix = match slot.transform.map(texture_transform) {
            None => TextureRef::IDENTITY,
            Some(Some(m)) => m,
            Some(None) => {
                self.unused_slots
                    .entry("KHR_texture_transform has a malformed offset, rotation or scale: the texture is used untransformed".to_string())
                    .or_default()
                    .push(who.clone());
                TextureRef::IDENTITY
            }
        };
        let sources = self.sources(texture);
        if sources.is_empty() {
            self.no_source(texture, &who);
            return None;
        }
        // The preferred image that decodes (those that do not are noted).
        let (format, image) = sources
            .iter()
            .find_map(|&(f, s)| Some((f, self.images.image(s, notes)?)))?;
        if sources.len() > 1 {
            let others = sources.iter().map(|s| s.0).filter(|f| *f != format);
            self.choices.insert(ti, (format, others.collect()));
        }
        let sampler = texture.sampler();
        let wrap = |mode| match mode {
            WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
            WrappingMode::Repeat => Wrap::Repeat,
        };
        Some(TextureRef {
            image,
            texcoord: texcoord as u32,
            transform: matrix,
            wrap_s: wrap(sampler.wrap_s()),
            wrap_t: wrap(sampler.wrap_t()),
            nearest: sampler.mag_filter() == Some(MagFilter::Nearest),
        })
    }

    /// The images texture `texture` offers (its `source`, and those of the
    /// image extensions vkpt decodes), most preferred first, with their
    /// formats.
    fn sources(&self, texture: &gltf::Texture) -> Vec<(&'static str, usize)> {
        let images = self.gltf.doc.as_json().images.len();
        let mut sources: Vec<usize> = texture_source(self.gltf, texture.index())
            .into_iter()
            .collect();
        for ext in DECODED_SOURCES {
            if let Some(s) = texture
                .extension_value(ext)
                .and_then(|e| e.get("source"))
                .and_then(Value::as_u64)
                .filter(|&s| (s as usize) < images)
            {
                sources.push(s as usize);
            }
        }
        sources.dedup();
        let mut sources: Vec<(&'static str, usize)> = sources
            .into_iter()
            .map(|s| (image_format(self.gltf, s), s))
            .collect();
        sources.sort_by_key(|(f, _)| PREFERENCE.iter().position(|p| p == f));
        sources
    }

    /// Says why a texture without a source image is not used: its image
    /// format extensions (none of which vkpt decodes), or nothing at all.
    fn no_source(&mut self, texture: &gltf::Texture, who: &str) {
        let ti = texture.index();
        let exts: Vec<String> = texture
            .extensions()
            .map(|o| o.keys().cloned().collect())
            .unwrap_or_default();
        for e in &exts {
            if DECODED_SOURCES.contains(&e.as_str()) {
                // Its image index is past the images: `check_images` warns.
                continue;
            }
            let e = if UNDECODABLE_SOURCES.contains(&e.as_str()) {
                e.clone()
            } else {
                format!("{e} (unknown)")
            };
            self.skipped_extensions
                .entry(e)
                .or_default()
                .push(format!("texture #{ti}"));
        }
        if exts.is_empty() {
            self.unused_slots
                .entry("the texture has no source image: ignored".to_string())
                .or_default()
                .push(format!("{who} texture #{ti}"));
        }
    }

    /// Notes for what was skipped; the decoded images, shrunk to the texel
    /// budget.
    pub fn finish(mut self, notes: &mut Vec<String>) -> Vec<TextureImage> {
        for (ext, textures) in &self.skipped_extensions {
            notes.push(format!(
                "{ext} image format is not supported: {} ignored (the factors are used)",
                textures.join(", ")
            ));
        }
        if !self.choices.is_empty() {
            notes.push(choices_note(&self.choices));
        }
        // One line per reason, counting the texture references.
        for (why, who) in &self.unused_slots {
            let more = match who.len() {
                n if n > 3 => format!(" and {} more", n - 3),
                _ => String::new(),
            };
            notes.push(format!(
                "{} ({}{more}): {why}",
                plural(who.len(), "texture reference", "texture references"),
                who[..who.len().min(3)].join(", ")
            ));
        }
        if !self.occlusion.is_empty() {
            self.occlusion.sort();
            self.occlusion.dedup();
            notes.push(format!(
                "occlusionTexture ignored on {} material(s) (a path tracer computes occlusion itself)",
                self.occlusion.len()
            ));
        }
        self.images.finish(notes)
    }
}

/// One note for the textures that offer several images: how many used
/// each format, rather than which, and in what order vkpt prefers them.
fn choices_note(choices: &BTreeMap<usize, (&'static str, Vec<&'static str>)>) -> String {
    let mut by_format: BTreeMap<(&str, Vec<&str>), Vec<String>> = BTreeMap::new();
    for (t, (used, others)) in choices {
        by_format
            .entry((used, others.clone()))
            .or_default()
            .push(format!("#{t}"));
    }
    let parts: Vec<String> = by_format
        .iter()
        .map(|((used, others), textures)| {
            let shown = textures
                .iter()
                .take(3)
                .cloned()
                .collect::<Vec<_>>()
                .join(", ");
            let more = if textures.len() > 3 {
                format!(" and {} more", textures.len() - 3)
            } else {
                String::new()
            };
            format!(
                "{} {} the {used} image rather than the {} ({shown}{more})",
                plural(textures.len(), "texture", "textures"),
                if textures.len() == 1 { "uses" } else { "use" },
                others.join(" or ")
            )
        })
        .collect();
    format!(
        "textures offering several images: {} (vkpt prefers {})",
        parts.join("; "),
        PREFERENCE.join(" > ")
    )
}

/// `KHR_texture_transform` as the rows of `translation * rotation * scale`
/// (the extension's definition), or `None` when malformed.
fn texture_transform(t: &Value) -> Option<[[f32; 3]; 2]> {
    let pair = |key: &str, default: [f32; 2]| -> Option<[f32; 2]> {
        match t.get(key) {
            None => Some(default),
            Some(v) => {
                let a = v.as_array().filter(|a| a.len() == 2)?;
                let x = a[0].as_f64()? as f32;
                let y = a[1].as_f64()? as f32;
                (x.is_finite() && y.is_finite()).then_some([x, y])
            }
        }
    };
    let offset = pair("offset", [0.0, 0.0])?;
    let scale = pair("scale", [1.0, 1.0])?;
    let rotation = match t.get("rotation") {
        None => 0.0,
        Some(v) => v.as_f64().filter(|r| r.is_finite())? as f32,
    };
    let (s, c) = rotation.sin_cos();
    // The extension's GLSL builds the rotation column by column:
    // mat3(cos, sin, 0, -sin, cos, 0, 0, 0, 1); its rows are (cos, -sin)
    // and (sin, cos).
    Some([
        [c * scale[0], -s * scale[1], offset[0]],
        [s * scale[0], c * scale[1], offset[1]],
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_transform_is_translation_rotation_scale() {
        let t: Value = gltf::json::deserialize::from_str(
            r#"{"offset": [0.5, 0.25], "rotation": 1.5707964, "scale": [2, 3]}"#,
        )
        .unwrap();
        let m = texture_transform(&t).unwrap();
        // (u, v) = (1, 0): scaled (2, 0), rotated to (0, 2), offset (0.5, 2.25).
        let apply = |r: [f32; 3]| r[0] * 1.0 + r[1] * 0.0 + r[2];
        assert!((apply(m[0]) - 0.5).abs() < 1e-6 && (apply(m[1]) - 2.25).abs() < 1e-6);
        let bad: Value = gltf::json::deserialize::from_str(r#"{"scale": [1]}"#).unwrap();
        assert!(texture_transform(&bad).is_none());
    }
}
