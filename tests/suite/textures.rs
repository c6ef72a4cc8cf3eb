//! Textures on both back ends: `scenes/textured.gltf` (sRGB base colour with
//! KHR_texture_transform, TEXCOORD_1 with mirrored-repeat and clamp wraps
//! and nearest filtering, a normal map with generated tangents, an emissive
//! texture, an alpha-MASK cutout) renders the same on the GPU and the CPU
//! reference, pixel by pixel with the same seed and statistically with
//! independent seeds; the comparison sees a wrong wrap mode or a missing
//! sRGB decode on the GPU side alone; and an alpha-masked quad lets exactly
//! as much light through as geometry with real holes.

use crate::common;

use common::*;
use vkpt::constants::{TEXTURE_WRAP_T_SHIFT, WRAP_MIRRORED_REPEAT, WRAP_REPEAT};
use vkpt::image::compare::compare;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{Scene, Wrap};

const ALPHA: f64 = 0.01;
const TEXTURED: &str = "scenes/textured.gltf";

fn settings(seed: u32, size: u32, spp: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        spp,
        max_depth: None,
        seed,
        camera: 0,
        ..Default::default()
    }
}

#[test]
fn textured_scene_loads_every_texture_feature() {
    let scene = Scene::load(&repo_path(TEXTURED)).expect("loads");
    let by_name = |n: &str| scene.materials.iter().find(|m| m.name == n).expect(n);
    assert_eq!(scene.images.len(), 5);
    let floor = by_name("checker floor")
        .textures
        .base_color
        .expect("floor texture");
    // scale 3, rotation 0.3, offset (0.1, 0): rows (3 cos, -3 sin, 0.1), (3 sin, 3 cos, 0).
    let (s, c) = 0.3f32.sin_cos();
    let expected = [[3.0 * c, -3.0 * s, 0.1], [3.0 * s, 3.0 * c, 0.0]];
    for (row, want) in floor.transform.iter().zip(expected) {
        for (x, y) in row.iter().zip(want) {
            assert!((x - y).abs() < 1e-6, "{:?}", floor.transform);
        }
    }
    assert!(!floor.nearest);
    let wall = by_name("letter wall")
        .textures
        .base_color
        .expect("wall texture");
    assert_eq!(
        (wall.texcoord, wall.wrap_s, wall.wrap_t, wall.nearest),
        (1, Wrap::MirroredRepeat, Wrap::ClampToEdge, true)
    );
    assert!(by_name("bumpy panel").textures.normal.is_some());
    assert!(by_name("striped light").textures.emissive.is_some());
    assert_eq!(
        by_name("cutout grid").alpha_mode,
        vkpt::scene::AlphaMode::Mask { cutoff: 0.5 }
    );
    assert_eq!(scene.texcoords.len(), scene.triangles.len());
    let notes = scene.notes.join("\n");
    assert!(notes.contains("generated tangents"), "{notes}");
    assert!(!notes.contains("not rendered"), "{notes}");
}

#[test]
fn textured_scene_same_seed_traces_the_same_paths() {
    let test = "textured_scene_same_seed_traces_the_same_paths";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, packed) = load(TEXTURED);
    let s = settings(7, 64, 8);
    let a = render_gpu(&mut gpu, &scene, &packed, &s);
    let b = render_cpu(&scene, &packed, &s);
    let differing = pixels_differing(&a, &b, 1e-4);
    let fraction = differing as f64 / a.mean.len() as f64;
    println!(
        "{test}: {differing} of {} pixels differ by more than 1e-4",
        a.mean.len()
    );
    assert!(fraction < 0.01, "{:.1}% of pixels differ", fraction * 100.0);
}

#[test]
fn textured_scene_gpu_matches_cpu() {
    let test = "textured_scene_gpu_matches_cpu";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, packed) = load(TEXTURED);
    let a = render_gpu(&mut gpu, &scene, &packed, &settings(1, 40, 256));
    let b = render_cpu(&scene, &packed, &settings(2, 40, 256));
    assert_agree(test, &a, &b);
}

