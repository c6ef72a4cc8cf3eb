//! Compressed glTF: `KHR_mesh_quantization`, `KHR_draco_mesh_compression`,
//! `EXT_meshopt_compression`, `KHR_texture_basisu` and `EXT_texture_webp`.
//! Files written here are checked against the same content stored plainly;
//! the public samples in `../shared/gltf-samples/compressed` against their
//! plain variants (skipped, with a notice, where that folder is absent).

use crate::common;

use common::gltf_builder::base64;
use glam::{DVec3, Vec3};
use std::path::{Path, PathBuf};
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::Scene;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("test file written");
    path
}

/// `../shared/gltf-samples/compressed/<folder>/<file>`, or `None` with a
/// printed notice where the samples are absent (a user's own clone).
fn sample(relative: &str) -> Option<PathBuf> {
    let path = common::repo_path("../shared/gltf-samples").join(relative);
    if path.is_file() {
        Some(path)
    } else {
        println!("skipping: {} not found", path.display());
        None
    }
}

/// One buffer of accessors of any component type, each in a bufferView
/// of its own, and the JSON that describes them.
#[derive(Default)]
struct Accessors {
    data: Vec<u8>,
    json: Vec<String>,
    views: Vec<String>,
}

impl Accessors {
    /// Appends an accessor over `bytes` (its view aligned to 4, with
    /// `stride` when given); returns its index.
    fn add_strided(
        &mut self,
        bytes: &[u8],
        count: usize,
        kind: &str,
        component_type: u32,
        stride: Option<usize>,
        extra: &str,
    ) -> usize {
        let offset = self.data.len();
        self.data.extend_from_slice(bytes);
        let stride = stride.map_or(String::new(), |s| format!(r#", "byteStride": {s}"#));
        self.views.push(format!(
            r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {}{stride}}}"#,
            bytes.len()
        ));
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        self.json.push(format!(
            r#"{{"bufferView": {}, "componentType": {component_type}, "count": {count}, "type": "{kind}"{extra}}}"#,
            self.views.len() - 1
        ));
        self.json.len() - 1
    }

    fn add(&mut self, bytes: &[u8], count: usize, kind: &str, ty: u32, extra: &str) -> usize {
        self.add_strided(bytes, count, kind, ty, None, extra)
    }

    fn finish(&self, body: &str) -> String {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, {body},
  "accessors": [{}],
  "bufferViews": [{}],
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}]}}"#,
            self.json.join(",\n    "),
            self.views.join(",\n    "),
            self.data.len(),
            base64(&self.data)
        )
    }
}

fn bytes_of<T: Copy, const N: usize>(values: &[T], le: fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|v| le(*v)).collect()
}

