//! BVH construction with obvhs (PLOC + reinsertion + leaf collapse), and its
//! flattening into the node layout both back ends traverse.

use crate::constants::{
    BVH_LEAF_BIT, BVH_LEAF_COUNT_MASK, BVH_LEAF_COUNT_SHIFT, BVH_LEAF_FIRST_MASK,
};
use crate::layout::BvhNode;
use crate::scene::Triangle;
use glam::Vec3A;
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2_from_tris, triangle::Triangle as BuildTri};
use std::time::{Duration, Instant};

/// A flattened BVH2 over triangles stored in BVH order.
pub struct Bvh {
    /// Inner nodes, depth first (a node's left subtree follows it).
    pub nodes: Vec<BvhNode>,
    /// The item traversal starts from: node 0, or a leaf when the whole
    /// scene fits in one.
    pub root: u32,
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
        triangles.len() <= BVH_LEAF_FIRST_MASK as usize,
        "{} triangles exceed the {} a BVH leaf can address",
        triangles.len(),
        BVH_LEAF_FIRST_MASK
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
    let source = &bvh2.nodes;
    let leaf_item = |n: &obvhs::bvh2::node::Bvh2Node| {
        debug_assert!(n.prim_count <= BVH_LEAF_COUNT_MASK);
        BVH_LEAF_BIT | (n.prim_count << BVH_LEAF_COUNT_SHIFT) | n.first_index
    };
    let mut nodes = Vec::new();
    let root = if source[0].is_leaf() {
        leaf_item(&source[0])
    } else {
        // Depth-first: emit a node, then fill in its children's items once
        // their own indices are known.
        let mut pending = vec![(0usize, None::<(usize, bool)>)];
        while let Some((src, parent)) = pending.pop() {
            let n = &source[src];
            let item = if n.is_leaf() {
                leaf_item(n)
            } else {
                let (l, r) = (
                    &source[n.first_index as usize],
                    &source[n.first_index as usize + 1],
                );
                nodes.push(BvhNode {
                    left_min: l.aabb.min.into(),
                    left_max: l.aabb.max.into(),
                    right_min: r.aabb.min.into(),
                    right_max: r.aabb.max.into(),
                    ..Default::default()
                });
                let index = nodes.len() - 1;
                pending.push((n.first_index as usize + 1, Some((index, false))));
                pending.push((n.first_index as usize, Some((index, true))));
                index as u32
            };
            match parent {
                Some((p, true)) => nodes[p].left = item,
                Some((p, false)) => nodes[p].right = item,
                None => {}
            }
        }
        0
    };
    Ok(Bvh {
        nodes,
        root,
        order: bvh2.primitive_indices.clone(),
        build_time: start.elapsed(),
    })
}
