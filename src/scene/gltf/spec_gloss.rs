//! The archived `KHR_materials_pbrSpecularGlossiness`, converted to the
//! metallic-roughness model vkpt renders, as Khronos' conversion notes do
//! (the glTF-Sample-Viewer / Microsoft glTF-Toolkit solver): roughness is
//! 1 - glossiness, and the metalness is the root of the quadratic that
//! splits the perceived brightness of the specular colour between a 4 %
//! dielectric F0 and a metal's base colour. The conversion is not linear,
//! so textured materials get new base-colour and metallic-roughness images
//! converted texel by texel.

use super::json::f32_array;
use crate::scene::texture::{TextureImage, TextureRef};
use crate::scene::{Material, MaterialKind, Scene};
use anyhow::{Context, Result, ensure};
use glam::{Vec3, Vec4};
use gltf::json::Value;

const DIELECTRIC_F0: f32 = 0.04;

/// A material's specular-glossiness parameters and its two textures.
#[derive(Clone, Debug)]
pub(super) struct SpecGloss {
    /// Linear diffuse colour and alpha.
    pub diffuse: Vec4,
    pub specular: Vec3,
    pub glossiness: f32,
    /// RGB (sRGB) × diffuse, A × alpha.
    pub diffuse_texture: Option<TextureRef>,
    /// RGB (sRGB) × specular, A × glossiness.
    pub specular_glossiness_texture: Option<TextureRef>,
}

/// The extension's factors (textures are filled in by the caller).
pub(super) fn read(ext: &Value, label: &str) -> Result<SpecGloss> {
    let what = |k: &str| format!("{label}: KHR_materials_pbrSpecularGlossiness {k}");
    let diffuse = f32_array::<4>(ext.get("diffuseFactor"), &what("diffuseFactor"))?
        .map_or(Vec4::ONE, Vec4::from);
    let specular = f32_array::<3>(ext.get("specularFactor"), &what("specularFactor"))?
        .map_or(Vec3::ONE, Vec3::from);
    let glossiness = match ext.get("glossinessFactor") {
        None => 1.0,
        Some(v) => v
            .as_f64()
            .map(|g| g as f32)
            .filter(|g| (0.0..=1.0).contains(g))
            .with_context(|| {
                format!(
                    "{} must be between 0 and 1, found {v}",
                    what("glossinessFactor")
                )
            })?,
    };
    ensure!(
        diffuse.min_element() >= 0.0 && diffuse.max_element() <= 1.0,
        "{} must lie between 0 and 1, found {diffuse}",
        what("diffuseFactor")
    );
    ensure!(
        specular.min_element() >= 0.0 && specular.max_element() <= 1.0,
        "{} must lie between 0 and 1, found {specular}",
        what("specularFactor")
    );
    Ok(SpecGloss {
        diffuse,
        specular,
        glossiness,
        diffuse_texture: None,
        specular_glossiness_texture: None,
    })
}

fn perceived_brightness(c: Vec3) -> f32 {
    (0.299 * c.x * c.x + 0.587 * c.y * c.y + 0.114 * c.z * c.z).sqrt()
}

/// Metalness from the perceived brightness of the diffuse and specular
/// colours: the root in [0, 1] of
/// `F0 m^2 + (d (1 - s_max) / (1 - F0) + s - 2 F0) m + (F0 - s) = 0`.
fn solve_metallic(diffuse: f32, specular: f32, one_minus_specular_strength: f32) -> f32 {
    if specular < DIELECTRIC_F0 {
        return 0.0;
    }
    let a = DIELECTRIC_F0;
    let b = diffuse * one_minus_specular_strength / (1.0 - DIELECTRIC_F0) + specular
        - 2.0 * DIELECTRIC_F0;
    let c = DIELECTRIC_F0 - specular;
    let d = (b * b - 4.0 * a * c).max(0.0);
    ((-b + d.sqrt()) / (2.0 * a)).clamp(0.0, 1.0)
}

/// (base colour, metallic, roughness) of linear `diffuse`, `specular` and
/// `glossiness`.
pub fn to_metallic_roughness(diffuse: Vec3, specular: Vec3, glossiness: f32) -> (Vec3, f32, f32) {
    let one_minus = 1.0 - specular.max_element();
    let metallic = solve_metallic(
        perceived_brightness(diffuse),
        perceived_brightness(specular),
        one_minus,
    );
    let from_diffuse = diffuse * (one_minus / (1.0 - DIELECTRIC_F0) / (1.0 - metallic).max(1e-4));
    let from_specular =
        (specular - Vec3::splat(DIELECTRIC_F0 * (1.0 - metallic))) / metallic.max(1e-4);
    let base = from_diffuse.lerp(from_specular, metallic * metallic);
    (
        base.clamp(Vec3::ZERO, Vec3::ONE),
        metallic,
        1.0 - glossiness,
    )
}

