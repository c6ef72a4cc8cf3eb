//! Host side of light sampling: the analytic lights as the kernels read them
//! (`layout::Light`), the environment map's sampling distribution, and how
//! light sampling splits its choice between the environment, the emissive
//! triangles and the analytic lights. `packed.rs` calls `pack_lights`; both
//! back ends then read the same arrays.
//!
//! Selection is proportional to an estimate of each light's power (as
//! pbrt-v4's power light sampler does): pi L A for a one-sided emitting
//! triangle of radiance L and area A (twice for double-sided), 4 pi^2 r^2 L
//! for a sphere, 4 pi I for a point light, 2 pi (1 - (cos_inner + cos_outer)
//! / 2) I for a spot, and pi R^2 E for light from infinity: a directional or
//! sun light of irradiance E, or an environment with E = the integral of its
//! luminance over the sphere, where R is the radius of the scene's bounding
//! sphere. Power is measured as luminance (Rec. 709 weights).

use crate::constants::*;
use crate::packed::layout::{Light, LightParams};
use crate::scene::{EnvironmentMap, LightKind, Scene};
use glam::Vec3;
use std::f64::consts::PI;

pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// What `pack_lights` produces for `PackedScene`.
pub struct PackedLights {
    pub light_params: LightParams,
    /// Spheres first, then suns, then the delta lights.
    pub lights: Vec<Light>,
    /// Probability that light sampling picks the environment.
    pub env_select_prob: f32,
    /// Marginal cdf (height + 1), then per-row conditional cdfs (width + 1
    /// each); one 0 when there is no map (a buffer may not be empty).
    pub env_cdf: Vec<f32>,
    /// Radiance texels (rgb, 0), row-major; one zero texel when there is no map.
    pub env_radiance: Vec<[f32; 4]>,
    /// Each entry of `lights`' power (luminance), for the light BVH.
    pub powers: Vec<f64>,
}

/// Sampling distribution of an equirectangular map: each texel is weighted
/// by its luminance times sin(theta) at the texel row's centre (the solid
/// angle it covers), plus 1e-3 of the mean weight so that every texel with
/// radiance keeps a probability f32 can represent. Returns the cdfs laid out
/// as `env_cdf` and the integral of luminance over the sphere (for power).
pub fn env_distribution(map: &EnvironmentMap) -> (Vec<f32>, f64) {
    let (w, h) = (map.width as usize, map.height as usize);
    let mut f = vec![0.0f64; w * h];
    let mut integral = 0.0f64;
    let texel_solid_angle = |y: usize| {
        let sin_theta = (PI * (y as f64 + 0.5) / h as f64).sin();
        (2.0 * PI / w as f64) * (PI / h as f64) * sin_theta
    };
    for y in 0..h {
        let sin_theta = (PI * (y as f64 + 0.5) / h as f64).sin();
        for x in 0..w {
            let lum = luminance(map.texels[y * w + x]) as f64;
            f[y * w + x] = lum * sin_theta;
            integral += lum * texel_solid_angle(y);
        }
    }
    let mean = f.iter().sum::<f64>() / (w * h) as f64;
    let floor = 1e-3 * mean;
    let mut cdf = vec![0.0f32; (h + 1) + h * (w + 1)];
    let mut row_sums = vec![0.0f64; h];
    for y in 0..h {
        let row = &f[y * w..(y + 1) * w];
        let total: f64 = row.iter().map(|v| v + floor).sum();
        row_sums[y] = total;
        let base = (h + 1) + y * (w + 1);
        let mut running = 0.0f64;
        for x in 0..w {
            running += row[x] + floor;
            cdf[base + x + 1] = if total > 0.0 {
                (running / total) as f32
            } else {
                (x + 1) as f32 / w as f32
            };
        }
        cdf[base + w] = 1.0;
    }
    let total: f64 = row_sums.iter().sum();
    let mut running = 0.0f64;
    for y in 0..h {
        running += row_sums[y];
        cdf[y + 1] = if total > 0.0 {
            (running / total) as f32
        } else {
            (y + 1) as f32 / h as f32
        };
    }
    cdf[h] = 1.0;
    (cdf, integral)
}

