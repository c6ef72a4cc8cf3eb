//! glTF images: decoding the PNG or JPEG a texture reads (from a file, a
//! data URI or a bufferView) on first use, checking that the images a file
//! names exist and stay in its folder, and fitting all of them into what
//! the packed texel format addresses (16 GiB: 32-bit word offsets; no view
//! or binding bounds it, `packed::bindings`). An image that is missing or cannot be decoded leaves its
//! textures' factors alone, with a note.
//!
//! Images are read from the crate's typed JSON (`json::Image`), not through
//! `gltf::Image::source`, which panics on a bufferView image without a
//! `mimeType`: vkpt has always told PNG from JPEG by their bytes.

use super::buffer::Buffer;
use super::data;
use super::decoder_panic::catch_quietly;
use super::document::Gltf;
use super::materials::material_name;
use super::notes::{name_suffix, plural};
use super::textures::texture_slots;
use super::uri::{self, percent_decode};
use crate::constants::SRGB_TABLE_WORDS;
use crate::scene::mip_levels;
use crate::scene::texture::TextureImage;
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::path::Path;

/// The glTF image texture `t` names, if any. Read from the typed JSON:
/// `Texture::source` panics on an index past the images, which vkpt
/// reports as a warning instead (`check_images`).
pub(super) fn texture_source(gltf: &Gltf, t: usize) -> Option<usize> {
    let source = gltf.doc.as_json().textures.get(t)?.source.value();
    // The crate's "no source" (`allow_empty_texture`).
    (source != u32::MAX as usize).then_some(source)
}

/// Images decoded so far, by glTF image index.
pub(super) struct ImageLoader<'a> {
    gltf: &'a Gltf,
    base: &'a Path,
    buffers: &'a [Buffer],
    /// glTF image index -> index in `images`, or `None` once it failed.
    decoded: BTreeMap<usize, Option<u32>>,
    images: Vec<TextureImage>,
}

impl<'a> ImageLoader<'a> {
    pub fn new(gltf: &'a Gltf, base: &'a Path, buffers: &'a [Buffer]) -> Self {
        ImageLoader {
            gltf,
            base,
            buffers,
            decoded: BTreeMap::new(),
            images: Vec::new(),
        }
    }

