//! The glTF loader on the bundled scenes and on small hand-written files:
//! winding, normals, cameras, defaults, and clean errors on bad input.

use crate::common;
use glam::Vec3;
use std::path::{Path, PathBuf};
use vkpt::scene::{AlphaMode, MaterialKind, Scene, Triangle};

fn bundled(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// The scene with its positions back in the file's coordinates: the loader
/// stores them relative to `Scene::world_origin` (the camera), and these
/// tests check where the file put things. (Exact to f32 rounding here: the
/// scenes lie within a few units of the file's origin.)
fn in_file_coordinates(mut scene: Scene) -> Scene {
    let origin = scene.world_origin;
    let back = |p: &mut Vec3| *p = (origin + p.as_dvec3()).as_vec3();
    scene
        .triangles
        .iter_mut()
        .for_each(|t| t.positions.iter_mut().for_each(back));
    scene.cameras.iter_mut().for_each(|c| back(&mut c.position));
    scene.lights.iter_mut().for_each(|l| back(&mut l.position));
    scene.world_origin = glam::DVec3::ZERO;
    scene
}

fn geometric_normal(t: &Triangle) -> Vec3 {
    let [p0, p1, p2] = t.positions;
    (p1 - p0).cross(p2 - p0).normalize()
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// A one-node glTF with non-indexed triangles (positions, optional normals)
/// whose buffer is a data URI. `node_extra` is spliced into the node object.
fn tiny_gltf(positions: &[f32], normals: Option<&[f32]>, node_extra: &str) -> String {
    let mut data = f32_bytes(positions);
    let count = positions.len() / 3;
    let mut attributes = r#""POSITION": 0"#.to_string();
    let mut accessors = format!(
        r#"{{"bufferView": 0, "componentType": 5126, "count": {count}, "type": "VEC3", "min": [-10, -10, -10], "max": [10, 10, 10]}}"#
    );
    let mut views = format!(
        r#"{{"buffer": 0, "byteOffset": 0, "byteLength": {}}}"#,
        data.len()
    );
    if let Some(n) = normals {
        let offset = data.len();
        data.extend(f32_bytes(n));
        attributes.push_str(r#", "NORMAL": 1"#);
        accessors.push_str(&format!(
            r#", {{"bufferView": 1, "componentType": 5126, "count": {count}, "type": "VEC3"}}"#
        ));
        views.push_str(&format!(
            r#", {{"buffer": 0, "byteOffset": {offset}, "byteLength": {}}}"#,
            data.len() - offset
        ));
    }
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0, "name": "the node" {node_extra}}}],
  "meshes": [{{"name": "tri", "primitives": [{{"attributes": {{{attributes}}}}}]}}],
  "accessors": [{accessors}],
  "bufferViews": [{views}],
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}]
}}"#,
        data.len(),
        common::gltf_builder::base64(&data)
    )
}

const ONE_TRIANGLE: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
const UP_NORMALS: [f32; 9] = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];

fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, contents).expect("can write a temp file");
    path
}

/// Loads without panicking; an error must name the file.
fn load_checked(path: &Path) -> Result<Scene, String> {
    let result = std::panic::catch_unwind(|| Scene::load(path))
        .unwrap_or_else(|_| panic!("the loader panicked on {}", path.display()));
    result.map_err(|e| {
        let message = format!("{e:#}");
        let name = path.file_name().unwrap().to_string_lossy();
        assert!(
            message.contains(&*name),
            "the error does not name the file: {message}"
        );
        assert!(
            format!("{e}").contains(&*name),
            "the top-level error does not name the file: {e}"
        );
        message
    })
}

