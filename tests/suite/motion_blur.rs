//! Motion blur over the shutter, both ways vkpt blurs: a time per path in
//! the kernels (`scene::motion`, `motion.glsl`) and time steps on the host
//! (`render::motion`, the fallback). On the moving square
//! (scenes/animated/moving-square.gltf: a white emissive square, side 0.5,
//! crossing a black background at 2 units/s; the view is 4 units wide at
//! the square) the blurred render is the average of instant renders over
//! the shutter, on both back ends; CPU and GPU agree; and the blurred edge
//! is the linear ramp of the closed form. Bundled scenes given a motion in
//! code (turning, growing, the camera moving) check the per-path time
//! against instants and GPU against CPU path by path, through emitters,
//! normal maps and anisotropy.

use crate::common;

use common::{Gpu, assert_agree, gpu_renderer, in_motion, load, pixels_differing, repo_path};
use glam::{Vec3, Vec4};
use vkpt::film::Film;
use vkpt::image::Image;
use vkpt::packed::PackedScene;
use vkpt::render::motion::{Shutter, render_motion_blur};
use vkpt::render::{RenderResult, RenderSettings};
use vkpt::scene::motion::{motion_lerp, pose_over_shutter};
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

/// The two ways of blurring.
#[derive(Clone, Copy, Debug)]
enum Blur {
    /// Every path at its own time, in the kernels.
    PerPath,
    /// Sample ranges at time steps, posed on the host.
    HostSteps,
}

const BOTH: [Blur; 2] = [Blur::PerPath, Blur::HostSteps];

