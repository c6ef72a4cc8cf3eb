//! White furnaces of the glTF layer lobes (a module of `furnace.rs`, whose
//! helpers it uses): the unit sphere of `scenes/white-furnace.gltf` with its
//! material replaced, each pixel against the material's directional albedo
//! computed here by f64 quadrature from the formulas, independently of the
//! renderers' code (their tables and fits are not used).
//!
//! - White sheen (Charlie lobe, Estevez & Kulla visibility) over a white
//!   Lambertian base (glTF dielectric with specularFactor 0), with
//!   Khronos' albedo scaling: never above 1.

use super::*;
use std::f64::consts::PI;
use vkpt::scene::MaterialKind;

/// f64 sheen model (KHR_materials_sheen; see `src/cpu/sheen.rs`).
mod sheen64 {
    use super::PI;

    fn l(x: f64, alpha: f64) -> f64 {
        let w = (1.0 - alpha).powi(2);
        let m = |a: f64, b: f64| a + (b - a) * w;
        m(21.5473, 25.3245) / (1.0 + m(3.82987, 3.32435) * x.powf(m(0.19823, 0.16801)))
            + m(-1.97760, -1.27393) * x
            + m(-4.32054, -4.85967)
    }

    fn lambda(c: f64, alpha: f64) -> f64 {
        if c < 0.5 {
            l(c, alpha).exp()
        } else {
            (2.0 * l(0.5, alpha) - l(1.0 - c, alpha)).exp()
        }
    }

