//! Twin of `shaders/common/camera.glsl`.

use super::rng::{RngKey, rng_float2};
use crate::constants::DIM_CAMERA_JITTER;
use crate::layout::RenderParams;
use glam::Vec3;

pub fn generate_camera_ray(p: &RenderParams, pixel: u32, key: RngKey) -> (Vec3, Vec3) {
    let u = rng_float2(key, DIM_CAMERA_JITTER);
    let x = (pixel % p.width) as f32 + u.x;
    let y = (pixel / p.width) as f32 + u.y;
    let sx = 2.0 * x / p.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * y / p.height as f32;
    let direction = (Vec3::from(p.cam_forward)
        + (sx * p.tan_half_fov * p.aspect) * Vec3::from(p.cam_right)
        + (sy * p.tan_half_fov) * Vec3::from(p.cam_up))
    .normalize();
    (Vec3::from(p.cam_position), direction)
}
