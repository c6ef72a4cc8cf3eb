//! The kernels' motion buffer (`motion_texels`, read by
//! `shaders/common/motion.glsl` and `src/cpu/common/motion.rs`): the scene's time
//! steps over the shutter (`scene::motion`), as RGBA32UI texels of f32 bits.
//!
//! - Camera frames: camera c, step s at texel `4 (c S + s)`: position,
//!   right, up, forward (xyz), as `render_params` derives them.
//! - Vertex positions from `motion_vertex_base`: triangle i (BVH order),
//!   step s, vertex j at `3 (s T + i) + j`; then the vertex normals, the
//!   same way, from `motion_vertex_base + 3 S T`; then, in textured scenes,
//!   the tangents (xyzw) from `motion_vertex_base + 6 S T`.

use crate::scene::motion::SceneMotion;
use crate::scene::{Camera, Scene};
use glam::Vec3;

pub struct PackedMotion {
    pub texels: Vec<[u32; 4]>,
    /// Time steps (at least 2).
    pub steps: u32,
    /// Texel where the vertex positions start.
    pub vertex_base: u32,
}

impl PackedMotion {
    /// Whether camera `c`'s frame differs between the time steps.
    pub fn camera_moves(&self, c: usize) -> bool {
        let steps = self.steps as usize;
        let frames = &self.texels[4 * steps * c..4 * steps * (c + 1)];
        frames.chunks(4).any(|f| f != &frames[..4])
    }
}

fn texel(v: Vec3) -> [u32; 4] {
    [v.x.to_bits(), v.y.to_bits(), v.z.to_bits(), 0]
}

/// The camera's frame as the kernels use it: position, right, up, forward.
pub fn camera_frame(camera: &Camera) -> [Vec3; 4] {
    let right = camera.right();
    let up = right.cross(camera.forward).normalize();
    [camera.position, right, up, camera.forward]
}

/// Packs `motion`, with triangles in BVH `order`.
pub fn pack_motion(scene: &Scene, motion: &SceneMotion, order: &[u32]) -> PackedMotion {
    let steps = &motion.steps;
    let mut texels = Vec::new();
    for c in 0..scene.cameras.len() {
        for step in steps {
            texels.extend(camera_frame(&step.cameras[c]).map(texel));
        }
    }
    let vertex_base = texels.len() as u32;
    for step in steps {
        for &i in order {
            texels.extend(step.triangles[i as usize].positions.map(texel));
        }
    }
    for step in steps {
        for &i in order {
            texels.extend(step.triangles[i as usize].normals.map(texel));
        }
    }
    if !scene.texcoords.is_empty() {
        for step in steps {
            for &i in order {
                let t = &step.texcoords[i as usize].tangents;
                texels.extend(t.map(|v| v.to_array().map(f32::to_bits)));
            }
        }
    }
    PackedMotion {
        texels,
        steps: steps.len() as u32,
        vertex_base,
    }
}
