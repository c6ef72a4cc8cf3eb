//! The triangles of each BVH node's leaves again, eight at a time in
//! blocks, for the CPU back end's single-ray triangle test. A node's leaf
//! triangles are tested in windows of eight from its `primitive_base_idx`
//! (`cpu::bvh`); block `triangle_block + w` of the node holds window `w`'s
//! nine coordinate vectors side by side, so a window is 288 contiguous
//! bytes (five cache lines) instead of half a line in each of nine arrays
//! (`triangle_soa`, which moving scenes still use). Still scenes only: the
//! values are `tri_verts`' own. Built on first use.
//!
//! The order-free traversal (`leaf_window`) reads its own copy in
//! blocks of a vector register (`WIDTH`: sixteen with AVX-512), indexed
//! by `CpuScene::tight_nodes`' `triangle_block`.

use crate::packed::layout::{CwBvhNode, TriangleVerts};

/// Eight triangles' coordinates, `coords[3 * vertex + axis][lane]`; lanes
/// past the last triangle are zero.
#[repr(C, align(32))]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TriangleBlock {
    pub coords: [[f32; 8]; 9],
}

impl TriangleBlock {
    /// The block of triangles `first .. first + 8` (those that exist).
    pub fn new(tris: &[TriangleVerts], first: usize) -> TriangleBlock {
        let mut block = TriangleBlock::default();
        fill(&mut block.coords, tris, first);
        block
    }
}

use crate::cpu::fast::wide::WIDTH;

/// `WIDTH` triangles' coordinates, as `TriangleBlock` (a cache line per
/// row with sixteen).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowBlock {
    pub coords: [[f32; WIDTH]; 9],
}

impl WindowBlock {
    /// The block of triangles `first .. first + WIDTH` (those that exist).
    pub fn new(tris: &[TriangleVerts], first: usize) -> WindowBlock {
        let mut block = WindowBlock {
            coords: [[0.0; WIDTH]; 9],
        };
        fill(&mut block.coords, tris, first);
        block
    }
}

/// `coords[3 * vertex + axis][lane]` of triangles `first .. first + N`.
fn fill<const N: usize>(coords: &mut [[f32; N]; 9], tris: &[TriangleVerts], first: usize) {
    for (lane, t) in tris.iter().skip(first).take(N).enumerate() {
        for (vertex, v) in [t.v0, t.v1, t.v2].into_iter().enumerate() {
            for (axis, x) in v.into_iter().enumerate() {
                coords[3 * vertex + axis][lane] = x;
            }
        }
    }
}

/// How many windows of eight a node's leaf triangles span: up to the end
/// of its last leaf child's run (child_meta byte m: the run starts at
/// m & 31 and has as many triangles as m >> 5 has bits).
pub fn node_windows(n: &CwBvhNode) -> u32 {
    node_windows_of(n, 8)
}

/// How many windows of `width` a node's leaf triangles span.
pub fn node_windows_of(n: &CwBvhNode, width: u32) -> u32 {
    let imask = n.e_imask >> 24;
    let end = (0..8)
        .filter(|&slot| imask & (1 << slot) == 0)
        .map(|slot| (n.child_meta[slot / 4] >> (8 * (slot % 4))) & 0xFF)
        .filter(|&m| m != 0)
        .map(|m| (m & 31) + (m >> 5).count_ones())
        .max()
        .unwrap_or(0);
    end.div_ceil(width)
}

/// Each node's first block: the windows of the nodes before it.
pub fn first_blocks(nodes: &[CwBvhNode]) -> Vec<u32> {
    first_blocks_of(nodes, 8)
}

/// Each node's first block of windows of `width`.
pub fn first_blocks_of(nodes: &[CwBvhNode], width: u32) -> Vec<u32> {
    nodes
        .iter()
        .scan(0u32, |next, n| {
            let first = *next;
            *next += node_windows_of(n, width);
            Some(first)
        })
        .collect()
}

/// Every node's windows, in node order (`first_blocks`).
pub fn build(nodes: &[CwBvhNode], tris: &[TriangleVerts]) -> Vec<TriangleBlock> {
    every_window(nodes, 8, |first| TriangleBlock::new(tris, first))
}

/// Every node's windows of `WIDTH`, in node order (`first_blocks_of`).
pub fn build_windows(nodes: &[CwBvhNode], tris: &[TriangleVerts]) -> Vec<WindowBlock> {
    every_window(nodes, WIDTH as u32, |first| WindowBlock::new(tris, first))
}

/// `block(first)` for every node's windows of `width`, in node order, in
/// an array sized first (grown by doubling, it was copied as it grew and
/// held up to half again its size at its peak: 75 MiB more on 5 M
/// triangles) and on huge pages (`huge_pages`).
fn every_window<B>(nodes: &[CwBvhNode], width: u32, block: impl Fn(usize) -> B) -> Vec<B> {
    let count = nodes
        .iter()
        .map(|n| node_windows_of(n, width) as usize)
        .sum();
    let mut blocks = crate::huge_pages::with_capacity(count);
    for n in nodes {
        for w in 0..node_windows_of(n, width) {
            blocks.push(block((n.primitive_base_idx + width * w) as usize));
        }
    }
    blocks
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The windows of a node cover every triangle its leaves name, and no
    /// more windows than that.
    #[test]
    fn windows_reach_the_last_leaf_triangle() {
        // Slot 0: inner (imask bit 0); slot 1: a leaf of 3 triangles from
        // offset 7; slot 2: a leaf of 2 from offset 14.
        let mut n = CwBvhNode {
            e_imask: 1 << 24,
            child_meta: [((0b111 << 5) | 7) << 8 | ((0b11 << 5) | 14) << 16 | 0xFF, 0],
            ..Default::default()
        };
        // 14 + 2 = 16 triangles: two windows, whatever the inner slot's byte.
        assert_eq!(node_windows(&n), 2);
        n.child_meta[0] = (0b11 << 5 | 15) << 16;
        assert_eq!(node_windows(&n), 3);
        assert_eq!(node_windows(&CwBvhNode::default()), 0);
        // Sixteen at a time: one window for 16 triangles, two for 17.
        assert_eq!(node_windows_of(&n, 16), 2);
        n.child_meta[0] = (0b11 << 5 | 14) << 16;
        assert_eq!(node_windows_of(&n, 16), 1);
    }
}
