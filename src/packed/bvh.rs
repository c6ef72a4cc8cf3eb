//! BVH construction with obvhs (PLOC + reinsertion) or vkpt's binned SAH
//! builder (`packed::binned`), collapsed into a compressed wide BVH8, in
//! the node layout both back ends traverse (`layout::CwBvhNode`).

use crate::packed::binned;
use crate::packed::collapse::{collapse, collapse_with_slots};
use crate::packed::layout::CwBvhNode;
use crate::scene::Triangle;
use glam::{Vec3, Vec3A};
use obvhs::{
    BvhBuildParams, aabb::Aabb, bvh2::reinsertion::ReinsertionOptimizer, ploc::PlocBuilder,
};
use rayon::prelude::*;
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

/// The BVH builds vkpt may use: vkpt's binned-SAH builder, then obvhs'
/// PLOC presets, fastest build first. Each PLOC preset is obvhs' preset of
/// that name without spatial pre-splits, so every triangle sits in exactly
/// one leaf (emitter tables index BVH slots), as in the binned build.
/// Measured on `bumpy-1.31m` of `benches/large_scenes.py`
/// (`examples/bvh_build.rs`; docs/performance.md, "BVH build"):
/// `VeryFast`'s tree is within 1 % of `Medium`'s SAH cost for about 70 %
/// of its build time, `Fastest`'s 8 % above it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuildPreset {
    /// vkpt's parallel binned-SAH builder (`packed::binned`), no
    /// reinsertion.
    BinnedSah,
    /// The binned builder with its ranges of up to 4,096 triangles in
    /// Morton order and coarser bins (`binned::Params::FAST`): a faster
    /// build, a slower tree; only by `VKPT_BVH_PRESET` (a whole render
    /// of bumpy-5m at 64 spp took more CPU time with it).
    BinnedMorton,
    /// PLOC with search distance 1, no reinsertion.
    Fastest,
    /// PLOC with search distance 1, reinsertion of 1 % of the nodes.
    VeryFast,
    /// PLOC with search distance 6 (1 below depth 2), 2 % reinsertion.
    Fast,
    /// PLOC with search distance 14 (1 below depth 3), 5 % reinsertion
    /// and a second pass after the collapse.
    Medium,
}

impl BuildPreset {
    pub const ALL: [BuildPreset; 6] = [
        BuildPreset::BinnedMorton,
        BuildPreset::BinnedSah,
        BuildPreset::Fastest,
        BuildPreset::VeryFast,
        BuildPreset::Fast,
        BuildPreset::Medium,
    ];

    pub fn name(self) -> &'static str {
        match self {
            BuildPreset::BinnedSah => "binned-sah",
            BuildPreset::BinnedMorton => "binned-morton",
            BuildPreset::Fastest => "fastest",
            BuildPreset::VeryFast => "very-fast",
            BuildPreset::Fast => "fast",
            BuildPreset::Medium => "medium",
        }
    }

    /// The preset a scene of `primitives` triangles (or boxes) gets.
    /// `VKPT_BVH_PRESET=<name>` overrides it (benchmarks compare presets
    /// in whole renders; docs/performance.md, "BVH build").
    pub fn for_size(primitives: usize) -> BuildPreset {
        if let Ok(name) = std::env::var("VKPT_BVH_PRESET")
            && let Some(p) = BuildPreset::ALL.into_iter().find(|p| p.name() == name)
        {
            return p;
        }
        if primitives > LARGE_SCENE_PRIMITIVES {
            BuildPreset::BinnedSah
        } else {
            BuildPreset::Medium
        }
    }

    /// The binned builder's parameters, for its presets.
    fn binned(self) -> Option<binned::Params> {
        match self {
            BuildPreset::BinnedSah => Some(binned::Params::FULL),
            BuildPreset::BinnedMorton => Some(binned::Params::FAST),
            _ => None,
        }
    }

    fn params(self) -> BvhBuildParams {
        let mut params = match self {
            BuildPreset::Fastest | BuildPreset::BinnedSah | BuildPreset::BinnedMorton => {
                BvhBuildParams::fastest_build()
            }
            BuildPreset::VeryFast => BvhBuildParams::very_fast_build(),
            BuildPreset::Fast => BvhBuildParams::fast_build(),
            BuildPreset::Medium => BvhBuildParams::medium_build(),
        };
        params.pre_split = false;
        // The CWBVH takes at most 3 per leaf; obvhs' fastest preset asks 1.
        params.max_prims_per_leaf = params.max_prims_per_leaf.max(3);
        params
    }
}

