//! Shared by the rendering tests: both back ends on one scene, and the rule
//! for a machine without Vulkan (skip with one line, unless CI requires it).

#![allow(dead_code)]

pub mod gltf_builder;

use glam::Vec3;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use vkpt::gpu::GpuRenderer;
use vkpt::gpu::context::VALIDATION_MESSAGES;
use vkpt::gpu::context::VulkanDevice;
use vkpt::image::Image;
use vkpt::image::compare::{compare, write_failure_evidence};
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{Scene, Triangle};

/// The folder `target/test-output/<path>` for a suite's or a test's files,
/// created if missing (kept between runs, so a failure's files can be
/// read).
pub fn output_dir(path: &str) -> PathBuf {
    let dir = repo_path("target/test-output").join(path);
    std::fs::create_dir_all(&dir).expect("can create the test output folder");
    dir
}

/// `output_dir(<suite>/<test>)` emptied first: one test's files, none left
/// from an earlier run.
pub fn fresh_output_dir(suite: &str, test: &str) -> PathBuf {
    let dir = repo_path("target/test-output").join(suite).join(test);
    let _ = std::fs::remove_dir_all(&dir);
    output_dir(&format!("{suite}/{test}"))
}

pub fn repo_path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

pub fn load(relative: &str) -> (Scene, PackedScene) {
    let scene = Scene::load(&repo_path(relative)).expect("bundled scene loads");
    let packed = PackedScene::new(&scene).expect("bundled scene packs");
    (scene, packed)
}

/// A Vulkan renderer that fails the test if the validation layer reported
/// anything, during rendering or at teardown (leaked objects are reported
/// when the device is destroyed).
pub struct Gpu(Option<GpuRenderer>);

impl std::ops::Deref for Gpu {
    type Target = GpuRenderer;
    fn deref(&self) -> &GpuRenderer {
        self.0.as_ref().expect("renderer alive until drop")
    }
}

impl std::ops::DerefMut for Gpu {
    fn deref_mut(&mut self) -> &mut GpuRenderer {
        self.0.as_mut().expect("renderer alive until drop")
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        drop(self.0.take());
        if !std::thread::panicking() {
            assert_eq!(
                VALIDATION_MESSAGES.load(Ordering::Relaxed),
                0,
                "the Vulkan validation layer reported problems (printed above)"
            );
        }
    }
}

/// A Vulkan renderer with validation on wherever the layer is installed, or
/// `None` (with a printed notice) on a machine without Vulkan. With
/// `VKPT_REQUIRE_GPU=1` (set by .ci/run) a missing device fails the test.
pub fn gpu_renderer(test: &str) -> Option<Gpu> {
    checked_gpu(
        test,
        GpuRenderer::with_validation(VulkanDevice::Best, Some(true)),
    )
}

/// As `gpu_renderer`, as `devices` lavapipe devices that split every pass
/// (`vkpt::gpu::split`); a GPU stays one device.
pub fn gpu_renderer_with_devices(test: &str, devices: usize) -> Option<Gpu> {
    checked_gpu(
        test,
        GpuRenderer::with_lavapipe_devices(VulkanDevice::Best, Some(true), devices),
    )
}

fn checked_gpu(test: &str, opened: anyhow::Result<GpuRenderer>) -> Option<Gpu> {
    match opened {
        Ok(r) => Some(Gpu(Some(r))),
        Err(e) if std::env::var("VKPT_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
            panic!("{test}: VKPT_REQUIRE_GPU=1 but no Vulkan device: {e:#}")
        }
        Err(e) => {
            println!("{test}: skipping the Vulkan half, no Vulkan device: {e:#}");
            None
        }
    }
}

pub fn render_gpu(
    renderer: &mut GpuRenderer,
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
) -> Image {
    let result = renderer
        .render(scene, packed, settings, &|_, _| {})
        .expect("GPU render succeeds");
    assert_eq!(
        VALIDATION_MESSAGES.load(Ordering::Relaxed),
        0,
        "the Vulkan validation layer reported problems (printed above)"
    );
    assert_eq!(
        result.traversal_overflows, 0,
        "BVH traversal overflowed on the GPU"
    );
    assert_eq!(result.nonfinite_samples, 0, "non-finite samples on the GPU");
    result.film.to_image()
}