/// A 4x4 checker texture (red and white) as a PNG.
fn checker_png() -> Vec<u8> {
    let img = image::RgbaImage::from_fn(4, 4, |x, y| {
        if (x + y) % 2 == 0 {
            image::Rgba([255, 32, 32, 255])
        } else {
            image::Rgba([255, 255, 255, 255])
        }
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png)
        .expect("PNG encodes");
    out.into_inner()
}

/// The textured-material part of a test file, over an image `uri`.
fn textured_material(uri: &str) -> String {
    format!(
        r#""materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicFactor": 0}}}}],
  "textures": [{{"source": 0, "sampler": 0}}],
  "samplers": [{{"magFilter": 9728, "minFilter": 9728}}],
  "images": [{{"uri": "{uri}"}}]"#
    )
}

/// A quad's positions (i16 normalized), UVs (u8 normalized) and normals
/// (i8 normalized) as the spec dequantizes them: `max(c / 32767, -1)`,
/// `c / 255`, `max(c / 127, -1)`.
const QUAD_POSITIONS: [i16; 12] = [
    -32768, -16384, 0, 32767, -32767, 0, 30000, 32767, 100, -20000, 16384, -100,
];
const QUAD_UVS: [u8; 8] = [0, 255, 255, 204, 230, 0, 51, 25];
const QUAD_NORMALS: [i8; 12] = [0, 0, 127, 0, -3, 127, 5, 0, 127, -128, 0, 127];
const QUAD_INDICES: [u16; 6] = [0, 1, 2, 0, 2, 3];

fn signed(c: i64, bits: u32) -> f32 {
    (c as f64 / ((1i64 << (bits - 1)) - 1) as f64).max(-1.0) as f32
}

fn unsigned(c: i64, bits: u32) -> f32 {
    (c as f64 / ((1i64 << bits) - 1) as f64) as f32
}

/// The quad stored quantized (`KHR_mesh_quantization`, required) or as
/// floats holding the dequantized values.
fn quad_file(quantized: bool, image_uri: &str) -> String {
    let mut a = Accessors::default();
    let (pos, uv, normal) = if quantized {
        (
            a.add(
                &bytes_of(&QUAD_POSITIONS, i16::to_le_bytes),
                4,
                "VEC3",
                5122,
                r#", "normalized": true, "min": [-32768, -32767, -100], "max": [32767, 32767, 100]"#,
            ),
            a.add(&QUAD_UVS, 4, "VEC2", 5121, r#", "normalized": true"#),
            // i8 VEC3 elements are padded to 4 bytes, as the spec requires.
            a.add_strided(
                &QUAD_NORMALS
                    .chunks(3)
                    .flat_map(|n| [n[0] as u8, n[1] as u8, n[2] as u8, 0])
                    .collect::<Vec<u8>>(),
                4,
                "VEC3",
                5120,
                Some(4),
                r#", "normalized": true"#,
            ),
        )
    } else {
        let pos: Vec<f32> = QUAD_POSITIONS
            .iter()
            .map(|&c| signed(c as i64, 16))
            .collect();
        let uv: Vec<f32> = QUAD_UVS.iter().map(|&c| unsigned(c as i64, 8)).collect();
        let normal: Vec<f32> = QUAD_NORMALS.iter().map(|&c| signed(c as i64, 8)).collect();
        (
            a.add(
                &bytes_of(&pos, f32::to_le_bytes),
                4,
                "VEC3",
                5126,
                r#", "min": [-1, -1, -0.01], "max": [1, 1, 0.01]"#,
            ),
            a.add(&bytes_of(&uv, f32::to_le_bytes), 4, "VEC2", 5126, ""),
            a.add(&bytes_of(&normal, f32::to_le_bytes), 4, "VEC3", 5126, ""),
        )
    };
    let idx = a.add(
        &bytes_of(&QUAD_INDICES, u16::to_le_bytes),
        6,
        "SCALAR",
        5123,
        "",
    );
    let required = if quantized {
        r#""extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"],"#
    } else {
        ""
    };
    a.finish(&format!(
        r#"{required} "scenes": [{{"nodes": [0, 1]}}], "scene": 0,
  "nodes": [{{"mesh": 0, "scale": [2, 2, 2]}},
            {{"camera": 0, "translation": [0, 0, 5]}}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "znear": 0.1}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}, "TEXCOORD_0": {uv}, "NORMAL": {normal}}}, "indices": {idx}, "material": 0}}]}}],
  {}"#,
        textured_material(image_uri)
    ))
}

fn load(path: &Path) -> Scene {
    Scene::load(path).unwrap_or_else(|e| panic!("{}: {e:#}", path.display()))
}

fn settings(spp: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width: 32,
        height: 32,
        spp,
        seed,
        ..Default::default()
    }
}

fn render(scene: &Scene, settings: &RenderSettings) -> vkpt::image::Image {
    let packed = PackedScene::new(scene).expect("scene packs");
    common::render_cpu(scene, &packed, settings)
}

/// World-space corners (f64, `world_origin` added back).
fn world_positions(scene: &Scene) -> Vec<DVec3> {
    scene
        .triangles
        .iter()
        .flat_map(|t| t.positions)
        .map(|p| p.as_dvec3() + scene.world_origin)
        .collect()
}

