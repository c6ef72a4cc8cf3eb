//! `--denoise` with the real Intel Open Image Denoise 2.x: a denoised Cornell
//! box is closer to a converged render than the raw one, the auxiliary-image
//! flow runs, and a missing library is one line and exit status 1 before any
//! rendering, with nothing written.
//!
//! Without the library the tests that need it skip with a printed line,
//! unless `VKPT_REQUIRE_GPU=1` or `CI` is set (as in .ci/run): then they fail.

use crate::common;
use std::path::Path;
use std::process::{Command, Output};
use vkpt::image::compare::rel_mse;
use vkpt::image::read_exr;

fn vkpt(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_vkpt"));
    command.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    for (k, v) in env {
        command.env(k, v);
    }
    command.output().expect("vkpt runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Whether this machine must have the library: CI exercises the real one.
fn library_required() -> bool {
    std::env::var("VKPT_REQUIRE_GPU").is_ok_and(|v| v == "1")
        || std::env::var_os("CI").is_some_and(|v| !v.is_empty())
}

/// True when Open Image Denoise loads; otherwise skips (with a line) or,
/// where it is required, fails.
fn library_or_skip(test: &str) -> bool {
    match vkpt::image::denoise::available() {
        Ok(()) => true,
        Err(e) if library_required() => {
            panic!("{test}: Open Image Denoise is required here (VKPT_REQUIRE_GPU=1 or CI): {e}")
        }
        Err(e) => {
            println!("{test}: skipping, no Open Image Denoise: {e}");
            false
        }
    }
}

fn render(args: &[&str], output: &Path) {
    let mut all = vec!["scenes/cornell-box.gltf", "--device", "cpu", "-q"];
    all.extend_from_slice(args);
    let output = output.to_str().expect("UTF-8 path");
    all.extend_from_slice(&["-o", output]);
    let o = vkpt(&all, &[]);
    assert!(
        o.status.success(),
        "vkpt {all:?} failed: {}{}",
        text(&o.stdout),
        text(&o.stderr)
    );
}

#[test]
fn denoised_cornell_box_is_closer_to_the_reference() {
    let test = "denoised_cornell_box_is_closer_to_the_reference";
    if !library_or_skip(test) {
        return;
    }
    let dir = common::output_dir(&format!("denoise/{test}"));
    let size = ["--width", "64", "--height", "64"];
    let reference = dir.join("reference.exr");
    render(
        &[&size[..], &["--spp", "512", "--seed", "1"]].concat(),
        &reference,
    );
    let noisy = dir.join("noisy.exr");
    render(&[&size[..], &["--spp", "8", "--denoise"]].concat(), &noisy);

    let reference = read_exr(&reference).expect("reference EXR");
    let mut image = read_exr(&noisy).expect("denoised EXR");
    assert!(reference.denoised.is_none(), "no --denoise, no layer");
    let denoised = image.denoised.take().expect("a denoised.R/G/B layer");
    let raw_error = rel_mse(&image, &reference);
    let denoised_image = vkpt::image::Image {
        mean: denoised,
        ..image.clone()
    };
    let denoised_error = rel_mse(&denoised_image, &reference);
    println!("relMSE at 8 spp: raw {raw_error:.3e}, denoised {denoised_error:.3e}");
    assert!(
        denoised_error * 3.0 < raw_error,
        "denoising should cut the relMSE at least 3x: raw {raw_error:.3e}, denoised {denoised_error:.3e}"
    );
    // The raw beauty is untouched: its estimated error is that of 8 spp.
    assert!(image.variance.is_some() && image.samples.is_some());
}

#[test]
fn denoise_with_albedo_and_normal_prefilters_them() {
    let test = "denoise_with_albedo_and_normal_prefilters_them";
    if !library_or_skip(test) {
        return;
    }
    // A flat grey wall with salt-and-pepper noise, noisy aux images too.
    let (w, h) = (32u32, 24u32);
    let n = (w * h) as usize;
    let noise = |i: usize, k: u32| {
        let x = (i as u32).wrapping_mul(2_654_435_761).wrapping_add(k) >> 16;
        (x % 1000) as f32 / 1000.0
    };
    let color: Vec<[f32; 3]> = (0..n).map(|i| [noise(i, 1); 3]).collect();
    let albedo: Vec<[f32; 3]> = (0..n).map(|i| [0.4 + 0.2 * noise(i, 2); 3]).collect();
    let normal: Vec<[f32; 3]> = (0..n)
        .map(|i| [0.1 * (noise(i, 3) - 0.5), 0.0, 1.0])
        .collect();
    let out = vkpt::image::denoise::denoise(w, h, &color, Some(&albedo), Some(&normal))
        .expect("denoising with albedo and normal");
    assert_eq!(out.len(), n);
    assert!(out.iter().flatten().all(|v| v.is_finite()));
    let mean = |img: &[[f32; 3]]| img.iter().map(|p| p[0] as f64).sum::<f64>() / n as f64;
    let spread = |img: &[[f32; 3]]| {
        let m = mean(img);
        img.iter().map(|p| (p[0] as f64 - m).powi(2)).sum::<f64>() / n as f64
    };
    println!(
        "mean {:.3} -> {:.3}, variance {:.4} -> {:.4}",
        mean(&color),
        mean(&out),
        spread(&color),
        spread(&out)
    );
    assert!(
        spread(&out) < spread(&color) / 2.0,
        "the wall should come out smoother"
    );
    assert!((mean(&out) - mean(&color)).abs() < 0.1 * mean(&color));
    let albedo_only = vkpt::image::denoise::denoise(w, h, &color, Some(&albedo), None)
        .expect("denoising with albedo alone");
    assert_eq!(albedo_only.len(), n);
}

#[test]
fn missing_library_is_one_line_before_rendering_and_writes_nothing() {
    let dir = common::output_dir("denoise/missing_library");
    let output = dir.join("never.exr");
    let _ = std::fs::remove_file(&output);
    let missing = [("VKPT_OIDN_LIB", "/nonexistent/libOpenImageDenoise.so.2")];
    let o = vkpt(
        &[
            "scenes/cornell-box.gltf",
            "--device",
            "cpu",
            "--width",
            "32",
            "--spp",
            "4",
            "--denoise",
            "-o",
            output.to_str().unwrap(),
        ],
        &missing,
    );
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(
        err.starts_with("error: ")
            && err.contains("VKPT_OIDN_LIB=/nonexistent/libOpenImageDenoise.so.2")
            && err.contains("pip install --no-deps pyoidn"),
        "{err}"
    );
    assert!(!text(&o.stdout).contains("rendered"), "{}", text(&o.stdout));
    assert!(!output.exists(), "nothing is written");

    // Before the scene is even read: a missing scene is not what it reports.
    let o = vkpt(&["scenes/no-such-scene.gltf", "--denoise"], &missing);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("Open Image Denoise") && !err.contains("no-such-scene"),
        "{err}"
    );
}

#[test]
fn a_library_that_is_not_oidn_2_is_refused_in_one_line() {
    for (library, expected) in [
        // Not a shared library at all.
        ("README.md", "invalid ELF header"),
        // A shared library without OIDN's functions.
        (
            "libm.so.6",
            "has no oidnNewDevice: not Open Image Denoise 2.x",
        ),
    ] {
        let o = vkpt(
            &["scenes/cornell-box.gltf", "--denoise", "--spp", "1"],
            &[("VKPT_OIDN_LIB", library)],
        );
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{library}: {err}");
        assert_eq!(err.lines().count(), 1, "{library}: one line: {err}");
        assert!(
            err.contains(expected) && err.contains(&format!("VKPT_OIDN_LIB={library}")),
            "{library}: {err}"
        );
    }
}

#[test]
fn help_explains_denoise() {
    let o = vkpt(&["--help"], &[]);
    let help = text(&o.stdout);
    assert!(o.status.success());
    for needle in [
        "--denoise",
        "Open Image Denoise",
        "denoised.R/G/B",
        "biased",
        "VKPT_OIDN_LIB",
    ] {
        assert!(help.contains(needle), "--help lacks {needle}");
    }
}

#[test]
fn bench_denoise_adds_a_denoised_series_with_lower_error() {
    let test = "bench_denoise_adds_a_denoised_series_with_lower_error";
    if !library_or_skip(test) {
        return;
    }
    let dir = common::output_dir(&format!("denoise/{test}"));
    let reference = dir.join("reference.exr");
    render(
        &[
            "--width", "64", "--height", "64", "--spp", "512", "--seed", "1",
        ],
        &reference,
    );
    let out = dir.join("bench");
    let o = vkpt(
        &[
            "bench",
            "scenes/cornell-box.gltf",
            "--device",
            "cpu",
            "--spp",
            "4,16",
            "--width",
            "64",
            "--reference",
            reference.to_str().expect("UTF-8 path"),
            "--denoise",
            "-o",
            out.to_str().expect("UTF-8 path"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}{}", text(&o.stdout), text(&o.stderr));
    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv");
    // (spp, relMSE) of each series.
    let series = |backend: &str| -> Vec<(u32, f64)> {
        csv.lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|f| f[1] == backend)
            .map(|f| (f[4].parse().expect("spp"), f[9].parse().expect("relMSE")))
            .collect()
    };
    let (raw, denoised) = (series("cpu"), series("cpu+denoise"));
    println!("raw {raw:?}\ndenoised {denoised:?}");
    assert_eq!(raw.len(), 2, "{csv}");
    assert_eq!(denoised.len(), 2, "{csv}");
    for ((spp, r), (dspp, d)) in raw.iter().zip(&denoised) {
        assert_eq!(spp, dspp);
        assert!(
            d * 2.0 < *r,
            "at {spp} spp denoised relMSE {d:.3e} vs raw {r:.3e}"
        );
    }
}
