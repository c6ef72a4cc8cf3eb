//! The scene's textures flattened for the kernels (`textures.glsl`): the
//! texture table `MaterialData`'s slots index, one texel buffer (the sRGB
//! decode table, then every image's texels: RGBA8 words, or one byte per
//! texel for grey images and two for grey with alpha) and each triangle's
//! texture coordinates and tangents in BVH order. The CPU reference reads the
//! same arrays (`cpu/textures.rs`), so both back ends filter identical data.

use crate::constants::{
    INV_255, NO_FOOTPRINT, NO_TEXTURE, SRGB_TABLE_WORDS, TEXEL_COORD_LIMIT, TEXTURE_GREY,
    TEXTURE_GREY_ALPHA, TEXTURE_NEAREST, TEXTURE_TEXCOORD_1, TEXTURE_WRAP_T_SHIFT,
    WRAP_CLAMP_TO_EDGE, WRAP_MIRRORED_REPEAT, WRAP_REPEAT,
};
use crate::packed::layout::{MaterialData, TextureInfo, TriangleTexcoords};
use crate::scene::{Scene, TexelStorage, TextureRef, Wrap};
use glam::{Vec2, Vec3, Vec4};

/// A footprint that samples the image itself (`texture_sample`).
pub const NO_FOOTPRINT_VEC: Vec3 = Vec3::new(NO_FOOTPRINT, 0.0, 0.0);

#[derive(Clone, Debug, Default)]
pub struct PackedTextures {
    pub textures: Vec<TextureInfo>,
    /// `SRGB_TABLE_WORDS` f32 bit patterns, then the images' texels, each
    /// image as its `TexelStorage` lays it out.
    pub texels: Vec<u32>,
    /// Empty when the scene has no textures.
    pub tri_texcoords: Vec<TriangleTexcoords>,
}

/// The sRGB transfer function (IEC 61966-2-1) for each 8-bit code, in f64
/// and rounded once to f32.
pub fn srgb_table() -> [f32; 256] {
    std::array::from_fn(|c| {
        let v = c as f64 / 255.0;
        let linear = if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        };
        linear as f32
    })
}

fn storage_bits(s: TexelStorage) -> u32 {
    match s {
        TexelStorage::Rgba8 => 0,
        TexelStorage::Grey8 => TEXTURE_GREY,
        TexelStorage::GreyAlpha8 => TEXTURE_GREY_ALPHA,
    }
}

fn wrap_bits(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => WRAP_REPEAT,
        Wrap::ClampToEdge => WRAP_CLAMP_TO_EDGE,
        Wrap::MirroredRepeat => WRAP_MIRRORED_REPEAT,
    }
}

