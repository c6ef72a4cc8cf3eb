//! BVH construction with obvhs (PLOC + reinsertion, collapsed into a
//! compressed wide BVH8), in the node layout both back ends traverse
//! (`layout::CwBvhNode`).

use crate::packed::layout::CwBvhNode;
use crate::scene::Triangle;
use glam::{Vec3, Vec3A};
use obvhs::{
    BvhBuildParams,
    aabb::Aabb,
    cwbvh::builder::{build_cwbvh, build_cwbvh_from_tris},
    triangle::Triangle as BuildTri,
};
use std::time::{Duration, Instant};

/// A compressed wide BVH8 over triangles stored in BVH order.
pub struct Bvh {
    /// Nodes; traversal starts at node 0.
    pub nodes: Vec<CwBvhNode>,
    /// `order[i]` is the scene triangle stored at BVH slot `i`.
    pub order: Vec<u32>,
    pub build_time: Duration,
}

/// Byte `k` of a packed byte array (`CwBvhNode`'s `[u32; 2]` fields).
pub fn byte(words: [u32; 2], k: usize) -> u32 {
    (words[k / 4] >> (8 * (k % 4))) & 0xFF
}

fn set_byte(words: &mut [u32; 2], k: usize, value: u32) {
    let shift = 8 * (k % 4);
    words[k / 4] = (words[k / 4] & !(0xFF << shift)) | ((value & 0xFF) << shift);
}

/// The grid step of each axis: the float with exponent bits `e`.
pub fn grid_step(e_imask: u32) -> Vec3 {
    Vec3::new(
        f32::from_bits((e_imask & 0xFF) << 23),
        f32::from_bits(((e_imask >> 8) & 0xFF) << 23),
        f32::from_bits(((e_imask >> 16) & 0xFF) << 23),
    )
}

/// A plane of the quantization grid, as traversal computes it: `p + e * q`
/// in f32 (`e * q` is exact: a power of two times an 8-bit integer).
pub fn grid_plane(p: f32, e: f32, q: u32) -> f32 {
    p + e * q as f32
}

/// obvhs's CWBVH exactly as the renderer builds it, before vkpt re-fits the
/// quantized boxes: PLOC with reinsertion, and no spatial pre-splits, so
/// every triangle sits in exactly one leaf (emitter tables index BVH slots).
/// The traversal benchmark times this raw tree too.
pub fn build_obvhs_cwbvh(triangles: &[Triangle]) -> obvhs::cwbvh::CwBvh {
    let build_tris: Vec<BuildTri> = triangles
        .iter()
        .map(|t| BuildTri {
            v0: Vec3A::from(t.positions[0]),
            v1: Vec3A::from(t.positions[1]),
            v2: Vec3A::from(t.positions[2]),
        })
        .collect();
    build_cwbvh_from_tris(&build_tris, build_params(), &mut Duration::default())
}

/// PLOC with reinsertion (obvhs' medium preset), without pre-splits.
fn build_params() -> BvhBuildParams {
    let mut params = BvhBuildParams::medium_build();
    params.pre_split = false;
    params
}

/// Builds the BVH.
pub fn build(triangles: &[Triangle]) -> anyhow::Result<Bvh> {
    build_with(triangles, None)
}

/// Builds the BVH over triangles that move: `steps[k][i]` is triangle i at
/// time step k (`scene::SceneMotion`), and every box encloses its
/// triangle's vertices at all steps. A vertex interpolated linearly between
/// two steps stays inside the hull of both, so the swept boxes hold the
/// triangle at every time traversal may ask for; the traversal itself does
/// not change.
pub fn build_swept(steps: &[&[Triangle]]) -> anyhow::Result<Bvh> {
    let first = steps.first().copied().unwrap_or(&[]);
    anyhow::ensure!(
        steps.iter().all(|s| s.len() == first.len()),
        "the time steps of a moving scene hold different numbers of triangles"
    );
    build_with(first, Some(steps))
}

fn build_with(triangles: &[Triangle], steps: Option<&[&[Triangle]]>) -> anyhow::Result<Bvh> {
    anyhow::ensure!(
        !triangles.is_empty(),
        "cannot build a BVH over zero triangles"
    );
    let start = Instant::now();
    let leaf_bounds = |i: usize| -> Bounds {
        let mut b = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        let mut add = |t: &Triangle| {
            for v in t.positions {
                b = (b.0.min(v), b.1.max(v));
            }
        };
        match steps {
            Some(steps) => steps.iter().for_each(|s| add(&s[i])),
            None => add(&triangles[i]),
        }
        b
    };
    let cwbvh = match steps {
        None => build_obvhs_cwbvh(triangles),
        Some(_) => {
            let boxes: Vec<Aabb> = (0..triangles.len())
                .map(|i| {
                    let (lo, hi) = leaf_bounds(i);
                    Aabb::new(lo.into(), hi.into())
                })
                .collect();
            build_cwbvh(&boxes, build_params(), &mut Duration::default())
        }
    };
    finish(cwbvh, triangles.len(), &leaf_bounds, start)
}

