//! Bad input gets a one-line error naming the file and the element, and
//! loses nothing: missing or unreadable buffers, URIs that leave the
//! scene's folder, scenes over the device's limits, and every input the
//! loader fuzzer (fuzz/) ever crashed on.

use crate::common;

use std::path::Path;
use std::process::Command;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{LoadOptions, Scene};

/// One triangle whose positions are in the buffer at `uri` (36 bytes), and
/// optionally an image at `image_uri`.
fn gltf_with_buffer(uri: &str, image_uri: Option<&str>) -> String {
    let images = match image_uri {
        Some(u) => format!(r#""images": [{{"uri": "{u}"}}], "#),
        None => String::new(),
    };
    format!(
        r#"{{"asset": {{"version": "2.0"}}, {images}"scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"name": "tri", "primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "buffers": [{{"name": "geometry", "byteLength": 36, "uri": "{uri}"}}]}}"#
    )
}

fn triangle_bytes() -> Vec<u8> {
    [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect()
}

/// Loads without panicking; an error is one line naming the file.
fn load(path: &Path, options: &LoadOptions) -> Result<Scene, String> {
    let result = std::panic::catch_unwind(|| Scene::load_with(path, options))
        .unwrap_or_else(|_| panic!("the loader panicked on {}", path.display()));
    result.map_err(|e| {
        let message = format!("{e:#}");
        assert!(!message.contains('\n'), "not one line: {message}");
        let name = path.file_name().unwrap().to_string_lossy();
        assert!(
            message.contains(&*name),
            "does not name the file: {message}"
        );
        message
    })
}

fn vkpt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_vkpt"))
        .args(args)
        .output()
        .expect("vkpt runs")
}

#[test]
fn missing_or_unreadable_buffers_are_named() {
    let dir = common::fresh_output_dir("bad_input", "buffers");
    let scene = dir.join("missing-bin.gltf");
    std::fs::write(&scene, gltf_with_buffer("geometry.bin", None)).unwrap();
    let err = load(&scene, &LoadOptions::default()).unwrap_err();
    assert!(
        err.contains("buffer #0 'geometry'") && err.contains("geometry.bin"),
        "{err}"
    );

    // A directory where the .bin should be: unreadable.
    std::fs::create_dir_all(dir.join("geometry.bin")).unwrap();
    let err = load(&scene, &LoadOptions::default()).unwrap_err();
    assert!(err.contains("cannot read"), "{err}");
    std::fs::remove_dir(dir.join("geometry.bin")).unwrap();

    // Too short for its byteLength (the file is named), or empty.
    std::fs::write(dir.join("geometry.bin"), &triangle_bytes()[..20]).unwrap();
    let err = load(&scene, &LoadOptions::default()).unwrap_err();
    assert!(
        err.contains("byteLength is 36")
            && err.contains("only 20 bytes were found in")
            && err.contains("geometry.bin"),
        "{err}"
    );
    std::fs::write(dir.join("geometry.bin"), b"").unwrap();
    let err = load(&scene, &LoadOptions::default()).unwrap_err();
    assert!(
        err.contains("only 0 bytes") && err.contains("geometry.bin"),
        "{err}"
    );

    std::fs::write(dir.join("geometry.bin"), triangle_bytes()).unwrap();
    assert_eq!(
        load(&scene, &LoadOptions::default())
            .unwrap()
            .triangles
            .len(),
        1
    );

    // The command: one line on stderr, status 1.
    std::fs::remove_file(dir.join("geometry.bin")).unwrap();
    let o = vkpt(&[scene.to_str().unwrap(), "--device", "cpu", "-q"]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("error: ") && stderr.contains("missing-bin.gltf"));
}

/// An index past the vertices is an error naming the first one, also when
/// the indices are many (checked in parts on every core), read in place
/// (u32) or decoded (u16).
#[test]
fn the_first_index_out_of_range_is_named() {
    let dir = common::fresh_output_dir("bad_input", "indices");
    let n = 3 * 20_000;
    for (component_type, size) in [(5125, 4), (5123, 2)] {
        let mut bytes = triangle_bytes();
        for i in 0..n {
            let v: u32 = match i {
                17_001 => 9,
                40_000 => 3,
                _ => (i % 3) as u32,
            };
            bytes.extend(&v.to_le_bytes()[..size]);
        }
        let gltf = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"name": "tri", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}},
                {{"bufferView": 1, "componentType": {component_type}, "count": {n}, "type": "SCALAR"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}},
                  {{"buffer": 0, "byteOffset": 36, "byteLength": {}}}],
  "buffers": [{{"byteLength": {}, "uri": "indices.bin"}}]}}"#,
            n * size,
            bytes.len()
        );
        std::fs::write(dir.join("indices.bin"), &bytes).unwrap();
        let scene = dir.join("indices.gltf");
        std::fs::write(&scene, gltf).unwrap();
        let err = load(&scene, &LoadOptions::default()).unwrap_err();
        assert!(
            err.contains("index #17001 is 9, but there are only 3 vertices"),
            "{component_type}: {err}"
        );
    }
}

