//! Photometric stereo, end to end (the lecture in `shared/seeds/`): a
//! Lambertian sphere of known albedo rendered under m directional lights
//! from known directions, one image per light (direct light only: no
//! environment, `max_depth` 2, so no interreflection), then per pixel
//! `I = L G` solved by least squares, `G = (LᵀL)⁻¹ LᵀI`: albedo ∝ |G|,
//! normal = G / |G|. The recovered normals and albedo are compared with the
//! renderer's own normal and albedo outputs (`--aov`).
//!
//!     cargo run --release --example photometric_stereo [-- SIZE SPP [DIR]]
//!
//! With DIR it also writes the true normals, the recovered normals (both as
//! n·½ + ½) and the recovered albedo of the sphere alone as PNGs there.
//!
//! It runs twice: the sphere alone, where the method's assumptions hold,
//! and the sphere on a white floor with unlimited depth, where light
//! bounced off the floor (interreflection) and the floor's own shading add
//! to the images and bias the solve.
//!
//! Pixels used: those the sphere covers entirely (the mean normal has unit
//! length there) and that every light reaches (n·l > 0.05 for each light:
//! attached shadows break `I = L G`). The sphere is a smooth-shaded UV
//! sphere; shading uses the interpolated normal, which the normal output
//! records too, so the comparison is with the normal the image was made of.

use glam::Vec3;
use std::f32::consts::PI;
use vkpt::image::Image;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{Camera, Light, LightKind, Material, Scene, Triangle};

/// The sphere's albedo (red channel is used for the solve).
const ALBEDO: f32 = 0.7;
/// Irradiance of each directional light on a surface facing it.
const IRRADIANCE: f32 = 3.0;

/// A smooth UV sphere of radius `r` at the origin.
fn sphere(r: f32, rings: u32, segments: u32) -> Vec<Triangle> {
    let point = |i: u32, j: u32| {
        let theta = PI * i as f32 / rings as f32;
        let phi = 2.0 * PI * j as f32 / segments as f32;
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        )
    };
    let mut tris = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            for [p, q, s] in [[a, c, b], [a, d, c]] {
                if (q - p).cross(s - p).length() > 1e-9 {
                    tris.push(Triangle {
                        positions: [p * r, q * r, s * r],
                        normals: [p, q, s],
                        material: 0,
                    });
                }
            }
        }
    }
    tris
}

/// Directions the light travels (towards the sphere), from above-front.
pub fn light_directions() -> Vec<Vec3> {
    [
        Vec3::new(0.4, -0.3, -1.0),
        Vec3::new(-0.4, -0.3, -1.0),
        Vec3::new(0.0, -0.55, -1.0),
        Vec3::new(0.1, -0.05, -1.0),
    ]
    .map(|d| d.normalize())
    .to_vec()
}

/// A white floor under the sphere, at y = -1, facing +Y.
fn floor() -> [Triangle; 2] {
    let tri = |a: [f32; 3], b: [f32; 3], c: [f32; 3]| Triangle {
        positions: [a.into(), b.into(), c.into()],
        normals: [Vec3::Y; 3],
        material: 1,
    };
    let (h, y) = (20.0, -1.0);
    [
        tri([-h, y, -h], [-h, y, h], [h, y, h]),
        tri([-h, y, -h], [h, y, h], [h, y, -h]),
    ]
}

fn scene(light: Vec3, with_floor: bool) -> Scene {
    let mut triangles = sphere(1.0, 96, 192);
    if with_floor {
        triangles.extend(floor());
    }
    Scene {
        source: "photometric stereo sphere".into(),
        triangles,
        materials: vec![
            Material::lambert("albedo 0.7", Vec3::splat(ALBEDO)),
            Material::lambert("white floor", Vec3::splat(0.8)),
        ],
        cameras: vec![Camera {
            aspect_ratio: Some(1.0),
            ..Camera::pinhole(
                "front",
                Vec3::new(0.0, 0.0, 4.0),
                Vec3::NEG_Z,
                Vec3::Y,
                2.0 * (1.1f32 / 4.0).atan(),
            )
        }],
        lights: vec![Light {
            name: "light".into(),
            kind: LightKind::Directional,
            position: Vec3::ZERO,
            direction: light,
            color: Vec3::splat(IRRADIANCE),
            range: None,
        }],
        ..Default::default()
    }
}

fn render(scene: &Scene, size: u32, spp: u32, aov: bool, depth: Option<u32>) -> Image {
    let packed = PackedScene::new(scene).expect("the sphere packs");
    let settings = RenderSettings {
        width: size,
        height: size,
        spp,
        max_depth: depth,
        aov,
        ..Default::default()
    };
    vkpt::cpu::render::render(scene, &packed, &settings, &|_, _| {})
        .expect("CPU render")
        .film
        .to_image()
}

/// Solves the 3×3 system `a x = b` by Cramer's rule.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    if d.abs() < 1e-12 {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, xk) in x.iter_mut().enumerate() {
        let mut m = a;
        for row in 0..3 {
            m[row][k] = b[row];
        }
        *xk = det(m) / d;
    }
    Some(x)
}