fn bounds(points: &[DVec3]) -> (DVec3, DVec3) {
    points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

fn no_warnings(scene: &Scene) {
    for note in &scene.notes {
        assert!(
            !note.contains("warning") && !note.contains("not supported"),
            "unexpected note: {note}"
        );
    }
}

#[test]
fn a_quantized_quad_loads_and_renders_as_the_same_quad_in_floats() {
    let dir = common::output_dir("gltf_compressed/quantized_quad");
    std::fs::write(dir.join("checker.png"), checker_png()).unwrap();
    let quantized = load(&write(
        &dir,
        "quantized.gltf",
        &quad_file(true, "checker.png"),
    ));
    let plain = load(&write(&dir, "plain.gltf", &quad_file(false, "checker.png")));
    no_warnings(&quantized);
    assert_eq!(quantized.triangles.len(), 2);
    assert_eq!(world_positions(&quantized), world_positions(&plain));
    let normals = |s: &Scene| -> Vec<Vec3> { s.triangles.iter().flat_map(|t| t.normals).collect() };
    assert_eq!(normals(&quantized), normals(&plain));
    let uvs = |s: &Scene| -> Vec<glam::Vec2> { s.texcoords.iter().flat_map(|t| t.uv[0]).collect() };
    assert_eq!(uvs(&quantized), uvs(&plain));
    assert_eq!(quantized.images.len(), 1);
    // The same paths (same seed) give the same pixels; independent seeds
    // agree statistically.
    let a = render(&quantized, &settings(4, 1));
    let b = render(&plain, &settings(4, 1));
    assert_eq!(common::pixels_differing(&a, &b, 0.0), 0);
    let c = render(&plain, &settings(16, 2));
    let d = render(&quantized, &settings(16, 3));
    common::assert_agree(
        "a_quantized_quad_loads_and_renders_as_the_same_quad_in_floats",
        &d,
        &c,
    );
}

#[test]
fn the_quantized_lantern_loads_within_its_dequantized_bounds() {
    let Some(path) = sample("compressed/Lantern-glTF-Quantized/Lantern.gltf") else {
        return;
    };
    let scene = load(&path);
    // Its only node places the u16 positions (min 0, max [9889, 16383,
    // 2957]) by scale 0.00156651519 and a translation.
    let scale = 0.00156651519;
    let t = DVec3::new(-3.92244506, 0.18392086, -2.31570983);
    let lo = t;
    let hi = t + DVec3::new(9889.0, 16383.0, 2957.0) * scale;
    let points = world_positions(&scene);
    assert!(points.iter().all(|p| p.is_finite()));
    let (min, max) = bounds(&points);
    println!(
        "Lantern: {} triangles, bounds {min:?} .. {max:?}",
        scene.triangles.len()
    );
    assert!((min - lo).abs().max_element() < 1e-4, "{min:?} vs {lo:?}");
    assert!((max - hi).abs().max_element() < 1e-4, "{max:?} vs {hi:?}");
    assert!(scene.triangles.len() > 5000, "{}", scene.triangles.len());
    assert!(
        scene
            .notes
            .iter()
            .all(|n| !n.contains("KHR_mesh_quantization")),
        "{:?}",
        scene.notes
    );
    // Normals and tangents are i8 normalized: unit length after decoding.
    for t in &scene.triangles {
        for n in t.normals {
            assert!((n.length() - 1.0).abs() < 1e-3, "{n:?}");
        }
    }
}

/// A compressed sample and its plain variant, loaded.
fn pair(compressed: &str, plain: &str) -> Option<(Scene, Scene)> {
    let (a, b) = (sample(compressed)?, sample(plain)?);
    Some((load(&a), load(&b)))
}

/// Every point of `a` lies within `tol` of a point of `b` (a grid of
/// cells `tol` wide holds `b`); returns the largest such distance.
fn farthest_from(a: &[DVec3], b: &[DVec3], tol: f64) -> f64 {
    use std::collections::HashMap;
    let cell = |p: DVec3| (p / tol).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<DVec3>> = HashMap::new();
    for p in b {
        grid.entry(cell(*p)).or_default().push(*p);
    }
    let mut worst = 0.0f64;
    for p in a {
        let c = cell(*p);
        let mut best = f64::INFINITY;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let k = c + glam::IVec3::new(dx, dy, dz);
                    for q in grid.get(&k).into_iter().flatten() {
                        best = best.min(p.distance(*q));
                    }
                }
            }
        }
        worst = worst.max(best);
    }
    worst
}

/// The Draco variant has the plain variant's triangles: the same count,
/// the same bounds and every corner within the quantization step of a
/// corner of the other (both ways), and the two render alike.
fn draco_matches_plain(test: &str, compressed: &str, plain: &str) {
    let Some((draco, plain)) = pair(compressed, plain) else {
        return;
    };
    assert!(
        draco
            .notes
            .iter()
            .any(|n| n.contains("KHR_draco_mesh_compression")),
        "{:?}",
        draco.notes
    );
    assert_eq!(draco.triangles.len(), plain.triangles.len());
    let (a, b) = (world_positions(&draco), world_positions(&plain));
    let (lo, hi) = bounds(&b);
    // The Khronos samples quantize positions to at least 11 bits: a step
    // of extent / 2047 at most per axis.
    let step = (hi - lo).max_element() / 2047.0;
    let (dlo, dhi) = bounds(&a);
    assert!(
        (dlo - lo).abs().max_element() <= step && (dhi - hi).abs().max_element() <= step,
        "{test}: bounds {dlo:?}..{dhi:?} vs {lo:?}..{hi:?} (step {step})"
    );
    let worst = farthest_from(&a, &b, step).max(farthest_from(&b, &a, step));
    println!(
        "{test}: {} triangles, farthest corner {worst:.3e} (step {step:.3e})",
        draco.triangles.len()
    );
    assert!(
        worst <= step,
        "{test}: a corner is {worst} from the other variant's (step {step})"
    );
    assert_eq!(draco.images.len(), plain.images.len());
    // Independent seeds: the two renders have the same expectation.
    let aspect = plain.cameras[0].aspect_ratio.unwrap_or(1.0);
    let s = |seed| RenderSettings {
        height: ((32.0 / aspect).round() as u32).max(1),
        ..settings(16, seed)
    };
    let x = render(&draco, &s(11));
    let y = render(&plain, &s(12));
    common::assert_agree(test, &x, &y);
}

