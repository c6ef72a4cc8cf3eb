//! glTF cameras as vkpt reads them: perspective with the vkpt lens extras,
//! orthographic, and clear errors and notes for bad lens data.

use crate::common;
use std::path::{Path, PathBuf};
use vkpt::scene::{FilterKind, PixelFilter, Projection, Scene};

fn scene_path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

#[test]
fn depth_of_field_scene_has_a_six_blade_lens_and_an_orthographic_camera() {
    let scene = Scene::load(&scene_path("scenes/depth-of-field.gltf")).expect("loads");
    assert!(
        scene.notes.iter().all(|n| !n.contains("camera")),
        "{:?}",
        scene.notes
    );
    let main = &scene.cameras[0];
    assert_eq!(main.name, "main");
    assert_eq!(main.projection, Projection::Perspective);
    assert_eq!(main.lens.focal_length, Some(0.085));
    assert_eq!(main.lens.fstop, 1.2);
    assert_eq!(main.lens.focus_distance, Some(2.5));
    assert_eq!(main.lens.blades, 6);
    // Aperture diameter = focal length / f-number.
    assert!((2.0 * main.lens.aperture_radius(main.yfov) - 0.085 / 1.2).abs() < 1e-7);
    assert_eq!(main.filter, PixelFilter::default());
    assert_eq!(main.filter.kind, FilterKind::Box);
    let ortho = &scene.cameras[1];
    assert_eq!(
        ortho.projection,
        Projection::Orthographic { half_height: 0.4 }
    );
    assert!((ortho.aspect_ratio.unwrap() - 1.5).abs() < 1e-6);
    assert!(ortho.lens.is_pinhole());
}

/// A minimal glTF (one triangle, one camera) with the given camera JSON.
fn with_camera(name: &str, camera: &str) -> PathBuf {
    let dir = common::output_dir("camera_loading");
    let path = dir.join(format!("{name}.gltf"));
    // Three vertices (0,0,0), (1,0,0), (0,1,0) as base64 float32.
    let positions = "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
        "nodes":[{{"mesh":0}},{{"camera":0,"translation":[0,0,3]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}],
        "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{positions}"}}],
        "cameras":[{camera}]}}"#
    );
    std::fs::write(&path, json).expect("written");
    path
}

fn load_error(name: &str, camera: &str) -> String {
    let err = Scene::load(&with_camera(name, camera)).expect_err("must fail");
    format!("{err:#}")
}

#[test]
fn bad_lens_extras_are_errors_naming_the_camera() {
    let persp = |extras: &str| {
        format!(
            r#"{{"name":"cam","type":"perspective","perspective":{{"yfov":0.5}},"extras":{{"vkpt":{extras}}}}}"#
        )
    };
    let e = load_error(
        "negative-fstop",
        &persp(r#"{"lens":{"fstop":-1,"focus_distance":2}}"#),
    );
    assert!(
        e.contains("camera #0 'cam': extras vkpt.lens.fstop must be a non-negative number"),
        "{e}"
    );
    let e = load_error("no-focus", &persp(r#"{"lens":{"fstop":2}}"#));
    assert!(
        e.contains("camera 'cam' has f-number 2 but no focus distance"),
        "{e}"
    );
    let e = load_error(
        "two-blades",
        &persp(r#"{"lens":{"fstop":2,"focus_distance":1,"blades":2}}"#),
    );
    assert!(
        e.contains("blades must be 0 (a round aperture) or 3 to 64 blades"),
        "{e}"
    );
    let e = load_error("lens-string", &persp(r#"{"lens":"fast"}"#));
    assert!(e.contains("extras vkpt.lens must be an object"), "{e}");
    let e = load_error(
        "ortho-zero",
        r#"{"type":"orthographic","orthographic":{"xmag":1,"ymag":0}}"#,
    );
    assert!(
        e.contains("orthographic.ymag must be a non-zero number"),
        "{e}"
    );
}

#[test]
fn lens_decisions_are_notes() {
    let scene = Scene::load(&with_camera(
        "notes",
        r#"{"name":"cam","type":"perspective","perspective":{"yfov":0.5},
            "extras":{"vkpt":{"lens":{"fstop":2,"focus_distance":2,"focal_length":0.05,"sensor_height":0.036,"zoom":3}}}}"#,
    ))
    .expect("loads");
    let notes = scene.notes.join("\n");
    assert!(
        notes.contains("extras vkpt.lens.zoom is not understood"),
        "{notes}"
    );
    assert!(notes.contains("yfov sets the field of view"), "{notes}");
    let scene = Scene::load(&with_camera(
        "derived-focal-length",
        r#"{"name":"cam","type":"perspective","perspective":{"yfov":0.5},
            "extras":{"vkpt":{"lens":{"fstop":2,"focus_distance":2}}}}"#,
    ))
    .expect("loads");
    let notes = scene.notes.join("\n");
    assert!(notes.contains("no focal length given"), "{notes}");
    // 24 mm / (2 tan 0.25) = 47.1 mm.
    let f = scene.cameras[0].lens.focal_length(0.5);
    assert!((f - 0.024 / (2.0 * 0.25f32.tan())).abs() < 1e-7);
}