/// The statistical comparison has the power to see texture bugs that only
/// one back end has: the GPU is handed a texture table whose mirrored-repeat
/// wraps are plain repeats, or a texel buffer whose sRGB table is the
/// identity (no decode), and must be told apart from the correct CPU render.
#[test]
fn comparison_sees_a_wrong_wrap_mode_or_srgb_decode_on_the_gpu_side() {
    let test = "comparison_sees_a_wrong_wrap_mode_or_srgb_decode_on_the_gpu_side";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, packed) = load(TEXTURED);
    let b = render_cpu(&scene, &packed, &settings(2, 40, 256));

    let mut wrong_wrap = PackedScene::new(&scene).expect("packs");
    let mut changed = 0;
    for t in &mut wrong_wrap.textures.textures {
        if t.flags & 3 == WRAP_MIRRORED_REPEAT {
            t.flags = (t.flags & !3) | WRAP_REPEAT;
            changed += 1;
        }
        if (t.flags >> TEXTURE_WRAP_T_SHIFT) & 3 == WRAP_MIRRORED_REPEAT {
            t.flags &= !(3 << TEXTURE_WRAP_T_SHIFT);
            changed += 1;
        }
    }
    assert!(changed > 0, "the scene has no mirrored-repeat texture");
    let a = render_gpu(&mut gpu, &scene, &wrong_wrap, &settings(1, 40, 256));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("wrong wrap mode on the GPU: {cmp}");
    assert!(!cmp.passed(), "a wrong wrap mode went unnoticed");

    let mut no_srgb = PackedScene::new(&scene).expect("packs");
    for (c, word) in no_srgb.textures.texels[..256].iter_mut().enumerate() {
        *word = (c as f32 / 255.0).to_bits();
    }
    let a = render_gpu(&mut gpu, &scene, &no_srgb, &settings(1, 40, 256));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("no sRGB decode on the GPU: {cmp}");
    assert!(!cmp.passed(), "a missing sRGB decode went unnoticed");
}

/// An alpha-MASK quad whose 4×4 nearest-filtered alpha checker cuts out
/// every other cell must cast the same shadow and show the same floor as
/// the opaque cells built from real geometry (independent seeds, both back
/// ends); with the alpha test switched off the comparison must fail.
#[test]
fn alpha_mask_cutout_matches_real_holes() {
    let test = "alpha_mask_cutout_matches_real_holes";
    let (mask_scene, mask) = load("scenes/alpha-mask.gltf");
    let (holes_scene, holes) = load("scenes/alpha-holes.gltf");
    assert!(mask.tri_verts.iter().any(|t| t.alpha_mask != 0));
    let reference = render_cpu(&holes_scene, &holes, &settings(11, 40, 256));
    let cpu = render_cpu(&mask_scene, &mask, &settings(12, 40, 256));
    assert_agree(&format!("{test} (CPU)"), &cpu, &reference);

    let mut opaque = PackedScene::new(&mask_scene).expect("packs");
    for t in &mut opaque.tri_verts {
        t.alpha_mask = 0;
    }
    let no_mask = render_cpu(&mask_scene, &opaque, &settings(12, 40, 256));
    let cmp = compare(&no_mask, &reference, ALPHA).expect("comparable images");
    println!("alpha test off: {cmp}");
    assert!(!cmp.passed(), "switching the alpha test off went unnoticed");

    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let gpu_image = render_gpu(&mut gpu, &mask_scene, &mask, &settings(13, 40, 256));
    assert_agree(&format!("{test} (GPU)"), &gpu_image, &reference);
}

