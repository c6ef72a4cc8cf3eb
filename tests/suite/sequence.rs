//! Frame sequences: frames rendered one after the other on one back end
//! (the GPU keeps its buffers and re-uploads only what changed) are
//! bit-identical to the same frames rendered one by one, and the command
//! line writes them under a %04d pattern.

use crate::common;

use common::{gpu_renderer, render_cpu, render_gpu, repo_path};
use vkpt::image::Image;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{GltfFile, LoadOptions, Scene};

const FPS: f64 = 3.0;
const FRAMES: u32 = 3;

fn settings() -> RenderSettings {
    RenderSettings {
        width: 48,
        height: 48,
        spp: 4,
        seed: 7,
        ..Default::default()
    }
}

/// The frames of the moving square, posed by one `GltfFile`.
fn frames() -> Vec<(Scene, PackedScene)> {
    let path = repo_path("scenes/animated/moving-square.gltf");
    let file = GltfFile::open(&path, &LoadOptions::default()).expect("loads");
    (0..FRAMES)
        .map(|n| {
            let scene = file.at(n as f64 / FPS).expect("poses");
            let packed = PackedScene::new(&scene).expect("packs");
            (scene, packed)
        })
        .collect()
}

/// Bit for bit: means and variances.
fn assert_identical(what: &str, a: &Image, b: &Image) {
    let differing = |x: &[[f32; 3]], y: &[[f32; 3]]| {
        assert_eq!(x.len(), y.len(), "{what}: sizes differ");
        x.iter()
            .zip(y)
            .filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits))
            .count()
    };
    let n = differing(&a.mean, &b.mean);
    assert_eq!(n, 0, "{what}: {n} pixel means differ");
    let n = differing(
        a.variance.as_deref().expect("variance"),
        b.variance.as_deref().expect("variance"),
    );
    assert_eq!(n, 0, "{what}: {n} pixel variances differ");
}

#[test]
fn a_sequence_on_one_gpu_renderer_equals_frames_rendered_one_by_one() {
    let frames = frames();
    // The frames differ (the square moves), so a stale buffer would show.
    let cpu: Vec<Image> = frames
        .iter()
        .map(|(s, p)| render_cpu(s, p, &settings()))
        .collect();
    assert_ne!(cpu[0].mean, cpu[1].mean, "the square moves between frames");
    let Some(mut sequence) = gpu_renderer("sequence") else {
        return;
    };
    let in_sequence: Vec<Image> = frames
        .iter()
        .map(|(s, p)| render_gpu(&mut sequence, s, p, &settings()))
        .collect();
    assert!(
        sequence.last_upload.reused,
        "the last frame kept the buffers of the one before"
    );
    drop(sequence);
    for (n, (s, p)) in frames.iter().enumerate() {
        let mut alone = gpu_renderer("one frame").expect("a device, as above");
        let one = render_gpu(&mut alone, s, p, &settings());
        assert_identical(&format!("GPU frame {n}"), &in_sequence[n], &one);
    }
}

#[test]
fn the_command_line_writes_a_sequence_equal_to_single_renders() {
    sequence_equals_single_renders(&[]);
    // Motion-blurred frames: every path at its own time in each.
    sequence_equals_single_renders(&["--shutter", "0.1"]);
}

/// `vkpt --frames` with the options `extra` against single `--time` renders.
fn sequence_equals_single_renders(extra: &[&str]) {
    let dir = common::fresh_output_dir("sequence", &extra.len().to_string());
    let scene = "scenes/animated/moving-square.gltf";
    let common = [
        &[
            "--width", "32", "--spp", "2", "--seed", "3", "--device", "cpu", "-q",
        ][..],
        extra,
    ]
    .concat();
    let pattern = dir.join("f_%04d.exr");
    let out = common::vkpt(
        &[
            &[
                scene,
                "--frames",
                "1..3",
                "--fps",
                "4",
                "-o",
                pattern.to_str().unwrap(),
            ][..],
            &common,
        ]
        .concat(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("frame 2 (t = 0.5000 s)"), "{stdout}");
    assert!(!dir.join("f_0000.exr").exists(), "frame 0 is not in 1..3");
    for (frame, time) in [(1, "0.25"), (2, "0.5")] {
        let single = dir.join(format!("single_{frame}.exr"));
        let out = common::vkpt(
            &[
                &[scene, "--time", time, "-o", single.to_str().unwrap()][..],
                &common,
            ]
            .concat(),
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let a = vkpt::image::read_exr(&dir.join(format!("f_{frame:04}.exr"))).unwrap();
        let b = vkpt::image::read_exr(&single).unwrap();
        assert_identical(&format!("frame {frame}"), &a, &b);
    }
    // Several frames need a pattern.
    let out = common::vkpt(
        &[
            &[
                scene,
                "--frames",
                "0..2",
                "-o",
                dir.join("one.png").to_str().unwrap(),
            ][..],
            &common,
        ]
        .concat(),
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("2 frames need a file name pattern with %04d"),
        "{err}"
    );
}