/// Builds the BVH over boxes (the top level of a two-level scene: one box
/// per instance), in the same node layout; `order[i]` is the box at slot i.
pub fn build_over_boxes(boxes: &[Bounds]) -> anyhow::Result<Bvh> {
    anyhow::ensure!(!boxes.is_empty(), "cannot build a BVH over zero boxes");
    let start = Instant::now();
    let aabbs: Vec<Aabb> = boxes
        .iter()
        .map(|&(lo, hi)| Aabb::new(lo.into(), hi.into()))
        .collect();
    let cwbvh = build_cwbvh(&aabbs, build_params(), &mut Duration::default());
    finish(cwbvh, boxes.len(), &|i| boxes[i], start)
}

/// obvhs' tree in vkpt's node layout, its boxes made conservative.
fn finish(
    cwbvh: obvhs::cwbvh::CwBvh,
    count: usize,
    leaf_bounds: &dyn Fn(usize) -> Bounds,
    start: Instant,
) -> anyhow::Result<Bvh> {
    anyhow::ensure!(
        cwbvh.primitive_indices.len() == count && !cwbvh.nodes.is_empty(),
        "the CWBVH holds {} of {} primitives",
        cwbvh.primitive_indices.len(),
        count
    );
    let order = cwbvh.primitive_indices;
    let mut nodes: Vec<CwBvhNode> = cwbvh
        .nodes
        .iter()
        .map(|n| {
            let w = |b: &[u8; 8]| {
                [
                    u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                    u32::from_le_bytes([b[4], b[5], b[6], b[7]]),
                ]
            };
            CwBvhNode {
                p: n.p.into(),
                e_imask: u32::from_le_bytes([n.e[0], n.e[1], n.e[2], n.imask]),
                child_base_idx: n.child_base_idx,
                primitive_base_idx: n.primitive_base_idx,
                child_meta: w(&n.child_meta),
                qlo_x: w(&n.child_min_x),
                qhi_x: w(&n.child_max_x),
                qlo_y: w(&n.child_min_y),
                qhi_y: w(&n.child_max_y),
                qlo_z: w(&n.child_min_z),
                qhi_z: w(&n.child_max_z),
            }
        })
        .collect();
    make_conservative(&mut nodes, &order, leaf_bounds)?;
    Ok(Bvh {
        nodes,
        order,
        build_time: start.elapsed(),
    })
}

/// Exact bounds of a child slot's subtree.
pub type Bounds = (Vec3, Vec3);