#[test]
fn uris_outside_the_scene_folder_are_refused_unless_allowed() {
    let dir = common::fresh_output_dir("bad_input", "uris");
    let inside = dir.join("scene");
    std::fs::create_dir_all(inside.join("sub")).unwrap();
    std::fs::write(dir.join("secret.bin"), triangle_bytes()).unwrap();
    let absolute = dir.join("secret.bin").to_string_lossy().into_owned();
    let allow = LoadOptions {
        allow_outside_uris: true,
        ..Default::default()
    };
    for (k, uri) in [
        "../secret.bin",
        "%2E%2E/secret.bin",
        "sub/../../secret.bin",
        &absolute,
    ]
    .iter()
    .enumerate()
    {
        let scene = inside.join(format!("escape-{k}.gltf"));
        std::fs::write(&scene, gltf_with_buffer(uri, None)).unwrap();
        let err = load(&scene, &LoadOptions::default()).unwrap_err();
        assert!(
            err.contains("buffer #0 'geometry'") && err.contains("allow_outside_uris"),
            "{uri}: {err}"
        );
        assert_eq!(load(&scene, &allow).unwrap().triangles.len(), 1, "{uri}");
    }

    // A symbolic link inside the folder that leads out of it.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(dir.join("secret.bin"), inside.join("link.bin")).unwrap();
        let scene = inside.join("symlink.gltf");
        std::fs::write(&scene, gltf_with_buffer("link.bin", None)).unwrap();
        let err = load(&scene, &LoadOptions::default()).unwrap_err();
        assert!(err.contains("symbolic link"), "{err}");
        assert!(load(&scene, &allow).is_ok());
    }

    // Images too (they are not read yet, but must not be probed outside).
    std::fs::write(inside.join("geometry.bin"), triangle_bytes()).unwrap();
    let scene = inside.join("image-escape.gltf");
    std::fs::write(
        &scene,
        gltf_with_buffer("geometry.bin", Some("../../etc/passwd")),
    )
    .unwrap();
    let err = load(&scene, &LoadOptions::default()).unwrap_err();
    assert!(err.contains("image #0") && err.contains("outside"), "{err}");

    // The command refuses, and renders with --allow-outside-uris.
    let scene = inside.join("escape-0.gltf");
    let out = dir.join("out.png");
    let args = [
        scene.to_str().unwrap(),
        "--device",
        "cpu",
        "--width",
        "4",
        "--spp",
        "1",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ];
    let o = vkpt(&args);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--allow-outside-uris"));
    let mut allowed = args.to_vec();
    allowed.push("--allow-outside-uris");
    let o = vkpt(&allowed);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.is_file());
}

