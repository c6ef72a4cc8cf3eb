//! Splitting a render on the command line: `--samples` and `--region`
//! parts carry headers saying what they hold, `vkpt merge` joins them into
//! the single render (checked with `vkpt compare --tolerance`), refuses
//! parts that do not belong together with one line and writes nothing, and
//! a render stopped early resumes with the rest of its range.

use crate::common;

use common::vkpt;
use std::path::Path;
use std::process::{Command, Output};
use vkpt::image::{RenderHeader, read_exr_header};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Renders the Cornell box, 24x16 on the CPU, seed 3 (unless `extra`
/// gives one), with `extra` options.
fn render(out: &Path, extra: &[&str]) {
    let mut args = vec![
        "scenes/cornell-box.gltf",
        "--device",
        "cpu",
        "--width",
        "24",
        "--height",
        "16",
        "-q",
        "-o",
        out.to_str().expect("utf-8 path"),
    ];
    if !extra.contains(&"--seed") {
        args.extend(["--seed", "3"]);
    }
    args.extend_from_slice(extra);
    let o = vkpt(&args);
    assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn header(path: &Path) -> RenderHeader {
    read_exr_header(path)
        .expect("readable")
        .expect("a vkpt header")
}

/// `vkpt merge PARTS -o OUT` plus `extra`.
fn merge(parts: &[&Path], out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(|p| path_str(p)));
    args.extend(["-o", path_str(out)]);
    args.extend_from_slice(extra);
    vkpt(&args)
}

/// `vkpt compare A B --tolerance 1e-5` agrees.
fn assert_same_image(a: &Path, b: &Path, tolerance: &str) {
    let o = vkpt(&[
        "compare",
        path_str(a),
        path_str(b),
        "--tolerance",
        tolerance,
    ]);
    let out = text(&o.stdout);
    println!("{}", out.lines().last().unwrap_or_default());
    assert_eq!(o.status.code(), Some(0), "{out}{}", text(&o.stderr));
    assert!(out.contains("the same image"), "{out}");
}

#[test]
fn parts_carry_headers_and_merge_into_the_single_render() {
    let dir = common::fresh_output_dir(
        "merge_cli",
        "parts_carry_headers_and_merge_into_the_single_render",
    );
    let full = dir.join("full.exr");
    render(&full, &["--spp", "8"]);
    let h = header(&full);
    assert_eq!(h.scene, "scenes/cornell-box.gltf");
    assert_eq!(h.scene_hash.len(), 16, "{}", h.scene_hash);
    assert_eq!(
        (h.width, h.height, h.region.to_string()),
        (24, 16, "0,0,24,16".into())
    );
    assert_eq!((h.samples.clone(), h.seed, h.max_depth), (0..8, 3, None));
    assert_eq!(
        (h.sampler.as_str(), h.filter.as_str()),
        ("sobol", "box 0.5")
    );
    assert_eq!(h.version, env!("CARGO_PKG_VERSION"));
    assert!(h.backend.starts_with("CPU back end"), "{}", h.backend);

    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    render(&a, &["--samples", "0..3"]);
    render(&b, &["--samples", "3..8"]);
    assert_eq!(header(&b).samples, 3..8);
    let merged = dir.join("merged.exr");
    let o = merge(&[&b, &a], &merged, &["--samples", "0..8"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("merged 2 parts (1 region) into 24x16, samples 0..8"));
    assert_eq!(header(&merged).samples, 0..8);
    assert_same_image(&merged, &full, "1e-5");

    // Regions keep the full image's camera: they assemble exactly.
    let (top, bottom) = (dir.join("top.exr"), dir.join("bottom.exr"));
    render(&top, &["--spp", "8", "--region", "0,0,24,9"]);
    render(&bottom, &["--spp", "8", "--region", "0,9,24,16"]);
    assert_eq!(header(&bottom).region.to_string(), "0,9,24,16");
    let image = vkpt::image::read_exr(&bottom).expect("reads");
    assert_eq!((image.width, image.height), (24, 7));
    let assembled = dir.join("assembled.exr");
    let o = merge(&[&top, &bottom], &assembled, &[]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_same_image(&assembled, &full, "0");
}

#[test]
fn bad_merges_are_one_line_errors_and_write_nothing() {
    let dir = common::fresh_output_dir(
        "merge_cli",
        "bad_merges_are_one_line_errors_and_write_nothing",
    );
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    render(&a, &["--samples", "0..3"]);
    render(&b, &["--samples", "3..8"]);
    let seed4 = dir.join("seed4.exr");
    render(&seed4, &["--samples", "3..8", "--seed", "4"]);
    let overlapping = dir.join("overlapping.exr");
    render(&overlapping, &["--samples", "2..8"]);
    let red = dir.join("red.exr");
    render(&red, &["--samples", "3..8", "--background", "1,0,0"]);
    let top = dir.join("top.exr");
    render(&top, &["--samples", "0..3", "--region", "0,0,24,9"]);
    // A part cut short, as by a full disk or a copy that did not finish.
    let truncated = dir.join("truncated.exr");
    let bytes = std::fs::read(&b).expect("b.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() * 2 / 3]).expect("written");
    // An EXR from another tool: no header.
    let foreign = dir.join("foreign.exr");
    vkpt::image::write_image(
        &foreign,
        &vkpt::image::Image::new(24, 16),
        &Default::default(),
    )
    .expect("written");

    let out = dir.join("merged.exr");
    let cases: [(&[&Path], &[&str], &str); 7] = [
        (&[&a, &seed4], &[], "render different images (seed: 3 vs 4)"),
        (
            &[&a, &red],
            &[],
            "render different images (scene content hash",
        ),
        (&[&a, &overlapping], &[], "sample ranges 0..3 ("),
        (
            &[&top],
            &[],
            "the parts leave 168 pixels of the 24x16 image uncovered, the first at (0, 9)",
        ),
        (&[&a, &truncated], &[], "truncated.exr"),
        (
            &[&a, &b],
            &["--samples", "0..16"],
            "the parts hold samples 0..8, not the 0..16 expected",
        ),
        (
            &[&a, &foreign],
            &[],
            "foreign.exr has no vkpt render header",
        ),
    ];
    for (parts, extra, expected) in cases {
        let o = merge(parts, &out, extra);
        let err = text(&o.stderr);
        println!("{err}");
        assert_eq!(o.status.code(), Some(1), "{parts:?}: {err}");
        assert_eq!(err.lines().count(), 1, "not one line: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(expected),
            "{parts:?}: {err}"
        );
        assert!(!out.exists(), "{parts:?}: wrote {}", out.display());
    }
    let overlap = text(&merge(&[&a, &overlapping], &out, &[]).stderr);
    assert!(overlap.contains("overlap"), "{overlap}");
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    // With --allow-holes the lone region makes an image, black below.
    let o = merge(&[&top], &out, &["--allow-holes"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("note: 168 pixels are in no part"));
}

#[test]
fn split_flags_are_checked() {
    let usage = |args: &[&str], flag: &str, message: &str| {
        let mut all = vec!["scenes/cornell-box.gltf", "-q", "--device", "cpu"];
        all.extend_from_slice(args);
        let o = vkpt(&all);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains(flag) && err.contains(message),
            "{args:?}: {err}"
        );
    };
    usage(
        &["--samples", "8..8"],
        "--samples",
        "is empty: A must be below B",
    );
    usage(&["--samples", "8"], "--samples", "expects A..B");
    usage(
        &["--samples", "0..99999999"],
        "--samples",
        "above the 16777216",
    );
    usage(
        &["--samples", "0..8", "--spp", "8"],
        "--spp",
        "cannot be used with",
    );
    usage(&["--region", "4,0,4,8"], "--region", "is empty");
    usage(&["--region", "0,0,8"], "--region", "expects X0,Y0,X1,Y1");
    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "-q",
        "--width",
        "16",
        "--region",
        "0,0,17,4",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("region 0,0,17,4 reaches outside the 16x16 image"),
        "{}",
        text(&o.stderr)
    );
}

/// A render stopped by its time limit says how to finish it; the rest of
/// its range, merged with it, is the render that was asked for.
#[test]
fn a_stopped_render_resumes_with_the_rest_of_its_range() {
    let dir = common::fresh_output_dir(
        "merge_cli",
        "a_stopped_render_resumes_with_the_rest_of_its_range",
    );
    let stopped = dir.join("stopped.exr");
    let o = vkpt(&[
        "scenes/cornell-box.gltf",
        "--device",
        "cpu",
        "--width",
        "32",
        "--samples",
        "0..64",
        "--time-limit",
        "0.001",
        "-q",
        "-o",
        path_str(&stopped),
    ]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let k = header(&stopped).samples.end;
    assert!(k < 64, "{stdout}");
    let hint = format!("to finish it: render --samples {k}..64");
    assert!(stdout.contains(&hint), "{stdout}");

    let rest = dir.join("rest.exr");
    let range = format!("{k}..64");
    let common = [
        "scenes/cornell-box.gltf",
        "--device",
        "cpu",
        "--width",
        "32",
        "-q",
    ];
    let o = vkpt(&[&common[..], &["--samples", &range, "-o", path_str(&rest)]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let full = dir.join("full.exr");
    let o = vkpt(&[&common[..], &["--spp", "64", "-o", path_str(&full)]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let merged = dir.join("merged.exr");
    let o = merge(&[&stopped, &rest], &merged, &["--samples", "0..64"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_same_image(&merged, &full, "1e-5");
}

/// A checkpoint carries the header too, with the samples taken so far.
#[test]
fn checkpoints_say_which_samples_they_hold() {
    let dir = common::fresh_output_dir("merge_cli", "checkpoints_say_which_samples_they_hold");
    let out = dir.join("checkpoint.exr");
    let child = Command::new(env!("CARGO_BIN_EXE_vkpt"))
        .args([
            "scenes/cornell-box.gltf",
            "--device",
            "cpu",
            "--width",
            "32",
            "--samples",
            "100..1000000",
            "--checkpoint",
            "0.2",
            "-q",
            "-o",
            path_str(&out),
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("vkpt starts");
    let start = std::time::Instant::now();
    while !out.exists() {
        assert!(start.elapsed().as_secs() < 60, "no checkpoint in 60 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let checkpoint = header(&out);
    // SAFETY: kill(2) on our own child's pid.
    let sent = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    assert_eq!(sent, 0, "SIGINT sent");
    let o = child.wait_with_output().expect("vkpt exits");
    assert_eq!(o.status.code(), Some(130), "{}", text(&o.stderr));
    println!("checkpoint holds samples {:?}", checkpoint.samples);
    assert_eq!(checkpoint.samples.start, 100);
    assert!((101..1_000_000).contains(&checkpoint.samples.end));
    let last = header(&out).samples;
    assert!(last.start == 100 && last.end >= checkpoint.samples.end);
    let hint = format!("to finish it: render --samples {}..1000000", last.end);
    assert!(text(&o.stdout).contains(&hint), "{}", text(&o.stdout));
}
