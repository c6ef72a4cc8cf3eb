//! Twin of `shaders/common/camera.glsl`: the pixel filter, the aperture and
//! the primary ray, with the same functions in the same order.

use super::rng::{RngKey, rng_float, rng_float2};
use super::sampling::sample_concentric_disk;
use crate::constants::*;
use crate::packed::PackedScene;
use crate::packed::layout::RenderParams;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// erf by Abramowitz and Stegun 7.1.26 (absolute error below 1.5e-7). The
/// coefficients stay as published, as in the GLSL twin.
#[allow(clippy::excessive_precision)]
pub fn filter_erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.3275911 * x.abs());
    let poly = t
        * (0.254829592
            + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let y = 1.0 - poly * (-x * x).exp();
    if x < 0.0 { -y } else { y }
}

/// Normalized CDF at `x` in [-r, r] of one axis of the Gaussian or
/// Blackman-Harris profile (see [`filter_profile`]).
pub fn filter_cdf(kind: u32, r: f32, x: f32) -> f32 {
    if kind == FILTER_GAUSSIAN {
        let s = r / 3.0;
        let a = 1.0 / (s * 2.0f32.sqrt());
        let edge = (-4.5f32).exp();
        let g = s * (0.5 * PI).sqrt();
        let total = 2.0 * g * filter_erf(a * r) - 2.0 * r * edge;
        return (g * (filter_erf(a * x) + filter_erf(a * r)) - edge * (x + r)) / total;
    }
    let t = (x + r) / (2.0 * r);
    let w = 2.0 * PI * t;
    (BLACKMAN_HARRIS_A0 * t - BLACKMAN_HARRIS_A1 * w.sin() / (2.0 * PI)
        + BLACKMAN_HARRIS_A2 * (2.0 * w).sin() / (4.0 * PI)
        - BLACKMAN_HARRIS_A3 * (3.0 * w).sin() / (6.0 * PI))
        / BLACKMAN_HARRIS_A0
}

pub fn sample_filter_1d(kind: u32, r: f32, u: f32) -> f32 {
    if kind == FILTER_BOX {
        return (2.0 * u - 1.0) * r;
    }
    if kind == FILTER_TENT {
        return if u < 0.5 {
            r * ((2.0 * u).sqrt() - 1.0)
        } else {
            r * (1.0 - (2.0 - 2.0 * u).sqrt())
        };
    }
    let mut lo = -r;
    let mut hi = r;
    for _ in 0..FILTER_BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        if filter_cdf(kind, r, mid) < u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

pub fn sample_filter(kind: u32, r: f32, u: Vec2) -> Vec2 {
    Vec2::new(
        sample_filter_1d(kind, r, u.x),
        sample_filter_1d(kind, r, u.y),
    )
}

/// The unnormalized profile of one axis of each filter on [-r, r] (0
/// outside), written from the definitions rather than from the samplers
/// above, so tests can check the samplers against it.
pub fn filter_profile(kind: u32, r: f32, x: f64) -> f64 {
    let r = r as f64;
    if x.abs() > r {
        return 0.0;
    }
    match kind {
        FILTER_BOX => 1.0,
        FILTER_TENT => r - x.abs(),
        FILTER_GAUSSIAN => {
            let s = r / 3.0;
            (-x * x / (2.0 * s * s)).exp() - (-r * r / (2.0 * s * s)).exp()
        }
        _ => {
            let t = 2.0 * std::f64::consts::PI * (x + r) / (2.0 * r);
            BLACKMAN_HARRIS_A0 as f64 - BLACKMAN_HARRIS_A1 as f64 * t.cos()
                + BLACKMAN_HARRIS_A2 as f64 * (2.0 * t).cos()
                - BLACKMAN_HARRIS_A3 as f64 * (3.0 * t).cos()
        }
    }
}

pub fn sample_aperture(blades: u32, rotation: f32, u: Vec2, ublade: f32) -> Vec2 {
    sample_aperture_with(blades, u, ublade, |k| aperture_corner(blades, rotation, k))
}

/// Corner `k` of a polygonal aperture of `blades` blades: the cosine and
/// sine of its angle. A render may compute them once (`lanes` does): they
/// depend on the camera alone.
pub fn aperture_corner(blades: u32, rotation: f32, k: f32) -> Vec2 {
    let a = rotation + 2.0 * PI * k / blades as f32;
    Vec2::new(a.cos(), a.sin())
}

/// `sample_aperture` with the corners from `corner`.
#[inline(always)]
fn sample_aperture_with(blades: u32, u: Vec2, ublade: f32, corner: impl Fn(f32) -> Vec2) -> Vec2 {
    if blades < 3 {
        return sample_concentric_disk(u);
    }
    let n = blades as f32;
    let k = (ublade * n).floor().min(n - 1.0);
    let s = u.x.sqrt();
    (s * (1.0 - u.y)) * corner(k) + (s * u.y) * corner(k + 1.0)
}

/// Pixels of the film: the rendered region's.
pub fn film_pixel_count(p: &RenderParams) -> u32 {
    p.region_width * p.region_height
}

/// Which pixel and sample a path renders (see `path_pixel_sample`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathSample {
    /// Index into the film (the region, row-major).
    pub film_pixel: u32,
    /// Index into the full image: camera rays and random numbers use it.
    pub pixel: u32,
    /// Counted from the full render's first sample.
    pub sample_index: u32,
}