/// An image that cannot be decoded is a note, and its texture is dropped
/// (the factor alone), not an error.
#[test]
fn an_undecodable_image_is_a_note_and_the_factor_is_used() {
    let text = std::fs::read_to_string(repo_path(TEXTURED)).expect("bundled scene");
    let broken = text.replacen(
        "\"uri\": \"data:image/png;base64,",
        "\"uri\": \"data:image/png;base64,AAAA",
        1,
    );
    assert_ne!(broken, text);
    let dir = std::env::temp_dir().join(format!("vkpt-textures-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("broken.gltf");
    std::fs::write(&path, broken).expect("written");
    let scene = Scene::load(&path).expect("still loads");
    let notes = scene.notes.join("\n");
    assert!(notes.contains("cannot decode"), "{notes}");
    let wall = scene
        .materials
        .iter()
        .find(|m| m.name == "letter wall")
        .expect("wall");
    assert!(wall.textures.base_color.is_none());
    PackedScene::new(&scene).expect("packs");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Textures are rendered at full resolution until the device's memory is
/// the limit: twelve 4096x4096 maps (768 MiB of texels, more than any one
/// texel view of lavapipe holds: its texels are split over two views) load
/// without a downsampling note and render the same paths on the GPU and
/// the CPU. Each map is a different pattern on an emissive quad the
/// camera sees directly, so a texel read from the wrong place shows.
#[test]
fn textures_of_any_size_render_at_full_resolution() {
    use image::ImageEncoder;
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    const SIZE: u32 = 4096;
    const MAPS: usize = 12;
    let test = "textures_of_any_size_render_at_full_resolution";
    let dir = fresh_output_dir("textures", test);
    let start = std::time::Instant::now();
    std::thread::scope(|s| {
        for k in 0..MAPS {
            let dir = &dir;
            s.spawn(move || {
                let mut rgba = vec![0u8; (SIZE * SIZE * 4) as usize];
                for (i, texel) in rgba.chunks_exact_mut(4).enumerate() {
                    let (x, y) = (i as u32 % SIZE, i as u32 / SIZE);
                    texel[0] = (x / 16 + 20 * k as u32) as u8;
                    texel[1] = (y / 16 + 50 * k as u32) as u8;
                    texel[2] = ((x ^ y) / 64 + 91 * k as u32) as u8;
                    texel[3] = 255;
                }
                let file = std::fs::File::create(dir.join(format!("map{k}.png"))).expect("png");
                PngEncoder::new_with_quality(
                    std::io::BufWriter::new(file),
                    CompressionType::Fast,
                    FilterType::Sub,
                )
                .write_image(&rgba, SIZE, SIZE, image::ExtendedColorType::Rgba8)
                .expect("png written");
            });
        }
    });
    println!(
        "{test}: {MAPS} maps of {SIZE}x{SIZE} written in {:.1} s",
        start.elapsed().as_secs_f64()
    );

    // A 4 x 3 grid of unit quads at z = 0, quad k emitting map k.
    let mut b = gltf_builder::GltfBuilder::default();
    let mut primitives = Vec::new();
    for k in 0..MAPS {
        let (x0, y0) = (-2.15 + 1.1 * (k % 4) as f32, -1.6 + 1.1 * (k / 4) as f32);
        let (x1, y1) = (x0 + 1.0, y0 + 1.0);
        let positions = b.floats(
            &[
                x0, y0, 0.0, x1, y0, 0.0, x1, y1, 0.0, x0, y0, 0.0, x1, y1, 0.0, x0, y1, 0.0,
            ],
            "VEC3",
        );
        let uvs = b.floats(
            &[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0],
            "VEC2",
        );
        primitives.push(format!(
            r#"{{"attributes": {{"POSITION": {positions}, "TEXCOORD_0": {uvs}}}, "material": {k}}}"#
        ));
    }
    let list = |f: &dyn Fn(usize) -> String| (0..MAPS).map(f).collect::<Vec<_>>().join(", ");
    let body = format!(
        r#""scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0, 0, 5]}}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.85, "znear": 0.1, "aspectRatio": 1.0}}}}],
  "meshes": [{{"primitives": [{}]}}],
  "materials": [{}],
  "textures": [{}],
  "images": [{}]"#,
        primitives.join(", "),
        list(&|k| format!(
            r#"{{"pbrMetallicRoughness": {{"baseColorFactor": [0, 0, 0, 1]}}, "emissiveFactor": [1, 1, 1], "emissiveTexture": {{"index": {k}}}}}"#
        )),
        list(&|k| format!(r#"{{"source": {k}}}"#)),
        list(&|k| format!(r#"{{"uri": "map{k}.png"}}"#)),
    );
    let path = dir.join("maps.gltf");
    std::fs::write(&path, b.finish(&body)).expect("scene written");

    let scene = Scene::load(&path).expect("loads");
    let notes = scene.notes.join("\n");
    assert!(!notes.contains("downsampled"), "{notes}");
    assert_eq!(scene.images.len(), MAPS);
    assert!(
        scene
            .images
            .iter()
            .all(|i| (i.width, i.height) == (SIZE, SIZE))
    );
    let packed = PackedScene::new(&scene).expect("packs");
    let bytes = 4 * packed.textures.texels.len() as u64;
    assert!(bytes > 3 * (256 << 20), "{bytes} bytes of texels");

    let s = settings(3, 32, 2);
    let cpu = render_cpu(&scene, &packed, &s);
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let result = gpu
        .render(&scene, &packed, &s, &|_, _| {})
        .expect("the GPU renders every texel");
    println!(
        "{test}: {:.1} MiB of texels; kernels: {}",
        bytes as f64 / 1048576.0,
        result.kernel_variant.as_deref().unwrap_or("")
    );
    let a = result.film.to_image();
    let differing = pixels_differing(&a, &cpu, 1e-4);
    println!(
        "{test}: {differing} of {} pixels differ by more than 1e-4",
        a.mean.len()
    );
    assert!(
        differing as f64 / (a.mean.len() as f64) < 0.01,
        "{differing} pixels differ"
    );
    drop(gpu);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A PNG of `channels` (1: grey, 2: grey and alpha) as a data URI.
fn png_data_uri(size: u32, channels: usize, texel: impl Fn(u32, u32) -> Vec<u8>) -> String {
    use image::ImageEncoder;
    use image::codecs::png::PngEncoder;
    let data: Vec<u8> = (0..size * size)
        .flat_map(|i| texel(i % size, i / size))
        .collect();
    assert_eq!(data.len(), (size * size) as usize * channels);
    let kind = match channels {
        1 => image::ExtendedColorType::L8,
        _ => image::ExtendedColorType::La8,
    };
    let mut png = Vec::new();
    PngEncoder::new(&mut png)
        .write_image(&data, size, size, kind)
        .expect("png encoded");
    format!("data:image/png;base64,{}", gltf_builder::base64(&png))
}

/// Grey images are stored at one byte per texel (grey with alpha at two)
/// and must read exactly what the RGBA8 words they replace read: a scene
/// whose base colour, metallic-roughness, emissive and alpha-MASK textures
/// are grey PNGs (odd sizes, so rows straddle words) renders the same bits
/// from its compact texels as from the same texels widened to RGBA8, on
/// the CPU and on the GPU, and the two back ends trace the same paths.
#[test]
fn grey_textures_at_one_byte_per_texel_render_the_same_bits_as_rgba8() {
    use vkpt::constants::{TEXTURE_GREY, TEXTURE_GREY_ALPHA};
    use vkpt::scene::TexelStorage;
    let test = "grey_textures_at_one_byte_per_texel_render_the_same_bits_as_rgba8";
    let mut b = gltf_builder::GltfBuilder::default();
    let quad = |b: &mut gltf_builder::GltfBuilder, corners: [[f32; 3]; 4]| {
        let [p, q, r, s] = corners;
        let positions: Vec<f32> = [p, q, r, p, r, s].concat();
        let positions = b.floats(&positions, "VEC3");
        let uvs = b.floats(
            &[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0],
            "VEC2",
        );
        (positions, uvs)
    };
    let floor = quad(
        &mut b,
        [
            [-2.0, 0.0, 2.0],
            [2.0, 0.0, 2.0],
            [2.0, 0.0, -2.0],
            [-2.0, 0.0, -2.0],
        ],
    );
    let cutout = quad(
        &mut b,
        [
            [-0.9, 0.8, 0.9],
            [0.9, 0.8, 0.9],
            [0.9, 0.8, -0.9],
            [-0.9, 0.8, -0.9],
        ],
    );
    let lamp = quad(
        &mut b,
        [
            [-1.5, 0.05, -1.2],
            [1.5, 0.05, -1.2],
            [1.5, 1.0, -1.2],
            [-1.5, 1.0, -1.2],
        ],
    );
    let prim = |(p, t): (usize, usize), m: usize| {
        format!(r#"{{"attributes": {{"POSITION": {p}, "TEXCOORD_0": {t}}}, "material": {m}}}"#)
    };
    let checker = png_data_uri(13, 1, |x, y| {
        vec![if (x / 2 + y / 3) % 2 == 0 { 40 } else { 220 }]
    });
    let gradient = png_data_uri(7, 1, |x, y| vec![(30 * x + 5 * y + 20) as u8]);
    let holes = png_data_uri(9, 2, |x, y| {
        vec![(25 * y + 30) as u8, if (x + y) % 3 == 0 { 0 } else { 255 }]
    });
    let stripes = png_data_uri(5, 1, |x, _| vec![(60 * x) as u8]);
    let body = format!(
        r#""scene": 0,
  "scenes": [{{"nodes": [0, 1], "extras": {{"vkpt": {{"environment": [0.6, 0.6, 0.6]}}}}}}],
  "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0, 2.2, 2.2], "rotation": [-0.3826834, 0, 0, 0.9238795]}}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 1.0, "znear": 0.1, "aspectRatio": 1.0}}}}],
  "meshes": [{{"primitives": [{}, {}, {}]}}],
  "materials": [
    {{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicRoughnessTexture": {{"index": 1}}}}}},
    {{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 2}}}}, "alphaMode": "MASK", "doubleSided": true}},
    {{"pbrMetallicRoughness": {{"baseColorFactor": [0, 0, 0, 1]}}, "emissiveFactor": [3, 3, 3], "emissiveTexture": {{"index": 3}}, "doubleSided": true}}
  ],
  "textures": [{{"source": 0}}, {{"source": 1}}, {{"source": 2}}, {{"source": 3}}],
  "images": [{{"uri": "{checker}"}}, {{"uri": "{gradient}"}}, {{"uri": "{holes}"}}, {{"uri": "{stripes}"}}]"#,
        prim(floor, 0),
        prim(cutout, 1),
        prim(lamp, 2),
    );
    let dir = fresh_output_dir("textures", test);
    let path = dir.join("grey.gltf");
    std::fs::write(&path, b.finish(&body)).expect("scene written");
    let scene = Scene::load(&path).expect("loads");
    let packed = PackedScene::new(&scene).expect("packs");
    let flags: Vec<u32> = packed.textures.textures.iter().map(|t| t.flags).collect();
    assert_eq!(
        flags.iter().filter(|&&f| f & TEXTURE_GREY != 0).count(),
        3,
        "{flags:?}"
    );
    assert_eq!(
        flags
            .iter()
            .filter(|&&f| f & TEXTURE_GREY_ALPHA != 0)
            .count(),
        1,
        "{flags:?}"
    );
    let mut wide = PackedScene::new(&scene).expect("packs");
    wide.textures = packed.textures.widened_to_rgba8();
    let words = |p: &PackedScene| p.textures.texels.len() - 256;
    println!(
        "{test}: {} words of texels stored compactly, {} as RGBA8",
        words(&packed),
        words(&wide)
    );
    // Each image with its mip levels (the emissive stripes have none).
    let pyramids = |p: &PackedScene, compact: bool| -> u64 {
        let mut seen = std::collections::HashSet::new();
        p.textures
            .textures
            .iter()
            .filter(|t| seen.insert(t.offset))
            .map(|t| {
                let storage = match t.flags & (TEXTURE_GREY | TEXTURE_GREY_ALPHA) {
                    _ if !compact => TexelStorage::Rgba8,
                    TEXTURE_GREY => TexelStorage::Grey8,
                    TEXTURE_GREY_ALPHA => TexelStorage::GreyAlpha8,
                    _ => TexelStorage::Rgba8,
                };
                storage.pyramid_words(t.width, t.height, t.levels)
            })
            .sum()
    };
    let levels: Vec<u32> = packed.textures.textures.iter().map(|t| t.levels).collect();
    assert_eq!(
        levels,
        [5, 4, 5, 1],
        "13x13, 7x7, 9x9 mip-mapped; emission not"
    );
    assert_eq!(words(&packed) as u64, pyramids(&packed, true));
    assert_eq!(words(&wide) as u64, pyramids(&packed, false));
    assert_eq!(
        pyramids(&packed, true),
        // Grey 13x13 (169, 49, 16, 4, 1 texels, a byte each, rounded up to
        // words), grey 7x7, grey+alpha 9x9 (81, 25, 9, 4, 1 at two bytes),
        // grey 5x5 emissive without levels.
        (43 + 13 + 4 + 1 + 1) + (13 + 4 + 1 + 1) + (41 + 13 + 5 + 2 + 1) + 7
    );

    let s = settings(5, 48, 16);
    let same_bits = |what: &str, a: &vkpt::image::Image, b: &vkpt::image::Image| {
        let differing = pixels_differing(a, b, 0.0);
        println!("{test}: {what}: {differing} pixels differ");
        assert_eq!(
            differing, 0,
            "{what}: compact and RGBA8 texels render differently"
        );
    };
    let cpu = render_cpu(&scene, &packed, &s);
    same_bits("CPU", &cpu, &render_cpu(&scene, &wide, &s));
    let lit = cpu.mean.iter().filter(|p| p[0] > 0.0).count();
    assert!(lit > cpu.mean.len() / 2, "{lit} lit pixels");
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let a = render_gpu(&mut gpu, &scene, &packed, &s);
    same_bits("GPU", &a, &render_gpu(&mut gpu, &scene, &wide, &s));
    let differing = pixels_differing(&a, &cpu, 1e-4);
    println!("{test}: {differing} pixels differ between GPU and CPU by more than 1e-4");
    assert!(
        differing as f64 / (a.mean.len() as f64) < 0.01,
        "{differing} pixels differ"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A floor of 100 m x 100 m under a uniform white sky, seen from 1.5 m at a
/// slant, tiled 50 times with a 256x256 grey noise texture (base colour):
/// every pixel covers a few texels near the camera and hundreds far away,
/// so the mip level varies over the image. Returns the scene and its file
/// (in the test's output folder).
fn noise_floor(test: &str) -> (Scene, std::path::PathBuf) {
    let mut b = gltf_builder::GltfBuilder::default();
    let positions = b.floats(
        &[
            -50.0, 0.0, 5.0, 50.0, 0.0, 5.0, 50.0, 0.0, -95.0, -50.0, 0.0, 5.0, 50.0, 0.0, -95.0,
            -50.0, 0.0, -95.0,
        ],
        "VEC3",
    );
    let uvs = b.floats(
        &[
            0.0, 50.0, 50.0, 50.0, 50.0, 0.0, 0.0, 50.0, 50.0, 0.0, 0.0, 0.0,
        ],
        "VEC2",
    );
    let noise = png_data_uri(256, 1, |x, y| {
        let h =
            (x.wrapping_mul(73_856_093) ^ y.wrapping_mul(19_349_663)).wrapping_mul(2_654_435_761);
        vec![(h >> 24) as u8]
    });
    let body = format!(
        r#""scene": 0,
  "scenes": [{{"nodes": [0, 1], "extras": {{"vkpt": {{"environment": [1, 1, 1]}}}}}}],
  "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0, 1.5, 2], "rotation": [-0.2955202, 0, 0, 0.9553365]}}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "znear": 0.1, "aspectRatio": 1.0}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {positions}, "TEXCOORD_0": {uvs}}}, "material": 0}}]}}],
  "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicFactor": 0}}}}],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "{noise}"}}]"#
    );
    let dir = fresh_output_dir("textures", test);
    let path = dir.join("noise-floor.gltf");
    std::fs::write(&path, b.finish(&body)).expect("scene written");
    (Scene::load(&path).expect("loads"), dir)
}

/// With mip-mapping on, the GPU and the CPU trace the same paths through
/// the same mip levels on a floor whose level varies over the image.
#[test]
fn mip_mapped_floor_same_seed_traces_the_same_paths() {
    let test = "mip_mapped_floor_same_seed_traces_the_same_paths";
    let (scene, dir) = noise_floor(test);
    let packed = PackedScene::new(&scene).expect("packs");
    assert_eq!(packed.textures.textures[0].levels, 9, "256 to 1: 9 levels");
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let s = settings(9, 48, 4);
    let a = render_gpu(&mut gpu, &scene, &packed, &s);
    let b = render_cpu(&scene, &packed, &s);
    let differing = pixels_differing(&a, &b, 1e-4);
    println!(
        "{test}: {differing} of {} pixels differ by more than 1e-4",
        a.mean.len()
    );
    assert!(
        differing as f64 / (a.mean.len() as f64) < 0.01,
        "{differing} pixels differ"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// What mip-mapping buys: at 4 samples per pixel the minified noise floor's
/// pixels are less noisy with mip levels than with the full-resolution
/// image alone (bilinear), and the image's mean stays the converged mean.
/// The per-pixel variance is the film's estimate (the variance of each
/// pixel's mean); it includes the lighting's noise, which mip levels do not
/// remove, so the ratio is bounded by it. The means are compared within 4
/// standard errors of their difference (64-spp mip-mapped, 256-spp
/// bilinear; pixels independent).
#[test]
fn mip_mapping_lowers_the_noise_of_a_minified_texture_and_keeps_its_mean() {
    use vkpt::render::TextureFilter;
    let test = "mip_mapping_lowers_the_noise_of_a_minified_texture_and_keeps_its_mean";
    let (scene, dir) = noise_floor(test);
    let packed = PackedScene::new(&scene).expect("packs");
    let with = |filter, seed, spp| RenderSettings {
        texture_filter: filter,
        ..settings(seed, 32, spp)
    };
    let mip = render_cpu(&scene, &packed, &with(TextureFilter::Mip, 1, 4));
    let bilinear = render_cpu(&scene, &packed, &with(TextureFilter::Bilinear, 1, 4));
    let converged_mip = render_cpu(&scene, &packed, &with(TextureFilter::Mip, 3, 64));
    let reference = render_cpu(&scene, &packed, &with(TextureFilter::Bilinear, 2, 256));
    let mean_variance = |i: &vkpt::image::Image| {
        let v = i.variance.as_ref().expect("variance");
        v.iter().map(|p| p[1] as f64).sum::<f64>() / v.len() as f64
    };
    let image_mean = |i: &vkpt::image::Image| {
        i.mean.iter().map(|p| p[1] as f64).sum::<f64>() / i.mean.len() as f64
    };
    let (vm, vb) = (mean_variance(&mip), mean_variance(&bilinear));
    let (mm, mr) = (image_mean(&converged_mip), image_mean(&reference));
    let n = reference.mean.len() as f64;
    let se = ((mean_variance(&converged_mip) + mean_variance(&reference)) / n).sqrt();
    println!(
        "{test}: mean pixel variance at 4 spp: mip {vm:.3e}, bilinear {vb:.3e} ({:.1}x); \
         image mean: 64-spp mip {mm:.5}, 256-spp bilinear {mr:.5} (standard error {se:.1e})",
        vb / vm
    );
    assert!(vm < 0.5 * vb, "mip-mapping did not lower the noise");
    assert!(
        (mm - mr).abs() < 4.0 * se,
        "mip-mapped mean {mm} is not the converged {mr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