pub fn render_cpu(scene: &Scene, packed: &PackedScene, settings: &RenderSettings) -> Image {
    let result = vkpt::cpu::render::render(scene, packed, settings, &|_, _| {})
        .expect("CPU render succeeds");
    assert_eq!(
        result.traversal_overflows, 0,
        "BVH traversal overflowed on the CPU"
    );
    assert_eq!(result.nonfinite_samples, 0, "non-finite samples on the CPU");
    result.film.to_image()
}

/// The variance-aware comparison every rendering test uses: `a` and `b` must
/// have the same expectation (`stats::compare` at significance 0.01, per
/// pixel, block and image). Prints the comparison; on disagreement writes
/// the images under `failure_dir(test)` and fails the test.
pub fn assert_agree(test: &str, a: &Image, b: &Image) {
    let cmp = compare(a, b, 0.01).expect("comparable images");
    println!("{test}:\n{cmp}");
    if !cmp.passed() {
        let dir = failure_dir(test);
        write_failure_evidence(&dir, a, b, &cmp).expect("evidence written");
        panic!("{test}: the images disagree; evidence in {}", dir.display());
    }
}

/// Where a failing comparison leaves its images.
pub fn failure_dir(test: &str) -> PathBuf {
    repo_path("target/test-failures").join(test)
}

/// Pixels whose mean differs between two images by more than
/// `tolerance * (1 + |b|)` in any channel.
pub fn pixels_differing(a: &Image, b: &Image, tolerance: f32) -> usize {
    a.mean
        .iter()
        .zip(&b.mean)
        .filter(|(x, y)| (0..3).any(|c| (x[c] - y[c]).abs() > tolerance * (1.0 + y[c].abs())))
        .count()
}

/// A square of side 2·`half` at height `y`, facing +Y.
pub fn horizontal_square(half: f32, y: f32, material: u32) -> [Triangle; 2] {
    let tri = |a: [f32; 3], b: [f32; 3], c: [f32; 3]| Triangle {
        positions: [a.into(), b.into(), c.into()],
        normals: [Vec3::Y; 3],
        material,
    };
    let h = half;
    [
        tri([-h, y, -h], [-h, y, h], [h, y, h]),
        tri([-h, y, -h], [h, y, h], [h, y, -h]),
    ]
}

/// Runs the vkpt binary from the repository root.
pub fn vkpt(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_vkpt"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("vkpt runs")
}

/// `scene` given a motion over a shutter of one second: at its close every
/// point has turned by `angle` about a tilted axis through the middle of
/// the scene (a turn about the vertical would leave a wall's tangent where
/// its normal map reads it) and moved `grow` times as far from it (areas change, so
/// emitters' light-sampling densities do), and every camera has moved by
/// `shift` and turned by a tenth of `angle`.
pub fn in_motion(mut scene: Scene, angle: f32, grow: f32, shift: Vec3) -> Scene {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for t in &scene.triangles {
        for v in t.positions {
            (lo, hi) = (lo.min(v), hi.max(v));
        }
    }
    let centre = 0.5 * (lo + hi);
    let turn = glam::Quat::from_axis_angle(Vec3::new(0.3, 1.0, 0.2).normalize(), angle);
    let mut end = vkpt::scene::motion::MotionStep {
        triangles: scene.triangles.clone(),
        texcoords: scene.texcoords.clone(),
        cameras: scene.cameras.clone(),
    };
    for t in &mut end.triangles {
        t.positions = t.positions.map(|p| centre + grow * (turn * (p - centre)));
        t.normals = t.normals.map(|n| turn * n);
    }
    for t in &mut end.texcoords {
        t.tangents = t.tangents.map(|v| (turn * v.truncate()).extend(v.w));
    }
    let look = glam::Quat::from_rotation_y(0.1 * angle);
    for c in &mut end.cameras {
        c.position += shift;
        c.forward = look * c.forward;
        c.up = look * c.up;
    }
    let start = vkpt::scene::motion::MotionStep {
        triangles: scene.triangles.clone(),
        texcoords: scene.texcoords.clone(),
        cameras: scene.cameras.clone(),
    };
    scene.motion = Some(vkpt::scene::motion::SceneMotion {
        steps: vec![start, end],
        deviation: 0.0,
    });
    scene
}
