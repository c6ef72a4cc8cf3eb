//! The `vkpt` command as a user runs it: help, clear errors with the right
//! exit status for bad input, real EXR/PNG files, and `vkpt compare`
//! telling renders of the same scene from renders of a different one.

use crate::common;

use common::vkpt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A usage error: status 2, and a message naming the flag (as clap spells it,
/// `'--spp <N>'`) and saying what is wrong with the value.
fn assert_usage_error(o: &Output, flag: &str, message: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{flag}: {err}");
    assert!(
        err.contains(&format!("'{flag} ")) && err.contains(message),
        "{flag} / {message}: {err}"
    );
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
        "--sampler",
        "--time-limit",
        "--target-error",
        "--checkpoint",
        "Ctrl-C",
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
    assert_usage_error(&o, "--spp", "expects a number, got 'many'");

    let o = vkpt(&["scenes/cornell-box.gltf", "--frobnicate"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("unexpected argument '--frobnicate'"),
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
    let dir = common::output_dir("cli");
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
    // compare's per-pixel variance assumes independent samples.
    let ind = ["--sampler", "independent"];
    let a = render(
        "a.exr",
        &[&ind[..], &["--spp", "128", "--seed", "1"]].concat(),
    );
    let b = render(
        "b.exr",
        &[&ind[..], &["--spp", "128", "--seed", "2"]].concat(),
    );
    let direct = render(
        "direct.exr",
        &[
            &ind[..],
            &["--spp", "128", "--seed", "3", "--max-depth", "2"],
        ]
        .concat(),
    );
    let png = render("a.png", &["--spp", "4"]);

    let image = vkpt::image::read_exr(&a).expect("the EXR reads back");
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
    // compare estimates the noise from the images, says so, and runs the
    // levelled tests; --max-rel-mse is an extra criterion.
    let mut plain = image.clone();
    plain.variance = None;
    plain.samples = None;
    let plain_path = dir.join("plain.exr");
    vkpt::image::write_image(&plain_path, &plain, &Default::default()).expect("writes");
    let (p, b_str, d_str) = (
        plain_path.to_str().unwrap(),
        b.to_str().unwrap(),
        direct.to_str().unwrap(),
    );
    let same = vkpt(&["compare", p, b_str]);
    let same_text = String::from_utf8_lossy(&same.stdout).into_owned();
    assert_eq!(same.status.code(), Some(0), "{same_text}");
    assert!(same_text.contains("no variance layer in"), "{same_text}");
    assert!(
        same_text.contains("noise model: estimated from the images"),
        "{same_text}"
    );
    let different = vkpt(&["compare", p, d_str]);
    let text = String::from_utf8_lossy(&different.stdout).into_owned();
    assert_eq!(different.status.code(), Some(1), "{text}");
    assert!(text.contains("FAILED"), "{text}");
    let strict = vkpt(&["compare", p, b_str, "--max-rel-mse", "1e-9"]);
    let text = String::from_utf8_lossy(&strict.stdout).into_owned();
    assert_eq!(strict.status.code(), Some(1), "{text}");
    assert!(text.contains("TOO LARGE"), "{text}");
}

#[test]
fn bench_writes_csv_and_plot_with_falling_error() {
    let dir = common::output_dir("cli").join("bench");
    let cache = common::output_dir("cli").join("bench-cache");
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
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_vkpt"))
            .args(args)
            .args(extra)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env("VKPT_CACHE_DIR", &cache)
            .env("VKPT_VALIDATION", "1")
            .output()
            .expect("vkpt runs")
    };
    let o = run(&[]);
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
    for &backend in &backends {
        let rel: Vec<f64> = rows
            .iter()
            .filter(|r| r[col("backend")] == backend)
            .map(|r| r[col("rel_mse")].parse().expect("a number"))
            .collect();
        // 16x the samples: well under half the error (a few pixels that
        // partly cover the light dominate at this size, so not 1/16).
        assert!(rel[2] < rel[0] / 2.0, "{backend}: {rel:?}");
    }
    // The plot: an SVG with its axis titles and one legend entry per back end.
    let plot = std::fs::read_to_string(dir.join("cornell-box.svg")).expect("the plot reads back");
    assert!(
        plot.starts_with("<svg") && plot.contains(r#"width="800""#),
        "{plot}"
    );
    for label in ["wall time per image (s)", "relMSE against the reference"]
        .into_iter()
        .chain(backends.iter().copied())
    {
        assert!(plot.contains(label), "no {label} in the plot");
    }

    // The second run renders each step twice and keeps the faster: the
    // same seed gives the same images, so every relMSE is unchanged. It
    // finds the cached reference, and the Vulkan device (if any) the
    // pipeline cache file the first run saved.
    let o = run(&["--repeat", "2"]);
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
    let again = std::fs::read_to_string(dir.join("bench.csv")).expect("bench.csv");
    let rel_mse_column = |csv: &str| -> Vec<String> {
        csv.lines()
            .skip(1)
            .map(|l| l.split(',').nth(col("rel_mse")).unwrap_or("").to_string())
            .collect()
    };
    assert_eq!(rel_mse_column(&again), rel_mse_column(&csv), "{again}");
    // Another seed: other samples, so other errors (the steps' spread over
    // seeds is what `benches/mitsuba_cornell.py --seeds` reports).
    let o = run(&["--seed", "7"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let seeded = std::fs::read_to_string(dir.join("bench.csv")).expect("bench.csv");
    let (a, b) = (rel_mse_column(&seeded), rel_mse_column(&csv));
    assert_eq!(a.len(), b.len(), "{seeded}");
    assert!(a.iter().zip(&b).all(|(a, b)| a != b), "{seeded}\n{csv}");
    // The reference's own seed would correlate the renders with it.
    let o = run(&["--seed", "1592590337"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("reference's own seed"),
        "{}",
        stderr(&o)
    );
    let o = vkpt(&["bench", "scenes/cornell-box.gltf", "--repeat", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--repeat"), "{}", stderr(&o));
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
        assert_usage_error(
            &o,
            "--background",
            &format!("expects R,G,B: three non-negative numbers, got '{bad}'"),
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
        assert_usage_error(&o, args[0], needle);
    };
    usage(&["--fstop", "-2"], "must be a non-negative number");
    usage(&["--fstop", "f8"], "expects a number, got 'f8'");
    usage(&["--focus-distance", "0"], "must be a positive number");
    usage(&["--focal-length", "-0.05"], "must be a positive number");
    usage(
        &["--blades", "2"],
        "must be 0 (a round aperture) or 3 to 64",
    );
    usage(&["--blade-rotation", "nan"], "must be a number");
    usage(
        &["--filter", "lanczos"],
        "[possible values: box, tent, gaussian, blackman-harris]",
    );
    usage(&["--filter-radius", "0"], "must be a positive number");
    usage(&["--shutter", "-1"], "must be a positive number");
    usage(&["--iso", "0"], "must be a positive number");

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
    let out = common::output_dir("cli").join("dof.png");
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

#[test]
fn bad_sampler_and_stopping_values_are_rejected() {
    for (args, message) in [
        (
            &["--sampler", "halton"][..],
            "[possible values: independent, sobol]",
        ),
        (&["--time-limit", "0"], "must be above 0 seconds"),
        (&["--time-limit", "-3"], "expects seconds"),
        (&["--time-limit", "soon"], "expects a number, got 'soon'"),
        (&["--target-error", "0"], "must be a relative error above 0"),
        (
            &["--target-error", "nan"],
            "must be a relative error above 0",
        ),
        (&["--checkpoint", "inf"], "expects seconds"),
    ] {
        let o = vkpt(&[&["scenes/cornell-box.gltf"], args].concat());
        assert_usage_error(&o, args[0], message);
    }
}

/// The `N` of the summary's "at N spp".
fn summary_spp(stdout: &str) -> u32 {
    let at = stdout.find(" at ").expect("summary line") + 4;
    stdout[at..]
        .split_whitespace()
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no spp in the summary: {stdout}"))
}

/// Every pixel of a read-back EXR has a finite mean and variance (a film
/// stopped mid-pass would leave pixels with one sample fewer, or none).
fn assert_consistent_exr(path: &Path) {
    let image = vkpt::image::read_exr(path).expect("the EXR reads back");
    let var = image.variance.as_ref().expect("variance layer");
    assert!(image.mean.iter().flatten().all(|v| v.is_finite()));
    assert!(var.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn time_limit_stops_early_and_says_so() {
    let out = common::output_dir("cli").join("time-limit.exr");
    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--device",
        "cpu",
        "--width",
        "64",
        "--spp",
        "1000000",
        "--time-limit",
        "1.5",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    let spp = summary_spp(&stdout);
    assert!(spp < 1_000_000, "{stdout}");
    assert!(
        stdout.contains(&format!(
            "stopped at the time limit of 1.5 s after {spp} spp of the 1000000 asked for"
        )),
        "{stdout}"
    );
    assert_consistent_exr(&out);
}

#[test]
fn target_error_stops_once_reached() {
    let out = common::output_dir("cli").join("target-error.exr");
    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--device",
        "cpu",
        "--width",
        "32",
        "--target-error",
        "0.1",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    let spp = summary_spp(&stdout);
    assert!(
        stdout.contains(&format!("stopped at {spp} spp: estimated relative error")),
        "{stdout}"
    );
    // The written image's own estimate agrees with the target.
    let image = vkpt::image::read_exr(&out).expect("the EXR reads back");
    let error = image.estimated_rel_error();
    assert!(error <= 0.1, "estimated error {error} above the target");
    assert_consistent_exr(&out);
}

/// Ctrl-C: the render stops at the end of a pass, writes the image with the
/// samples it has and exits with status 130. The test waits for the first
/// checkpoint, so it knows the render (and the handler) started.
#[test]
fn ctrl_c_writes_the_image_so_far_and_exits_130() {
    let out = common::output_dir("cli").join("interrupted.png");
    let _ = std::fs::remove_file(&out);
    let child = Command::new(env!("CARGO_BIN_EXE_vkpt"))
        .args([
            "scenes/cornell-box.gltf",
            "--device",
            "cpu",
            "--width",
            "64",
            "--spp",
            "1000000",
            "--checkpoint",
            "0.2",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("vkpt starts");
    let start = std::time::Instant::now();
    while !out.exists() {
        assert!(
            start.elapsed().as_secs() < 60,
            "no checkpoint written in 60 s"
        );
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // SAFETY: kill(2) on our own child's pid.
    let sent = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    assert_eq!(sent, 0, "SIGINT sent");
    let o = child.wait_with_output().expect("vkpt exits");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(130), "{stdout}{}", stderr(&o));
    let spp = summary_spp(&stdout);
    assert!(spp < 1_000_000, "{stdout}");
    assert!(
        stdout.contains(&format!(
            "interrupted (Ctrl-C) after {spp} spp of the 1000000 asked for"
        )),
        "{stdout}"
    );
    let decoded = image::open(&out).expect("the PNG reads back");
    assert_eq!((decoded.width(), decoded.height()), (64, 64));
}

#[test]
fn environment_options_render() {
    let out = common::output_dir("cli").join("env-options.exr");
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

/// `--device auto` without a GPU: the back end predicted from its measured
/// rate and fixed cost to finish this render first renders, and the summary
/// says which and why; the measurement is cached per build, and the choice
/// follows what the cache says (a planted measurement flips it, and a
/// fixed cost loses a short render for the faster rate).
#[test]
fn auto_picks_the_back_end_predicted_faster_and_says_why() {
    let cache = common::output_dir("cli").join("auto-cache");
    let _ = std::fs::remove_dir_all(&cache);
    let out = common::output_dir("cli").join("auto.exr");
    let run_exe = |exe: &std::path::Path| {
        let o = Command::new(exe)
            .args([
                "scenes/cornell-box.gltf",
                "--spp",
                "1",
                "--width",
                "32",
                "-q",
                "-o",
            ])
            .arg(&out)
            .env("VKPT_CACHE_DIR", &cache)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .expect("vkpt runs");
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let run = || run_exe(std::path::Path::new(env!("CARGO_BIN_EXE_vkpt")));
    let first = run();
    if first.contains("auto: a GPU") || first.contains("auto: no usable Vulkan device") {
        if std::env::var("VKPT_REQUIRE_GPU").is_ok_and(|v| v == "1") && !first.contains("a GPU") {
            panic!("VKPT_REQUIRE_GPU=1 but no Vulkan device: {first}");
        }
        println!("no CPU Vulkan driver to race against the CPU back end: {first}");
        return;
    }
    assert!(
        first.contains("auto: no GPU, and ") && first.contains("(measured now;"),
        "{first}"
    );
    let second = run();
    assert!(second.contains("(cached;"), "{second}");
    let cached: Vec<PathBuf> = std::fs::read_dir(&cache)
        .expect("cache dir")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.to_string_lossy().contains("auto-device-"))
        .collect();
    assert_eq!(cached.len(), 1, "{cached:?}");
    // Samples/s of lavapipe's wavefront, its per-path loop, the CPU back
    // end, seconds per render of lavapipe and of the CPU back end, and the
    // CPU back end's samples/s on the scene probe of the scene measured (0:
    // the rates are used unscaled). The render is 32x32 at 1 spp, 1024
    // samples. A cached line's CPU seconds per render are replaced by this
    // scene's probe (measured now, a few ms), so the test reads them back
    // from the message and checks the winner and its ratio against them.
    std::fs::write(&cached[0], "1000 500 10000 0 0 0\n").expect("plant a measurement");
    let cpu = run();
    assert!(cpu.contains("device: CPU back end"), "{cpu}");
    check_prediction(
        &cpu,
        "the CPU back end",
        "lavapipe (wavefront)",
        1000.0,
        0.0,
        10000.0,
    );
    std::fs::write(&cached[0], "10000 2500 2000 0 0 0\n").expect("plant a measurement");
    let vulkan = run();
    assert!(vulkan.contains("device: llvmpipe"), "{vulkan}");
    check_prediction(
        &vulkan,
        "lavapipe (wavefront)",
        "the CPU back end",
        10000.0,
        0.0,
        2000.0,
    );
    std::fs::write(&cached[0], "1000 3000 1500 0 0 0\n").expect("plant a measurement");
    let looped = run();
    assert!(looped.contains("device: llvmpipe"), "{looped}");
    check_prediction(
        &looped,
        "lavapipe (per-path loop)",
        "the CPU back end",
        3000.0,
        0.0,
        1500.0,
    );
    // Five times the CPU back end's rate, but a second per render: the CPU
    // back end finishes 1024 samples first (0.51 s and its probe's fixed
    // cost against 1.10 s).
    std::fs::write(&cached[0], "10000 0 2000 1 0 0\n").expect("plant a measurement");
    let short = run();
    assert!(short.contains("device: CPU back end"), "{short}");
    check_prediction(
        &short,
        "the CPU back end",
        "lavapipe (wavefront)",
        10000.0,
        1.0,
        2000.0,
    );
    // A cache from before the scene probe (five numbers) is measured again.
    std::fs::write(&cached[0], "1000 500 10000 0 0\n").expect("plant an old measurement");
    assert!(run().contains("(measured now;"));
    // A cache from before the fixed costs (three numbers) is measured again.
    std::fs::write(&cached[0], "1000 500 10000\n").expect("plant an old measurement");
    assert!(run().contains("(measured now;"));
    // A cache from before the per-path loop (two numbers) is measured again.
    std::fs::write(&cached[0], "1000 10000\n").expect("plant an old measurement");
    assert!(run().contains("(measured now;"));
    // A rebuilt vkpt (here a copy: the same version, another file) may be
    // faster on one back end, so it measures again, then uses its own cache.
    let rebuilt = common::output_dir("cli").join("vkpt-rebuilt");
    std::fs::copy(env!("CARGO_BIN_EXE_vkpt"), &rebuilt).expect("copy vkpt");
    let fresh = run_exe(&rebuilt);
    assert!(fresh.contains("(measured now;"), "{fresh}");
    assert!(run_exe(&rebuilt).contains("(cached;"));
    assert!(run().contains("(cached;"));
}

/// Checks `auto`'s message: `winner` is predicted faster than `loser` by the
/// ratio of their predicted times for the test's 1024 samples, computed from
/// the planted lavapipe rate and seconds per render (`vulkan_rate`,
/// `vulkan_fixed`: whichever Vulkan schedule is named), the planted CPU rate,
/// and the CPU seconds per render the message prints (this scene's probe).
fn check_prediction(
    message: &str,
    winner: &str,
    loser: &str,
    vulkan_rate: f64,
    vulkan_fixed: f64,
    cpu_rate: f64,
) {
    let samples = 1024.0;
    let key = "the CPU back end: ";
    let cpu_fixed_ms: f64 = message
        .find(key)
        .and_then(|i| {
            let rest = &message[i + key.len()..];
            let plus = rest.find("+ ")?;
            let ms = rest[plus + 2..].split_whitespace().next()?;
            ms.parse().ok()
        })
        .unwrap_or_else(|| panic!("no CPU seconds per render in: {message}"));
    // The printed ms are rounded to a whole millisecond: the ratio at both
    // ends of that rounding.
    let ratio_at = |ms: f64| {
        let cpu = samples / cpu_rate + ms.max(0.0) * 1e-3;
        let vulkan = samples / vulkan_rate + vulkan_fixed;
        if winner == "the CPU back end" {
            vulkan / cpu
        } else {
            cpu / vulkan
        }
    };
    let (a, b) = (ratio_at(cpu_fixed_ms - 0.5), ratio_at(cpu_fixed_ms + 0.5));
    let (lo, hi) = (a.min(b), a.max(b));
    assert!(
        message.contains(&format!("{winner} is predicted ")),
        "{message}"
    );
    let tail = format!("x faster than {loser}");
    let ratio: f64 = message
        .find(&tail)
        .and_then(|i| message[..i].rsplit(' ').next()?.parse().ok())
        .unwrap_or_else(|| panic!("no ratio against {loser} in: {message}"));
    // The printed ratio is rounded to 0.01.
    assert!(
        ratio > 1.0 && ratio >= lo - 0.006 && ratio <= hi + 0.006,
        "predicted {ratio}x, expected {lo:.3}x to {hi:.3}x from the rates ({message})"
    );
}
