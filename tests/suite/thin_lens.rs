//! Thin-lens physics on the CPU reference: a small emitter off the focus
//! plane images as the aperture's shape, as large as the thin-lens circle
//! of confusion; on the focus plane it stays sharp.
//!
//! The "point" light is a tiny emissive square (punctual lights live on
//! another branch) whose pinhole image is about 3 pixels wide, against
//! circles of confusion of 32 to 60 pixels. The renderer builds depth of
//! field from a focus plane and an aperture and never uses the lens
//! equation; the expected sizes here come from the textbook formula
//! c = f^2 |d - s| / (N d (s - f)) on a sensor of height 2 v tan(yfov / 2)
//! with v = s f / (s - f) (the image distance when focused at s: vkpt keeps
//! the glTF field of view at the focused distance).

use glam::Vec3;
use std::path::PathBuf;
use vkpt::image::Image;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{Camera, Material, Scene, ThinLens, Triangle};

const SIZE: u32 = 96;
const FOCAL: f32 = 0.1;
const FSTOP: f32 = 1.0;
const FOCUS: f32 = 2.0;

/// A square emitter of side `w` at depth `d` facing a camera at the origin
/// looking down -Z with half-angle tangent `tan_half`.
fn scene(d: f32, w: f32, tan_half: f32, lens: ThinLens) -> Scene {
    let h = 0.5 * w;
    let p = |x: f32, y: f32| Vec3::new(x, y, -d);
    let quad = [p(-h, -h), p(h, -h), p(h, h), p(-h, h)];
    let tri = |a: usize, b: usize, c: usize| Triangle {
        positions: [quad[a], quad[b], quad[c]],
        normals: [Vec3::Z; 3],
        material: 0,
    };
    let mut light = Material::lambert("source", Vec3::ZERO);
    light.emission = Vec3::ONE;
    Scene {
        source: PathBuf::from("thin-lens test"),
        triangles: vec![tri(0, 1, 2), tri(0, 2, 3)],
        materials: vec![light],
        cameras: vec![Camera {
            aspect_ratio: Some(1.0),
            lens,
            ..Camera::pinhole(
                "lens",
                Vec3::ZERO,
                Vec3::NEG_Z,
                Vec3::Y,
                2.0 * tan_half.atan(),
            )
        }],
        environment: None,
        notes: Vec::new(),
        ..Default::default()
    }
}

fn lens(blades: u32) -> ThinLens {
    ThinLens {
        focal_length: Some(FOCAL),
        fstop: FSTOP,
        focus_distance: Some(FOCUS),
        blades,
        ..Default::default()
    }
}

/// Circle of confusion in pixels from the thin-lens equation.
fn coc_pixels(d: f32, tan_half: f32) -> f32 {
    let (f, s, n) = (FOCAL as f64, FOCUS as f64, FSTOP as f64);
    let d = d as f64;
    let c = f * f * (d - s).abs() / (n * d * (s - f));
    let v = s * f / (s - f);
    let sensor_height = 2.0 * v * tan_half as f64;
    (c / sensor_height * SIZE as f64) as f32
}

/// Pinhole image width in pixels of a square of side `w` at depth `d`.
fn source_pixels(d: f32, w: f32, tan_half: f32) -> f32 {
    w / (d * 2.0 * tan_half) * SIZE as f32
}

/// Renders emitters only (max depth 1) on the CPU reference.
fn render(scene: &Scene, spp: u32) -> Image {
    let packed = PackedScene::new(scene).expect("packs");
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        spp,
        max_depth: Some(1),
        seed: 17,
        camera: 0,
        ..Default::default()
    };
    vkpt::cpu::render::render(scene, &packed, &settings, &|_, _| {})
        .expect("renders")
        .film
        .to_image()
}

fn intensity(img: &Image, x: u32, y: u32) -> f64 {
    img.mean[img.index(x, y)][0] as f64
}

