//! glTF textures: the texture references of a material (texture, sampler,
//! texture coordinate set, `KHR_texture_transform`) and the images they
//! read (PNG or JPEG from a file, a data URI or a bufferView). An image that
//! is missing or cannot be decoded leaves the factor alone, with a note;
//! only images some material uses are decoded. All images together must fit
//! `TEXEL_BUDGET_BYTES`: the largest are halved until they do (a note says
//! which).

use super::data::{self as gltf_data, array, name_suffix};
use crate::scene::texture::{MaterialTextures, TextureImage, TextureRef, Wrap};
use crate::constants::{SRGB_TABLE_WORDS, TEXEL_BUDGET_BYTES};
use gltf::json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// glTF sampler constants.
const GL_NEAREST: u64 = 9728;
const GL_CLAMP_TO_EDGE: u64 = 33071;
const GL_MIRRORED_REPEAT: u64 = 33648;

/// Texture extensions whose images vkpt cannot decode (used only when the
/// texture has no PNG/JPEG `source` fallback).
const UNDECODABLE_SOURCES: [&str; 4] = [
    "KHR_texture_basisu",
    "EXT_texture_webp",
    "EXT_texture_avif",
    "MSFT_texture_dds",
];

/// Images decoded so far (by glTF image index) and what was said about them.
pub(super) struct ImageLoader<'a> {
    json: &'a Value,
    base: &'a Path,
    buffers: &'a [Vec<u8>],
    /// glTF image index -> index in `images`, or `None` once it failed.
    decoded: BTreeMap<usize, Option<u32>>,
    pub images: Vec<TextureImage>,
    /// (texture extension, texture index) that could not be used.
    skipped_extensions: BTreeMap<String, Vec<String>>,
    /// Occlusion textures seen (ignored: a path tracer computes occlusion).
    pub occlusion: Vec<String>,
}

impl<'a> ImageLoader<'a> {
    pub fn new(json: &'a Value, base: &'a Path, buffers: &'a [Vec<u8>]) -> Self {
        ImageLoader {
            json,
            base,
            buffers,
            decoded: BTreeMap::new(),
            images: Vec::new(),
            skipped_extensions: BTreeMap::new(),
            occlusion: Vec::new(),
        }
    }

    /// The texture slots of material `m` (named `name`). A slot whose
    /// texture cannot be used is left empty (the factor alone), with a note.
    pub fn material_textures(
        &mut self,
        m: &Value,
        name: &str,
        notes: &mut Vec<String>,
    ) -> MaterialTextures {
        let pbr = m.get("pbrMetallicRoughness");
        let ext = |e: &str| m.get("extensions").and_then(|x| x.get(e));
        let specular = ext("KHR_materials_specular");
        let mut slot = |info: Option<&Value>, what: &str| -> Option<TextureRef> {
            let info = info?;
            self.texture_ref(info, name, what, notes)
        };
        let textures = MaterialTextures {
            base_color: slot(
                pbr.and_then(|p| p.get("baseColorTexture")),
                "baseColorTexture",
            ),
            metallic_roughness: slot(
                pbr.and_then(|p| p.get("metallicRoughnessTexture")),
                "metallicRoughnessTexture",
            ),
            normal: slot(m.get("normalTexture"), "normalTexture"),
            emissive: slot(m.get("emissiveTexture"), "emissiveTexture"),
            specular: slot(
                specular.and_then(|s| s.get("specularTexture")),
                "specularTexture",
            ),
            specular_color: slot(
                specular.and_then(|s| s.get("specularColorTexture")),
                "specularColorTexture",
            ),
            transmission: slot(
                ext("KHR_materials_transmission").and_then(|t| t.get("transmissionTexture")),
                "transmissionTexture",
            ),
        };
        if m.get("occlusionTexture").is_some() {
            self.occlusion.push(name.to_string());
        }
        textures
    }

