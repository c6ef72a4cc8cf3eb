//! The BVH's nodes again, with their children's boxes decoded from the
//! quantized grid to floats, for the CPU back end's AVX2 node test: six
//! vector loads per node instead of six byte unpacks, conversions and
//! multiply-adds. Each plane is `bvh::grid_plane`'s value, the one traversal
//! computes from the grid, so the test's results do not change. Built on
//! first use, so the Vulkan back end never pays for it.
//!
//! `tight_nodes` decodes them again with each child's box shrunk from the
//! grid's planes to the exact bounds of what it holds: the grid of a node
//! spanning the room is 2 mm coarse, so the grid's box of the Cornell box's
//! light reaches below it and every shadow ray aimed at the light opened
//! it and tested its triangles (and the ceiling's). Only the traversals
//! whose order and work do not change what they find use them
//! (`nearest_first`, `packet`); the one that mirrors the kernels' work
//! budget keeps the grid's planes.

use crate::cpu::fast::wide::WIDTH;
use crate::packed::bvh::{grid_plane, grid_step};
use crate::packed::layout::{CwBvhNode, TriangleVerts};
use glam::Vec3;

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
    /// The node's first block of leaf triangles (`triangle_blocks`; in
    /// `tight_nodes`, of `window_blocks`).
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
    let mut decoded = crate::huge_pages::with_capacity(nodes.len());
    decoded.extend(
        nodes
            .iter()
            .zip(super::triangle_blocks::first_blocks(nodes))
            .map(|(n, triangle_block)| DecodedNode {
                triangle_block,
                ..DecodedNode::new(n)
            }),
    );
    decoded
}

/// How far a tight plane lies outside the exact bounds, as a fraction of
/// the scene's largest extent, and at least a float: a ray parallel to an
/// axis and exactly in a box's face plane gets (plane - origin) times the
/// clamped inverse direction, 0 there, and would leave the box at t = 0,
/// though the triangle test hits the edge it runs along (planted: planes
/// at the exact bounds, or one float out, fail `tests/suite/cpu_lanes.rs`).
/// 2^-20 of the extent is also several times the watertight triangle
/// test's rounding error (about four ulps of the distance from the origin
/// to the vertices, pbrt-v4's analysis) for origins within the scene, and
/// far less than the 1e-4 of its length that a shadow ray stops short of
/// its light (`SHADOW_RAY_SHORTEN`).
pub const TIGHT_MARGIN: f32 = 1.0 / 1_048_576.0;

/// `decode_nodes` with each node's first block of `WIDTH` triangles
/// (`CpuScene::window_blocks`), and each child's planes moved in from
/// the grid's to its exact bounds (its triangles' vertices, or its
/// subtree's) widened by `TIGHT_MARGIN` and rounded outward, never outside
/// the grid's planes: every box still holds what the kernels' box holds,
/// and less empty space. `tris`: the triangles in BVH order, still (a
/// moving scene's boxes cover its steps: the grid's planes stay).
pub fn tight_nodes(nodes: &[CwBvhNode], tris: &[TriangleVerts]) -> Vec<DecodedNode> {
    let windows = super::triangle_blocks::first_blocks_of(nodes, WIDTH as u32);
    let mut decoded: Vec<DecodedNode> = crate::huge_pages::with_capacity(nodes.len());
    decoded.extend(
        nodes
            .iter()
            .zip(windows)
            .map(|(n, triangle_block)| DecodedNode {
                triangle_block,
                ..DecodedNode::new(n)
            }),
    );
    let (scene_lo, scene_hi) = bounds_of(tris);
    let margin = (scene_hi - scene_lo).max_element().max(0.0) * TIGHT_MARGIN;
    // Exact bounds per node, children first: obvhs stores a node's inner
    // children after it.
    let empty = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    let mut node_bounds = vec![empty; nodes.len()];
    for index in (0..nodes.len()).rev() {
        let n = decoded[index];
        let imask = n.e_imask >> 24;
        let mut all = empty;
        for slot in 0..8 {
            let meta = (n.child_meta[slot / 4] >> (8 * (slot % 4))) & 0xFF;
            if meta == 0 {
                continue;
            }
            let (lo, hi) = if imask & (1 << slot) != 0 {
                let inner_before = (imask & ((1 << slot) - 1)).count_ones();
                node_bounds[(n.child_base_idx + inner_before) as usize]
            } else {
                let first = n.primitive_base_idx + (meta & 31);
                bounds_of(&tris[first as usize..(first + (meta >> 5).count_ones()) as usize])
            };
            let node = &mut decoded[index];
            for axis in 0..3 {
                let (grid_lo, grid_hi) = (node.lo[axis][slot], node.hi[axis][slot]);
                node.lo[axis][slot] = grid_lo.max((lo[axis] - margin).next_down());
                node.hi[axis][slot] = grid_hi.min((hi[axis] + margin).next_up());
            }
            all = (all.0.min(lo), all.1.max(hi));
        }
        node_bounds[index] = all;
    }
    decoded
}

/// The exact bounds of the triangles' vertices.
fn bounds_of(tris: &[TriangleVerts]) -> (Vec3, Vec3) {
    tris.iter().flat_map(|t| [t.v0, t.v1, t.v2]).fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), v| (lo.min(Vec3::from(v)), hi.max(Vec3::from(v))),
    )
}