fn srgb_to_linear(c: u32) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(x: f32) -> u32 {
    let x = x.clamp(0.0, 1.0);
    let c = if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0).round() as u32
}

fn channel(t: u32, c: u32) -> u32 {
    (t >> (8 * c)) & 0xFF
}

/// The nearest texel of `img` to texel (x, y) of a `w`×`h` image.
fn texel_at(img: &TextureImage, x: u32, y: u32, w: u32, h: u32) -> u32 {
    let sx = ((x as u64 * img.width as u64) / w as u64) as u32;
    let sy = ((y as u64 * img.height as u64) / h as u64) as u32;
    img.texels[(sy.min(img.height - 1) * img.width + sx.min(img.width - 1)) as usize]
}

/// Sets `material` to the metallic-roughness equivalent of `sg`, adding
/// converted images to `images` when `sg` has textures. The two textures
/// must share texture coordinates and transform to be converted texel by
/// texel; otherwise the specular-glossiness texture is left out (returned
/// `false` for a note).
pub(super) fn apply(
    sg: &SpecGloss,
    material: &mut Material,
    images: &mut Vec<TextureImage>,
) -> bool {
    material.kind = MaterialKind::Gltf;
    material.transmission = 0.0;
    material.alpha = sg.diffuse.w;
    let mut sg_texture = sg.specular_glossiness_texture;
    let aligned = match (&sg.diffuse_texture, &sg_texture) {
        (Some(d), Some(s)) => {
            d.texcoord == s.texcoord
                && d.transform == s.transform
                && d.wrap_s == s.wrap_s
                && d.wrap_t == s.wrap_t
        }
        _ => true,
    };
    if !aligned {
        sg_texture = None;
    }
    let Some(layout) = sg.diffuse_texture.or(sg_texture) else {
        let (base, metallic, roughness) =
            to_metallic_roughness(sg.diffuse.truncate(), sg.specular, sg.glossiness);
        material.base_color = base;
        material.metallic = metallic;
        material.roughness = roughness;
        return aligned;
    };
    let shape = &images[layout.image as usize];
    let (w, h, name) = (shape.width, shape.height, shape.name.clone());
    let diffuse_img = sg.diffuse_texture.map(|t| images[t.image as usize].clone());
    let sg_img = sg_texture.map(|t| images[t.image as usize].clone());
    let mut base_texels = Vec::with_capacity((w * h) as usize);
    let mut mr_texels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let (mut diffuse, mut alpha) = (sg.diffuse.truncate(), 255);
            if let Some(img) = &diffuse_img {
                let t = texel_at(img, x, y, w, h);
                diffuse *= Vec3::new(
                    srgb_to_linear(channel(t, 0)),
                    srgb_to_linear(channel(t, 1)),
                    srgb_to_linear(channel(t, 2)),
                );
                alpha = channel(t, 3);
            }
            let (mut specular, mut gloss) = (sg.specular, sg.glossiness);
            if let Some(img) = &sg_img {
                let t = texel_at(img, x, y, w, h);
                specular *= Vec3::new(
                    srgb_to_linear(channel(t, 0)),
                    srgb_to_linear(channel(t, 1)),
                    srgb_to_linear(channel(t, 2)),
                );
                gloss *= channel(t, 3) as f32 / 255.0;
            }
            let (base, metallic, roughness) = to_metallic_roughness(diffuse, specular, gloss);
            base_texels.push(
                linear_to_srgb(base.x)
                    | linear_to_srgb(base.y) << 8
                    | linear_to_srgb(base.z) << 16
                    | alpha << 24,
            );
            let unit = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u32;
            mr_texels.push(unit(roughness) << 8 | unit(metallic) << 16 | 0xFF << 24);
        }
    }
    let mut add = |suffix: &str, texels: Vec<u32>| {
        images.push(TextureImage {
            name: format!("{name} ({suffix})"),
            width: w,
            height: h,
            texels,
        });
        TextureRef {
            image: images.len() as u32 - 1,
            ..layout
        }
    };
    material.textures.base_color = Some(add("converted base colour", base_texels));
    material.textures.metallic_roughness = Some(add("converted metallic-roughness", mr_texels));
    material.base_color = Vec3::ONE;
    material.metallic = 1.0;
    material.roughness = 1.0;
    aligned
}

