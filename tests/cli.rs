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
    for needle in ["--max-depth", "--spp", "--device", "compare", "segments"] {
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

#[test]
fn bad_environment_options_get_a_clear_error() {
    let o = vkpt(&["scenes/cornell-box.gltf", "-q", "--env", "no/such/sky.exr"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no/such/sky.exr"), "{}", stderr(&o));

    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "-q",
        "--env",
        "scenes/cornell-box.gltf",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains(".exr or .hdr"), "{}", stderr(&o));

    for bad in ["1,2", "1,2,x", "1,-2,3", "1,2,3,4", "nan,1,1"] {
        let o = vkpt(&["scenes/cornell-box.gltf", "--background", bad]);
        assert_eq!(o.status.code(), Some(2), "--background {bad}");
        assert!(
            stderr(&o).contains(&format!(
                "--background expects R,G,B: three non-negative numbers, got '{bad}'"
            )),
            "{}",
            stderr(&o)
        );
    }

    let o = vkpt(&["scenes/cornell-box.gltf", "--env-intensity", "-1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--env-intensity"), "{}", stderr(&o));

    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "-q",
        "--env",
        "scenes/env/sky-with-sun.exr",
        "--background",
        "1,1,1",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("give one"), "{}", stderr(&o));
}

#[test]
fn environment_options_render() {
    let out = out_dir().join("env-options.exr");
    let o = vkpt(&[
        "scenes/env-sky.gltf",
        "-q",
        "--device",
        "cpu",
        "--width",
        "24",
        "--spp",
        "2",
        "--env",
        "scenes/env/sky-with-sun.exr",
        "--env-rotation",
        "90",
        "--env-intensity",
        "0.5",
        "--hide-env",
        "-o",
        out.to_str().expect("utf-8 path"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("environment map"), "{text}");

    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "-q",
        "--device",
        "cpu",
        "--width",
        "16",
        "--spp",
        "1",
        "--background",
        "0.2,0.3,0.4",
        "-o",
        out.to_str().expect("utf-8 path"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("environment"));
}