#[test]
fn draco_box_matches_the_plain_box() {
    draco_matches_plain(
        "draco_box_matches_the_plain_box",
        "compressed/Box-glTF-Draco/Box.gltf",
        "Box/Box.gltf",
    );
}

#[test]
fn draco_duck_matches_the_plain_duck() {
    draco_matches_plain(
        "draco_duck_matches_the_plain_duck",
        "compressed/Duck-glTF-Draco/Duck.gltf",
        "compressed/Duck/Duck.gltf",
    );
}

#[test]
fn draco_rigged_simple_matches_the_plain_one_with_joints_and_weights() {
    // Skinned: the joints and weights decoded from Draco pose the mesh.
    draco_matches_plain(
        "draco_rigged_simple_matches_the_plain_one_with_joints_and_weights",
        "compressed/RiggedSimple-glTF-Draco/RiggedSimple.gltf",
        "compressed/RiggedSimple/RiggedSimple.gltf",
    );
}

#[test]
fn draco_vc_matches_the_plain_vc() {
    draco_matches_plain(
        "draco_vc_matches_the_plain_vc",
        "compressed/VC-glTF-Draco/VC.gltf",
        "compressed/VC/VC.gltf",
    );
}

/// Copies a sample folder into the test's output folder.
fn copy_sample(folder: &str, dir: &Path) -> Option<()> {
    let src = common::repo_path("../shared/gltf-samples").join(folder);
    if !src.is_dir() {
        println!("skipping: {} not found", src.display());
        return None;
    }
    for entry in std::fs::read_dir(&src).unwrap().flatten() {
        // The samples are read-only; their copies must be writable (the
        // tests corrupt them, and the next run replaces them).
        let to = dir.join(entry.file_name());
        let _ = std::fs::remove_file(&to);
        std::fs::copy(entry.path(), &to).unwrap();
        let mut permissions = std::fs::metadata(&to).unwrap().permissions();
        #[allow(clippy::permissions_set_readonly_false)]
        permissions.set_readonly(false);
        std::fs::set_permissions(&to, permissions).unwrap();
    }
    Some(())
}

/// A load that must fail: its error, in one line.
fn load_error(path: &Path) -> String {
    let err = match Scene::load(path) {
        Ok(_) => panic!("{} loaded", path.display()),
        Err(e) => format!("{e:#}"),
    };
    assert!(!err.contains('\n'), "not one line: {err}");
    err
}

#[test]
fn a_corrupt_or_truncated_draco_buffer_is_an_error_naming_the_primitive() {
    let dir = common::output_dir("gltf_compressed/corrupt_draco");
    if copy_sample("compressed/Box-glTF-Draco", &dir).is_none() {
        return;
    }
    let bin = std::fs::read(dir.join("Box.bin")).unwrap();
    let gltf = std::fs::read_to_string(dir.join("Box.gltf")).unwrap();
    let json: gltf::json::Value = gltf::json::deserialize::from_str(&gltf).unwrap();
    let view = &json["bufferViews"][0];
    let (offset, length) = (
        view["byteOffset"].as_u64().unwrap_or(0) as usize,
        view["byteLength"].as_u64().unwrap() as usize,
    );
    // Garbage after the header, and every truncation of the stream: an
    // error or (where the stream still decodes) a scene, never a panic.
    let mut garbage = bin.clone();
    for b in &mut garbage[offset + 12..offset + length] {
        *b ^= 0x5A;
    }
    std::fs::write(dir.join("Box.bin"), &garbage).unwrap();
    let err = load_error(&dir.join("Box.gltf"));
    assert!(
        err.contains("mesh #0")
            && err.contains("primitive #0")
            && err.contains("KHR_draco_mesh_compression"),
        "{err}"
    );
    std::fs::write(dir.join("Box.bin"), &bin).unwrap();
    for cut in (0..length).step_by(7) {
        let text = gltf.replacen(
            &format!("\"byteLength\": {length}"),
            &format!("\"byteLength\": {cut}"),
            1,
        );
        assert_ne!(text, gltf, "the view's byteLength is written as expected");
        let path = write(&dir, "cut.gltf", &text);
        if let Err(e) = Scene::load(&path) {
            let e = format!("{e:#}");
            assert!(e.contains("primitive #0") && !e.contains('\n'), "{e}");
        }
    }
}