/// Above this many primitives a scene's BVH is built with
/// `BuildPreset::BinnedSah` instead of `Medium`: on bumpy-1.31m and
/// bumpy-5m it builds in about 0.75x PLOC `VeryFast`'s time, renders
/// 1.06-1.07x its samples/s and peaks at 0.58x its memory (the whole
/// process; docs/performance.md, "Memory per triangle"). Smaller scenes
/// build in well under a second either way, and keep the tree every
/// earlier measurement was made with.
pub const LARGE_SCENE_PRIMITIVES: usize = 200_000;

/// obvhs's CWBVH exactly as the renderer builds it with `preset`, before
/// vkpt re-fits the quantized boxes. The traversal benchmark times this
/// raw tree too.
pub fn build_obvhs_cwbvh(triangles: &[Triangle], preset: BuildPreset) -> obvhs::cwbvh::CwBvh {
    build_obvhs_over_boxes(triangles, preset)
}

/// obvhs reads each triangle's box once, into its first nodes: no array of
/// boxes beside the triangles (32 bytes a triangle at the build's peak).
impl obvhs::Boundable for Triangle {
    fn aabb(&self) -> Aabb {
        let [a, b, c] = self.positions.map(Vec3A::from);
        Aabb::new(a.min(b).min(c), a.max(b).max(c))
    }
}

/// obvhs' CWBVH over boxes: PLOC, reinsertion, collapse into 8-wide nodes
/// (`build_cwbvh_from_tris` without pre-splits, on boxes computed once).
fn build_obvhs_over_boxes<T: obvhs::Boundable + Sync>(
    boxes: &[T],
    preset: BuildPreset,
) -> obvhs::cwbvh::CwBvh {
    build_over_boxes_keeping_slots(boxes, preset).0
}

/// A CWBVH, and with the binned builder its binary tree's nodes and each
/// wide node's slots' binary nodes (`collapse_with_slots`), whose boxes
/// are the slots' exact boxes.
type Collapsed = (
    obvhs::cwbvh::CwBvh,
    Option<(Vec<obvhs::bvh2::node::Bvh2Node>, Vec<[u32; 8]>)>,
);

/// `build_obvhs_over_boxes`, keeping what the binned builder's tree says
/// about the slots' exact boxes.
fn build_over_boxes_keeping_slots<T: obvhs::Boundable + Sync>(
    boxes: &[T],
    preset: BuildPreset,
) -> Collapsed {
    let params = preset.params();
    if let Some(binned_params) = preset.binned() {
        let bvh2 = binned::build(boxes, binned_params);
        let (cwbvh, slots) = collapse_with_slots(&bvh2, params.max_prims_per_leaf);
        return (cwbvh, Some((bvh2.nodes, slots)));
    }
    let mut bvh2 = PlocBuilder::with_capacity(boxes.len()).build(
        params.ploc_search_distance,
        boxes,
        (0..boxes.len() as u32).collect(),
        params.sort_precision,
        params.search_depth_threshold,
    );
    if params.reinsertion_batch_ratio > 0.0 {
        ReinsertionOptimizer::default().run(&mut bvh2, params.reinsertion_batch_ratio, None);
    }
    (collapse(&bvh2, params.max_prims_per_leaf), None)
}

/// Builds the BVH with the preset for the scene's size.
pub fn build(triangles: &[Triangle]) -> anyhow::Result<Bvh> {
    build_with(triangles, None, BuildPreset::for_size(triangles.len()))
}

/// Builds the BVH with `preset` (benchmarks compare them).
pub fn build_preset(triangles: &[Triangle], preset: BuildPreset) -> anyhow::Result<Bvh> {
    build_with(triangles, None, preset)
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
    build_with(first, Some(steps), BuildPreset::for_size(first.len()))
}

fn build_with(
    triangles: &[Triangle],
    steps: Option<&[&[Triangle]]>,
    preset: BuildPreset,
) -> anyhow::Result<Bvh> {
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
    let (cwbvh, binary) = match steps {
        None => build_over_boxes_keeping_slots(triangles, preset),
        Some(_) => {
            let boxes: Vec<Aabb> = (0..triangles.len())
                .into_par_iter()
                .map(|i| {
                    let (lo, hi) = leaf_bounds(i);
                    Aabb::new(lo.into(), hi.into())
                })
                .collect();
            build_over_boxes_keeping_slots(&boxes, preset)
        }
    };
    let exact = match &binary {
        Some((nodes, slots)) => ExactBounds::Binary { nodes, slots },
        None => ExactBounds::Leaves(&leaf_bounds),
    };
    finish(cwbvh, triangles.len(), exact, start)
}