    /// Index in `images` of glTF image `i`, decoding it on first use.
    pub fn image(&mut self, i: usize, notes: &mut Vec<String>) -> Option<u32> {
        if let Some(&d) = self.decoded.get(&i) {
            return d;
        }
        let img = self.gltf.doc.as_json().images.get(i);
        let result = match img {
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
                        name_suffix(img.and_then(|img| img.name.as_deref()))
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
    fn decode(&self, i: usize, img: &gltf::json::Image) -> Result<TextureImage, Option<String>> {
        let (bytes, label) = if let Some(uri) = img.uri.as_deref() {
            if uri.starts_with("data:") {
                let data = gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
                    .map_err(|e| Some(format!("cannot decode its data URI ({e})")))?;
                (data.0, "data URI".to_string())
            } else if uri.contains("://") {
                return Err(Some(format!(
                    "uri {uri:?} is not a local file (only relative paths and data URIs are read)"
                )));
            } else {
                let file = self.base.join(percent_decode(uri));
                if !file.is_file() {
                    return Err(None);
                }
                let bytes = std::fs::read(&file)
                    .map_err(|e| Some(format!("cannot read {} ({e})", file.display())))?;
                (bytes, uri.to_string())
            }
        } else if let Some(view) = img.buffer_view {
            let v = view.value();
            let views = self.gltf.doc.views();
            let n = views.len();
            let view = self.gltf.doc.views().nth(v).ok_or_else(|| {
                Some(format!("bufferView #{v} does not exist (the file has {n})"))
            })?;
            let (bytes, _) =
                data::view_bytes(&view, self.buffers).map_err(|e| Some(format!("{e:#}")))?;
            (bytes.to_vec(), format!("bufferView #{v}"))
        } else {
            return Err(Some("has neither a uri nor a bufferView".to_string()));
        };
        let (width, height, texels) = if bytes.starts_with(&KTX2_MAGIC) {
            decode_ktx2(&bytes).map_err(|e| Some(format!("cannot decode {label} as KTX2 ({e})")))?
        } else {
            let decoded = image::load_from_memory(&bytes)
                .map_err(|e| {
                    Some(format!(
                        "cannot decode {label} as PNG, JPEG, WebP or KTX2 ({e})"
                    ))
                })?
                .into_rgba8();
            let (width, height) = decoded.dimensions();
            let texels = decoded.pixels().map(|p| u32::from_le_bytes(p.0)).collect();
            (width, height, texels)
        };
        let name = img
            .name
            .clone()
            .unwrap_or_else(|| format!("image #{i} ({label})"));
        Ok(TextureImage {
            name,
            width,
            height,
            texels,
        })
    }

    /// The decoded images at full resolution, unless together they are
    /// beyond what texel offsets address (then shrunk, with a note). A
    /// device with less memory than they need refuses the render with its
    /// memory named (`gpu::limits`); the CPU back end renders them.
    pub fn finish(mut self, notes: &mut Vec<String>) -> Vec<TextureImage> {
        fit_to_budget(&mut self.images, TEXEL_ADDRESS_BYTES, notes);
        self.images
    }
}

/// The texels a `TextureInfo::offset` (a u32 index of 4-byte words) can
/// reach: 16 GiB.
const TEXEL_ADDRESS_BYTES: u64 = 4 * u32::MAX as u64;

/// The first bytes of a KTX2 file.
const KTX2_MAGIC: [u8; 12] = [
    0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A,
];

/// The largest KTX2 image transcoded (1 GiB of RGBA8); larger ones are
/// refused before any allocation.
const MAX_KTX2_TEXELS: u64 = 1 << 28;

/// A KTX2 texture with a Basis Universal payload (`KHR_texture_basisu`:
/// ETC1S/BasisLZ or UASTC, zstd-supercompressed or not), its first mip
/// level transcoded to RGBA8 once: (width, height, texels).
fn decode_ktx2(bytes: &[u8]) -> Result<(u32, u32, Vec<u32>), String> {
    let result = catch_quietly(|| {
        let t = basisu::Transcoder::new(bytes).map_err(|e| format!("{e:?}"))?;
        let info = t.image_level_info(0).map_err(|e| format!("{e:?}"))?;
        let (width, height) = (info.width, info.height);
        // The transcoder allocates its output up front: a header claiming
        // a huge image would abort the process rather than fail.
        if width as u64 * height as u64 > MAX_KTX2_TEXELS {
            return Err(format!(
                "{width}x{height} texels is more than vkpt transcodes ({MAX_KTX2_TEXELS})"
            ));
        }
        let rgba = t
            .transcode(0, basisu::TargetFormat::Rgba32, basisu::DecodeFlags::NONE)
            .map_err(|e| format!("{e:?}"))?;
        let n = width as usize * height as usize;
        if width == 0 || height == 0 || rgba.len() < 4 * n {
            return Err(format!(
                "{width}x{height} texels, {} bytes transcoded",
                rgba.len()
            ));
        }
        let texels = rgba
            .chunks_exact(4)
            .take(n)
            .map(|p| u32::from_le_bytes([p[0], p[1], p[2], p[3]]))
            .collect();
        Ok((width, height, texels))
    });
    result.unwrap_or_else(|message| {
        Err(format!(
            "the transcoder failed on malformed data ({message})"
        ))
    })
}

/// Refuses images whose URIs leave the scene's folder (see `uri.rs`).
pub(super) fn check_image_uris(gltf: &Gltf, base: &Path, allow_outside: bool) -> Result<()> {
    for (i, img) in gltf.doc.as_json().images.iter().enumerate() {
        let Some(uri) = img.uri.as_deref() else {
            continue;
        };
        if !(uri.starts_with("data:") || uri.contains("://")) {
            uri::resolve(base, uri, allow_outside)
                .with_context(|| format!("image #{i}{}", name_suffix(img.name.as_deref())))?;
        }
    }
    Ok(())
}

/// Checks that every external image exists and every texture names an
/// existing image; problems are notes naming the users. A material's
/// texture references are found in its JSON, so those of extensions the
/// crate does not model count too.
pub(super) fn check_images(gltf: &Gltf, base: &Path, notes: &mut Vec<String>) {
    let images = &gltf.doc.as_json().images;
    // texture index -> "material 'm' (slot)" users.
    let mut users: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    for (i, m) in gltf.doc.materials().enumerate() {
        let mut slots = Vec::new();
        texture_slots(gltf.raw("materials", i), &mut slots);
        for (slot, tex) in slots {
            if let Some(t) = tex {
                users.entry(t).or_default().push(format!(
                    "material '{}' ({slot})",
                    material_name(m.name(), i)
                ));
            }
        }
    }
    let used_by = |t: u64| match users.get(&t) {
        Some(u) => format!("used by {}", u.join(", ")),
        None => "not used by any material".to_string(),
    };
    for tex in gltf.doc.textures() {
        let t = tex.index();
        let Some(src) = texture_source(gltf, t) else {
            continue;
        };
        if src >= images.len() {
            notes.push(format!(
                "warning: texture #{t}{} refers to image #{src}, which is missing (the file defines {}); {}",
                name_suffix(tex.name()),
                plural(images.len(), "image", "images"),
                used_by(t as u64)
            ));
        }
    }
    for (i, img) in images.iter().enumerate() {
        let Some(uri) = img.uri.as_deref() else {
            continue;
        };
        if uri.starts_with("data:") || uri.contains("://") {
            continue;
        }
        let file = base.join(percent_decode(uri));
        if !file.is_file() {
            let who: Vec<String> = gltf
                .doc
                .textures()
                .filter(|tex| texture_source(gltf, tex.index()) == Some(i))
                .map(|tex| {
                    format!(
                        "texture #{}{} {}",
                        tex.index(),
                        name_suffix(tex.name()),
                        used_by(tex.index() as u64)
                    )
                })
                .collect();
            notes.push(format!(
                "warning: image #{i}{} is missing: {} not found ({})",
                name_suffix(img.name.as_deref()),
                file.display(),
                if who.is_empty() {
                    "not used by any texture".to_string()
                } else {
                    who.join("; ")
                }
            ));
        }
    }
}

/// Halves the largest image until all fit `budget` bytes of texel buffer
/// (after the sRGB table), with a note naming what was shrunk.
fn fit_to_budget(images: &mut [TextureImage], budget: u64, notes: &mut Vec<String>) {
    // Halving keeps a grey image grey: its storage is fixed at full size.
    // Counted with a full mip pyramid, which packing may add.
    let storages: Vec<_> = images.iter().map(|i| i.storage()).collect();
    let words = |k: usize, i: &TextureImage| {
        storages[k].pyramid_words(i.width, i.height, mip_levels(i.width, i.height))
    };
    let total = |images: &[TextureImage]| -> u64 {
        4 * (SRGB_TABLE_WORDS as u64
            + images
                .iter()
                .enumerate()
                .map(|(k, i)| words(k, i))
                .sum::<u64>())
    };
    let before = total(images);
    let mut shrunk: BTreeMap<usize, (u32, u32)> = BTreeMap::new();
    while total(images) > budget {
        let Some((k, _)) = images
            .iter()
            .enumerate()
            .filter(|(_, i)| i.width * i.height > 1)
            .max_by_key(|&(k, i)| words(k, i))
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
            "textures need {:.1} MiB, above the {:.0} MiB that texel offsets address: downsampled (2x2 box filter) {}",
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

        // A grey image takes a byte per texel: 64 x 64 grey fits this budget.
        let mut images = vec![
            TextureImage {
                texels: vec![0xFF80_8080; 64 * 64],
                ..image("grey", 64, 64)
            },
            image("small", 8, 8),
        ];
        let mut notes = Vec::new();
        fit_to_budget(&mut images, budget, &mut notes);
        assert_eq!((images[0].width, notes.len()), (64, 0), "{notes:?}");

        let mut fits = vec![image("a", 4, 4)];
        let mut notes = Vec::new();
        fit_to_budget(&mut fits, budget, &mut notes);
        assert!(notes.is_empty() && fits[0].width == 4);
    }
}