/// Intensity-weighted centroid and mean squared distance from it, in
/// pixels (pixel centres at integer + 0.5).
fn moments(img: &Image) -> ((f64, f64), f64) {
    let (mut s, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for y in 0..img.height {
        for x in 0..img.width {
            let i = intensity(img, x, y);
            s += i;
            sx += i * (x as f64 + 0.5);
            sy += i * (y as f64 + 0.5);
        }
    }
    let c = (sx / s, sy / s);
    let mut r2 = 0.0;
    for y in 0..img.height {
        for x in 0..img.width {
            let (dx, dy) = (x as f64 + 0.5 - c.0, y as f64 + 0.5 - c.1);
            r2 += intensity(img, x, y) * (dx * dx + dy * dy);
        }
    }
    (c, r2 / s)
}

/// Diameter of the uniform disk whose image (convolved with the pinhole
/// image of the square source and sampled at pixel centres) has mean
/// squared radius `r2`: for a disk of radius R, E[r^2] = R^2 / 2; a square
/// of side w adds w^2 / 12 per axis and pixel-centre sampling 1 / 12.
fn disk_diameter(r2: f64, source_px: f32) -> f64 {
    let w = source_px as f64;
    2.0 * (2.0 * (r2 - 2.0 * (w * w + 1.0) / 12.0)).sqrt()
}

#[test]
fn out_of_focus_point_images_as_the_circle_of_confusion() {
    let tan_half = 0.025;
    for d in [4.0f32, 1.5] {
        let source = 3.0 * d * 2.0 * tan_half / SIZE as f32;
        let img = render(&scene(d, source, tan_half, lens(0)), 512);
        let ((cx, cy), r2) = moments(&img);
        let measured = disk_diameter(r2, source_pixels(d, source, tan_half));
        let expected = coc_pixels(d, tan_half) as f64;
        println!(
            "source at {d} m, focus {FOCUS} m: disk diameter {measured:.2} px, thin-lens circle of confusion {expected:.2} px, centre ({cx:.2}, {cy:.2})"
        );
        assert!(
            (measured / expected - 1.0).abs() < 0.02,
            "source at {d} m: diameter {measured:.2} px, expected {expected:.2} px"
        );
        let half = SIZE as f64 / 2.0;
        // Centred to within a pixel (the centroid of ~5000 hits scatters by
        // about 0.2 px).
        assert!((cx - half).abs() < 1.0 && (cy - half).abs() < 1.0);
    }
}

#[test]
fn in_focus_point_stays_sharp() {
    let tan_half = 0.025;
    let d = FOCUS;
    let source = 3.0 * d * 2.0 * tan_half / SIZE as f32;
    let sharp = render(&scene(d, source, tan_half, lens(6)), 64);
    let pinhole = render(&scene(d, source, tan_half, ThinLens::default()), 64);
    let (_, r2_lens) = moments(&sharp);
    let (_, r2_pinhole) = moments(&pinhole);
    println!(
        "source on the focus plane: mean squared radius {r2_lens:.3} px^2 with the f/{FSTOP} lens, {r2_pinhole:.3} px^2 pinhole"
    );
    assert!((r2_lens / r2_pinhole - 1.0).abs() < 0.05);
    // The source covers [46.5, 49.5] in both axes: no light outside the
    // pixels it touches (out of focus, this lens spreads it over tens).
    for y in 0..SIZE {
        for x in 0..SIZE {
            if !(46..50).contains(&x) || !(46..50).contains(&y) {
                assert_eq!(intensity(&sharp, x, y), 0.0, "light at pixel ({x}, {y})");
            }
        }
    }
}

/// Chord length through the centre, in pixels: the sum of intensities along
/// the centre row (`horizontal`) or column, averaged over the two central
/// lines, divided by the disk's interior intensity.
fn profile(img: &Image, horizontal: bool) -> Vec<f64> {
    let n = img.width;
    (0..n)
        .map(|t| {
            (0..n)
                .map(|u| {
                    if horizontal {
                        intensity(img, t, u)
                    } else {
                        intensity(img, u, t)
                    }
                })
                .sum::<f64>()
        })
        .collect()
}

/// With six blades and rotation 0 a vertex points along the camera's right
/// axis (image x): the bokeh reaches the circle of confusion's radius R
/// along x and only R cos 30° along y. Projected onto x, a regular hexagon
/// is a trapezoid whose sides fall linearly to 0 at +-R; projected onto y
/// it ends in a step at +-R cos 30° from height R (in chord-length units)
/// to 0. Both are measured on the projections (all hits count) and are
/// unchanged by the small symmetric blur of the source: the ramp's line
/// extrapolated to 0, and the step's half-height crossing.
#[test]
fn six_blades_image_a_hexagon_with_vertices_along_the_rotation() {
    let tan_half = 0.02;
    let d = 4.0f32;
    let source = 3.0 * d * 2.0 * tan_half / SIZE as f32;
    let img = render(&scene(d, source, tan_half, lens(6)), 1024);
    let r = coc_pixels(d, tan_half) as f64 / 2.0;
    let c = SIZE as f64 / 2.0;
    // Interior intensity: the hexagon's area (3 sqrt(3) / 2 R^2) holds all
    // the light.
    let total: f64 = img.mean.iter().map(|p| p[0] as f64).sum();
    let level = total / (1.5 * 3f64.sqrt() * r * r);

    // Along x: fit chord(t) = a + b |t - c| on R/2 + 3 < |t - c| < R - 3,
    // both sides, and extrapolate to 0.
    let px = profile(&img, true);
    let (mut n, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (i, v) in px.iter().enumerate() {
        let t = (i as f64 + 0.5 - c).abs();
        if t > r / 2.0 + 3.0 && t < r - 3.0 {
            let y = v / level;
            n += 1.0;
            sx += t;
            sy += y;
            sxx += t * t;
            sxy += t * y;
        }
    }
    let b = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    let a = (sy - b * sx) / n;
    let vertex_extent = -a / b;

    // Along y: the outermost half-height (R / 2) crossing on each side,
    // linearly interpolated between pixel centres.
    let py: Vec<f64> = profile(&img, false).iter().map(|v| v / level).collect();
    let crossing = |range: Vec<usize>| -> f64 {
        for w in range.windows(2) {
            let (i, j) = (w[0], w[1]);
            if py[i] < r / 2.0 && py[j] >= r / 2.0 {
                let f = (r / 2.0 - py[i]) / (py[j] - py[i]);
                let t = i as f64 + f * (j as f64 - i as f64) + 0.5;
                return (t - c).abs();
            }
        }
        panic!("no half-height crossing in the vertical profile");
    };
    let n = SIZE as usize;
    let flat_extent = 0.5 * (crossing((0..n / 2).collect()) + crossing((n / 2..n).rev().collect()));

    let flat_expected = r * (std::f64::consts::PI / 6.0).cos();
    println!(
        "hexagon: extent along the vertex direction {vertex_extent:.2} px (expected {r:.2}), along the flat side {flat_extent:.2} px (expected {flat_expected:.2})"
    );
    assert!(
        (vertex_extent / r - 1.0).abs() < 0.03,
        "vertex extent {vertex_extent:.2} px, expected {r:.2}"
    );
    assert!(
        (flat_extent / flat_expected - 1.0).abs() < 0.03,
        "flat extent {flat_extent:.2} px, expected {flat_expected:.2}"
    );
}