/// Converts every specular-glossiness material of `scene` (by index), with
/// one note for those whose two textures could not be combined.
pub(super) fn convert_all(list: &[(usize, SpecGloss)], scene: &mut Scene, notes: &mut Vec<String>) {
    let mut unaligned = Vec::new();
    for (i, sg) in list {
        let material = &mut scene.materials[*i];
        if !apply(sg, material, &mut scene.images) {
            unaligned.push(material.name.clone());
        }
    }
    if !unaligned.is_empty() {
        notes.push(format!(
            "KHR_materials_pbrSpecularGlossiness on {}: diffuseTexture and specularGlossinessTexture use different texture coordinates or transforms, so only the diffuse texture is converted (the specular and glossiness factors are used)",
            super::notes::list(&unaligned)
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The forward map of the metallic-roughness model to
    /// specular-glossiness: both give the same F0 (0.04 for a dielectric,
    /// the base colour for a metal) and the same diffuse albedo, which is
    /// base (1 - F0)(1 - metallic) in one and diffuse (1 - max specular) in
    /// the other.
    fn from_metallic_roughness(base: Vec3, metallic: f32) -> (Vec3, Vec3) {
        let specular = Vec3::splat(DIELECTRIC_F0).lerp(base, metallic);
        let diffuse = base * (1.0 - DIELECTRIC_F0) * (1.0 - metallic)
            / (1.0 - specular.max_element()).max(1e-6);
        (diffuse, specular)
    }

    #[test]
    fn dielectrics_and_metals_convert_back_to_themselves() {
        for base in [
            Vec3::new(0.8, 0.2, 0.1),
            Vec3::splat(0.5),
            Vec3::new(0.05, 0.6, 0.9),
        ] {
            for metallic in [0.0, 1.0] {
                let (diffuse, specular) = from_metallic_roughness(base, metallic);
                let (b, m, r) = to_metallic_roughness(diffuse, specular, 0.7);
                assert!(
                    (m - metallic).abs() < 1e-3,
                    "{base} {metallic}: metallic {m}"
                );
                assert!(
                    (b - base).abs().max_element() < 2e-3,
                    "{base} {metallic}: base {b}"
                );
                assert!((r - 0.3).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn a_partly_metallic_grey_converts_back_to_itself() {
        // For a grey, perceived brightness is the value itself, so the
        // quadratic recovers the forward map's metalness and base colour.
        for metallic in [0.25f32, 0.5, 0.75] {
            let base = Vec3::splat(0.6);
            let (diffuse, specular) = from_metallic_roughness(base, metallic);
            let (b, m, _) = to_metallic_roughness(diffuse, specular, 1.0);
            assert!((m - metallic).abs() < 1e-3, "{metallic}: metallic {m}");
            assert!(
                (b - base).abs().max_element() < 1e-3,
                "{metallic}: base {b}"
            );
        }
    }

    #[test]
    fn textures_are_converted_texel_by_texel() {
        let texel = |r: u32, g: u32, b: u32, a: u32| r | g << 8 | b << 16 | a << 24;
        let mut images = vec![
            TextureImage {
                name: "diffuse".into(),
                width: 2,
                height: 1,
                texels: vec![texel(200, 40, 20, 255), texel(0, 0, 0, 128)],
            },
            TextureImage {
                name: "specgloss".into(),
                width: 2,
                height: 1,
                texels: vec![texel(50, 50, 50, 255), texel(230, 180, 60, 51)],
            },
        ];
        let reference = |image: u32| TextureRef {
            image,
            texcoord: 0,
            transform: TextureRef::IDENTITY,
            wrap_s: Default::default(),
            wrap_t: Default::default(),
            nearest: false,
        };
        let sg = SpecGloss {
            diffuse: Vec4::ONE,
            specular: Vec3::ONE,
            glossiness: 1.0,
            diffuse_texture: Some(reference(0)),
            specular_glossiness_texture: Some(reference(1)),
        };
        let mut m = Material::lambert("m", Vec3::ONE);
        assert!(apply(&sg, &mut m, &mut images));
        let base = &images[m.textures.base_color.unwrap().image as usize];
        let mr = &images[m.textures.metallic_roughness.unwrap().image as usize];
        for x in 0..2 {
            let d = images[0].texels[x];
            let s = images[1].texels[x];
            let lin = |t: u32| {
                Vec3::new(
                    srgb_to_linear(channel(t, 0)),
                    srgb_to_linear(channel(t, 1)),
                    srgb_to_linear(channel(t, 2)),
                )
            };
            let (b, metal, rough) =
                to_metallic_roughness(lin(d), lin(s), channel(s, 3) as f32 / 255.0);
            let got = lin(base.texels[x]);
            assert!(
                (got - b).abs().max_element() < 0.01,
                "texel {x}: {got} vs {b}"
            );
            assert_eq!(channel(base.texels[x], 3), channel(d, 3), "alpha");
            assert!((channel(mr.texels[x], 1) as f32 / 255.0 - rough).abs() < 0.003);
            assert!((channel(mr.texels[x], 2) as f32 / 255.0 - metal).abs() < 0.003);
        }
        // Texel 0 is a dielectric (F0 about 0.04), texel 1 a coloured metal.
        assert_eq!(channel(mr.texels[0], 2), 0);
        assert!(channel(mr.texels[1], 2) > 200);
        assert_eq!(
            (m.metallic, m.roughness, m.base_color),
            (1.0, 1.0, Vec3::ONE)
        );
    }
}
