//! Textures as plain scene data: decoded images, the texture references a
//! material holds (image, texture coordinate set, `KHR_texture_transform`,
//! sampler), and each triangle's texture coordinates and tangents.

use glam::{Vec2, Vec4};

/// A decoded image: 8-bit RGBA, rows top to bottom (glTF's UV origin is the
/// image's top-left corner).
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    /// What the notes call it: the image's name, URI or index.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// `width * height` texels, red in the low byte.
    pub texels: Vec<u32>,
}

/// How the texel buffer stores an image: RGBA8 words, or fewer bytes per
/// texel where the image's channels allow it without changing any value a
/// fetch returns (`TEXTURE_GREY`, `TEXTURE_GREY_ALPHA` in `constants.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelStorage {
    /// One texel per word (R in the low byte).
    Rgba8,
    /// R = G = B and A = 255 everywhere: one byte per texel, four per word.
    Grey8,
    /// R = G = B everywhere: grey and alpha bytes, two texels per word.
    GreyAlpha8,
}

impl TexelStorage {
    pub fn texels_per_word(self) -> u64 {
        match self {
            TexelStorage::Rgba8 => 1,
            TexelStorage::Grey8 => 4,
            TexelStorage::GreyAlpha8 => 2,
        }
    }

    /// Words of texel buffer an image of `texels` texels takes (its last
    /// word padded, so the next image starts on a word).
    pub fn words(self, texels: u64) -> u64 {
        texels.div_ceil(self.texels_per_word())
    }

    /// Words a `width` x `height` image takes with its `levels` mip levels.
    pub fn pyramid_words(self, width: u32, height: u32, levels: u32) -> u64 {
        let (mut w, mut h, mut words) = (width as u64, height as u64, 0);
        for _ in 0..levels {
            words += self.words(w * h);
            w = w.div_ceil(2);
            h = h.div_ceil(2);
        }
        words
    }
}

/// The 8-bit code whose value in the increasing `table` is nearest `v`.
fn nearest_code(table: &[f32; 256], v: f32) -> u32 {
    let above = table.partition_point(|&t| t < v).min(255);
    if above > 0 && v - table[above - 1] <= table[above] - v {
        above as u32 - 1
    } else {
        above as u32
    }
}

/// Mip levels of a `width` x `height` image: halving (odd sizes round up)
/// down to 1x1, the image itself included.
pub fn mip_levels(width: u32, height: u32) -> u32 {
    let (mut w, mut h, mut n) = (width, height, 1);
    while w > 1 || h > 1 {
        w = w.div_ceil(2);
        h = h.div_ceil(2);
        n += 1;
    }
    n
}

impl TextureImage {
    /// The most compact storage that reads back every texel unchanged.
    pub fn storage(&self) -> TexelStorage {
        let mut alpha = false;
        for &t in &self.texels {
            let [r, g, b, a] = t.to_le_bytes();
            if r != g || g != b {
                return TexelStorage::Rgba8;
            }
            alpha |= a != 255;
        }
        if alpha {
            TexelStorage::GreyAlpha8
        } else {
            TexelStorage::Grey8
        }
    }

    /// The next mip level: halved in both directions (odd sizes round up,
    /// the edge texel repeating), each texel the mean of a 2x2 block, rounded
    /// to the nearest 8-bit code. With `srgb` (the decode table of
    /// `packed::textures::srgb_table`), RGB are averaged as linear values and
    /// encoded to the nearest code; alpha is always linear. Channels equal
    /// in every texel stay equal, so a grey image's levels are grey.
    pub fn mip_level(&self, srgb: Option<&[f32; 256]>) -> TextureImage {
        let (w, h) = (
            self.width.div_ceil(2).max(1),
            self.height.div_ceil(2).max(1),
        );
        let at = |x: u32, y: u32| {
            self.texels[(y.min(self.height - 1) * self.width + x.min(self.width - 1)) as usize]
        };
        let mut texels = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let block = [
                    at(2 * x, 2 * y),
                    at(2 * x + 1, 2 * y),
                    at(2 * x, 2 * y + 1),
                    at(2 * x + 1, 2 * y + 1),
                ];
                let mut out = 0u32;
                for c in 0..4 {
                    let codes = block.map(|t| (t >> (8 * c)) & 0xFF);
                    let code = match srgb {
                        Some(table) if c < 3 => {
                            let mean = codes.iter().map(|&k| table[k as usize]).sum::<f32>() / 4.0;
                            nearest_code(table, mean)
                        }
                        _ => (codes.iter().sum::<u32>() + 2) / 4,
                    };
                    out |= code << (8 * c);
                }
                texels.push(out);
            }
        }
        TextureImage {
            name: self.name.clone(),
            width: w,
            height: h,
            texels,
        }
    }

    /// Appends the image's texels to `out` as `storage` lays them out
    /// (`storage` must be one the image allows: see `storage`).
    pub fn push_words(&self, storage: TexelStorage, out: &mut Vec<u32>) {
        let per = storage.texels_per_word() as usize;
        out.reserve(self.texels.len().div_ceil(per));
        for chunk in self.texels.chunks(per) {
            let mut word = 0u32;
            for (k, &t) in chunk.iter().enumerate() {
                let [g, _, _, a] = t.to_le_bytes();
                word |= match storage {
                    TexelStorage::Rgba8 => t,
                    TexelStorage::Grey8 => (g as u32) << (8 * k),
                    TexelStorage::GreyAlpha8 => (g as u32 | (a as u32) << 8) << (16 * k),
                };
            }
            out.push(word);
        }
    }

    /// Halves the image in both directions (odd sizes round up), averaging
    /// each 2×2 block per channel as stored (a box filter; edge texels
    /// repeat): `mip_level` without an sRGB decode.
    pub fn downsample(&self) -> TextureImage {
        self.mip_level(None)
    }
}

