//! The BVH's nodes again, with their children's boxes decoded from the
//! quantized grid to floats, for the CPU back end's AVX2 node test: six
//! vector loads per node instead of six byte unpacks, conversions and
//! multiply-adds. Each plane is `bvh::grid_plane`'s value, the one traversal
//! computes from the grid, so the test's results do not change. Built on
//! first use, so the Vulkan back end never pays for it.

use super::bvh::{grid_plane, grid_step};
use super::layout::CwBvhNode;

/// One node, 224 bytes (32-byte aligned for the vector loads).
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DecodedNode {
    /// Per axis (x, y, z), the eight children's low planes.
    pub lo: [[f32; 8]; 3],
    /// Per axis, the eight children's high planes.
    pub hi: [[f32; 8]; 3],
    pub child_meta: [u32; 2],
    pub child_base_idx: u32,
    pub primitive_base_idx: u32,
    /// `CwBvhNode::e_imask`: its top byte says which slots are inner nodes.
    pub e_imask: u32,
    /// The node's first block of leaf triangles (`triangle_blocks`).
    pub triangle_block: u32,
}

impl DecodedNode {
    pub fn new(n: &CwBvhNode) -> DecodedNode {
        let e = grid_step(n.e_imask);
        let planes = |q: [u32; 2], axis: usize| {
            std::array::from_fn(|k| {
                grid_plane(n.p[axis], e[axis], (q[k / 4] >> (8 * (k % 4))) & 0xFF)
            })
        };
        DecodedNode {
            lo: [planes(n.qlo_x, 0), planes(n.qlo_y, 1), planes(n.qlo_z, 2)],
            hi: [planes(n.qhi_x, 0), planes(n.qhi_y, 1), planes(n.qhi_z, 2)],
            child_meta: n.child_meta,
            child_base_idx: n.child_base_idx,
            primitive_base_idx: n.primitive_base_idx,
            e_imask: n.e_imask,
            triangle_block: 0,
        }
    }
}

/// Every node of `nodes`, decoded, with its first block of triangles.
pub fn decode_nodes(nodes: &[CwBvhNode]) -> Vec<DecodedNode> {
    nodes
        .iter()
        .zip(super::triangle_blocks::first_blocks(nodes))
        .map(|(n, triangle_block)| DecodedNode {
            triangle_block,
            ..DecodedNode::new(n)
        })
        .collect()
}