/// Renders with `render` (a back end) blurred over `SHUTTER`.
fn blurred(how: Blur, settings: &RenderSettings, render: &mut Render) -> Image {
    let file = file();
    let mut pose = |t: f64, origin| file.at_from(t, origin);
    match how {
        Blur::PerPath => {
            let scene = pose_over_shutter(&mut pose, SHUTTER.open, SHUTTER.duration)
                .expect("poses")
                .expect("the kernels follow a straight motion");
            let steps = scene.motion.as_ref().map_or(0, |m| m.steps.len());
            assert_eq!(steps, 2, "a constant speed needs two time steps");
            let packed = PackedScene::new(&scene).expect("packs");
            let result = render(&scene, &packed, settings);
            assert_eq!(result.spp, settings.spp);
            result.film.to_image()
        }
        Blur::HostSteps => {
            let mut part = |s: &Scene, p: &PackedScene, r: &RenderSettings| Ok(render(s, p, r));
            let (result, stats) =
                render_motion_blur(SHUTTER, settings, &mut pose, &mut part).expect("renders");
            assert!(stats.steps > 1);
            assert_eq!(result.spp, settings.spp);
            result.film.to_image()
        }
    }
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

/// The CPU back end, and the GPU where there is one, as sample-range
/// renderers.
fn backends(test: &str) -> Vec<(&'static str, Box<Render<'static>>)> {
    let mut backends: Vec<(&str, Box<Render>)> = vec![("cpu", Box::new(cpu))];
    if let Some(mut gpu) = gpu_renderer(test) {
        backends.push((
            "gpu",
            Box::new(move |s: &Scene, p: &PackedScene, r: &RenderSettings| {
                checked(gpu.render(s, p, r, &|_, _| {}))
            }),
        ));
    }
    backends
}

#[test]
fn the_blurred_render_is_the_average_of_instants_over_the_shutter() {
    for (name, render) in &mut backends("motion_blur_average") {
        let reference = instants(32, 8, 32, render);
        for how in BOTH {
            let blur = blurred(how, &settings(32, 256, 1), render);
            let test = format!("motion_blur_average_{name}_{how:?}");
            assert_agree(&test, &blur, &reference);
        }
    }
}

#[test]
fn gpu_and_cpu_agree_on_a_moving_scene() {
    let Some(mut gpu) = gpu_renderer("motion_blur_gpu_cpu") else {
        return;
    };
    let s = settings(32, 128, 5);
    for how in BOTH {
        let on_cpu = blurred(how, &s, &mut cpu);
        let on_gpu = blurred(how, &s, &mut on(&mut gpu));
        assert_agree(&format!("motion_blur_gpu_vs_cpu_{how:?}"), &on_gpu, &on_cpu);
    }
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
    for (name, render) in &mut backends("motion_blur_ramp") {
        for how in BOTH {
            let image = blurred(how, &settings(32, 1024, 2), render);
            check(&image, &format!("{name} {how:?}"));
        }
    }
}

/// The interpolation scene (scenes/animated/interpolation-test.gltf): a
/// cube turning on LINEAR keys needs more than two time steps, and a STEP
/// key's jump inside the shutter cannot be followed linearly, so it is left
/// to the host's time steps.
#[test]
fn time_steps_follow_curved_motion_and_refuse_jumps() {
    let path = repo_path("scenes/animated/interpolation-test.gltf");
    let file = GltfFile::open(&path, &LoadOptions::default()).expect("loads");
    let mut pose = |t: f64, origin| file.at_from(t, origin);
    let smooth = pose_over_shutter(&mut pose, 1.2, 0.2).expect("poses");
    let steps = smooth.expect("followed").motion.expect("moves").steps.len();
    assert!(steps > 2, "a turning cube took {steps} steps");
    let jump = pose_over_shutter(&mut pose, 0.5, 0.5).expect("poses");
    let reason = jump.expect_err("a STEP key's jump is refused");
    assert!(reason.contains("not linear"), "{reason}");
}

/// The still scene a moving one shows at shutter fraction `w` (its two
/// steps interpolated as the kernels interpolate them).
fn instant(scene: &Scene, w: f32) -> Scene {
    let m = scene.motion.as_ref().expect("moves");
    let (a, b) = (&m.steps[0], &m.steps[1]);
    let mut s = scene.clone();
    s.motion = None;
    for (t, (x, y)) in s
        .triangles
        .iter_mut()
        .zip(a.triangles.iter().zip(&b.triangles))
    {
        for j in 0..3 {
            t.positions[j] = motion_lerp(x.positions[j], y.positions[j], w);
            t.normals[j] = motion_lerp(x.normals[j], y.normals[j], w).normalize();
        }
    }
    for (t, (x, y)) in s
        .texcoords
        .iter_mut()
        .zip(a.texcoords.iter().zip(&b.texcoords))
    {
        for j in 0..3 {
            let (p, q): (Vec4, Vec4) = (x.tangents[j], y.tangents[j]);
            t.tangents[j] = p + (q - p) * w;
        }
    }
    for (c, (x, y)) in s.cameras.iter_mut().zip(a.cameras.iter().zip(&b.cameras)) {
        c.position = motion_lerp(x.position, y.position, w);
        c.forward = motion_lerp(x.forward, y.forward, w).normalize();
        c.up = motion_lerp(x.up, y.up, w).normalize();
    }
    s
}

/// On both back ends (the GPU where there is one), `scene` blurred per path
/// at 512 spp equals the average of 32 instants of 16 spp each,
/// `instant_at(i)` the scene at the middle of the shutter's i-th 32nd.
fn assert_blur_is_the_average_of_instants(
    test: &str,
    scene: &Scene,
    width: u32,
    instant_at: &dyn Fn(u32) -> Scene,
) {
    let packed = PackedScene::new(scene).expect("packs");
    for (name, render) in &mut backends(test) {
        let blur = render(scene, &packed, &settings(width, 512, 3))
            .film
            .to_image();
        let mut total: Option<Film> = None;
        for i in 0..32 {
            let at = instant_at(i);
            let packed = PackedScene::new(&at).expect("packs");
            let film = render(&at, &packed, &settings(width, 16, 100 + i)).film;
            match &mut total {
                None => total = Some(film),
                Some(f) => f.merge(&film),
            }
        }
        let reference = total.expect("32 instants").to_image();
        assert_agree(&format!("{test}_{name}"), &blur, &reference);
    }
}

/// The Cornell box turning a quarter turn and growing by half (its light
/// too) while the camera slides and turns: the per-path blur equals the
/// average of 32 instants, on both back ends.
#[test]
fn a_moving_camera_and_growing_light_blur_to_the_average_of_instants() {
    let (still, _) = load("scenes/cornell-box.gltf");
    let scene = in_motion(still, 0.5, 1.5, Vec3::new(0.3, 0.1, 0.0));
    let instant_at = |i: u32| instant(&scene, (i as f32 + 0.5) / 32.0);
    assert_blur_is_the_average_of_instants("motion_blur_camera", &scene, 24, &instant_at);
}

/// The same random numbers give the same paths through moving geometry,
/// a moving or still camera, emitters, normal maps (scenes/textured.gltf) and
/// anisotropy (scenes/coat-grid.gltf) on both back ends.
#[test]
fn per_path_time_traces_the_same_paths_on_gpu_and_cpu() {
    let Some(mut gpu) = gpu_renderer("motion_blur_same_paths") else {
        return;
    };
    // The camera moves in all but the last (MOTION_CAMERA_STILL).
    for (path, camera_moves) in [
        ("scenes/cornell-box.gltf", true),
        ("scenes/textured.gltf", true),
        ("scenes/coat-grid.gltf", true),
        ("scenes/cornell-box.gltf", false),
    ] {
        let (still, _) = load(path);
        let mut scene = in_motion(still, 0.3, 1.2, Vec3::new(0.05, 0.0, 0.02));
        if !camera_moves {
            let m = scene.motion.as_mut().expect("moves");
            m.steps[1].cameras = m.steps[0].cameras.clone();
        }
        let packed = PackedScene::new(&scene).expect("packs");
        let s = settings(48, 8, 9);
        let a = on(&mut gpu)(&scene, &packed, &s).film.to_image();
        let b = cpu(&scene, &packed, &s).film.to_image();
        let differing = pixels_differing(&a, &b, 1e-4);
        println!(
            "{path}: {differing} of {} pixels differ by more than 1e-4",
            a.mean.len()
        );
        assert!(
            differing * 100 < a.mean.len(),
            "{path}: {differing} pixels differ between GPU and CPU"
        );
    }
}

/// A real skinned asset, Khronos' RiggedSimple (tests/data/khronos): the
/// bones bend the cylinder while the shutter is open, the kernels follow
/// it through time steps of the skinned vertices, and the blur equals the
/// average of 32 instants posed by the host, on both back ends.
#[test]
fn a_skinned_character_blurs_to_the_average_of_instants() {
    let path = repo_path("tests/data/khronos/RiggedSimple.glb");
    let file = GltfFile::open(&path, &LoadOptions::default()).expect("loads");
    let (open, duration) = (0.5, 0.25);
    let mut pose = |t: f64, origin| file.at_from(t, origin);
    let scene = pose_over_shutter(&mut pose, open, duration)
        .expect("poses")
        .expect("the kernels follow the skin");
    let steps = scene.motion.as_ref().expect("moves").steps.len();
    assert!(steps >= 2, "{steps} time steps");
    // The instants in the opening pose's coordinates, with vkpt's automatic
    // camera held still there, as per-path blur has them.
    let origin = Some(scene.world_origin);
    let instant_at = |i: u32| {
        let t = open + duration * (i as f64 + 0.5) / 32.0;
        let mut at = file.at_from(t, origin).expect("poses");
        at.cameras = scene.cameras.clone();
        at
    };
    assert_blur_is_the_average_of_instants("motion_blur_skin", &scene, 32, &instant_at);
}