/// A wavy 7x7 grid: positions, unit normals and u16 triangle indices.
fn wavy_grid() -> (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<u16>) {
    let n = 7;
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..n {
        for i in 0..n {
            let (x, z) = (i as f32 / 3.0 - 1.0, j as f32 / 3.0 - 1.0);
            let (y, dx, dz) = (
                0.3 * (2.0 * x).sin() * z,
                0.6 * (2.0 * x).cos() * z,
                0.3 * (2.0 * x).sin(),
            );
            positions.push([x, y, z]);
            normals.push(Vec3::new(-dx, 1.0, -dz).normalize().to_array());
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u16;
            let (b, c, d) = (a + 1, a + n as u16, a + n as u16 + 1);
            indices.extend_from_slice(&[a, c, b, b, c, d]);
        }
    }
    (positions, normals, indices)
}

/// The grid seen from above, compressed with `EXT_meshopt_compression`
/// (positions: ATTRIBUTES; normals: ATTRIBUTES with the OCTAHEDRAL filter,
/// i8 normalized; indices: TRIANGLES) over a fallback buffer without
/// data, or plainly (f32 and u16). `edit` may corrupt the compressed bytes.
fn meshopt_grid_file(compressed: bool, edit: impl Fn(usize, &mut Vec<u8>)) -> String {
    let (positions, normals, indices) = wavy_grid();
    let scene = |pos: usize, normal: usize, idx: usize| {
        format!(
            r#""scenes": [{{"nodes": [0, 1]}}], "scene": 0,
  "nodes": [{{"mesh": 0}}, {{"camera": 0, "translation": [0, 3, 0.5], "rotation": [-0.6755902, 0, 0, 0.7372773]}}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.9, "znear": 0.1}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {pos}, "NORMAL": {normal}}}, "indices": {idx}}}]}}]"#
        )
    };
    let bounds = r#", "min": [-1, -0.4, -1], "max": [1, 0.4, 1]"#;
    if !compressed {
        let mut a = Accessors::default();
        let flat = |v: &[[f32; 3]]| bytes_of(&v.concat(), f32::to_le_bytes);
        let pos = a.add(&flat(&positions), positions.len(), "VEC3", 5126, bounds);
        let normal = a.add(&flat(&normals), normals.len(), "VEC3", 5126, "");
        let idx = a.add(
            &bytes_of(&indices, u16::to_le_bytes),
            indices.len(),
            "SCALAR",
            5123,
            "",
        );
        return a.finish(&scene(pos, normal, idx));
    }
    let oct: Vec<[i8; 4]> = meshopt::encode_filter_oct(
        &normals
            .iter()
            .map(|n| [n[0], n[1], n[2], 0.0])
            .collect::<Vec<_>>(),
        8,
    );
    let wide: Vec<u32> = indices.iter().map(|&i| i as u32).collect();
    // (stream, element count, decoded stride, mode, filter)
    let streams = [
        (
            meshopt::encode_vertex_buffer(&positions).unwrap(),
            positions.len(),
            12,
            "ATTRIBUTES",
            "NONE",
        ),
        (
            meshopt::encode_vertex_buffer(&oct).unwrap(),
            oct.len(),
            4,
            "ATTRIBUTES",
            "OCTAHEDRAL",
        ),
        (
            meshopt::encode_index_buffer(&wide, positions.len()).unwrap(),
            indices.len(),
            2,
            "TRIANGLES",
            "NONE",
        ),
    ];
    let (mut data, mut views, mut fallback_offset) = (Vec::new(), Vec::new(), 0);
    for (k, (stream, count, stride, mode, filter)) in streams.iter().enumerate() {
        let mut stream = stream.clone();
        edit(k, &mut stream);
        let offset = data.len();
        data.extend_from_slice(&stream);
        while !data.len().is_multiple_of(4) {
            data.push(0);
        }
        let size = count * stride;
        let view_stride = if *mode == "ATTRIBUTES" {
            format!(r#", "byteStride": {stride}"#)
        } else {
            String::new()
        };
        views.push(format!(
            r#"{{"buffer": 1, "byteOffset": {fallback_offset}, "byteLength": {size}{view_stride},
      "extensions": {{"EXT_meshopt_compression": {{"buffer": 0, "byteOffset": {offset}, "byteLength": {}, "byteStride": {stride}, "count": {count}, "mode": "{mode}", "filter": "{filter}"}}}}}}"#,
            stream.len()
        ));
        fallback_offset += size.next_multiple_of(4);
    }
    format!(
        r#"{{"asset": {{"version": "2.0"}},
  "extensionsUsed": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
  "extensionsRequired": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
  {},
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": {}, "type": "VEC3"{bounds}}},
    {{"bufferView": 1, "componentType": 5120, "normalized": true, "count": {}, "type": "VEC3"}},
    {{"bufferView": 2, "componentType": 5123, "count": {}, "type": "SCALAR"}}],
  "bufferViews": [{}],
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}},
              {{"byteLength": {fallback_offset}, "extensions": {{"EXT_meshopt_compression": {{"fallback": true}}}}}}]}}"#,
        scene(0, 1, 2),
        positions.len(),
        normals.len(),
        indices.len(),
        views.join(",\n    "),
        data.len(),
        base64(&data)
    )
}