    /// A textureInfo object as a `TextureRef`, or `None` with a note.
    fn texture_ref(
        &mut self,
        info: &Value,
        material: &str,
        slot: &str,
        notes: &mut Vec<String>,
    ) -> Option<TextureRef> {
        let json = self.json;
        let who = format!("material '{material}' ({slot})");
        let Some(ti) = info
            .get("index")
            .and_then(Value::as_u64)
            .map(|i| i as usize)
        else {
            notes.push(format!("{who}: the texture has no valid index: ignored"));
            return None;
        };
        let Some(texture) = array(json, "textures").get(ti) else {
            notes.push(format!(
                "{who}: texture #{ti} does not exist (the file has {}): ignored",
                array(json, "textures").len()
            ));
            return None;
        };
        let transform = info
            .get("extensions")
            .and_then(|e| e.get("KHR_texture_transform"));
        let mut texcoord = info.get("texCoord").and_then(Value::as_u64).unwrap_or(0);
        if let Some(t) = transform
            .and_then(|t| t.get("texCoord"))
            .and_then(Value::as_u64)
        {
            texcoord = t;
        }
        if texcoord > 1 {
            notes.push(format!(
                "{who}: TEXCOORD_{texcoord} is not supported (only sets 0 and 1): the texture is ignored"
            ));
            return None;
        }
        let matrix = match transform.map(texture_transform) {
            None => TextureRef::IDENTITY,
            Some(Some(m)) => m,
            Some(None) => {
                notes.push(format!(
                    "{who}: KHR_texture_transform has a malformed offset, rotation or scale: the texture is used untransformed"
                ));
                TextureRef::IDENTITY
            }
        };
        let source = match texture.get("source").and_then(Value::as_u64) {
            Some(s) => s as usize,
            None => {
                let exts: Vec<String> = texture
                    .get("extensions")
                    .and_then(Value::as_object)
                    .map(|o| o.keys().cloned().collect())
                    .unwrap_or_default();
                for e in &exts {
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
                    notes.push(format!("{who}: texture #{ti} has no source image: ignored"));
                }
                return None;
            }
        };
        let image = self.image(source, notes)?;
        let sampler = texture
            .get("sampler")
            .and_then(Value::as_u64)
            .and_then(|s| array(json, "samplers").get(s as usize));
        let wrap = |key: &str| match sampler.and_then(|s| s.get(key)).and_then(Value::as_u64) {
            Some(GL_CLAMP_TO_EDGE) => Wrap::ClampToEdge,
            Some(GL_MIRRORED_REPEAT) => Wrap::MirroredRepeat,
            _ => Wrap::Repeat,
        };
        Some(TextureRef {
            image,
            texcoord: texcoord as u32,
            transform: matrix,
            wrap_s: wrap("wrapS"),
            wrap_t: wrap("wrapT"),
            nearest: sampler
                .and_then(|s| s.get("magFilter"))
                .and_then(Value::as_u64)
                == Some(GL_NEAREST),
        })
    }

    /// Index in `images` of glTF image `i`, decoding it on first use.
    fn image(&mut self, i: usize, notes: &mut Vec<String>) -> Option<u32> {
        if let Some(&d) = self.decoded.get(&i) {
            return d;
        }
        let result = match array(self.json, "images").get(i) {
            None => Err(None),
            Some(img) => self.decode(i, img),
        };
        let d = match result {
            Ok(image) => {
                self.images.push(image);
                Some(self.images.len() as u32 - 1)
            }
            Err(why) => {
                if let Some(why) = why {
                    notes.push(format!(
                        "warning: image #{i}{}: {why}; the textures using it are ignored (their factors are used)",
                        array(self.json, "images").get(i).map(name_suffix).unwrap_or_default()
                    ));
                }
                None
            }
        };
        self.decoded.insert(i, d);
        d
    }

    /// Decodes one image; `Err(None)` when the problem was reported already
    /// (a missing file or image: `check_images` names its users).
    fn decode(&self, i: usize, img: &Value) -> Result<TextureImage, Option<String>> {
        let (bytes, label) = if let Some(uri) = img.get("uri").and_then(Value::as_str) {
            if uri.starts_with("data:") {
                let data = gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
                    .map_err(|e| Some(format!("cannot decode its data URI ({e})")))?;
                (data.0, "data URI".to_string())
            } else if uri.contains("://") {
                return Err(Some(format!(
                    "uri {uri:?} is not a local file (only relative paths and data URIs are read)"
                )));
            } else {
                let file = self.base.join(gltf_data::percent_decode(uri));
                if !file.is_file() {
                    return Err(None);
                }
                let bytes = std::fs::read(&file)
                    .map_err(|e| Some(format!("cannot read {} ({e})", file.display())))?;
                (bytes, uri.to_string())
            }
        } else if let Some(view) = img.get("bufferView").and_then(Value::as_u64) {
            let bytes = gltf_data::buffer_view_bytes(self.json, self.buffers, view as usize)
                .map_err(|e| Some(format!("{e:#}")))?;
            (bytes.to_vec(), format!("bufferView #{view}"))
        } else {
            return Err(Some("has neither a uri nor a bufferView".to_string()));
        };
        let decoded = image::load_from_memory(&bytes)
            .map_err(|e| Some(format!("cannot decode {label} as PNG or JPEG ({e})")))?
            .into_rgba8();
        let (width, height) = decoded.dimensions();
        let texels = decoded.pixels().map(|p| u32::from_le_bytes(p.0)).collect();
        let name = img
            .get("name")
            .and_then(Value::as_str)
            .map(str::to_string)
            .unwrap_or_else(|| format!("image #{i} ({label})"));
        Ok(TextureImage {
            name,
            width,
            height,
            texels,
        })
    }

