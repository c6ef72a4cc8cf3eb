//! White furnace: a diffuse sphere of albedo 0.8 in a uniform environment of
//! radiance 1 shows exactly 0.8 (a convex object never sees itself, so every
//! path that leaves it sees the environment: 0.8 · 1), and the background
//! shows exactly 1, on both back ends, within statistical bounds.

mod common;

use common::*;
use glam::Vec3;
use vkpt::film::Image;
use vkpt::layout::RenderParams;
use vkpt::settings::RenderSettings;
use vkpt::stats::{compare, write_failure_evidence};

const ALBEDO: f32 = 0.8;

/// Distance from the sphere's centre (the origin) to the ray through the
/// film point (sx, sy) in [-1, 1]^2.
fn ray_miss_distance(p: &RenderParams, sx: f32, sy: f32) -> f32 {
    let o = Vec3::from(p.cam_position);
    let d = (Vec3::from(p.cam_forward)
        + sx * p.tan_half_fov * p.aspect * Vec3::from(p.cam_right)
        + sy * p.tan_half_fov * Vec3::from(p.cam_up))
    .normalize();
    o.cross(d).length()
}

/// The analytic answer where a pixel lies wholly on the sphere (0.8) or wholly
/// on the background (1); pixels on the silhouette take the rendered value
/// with no variance of their own, so they test nothing.
fn expected(p: &RenderParams, rendered: &Image) -> (Image, usize, usize) {
    let (w, h) = (p.width, p.height);
    let mut e = Image::new(w, h);
    e.variance = Some(vec![[0.0; 3]; (w * h) as usize]);
    let (mut on_sphere, mut on_background) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let corners = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)].map(|(cx, cy)| {
                let sx = 2.0 * cx as f32 / w as f32 - 1.0;
                let sy = 1.0 - 2.0 * cy as f32 / h as f32;
                ray_miss_distance(p, sx, sy)
            });
            let i = e.index(x, y);
            // The icosphere (subdivision 3) lies between radius 0.98 and 1.
            e.mean[i] = if corners.iter().all(|&d| d < 0.95) {
                on_sphere += 1;
                [ALBEDO; 3]
            } else if corners.iter().all(|&d| d > 1.02) {
                on_background += 1;
                [1.0; 3]
            } else {
                rendered.mean[i]
            };
        }
    }
    (e, on_sphere, on_background)
}

fn check(test: &str, image: &Image, params: &RenderParams) {
    let (e, on_sphere, on_background) = expected(params, image);
    assert!(
        on_sphere > 500 && on_background > 500,
        "the test scene frames the sphere"
    );
    let cmp = compare(image, &e, 0.01).expect("comparable");
    println!("{test}: {on_sphere} sphere pixels, {on_background} background pixels\n{cmp}");
    if !cmp.passed() {
        let dir = failure_dir(test);
        write_failure_evidence(&dir, image, &e, &cmp).expect("evidence written");
        panic!(
            "{test}: the furnace is not {ALBEDO}; evidence in {}",
            dir.display()
        );
    }
}

fn settings() -> RenderSettings {
    RenderSettings {
        width: 64,
        height: 64,
        spp: 64,
        max_depth: None,
        seed: 11,
        camera: 0,
    }
}

#[test]
fn white_furnace_cpu() {
    let (scene, packed) = load("scenes/white-furnace.gltf");
    let params = packed.render_params(&scene, &settings(), 0).unwrap();
    let image = render_cpu(&scene, &packed, &settings());
    check("white_furnace_cpu", &image, &params);
}

#[test]
fn white_furnace_gpu() {
    let Some(mut gpu) = gpu_renderer("white_furnace_gpu") else {
        return;
    };
    let (scene, packed) = load("scenes/white-furnace.gltf");
    let params = packed.render_params(&scene, &settings(), 0).unwrap();
    let image = render_gpu(&mut gpu, &scene, &packed, &settings());
    check("white_furnace_gpu", &image, &params);
}