    /// D V cos θi of a white sheen of perceptual roughness r (≥ 0.07).
    pub fn f_cos(r: f64, wo: [f64; 3], wi: [f64; 3]) -> f64 {
        let alpha = r.max(0.07).powi(2);
        let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
        let hz = h[2] / (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
        let d = (2.0 + 1.0 / alpha) * (1.0 - hz * hz).max(0.0).powf(0.5 / alpha) / (2.0 * PI);
        d / (4.0 * wo[2] * (1.0 + lambda(wo[2], alpha) + lambda(wi[2], alpha)))
    }
}

/// Midpoint quadrature over the upper hemisphere of g(wo, wi) for wo at
/// cos θo = mu, in (cos θi, φi) with φ over [0, π] doubled.
fn hemisphere(mu: f64, n: usize, g: &dyn Fn([f64; 3], [f64; 3]) -> f64) -> f64 {
    let mu = mu.max(1e-3);
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let mut sum = 0.0;
    for i in 0..n {
        let c = (i as f64 + 0.5) / n as f64;
        let s = (1.0 - c * c).sqrt();
        for j in 0..n / 2 {
            let phi = (j as f64 + 0.5) / (n / 2) as f64 * PI;
            sum += g(wo, [s * phi.cos(), s * phi.sin(), c]);
        }
    }
    sum * (1.0 / n as f64) * (2.0 * PI / (n / 2) as f64)
}

/// A function of cos θ tabulated at 257 points, linear between them.
fn tabulate(f: &dyn Fn(f64) -> f64) -> impl Fn(f64) -> f64 + use<> {
    const N: usize = 256;
    let t: Vec<f64> = (0..=N).map(|i| f(i as f64 / N as f64)).collect();
    move |mu: f64| {
        let x = mu.clamp(0.0, 1.0) * N as f64;
        let i = (x as usize).min(N - 1);
        let f = x - i as f64;
        t[i] * (1.0 - f) + t[i + 1] * f
    }
}

/// Per-pixel expected value of a sphere whose directional albedo is `a`
/// (cos θo), averaged over 8 x 8 points of the pixel on the analytic unit
/// sphere (as `rough_metal_expected`).
fn sphere_pixels(p: &RenderParams, a: impl Fn(f64) -> f64) -> impl Fn(u32, u32) -> f32 {
    let p = *p;
    move |x, y| {
        let o = Vec3::from(p.cam_position);
        let mut sum = 0.0;
        for j in 0..8 {
            for i in 0..8 {
                let px = x as f32 + (i as f32 + 0.5) / 8.0;
                let py = y as f32 + (j as f32 + 0.5) / 8.0;
                let sx = 2.0 * px / p.width as f32 - 1.0;
                let sy = 1.0 - 2.0 * py / p.height as f32;
                let d = (Vec3::from(p.cam_forward)
                    + sx * p.tan_half_fov * p.aspect * Vec3::from(p.cam_right)
                    + sy * p.tan_half_fov * Vec3::from(p.cam_up))
                .normalize();
                let b = o.dot(d);
                let t = -b - (b * b - o.dot(o) + 1.0).max(0.0).sqrt();
                let n = (o + t * d).normalize();
                sum += a((-d).dot(n) as f64);
            }
        }
        (sum / 64.0) as f32
    }
}

/// Directional albedo of white sheen (roughness r) over white Lambert:
/// ∫ [min(1 - Ē(μo), 1 - Ē(μi)) cos θi / π + f_sheen cos θi / max(1, E(μo))],
/// Ē = min(1, E), E the sheen lobe's own albedo (quadrature too).
fn sheen_over_white_albedo(r: f64) -> impl Fn(f64) -> f64 + use<> {
    let e = tabulate(&|mu| hemisphere(mu, 400, &|wo, wi| sheen64::f_cos(r, wo, wi)));
    tabulate(&move |mu| {
        let (eo, bar) = (e(mu), |x: f64| x.min(1.0));
        hemisphere(mu, 400, &|wo, wi| {
            let base = (1.0 - bar(eo)).min(1.0 - bar(e(wi[2]))) * wi[2] / PI;
            base + sheen64::f_cos(r, wo, wi) / eo.max(1.0)
        })
    })
}

/// The white furnace sphere with its material made by `f` from a white
/// glTF dielectric without specular (a white Lambertian base).
fn layered_furnace(
    test: &str,
    gpu: bool,
    f: &dyn Fn(&mut vkpt::scene::Material),
) -> Option<(Image, RenderParams)> {
    let (mut scene, _) = load("scenes/white-furnace.gltf");
    let m = &mut scene.materials[0];
    m.kind = MaterialKind::Gltf;
    m.base_color = Vec3::ONE;
    m.metallic = 0.0;
    m.roughness = 1.0;
    m.specular_factor = 0.0;
    f(m);
    let packed = vkpt::packed::PackedScene::new(&scene).expect("packs");
    let settings = settings();
    let params = file_params(&scene, &packed, &settings);
    let image = if gpu {
        let mut gpu = gpu_renderer(test)?;
        render_gpu(&mut gpu, &scene, &packed, &settings)
    } else {
        render_cpu(&scene, &packed, &settings)
    };
    Some((image, params))
}

fn sheen_furnace(test: &str, gpu: bool) {
    let r = 0.5;
    let Some((image, params)) = layered_furnace(test, gpu, &|m| {
        m.lobes.sheen_color = Vec3::ONE;
        m.lobes.sheen_roughness = r as f32;
    }) else {
        return;
    };
    let a = sheen_over_white_albedo(r);
    let top = (0..=100).map(|i| a(i as f64 / 100.0)).fold(0.0, f64::max);
    println!(
        "white sheen (roughness {r}) over white diffuse, albedo by quadrature: A(1) = {:.4}, A(0.5) = {:.4}, A(0.1) = {:.4}, max {top:.4}",
        a(1.0),
        a(0.5),
        a(0.1)
    );
    assert!(top <= 1.0 + 1e-9, "the model creates energy: {top}");
    check_with(test, &image, &params, &sphere_pixels(&params, a));
}

#[test]
fn sheen_furnace_cpu() {
    sheen_furnace("sheen_furnace_cpu", false);
}

#[test]
fn sheen_furnace_gpu() {
    sheen_furnace("sheen_furnace_gpu", true);
}