/// obvhs quantizes child bounds from rounded differences, so a decoded plane
/// `p + e * q` can land a rounding step inside the child's exact bounds, and
/// a ray grazing the child would miss it. Re-derives every child's grid
/// bounds so the planes, computed as traversal computes them, enclose the
/// exact bounds (the encoding is unchanged; almost every byte stays as
/// obvhs chose it). Nodes are visited children first: obvhs stores a node's
/// inner children after it.
fn make_conservative(
    nodes: &mut [CwBvhNode],
    order: &[u32],
    leaf_bounds: &dyn Fn(usize) -> Bounds,
) -> anyhow::Result<()> {
    let mut node_bounds = vec![(Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)); nodes.len()];
    for index in (0..nodes.len()).rev() {
        let n = nodes[index];
        let imask = n.e_imask >> 24;
        let mut children: [Option<Bounds>; 8] = [None; 8];
        for (slot, child) in children.iter_mut().enumerate() {
            let meta = byte(n.child_meta, slot);
            if meta == 0 {
                continue;
            }
            *child = Some(if imask & (1 << slot) != 0 {
                let inner_before = (imask & ((1 << slot) - 1)).count_ones();
                node_bounds[(n.child_base_idx + inner_before) as usize]
            } else {
                let first = n.primitive_base_idx + (meta & 31);
                let mut b = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
                for i in first..first + (meta >> 5).count_ones() {
                    let (lo, hi) = leaf_bounds(order[i as usize] as usize);
                    b = (b.0.min(lo), b.1.max(hi));
                }
                b
            });
        }
        let lo = children
            .iter()
            .flatten()
            .fold(Vec3::splat(f32::MAX), |m, c| m.min(c.0));
        let hi = children
            .iter()
            .flatten()
            .fold(Vec3::splat(f32::MIN), |m, c| m.max(c.1));
        anyhow::ensure!(lo.cmple(hi).all(), "CWBVH node {index} has no children");
        node_bounds[index] = (lo, hi);

        let p = Vec3::from(n.p);
        anyhow::ensure!(
            p.cmple(lo).all(),
            "CWBVH node {index}: grid origin {p} is not below its bounds' minimum {lo}"
        );
        // Grow a grid step until 255 steps reach the node's maximum.
        let mut e_imask = n.e_imask;
        for axis in 0..3 {
            let shift = 8 * axis;
            let mut e = (e_imask >> shift) & 0xFF;
            while grid_plane(p[axis], f32::from_bits(e << 23), 255) < hi[axis] {
                anyhow::ensure!(e < 254, "CWBVH node {index}: grid step overflows");
                e += 1;
            }
            e_imask = (e_imask & !(0xFF << shift)) | (e << shift);
        }
        let step = grid_step(e_imask);
        let mut node = n;
        node.e_imask = e_imask;
        for (slot, child) in children.iter().enumerate() {
            let Some((cmin, cmax)) = child else {
                continue;
            };
            for axis in 0..3 {
                let (qlo, qhi) = match axis {
                    0 => (&mut node.qlo_x, &mut node.qhi_x),
                    1 => (&mut node.qlo_y, &mut node.qhi_y),
                    _ => (&mut node.qlo_z, &mut node.qhi_z),
                };
                let plane = |q: u32| grid_plane(p[axis], step[axis], q);
                let mut lo_q = byte(*qlo, slot);
                let mut hi_q = byte(*qhi, slot);
                // Start from obvhs' values when the step is unchanged.
                if e_imask != n.e_imask {
                    lo_q = (((cmin[axis] - p[axis]) / step[axis]).floor()).clamp(0.0, 255.0) as u32;
                    hi_q = (((cmax[axis] - p[axis]) / step[axis]).ceil()).clamp(0.0, 255.0) as u32;
                }
                while lo_q > 0 && plane(lo_q) > cmin[axis] {
                    lo_q -= 1;
                }
                while lo_q < hi_q && plane(lo_q + 1) <= cmin[axis] {
                    lo_q += 1;
                }
                while hi_q < 255 && plane(hi_q) < cmax[axis] {
                    hi_q += 1;
                }
                while hi_q > lo_q && plane(hi_q - 1) >= cmax[axis] {
                    hi_q -= 1;
                }
                anyhow::ensure!(
                    plane(lo_q) <= cmin[axis] && plane(hi_q) >= cmax[axis],
                    "CWBVH node {index}, child {slot}: cannot enclose its bounds on axis {axis}"
                );
                set_byte(qlo, slot, lo_q);
                set_byte(qhi, slot, hi_q);
            }
        }
        nodes[index] = node;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> Triangle {
        Triangle {
            positions: [a.into(), b.into(), c.into()],
            normals: [Vec3::Z; 3],
            material: 0,
        }
    }

    #[test]
    fn one_triangle_builds_a_root_with_one_leaf() {
        let bvh = build(&[tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])]).unwrap();
        assert_eq!(bvh.order, vec![0]);
        assert!(!bvh.nodes.is_empty());
        assert_eq!(
            bvh.nodes[0].e_imask >> 24,
            0,
            "the root's only child is a leaf"
        );
    }

    #[test]
    fn every_triangle_is_in_exactly_one_leaf() {
        let tris: Vec<Triangle> = (0..1000)
            .map(|i| {
                let x = (i % 10) as f32 * 1.37;
                let y = (i / 10 % 10) as f32 * 0.91;
                let z = (i / 100) as f32 * 2.03;
                tri([x, y, z], [x + 1.0, y, z + 0.3], [x, y + 1.1, z - 0.2])
            })
            .collect();
        let bvh = build(&tris).unwrap();
        let mut seen = vec![0u32; tris.len()];
        for n in &bvh.nodes {
            let imask = n.e_imask >> 24;
            for slot in 0..8 {
                let meta = byte(n.child_meta, slot);
                if meta != 0 && imask & (1 << slot) == 0 {
                    let first = n.primitive_base_idx + (meta & 31);
                    for i in first..first + (meta >> 5).count_ones() {
                        seen[bvh.order[i as usize] as usize] += 1;
                    }
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
    }
}
