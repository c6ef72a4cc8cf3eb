//! Motion over the shutter as the kernels see it: the scene posed at a few
//! moments of the shutter (time steps, equally spaced, the first at its
//! opening and the last at its closing), and every path at its own time
//! in between (`shaders/common/motion.glsl`). Between two steps a vertex,
//! a normal, a tangent and the camera's position move linearly, and the
//! camera's axes turn by normalized linear interpolation.
//!
//! Why this representation: it serves everything the host can pose (rigid
//! nodes, cameras, skins, morph targets) with one mechanism, the BVH stays
//! one tree over boxes that enclose each triangle at every step (a vertex
//! between two steps stays in the hull of both), and the kernels change
//! only where they read a vertex or the camera. Curved motion (a turning
//! node, a bending skin) is followed by more steps: [`pose_over_shutter`]
//! doubles them until linear interpolation stays within
//! [`MOTION_TOLERANCE`] of the true pose at every segment's quarter points
//! (motion that returns to the same pose at all of them escapes this), and
//! motion that does not get there within [`MAX_MOTION_SEGMENTS`] (a STEP
//! key's jump) is left to the host's time steps, which pose it exactly.
//! The price is memory: vertex data once per step (the later poses are
//! kept only as what moves: triangles, texture coordinates, cameras).
//!
//! Lights that move, or a camera whose lens or field of view changes, are
//! not interpolated: for those scenes the caller falls back to the host's
//! time steps (`render::motion`), and the reason says why.

use super::{Camera, Scene, Texcoords, Triangle};
use crate::constants::TEXEL_BUDGET_BYTES;
use glam::{DVec3, Vec3};

/// The most segments (steps − 1) the shutter is split into.
pub const MAX_MOTION_SEGMENTS: usize = 32;
/// How far linear interpolation between steps may stray from the true pose
/// inside a segment: as a fraction of the scene's size for points,
/// in radians for the camera's axes.
pub const MOTION_TOLERANCE: f32 = 1e-3;

/// The scene at every time step of the shutter; step 0 is the scene's own
/// pose (`Scene::triangles`, `Scene::cameras`).
#[derive(Clone, Debug, Default)]
pub struct SceneMotion {
    /// Step k is at `open + duration * k / (steps - 1)` of the shutter.
    pub steps: Vec<MotionStep>,
    /// The largest deviation from linear found with these steps (as
    /// [`MOTION_TOLERANCE`] measures it).
    pub deviation: f32,
}

/// What moves, posed at one time step.
#[derive(Clone, Debug, Default)]
pub struct MotionStep {
    pub triangles: Vec<Triangle>,
    /// Texture coordinates do not move; tangents do.
    pub texcoords: Vec<Texcoords>,
    pub cameras: Vec<Camera>,
}

/// Linear interpolation as the kernels compute it (`motion_lerp`).
pub fn motion_lerp(a: Vec3, b: Vec3, w: f32) -> Vec3 {
    a + (b - a) * w
}

/// Why the kernels cannot interpolate from `a` to `b` (the same file posed
/// at two times), if they cannot.
fn not_interpolable(a: &Scene, b: &Scene) -> Option<String> {
    if a.triangles.len() != b.triangles.len()
        || a.texcoords.len() != b.texcoords.len()
        || a.triangles
            .iter()
            .zip(&b.triangles)
            .any(|(s, t)| s.material != t.material)
    {
        return Some("the triangles change while the shutter is open".into());
    }
    if a.lights != b.lights {
        return Some("lights move while the shutter is open".into());
    }
    let same_lens = a.cameras.len() == b.cameras.len()
        && a.cameras.iter().zip(&b.cameras).all(|(c, d)| {
            let moved = Camera {
                position: c.position,
                forward: c.forward,
                up: c.up,
                ..d.clone()
            };
            moved == *c
        });
    if !same_lens {
        return Some("a camera's lens or field of view changes while the shutter is open".into());
    }
    None
}

/// How far `mid` is from `w` of the way from `a` to `b` (as the kernels
/// interpolate), relative to `size` for points and in radians for camera
/// axes.
fn deviation_from_linear(
    a: &MotionStep,
    mid: &MotionStep,
    b: &MotionStep,
    w: f32,
    size: f32,
) -> f32 {
    let mut points = 0.0f32;
    for ((s, m), t) in a.triangles.iter().zip(&mid.triangles).zip(&b.triangles) {
        for j in 0..3 {
            let guess = motion_lerp(s.positions[j], t.positions[j], w);
            points = points.max((guess - m.positions[j]).abs().max_element());
        }
    }
    let mut angle = 0.0f32;
    for ((c, m), d) in a.cameras.iter().zip(&mid.cameras).zip(&b.cameras) {
        let guess = motion_lerp(c.position, d.position, w);
        points = points.max((guess - m.position).abs().max_element());
        for (x, y, z) in [(c.forward, m.forward, d.forward), (c.up, m.up, d.up)] {
            let turned = motion_lerp(x, z, w).normalize_or_zero();
            angle = angle.max(turned.angle_between(y));
        }
    }
    (points / size).max(angle)
}

