//! BVH construction with obvhs (PLOC + reinsertion + leaf collapse), and its
//! flattening into the node layout both back ends traverse.

use crate::layout::BvhNode;
use crate::scene::Triangle;
use glam::Vec3A;
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris, triangle::Triangle as BuildTri};
use std::time::{Duration, Instant};

/// A flattened BVH2 over triangles stored in BVH order.
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// `order[i]` is the scene triangle stored at BVH slot `i`.
    pub order: Vec<u32>,
    pub build_time: Duration,
}

/// Builds the BVH. Spatial pre-splits stay off so every triangle sits in
/// exactly one leaf (emitter tables index BVH slots).
pub fn build(triangles: &[Triangle]) -> anyhow::Result<Bvh> {
    anyhow::ensure!(
        !triangles.is_empty(),
        "cannot build a BVH over zero triangles"
    );
    anyhow::ensure!(
        triangles.len() < (u32::MAX / 2) as usize,
        "{} triangles exceed the 2^31 a BVH index can address",
        triangles.len()
    );
    let start = Instant::now();
    let build_tris: Vec<BuildTri> = triangles
        .iter()
        .map(|t| BuildTri {
            v0: Vec3A::from(t.positions[0]),
            v1: Vec3A::from(t.positions[1]),
            v2: Vec3A::from(t.positions[2]),
        })
        .collect();
    let mut params = BvhBuildParams::medium_build();
    params.pre_split = false;
    let bvh2 = build_bvh2_from_tris(&build_tris, params, &mut Duration::default());
    let nodes = bvh2
        .nodes
        .iter()
        .map(|n| BvhNode {
            min: n.aabb.min.into(),
            first: n.first_index,
            max: n.aabb.max.into(),
            count: n.prim_count,
        })
        .collect();
    Ok(Bvh {
        nodes,
        order: bvh2.primitive_indices.clone(),
        build_time: start.elapsed(),
    })
}