/// Fills the texture slots of `materials` (same order as `scene.materials`)
/// and returns the arrays they index. `order` is the BVH's triangle order.
pub fn pack_textures(
    scene: &Scene,
    order: &[u32],
    materials: &mut [MaterialData],
) -> anyhow::Result<PackedTextures> {
    let mut out = PackedTextures {
        texels: srgb_table().iter().map(|f| f.to_bits()).collect(),
        ..Default::default()
    };
    debug_assert_eq!(out.texels.len(), SRGB_TABLE_WORDS as usize);
    // Mip levels where they may pay: images a slot samples with a pixel's
    // footprint (`MIP_SLOTS`) through a bilinear sampler, averaged in linear
    // space where a slot reads them as sRGB.
    let mut mipped = vec![false; scene.images.len()];
    let mut srgb = vec![false; scene.images.len()];
    for m in &scene.materials {
        let t = &m.textures;
        let mip_slots = [
            &t.base_color,
            &t.metallic_roughness,
            &t.specular,
            &t.specular_color,
            &t.transmission,
            &t.clearcoat,
            &t.clearcoat_roughness,
            &t.sheen_color,
            &t.sheen_roughness,
            &t.iridescence,
            &t.iridescence_thickness,
            &t.anisotropy,
            &t.diffuse_transmission,
            &t.diffuse_transmission_color,
            &t.thickness,
        ];
        for r in mip_slots.into_iter().flatten() {
            mipped[r.image as usize] |= !r.nearest;
        }
        let srgb_slots = [
            &t.base_color,
            &t.specular_color,
            &t.sheen_color,
            &t.diffuse_transmission_color,
        ];
        for r in srgb_slots.into_iter().flatten() {
            srgb[r.image as usize] = true;
        }
    }
    let table = srgb_table();
    let mut offsets = Vec::with_capacity(scene.images.len());
    let mut storages = Vec::with_capacity(scene.images.len());
    let mut levels = Vec::with_capacity(scene.images.len());
    for (k, image) in scene.images.iter().enumerate() {
        offsets.push(out.texels.len() as u32);
        let storage = image.storage();
        storages.push(storage);
        image.push_words(storage, &mut out.texels);
        let mut n = 1;
        if mipped[k] && (image.width > 1 || image.height > 1) {
            let mut level = image.mip_level(srgb[k].then_some(&table));
            level.push_words(storage, &mut out.texels);
            n += 1;
            while level.width > 1 || level.height > 1 {
                level = level.mip_level(srgb[k].then_some(&table));
                level.push_words(storage, &mut out.texels);
                n += 1;
            }
        }
        levels.push(n);
    }
    let mut entry = |r: &Option<TextureRef>| -> u32 {
        let Some(r) = r else { return NO_TEXTURE };
        let image = &scene.images[r.image as usize];
        let info = TextureInfo {
            transform_s: r.transform[0],
            offset: offsets[r.image as usize],
            transform_t: r.transform[1],
            flags: wrap_bits(r.wrap_s)
                | wrap_bits(r.wrap_t) << TEXTURE_WRAP_T_SHIFT
                | storage_bits(storages[r.image as usize])
                | if r.nearest { TEXTURE_NEAREST } else { 0 }
                | if r.texcoord == 1 {
                    TEXTURE_TEXCOORD_1
                } else {
                    0
                },
            width: image.width,
            height: image.height,
            levels: if r.nearest {
                1
            } else {
                levels[r.image as usize]
            },
            ..Default::default()
        };
        match out.textures.iter().position(|t| *t == info) {
            Some(i) => i as u32,
            None => {
                out.textures.push(info);
                out.textures.len() as u32 - 1
            }
        }
    };
    for (m, d) in scene.materials.iter().zip(materials.iter_mut()) {
        let t = &m.textures;
        d.base_color_texture = entry(&t.base_color);
        d.metallic_roughness_texture = entry(&t.metallic_roughness);
        d.normal_texture = entry(&t.normal);
        d.emissive_texture = entry(&t.emissive);
        d.specular_texture = entry(&t.specular);
        d.specular_color_texture = entry(&t.specular_color);
        d.transmission_texture = entry(&t.transmission);
        d.clearcoat_texture = entry(&t.clearcoat);
        d.clearcoat_roughness_texture = entry(&t.clearcoat_roughness);
        d.clearcoat_normal_texture = entry(&t.clearcoat_normal);
        d.sheen_color_texture = entry(&t.sheen_color);
        d.sheen_roughness_texture = entry(&t.sheen_roughness);
        d.iridescence_texture = entry(&t.iridescence);
        d.iridescence_thickness_texture = entry(&t.iridescence_thickness);
        d.anisotropy_texture = entry(&t.anisotropy);
        d.diffuse_transmission_texture = entry(&t.diffuse_transmission);
        d.diffuse_transmission_color_texture = entry(&t.diffuse_transmission_color);
        d.thickness_texture = entry(&t.thickness);
    }
    if !scene.texcoords.is_empty() {
        anyhow::ensure!(
            scene.texcoords.len() == order.len(),
            "{}: {} triangles but {} texture coordinate records",
            scene.source.display(),
            order.len(),
            scene.texcoords.len()
        );
        out.tri_texcoords = order
            .iter()
            .map(|&i| {
                let t = &scene.texcoords[i as usize];
                let [a, b] = t.uv;
                TriangleTexcoords {
                    uv0_01: [a[0].x, a[0].y, a[1].x, a[1].y],
                    uv0_2_uv1_0: [a[2].x, a[2].y, b[0].x, b[0].y],
                    uv1_12: [b[1].x, b[1].y, b[2].x, b[2].y],
                    tangent0: t.tangents[0].into(),
                    tangent1: t.tangents[1].into(),
                    tangent2: t.tangents[2].into(),
                }
            })
            .collect();
    }
    Ok(out)
}