#[test]
fn a_meshopt_compressed_grid_matches_the_plain_grid() {
    let dir = common::output_dir("gltf_compressed/meshopt_grid");
    let packed = load(&write(
        &dir,
        "meshopt.gltf",
        &meshopt_grid_file(true, |_, _| {}),
    ));
    let plain = load(&write(
        &dir,
        "plain.gltf",
        &meshopt_grid_file(false, |_, _| {}),
    ));
    no_warnings(&packed);
    assert!(
        packed
            .notes
            .iter()
            .any(|n| n.contains("3 bufferViews (EXT_meshopt_compression)")),
        "{:?}",
        packed.notes
    );
    assert_eq!(packed.triangles.len(), 72);
    // Positions and indices are lossless; 8-bit octahedral normals are
    // within about 1/127 rad of the originals.
    assert_eq!(world_positions(&packed), world_positions(&plain));
    for (a, b) in packed.triangles.iter().zip(&plain.triangles) {
        for (n, m) in a.normals.iter().zip(&b.normals) {
            assert!(n.angle_between(*m) < 0.02, "{n:?} vs {m:?}");
        }
    }
    let x = render(&packed, &settings(16, 21));
    let y = render(&plain, &settings(16, 22));
    common::assert_agree("a_meshopt_compressed_grid_matches_the_plain_grid", &x, &y);
}

#[test]
fn a_corrupt_or_truncated_meshopt_stream_is_an_error_naming_the_view_and_primitive() {
    let dir = common::output_dir("gltf_compressed/corrupt_meshopt");
    for stream in 0..3 {
        for (how, edit) in [
            (
                "flipped",
                &(|s: &mut Vec<u8>| s.iter_mut().skip(1).for_each(|b| *b ^= 0xA5))
                    as &dyn Fn(&mut Vec<u8>),
            ),
            ("truncated", &|s: &mut Vec<u8>| s.truncate(s.len() / 2)),
            ("empty", &|s: &mut Vec<u8>| s.clear()),
        ] {
            let text = meshopt_grid_file(true, |k, s| {
                if k == stream {
                    edit(s)
                }
            });
            let path = write(&dir, &format!("{how}-{stream}.gltf"), &text);
            // A flipped stream may still decode (to garbage that is then
            // checked like any data); a truncated or empty one may not.
            match Scene::load(&path) {
                Ok(_) => assert_eq!(how, "flipped", "{how} stream {stream} loaded"),
                Err(e) => {
                    let e = format!("{e:#}");
                    assert!(!e.contains('\n'), "{e}");
                    assert!(e.contains("mesh #0") && e.contains("primitive #0"), "{e}");
                }
            }
        }
    }
}