/// Packs the analytic lights and the environment and splits light
/// selection by power. `triangle_power` is the emissive triangles' total
/// (already computed by `packed.rs` for their own cdf, without the pi).
///
/// With `tree` (the light BVH, `packed::light_bvh`), the tree takes the
/// share of the emissive triangles and of the spheres, point and spot
/// lights together (`tri_select_prob`), and the analytic lights' cdf
/// covers the lights at infinity alone (the others get pmf 0).
pub fn pack_lights(scene: &Scene, triangle_power: f64, tree: bool) -> PackedLights {
    let radius = scene
        .bounds()
        .map(|(lo, hi)| 0.5 * (hi - lo).length() as f64)
        .filter(|r| *r > 0.0 && r.is_finite())
        .unwrap_or(1.0);
    let infinite_area = PI * radius * radius;

    // Spheres, then suns, then the rest: ray tests loop over the first two.
    let order = |k: &LightKind| match k {
        LightKind::Sphere { .. } => 0,
        LightKind::Sun { .. } => 1,
        _ => 2,
    };
    let mut sorted: Vec<&crate::scene::Light> = scene.lights.iter().collect();
    sorted.sort_by_key(|l| order(&l.kind));

    let mut lights = Vec::with_capacity(sorted.len());
    let mut powers = Vec::with_capacity(sorted.len());
    let (mut num_spheres, mut num_suns) = (0u32, 0u32);
    for l in sorted {
        let lum = luminance(l.color) as f64;
        let mut g = Light {
            position: l.position.into(),
            direction: l.direction.into(),
            range: l.range.unwrap_or(0.0),
            emission: l.color.into(),
            ..Default::default()
        };
        let power = match l.kind {
            LightKind::Point => {
                g.kind = LIGHT_POINT;
                4.0 * PI * lum
            }
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => {
                g.kind = LIGHT_SPOT;
                let (ci, co) = ((inner_cone as f64).cos(), (outer_cone as f64).cos());
                // KHR_lights_punctual: scale = 1 / max(0.001, cos_inner - cos_outer).
                let scale = 1.0 / (ci - co).max(0.001);
                g.spot_scale = scale as f32;
                g.spot_offset = (-co * scale) as f32;
                2.0 * PI * (1.0 - 0.5 * (ci + co)) * lum
            }
            LightKind::Directional => {
                g.kind = LIGHT_DIRECTIONAL;
                infinite_area * lum
            }
            LightKind::Sphere { radius: r } => {
                g.kind = LIGHT_SPHERE;
                num_spheres += 1;
                g.radius = r;
                // Radiance I / (pi r^2): the sphere's intensity is I.
                let r = r as f64;
                g.emission = (l.color / (PI * r * r) as f32).into();
                4.0 * PI * lum
            }
            LightKind::Sun { angular_diameter } => {
                g.kind = LIGHT_SUN;
                num_suns += 1;
                let half = 0.5 * angular_diameter as f64;
                let s = half.sin();
                g.cos_max = half.cos() as f32;
                g.one_minus_cos_max = (s * s / (1.0 + half.cos())) as f32;
                // Radiance E / (pi sin^2): irradiance E facing the disk.
                g.emission = (l.color / (PI * s * s) as f32).into();
                infinite_area * lum
            }
        };
        lights.push(g);
        powers.push(power.max(0.0));
    }

    let env = scene.environment.unwrap_or(Vec3::ZERO);
    let (env_cdf, env_radiance, env_integral) = match &scene.environment_map {
        Some(map) => {
            let (cdf, integral) = env_distribution(map);
            let texels = map.texels.iter().map(|t| [t.x, t.y, t.z, 0.0]).collect();
            (cdf, texels, integral * luminance(env) as f64)
        }
        None => (vec![0.0], vec![[0.0; 4]], 4.0 * PI * luminance(env) as f64),
    };
    let env_power = if env.max_element() > 0.0 {
        infinite_area * env_integral
    } else {
        0.0
    };
    let in_tree = |g: &Light| tree && matches!(g.kind, LIGHT_SPHERE | LIGHT_POINT | LIGHT_SPOT);
    let tree_power: f64 = lights
        .iter()
        .zip(&powers)
        .filter(|(g, _)| in_tree(g))
        .map(|(_, p)| p)
        .sum();
    // What the analytic lights' own cdf picks among.
    let own: Vec<f64> = lights
        .iter()
        .zip(&powers)
        .map(|(g, &p)| if in_tree(g) { 0.0 } else { p })
        .collect();
    let tri_power = PI * triangle_power + tree_power;
    let light_power: f64 = own.iter().sum();
    let total = env_power + tri_power + light_power;
    let (env_select_prob, tri_select_prob) = if total > 0.0 {
        let pe = (env_power / total) as f32;
        let pt = if light_power > 0.0 {
            (tri_power / total) as f32
        } else {
            1.0 - pe
        };
        (pe, pt)
    } else {
        (0.0, 0.0)
    };
    let lights_prob = 1.0 - env_select_prob as f64 - tri_select_prob as f64;
    let mut running = 0.0f64;
    let n = lights.len();
    // The last light the cdf can pick ends it at exactly 1.
    let last = own
        .iter()
        .rposition(|&p| p > 0.0)
        .unwrap_or(n.saturating_sub(1));
    for (k, (g, p)) in lights.iter_mut().zip(&own).enumerate() {
        running += p;
        g.pmf = if light_power > 0.0 {
            (lights_prob * p / light_power) as f32
        } else {
            0.0
        };
        g.cdf = if k >= last {
            1.0
        } else if light_power > 0.0 {
            (running / light_power) as f32
        } else {
            0.0
        };
    }
    let rotation = (scene.environment_rotation as f64).to_radians();
    let (width, height) = scene
        .environment_map
        .as_ref()
        .map_or((0, 0), |m| (m.width, m.height));
    PackedLights {
        light_params: LightParams {
            num_lights: lights.len() as u32,
            tri_select_prob,
            env_width: width,
            env_height: height,
            env_rot_cos: rotation.cos() as f32,
            env_rot_sin: rotation.sin() as f32,
            env_hidden: scene.environment_hidden as u32,
            env_sampling: ENV_SAMPLE_IMPORTANCE,
            num_spheres,
            num_suns,
            ..Default::default()
        },
        lights: if n == 0 {
            vec![Light::default()]
        } else {
            lights
        },
        env_select_prob,
        env_cdf,
        env_radiance,
        powers,
    }
}
