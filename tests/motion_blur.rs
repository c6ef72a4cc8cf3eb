//! Motion blur over the shutter (`render::motion`) on the moving square
//! (scenes/animated/moving-square.gltf: a white emissive square, side 0.5,
//! crossing a black background at 2 units/s; the view is 4 units wide at
//! the square): the blurred render is the average of instant renders over
//! the shutter, on both back ends; CPU and GPU agree; and the blurred edge
//! is the linear ramp of the closed form.

mod common;

use common::{Gpu, assert_agree, gpu_renderer, repo_path};
use vkpt::film::Film;
use vkpt::image::Image;
use vkpt::packed::PackedScene;
use vkpt::render::motion::{Shutter, render_motion_blur};
use vkpt::render::{RenderResult, RenderSettings};
use vkpt::scene::{GltfFile, LoadOptions, Scene};

const SHUTTER: Shutter = Shutter {
    open: 0.0,
    duration: 0.25,
};

fn file() -> GltfFile {
    let path = repo_path("scenes/animated/moving-square.gltf");
    GltfFile::open(&path, &LoadOptions::default()).expect("loads")
}

fn settings(width: u32, spp: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width,
        height: width,
        spp,
        seed,
        ..Default::default()
    }
}

/// A back end rendering a sample range.
type Render<'a> = dyn FnMut(&Scene, &PackedScene, &RenderSettings) -> RenderResult + 'a;

/// Renders with `render` (a back end) blurred over `SHUTTER`.
fn blurred(settings: &RenderSettings, render: &mut Render) -> Image {
    let file = file();
    let mut pose = |t: f64| file.at(t);
    let mut part = |s: &Scene, p: &PackedScene, r: &RenderSettings| Ok(render(s, p, r));
    let (result, stats) =
        render_motion_blur(SHUTTER, settings, &mut pose, &mut part).expect("renders");
    assert!(stats.steps > 1);
    assert_eq!(result.spp, settings.spp);
    result.film.to_image()
}

/// The average of `n` instant renders at the midpoints of n equal parts of
/// the shutter, each of `spp` samples (independent seeds).
fn instants(n: u32, spp: u32, width: u32, render: &mut Render) -> Image {
    let file = file();
    let mut total: Option<Film> = None;
    for i in 0..n {
        let t = SHUTTER.open + SHUTTER.duration * (i as f64 + 0.5) / n as f64;
        let scene = file.at(t).expect("poses");
        let packed = PackedScene::new(&scene).expect("packs");
        let film = render(&scene, &packed, &settings(width, spp, 1000 + i)).film;
        match &mut total {
            None => total = Some(film),
            Some(f) => f.merge(&film),
        }
    }
    total.expect("n > 0").to_image()
}

fn checked(result: anyhow::Result<RenderResult>) -> RenderResult {
    let result = result.expect("renders");
    assert_eq!(result.traversal_overflows, 0);
    assert_eq!(result.nonfinite_samples, 0);
    result
}

fn cpu(s: &Scene, p: &PackedScene, r: &RenderSettings) -> RenderResult {
    checked(vkpt::cpu::render::render(s, p, r, &|_, _| {}))
}

fn on(gpu: &mut Gpu) -> impl FnMut(&Scene, &PackedScene, &RenderSettings) -> RenderResult + '_ {
    move |s, p, r| checked(gpu.render(s, p, r, &|_, _| {}))
}

#[test]
fn the_blurred_render_is_the_average_of_instants_over_the_shutter() {
    let blur = blurred(&settings(32, 256, 1), &mut cpu);
    let reference = instants(32, 8, 32, &mut cpu);
    assert_agree("motion_blur_average_cpu", &blur, &reference);
    let Some(mut gpu) = gpu_renderer("motion_blur_average") else {
        return;
    };
    let mut on_gpu = on(&mut gpu);
    let blur = blurred(&settings(32, 256, 1), &mut on_gpu);
    let reference = instants(32, 8, 32, &mut on_gpu);
    assert_agree("motion_blur_average_gpu", &blur, &reference);
}

#[test]
fn gpu_and_cpu_agree_on_a_moving_scene() {
    let Some(mut gpu) = gpu_renderer("motion_blur_gpu_cpu") else {
        return;
    };
    let s = settings(32, 128, 5);
    let on_cpu = blurred(&s, &mut cpu);
    let on_gpu = blurred(&s, &mut on(&mut gpu));
    assert_agree("motion_blur_gpu_vs_cpu", &on_gpu, &on_cpu);
}

/// The square's right edge starts at x = -0.75 and moves at 2 units/s: over
/// the 0.25 s shutter a point x in [-0.75, -0.25] is covered for the last
/// (0.25 - (x + 0.75) / 2) s, so its value is 1 - (x + 0.75) / 0.5; the
/// left edge, from -1.25, uncovers x in [-1.25, -0.75] after (x + 1.25) / 2
/// s: value (x + 1.25) / 0.5. A box pixel filter averages a linear ramp to
/// its value at the pixel centre, for pixels inside the ramp. At 32 pixels
/// over 4 units, pixel i's centre is at x = -2 + (i + 0.5) / 8.
#[test]
fn the_blurred_edge_is_the_closed_form_linear_ramp() {
    let expected = |x: f64| -> f64 {
        if (-1.25..=-0.75).contains(&x) {
            (x + 1.25) / 0.5
        } else if (-0.75..=-0.25).contains(&x) {
            1.0 - (x + 0.75) / 0.5
        } else {
            f64::NAN
        }
    };
    let check = |image: &Image, what: &str| {
        let var = image.variance.as_ref().expect("variance");
        for row in [15u32, 16] {
            for i in (6..=13).filter(|&i| i != 9 && i != 10) {
                // Pixels 9 and 10 straddle x = -0.75, where the two ramps meet.
                let x = -2.0 + (i as f64 + 0.5) / 8.0;
                let k = (row * 32 + i) as usize;
                let got = image.mean[k][0] as f64;
                let sd = (var[k][0] as f64).sqrt();
                let want = expected(x);
                assert!(
                    (got - want).abs() <= 5.0 * sd + 2e-3,
                    "{what}: pixel ({i}, {row}) at x = {x}: {got} ± {sd}, closed form {want}"
                );
            }
            // Outside the swept band: black.
            for i in [0u32, 3, 20, 31] {
                let k = (row * 32 + i) as usize;
                assert_eq!(
                    image.mean[k], [0.0; 3],
                    "{what}: pixel ({i}, {row}) is not black"
                );
            }
        }
    };
    check(&blurred(&settings(32, 1024, 2), &mut cpu), "CPU");
    let Some(mut gpu) = gpu_renderer("motion_blur_ramp") else {
        return;
    };
    check(&blurred(&settings(32, 1024, 2), &mut on(&mut gpu)), "GPU");
}