    /// Notes for what was skipped; shrinks the images to the texel budget.
    pub fn finish(mut self, notes: &mut Vec<String>) -> Vec<TextureImage> {
        for (ext, textures) in &self.skipped_extensions {
            notes.push(format!(
                "{ext} image format is not supported: {} ignored (the factors are used)",
                textures.join(", ")
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
        fit_to_budget(&mut self.images, TEXEL_BUDGET_BYTES as u64, notes);
        self.images
    }
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

/// Halves the largest image until all fit `budget` bytes of texel buffer
/// (after the sRGB table), with a note naming what was shrunk.
pub fn fit_to_budget(images: &mut [TextureImage], budget: u64, notes: &mut Vec<String>) {
    let total = |images: &[TextureImage]| -> u64 {
        4 * (SRGB_TABLE_WORDS as u64
            + images
                .iter()
                .map(|i| i.width as u64 * i.height as u64)
                .sum::<u64>())
    };
    let before = total(images);
    let mut shrunk: BTreeMap<usize, (u32, u32)> = BTreeMap::new();
    while total(images) > budget {
        let Some((k, _)) = images
            .iter()
            .enumerate()
            .filter(|(_, i)| i.width * i.height > 1)
            .max_by_key(|(_, i)| i.width as u64 * i.height as u64)
        else {
            break;
        };
        shrunk
            .entry(k)
            .or_insert((images[k].width, images[k].height));
        images[k] = images[k].downsample();
    }
    if !shrunk.is_empty() {
        let list: Vec<String> = shrunk
            .iter()
            .map(|(&k, &(w, h))| {
                format!(
                    "'{}' {w}x{h} -> {}x{}",
                    images[k].name, images[k].width, images[k].height
                )
            })
            .collect();
        notes.push(format!(
            "textures need {:.1} MiB, above the {:.0} MiB texel buffer: downsampled (2x2 box filter) {}",
            before as f64 / 1048576.0,
            budget as f64 / 1048576.0,
            list.join(", ")
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(name: &str, width: u32, height: u32) -> TextureImage {
        TextureImage {
            name: name.to_string(),
            width,
            height,
            texels: (0..width * height).collect(),
        }
    }

    #[test]
    fn downsample_averages_2x2_blocks_and_rounds_odd_sizes_up() {
        let img = TextureImage {
            name: "x".into(),
            width: 3,
            height: 1,
            texels: vec![0x0000_0010, 0x0000_0020, 0xFF00_0040],
        };
        let half = img.downsample();
        assert_eq!((half.width, half.height), (2, 1));
        // (0x10 + 0x20 + 0x10 + 0x20) / 4 = 0x18; the odd column repeats.
        assert_eq!(half.texels, vec![0x0000_0018, 0xFF00_0040]);
    }

    #[test]
    fn the_largest_images_are_halved_until_all_fit_with_a_note() {
        let mut images = vec![image("big", 64, 64), image("small", 8, 8)];
        let mut notes = Vec::new();
        let budget = 4 * (SRGB_TABLE_WORDS as u64 + 40 * 40);
        fit_to_budget(&mut images, budget, &mut notes);
        assert_eq!((images[0].width, images[0].height), (32, 32));
        assert_eq!((images[1].width, images[1].height), (8, 8));
        assert_eq!(notes.len(), 1);
        assert!(notes[0].contains("'big' 64x64 -> 32x32"), "{notes:?}");

        let mut fits = vec![image("a", 4, 4)];
        let mut notes = Vec::new();
        fit_to_budget(&mut fits, budget, &mut notes);
        assert!(notes.is_empty() && fits[0].width == 4);
    }

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