#[test]
fn cornell_box_is_the_classic_one() {
    let scene = Scene::load(&bundled("cornell-box.gltf")).expect("the bundled Cornell box loads");
    assert_eq!(
        scene.cameras[0].position,
        Vec3::ZERO,
        "the camera is the origin"
    );
    let scene = in_file_coordinates(scene);
    assert!(
        scene.notes.is_empty(),
        "unexpected notes: {:?}",
        scene.notes
    );
    assert_eq!(scene.environment, None);
    assert_eq!(scene.cameras.len(), 1);
    let cam = &scene.cameras[0];
    assert_eq!(cam.name, "main");
    assert!(cam.position.distance(Vec3::new(0.278, 0.273, -0.8)) < 1e-5);
    assert!(
        cam.forward.distance(Vec3::Z) < 1e-5,
        "camera looks along {}",
        cam.forward
    );
    assert!(cam.up.distance(Vec3::Y) < 1e-5);
    assert!((cam.yfov.to_degrees() - 39.3077).abs() < 1e-3);
    assert_eq!(cam.aspect_ratio, Some(1.0));

    // The light: two triangles facing down, single-sided, emission (17, 12, 4).
    assert_eq!(scene.emissive_triangle_count(), 2);
    for t in &scene.triangles {
        let m = &scene.materials[t.material as usize];
        let n = geometric_normal(t);
        for shading in t.normals {
            assert!(
                shading.distance(n) < 1e-4,
                "shading normal {shading} vs face normal {n}"
            );
        }
        if m.is_emissive() {
            assert!(n.distance(Vec3::NEG_Y) < 1e-5, "light normal {n}");
            assert!(m.emission.distance(Vec3::new(17.0, 12.0, 4.0)) < 1e-4);
            assert!(!m.double_sided);
            assert!(t.positions.iter().all(|p| (p.y - 0.5487).abs() < 1e-6));
        }
    }
    let white = scene
        .materials
        .iter()
        .position(|m| m.name == "white")
        .unwrap();
    let red = scene
        .materials
        .iter()
        .position(|m| m.name == "red")
        .unwrap();
    let green = scene
        .materials
        .iter()
        .position(|m| m.name == "green")
        .unwrap();
    assert_eq!(
        scene.materials[red].base_color,
        Vec3::new(0.63, 0.065, 0.05)
    );

    // Walls face into the room, boxes face outward.
    let room_centre = Vec3::new(0.278, 0.2744, 0.2796);
    let short_box = Vec3::new(0.186, 0.0825, 0.1685);
    let tall_box = Vec3::new(0.3685, 0.165, 0.3512);
    let (mut walls, mut boxes) = (0, 0);
    for t in &scene.triangles {
        let n = geometric_normal(t);
        let c = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
        let on = |f: fn(Vec3) -> f32, v: f32| t.positions.iter().all(|p| (f(*p) - v).abs() < 1e-6);
        let is_wall = t.material as usize == red
            || t.material as usize == green
            || (t.material as usize == white
                && (on(|p| p.y, 0.0) || on(|p| p.y, 0.5488) || on(|p| p.z, 0.5592)));
        if is_wall {
            walls += 1;
            assert!(
                n.dot(room_centre - c) > 0.0,
                "wall triangle {:?} faces out of the box",
                t.positions
            );
        } else if t.material as usize == white {
            boxes += 1;
            let centre = if c.distance(short_box) < c.distance(tall_box) {
                short_box
            } else {
                tall_box
            };
            assert!(
                n.dot(c - centre) > 0.0,
                "box triangle {:?} faces inward",
                t.positions
            );
        }
    }
    assert_eq!(walls, 10, "5 walls of 2 triangles");
    assert_eq!(boxes, 20, "2 boxes of 5 faces of 2 triangles");
}

#[test]
fn white_furnace_sets_its_environment() {
    let scene =
        Scene::load(&bundled("white-furnace.gltf")).expect("the bundled white furnace loads");
    let scene = in_file_coordinates(scene);
    assert_eq!(scene.environment, Some(Vec3::ONE));
    assert!(
        !scene
            .notes
            .iter()
            .any(|n| n.contains("light") || n.contains("environment")),
        "notes about lights: {:?}",
        scene.notes
    );
    assert_eq!(scene.triangles.len(), 1280);
    assert_eq!(scene.materials[0].name, "albedo 0.8");
    assert_eq!(scene.materials[0].base_color, Vec3::splat(0.8));
    assert_eq!(scene.emissive_triangle_count(), 0);
    for t in &scene.triangles {
        let c = (t.positions[0] + t.positions[1] + t.positions[2]) / 3.0;
        assert!(geometric_normal(t).dot(c) > 0.0, "inward-facing triangle");
        for (p, n) in t.positions.iter().zip(t.normals) {
            assert!((p.length() - 1.0).abs() < 1e-5);
            assert!(n.distance(p.normalize()) < 1e-4, "smooth normals");
        }
    }
    let cam = &scene.cameras[0];
    assert!(cam.position.distance(Vec3::new(0.0, 0.0, 4.0)) < 1e-6);
    assert!(cam.forward.distance(Vec3::NEG_Z) < 1e-6);
    let fill = (0.25f32).asin().tan() / (0.5 * cam.yfov).tan();
    assert!(
        (fill - 0.6).abs() < 0.01,
        "the sphere fills {fill} of the frame height"
    );
}