/// What the method recovered, against the renderer's outputs.
pub struct Recovery {
    /// Per pixel, 0 where not solved: the recovered normal and albedo, and
    /// the renderer's normal.
    pub normal: Vec<[f32; 3]>,
    pub albedo: Vec<f32>,
    pub true_normal: Vec<[f32; 3]>,
    pub pixels: usize,
    pub mean_angle_deg: f64,
    pub p95_angle_deg: f64,
    pub mean_albedo: f64,
}

/// Renders the sphere under each light and solves per pixel; `with_floor`
/// adds the floor and lets paths bounce without limit.
pub fn photometric_stereo(size: u32, spp: u32, with_floor: bool) -> Recovery {
    let depth = if with_floor { None } else { Some(2) };
    let dirs = light_directions();
    // Rows of L: the unit vectors towards each light, scaled by E / π
    // (the Lambertian radiance is albedo · E/π · n·l).
    let l: Vec<Vec3> = dirs.iter().map(|d| -*d).collect();
    let images: Vec<Image> = dirs
        .iter()
        .enumerate()
        .map(|(k, d)| render(&scene(*d, with_floor), size, spp, k == 0, depth))
        .collect();
    let truth = images[0].aovs.normal.as_ref().expect("normal output");
    let mut ata = [[0.0f64; 3]; 3];
    for li in &l {
        for r in 0..3 {
            for c in 0..3 {
                ata[r][c] += (li[r] * li[c]) as f64;
            }
        }
    }
    let mut angles = Vec::new();
    let mut albedo_sum = 0.0;
    let mut normal = vec![[0.0f32; 3]; truth.len()];
    let mut albedo = vec![0.0f32; truth.len()];
    for (i, n_true) in truth.iter().enumerate() {
        let n_true = Vec3::from(*n_true);
        // Covered entirely, and lit by every light.
        if (n_true.length() - 1.0).abs() > 1e-3
            || l.iter().any(|li| n_true.normalize().dot(*li) < 0.05)
        {
            continue;
        }
        let mut atb = [0.0f64; 3];
        for (li, image) in l.iter().zip(&images) {
            let intensity = image.mean[i][0] as f64;
            for r in 0..3 {
                atb[r] += li[r] as f64 * intensity;
            }
        }
        let Some(g) = solve3(ata, atb) else { continue };
        let g = Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32);
        let cos = g.normalize().dot(n_true.normalize()).clamp(-1.0, 1.0);
        angles.push((cos as f64).acos().to_degrees());
        albedo_sum += (g.length() * PI / IRRADIANCE) as f64;
        normal[i] = g.normalize().into();
        albedo[i] = g.length() * PI / IRRADIANCE;
    }
    angles.sort_by(f64::total_cmp);
    let n = angles.len();
    Recovery {
        normal,
        albedo,
        true_normal: truth.clone(),
        pixels: n,
        mean_angle_deg: angles.iter().sum::<f64>() / n.max(1) as f64,
        p95_angle_deg: angles
            .get((n * 95 / 100).min(n.saturating_sub(1)))
            .copied()
            .unwrap_or(f64::NAN),
        mean_albedo: albedo_sum / n.max(1) as f64,
    }
}

#[allow(dead_code)]
fn main() {
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let size = args.first().copied().unwrap_or(96);
    let spp = args.get(1).copied().unwrap_or(16);
    let dir = std::env::args().nth(3).map(std::path::PathBuf::from);
    for (with_floor, what) in [
        (false, "sphere alone, direct light"),
        (true, "on a white floor, all bounces"),
    ] {
        let r = photometric_stereo(size, spp, with_floor);
        println!(
            "{what}: {size}x{size}, {spp} spp, {} lights, {} pixels solved: normal error mean \
             {:.3} deg, 95th percentile {:.3} deg; mean recovered albedo {:.4} (true {ALBEDO})",
            light_directions().len(),
            r.pixels,
            r.mean_angle_deg,
            r.p95_angle_deg,
            r.mean_albedo
        );
        if let (Some(dir), false) = (&dir, with_floor) {
            write_maps(dir, size, &r).expect("the maps are written");
        }
    }
}

/// The recovered normals and albedo beside the true normals, as PNGs.
#[allow(dead_code)]
fn write_maps(dir: &std::path::Path, size: u32, r: &Recovery) -> anyhow::Result<()> {
    use vkpt::image::{PngSettings, ToneMap, write_image};
    let png = PngSettings {
        exposure_ev: 0.0,
        tonemap: ToneMap::Clamp,
    };
    let shown = |n: &[f32; 3]| {
        if n.iter().all(|c| *c == 0.0) {
            [0.0; 3]
        } else {
            n.map(|c| c * 0.5 + 0.5)
        }
    };
    let image = |mean: Vec<[f32; 3]>| Image {
        mean,
        ..Image::new(size, size)
    };
    std::fs::create_dir_all(dir)?;
    write_image(
        &dir.join("stereo-true-normal.png"),
        &image(r.true_normal.iter().map(shown).collect()),
        &png,
    )?;
    write_image(
        &dir.join("stereo-normal.png"),
        &image(r.normal.iter().map(shown).collect()),
        &png,
    )?;
    write_image(
        &dir.join("stereo-albedo.png"),
        &image(r.albedo.iter().map(|a| [*a; 3]).collect()),
        &png,
    )?;
    Ok(())
}
