//! The two-level acceleration structure of a scene with instancing: one
//! BVH per mesh kept once (the bottom level), and a BVH over the instances
//! that place them (the top level), all in the one node array both back
//! ends traverse (`shaders/common/instances.glsl`, `bvh.glsl`).
//!
//! Layout: the top level's nodes first (its root is node 0, where every
//! traversal starts), then each mesh's nodes; a mesh's triangles are
//! stored once, in its BVH's order, one mesh after another. A top-level
//! leaf's primitive is an instance: `Instance` records are stored in the
//! top level's leaf order. The triangles in place (those of meshes used
//! once) are one more mesh, placed once by the identity.

use super::bvh::{self, Bounds};
use super::layout::{CwBvhNode, Instance};
use crate::constants::{INSTANCE_MIRRORED, LIGHT_HIT_FLAG};
use crate::scene::{Instancing, Scene, placeable, triangle_bounds};
use glam::{DMat4, DVec3};
use std::time::{Duration, Instant};

/// The two levels, ready to pack.
pub struct TwoLevel {
    /// The top level's nodes, then every mesh's.
    pub nodes: Vec<CwBvhNode>,
    /// Nodes of the top level (they come first).
    pub top_nodes: u32,
    /// `order[s]`: the scene triangle stored at slot `s`.
    pub order: Vec<u32>,
    pub instances: Vec<Instance>,
    pub stats: InstancingStats,
}

/// What the summary says of a two-level scene.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct InstancingStats {
    /// Meshes with a BVH of their own (the triangles in place count as one).
    pub meshes: usize,
    pub instances: usize,
    /// Triangles stored once.
    pub unique_triangles: u64,
    /// Triangles the instances place (what a one-level scene would store).
    pub placed_triangles: u64,
    /// Building the meshes' BVHs, and the top level's.
    pub bottom_build_time: Duration,
    pub top_build_time: Duration,
}

/// The rows of a 3x4 matrix (the affine part of `m`), in f32.
fn rows(m: &DMat4) -> [[f32; 4]; 3] {
    let r = m.transpose();
    [r.x_axis, r.y_axis, r.z_axis].map(|v| v.as_vec4().to_array())
}

/// Builds both levels. Errors name what cannot be built.
pub fn build(scene: &Scene, inst: &Instancing) -> anyhow::Result<TwoLevel> {
    // The meshes: the triangles in place (if any), then each kept one.
    let mut meshes: Vec<std::ops::Range<usize>> = Vec::new();
    let mut placements: Vec<(usize, DMat4)> = Vec::new();
    if inst.placed > 0 {
        meshes.push(0..inst.placed);
        placements.push((0, DMat4::IDENTITY));
    }
    let first_kept = meshes.len();
    meshes.extend(inst.meshes.iter().cloned());
    for (k, i) in inst.instances.iter().enumerate() {
        anyhow::ensure!(
            i.mesh < inst.meshes.len(),
            "instance #{k} places mesh #{} of {}",
            i.mesh,
            inst.meshes.len()
        );
        anyhow::ensure!(
            placeable(&i.to_world),
            "instance #{k}: its transform is not invertible"
        );
        placements.push((first_kept + i.mesh, i.to_world));
    }
    anyhow::ensure!(!placements.is_empty(), "no instances to place");

    // The bottom level: one BVH per mesh, nodes after the top level's.
    let start = Instant::now();
    let mut bottom = Vec::with_capacity(meshes.len());
    for (m, range) in meshes.iter().enumerate() {
        let tris = &scene.triangles[range.clone()];
        let b = bvh::build(tris).map_err(|e| anyhow::anyhow!("mesh #{m}: {e}"))?;
        let bounds = triangle_bounds(tris).expect("a BVH holds triangles");
        bottom.push((b, bounds));
    }
    let bottom_build_time = start.elapsed();

    // The top level over the instances' world boxes.
    let start = Instant::now();
    let boxes: Vec<Bounds> = placements
        .iter()
        .map(|(m, to_world)| world_box(to_world, bottom[*m].1))
        .collect();
    let top = bvh::build_over_boxes(&boxes)?;
    let top_build_time = start.elapsed();

    // Concatenate: the top level first, then each mesh, its node and
    // triangle indices moved by where it starts.
    let top_nodes = top.nodes.len() as u32;
    let mut nodes = top.nodes;
    let mut order: Vec<u32> = Vec::with_capacity(scene.triangles.len());
    let mut roots = Vec::with_capacity(meshes.len());
    for ((b, _), range) in bottom.into_iter().zip(&meshes) {
        let node_base = nodes.len() as u32;
        let first_triangle = order.len() as u32;
        nodes.extend(b.nodes.into_iter().map(|mut n| {
            n.child_base_idx += node_base;
            n.primitive_base_idx += first_triangle;
            n
        }));
        order.extend(b.order.iter().map(|&i| i + range.start as u32));
        roots.push((node_base, first_triangle));
    }

    // The instances in the top level's leaf order, their ids numbered in
    // that order.
    let mut instances = Vec::with_capacity(placements.len());
    let mut id_base = 0u64;
    for &slot in &top.order {
        let (m, to_world) = &placements[slot as usize];
        let (root, first_triangle) = roots[*m];
        let [to_world_x, to_world_y, to_world_z] = rows(to_world);
        let [to_object_x, to_object_y, to_object_z] = rows(&to_world.inverse());
        instances.push(Instance {
            to_world_x,
            to_world_y,
            to_world_z,
            to_object_x,
            to_object_y,
            to_object_z,
            root,
            id_base: id_base as u32,
            first_triangle,
            flags: if to_world.determinant() < 0.0 {
                INSTANCE_MIRRORED
            } else {
                0
            },
        });
        id_base += meshes[*m].len() as u64;
    }
    anyhow::ensure!(
        id_base < LIGHT_HIT_FLAG as u64,
        "the instances place {id_base} triangles; vkpt numbers at most {} (2^31 - 1)",
        LIGHT_HIT_FLAG - 1
    );
    Ok(TwoLevel {
        nodes,
        top_nodes,
        order,
        instances,
        stats: InstancingStats {
            meshes: meshes.len(),
            instances: placements.len(),
            unique_triangles: scene.triangles.len() as u64,
            placed_triangles: id_base,
            bottom_build_time,
            top_build_time,
        },
    })
}

/// The world box of a mesh with object bounds `(lo, hi)` placed by
/// `to_world`: its eight corners placed in f64, grown by a few float steps
/// so that rounding never shrinks it below what the rays meet.
fn world_box(to_world: &DMat4, (lo, hi): Bounds) -> Bounds {
    let mut a = DVec3::splat(f64::MAX);
    let mut b = DVec3::splat(f64::MIN);
    for k in 0..8 {
        let corner = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x } as f64,
            if k & 2 == 0 { lo.y } else { hi.y } as f64,
            if k & 4 == 0 { lo.z } else { hi.z } as f64,
        );
        let p = to_world.transform_point3(corner);
        a = a.min(p);
        b = b.max(p);
    }
    let pad = 1e-5 * (b - a).max_element() + 1e-6 * a.abs().max(b.abs()).max_element();
    ((a - pad).as_vec3(), (b + pad).as_vec3())
}
