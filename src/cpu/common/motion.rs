//! Motion over the shutter (twin: shaders/common/motion.glsl; the
//! representation: `scene::motion`, the buffer: `packed::motion`). A path's
//! time is a fraction of the shutter (`path_time`); the camera and the triangles are where they are then,
//! linear between the two time steps around it. The kernels' `motion_on()`
//! is `scene.motion.is_some()` here (the CPU has no specialization).

use super::rng::{RngKey, rng_float, sobol_float2_third};
use crate::constants::{DIM_CAMERA_JITTER, DIM_CAMERA_TIME, SAMPLER_SOBOL};
use crate::packed::PackedScene;
use crate::packed::layout::RenderParams;
use crate::packed::motion::PackedMotion;
use crate::scene::motion::motion_lerp;
use glam::{Vec3, Vec4};

/// The path's moment in the shutter, in [0, 1). Under Sobol, the third
/// coordinate of the pixel jitter's point: a moving edge is an integrand of
/// position and time together, which then are stratified jointly.
#[inline(never)] // kept out of still scenes' hot code
pub fn path_time(key: RngKey) -> f32 {
    if key.kind == SAMPLER_SOBOL {
        return sobol_float2_third(key, DIM_CAMERA_JITTER);
    }
    rng_float(key, DIM_CAMERA_TIME)
}

/// The path's time when the scene moves, else 0 (unused).
pub fn time_of_path(scene: &PackedScene, key: RngKey) -> f32 {
    if scene.motion.is_some() {
        path_time(key)
    } else {
        0.0
    }
}

/// The time steps around `time`: step k and k + 1, at weight w of the way.
pub fn motion_segment(m: &PackedMotion, time: f32) -> (u32, f32) {
    let f = time * (m.steps - 1) as f32;
    let step = (f as u32).min(m.steps - 2);
    (step, f - step as f32)
}

fn texel(m: &PackedMotion, i: u32) -> Vec3 {
    let t = m.texels[i as usize];
    Vec3::new(
        f32::from_bits(t[0]),
        f32::from_bits(t[1]),
        f32::from_bits(t[2]),
    )
}

fn texel4(m: &PackedMotion, i: u32) -> Vec4 {
    Vec4::from_array(m.texels[i as usize].map(f32::from_bits))
}

fn lerp4(a: Vec4, b: Vec4, w: f32) -> Vec4 {
    a + (b - a) * w
}

/// Three consecutive records (vertices, normals) of the section at
/// `section`, at `time`.
fn triangle_record(
    scene: &PackedScene,
    m: &PackedMotion,
    section: u32,
    tri: u32,
    time: f32,
) -> [Vec3; 3] {
    let (step, w) = motion_segment(m, time);
    let t = scene.tri_verts.len() as u32;
    let i = section + 3 * (step * t + tri);
    let j = i + 3 * t;
    [0, 1, 2].map(|k| motion_lerp(texel(m, i + k), texel(m, j + k), w))
}

/// The triangle's vertices at `time` (the scene must move).
#[inline(never)] // kept out of still scenes' hot code
pub fn moving_triangle(scene: &PackedScene, m: &PackedMotion, tri: u32, time: f32) -> [Vec3; 3] {
    triangle_record(scene, m, m.vertex_base, tri, time)
}

/// Its vertex normals at `time`.
#[inline(never)] // kept out of still scenes' hot code
pub fn moving_triangle_normals(
    scene: &PackedScene,
    m: &PackedMotion,
    tri: u32,
    time: f32,
) -> [Vec3; 3] {
    let section = m.vertex_base + 3 * m.steps * scene.tri_verts.len() as u32;
    triangle_record(scene, m, section, tri, time)
}

/// Its vertex tangents (xyz, bitangent sign w) at `time`: textured scenes.
#[inline(never)] // kept out of still scenes' hot code
pub fn moving_triangle_tangents(
    scene: &PackedScene,
    m: &PackedMotion,
    tri: u32,
    time: f32,
) -> [Vec4; 3] {
    let (step, w) = motion_segment(m, time);
    let t = scene.tri_verts.len() as u32;
    let i = m.vertex_base + 6 * m.steps * t + 3 * (step * t + tri);
    let j = i + 3 * t;
    [0, 1, 2].map(|k| lerp4(texel4(m, i + k), texel4(m, j + k), w))
}

/// The render camera's frame at `time`: position, right, up, forward.
#[inline(never)] // kept out of still scenes' hot code
pub fn moving_camera(m: &PackedMotion, p: &RenderParams, time: f32) -> [Vec3; 4] {
    let (step, w) = motion_segment(m, time);
    let i = p.motion_camera_base + 4 * step;
    let position = motion_lerp(texel(m, i), texel(m, i + 4), w);
    let axis = |k: u32| motion_lerp(texel(m, i + k), texel(m, i + 4 + k), w).normalize();
    [position, axis(1), axis(2), axis(3)]
}