/// The checker as a lossless WebP.
fn checker_webp() -> Vec<u8> {
    let png = image::load_from_memory(&checker_png())
        .unwrap()
        .into_rgba8();
    let mut out = Vec::new();
    image::codecs::webp::WebPEncoder::new_lossless(&mut out)
        .encode(png.as_raw(), 4, 4, image::ExtendedColorType::Rgba8)
        .expect("WebP encodes");
    out
}

#[test]
fn a_webp_texture_renders_like_the_same_png() {
    let dir = common::output_dir("gltf_compressed/webp_texture");
    std::fs::write(dir.join("checker.png"), checker_png()).unwrap();
    std::fs::write(dir.join("checker.webp"), checker_webp()).unwrap();
    let png = load(&write(&dir, "png.gltf", &quad_file(false, "checker.png")));
    let webp = load(&write(&dir, "webp.gltf", &quad_file(false, "checker.webp")));
    no_warnings(&webp);
    assert_eq!(webp.images.len(), 1);
    assert_eq!(webp.images[0].texels, png.images[0].texels);
    let a = render(&webp, &settings(4, 1));
    let b = render(&png, &settings(4, 1));
    assert_eq!(common::pixels_differing(&a, &b, 0.0), 0);

    // A texture offering a WebP (EXT_texture_webp, required) and a
    // KTX2 that does not exist besides a PNG uses the PNG, says so once,
    // and warns of nothing (the KTX2 is never read).
    let text = quad_file(false, "checker.png").replace(
        r#""textures": [{"source": 0, "sampler": 0}],
  "samplers": [{"magFilter": 9728, "minFilter": 9728}],
  "images": [{"uri": "checker.png"}]"#,
        r#""extensionsUsed": ["EXT_texture_webp", "KHR_texture_basisu"],
  "extensionsRequired": ["EXT_texture_webp"],
  "textures": [{"source": 0, "sampler": 0, "extensions": {"EXT_texture_webp": {"source": 1}, "KHR_texture_basisu": {"source": 2}}},
               {"extensions": {"EXT_texture_webp": {"source": 1}}}],
  "samplers": [{"magFilter": 9728, "minFilter": 9728}],
  "images": [{"uri": "checker.png"}, {"uri": "checker.webp"}, {"uri": "absent.ktx2", "mimeType": "image/ktx2"}]"#,
    );
    assert!(text.contains("EXT_texture_webp"), "the edit applies");
    let both = load(&write(&dir, "both.gltf", &text));
    let choices: Vec<&String> = both
        .notes
        .iter()
        .filter(|n| n.contains("several images"))
        .collect();
    assert_eq!(choices.len(), 1, "{:?}", both.notes);
    assert!(
        choices[0].contains("1 texture uses the PNG image rather than the WebP or KTX2"),
        "{}",
        choices[0]
    );
    assert_eq!(both.images.len(), 1);
    assert_eq!(both.images[0].texels, png.images[0].texels);
    // The missing KTX2 file is still named among the file's images.
    assert!(
        both.notes
            .iter()
            .any(|n| n.starts_with("warning: image #2") && n.contains("absent.ktx2")),
        "{:?}",
        both.notes
    );
}

#[test]
fn the_ktx2_barn_lamp_loads_its_basis_textures() {
    let Some(path) =
        sample("compressed/AnisotropyBarnLamp-glTF-KTX2-Basisu/AnisotropyBarnLamp.gltf")
    else {
        return;
    };
    let scene = load(&path);
    for note in &scene.notes {
        assert!(
            !note.contains("ignored (")
                && !note.contains("warning")
                && !note.contains("KHR_texture_basisu"),
            "{note}"
        );
    }
    // Four UASTC/zstd 2048x2048 KTX2 images, each decoded once.
    assert_eq!(
        scene.images.len(),
        4,
        "{:?}",
        scene.images.iter().map(|i| &i.name).collect::<Vec<_>>()
    );
    for img in &scene.images {
        assert_eq!((img.width, img.height), (2048, 2048), "{}", img.name);
        // Not a flat colour: the transcoder produced an image (the normal
        // map is mostly flat: about 4 % of its texels differ from the first).
        let first = img.texels[0];
        let differing = img.texels.iter().filter(|&&t| t != first).count();
        assert!(
            differing > 10_000,
            "{}: {differing} texels differ",
            img.name
        );
    }
}