/// Path `k` of a chunk that starts at film pixel `pixel_start` of the
/// render's sample `sample_start`: paths walk the film row by row and wrap
/// to the next sample. Adding the render's `sample_offset` and the region's
/// corner makes a render of a sample range or a region trace exactly the
/// paths the full render traces for those samples. Every schedule maps its
/// paths through this function (the GLSL twin for the kernels).
pub fn path_pixel_sample(
    p: &RenderParams,
    pixel_start: u32,
    sample_start: u32,
    k: u32,
) -> PathSample {
    let pixels = film_pixel_count(p);
    let film_pixel = (pixel_start + k) % pixels;
    let sample_index = p.sample_offset + sample_start + (pixel_start + k) / pixels;
    let x = p.region_x + film_pixel % p.region_width;
    let y = p.region_y + film_pixel / p.region_width;
    PathSample {
        film_pixel,
        pixel: y * p.width + x,
        sample_index,
    }
}

pub fn generate_camera_ray(
    scene: &PackedScene,
    p: &RenderParams,
    pixel: u32,
    key: RngKey,
) -> (Vec3, Vec3) {
    generate_camera_ray_with(scene, p, pixel, key, |k| {
        aperture_corner(p.aperture_blades, p.blade_rotation, k)
    })
}

/// `generate_camera_ray` with the aperture's corners from `corner` (a
/// table of `aperture_corner`s gives the same rays).
#[inline(always)]
pub fn generate_camera_ray_with(
    scene: &PackedScene,
    p: &RenderParams,
    pixel: u32,
    key: RngKey,
    corner: impl Fn(f32) -> Vec2,
) -> (Vec3, Vec3) {
    let offset = sample_filter(
        p.filter_kind,
        p.filter_radius,
        rng_float2(key, DIM_CAMERA_JITTER),
    );
    let x = (pixel % p.width) as f32 + 0.5 + offset.x;
    let y = (pixel / p.width) as f32 + 0.5 + offset.y;
    let sx = 2.0 * x / p.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * y / p.height as f32;
    let [position, right, up, forward] = match &scene.motion {
        Some(m) if p.motion_camera_base != MOTION_CAMERA_STILL => {
            super::motion::moving_camera(m, p, super::motion::path_time(key))
        }
        _ => [
            Vec3::from(p.cam_position),
            Vec3::from(p.cam_right),
            Vec3::from(p.cam_up),
            Vec3::from(p.cam_forward),
        ],
    };
    let film = (sx * p.tan_half_fov * p.aspect) * right + (sy * p.tan_half_fov) * up;
    if p.projection == PROJECTION_ORTHOGRAPHIC {
        return (position + film, forward);
    }
    let pinhole = forward + film;
    if p.lens_radius <= 0.0 {
        return (position, pinhole.normalize());
    }
    let lens = p.lens_radius
        * sample_aperture_with(
            p.aperture_blades,
            rng_float2(key, DIM_CAMERA_LENS),
            rng_float(key, DIM_CAMERA_BLADE),
            corner,
        );
    let lens_offset = lens.x * right + lens.y * up;
    (
        position + lens_offset,
        (p.focus_distance * pinhole - lens_offset).normalize(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::common::rng::rng_path_key;

    /// Chi-square statistic of `samples` offsets in `bins` equal bins over
    /// [-r, r] against the profile's integral over each bin (Simpson's rule
    /// on the definition, independent of the sampler's CDF).
    fn chi_square(kind: u32, r: f32, samples: &[f32], bins: usize) -> f64 {
        let mut counts = vec![0u64; bins];
        for &x in samples {
            assert!(x.abs() <= r, "offset {x} outside radius {r}");
            let b = (((x + r) / (2.0 * r)) * bins as f32).floor() as usize;
            counts[b.min(bins - 1)] += 1;
        }
        let integral = |a: f64, b: f64| {
            let steps = 64;
            let h = (b - a) / steps as f64;
            (0..=steps)
                .map(|i| {
                    let w = if i == 0 || i == steps {
                        1.0
                    } else if i % 2 == 1 {
                        4.0
                    } else {
                        2.0
                    };
                    w * filter_profile(kind, r, a + i as f64 * h)
                })
                .sum::<f64>()
                * h
                / 3.0
        };
        let edges: Vec<f64> = (0..=bins)
            .map(|i| -r as f64 + 2.0 * r as f64 * i as f64 / bins as f64)
            .collect();
        let masses: Vec<f64> = edges.windows(2).map(|w| integral(w[0], w[1])).collect();
        let total: f64 = masses.iter().sum();
        let n = samples.len() as f64;
        counts
            .iter()
            .zip(&masses)
            .map(|(&c, &m)| {
                let e = n * m / total;
                (c as f64 - e).powi(2) / e
            })
            .sum()
    }

    /// Offsets drawn with the renderer's own random numbers (dimension
    /// `DIM_CAMERA_JITTER` of many path keys).
    fn offsets(kind: u32, r: f32, n: u32) -> Vec<f32> {
        (0..n)
            .flat_map(|i| {
                let o = sample_filter(
                    kind,
                    r,
                    rng_float2(rng_path_key(i, 0, 11), DIM_CAMERA_JITTER),
                );
                [o.x, o.y]
            })
            .collect()
    }

    /// 39 degrees of freedom: 72.05 is the 0.999 quantile of chi-square(39).
    const CHI2_39_999: f64 = 72.05;

    #[test]
    fn every_filter_sampler_follows_its_profile() {
        for (kind, r) in [
            (FILTER_BOX, 0.5),
            (FILTER_TENT, 1.0),
            (FILTER_GAUSSIAN, 1.5),
            (FILTER_BLACKMAN_HARRIS, 2.0),
            (FILTER_GAUSSIAN, 0.7),
        ] {
            let chi2 = chi_square(kind, r, &offsets(kind, r, 100_000), 40);
            println!("filter {kind} radius {r}: chi2 = {chi2:.1} (40 bins)");
            assert!(
                chi2 < CHI2_39_999,
                "filter {kind} radius {r}: chi2 = {chi2}"
            );
        }
    }

    /// The chi-square test has the power to tell the filters apart: tent
    /// samples are rejected against the Gaussian profile and Gaussian ones
    /// against Blackman-Harris at the same radius.
    #[test]
    fn filter_chi_square_tells_filters_apart() {
        let chi2 = chi_square(
            FILTER_GAUSSIAN,
            1.5,
            &offsets(FILTER_TENT, 1.5, 100_000),
            40,
        );
        assert!(chi2 > CHI2_39_999, "tent passed as Gaussian: {chi2}");
        let chi2 = chi_square(
            FILTER_BLACKMAN_HARRIS,
            2.0,
            &offsets(FILTER_GAUSSIAN, 2.0, 100_000),
            40,
        );
        assert!(
            chi2 > CHI2_39_999,
            "Gaussian passed as Blackman-Harris: {chi2}"
        );
    }

    #[test]
    fn filter_erf_matches_known_values() {
        for (x, erf) in [
            (0.0, 0.0),
            (0.5, 0.5204999),
            (1.0, 0.8427008),
            (2.0, 0.9953223),
        ] {
            assert!((filter_erf(x) - erf).abs() < 3e-7, "erf({x})");
            assert!((filter_erf(-x) + erf).abs() < 3e-7, "erf(-{x})");
        }
    }

    /// Uniform over the polygon: equal counts in the N triangles, every
    /// point inside, and the fraction inside the inscribed circle equal to
    /// that circle's share of the polygon's area.
    #[test]
    fn aperture_samples_fill_the_polygon_uniformly() {
        for blades in [3u32, 5, 6] {
            let n = blades as f32;
            let rotation = 0.3;
            let apothem = (PI / n).cos();
            let polygon_area = 0.5 * n * (2.0 * PI / n).sin();
            let inscribed_share = PI * apothem * apothem / polygon_area;
            let count = 200_000;
            let mut inside_circle = 0;
            for i in 0..count {
                let key = rng_path_key(i, 3, 5);
                let p = sample_aperture(
                    blades,
                    rotation,
                    rng_float2(key, DIM_CAMERA_LENS),
                    rng_float(key, DIM_CAMERA_BLADE),
                );
                // Inside every edge's half-plane: distance to the edge
                // normal's direction at most the apothem.
                for k in 0..blades {
                    let mid = rotation + PI * (2 * k + 1) as f32 / n;
                    assert!(p.dot(Vec2::new(mid.cos(), mid.sin())) <= apothem + 1e-5);
                }
                if p.length() < apothem {
                    inside_circle += 1;
                }
            }
            let share = inside_circle as f64 / count as f64;
            let sd =
                (inscribed_share as f64 * (1.0 - inscribed_share as f64) / count as f64).sqrt();
            assert!(
                (share - inscribed_share as f64).abs() < 4.0 * sd,
                "{blades} blades: {share} inside the inscribed circle, expected {inscribed_share}"
            );
        }
    }
}
