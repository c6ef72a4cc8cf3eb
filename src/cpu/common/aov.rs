//! Twin of `shaders/common/aov.glsl`: the auxiliary outputs of one path
//! sample, for denoisers and compositing. The depth of the camera ray's
//! hit, and the albedo and shading normal of the first surface that is not
//! a mirror or smooth glass (through delta bounces the path is followed to
//! the first rough surface, as Open Image Denoise asks). A path that escapes
//! on that chain sees the environment: albedo its radiance (at most 1),
//! normal 0. Depth is the distance along the camera ray, +inf when it meets
//! nothing.

use super::bvh::{Hit, NO_HIT, OVERFLOW_HIT};
use super::integrator::ShadeResult;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AovSample {
    pub albedo: Vec3,
    pub depth: f32,
    pub normal: Vec3,
    /// No surface has ended the delta chain yet.
    pub open: bool,
}

impl Default for AovSample {
    fn default() -> Self {
        AovSample {
            albedo: Vec3::ZERO,
            depth: f32::INFINITY,
            normal: Vec3::ZERO,
            open: true,
        }
    }
}

/// Updates `a` after shading `hit` at `bounce` (`r`: shade_path's result).
/// Returns whether `a` changed. At bounce 0 it starts over.
pub fn aov_after_bounce(a: &mut AovSample, bounce: u32, hit: &Hit, r: &ShadeResult) -> bool {
    let mut changed = false;
    if bounce == 0 {
        let missed = hit.triangle == NO_HIT || hit.triangle == OVERFLOW_HIT;
        *a = AovSample {
            depth: if missed { f32::INFINITY } else { hit.t },
            ..AovSample::default()
        };
        changed = true;
    }
    if a.open && r.aov_event {
        a.albedo = r.aov_albedo;
        a.normal = r.aov_normal;
        a.open = false;
        changed = true;
    }
    changed
}