/// Where `finish` reads each CWBVH child slot's exact box.
enum ExactBounds<'a> {
    /// Primitive `i`'s box is `leaf_bounds(i)`; a subtree's is the union
    /// of its primitives'.
    Leaves(&'a (dyn Fn(usize) -> Bounds + Sync)),
    /// Slot `s` of wide node `w` holds binary node `slots[w][s]`
    /// (`u32::MAX`: empty), whose box is its primitives' exact union (the
    /// binned builder's are): no primitive is read again.
    Binary {
        nodes: &'a [obvhs::bvh2::node::Bvh2Node],
        slots: &'a [[u32; 8]],
    },
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
    let preset = BuildPreset::for_size(boxes.len());
    let cwbvh = build_obvhs_over_boxes(&aabbs, preset);
    finish(
        cwbvh,
        boxes.len(),
        ExactBounds::Leaves(&|i| boxes[i]),
        start,
    )
}

/// obvhs' tree in vkpt's node layout, its boxes made conservative.
fn finish(
    cwbvh: obvhs::cwbvh::CwBvh,
    count: usize,
    exact: ExactBounds,
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
        .par_iter()
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
    match exact {
        ExactBounds::Leaves(leaf_bounds) => make_conservative(&mut nodes, &order, leaf_bounds)?,
        ExactBounds::Binary {
            nodes: binary,
            slots,
        } => make_conservative_from_binary(&mut nodes, binary, slots)?,
    }
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
    leaf_bounds: &(dyn Fn(usize) -> Bounds + Sync),
) -> anyhow::Result<()> {
    // The leaves' bounds in slot order: a node's leaves then read
    // neighbouring entries instead of triangles scattered over the scene.
    let slot_bounds: Vec<Bounds> = order.par_iter().map(|&i| leaf_bounds(i as usize)).collect();
    const EMPTY: Bounds = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    // A child slot's exact bounds: a leaf's from its triangles, an inner
    // child's from `node_bounds` (None: an empty slot).
    let child_bounds = |n: &CwBvhNode, slot: usize, node_bounds: Option<&[Bounds]>| {
        let meta = byte(n.child_meta, slot);
        if meta == 0 {
            return None;
        }
        let imask = n.e_imask >> 24;
        if imask & (1 << slot) != 0 {
            let inner_before = (imask & ((1 << slot) - 1)).count_ones();
            return Some(
                node_bounds.map_or(EMPTY, |b| b[(n.child_base_idx + inner_before) as usize]),
            );
        }
        let first = n.primitive_base_idx + (meta & 31);
        let mut b = EMPTY;
        for &(lo, hi) in &slot_bounds[first as usize..(first + (meta >> 5).count_ones()) as usize] {
            b = (b.0.min(lo), b.1.max(hi));
        }
        Some(b)
    };
    let union = |a: Bounds, b: Bounds| (a.0.min(b.0), a.1.max(b.1));
    // Each node's leaf children (in parallel: the triangles are most of the
    // work), then its inner children, children first (serial, a few min
    // and max per node).
    let mut node_bounds: Vec<Bounds> = nodes
        .par_iter()
        .map(|n| {
            (0..8)
                .filter(|&slot| (n.e_imask >> 24) & (1 << slot) == 0)
                .filter_map(|slot| child_bounds(n, slot, None))
                .fold(EMPTY, union)
        })
        .collect();
    for index in (0..nodes.len()).rev() {
        let n = &nodes[index];
        let imask = n.e_imask >> 24;
        for k in 0..imask.count_ones() {
            let child = node_bounds[(n.child_base_idx + k) as usize];
            node_bounds[index] = union(node_bounds[index], child);
        }
        let (lo, hi) = node_bounds[index];
        anyhow::ensure!(lo.cmple(hi).all(), "CWBVH node {index} has no children");
    }
    nodes
        .par_iter_mut()
        .enumerate()
        .try_for_each(|(index, node)| {
            let n = *node;
            let children: [Option<Bounds>; 8] =
                std::array::from_fn(|slot| child_bounds(&n, slot, Some(&node_bounds)));
            *node = conservative_node(index, n, node_bounds[index], &children)?;
            anyhow::Ok(())
        })
}

/// `make_conservative` with each slot's exact box read from the binary
/// node it holds (`ExactBounds::Binary`): the same boxes, without reading
/// every primitive's at random (a tenth of the 5 M-triangle build).
fn make_conservative_from_binary(
    nodes: &mut [CwBvhNode],
    binary: &[obvhs::bvh2::node::Bvh2Node],
    slots: &[[u32; 8]],
) -> anyhow::Result<()> {
    anyhow::ensure!(
        slots.len() == nodes.len(),
        "{} CWBVH nodes but {} slot records",
        nodes.len(),
        slots.len()
    );
    nodes
        .par_iter_mut()
        .zip(slots)
        .enumerate()
        .try_for_each(|(index, (node, slots))| {
            let children: [Option<Bounds>; 8] = std::array::from_fn(|slot| {
                let b = binary.get(slots[slot] as usize)?.aabb();
                Some((b.min.into(), b.max.into()))
            });
            let bounds = children
                .iter()
                .flatten()
                .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |a, b| {
                    (a.0.min(b.0), a.1.max(b.1))
                });
            anyhow::ensure!(
                bounds.0.cmple(bounds.1).all(),
                "CWBVH node {index} has no children"
            );
            *node = conservative_node(index, *node, bounds, &children)?;
            anyhow::Ok(())
        })
}

