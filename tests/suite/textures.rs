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
