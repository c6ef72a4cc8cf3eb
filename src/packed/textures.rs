//! The scene's textures flattened for the kernels (`textures.glsl`): the
//! texture table `MaterialData`'s slots index, one texel buffer (the sRGB
//! decode table, then every image's RGBA8 texels) and each triangle's
//! texture coordinates and tangents in BVH order. The CPU reference reads the
//! same arrays (`cpu/textures.rs`), so both back ends filter identical data.

use crate::constants::{
    INV_255, NO_TEXTURE, SRGB_TABLE_WORDS, TEXEL_COORD_LIMIT, TEXTURE_NEAREST, TEXTURE_TEXCOORD_1,
    TEXTURE_WRAP_T_SHIFT, WRAP_CLAMP_TO_EDGE, WRAP_MIRRORED_REPEAT, WRAP_REPEAT,
};
use crate::packed::layout::{MaterialData, TextureInfo, TriangleTexcoords};
use crate::scene::{Scene, TextureRef, Wrap};
use glam::{Vec2, Vec3, Vec4};

#[derive(Clone, Debug, Default)]
pub struct PackedTextures {
    pub textures: Vec<TextureInfo>,
    /// `SRGB_TABLE_WORDS` f32 bit patterns, then the images' texels.
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
    let mut offsets = Vec::with_capacity(scene.images.len());
    for image in &scene.images {
        offsets.push(out.texels.len() as u32);
        out.texels.extend_from_slice(&image.texels);
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
                | if r.nearest { TEXTURE_NEAREST } else { 0 }
                | if r.texcoord == 1 {
                    TEXTURE_TEXCOORD_1
                } else {
                    0
                },
            width: image.width,
            height: image.height,
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
            scene.texcoords.len() == scene.triangles.len(),
            "{}: {} triangles but {} texture coordinate records",
            scene.source.display(),
            scene.triangles.len(),
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

fn fetch_texel(tex: &PackedTextures, ti: &TextureInfo, x: i32, y: i32, srgb: bool) -> Vec4 {
    let i = ti.offset + y as u32 * ti.width + x as u32;
    decode_texel(tex, texel_word(tex, i), srgb)
}

/// GLSL's `mix`.
fn mix(a: Vec4, b: Vec4, t: f32) -> Vec4 {
    a * (1.0 - t) + b * t
}

/// Texture table row `t` at texture coordinates `uv0` / `uv1`.
pub fn texture_sample(tex: &PackedTextures, t: u32, uv0: Vec2, uv1: Vec2, srgb: bool) -> Vec4 {
    let ti = &tex.textures[t as usize];
    let uv = if ti.flags & TEXTURE_TEXCOORD_1 != 0 {
        uv1
    } else {
        uv0
    };
    let uvh = uv.extend(1.0);
    let (w, h) = (ti.width as i32, ti.height as i32);
    let x = (Vec3::from(ti.transform_s).dot(uvh) * w as f32)
        .clamp(-TEXEL_COORD_LIMIT, TEXEL_COORD_LIMIT);
    let y = (Vec3::from(ti.transform_t).dot(uvh) * h as f32)
        .clamp(-TEXEL_COORD_LIMIT, TEXEL_COORD_LIMIT);
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
            let c = texture_sample(tex, t, uv0, uv1, true);
            sum += 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
        }
    }
    sum / (N * N) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

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