#[test]
fn a_corrupt_ktx2_image_is_a_one_line_warning_naming_it() {
    let dir = common::output_dir("gltf_compressed/corrupt_ktx2");
    if copy_sample("compressed/AnisotropyBarnLamp-glTF-KTX2-Basisu", &dir).is_none() {
        return;
    }
    let name = "AnisotropyBarnLamp_basecolor.ktx2";
    let bytes = std::fs::read(dir.join(name)).unwrap();
    for (how, cut) in [
        ("header", 60),
        ("half", bytes.len() / 2),
        ("last byte", bytes.len() - 1),
    ] {
        std::fs::write(dir.join(name), &bytes[..cut]).unwrap();
        let scene = load(&dir.join("AnisotropyBarnLamp.gltf"));
        let warnings: Vec<&String> = scene.notes.iter().filter(|n| n.contains(name)).collect();
        assert_eq!(warnings.len(), 1, "{how}: {:?}", scene.notes);
        assert!(
            warnings[0].starts_with("warning: image #")
                && warnings[0].contains("KTX2")
                && !warnings[0].contains('\n'),
            "{how}: {}",
            warnings[0]
        );
        assert_eq!(scene.images.len(), 3, "{how}");
    }
}

#[test]
fn properties_driven_by_several_animations_are_one_note_with_a_count() {
    // Five nodes whose rotations three animations all drive (a rigged
    // character's clips): one line, not five.
    let mut a = Accessors::default();
    let tri = a.add(
        &bytes_of(
            &[0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            f32::to_le_bytes,
        ),
        3,
        "VEC3",
        5126,
        r#", "min": [0, 0, 0], "max": [1, 1, 0]"#,
    );
    let times = a.add(
        &bytes_of(&[0.0f32, 1.0], f32::to_le_bytes),
        2,
        "SCALAR",
        5126,
        r#", "min": [0], "max": [1]"#,
    );
    let quats = a.add(
        &bytes_of(
            &[0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            f32::to_le_bytes,
        ),
        2,
        "VEC4",
        5126,
        "",
    );
    let channels: Vec<String> = (0..5)
        .map(|n| format!(r#"{{"sampler": 0, "target": {{"node": {n}, "path": "rotation"}}}}"#))
        .collect();
    let animation = format!(
        r#"{{"samplers": [{{"input": {times}, "output": {quats}}}], "channels": [{}]}}"#,
        channels.join(", ")
    );
    let text = a.finish(&format!(
        r#""scenes": [{{"nodes": [0]}}], "scene": 0,
  "nodes": [{{"mesh": 0, "children": [1]}}, {{"children": [2]}}, {{"children": [3]}}, {{"children": [4]}}, {{}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {tri}}}}}]}}],
  "animations": [{animation}, {animation}, {animation}]"#
    ));
    let dir = common::output_dir("gltf_compressed/animation_conflicts");
    let scene = load(&write(&dir, "clips.gltf", &text));
    let conflicts: Vec<&String> = scene
        .notes
        .iter()
        .filter(|n| n.contains("last wins"))
        .collect();
    assert_eq!(conflicts.len(), 1, "{:?}", scene.notes);
    assert!(
        conflicts[0].starts_with(
            "5 node properties are driven by animation #0, animation #1, animation #2: the last wins"
        ) && conflicts[0].ends_with("e.g. the rotation of node #0, the rotation of node #1, the rotation of node #2 and 2 more"),
        "{}",
        conflicts[0]
    );
    assert_eq!(vkpt::scene::note_line("warning: x"), "warning: x");
    assert_eq!(vkpt::scene::note_line("x"), "note: x");
}

#[test]
fn unusable_texture_references_are_one_note_per_reason_with_a_count() {
    let dir = common::output_dir("gltf_compressed/texture_notes");
    std::fs::write(dir.join("checker.png"), checker_png()).unwrap();
    let text = quad_file(false, "checker.png").replace(
        r#""baseColorTexture": {"index": 0}, "metallicFactor": 0}"#,
        r#""baseColorTexture": {"index": 0, "texCoord": 2}, "metallicFactor": 0}, "emissiveTexture": {"index": 0, "texCoord": 3}, "normalTexture": {"index": 0, "texCoord": 2}"#,
    );
    assert!(text.contains("texCoord"), "the edit applies");
    let scene = load(&write(&dir, "texcoords.gltf", &text));
    let unsupported: Vec<&String> = scene
        .notes
        .iter()
        .filter(|n| n.contains("is not supported (only sets 0 and 1)"))
        .collect();
    assert_eq!(unsupported.len(), 2, "{:?}", scene.notes);
    assert!(
        unsupported
            .iter()
            .any(|n| n.starts_with("2 texture references (material ") && n.contains("TEXCOORD_2")),
        "{unsupported:?}"
    );
}
