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

    // The report leads with error metrics that need no variance.
    let text = String::from_utf8_lossy(&different.stdout).into_owned();
    for needle in ["bias a-b", "RMSE", "relMSE", "worst 16x16 block"] {
        assert!(
            text.contains(needle),
            "compare report lacks {needle}:\n{text}"
        );
    }

    // An EXR without variance layers (as another renderer writes them):
    // compare says the z-test cannot run and judges by relMSE alone.
    let mut plain = image.clone();
    plain.variance = None;
    plain.samples = None;
    let plain_path = dir.join("plain.exr");
    vkpt::output::write_image(&plain_path, &plain, &Default::default()).expect("writes");
    let (p, b_str, d_str) = (
        plain_path.to_str().unwrap(),
        b.to_str().unwrap(),
        direct.to_str().unwrap(),
    );
    let same = vkpt(&["compare", p, b_str, "--max-rel-mse", "0.05"]);
    let same_text = String::from_utf8_lossy(&same.stdout).into_owned();
    assert_eq!(same.status.code(), Some(0), "{same_text}");
    assert!(same_text.contains("no variance layer in"), "{same_text}");
    let different = vkpt(&["compare", p, d_str, "--max-rel-mse", "0.05"]);
    let text = String::from_utf8_lossy(&different.stdout).into_owned();
    assert_eq!(different.status.code(), Some(1), "{text}");
    assert!(text.contains("DIFFERENT"), "{text}");
}

#[test]
fn bench_writes_csv_and_plot_with_falling_error() {
    let dir = out_dir().join("bench");
    let cache = out_dir().join("bench-cache");
    // A fresh cache: the reference is rendered, stored, then read back.
    let _ = std::fs::remove_dir_all(&cache);
    let _ = std::fs::remove_dir_all(&dir);
    let args = [
        "bench",
        "scenes/cornell-box.gltf",
        "--width",
        "16",
        "--spp",
        "1,4,16",
        "--reference-spp",
        "256",
        "-o",
        dir.to_str().unwrap(),
    ];
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_vkpt"))
            .args(args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("VKPT_CACHE_DIR", &cache)
            .env("VKPT_VALIDATION", "1")
            .output()
            .expect("vkpt runs")
    };
    let o = run();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{stdout}{}", stderr(&o));
    assert!(stdout.contains("time to relMSE 1e-2"), "{stdout}");
    assert!(stdout.contains("BVH build"), "{stdout}");

    let csv = std::fs::read_to_string(dir.join("bench.csv")).expect("bench.csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    for column in [
        "backend",
        "spp",
        "wall_s",
        "kernel_s",
        "samples_per_s",
        "rays_per_s",
        "rel_mse",
    ] {
        assert!(header.contains(&column), "no column {column} in {header:?}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    let backends: std::collections::BTreeSet<&str> =
        rows.iter().map(|r| r[col("backend")].as_str()).collect();
    assert!(backends.contains("cpu"), "{csv}");
    assert_eq!(rows.len(), 3 * backends.len(), "{csv}");
    for backend in backends {
        let rel: Vec<f64> = rows
            .iter()
            .filter(|r| r[col("backend")] == backend)
            .map(|r| r[col("rel_mse")].parse().expect("a number"))
            .collect();
        // 16x the samples: well under half the error (a few pixels that
        // partly cover the light dominate at this size, so not 1/16).
        assert!(rel[2] < rel[0] / 2.0, "{backend}: {rel:?}");
    }
    let plot = image::open(dir.join("cornell-box.png")).expect("the plot reads back");
    assert_eq!((plot.width(), plot.height()), (800, 520));

    // The second run finds the cached reference, and the Vulkan device (if
    // any) the pipeline cache file the first run saved.
    let o = run();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success() && stdout.contains("(cached)"),
        "{stdout}"
    );
    if stdout.contains("kernel compile") {
        assert!(stdout.contains("pipeline cache loaded"), "{stdout}");
        let saved = std::fs::read_dir(&cache)
            .expect("cache dir")
            .filter_map(|e| e.ok())
            .any(|e| e.file_name().to_string_lossy().starts_with("pipelines-"));
        assert!(saved, "no pipelines-*.bin in {}", cache.display());
    }
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
