//! The light BVH's steps as the CPU's walk reads them: for each interior
//! node, the four candidates of its step (the twin's lanes,
//! `light_tree_grandchildren`) with their fields already in SIMD
//! registers, and where each candidate leads. The twin gathers the fields of six nodes a step, a scalar at a
//! time; this reads four aligned cache lines.

use crate::constants::LIGHT_TREE_LEAF;
use crate::cpu::common::light_bvh::LightTreeQuad;
use crate::packed::layout::LightTreeNode;
use glam::BVec4A;

/// `next` of a candidate that is a leaf: the walk ends there.
pub const AT_LEAF: u32 = u32::MAX;

/// One interior node's step: its candidates' fields (`quad`), which count
/// (`counts`: false for a leaf child's second), their nodes, and for each
/// the index of its own step (`AT_LEAF` for a leaf). The step of
/// the node whose children are `c` and `c + 1` is at `(c - 1) / 2`: the
/// builder pushes children in pairs after the root.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct LightTreeStep {
    pub quad: LightTreeQuad,
    pub counts: BVec4A,
    pub node: [u32; 4],
    pub next: [u32; 4],
}

/// The step of node `n`, or `AT_LEAF` for a leaf.
pub fn step_of(n: &LightTreeNode) -> u32 {
    if n.flags & LIGHT_TREE_LEAF != 0 {
        AT_LEAF
    } else {
        (n.child_or_light - 1) / 2
    }
}

/// Every interior node's step, in the order `step_of` indexes.
pub fn build(nodes: &[LightTreeNode]) -> Vec<LightTreeStep> {
    let mut steps = Vec::with_capacity(nodes.len() / 2);
    for c in (1..nodes.len()).step_by(2) {
        let (a, b) = (&nodes[c], &nodes[c + 1]);
        debug_assert_eq!(steps.len(), (c - 1) / 2);
        let lanes = |x: &LightTreeNode, i: usize| {
            if x.flags & LIGHT_TREE_LEAF != 0 {
                [i, i]
            } else {
                let g = x.child_or_light as usize;
                [g, g + 1]
            }
        };
        let ([a0, a1], [b0, b1]) = (lanes(a, c), lanes(b, c + 1));
        let node = [a0, a1, b0, b1];
        let leaf = [a, b].map(|x| x.flags & LIGHT_TREE_LEAF != 0);
        steps.push(LightTreeStep {
            quad: LightTreeQuad::of(node.map(|i| &nodes[i])),
            counts: BVec4A::new(true, !leaf[0], true, !leaf[1]),
            node: node.map(|i| i as u32),
            next: node.map(|i| step_of(&nodes[i])),
        });
    }
    steps
}
