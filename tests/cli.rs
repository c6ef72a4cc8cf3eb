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
fn bad_sampler_and_stopping_values_are_rejected() {
    for (args, message) in [
        (
            &["--sampler", "halton"][..],
            "--sampler must be one of independent, sobol, got 'halton'",
        ),
        (
            &["--time-limit", "0"],
            "--time-limit must be above 0 seconds",
        ),
        (&["--time-limit", "-3"], "--time-limit expects seconds"),
        (
            &["--time-limit", "soon"],
            "--time-limit expects a number, got 'soon'",
        ),
        (
            &["--target-error", "0"],
            "--target-error must be a relative error above 0",
        ),
        (
            &["--target-error", "nan"],
            "--target-error must be a relative error above 0",
        ),
        (&["--checkpoint", "inf"], "--checkpoint expects seconds"),
    ] {
        let o = vkpt(&[&["scenes/cornell-box.gltf"], args].concat());
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(message), "{args:?}: {}", stderr(&o));
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
    let image = vkpt::output::read_exr(path).expect("the EXR reads back");
    let var = image.variance.as_ref().expect("variance layer");
    assert!(image.mean.iter().flatten().all(|v| v.is_finite()));
    assert!(var.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn time_limit_stops_early_and_says_so() {
    let out = out_dir().join("time-limit.exr");
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
    let out = out_dir().join("target-error.exr");
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
    let image = vkpt::output::read_exr(&out).expect("the EXR reads back");
    let error = image.estimated_rel_error();
    assert!(error <= 0.1, "estimated error {error} above the target");
    assert_consistent_exr(&out);
}

/// Ctrl-C: the render stops at the end of a pass, writes the image with the
/// samples it has and exits with status 130. The test waits for the first
/// checkpoint, so it knows the render (and the handler) started.
#[test]
fn ctrl_c_writes_the_image_so_far_and_exits_130() {
    let out = out_dir().join("interrupted.png");
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