/// glTF sampler wrap mode (the `WRAP_*` constants on the GPU).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    Repeat,
    ClampToEdge,
    MirroredRepeat,
}

/// How a material slot reads a texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into `Scene::images`.
    pub image: u32,
    /// Texture coordinate set: 0 (TEXCOORD_0) or 1 (TEXCOORD_1).
    pub texcoord: u32,
    /// `KHR_texture_transform` as rows: `s = row0 · (u, v, 1)`,
    /// `t = row1 · (u, v, 1)`.
    pub transform: [[f32; 3]; 2],
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    /// magFilter NEAREST (texels kept, no mip levels); otherwise bilinear,
    /// trilinear between mip levels where minified (vkpt builds its own
    /// levels whatever the minFilter says).
    pub nearest: bool,
}

impl TextureRef {
    pub const IDENTITY: [[f32; 3]; 2] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
}

/// The texture slots of a material; each multiplies the factor beside it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialTextures {
    /// RGB (sRGB) × base colour, A × alpha.
    pub base_color: Option<TextureRef>,
    /// G × roughness, B × metallic (linear).
    pub metallic_roughness: Option<TextureRef>,
    /// Tangent-space normal (linear), scaled by `normal_scale`.
    pub normal: Option<TextureRef>,
    /// RGB (sRGB) × emission.
    pub emissive: Option<TextureRef>,
    /// `KHR_materials_specular`: A × specular factor.
    pub specular: Option<TextureRef>,
    /// `KHR_materials_specular`: RGB (sRGB) × specular colour.
    pub specular_color: Option<TextureRef>,
    /// `KHR_materials_transmission`: R × transmission.
    pub transmission: Option<TextureRef>,
    /// `KHR_materials_clearcoat`: R × clearcoat, G × clearcoat roughness,
    /// and the coat's own tangent-space normal.
    pub clearcoat: Option<TextureRef>,
    pub clearcoat_roughness: Option<TextureRef>,
    pub clearcoat_normal: Option<TextureRef>,
    /// `KHR_materials_sheen`: RGB (sRGB) × sheen colour, A × sheen roughness.
    pub sheen_color: Option<TextureRef>,
    pub sheen_roughness: Option<TextureRef>,
    /// `KHR_materials_iridescence`: R × iridescence; G picks the thickness
    /// between its minimum and maximum.
    pub iridescence: Option<TextureRef>,
    pub iridescence_thickness: Option<TextureRef>,
    /// `KHR_materials_anisotropy`: RG direction in tangent space, B × strength.
    pub anisotropy: Option<TextureRef>,
    /// `KHR_materials_diffuse_transmission`: A × factor, RGB (sRGB) × colour.
    pub diffuse_transmission: Option<TextureRef>,
    pub diffuse_transmission_color: Option<TextureRef>,
    /// `KHR_materials_volume`: G × thickness (0 makes the point thin-walled).
    pub thickness: Option<TextureRef>,
}

impl MaterialTextures {
    pub fn any(&self) -> bool {
        self.slots().iter().any(Option::is_some)
    }

    /// The slots in `MaterialData` order.
    pub fn slots(&self) -> [Option<TextureRef>; 18] {
        [
            self.base_color,
            self.metallic_roughness,
            self.normal,
            self.emissive,
            self.specular,
            self.specular_color,
            self.transmission,
            self.clearcoat,
            self.clearcoat_roughness,
            self.clearcoat_normal,
            self.sheen_color,
            self.sheen_roughness,
            self.iridescence,
            self.iridescence_thickness,
            self.anisotropy,
            self.diffuse_transmission,
            self.diffuse_transmission_color,
            self.thickness,
        ]
    }
}

/// A triangle's texture coordinates (two sets) and tangents (xyz, world
/// space; w the bitangent sign), per vertex in the triangle's vertex order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Texcoords {
    pub uv: [[Vec2; 3]; 2],
    pub tangents: [Vec4; 3],
}
