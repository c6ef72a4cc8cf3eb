//! Writes `scenes/env/sky-with-sun.exr`, the bundled environment map: a
//! 256x128 equirectangular sky (vkpt's convention: row 0 straight up, the
//! centre column toward -Z) with a blue gradient above the horizon, a grey
//! ground below it and a small, very bright sun (2 degrees in radius,
//! radiance 5000) at 35 degrees elevation. Procedural and deterministic:
//!
//!     cargo run --release --example sky_with_sun

use std::f64::consts::PI;

const WIDTH: usize = 256;
const HEIGHT: usize = 128;
/// Sun direction: elevation 35 degrees, azimuth 30 degrees from -Z toward +X.
const SUN_ELEVATION: f64 = 35.0;
const SUN_AZIMUTH: f64 = 30.0;
const SUN_RADIUS_DEG: f64 = 2.0;
const SUN_RADIANCE: f64 = 5000.0;

fn direction(u: f64, v: f64) -> [f64; 3] {
    let (theta, phi) = (PI * v, 2.0 * PI * (u - 0.5));
    [
        theta.sin() * phi.sin(),
        theta.cos(),
        -theta.sin() * phi.cos(),
    ]
}

fn radiance(d: [f64; 3]) -> [f64; 3] {
    let (el, az) = (SUN_ELEVATION.to_radians(), SUN_AZIMUTH.to_radians());
    let sun = [el.cos() * az.sin(), el.sin(), -el.cos() * az.cos()];
    let cos_sun = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
    if cos_sun >= SUN_RADIUS_DEG.to_radians().cos() {
        return [SUN_RADIANCE, SUN_RADIANCE * 0.95, SUN_RADIANCE * 0.85];
    }
    if d[1] < 0.0 {
        return [0.12, 0.11, 0.10];
    }
    let t = d[1].powf(0.5);
    [0.9 - 0.6 * t, 1.0 - 0.5 * t, 1.2 - 0.1 * t]
}

fn main() {
    // 4x4 samples per texel so the sun's edge is antialiased.
    let n = 4;
    let mut texels = vec![[0.0f32; 3]; WIDTH * HEIGHT];
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let mut sum = [0.0f64; 3];
            for j in 0..n {
                for i in 0..n {
                    let u = (x as f64 + (i as f64 + 0.5) / n as f64) / WIDTH as f64;
                    let v = (y as f64 + (j as f64 + 0.5) / n as f64) / HEIGHT as f64;
                    let r = radiance(direction(u, v));
                    for c in 0..3 {
                        sum[c] += r[c] / (n * n) as f64;
                    }
                }
            }
            texels[y * WIDTH + x] = sum.map(|s| s as f32);
        }
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/env/sky-with-sun.exr");
    exr::prelude::write_rgb_file(&path, WIDTH, HEIGHT, |x, y| {
        let t = texels[y * WIDTH + x];
        (t[0], t[1], t[2])
    })
    .expect("writes the EXR");
    println!("wrote {}", path.display());
}