/// The largest extent of the triangles' bounds (1 for an empty scene).
fn scene_size(scene: &Scene) -> f32 {
    let mut lo = Vec3::splat(f32::MAX);
    let mut hi = Vec3::splat(f32::MIN);
    for t in &scene.triangles {
        for v in t.positions {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let size = (hi - lo).max_element();
    if size.is_finite() && size > 0.0 {
        size
    } else {
        1.0
    }
}

/// Texels (16 bytes) the kernels' motion buffer takes for `steps` steps.
fn motion_texels(scene: &Scene, steps: usize) -> usize {
    let per_triangle = if scene.texcoords.is_empty() { 6 } else { 9 };
    steps * (4 * scene.cameras.len() + per_triangle * scene.triangles.len())
}

/// What of a pose moves (a clone of the scene's own parts).
fn step_of(scene: &Scene) -> MotionStep {
    MotionStep {
        triangles: scene.triangles.clone(),
        texcoords: scene.texcoords.clone(),
        cameras: scene.cameras.clone(),
    }
}

/// The scene `pose` gives at `open`, with its motion over the shutter for
/// the kernels; `Err(reason)` when the kernels cannot follow it (the
/// caller then renders with host time steps). `pose(time, origin)` poses
/// the file at `time` with positions measured from `origin` (`None` for
/// the first pose: the file's own choice, which every later pose shares).
/// Only what moves is kept of the later poses.
pub fn pose_over_shutter(
    pose: &mut dyn FnMut(f64, Option<DVec3>) -> anyhow::Result<Scene>,
    open: f64,
    duration: f64,
) -> anyhow::Result<Result<Scene, String>> {
    let at = |k: usize, segments: usize| open + duration * k as f64 / segments as f64;
    let first = pose(open, None)?;
    let origin = Some(first.world_origin);
    // A camera vkpt framed on the scene holds still where the shutter opens
    // (framing every step anew would move it with the animation).
    let held: Vec<Option<Camera>> = first
        .cameras
        .iter()
        .map(|c| c.framed_automatically.then(|| c.clone()))
        .collect();
    let mut step_at = |time: f64| -> anyhow::Result<Result<MotionStep, String>> {
        let mut scene = pose(time, origin)?;
        for (c, h) in scene.cameras.iter_mut().zip(&held) {
            if let Some(h) = h {
                *c = h.clone();
            }
        }
        if let Some(reason) = not_interpolable(&first, &scene) {
            return Ok(Err(reason));
        }
        Ok(Ok(MotionStep {
            triangles: scene.triangles,
            texcoords: scene.texcoords,
            cameras: scene.cameras,
        }))
    };
    let last = match step_at(open + duration)? {
        Ok(step) => step,
        Err(reason) => return Ok(Err(reason)),
    };
    let mut steps = vec![step_of(&first), last];
    let size = scene_size(&first);
    let budget = TEXEL_BUDGET_BYTES as usize / 16;
    if motion_texels(&first, 2) > budget {
        return Ok(Err(format!(
            "{} triangles at two time steps exceed the kernels' buffer budget",
            first.triangles.len()
        )));
    }
    let deviation = loop {
        let segments = steps.len() - 1;
        let mut mids = Vec::with_capacity(segments);
        let mut deviation = 0.0f32;
        for k in 0..segments {
            // The quarter points too: a motion that comes back (a swing)
            // can pass its midpoint where a straight one would.
            for q in 1..4 {
                let between = match step_at(at(4 * k + q, 4 * segments))? {
                    Ok(step) => step,
                    Err(reason) => return Ok(Err(reason)),
                };
                let w = q as f32 / 4.0;
                deviation = deviation.max(deviation_from_linear(
                    &steps[k],
                    &between,
                    &steps[k + 1],
                    w,
                    size,
                ));
                if q == 2 {
                    mids.push(between);
                }
            }
        }
        if deviation <= MOTION_TOLERANCE {
            break deviation;
        }
        let room = motion_texels(&first, 2 * segments + 1) <= budget;
        if 2 * segments > MAX_MOTION_SEGMENTS || !room {
            // A jump (a STEP key) or a fast turn: host time steps sample
            // the true poses instead.
            return Ok(Err(format!(
                "the motion is not linear within {MOTION_TOLERANCE:e} of the scene's size between {} time steps (off by {deviation:.1e})",
                segments + 1
            )));
        }
        let mut finer = Vec::with_capacity(2 * segments + 1);
        let mut coarse = std::mem::take(&mut steps).into_iter();
        for mid in mids {
            finer.push(coarse.next().expect("a step before each midpoint"));
            finer.push(mid);
        }
        finer.extend(coarse);
        steps = finer;
    };
    let mut scene = first;
    scene.motion = Some(SceneMotion { steps, deviation });
    Ok(Ok(scene))
}