/// A scene over a device limit is refused before anything is allocated,
/// naming the limit and the excess (limits lowered through the renderer's
/// override instead of building a huge scene). No binding's range bounds
/// a scene array (they are read through texel views, split into parts
/// where large: `vkpt::packed::bindings`); what can bound one is the number
/// of views an array may take, and the device's memory.
#[test]
fn a_scene_over_the_device_limits_is_refused_with_the_excess() {
    let Some(mut gpu) = common::gpu_renderer("a_scene_over_the_device_limits_is_refused") else {
        return;
    };
    let (scene, packed) = common::load("scenes/cornell-box.gltf");
    let settings = RenderSettings {
        width: 8,
        height: 8,
        spp: 1,
        ..RenderSettings::default()
    };
    let nodes = std::mem::size_of_val(packed.nodes.as_slice()) as u64;
    let original = gpu.limits_mut().clone();
    // Views of a 16th of the nodes' texels: more than SCENE_VIEWS parts.
    gpu.limits_mut().max_texel_buffer_elements = nodes / 16 / 16;
    let err = match gpu.render(&scene, &packed, &settings, &|_, _| {}) {
        Ok(_) => panic!("rendered with views of {} texels", nodes / 256),
        Err(e) => format!("{e:#}"),
    };
    println!("{err}");
    assert!(
        err.contains("texel views hold")
            && err.contains("maxTexelBufferElements")
            && err.contains("at most 8 of them")
            && err.contains(" over"),
        "{err}"
    );

    *gpu.limits_mut() = original.clone();
    gpu.limits_mut().device_memory = 1 << 20;
    let err = match gpu.render(&scene, &packed, &settings, &|_, _| {}) {
        Ok(_) => panic!("rendered with 1 MiB of device memory"),
        Err(e) => format!("{e:#}"),
    };
    assert!(err.contains("device memory"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");

    // Restored, the same render works.
    *gpu.limits_mut() = original;
    let image = common::render_gpu(&mut gpu, &scene, &packed, &settings);
    assert_eq!(image.mean.len(), 64);
}

/// Every input in tests/fuzz-regressions/ once crashed the loader (see
/// fuzz/README.md); each must now load or fail cleanly, and pack if it loads.
#[test]
fn fuzzer_crash_inputs_fail_cleanly() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz-regressions");
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return;
    };
    let scratch = common::fresh_output_dir("bad_input", "fuzz");
    for entry in entries {
        let path = entry.unwrap().path();
        let data = std::fs::read(&path).unwrap();
        let ext = if data.starts_with(b"glTF") {
            "glb"
        } else {
            "gltf"
        };
        let copy = scratch.join(format!(
            "{}.{ext}",
            path.file_name().unwrap().to_string_lossy()
        ));
        std::fs::write(&copy, &data).unwrap();
        if let Ok(scene) = load(&copy, &LoadOptions::default()) {
            let packed = std::panic::catch_unwind(|| PackedScene::new(&scene));
            assert!(packed.is_ok(), "packing panicked on {}", path.display());
        }
    }
}

/// A Draco stream the decoder crate panics on (found by the fuzzer: an
/// assertion inside draco-oxide's inverse transform): the panic is caught
/// and the user reads one line naming the primitive, with no panic report
/// or backtrace above it.
#[test]
fn a_decoder_panic_is_one_line_of_error() {
    let input = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fuzz-regressions/draco-decoder-panic.glb");
    let dir = common::fresh_output_dir("bad_input", "decoder_panic");
    let out = dir.join("never.exr");
    let run = Command::new(env!("CARGO_BIN_EXE_vkpt"))
        .args([
            input.to_str().unwrap(),
            "--device",
            "cpu",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "-o",
        ])
        .arg(&out)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("vkpt runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert!(!run.status.success(), "a broken Draco stream must fail");
    assert_eq!(lines.len(), 1, "one line of error, not:\n{stderr}");
    assert!(
        lines[0].starts_with("error: ")
            && lines[0].contains("mesh #0 'Mesh' primitive #0")
            && lines[0].contains("the Draco decoder failed on malformed data"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing is written");
}
