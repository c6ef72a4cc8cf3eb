//! Twin of `shaders/common/instances.glsl`: the instances of a two-level
//! scene (`packed::instances`). A ray enters a mesh's BVH in the mesh's own
//! space (`to_object`); what it hits is placed in the world (`to_world`):
//! points and tangents by the matrix, normals by its inverse transpose,
//! and a mirroring instance turns its triangles' winding, so their front
//! faces stay in front. The same arithmetic, in the same order, as the
//! kernels (each row `((a x + b y) + c z) + d`, no fused multiply-add).

use crate::constants::{GAMMA7, INSTANCE_MIRRORED, NO_INSTANCE};
use crate::packed::PackedScene;
use crate::packed::layout::Instance;
use glam::{Vec3, Vec4};

/// Rows of a 3x4 matrix, as `Instance` stores them.
pub type Rows = [[f32; 4]; 3];

/// Point `p` placed by `m`.
#[inline(always)]
pub fn instance_point(m: &Rows, p: Vec3) -> Vec3 {
    let row = |r: &[f32; 4]| r[0] * p.x + r[1] * p.y + r[2] * p.z + r[3];
    Vec3::new(row(&m[0]), row(&m[1]), row(&m[2]))
}

/// Direction `v` turned by the linear part of `m`.
#[inline(always)]
pub fn instance_vector(m: &Rows, v: Vec3) -> Vec3 {
    let row = |r: &[f32; 4]| r[0] * v.x + r[1] * v.y + r[2] * v.z;
    Vec3::new(row(&m[0]), row(&m[1]), row(&m[2]))
}

/// Normal `n` placed by the inverse transpose of `to_object`'s inverse,
/// that is by `to_object`'s transpose, normalized.
pub fn instance_normal(to_object: &Rows, n: Vec3) -> Vec3 {
    let m = to_object;
    let col = |c: usize| m[0][c] * n.x + m[1][c] * n.y + m[2][c] * n.z;
    let w = Vec3::new(col(0), col(1), col(2));
    let len = w.length();
    if len > 0.0 { w / len } else { w }
}

/// The instance whose ids hold hit id `id`: instances number their
/// triangles' ids in order, so a binary search over `id_base` finds it.
pub fn instance_of_id(instances: &[Instance], id: u32) -> u32 {
    let (mut lo, mut hi) = (0u32, instances.len() as u32);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if instances[mid as usize].id_base <= id {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The triangle slot hit id `id` names, and its instance (`NO_INSTANCE`
/// in a one-level scene, where an id is a slot).
pub fn hit_slot(scene: &PackedScene, id: u32) -> (u32, u32) {
    if scene.instances.is_empty() {
        return (id, NO_INSTANCE);
    }
    let k = instance_of_id(&scene.instances, id);
    let inst = &scene.instances[k as usize];
    (id - inst.id_base + inst.first_triangle, k)
}

/// -1 where instance `inst` mirrors (its placed triangles' cross
/// products point to their back faces), else 1.
pub fn instance_facing(scene: &PackedScene, inst: u32) -> f32 {
    if inst != NO_INSTANCE && scene.instances[inst as usize].flags & INSTANCE_MIRRORED != 0 {
        -1.0
    } else {
        1.0
    }
}

/// The triangle's vertices `v` placed by instance `inst` (as they are in a
/// one-level scene).
pub fn world_triangle(scene: &PackedScene, inst: u32, v: [Vec3; 3]) -> [Vec3; 3] {
    if inst == NO_INSTANCE {
        return v;
    }
    let m = scene.instances[inst as usize].to_world();
    v.map(|p| instance_point(&m, p))
}

/// `|m|` applied to the non-negative `v`, with `|translation|` added
/// where `t` is 1: a bound on what `m`'s rows round.
fn abs_rows(m: &Rows, v: Vec3, t: f32) -> Vec3 {
    let row =
        |r: &[f32; 4]| r[0].abs() * v.x + r[1].abs() * v.y + r[2].abs() * v.z + r[3].abs() * t;
    Vec3::new(row(&m[0]), row(&m[1]), row(&m[2]))
}

/// What instance `inst` adds to the error of world point `p` of one of
/// its surfaces: placing the hit in the world, and taking the next ray
/// from near it back into the instance's space, each round (as pbrt-v4's
/// transforms carry their points' error). Without it a ray leaving a
/// small instance far from the camera can hit the surface it left.
pub fn instance_error(scene: &PackedScene, inst: u32, p: Vec3) -> Vec3 {
    if inst == NO_INSTANCE {
        return Vec3::ZERO;
    }
    let i = &scene.instances[inst as usize];
    let (m, w) = (i.to_world(), i.to_object());
    // The point in the instance's space, bounded, and that bound placed.
    let back = abs_rows(&w, p.abs(), 1.0);
    let placed = abs_rows(&m, back, 0.0);
    GAMMA7 * (2.0 * placed + abs_rows(&m, Vec3::ZERO, 1.0))
}

/// Vertex normals placed by instance `inst`.
pub fn world_normals(scene: &PackedScene, inst: u32, n: [Vec3; 3]) -> [Vec3; 3] {
    if inst == NO_INSTANCE {
        return n;
    }
    let m = scene.instances[inst as usize].to_object();
    n.map(|n| instance_normal(&m, n))
}

/// A vertex tangent (xyz, bitangent sign w) placed by instance `inst`: the
/// direction by the matrix, normalized; a mirror turns the bitangent.
pub fn world_tangent(scene: &PackedScene, inst: u32, t: Vec4) -> Vec4 {
    if inst == NO_INSTANCE {
        return t;
    }
    let i = &scene.instances[inst as usize];
    let v = instance_vector(&i.to_world(), t.truncate());
    let len = v.length();
    let v = if len > 0.0 { v / len } else { v };
    let w = if i.flags & INSTANCE_MIRRORED != 0 {
        -t.w
    } else {
        t.w
    };
    v.extend(w)
}