/// `n` with its grid grown and its children's grid bounds re-derived to
/// enclose `children` (the node's exact bounds: `bounds`).
fn conservative_node(
    index: usize,
    n: CwBvhNode,
    (lo, hi): Bounds,
    children: &[Option<Bounds>; 8],
) -> anyhow::Result<CwBvhNode> {
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
    Ok(node)
}

/// The SAH cost of a CWBVH, from its quantized child boxes: each inner
/// child's box area times `NODE_COST` plus each leaf's area times its
/// triangles times `TRIANGLE_COST`, over the root's area (the root's own
/// visit counts `NODE_COST`). A tree quality measure for comparing builds
/// of one scene; lower traces faster (docs/performance.md, "BVH build").
pub fn sah_cost(nodes: &[CwBvhNode]) -> f64 {
    const NODE_COST: f64 = 1.0;
    const TRIANGLE_COST: f64 = 0.3;
    let area = |lo: Vec3, hi: Vec3| {
        let d = (hi - lo).max(Vec3::ZERO).as_dvec3();
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    };
    let per_node = |n: &CwBvhNode| -> (f64, Bounds) {
        let p = Vec3::from(n.p);
        let step = grid_step(n.e_imask);
        let imask = n.e_imask >> 24;
        let mut cost = 0.0;
        let mut bounds = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for slot in 0..8 {
            let meta = byte(n.child_meta, slot);
            if meta == 0 {
                continue;
            }
            let plane =
                |words: [u32; 2], axis: usize| grid_plane(p[axis], step[axis], byte(words, slot));
            let lo = Vec3::new(plane(n.qlo_x, 0), plane(n.qlo_y, 1), plane(n.qlo_z, 2));
            let hi = Vec3::new(plane(n.qhi_x, 0), plane(n.qhi_y, 1), plane(n.qhi_z, 2));
            bounds = (bounds.0.min(lo), bounds.1.max(hi));
            let weight = if imask & (1 << slot) != 0 {
                NODE_COST
            } else {
                TRIANGLE_COST * (meta >> 5).count_ones() as f64
            };
            cost += weight * area(lo, hi);
        }
        (cost, bounds)
    };
    let Some(root) = nodes.first() else {
        return 0.0;
    };
    let (_, (lo, hi)) = per_node(root);
    let root_area = area(lo, hi).max(f64::MIN_POSITIVE);
    let total: f64 = nodes.par_iter().map(|n| per_node(n).0).sum();
    NODE_COST + total / root_area
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

    /// Re-quantizing from the binned builder's binary boxes gives the
    /// same nodes, byte for byte, as from the triangles themselves.
    #[test]
    fn exact_boxes_from_binary_nodes_match_the_triangles() {
        let mut seed = 12345u32;
        let mut next = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1 << 24) as f32 * 10.0 - 5.0
        };
        let tris: Vec<Triangle> = (0..5000)
            .map(|_| {
                let a = [next(), next(), next()];
                let b = [a[0] + next() * 0.1, a[1] + next() * 0.1, a[2]];
                let c = [a[0], a[1] + next() * 0.1, a[2] + next() * 0.1];
                tri(a, b, c)
            })
            .collect();
        let (cwbvh, binary) = build_over_boxes_keeping_slots(&tris, BuildPreset::BinnedSah);
        let (nodes, slots) = binary.expect("the binned builder keeps its binary tree");
        let leaf_bounds = |i: usize| -> Bounds {
            let [a, b, c] = tris[i].positions;
            (a.min(b).min(c), a.max(b).max(c))
        };
        let start = Instant::now();
        let from_binary = finish(
            cwbvh.clone(),
            tris.len(),
            ExactBounds::Binary {
                nodes: &nodes,
                slots: &slots,
            },
            start,
        )
        .unwrap();
        let from_leaves =
            finish(cwbvh, tris.len(), ExactBounds::Leaves(&leaf_bounds), start).unwrap();
        assert!(from_binary.nodes.len() > 100);
        assert!(
            bytemuck::cast_slice::<_, u8>(&from_binary.nodes)
                == bytemuck::cast_slice::<_, u8>(&from_leaves.nodes)
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