impl PackedTextures {
    /// The same textures with every image stored as RGBA8 words, as packing
    /// stored them before grey storage: tests render a scene both ways and
    /// expect the same bits.
    pub fn widened_to_rgba8(&self) -> PackedTextures {
        let mut out = PackedTextures {
            textures: self.textures.clone(),
            texels: self.texels[..SRGB_TABLE_WORDS as usize].to_vec(),
            tri_texcoords: self.tri_texcoords.clone(),
        };
        let mut moved = std::collections::HashMap::new();
        for t in &mut out.textures {
            let offset = *moved.entry(t.offset).or_insert_with(|| {
                let start = out.texels.len() as u32;
                for k in 0..t.levels {
                    let level = texture_level(t, k);
                    let texels = level.width as u64 * level.height as u64;
                    out.texels
                        .extend((0..texels as u32).map(|i| texel_rgba8(self, &level, i)));
                }
                start
            });
            t.offset = offset;
            t.flags &= !(TEXTURE_GREY | TEXTURE_GREY_ALPHA);
        }
        out
    }
}

// Reading the packed texel format: the first half of
// `shaders/common/textures.glsl` (same names and operations).

fn texel_word(tex: &PackedTextures, i: u32) -> u32 {
    tex.texels[i as usize]
}

/// `i mod n` in `[0, n)` (GLSL's `floor_mod`).
pub fn floor_mod(i: i32, n: i32) -> i32 {
    i.rem_euclid(n)
}

/// A texel coordinate wrapped into `[0, n)` by a `WRAP_*` mode.
pub fn wrap_texel(i: i32, n: i32, mode: u32) -> i32 {
    if mode == WRAP_CLAMP_TO_EDGE {
        return i.clamp(0, n - 1);
    }
    if mode == WRAP_MIRRORED_REPEAT {
        let m = floor_mod(i, 2 * n);
        return if m < n { m } else { 2 * n - 1 - m };
    }
    floor_mod(i, n)
}

/// An RGBA8 texel as floats; with `srgb`, RGB through the sRGB table.
pub fn decode_texel(tex: &PackedTextures, w: u32, srgb: bool) -> Vec4 {
    let c = [w & 0xFF, (w >> 8) & 0xFF, (w >> 16) & 0xFF, w >> 24];
    let mut v = Vec4::new(c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32) * INV_255;
    if srgb {
        let lut = |k: u32| f32::from_bits(texel_word(tex, k));
        v = Vec4::new(lut(c[0]), lut(c[1]), lut(c[2]), v.w);
    }
    v
}

/// Texel `i` (row-major) of `ti` as its RGBA8 word, whatever its storage:
/// a grey byte `g` reads as (g, g, g, 255), grey and alpha as (g, g, g, a).
pub fn texel_rgba8(tex: &PackedTextures, ti: &TextureInfo, i: u32) -> u32 {
    if ti.flags & TEXTURE_GREY != 0 {
        let g = (texel_word(tex, ti.offset + (i >> 2)) >> (8 * (i & 3))) & 0xFF;
        return (g * 0x010101) | 0xFF000000;
    }
    if ti.flags & TEXTURE_GREY_ALPHA != 0 {
        let ga = (texel_word(tex, ti.offset + (i >> 1)) >> (16 * (i & 1))) & 0xFFFF;
        return ((ga & 0xFF) * 0x010101) | ((ga >> 8) << 24);
    }
    texel_word(tex, ti.offset + i)
}