#[test]
fn negative_scale_flips_the_winding() {
    let dir = common::fresh_output_dir("scene_loading", "mirror");
    let plain = write(
        &dir,
        "plain.gltf",
        tiny_gltf(&ONE_TRIANGLE, Some(&UP_NORMALS), ""),
    );
    let mirrored = write(
        &dir,
        "mirrored.gltf",
        tiny_gltf(&ONE_TRIANGLE, Some(&UP_NORMALS), r#", "scale": [-1, 1, 1]"#),
    );
    for path in [plain, mirrored] {
        let scene = load_checked(&path).unwrap();
        assert_eq!(scene.triangles.len(), 1);
        let t = &scene.triangles[0];
        assert!(
            geometric_normal(t).distance(Vec3::Z) < 1e-6,
            "{}: front face turned to {}",
            path.display(),
            geometric_normal(t)
        );
        for n in t.normals {
            assert!(n.distance(Vec3::Z) < 1e-6, "shading normal {n}");
        }
    }
    // The mirrored triangle is really mirrored.
    let scene = load_checked(&dir.join("mirrored.gltf")).unwrap();
    assert!(scene.triangles[0].positions.iter().any(|p| p.x < -0.5));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn non_indexed_primitive_without_normals_gets_flat_normals() {
    let dir = common::fresh_output_dir("scene_loading", "flat");
    // A quad in the XZ plane as two non-indexed triangles facing +Y, plus a
    // degenerate triangle that must be dropped with a note.
    let positions = [
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, //
        0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, //
        0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0,
    ];
    let path = write(
        &dir,
        "quad.gltf",
        tiny_gltf(&positions, None, r#", "translation": [0, 2, 0]"#),
    );
    let scene = in_file_coordinates(load_checked(&path).unwrap());
    assert_eq!(scene.triangles.len(), 2);
    for t in &scene.triangles {
        assert!(geometric_normal(t).distance(Vec3::Y) < 1e-6);
        assert_eq!(t.normals, [Vec3::Y; 3]);
        assert!(t.positions.iter().all(|p| p.y == 2.0));
    }
    assert!(
        scene
            .notes
            .iter()
            .any(|n| n.contains("dropped 1 zero-area triangle")),
        "{:?}",
        scene.notes
    );
    // Defaults: the glTF default material, an automatic camera, a white environment.
    assert_eq!(scene.materials.len(), 1);
    assert_eq!(scene.materials[0], vkpt::scene::Material::gltf_default());
    // glTF 2.0's default material: every property at its default.
    let m = &scene.materials[0];
    assert_eq!(
        (m.kind, m.base_color, m.metallic, m.roughness),
        (MaterialKind::Gltf, Vec3::ONE, 1.0, 1.0)
    );
    assert!(
        scene
            .notes
            .iter()
            .any(|n| n.contains("glTF default material")),
        "{:?}",
        scene.notes
    );
    assert_eq!(scene.cameras.len(), 1);
    assert_eq!(scene.cameras[0].name, "auto");
    assert_eq!(scene.environment, Some(Vec3::ONE));
    assert!(scene.notes.iter().any(|n| n.contains("camera 'auto'")));
    assert!(
        scene
            .notes
            .iter()
            .any(|n| n.contains("scene has no lights"))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_files_fail_with_errors_naming_them() {
    let dir = common::fresh_output_dir("scene_loading", "bad");
    let malformed = write(
        &dir,
        "malformed.gltf",
        "{ \"asset\": { \"version\": \"2.0\" ",
    );
    let err = load_checked(&malformed).unwrap_err();
    assert!(err.contains("JSON"), "{err}");

    let missing = dir.join("does-not-exist.gltf");
    load_checked(&missing).unwrap_err();

    // A valid .glb, then every truncation of it.
    let json = tiny_gltf(&ONE_TRIANGLE, None, "");
    let mut json_bytes = json.into_bytes();
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let total = 12 + 8 + json_bytes.len();
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend((total as u32).to_le_bytes());
    glb.extend((json_bytes.len() as u32).to_le_bytes());
    glb.extend(0x4E4F_534Au32.to_le_bytes());
    glb.extend(&json_bytes);
    let whole = write(&dir, "whole.glb", &glb);
    assert_eq!(load_checked(&whole).unwrap().triangles.len(), 1);
    for len in (0..glb.len()).step_by(7) {
        let truncated = write(&dir, "truncated.glb", &glb[..len]);
        load_checked(&truncated).unwrap_err();
    }

    // Structural damage: bad indices and counts fail cleanly (or load).
    let good = tiny_gltf(&ONE_TRIANGLE, Some(&UP_NORMALS), "");
    let mutations = [
        (
            r#""count": 3, "type": "VEC3", "min""#,
            r#""count": 4000000000, "type": "VEC3", "min""#,
        ),
        (r#""POSITION": 0"#, r#""POSITION": 7"#),
        (r#""bufferView": 0"#, r#""bufferView": 9"#),
        (r#""mesh": 0"#, r#""mesh": 3"#),
        (r#""nodes": [0]"#, r#""nodes": [0, 0]"#),
        (r#""nodes": [0]"#, r#""nodes": [5]"#),
        (r#""type": "VEC3", "min""#, r#""type": "VEC2", "min""#),
        (r#""componentType": 5126"#, r#""componentType": 5127"#),
        (r#""byteOffset": 0"#, r#""byteOffset": 1000000"#),
        (
            r#""name": "the node""#,
            r#""name": "the node", "matrix": [1, 2]"#,
        ),
        (
            r#""name": "the node""#,
            r#""name": "the node", "children": [0]"#,
        ),
        (r#""version": "2.0""#, r#""version": "1.0""#),
        (r#""scene": 0"#, r#""scene": 4"#),
    ];
    for (k, (from, to)) in mutations.iter().enumerate() {
        assert!(good.contains(from), "mutation {k} does not apply");
        let path = write(
            &dir,
            &format!("mutated-{k}.gltf"),
            good.replacen(from, to, 1),
        );
        let result = load_checked(&path);
        assert!(result.is_err(), "mutation {k} ({to}) was accepted");
    }

    // An unsupported required extension is named.
    let required = good.replacen(
        r#""asset""#,
        r#""extensionsRequired": ["KHR_gaussian_splatting"], "asset""#,
        1,
    );
    let err = load_checked(&write(&dir, "required.gltf", required)).unwrap_err();
    assert!(err.contains("KHR_gaussian_splatting"), "{err}");

    // A malformed vkpt environment is an error; a valid one is used.
    for bad in [r#"[1, 1]"#, r#"[1, -1, 1]"#, r#""white""#] {
        let text = good.replacen(
            r#""nodes": [0]}"#,
            &format!(r#""nodes": [0], "extras": {{"vkpt": {{"environment": {bad}}}}}}}"#),
            1,
        );
        let err = load_checked(&write(&dir, "env.gltf", text)).unwrap_err();
        assert!(err.contains("vkpt.environment"), "{err}");
    }
    let text = good.replacen(
        r#""nodes": [0]}"#,
        r#""nodes": [0], "extras": {"vkpt": {"environment": [0.5, 0.25, 0]}}}"#,
        1,
    );
    let scene = load_checked(&write(&dir, "env.gltf", text)).unwrap();
    assert_eq!(scene.environment, Some(Vec3::new(0.5, 0.25, 0.0)));
    assert!(
        !scene.notes.iter().any(|n| n.contains("environment")),
        "{:?}",
        scene.notes
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_images_and_unrendered_features_are_notes() {
    let dir = common::fresh_output_dir("scene_loading", "notes");
    let good = tiny_gltf(&ONE_TRIANGLE, None, "");
    let text = good
        .replacen(
            r#""primitives": [{"#,
            r#""primitives": [{"material": 0, "#,
            1,
        )
        .replacen(
            r#""asset""#,
            r#""materials": [{"name": "glass", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
                 "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}}],
               "textures": [{"source": 0}],
               "images": [{"uri": "no%20such.png"}],
               "asset""#,
            1,
        );
    let scene = load_checked(&write(&dir, "notes.gltf", text)).unwrap();
    let notes = scene.notes.join("\n");
    assert!(
        notes.contains("no such.png") && notes.contains("'glass'"),
        "{notes}"
    );
    // Transmission without a volume is rendered thin-walled, as the
    // extension defines: nothing to report.
    assert!(!notes.contains("thin-walled"), "{notes}");
    let glass = &scene.materials[0];
    assert_eq!(glass.kind, MaterialKind::Gltf);
    assert_eq!((glass.transmission, glass.thickness), (1.0, 0.0));
    assert!(notes.contains("baseColorTexture"), "{notes}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn material_models_load_from_gltf_and_extras() {
    let scene = Scene::load(&bundled("materials-showcase.gltf")).expect("loads");
    let by_name = |n: &str| {
        scene
            .materials
            .iter()
            .find(|m| m.name == n)
            .unwrap_or_else(|| panic!("material {n}"))
    };
    let mirror = by_name("mirror");
    assert_eq!(mirror.kind, MaterialKind::Mirror);
    assert_eq!(mirror.base_color, Vec3::splat(0.9));
    let glass = by_name("glass");
    assert_eq!((glass.kind, glass.ior), (MaterialKind::Gltf, 1.5));
    assert_eq!((glass.transmission, glass.thickness), (1.0, 1.0));
    let gold = by_name("rough gold");
    assert_eq!(gold.kind, MaterialKind::Gltf);
    assert_eq!((gold.metallic, gold.roughness), (1.0, 0.45));
    let green = by_name("absorbing green glass");
    // attenuationColor (0.2, 0.8, 0.3) after 0.05 m: -ln(c) / 0.05.
    let expect = Vec3::new(-(0.2f32.ln()), -(0.8f32.ln()), -(0.3f32.ln())) / 0.05;
    assert!(
        (green.attenuation - expect).abs().max_element() < 1e-4,
        "{}",
        green.attenuation
    );
    let tinted = by_name("half-metal, tinted specular");
    assert_eq!(tinted.specular_factor, 0.8);
    assert_eq!(tinted.specular_color, Vec3::new(1.0, 0.5, 0.5));
    let air = by_name("air in glass");
    assert_eq!((air.kind, air.ior), (MaterialKind::Gltf, 1.0 / 1.5));
    let phong = by_name("phong blue");
    assert_eq!(phong.kind, MaterialKind::Phong);
    assert_eq!(phong.specular, Vec3::splat(0.5));
    assert_eq!(phong.shininess, 60.0);
    assert_eq!(by_name("white").kind, MaterialKind::Lambert);
    // Nothing about these materials is reported as unrendered.
    let notes = scene.notes.join("\n");
    assert!(!notes.contains("not rendered"), "{notes}");
    assert!(!notes.contains("metallic"), "{notes}");

    let bubble = Scene::load(&bundled("furnace-glass-0.67.gltf")).expect("loads");
    assert_eq!(bubble.materials[0].kind, MaterialKind::Gltf);
    assert_eq!(bubble.materials[0].transmission, 1.0);
    assert_eq!(bubble.materials[0].ior, 0.67);
    let glass = Scene::load(&bundled("furnace-glass-1.5.gltf")).expect("loads");
    assert!(glass.notes.iter().all(|n| !n.contains("thin-walled")));
    let mirror = Scene::load(&bundled("furnace-mirror-0.8.gltf")).expect("loads");
    assert_eq!(mirror.materials[0].kind, MaterialKind::Mirror);
    assert_eq!(mirror.materials[0].base_color, Vec3::splat(0.8));
}

#[test]
fn phong_extras_are_clamped_to_conserve_energy_and_checked() {
    let dir = common::fresh_output_dir("scene_loading", "phong");
    let with_material = |material: &str| {
        tiny_gltf(&ONE_TRIANGLE, None, "")
            .replacen(
                r#""primitives": [{"#,
                r#""primitives": [{"material": 0, "#,
                1,
            )
            .replacen(
                r#""asset""#,
                &format!(r#""materials": [{material}], "asset""#),
                1,
            )
    };
    let text = with_material(
        r#"{"name": "hot", "extras": {"vkpt": {"phong": {"kd": [0.8, 0.2, 0.1], "ks": [0.6, 0.5, 0.2], "n": 10}}}}"#,
    );
    let scene = load_checked(&write(&dir, "hot.gltf", text)).unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.kind, MaterialKind::Phong);
    assert!(
        ((m.base_color + m.specular) - Vec3::new(1.0, 0.7, 0.3))
            .abs()
            .max_element()
            < 1e-6
    );
    assert!((m.base_color.x - 0.8 / 1.4).abs() < 1e-6);
    let notes = scene.notes.join("\n");
    assert!(
        notes.contains("warning: material 'hot'") && notes.contains("above 1"),
        "{notes}"
    );

    let bad = with_material(
        r#"{"name": "bad", "extras": {"vkpt": {"phong": {"ks": [0.5, 0.5], "n": 10}}}}"#,
    );
    let err = load_checked(&write(&dir, "bad.gltf", bad)).unwrap_err();
    assert!(err.contains("vkpt.phong.ks"), "{err}");
    let two = with_material(
        r#"{"extras": {"vkpt": {"phong": {"ks": [0.5, 0.5, 0.5], "n": 1}, "mirror": {}}}}"#,
    );
    let err = load_checked(&write(&dir, "two.gltf", two)).unwrap_err();
    assert!(err.contains("more than one material model"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gltf_material_parameters_are_checked() {
    let dir = common::fresh_output_dir("scene_loading", "pbr");
    let with_material = |material: &str| {
        tiny_gltf(&ONE_TRIANGLE, None, "")
            .replacen(
                r#""primitives": [{"#,
                r#""primitives": [{"material": 0, "#,
                1,
            )
            .replacen(
                r#""asset""#,
                &format!(r#""materials": [{material}], "asset""#),
                1,
            )
    };
    // Defaults: metallic 1, roughness 1 (the glTF spec's), a rough metal.
    let scene = load_checked(&write(
        &dir,
        "default.gltf",
        with_material(r#"{"name": "m"}"#),
    ))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!(
        (m.kind, m.metallic, m.roughness),
        (MaterialKind::Gltf, 1.0, 1.0)
    );
    // alphaMode: MASK with its cutoff (0.5 by default), BLEND as coverage (said).
    for (mode, expected) in [
        (r#""alphaMode": "OPAQUE""#, AlphaMode::Opaque),
        (r#""alphaMode": "MASK""#, AlphaMode::Mask { cutoff: 0.5 }),
        (
            r#""alphaMode": "MASK", "alphaCutoff": 0.25"#,
            AlphaMode::Mask { cutoff: 0.25 },
        ),
        (r#""alphaMode": "BLEND""#, AlphaMode::Blend),
    ] {
        let gltf = with_material(&format!(r#"{{"name": "m", {mode}}}"#));
        let scene = load_checked(&write(&dir, "alpha.gltf", gltf)).unwrap();
        assert_eq!(scene.materials[0].alpha_mode, expected, "{mode}");
        let said = scene
            .notes
            .iter()
            .any(|n| n.contains("alphaMode BLEND on material 'm' is rendered as coverage"));
        assert_eq!(said, expected == AlphaMode::Blend, "{:?}", scene.notes);
    }
    // specularFactor 0 on a non-metal is Lambertian.
    let lambert = with_material(
        r#"{"name": "m", "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.3},
            "extensions": {"KHR_materials_specular": {"specularFactor": 0}}}"#,
    );
    let scene = load_checked(&write(&dir, "lambert.gltf", lambert)).unwrap();
    assert_eq!(scene.materials[0].kind, MaterialKind::Lambert);
    // Out-of-range factors are errors naming the material.
    for (bad, what) in [
        (
            r#"{"name": "m", "pbrMetallicRoughness": {"metallicFactor": 2}}"#,
            "metallicFactor",
        ),
        (
            r#"{"name": "m", "pbrMetallicRoughness": {"roughnessFactor": -1}}"#,
            "roughnessFactor",
        ),
        (
            r#"{"name": "m", "extensions": {"KHR_materials_volume": {"thicknessFactor": 1, "attenuationColor": [2, 1, 1]}}}"#,
            "attenuationColor",
        ),
        (r#"{"name": "m", "alphaMode": "ADD"}"#, "alphaMode"),
    ] {
        let err = load_checked(&write(&dir, "bad.gltf", with_material(bad)))
            .expect_err("out of range")
            .to_string();
        assert!(
            err.contains("material #0 'm'") && err.contains(what),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The Cornell box under a parent node translating it by 1e5, 1e6 and
/// 1e7 (camera included) loads to the untranslated box's f32 triangles,
/// camera and normals, to the last bit but for rounding ties (1 ULP):
/// transforms are composed in f64 and the camera's position subtracted
/// before anything becomes f32. The world origin is the camera's place in
/// the file.
#[test]
fn a_scene_far_from_the_origin_loads_to_the_same_camera_relative_geometry() {
    let near = Scene::load(&bundled("cornell-box.gltf")).unwrap();
    assert_eq!(near.world_origin, glam::DVec3::new(0.278, 0.273, -0.8));
    for (name, shift) in [
        ("cornell-translated-1e5", [1e5, 1e5, 1e5]),
        ("cornell-translated-1e6", [1e6, -1e6, 1e6]),
        ("cornell-translated-1e7", [1e7, 1e7, -1e7]),
    ] {
        let far = Scene::load(&bundled(&format!("hard/{name}.gltf"))).unwrap();
        let moved = near.world_origin + glam::DVec3::from(shift);
        assert_eq!(far.world_origin, moved, "{name}: world origin");
        // f64 rounds 1e7 + 0.278 and 0.278 differently (by ~1e-10 m), so
        // a coordinate may round to the neighbouring f32; never further.
        let ulps = |a: f32, b: f32| (a.to_bits() as i64 - b.to_bits() as i64).unsigned_abs();
        let (mut differing, mut worst) = (0, 0);
        for (a, b) in near.triangles.iter().zip(&far.triangles) {
            assert_eq!(a.material, b.material);
            let pairs = a.positions.iter().zip(&b.positions);
            let pairs = pairs.chain(a.normals.iter().zip(&b.normals));
            for (p, q) in pairs {
                for k in 0..3 {
                    let d = ulps(p[k], q[k]);
                    differing += (d > 0) as usize;
                    worst = worst.max(d);
                }
            }
        }
        println!(
            "{name}: {differing} of {} coordinates differ, by at most {worst} ULP",
            near.triangles.len() * 18
        );
        assert!(worst <= 1, "{name}: a coordinate moved by {worst} ULP");
        assert_eq!(far.cameras[0].position, Vec3::ZERO, "{name}: camera");
        assert_eq!(near.cameras[0].forward, far.cameras[0].forward);
        assert!(
            !far.notes.iter().any(|n| n.contains("far from")),
            "{name}: a node translation loses nothing, yet a note says so: {:?}",
            far.notes
        );
    }
}

/// Rendering through another camera (`--camera`, `LoadOptions::camera`)
/// makes that camera the origin; a name or an index finds it.
#[test]
fn the_rendering_camera_is_the_world_origin() {
    let dir = common::fresh_output_dir("scene_loading", "origin-camera");
    let positions = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let gltf = tiny_gltf(
        &positions,
        None,
        r#", "translation": [1e6, 0, 0], "children": [1, 2]},
        {"camera": 0, "name": "near", "translation": [0, 0, 3]},
        {"camera": 0, "name": "far", "translation": [0, 0, 300]"#,
    )
    .replace(
        r#""meshes""#,
        r#""cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}], "meshes""#,
    );
    let path = write(&dir, "two-cameras.gltf", gltf);
    let load = |camera: Option<&str>| {
        let options = vkpt::scene::LoadOptions {
            camera: camera.map(str::to_string),
            ..Default::default()
        };
        Scene::load_with(&path, &options).unwrap()
    };
    for (wanted, index, z) in [
        (None, 0, 3.0),
        (Some("far"), 1, 300.0),
        (Some("1"), 1, 300.0),
    ] {
        let scene = load(wanted);
        assert_eq!(scene.world_origin, glam::DVec3::new(1e6, 0.0, z));
        assert_eq!(scene.cameras[index].position, Vec3::ZERO, "{wanted:?}");
        let other = &scene.cameras[1 - index];
        assert_eq!(other.position.z, (if index == 0 { 297.0 } else { -297.0 }));
        assert_eq!(
            scene.triangles[0].positions[1],
            Vec3::new(1.0, 0.0, -z as f32)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Positions stored in the file's vertex buffer 1e5 from the origin (f32
/// steps of 0.0078) are rounded before vkpt sees them: a note says so,
/// naming the mesh; the same triangle near the origin gets no note.
#[test]
fn huge_coordinates_in_the_vertex_buffer_get_a_note() {
    let dir = common::fresh_output_dir("scene_loading", "huge-vertices");
    let far: Vec<f32> = [0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.5, 0.0]
        .iter()
        .map(|c| c + 1e5)
        .collect();
    let scene = load_checked(&write(&dir, "far.gltf", tiny_gltf(&far, None, ""))).unwrap();
    let note = scene.notes.iter().find(|n| n.contains("far from"));
    println!("{note:?}");
    let note = note.expect("a note about coarse positions");
    assert!(
        note.contains("mesh 'tri'") && note.contains("7.81e-3"),
        "{note}"
    );
    let near = [0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.5, 0.0];
    let scene = load_checked(&write(&dir, "near.gltf", tiny_gltf(&near, None, ""))).unwrap();
    assert!(
        !scene.notes.iter().any(|n| n.contains("far from")),
        "{:?}",
        scene.notes
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `KHR_materials_variants`: `--variant` (`LoadOptions::variant`) swaps
/// the materials a primitive maps for that variant, by name or index; the
/// default keeps the primitive's own material and says which variants
/// exist; unknown variants and mappings to missing materials are errors.
#[test]
fn material_variants_pick_the_mapped_material() {
    let dir = common::fresh_output_dir("scene_loading", "variants");
    let variants = |mappings: &str| {
        tiny_gltf(&ONE_TRIANGLE, None, "")
            .replace(
                r#""primitives": [{"#,
                &format!(
                    r#""primitives": [{{"material": 0, "extensions": {{"KHR_materials_variants": {{"mappings": [{mappings}]}}}}, "#
                ),
            )
            .replace(
                r#""scene": 0,"#,
                r#""scene": 0,
  "extensionsUsed": ["KHR_materials_variants"],
  "extensions": {"KHR_materials_variants": {"variants": [{"name": "red"}, {"name": "blue"}, {"name": "plain"}]}},
  "materials": [
    {"name": "own", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}},
    {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1]}},
    {"name": "blue", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 1, 1]}}],"#,
            )
    };
    let good = write(
        &dir,
        "variants.gltf",
        variants(r#"{"material": 1, "variants": [0]}, {"material": 2, "variants": [1]}"#),
    );
    let load = |variant: Option<&str>| {
        let options = vkpt::scene::LoadOptions {
            variant: variant.map(str::to_string),
            ..Default::default()
        };
        Scene::load_with(&good, &options).map_err(|e| format!("{e:#}"))
    };
    let material_of = |scene: &Scene| {
        scene.materials[scene.triangles[0].material as usize]
            .name
            .clone()
    };
    let default = load(None).unwrap();
    assert_eq!(material_of(&default), "own");
    assert!(
        default
            .notes
            .iter()
            .any(|n| n.contains("variants 'red', 'blue', 'plain'")),
        "no note lists the variants: {:?}",
        default.notes
    );
    assert_eq!(material_of(&load(Some("red")).unwrap()), "red");
    assert_eq!(material_of(&load(Some("blue")).unwrap()), "blue");
    assert_eq!(material_of(&load(Some("1")).unwrap()), "blue");
    // A variant the primitive does not map keeps its own material.
    assert_eq!(material_of(&load(Some("plain")).unwrap()), "own");
    let err = load(Some("green")).unwrap_err();
    assert!(
        err.contains("--variant green") && err.contains("'red', 'blue', 'plain'"),
        "{err}"
    );

    let bad = write(
        &dir,
        "bad-mapping.gltf",
        variants(r#"{"material": 7, "variants": [0]}"#),
    );
    let err = format!("{:#}", Scene::load(&bad).unwrap_err());
    assert!(
        err.contains("mesh #0 primitive #0") && err.contains("material 7 does not exist"),
        "{err}"
    );
    let no_variants = write(&dir, "plain.gltf", tiny_gltf(&ONE_TRIANGLE, None, ""));
    let options = vkpt::scene::LoadOptions {
        variant: Some("red".into()),
        ..Default::default()
    };
    let err = format!(
        "{:#}",
        Scene::load_with(&no_variants, &options).unwrap_err()
    );
    assert!(err.contains("no material variants"), "{err}");
}

/// `KHR_materials_unlit`: the base colour becomes emission, nothing is
/// scattered, and an unlit surface is not a lamp: the scene still gets the
/// default light, so lit materials beside it are not left black.
#[test]
fn unlit_materials_emit_their_base_colour() {
    let dir = common::fresh_output_dir("scene_loading", "unlit");
    let gltf = tiny_gltf(&ONE_TRIANGLE, None, "")
        .replace(r#""primitives": [{"#, r#""primitives": [{"material": 0, "#)
        .replace(
            r#""scene": 0,"#,
            r#""scene": 0,
  "extensionsUsed": ["KHR_materials_unlit"],
  "materials": [{"name": "flat", "doubleSided": true,
    "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 1], "metallicFactor": 0},
    "extensions": {"KHR_materials_unlit": {}}}],"#,
        );
    let scene = Scene::load(&write(&dir, "unlit.gltf", gltf)).unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.emission, Vec3::new(0.2, 0.4, 0.6));
    assert_eq!(
        m.base_color,
        Vec3::ZERO,
        "an unlit surface scatters nothing"
    );
    assert_eq!(m.kind, MaterialKind::Lambert);
    assert!(m.double_sided);
    assert_eq!(scene.environment, Some(Vec3::ONE), "{:?}", scene.notes);
    assert!(
        scene
            .notes
            .iter()
            .any(|n| n.contains("KHR_materials_unlit on material 'flat'")
                && !n.contains("not rendered")),
        "{:?}",
        scene.notes
    );
}
