//! The `vkpt` command as a user runs it: help, clear errors with the right
//! exit status for bad input, real EXR/PNG files, and `vkpt compare`
//! telling renders of the same scene from renders of a different one.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn vkpt(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vkpt"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("vkpt runs")
}

fn out_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-output/cli");
    std::fs::create_dir_all(&dir).expect("output dir");
    dir
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn help_explains_the_options() {
    let o = vkpt(&["--help"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for needle in [
        "--max-depth",
        "--spp",
        "--device",
        "compare",
        "segments",
        "--fstop",
        "--filter",
        "--shutter",
    ] {
        assert!(text.contains(needle), "--help does not mention {needle}");
    }
}

#[test]
fn bad_input_gets_a_clear_error_and_status() {
    let o = vkpt(&["no/such/scene.gltf", "-q"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no/such/scene.gltf"), "{}", stderr(&o));

    let o = vkpt(&["scenes/cornell-box.gltf", "--spp", "many"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--spp expects a number, got 'many'"),
        "{}",
        stderr(&o)
    );

    let o = vkpt(&["scenes/cornell-box.gltf", "--frobnicate"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("unknown option '--frobnicate'"),
        "{}",
        stderr(&o)
    );

    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "-o",
        "out.jpg",
        "--device",
        "cpu",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("out.jpg"), "{}", stderr(&o));

    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--camera",
        "nope",
        "--device",
        "cpu",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no camera 'nope'"), "{}", stderr(&o));

    let o = vkpt(&["scenes/cornell-box.gltf", "--max-depth", "0"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn renders_files_and_compare_tells_same_from_different() {
    let dir = out_dir();
    let render = |name: &str, extra: &[&str]| {
        let path = dir.join(name);
        let path_str = path.to_str().expect("utf-8 path").to_string();
        let mut args = vec![
            "scenes/cornell-box.gltf",
            "--device",
            "cpu",
            "--width",
            "32",
            "-q",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["-o", &path_str]);
        let o = vkpt(&args);
        assert!(o.status.success(), "render failed: {}", stderr(&o));
        let summary = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(
            summary.contains("samples/s") && summary.contains("rays/s"),
            "{summary}"
        );
        path
    };
    let a = render("a.exr", &["--spp", "128", "--seed", "1"]);
    let b = render("b.exr", &["--spp", "128", "--seed", "2"]);
    let direct = render(
        "direct.exr",
        &["--spp", "128", "--seed", "3", "--max-depth", "2"],
    );
    let png = render("a.png", &["--spp", "4"]);

    let image = vkpt::output::read_exr(&a).expect("the EXR reads back");
    assert_eq!((image.width, image.height), (32, 32));
    assert!(
        image.variance.is_some(),
        "the EXR carries its variance layer"
    );
    let decoded = image::open(&png).expect("the PNG reads back");
    assert_eq!((decoded.width(), decoded.height()), (32, 32));

    let same = vkpt(&["compare", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert_eq!(
        same.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&same.stdout)
    );
    // Direct lighting only is darker than full transport: they must disagree.
    let different = vkpt(&["compare", a.to_str().unwrap(), direct.to_str().unwrap()]);
    assert_eq!(
        different.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&different.stdout)
    );
    let bad = vkpt(&["compare", a.to_str().unwrap(), png.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(2));
}

/// Camera flags: bad values are usage errors (status 2) naming the flag; a
/// lens that cannot be rendered is an error naming the camera (status 1).
#[test]
fn camera_flags_reject_bad_values() {
    let usage = |args: &[&str], needle: &str| {
        let mut all = vec!["scenes/depth-of-field.gltf", "--device", "cpu", "-q"];
        all.extend_from_slice(args);
        let o = vkpt(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
    };
    usage(&["--fstop", "-2"], "--fstop must be a non-negative number");
    usage(&["--fstop", "f8"], "--fstop expects a number, got 'f8'");
    usage(
        &["--focus-distance", "0"],
        "--focus-distance must be a positive number",
    );
    usage(
        &["--focal-length", "-0.05"],
        "--focal-length must be a positive number",
    );
    usage(
        &["--blades", "2"],
        "--blades must be 0 (a round aperture) or 3 to 64",
    );
    usage(
        &["--blade-rotation", "nan"],
        "--blade-rotation must be a number",
    );
    usage(
        &["--filter", "lanczos"],
        "--filter must be one of box, tent, gaussian, blackman-harris, got 'lanczos'",
    );
    usage(
        &["--filter-radius", "0"],
        "--filter-radius must be a positive number",
    );
    usage(&["--shutter", "-1"], "--shutter must be a positive number");
    usage(&["--iso", "0"], "--iso must be a positive number");

    // The Cornell box's camera has no focus distance to go with an f-number.
    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--fstop",
        "2.8",
        "--device",
        "cpu",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("camera 'main' has f-number 2.8 but no focus distance"),
        "{}",
        stderr(&o)
    );
    // A shutter time sets exposure only with an f-number.
    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--shutter",
        "0.01",
        "--device",
        "cpu",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("needs an f-number above 0"),
        "{}",
        stderr(&o)
    );
}

/// The camera flags reach the render: a tiny depth-of-field render with
/// every override, and the exposure note from shutter, ISO and f-number.
#[test]
fn camera_flags_render() {
    let out = out_dir().join("dof.png");
    let o = vkpt(&[
        "scenes/depth-of-field.gltf",
        "--device",
        "cpu",
        "-q",
        "--width",
        "24",
        "--spp",
        "1",
        "--fstop",
        "2",
        "--focus-distance",
        "2.4",
        "--focal-length",
        "0.05",
        "--blades",
        "5",
        "--blade-rotation",
        "18",
        "--filter",
        "gaussian",
        "--filter-radius",
        "1.2",
        "--shutter",
        "0.01",
        "--iso",
        "200",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // EV100 = log2(2^2 / 0.01) - log2(200 / 100) = 7.64.
    assert!(stderr(&o).contains("exposure EV100 7.64"), "{}", stderr(&o));
    assert!(out.exists());
}