/// Words of texel buffer `texels` texels of `ti`'s storage take.
pub fn texel_storage_words(ti: &TextureInfo, texels: u32) -> u32 {
    let per = if ti.flags & TEXTURE_GREY != 0 {
        4
    } else if ti.flags & TEXTURE_GREY_ALPHA != 0 {
        2
    } else {
        1
    };
    texels.div_ceil(per)
}

/// `ti` at mip level `level`: its first word, width and height (levels
/// follow the image, each halved with odd sizes rounded up, each starting
/// on a word).
pub fn texture_level(ti: &TextureInfo, level: u32) -> TextureInfo {
    let mut l = *ti;
    for _ in 0..level {
        l.offset += texel_storage_words(&l, l.width * l.height);
        l.width = l.width.div_ceil(2);
        l.height = l.height.div_ceil(2);
    }
    l
}

fn fetch_texel(tex: &PackedTextures, ti: &TextureInfo, x: i32, y: i32, srgb: bool) -> Vec4 {
    let i = y as u32 * ti.width + x as u32;
    decode_texel(tex, texel_rgba8(tex, ti, i), srgb)
}

/// GLSL's `mix`.
fn mix(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

/// The mip level (fractional) at which texture `ti` is sampled for a hit
/// whose `footprint` is `texture_footprint`'s: log2 of texels per pixel
/// footprint width. 0 (the image itself) without mip levels or footprint.
pub fn texture_lod(ti: &TextureInfo, footprint: Vec3) -> f32 {
    if ti.levels <= 1 || !(footprint.x > NO_FOOTPRINT) {
        return 0.0;
    }
    let uv = if ti.flags & TEXTURE_TEXCOORD_1 != 0 {
        footprint.z
    } else {
        footprint.y
    };
    // KHR_texture_transform scales texture-space areas by its determinant.
    let det = (ti.transform_s[0] * ti.transform_t[1] - ti.transform_s[1] * ti.transform_t[0]).abs();
    footprint.x + uv + 0.5 * (ti.width as f32 * ti.height as f32 * det).log2()
}

/// Texture row `ti`'s texture-space point for texture coordinates `uv0` /
/// `uv1`: the row picks the set and applies its KHR_texture_transform.
pub fn texture_st(ti: &TextureInfo, uv0: Vec2, uv1: Vec2) -> Vec2 {
    let uv = if ti.flags & TEXTURE_TEXCOORD_1 != 0 {
        uv1
    } else {
        uv0
    };
    let uvh = uv.extend(1.0);
    Vec2::new(
        Vec3::from(ti.transform_s).dot(uvh),
        Vec3::from(ti.transform_t).dot(uvh),
    )
}

/// Texture table row `t` at texture coordinates `uv0` / `uv1`, the image
/// itself (no mip level): emission, normal maps and alpha tests.
pub fn texture_sample_image(
    tex: &PackedTextures,
    t: u32,
    uv0: Vec2,
    uv1: Vec2,
    srgb: bool,
) -> Vec4 {
    let ti = &tex.textures[t as usize];
    sample_level(tex, ti, texture_st(ti, uv0, uv1), srgb)
}

/// Texture table row `t` at texture coordinates `uv0` / `uv1`, trilinear
/// between the mip levels `footprint` (`texture_footprint`; `NO_FOOTPRINT`
/// in x for the image itself) spans. (The GLSL twin reads its one or two
/// levels in a loop, to keep lavapipe's inlined kernel small; the
/// arithmetic is the same.)
pub fn texture_sample(
    tex: &PackedTextures,
    t: u32,
    uv0: Vec2,
    uv1: Vec2,
    srgb: bool,
    footprint: Vec3,
) -> Vec4 {
    let ti = &tex.textures[t as usize];
    let st = texture_st(ti, uv0, uv1);
    let lod = texture_lod(ti, footprint);
    // Only where it pays: a footprint under one texel reads the image itself.
    if !(lod > 0.0) {
        return sample_level(tex, ti, st, srgb);
    }
    let top = (ti.levels - 1) as f32;
    if lod >= top {
        return sample_level(tex, &texture_level(ti, ti.levels - 1), st, srgb);
    }
    let k = lod.floor();
    let fine = texture_level(ti, k as u32);
    let coarse = texture_level(&fine, 1);
    mix(
        sample_level(tex, &fine, st, srgb),
        sample_level(tex, &coarse, st, srgb),
        lod - k,
    )
}

/// One level `ti` (`texture_level`) at texture-space point `st`: nearest or
/// bilinear with the sampler's wrap modes.
fn sample_level(tex: &PackedTextures, ti: &TextureInfo, st: Vec2, srgb: bool) -> Vec4 {
    let (w, h) = (ti.width as i32, ti.height as i32);
    let x = (st.x * w as f32).clamp(-TEXEL_COORD_LIMIT, TEXEL_COORD_LIMIT);
    let y = (st.y * h as f32).clamp(-TEXEL_COORD_LIMIT, TEXEL_COORD_LIMIT);
    let wrap_s = ti.flags & 3;
    let wrap_t = (ti.flags >> TEXTURE_WRAP_T_SHIFT) & 3;
    if ti.flags & TEXTURE_NEAREST != 0 {
        return fetch_texel(
            tex,
            ti,
            wrap_texel(x.floor() as i32, w, wrap_s),
            wrap_texel(y.floor() as i32, h, wrap_t),
            srgb,
        );
    }
    let (x, y) = (x - 0.5, y - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let xa = wrap_texel(x0 as i32, w, wrap_s);
    let xb = wrap_texel(x0 as i32 + 1, w, wrap_s);
    let ya = wrap_texel(y0 as i32, h, wrap_t);
    let yb = wrap_texel(y0 as i32 + 1, h, wrap_t);
    let top = mix(
        fetch_texel(tex, ti, xa, ya, srgb),
        fetch_texel(tex, ti, xb, ya, srgb),
        fx,
    );
    let bottom = mix(
        fetch_texel(tex, ti, xa, yb, srgb),
        fetch_texel(tex, ti, xb, yb, srgb),
        fx,
    );
    mix(top, bottom, fy)
}

/// Texture coordinates (sets 0 and 1) at barycentrics `b12` of `tri`.
pub fn fetch_triangle_uvs(tex: &PackedTextures, tri: u32, b12: Vec2) -> (Vec2, Vec2) {
    let tc = &tex.tri_texcoords[tri as usize];
    let b0 = 1.0 - b12.x - b12.y;
    let v = |a: [f32; 4], hi: bool| {
        if hi {
            Vec2::new(a[2], a[3])
        } else {
            Vec2::new(a[0], a[1])
        }
    };
    let uv0 =
        b0 * v(tc.uv0_01, false) + b12.x * v(tc.uv0_01, true) + b12.y * v(tc.uv0_2_uv1_0, false);
    let uv1 =
        b0 * v(tc.uv0_2_uv1_0, true) + b12.x * v(tc.uv1_12, false) + b12.y * v(tc.uv1_12, true);
    (uv0, uv1)
}

/// Mean luminance of emissive texture `t` over triangle `tri` (BVH order),
/// from 16 stratified points: light selection scales the triangle's power
/// by it. Where it misses a small lit spot the triangle gets pmf 0, and MIS
/// then gives BSDF sampling full weight there: unbiased either way.
pub fn emissive_texture_mean(tex: &PackedTextures, t: u32, tri: u32) -> f32 {
    const N: u32 = 4;
    let mut sum = 0.0;
    for i in 0..N {
        for j in 0..N {
            let u = Vec2::new((i as f32 + 0.5) / N as f32, (j as f32 + 0.5) / N as f32);
            // Uniform on the triangle, as sampling.glsl's sample_uniform_triangle.
            let su = u.x.sqrt();
            let b12 = Vec2::new(1.0 - su, u.y * su);
            let (uv0, uv1) = fetch_triangle_uvs(tex, tri, b12);
            let c = texture_sample_image(tex, t, uv0, uv1, true);
            sum += 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
        }
    }
    sum / (N * N) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::scene::TextureImage;

    fn image(width: u32, height: u32, texel: impl Fn(u32) -> u32) -> TextureImage {
        TextureImage {
            name: "t".into(),
            width,
            height,
            texels: (0..width * height).map(texel).collect(),
        }
    }

    /// Packs `images` one after another as `pack_textures` does.
    fn packed(images: &[TextureImage]) -> PackedTextures {
        let mut out = PackedTextures {
            texels: srgb_table().iter().map(|f| f.to_bits()).collect(),
            ..Default::default()
        };
        for image in images {
            let storage = image.storage();
            out.textures.push(TextureInfo {
                offset: out.texels.len() as u32,
                flags: storage_bits(storage),
                width: image.width,
                height: image.height,
                levels: 1,
                ..Default::default()
            });
            image.push_words(storage, &mut out.texels);
        }
        out
    }

    #[test]
    fn grey_images_are_stored_compactly_and_read_back_every_texel_unchanged() {
        let grey = |i: u32| ((i * 37 % 256) * 0x010101) | 0xFF00_0000;
        let grey_alpha = |i: u32| ((i * 11 % 256) * 0x010101) | ((i * 53 % 256) << 24);
        let colour = |i: u32| i * 0x0102_0305;
        // Odd sizes: the last word of each compact image is padded.
        let images = [
            image(5, 3, grey),
            image(3, 3, grey_alpha),
            image(7, 1, colour),
            image(1, 1, grey),
        ];
        let storages: Vec<_> = images.iter().map(|i| i.storage()).collect();
        assert_eq!(
            storages,
            [
                TexelStorage::Grey8,
                TexelStorage::GreyAlpha8,
                TexelStorage::Rgba8,
                TexelStorage::Grey8
            ]
        );
        let tex = packed(&images);
        assert_eq!(
            tex.texels.len() - SRGB_TABLE_WORDS as usize,
            15usize.div_ceil(4) + 9usize.div_ceil(2) + 7 + 1
        );
        for (image, ti) in images.iter().zip(&tex.textures) {
            for (i, &t) in image.texels.iter().enumerate() {
                assert_eq!(texel_rgba8(&tex, ti, i as u32), t, "texel {i} of {ti:?}");
            }
        }
        let wide = tex.widened_to_rgba8();
        assert_eq!(
            wide.texels.len() - SRGB_TABLE_WORDS as usize,
            15 + 9 + 7 + 1
        );
        for (image, ti) in images.iter().zip(&wide.textures) {
            assert_eq!(ti.flags & (TEXTURE_GREY | TEXTURE_GREY_ALPHA), 0);
            let start = ti.offset as usize;
            assert_eq!(
                &wide.texels[start..start + image.texels.len()],
                image.texels
            );
        }
    }

    #[test]
    fn mip_levels_average_2x2_blocks_in_linear_space_where_read_as_srgb() {
        use crate::scene::mip_levels;
        assert_eq!(mip_levels(5, 3), 4); // 5x3, 3x2, 2x1, 1x1
        assert_eq!(mip_levels(1, 1), 1);
        assert_eq!(mip_levels(4096, 1), 13);
        // Black and white: linear mean 0.5, sRGB code 188; alpha 0 and 255
        // average to 128 (linear, rounded to nearest).
        let img = image(2, 2, |i| if i % 3 == 0 { 0xFFFF_FFFF } else { 0 });
        let table = srgb_table();
        let srgb = img.mip_level(Some(&table));
        assert_eq!((srgb.width, srgb.height), (1, 1));
        assert_eq!(srgb.texels[0], 0x80BC_BCBC);
        assert!((table[0xBC] - 0.5).abs() < (table[0xBC] - table[0xBB]).abs());
        assert_eq!(img.mip_level(None).texels[0], 0x8080_8080);
        // Odd sizes round up, the edge texel repeating; grey stays grey.
        let grey = image(5, 3, |i| ((i * 17 % 256) * 0x010101) | 0xFF00_0000);
        let mut level = grey.mip_level(Some(&table));
        assert_eq!((level.width, level.height), (3, 2));
        for _ in 0..2 {
            assert_eq!(level.storage(), TexelStorage::Grey8);
            level = level.mip_level(Some(&table));
        }
        assert_eq!((level.width, level.height), (1, 1));
    }

    #[test]
    fn each_mip_level_is_found_after_the_last_and_sampled_by_its_lod() {
        use crate::scene::mip_levels;
        for texel in [
            (|i: u32| ((i * 29 % 256) * 0x010101) | 0xFF00_0000) as fn(u32) -> u32,
            |i: u32| i.wrapping_mul(0x9E37_79B9),
        ] {
            let base = image(7, 5, texel);
            let mut levels = vec![base.clone()];
            while levels.last().unwrap().width > 1 || levels.last().unwrap().height > 1 {
                let next = levels.last().unwrap().mip_level(None);
                levels.push(next);
            }
            assert_eq!(levels.len() as u32, mip_levels(7, 5));
            let mut tex = packed(std::slice::from_ref(&base));
            let storage = base.storage();
            for l in &levels[1..] {
                l.push_words(storage, &mut tex.texels);
            }
            let ti = TextureInfo {
                levels: levels.len() as u32,
                transform_s: [1.0, 0.0, 0.0],
                transform_t: [0.0, 1.0, 0.0],
                ..tex.textures[0]
            };
            tex.textures[0] = ti;
            for (k, l) in levels.iter().enumerate() {
                let at = texture_level(&ti, k as u32);
                assert_eq!((at.width, at.height), (l.width, l.height));
                for (i, &t) in l.texels.iter().enumerate() {
                    assert_eq!(texel_rgba8(&tex, &at, i as u32), t, "level {k} texel {i}");
                }
            }
            let wide = tex.widened_to_rgba8();
            let uv = Vec2::new(0.3, 0.6);
            // A footprint of 2^lod texels of the 7x5 image (uv area 1, world
            // area 1, head-on): lod = x + 0.5 log2(35).
            let at_lod = |t: &PackedTextures, lod: f32| {
                let fp = Vec3::new(lod - 0.5 * 35f32.log2(), 0.0, 0.0);
                texture_sample(t, 0, uv, uv, true, fp)
            };
            let level = |t: &PackedTextures, k: u32| {
                sample_level(t, &texture_level(&t.textures[0], k), uv, true)
            };
            for t in [&tex, &wide] {
                assert_eq!(
                    at_lod(t, -3.0),
                    texture_sample(t, 0, uv, uv, true, NO_FOOTPRINT_VEC)
                );
                assert_eq!(at_lod(t, -3.0), level(t, 0));
                let (a, b) = (level(t, 1), level(t, 2));
                assert!(
                    (at_lod(t, 1.25) - (a * 0.75 + b * 0.25))
                        .abs()
                        .max_element()
                        < 1e-6
                );
                assert_eq!(at_lod(t, 9.0), level(t, 3));
            }
            assert_eq!(at_lod(&tex, 1.25), at_lod(&wide, 1.25));
        }
    }

    #[test]
    fn srgb_table_matches_the_standard_at_known_codes() {
        let t = srgb_table();
        assert_eq!(t[0], 0.0);
        assert_eq!(t[255], 1.0);
        // Code 10 is on the linear segment: 10 / 255 / 12.92.
        assert!((t[10] - (10.0 / 255.0 / 12.92)).abs() < 1e-9);
        // Mid grey: sRGB 128 is linear 0.2158605.
        assert!((t[128] - 0.215_860_5).abs() < 1e-6, "{}", t[128]);
        assert!(t.windows(2).all(|w| w[0] < w[1]));
    }
}
