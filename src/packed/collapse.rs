//! A binary BVH collapsed into the compressed wide BVH8 the kernels read:
//! the dynamic program of Ylitie, Karras and Laine (HPG 2017, section 4.1)
//! that chooses which binary nodes become wide nodes, leaves of up to three
//! triangles, or children spread over a parent's eight slots, then the
//! nodes encoded with their children in ray-octant order. It makes the
//! decisions obvhs' `bvh2_to_cwbvh` makes (the same costs, compared in the
//! same order) and writes the same node layout, but on every core: both
//! passes split at the top of the tree (`rayon::join`), and the node and
//! triangle ranges of each subtree are known from a counting pass before
//! it is written. It also keeps one byte per decision instead of eight,
//! which matters at the build's memory peak (docs/performance.md, "BVH
//! build" and "Memory per triangle").

use glam::{UVec3, Vec3A};
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::{CwBvh, node::CwBvhNode};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// The SAH cost of a triangle relative to a node (obvhs' `PRIM_COST`).
const PRIM_COST: f32 = 0.3;
/// Binary levels (cost pass) and wide levels (counting and writing) from
/// the root down that split into parallel tasks; below, a task runs
/// serially.
const PARALLEL_BINARY_LEVELS: u32 = 12;
const PARALLEL_WIDE_LEVELS: u32 = 4;

const LEAF: u8 = 0;
const INTERNAL: u8 = 1;
const DISTRIBUTE: u8 = 2;

/// One decision of the program: what a binary node becomes when it is to
/// fill `i + 1` slots. `kind` in bits 0-1, the left child's slot count
/// minus one in bits 2-4, the right child's in bits 5-7.
#[derive(Clone, Copy)]
struct Decision(u8);

impl Decision {
    fn new(kind: u8, left: u8, right: u8) -> Decision {
        Decision(kind | (left & 7) << 2 | (right & 7) << 5)
    }
    fn kind(self) -> u8 {
        self.0 & 3
    }
    fn left(self) -> usize {
        ((self.0 >> 2) & 7) as usize
    }
    fn right(self) -> usize {
        (self.0 >> 5) as usize
    }
}

/// The seven decisions of every binary node, a word each.
struct Decisions(Vec<AtomicU64>);

impl Decisions {
    fn get(&self, node: usize, i: usize) -> Decision {
        Decision((self.0[node].load(Ordering::Relaxed) >> (8 * i)) as u8)
    }
    fn set(&self, node: usize, d: [Decision; 7]) {
        let word = d
            .iter()
            .enumerate()
            .fold(0u64, |w, (i, d)| w | (d.0 as u64) << (8 * i));
        self.0[node].store(word, Ordering::Relaxed);
    }
}

/// The CWBVH of `bvh2` (whose leaves hold one primitive each, as PLOC
/// builds it), at most `max_prims_per_leaf` (1-3) primitives per leaf.
pub fn collapse(bvh2: &Bvh2, max_prims_per_leaf: u32) -> CwBvh {
    collapse_with_slots(bvh2, max_prims_per_leaf).0
}

/// `collapse`, and for each wide node the binary node in each of its
/// slots (`u32::MAX`: an empty slot): where the slots' exact boxes are,
/// so they need not be recomputed from the primitives.
pub fn collapse_with_slots(bvh2: &Bvh2, max_prims_per_leaf: u32) -> (CwBvh, Vec<[u32; 8]>) {
    if bvh2.nodes.is_empty() {
        return (CwBvh::default(), Vec::new());
    }
    let decisions = Decisions((0..bvh2.nodes.len()).map(|_| AtomicU64::new(0)).collect());
    let c = Collapse {
        bvh2,
        decisions,
        counts: (0..bvh2.nodes.len()).map(|_| AtomicU64::new(0)).collect(),
        max_prims: max_prims_per_leaf.clamp(1, 3),
    };
    c.cost(0, 0);
    let (node_count, prim_count) = c.count(0, 0);
    let mut nodes: Vec<CwBvhNode> = crate::huge_pages::zeroed_vec(node_count as usize);
    let mut slots = vec![[u32::MAX; 8]; node_count as usize];
    let mut prims = vec![0u32; prim_count as usize];
    let (root, descendants) = nodes.split_at_mut(1);
    let (root_slots, slot_descendants) = slots.split_at_mut(1);
    (root[0], root_slots[0]) = c.write(
        0,
        0,
        Out {
            base: 1,
            nodes: descendants,
            slots: slot_descendants,
            prim_base: 0,
            prims: &mut prims,
        },
    );
    let cwbvh = CwBvh {
        nodes,
        primitive_indices: prims,
        total_aabb: *bvh2.nodes[0].aabb(),
        exact_node_aabbs: None,
        uses_spatial_splits: false,
    };
    (cwbvh, slots)
}

/// Where a wide node's subtree goes: its descendants (`base` is the index
/// of `nodes[0]`), their slots' binary nodes, and its primitives
/// (`prim_base` is the index of `prims[0]`).
struct Out<'a> {
    base: u32,
    nodes: &'a mut [CwBvhNode],
    slots: &'a mut [[u32; 8]],
    prim_base: u32,
    prims: &'a mut [u32],
}

struct Collapse<'a> {
    bvh2: &'a Bvh2,
    decisions: Decisions,
    /// Wide nodes and primitives under each binary node that is a wide
    /// node (`count`), packed `nodes << 32 | primitives`.
    counts: Vec<AtomicU64>,
    max_prims: u32,
}

impl Collapse<'_> {
    /// Fills the decisions of `node`'s subtree; returns the cost of
    /// filling 1..=7 slots with it, and its primitive count.
    fn cost(&self, node: usize, depth: u32) -> ([f32; 7], u32) {
        let n = &self.bvh2.nodes[node];
        let half_area = n.aabb().half_area();
        if n.prim_count != 0 {
            let leaf = half_area * n.prim_count as f32 * PRIM_COST;
            self.decisions.set(node, [Decision::new(LEAF, 0, 0); 7]);
            return ([leaf; 7], n.prim_count);
        }
        let (l, r) = (n.first_index as usize, n.first_index as usize + 1);
        let ((left, lp), (right, rp)) = if depth < PARALLEL_BINARY_LEVELS {
            rayon::join(|| self.cost(l, depth + 1), || self.cost(r, depth + 1))
        } else {
            (self.cost(l, depth + 1), self.cost(r, depth + 1))
        };
        let prims = lp + rp;
        let mut cost = [0.0f32; 7];
        let mut d = [Decision::new(LEAF, 0, 0); 7];
        // i = 0: a leaf of all its triangles, or a wide node whose slots
        // the two children share.
        let leaf = if prims <= self.max_prims {
            prims as f32 * half_area * PRIM_COST
        } else {
            f32::INFINITY
        };
        let (mut best, mut best_k) = (f32::INFINITY, 7);
        for k in 0..7 {
            let c = left[k] + right[6 - k];
            if c < best {
                (best, best_k) = (c, k);
            }
        }
        let internal = best + half_area;
        let (kl, kr) = if best_k < 7 {
            (best_k as u8, 6 - best_k as u8)
        } else {
            (7, 7)
        };
        (cost[0], d[0]) = if leaf < internal {
            (leaf, Decision::new(LEAF, kl, kr))
        } else {
            (internal, Decision::new(INTERNAL, kl, kr))
        };
        // i > 0: the children spread over i + 1 slots, or fewer.
        for i in 1..7 {
            let mut best = cost[i - 1];
            let mut split = None;
            for k in 0..i {
                let c = left[k] + right[i - k - 1];
                if c < best {
                    best = c;
                    split = Some(k);
                }
            }
            cost[i] = best;
            d[i] = match split {
                Some(k) => Decision::new(DISTRIBUTE, k as u8, (i - k - 1) as u8),
                None => d[i - 1],
            };
        }
        self.decisions.set(node, d);
        (cost, prims)
    }

    /// The slots of the wide node made of binary node `node` with `i + 1`
    /// slots: binary nodes that are leaves or wide nodes of their own.
    fn children(&self, node: usize, i: usize, out: &mut [u32; 8], count: &mut usize) {
        let n = &self.bvh2.nodes[node];
        if n.prim_count != 0 {
            out[*count] = node as u32;
            *count += 1;
            return;
        }
        let d = self.decisions.get(node, i);
        for (child, slots) in [(n.first_index, d.left()), (n.first_index + 1, d.right())] {
            if self.decisions.get(child as usize, slots).kind() == DISTRIBUTE {
                self.children(child as usize, slots, out, count);
            } else {
                out[*count] = child;
                *count += 1;
            }
        }
    }

    /// Appends the primitives under binary node `node`, left first, to
    /// `out[*len..]`.
    fn leaf_prims(&self, node: usize, out: &mut [u32], len: &mut usize) {
        let n = &self.bvh2.nodes[node];
        if n.prim_count != 0 {
            let (first, count) = (n.first_index as usize, n.prim_count as usize);
            out[*len..*len + count]
                .copy_from_slice(&self.bvh2.primitive_indices[first..first + count]);
            *len += count;
        } else {
            self.leaf_prims(n.first_index as usize, out, len);
            self.leaf_prims(n.first_index as usize + 1, out, len);
        }
    }

    /// The wide node made of `node`: its slots in ray-octant order.
    fn slots(&self, node: usize) -> ([u32; 8], usize) {
        let mut children = [u32::MAX; 8];
        let mut count = 0;
        self.children(node, 0, &mut children, &mut count);
        (self.order(node, children, count), count)
    }

    /// Wide nodes and primitives in `node`'s subtree (it a wide node),
    /// remembered in `counts` for `write`.
    fn count(&self, node: usize, depth: u32) -> (u32, u32) {
        // The slots' order does not change the counts.
        let mut slots = [u32::MAX; 8];
        let mut count = 0;
        self.children(node, 0, &mut slots, &mut count);
        let mut inner = [0usize; 8];
        let mut inner_count = 0;
        let mut prims = 0;
        for &c in &slots[..count] {
            if self.is_wide(c as usize) {
                inner[inner_count] = c as usize;
                inner_count += 1;
            } else {
                prims += self.prim_count(c as usize);
            }
        }
        let inner = &inner[..inner_count];
        let add = |(n, p): (u32, u32), (cn, cp): (u32, u32)| (n + cn, p + cp);
        let (n, p) = if depth < PARALLEL_WIDE_LEVELS {
            let sub = inner
                .par_iter()
                .map(|&c| self.count(c, depth + 1))
                .reduce(|| (0, 0), add);
            add((1, prims), sub)
        } else {
            inner
                .iter()
                .map(|&c| self.count(c, depth + 1))
                .fold((1, prims), add)
        };
        self.counts[node].store((n as u64) << 32 | p as u64, Ordering::Relaxed);
        (n, p)
    }

    fn is_wide(&self, node: usize) -> bool {
        self.bvh2.nodes[node].prim_count == 0 && self.decisions.get(node, 0).kind() == INTERNAL
    }

    fn prim_count(&self, node: usize) -> u32 {
        let n = &self.bvh2.nodes[node];
        if n.prim_count != 0 {
            n.prim_count
        } else {
            self.prim_count(n.first_index as usize) + self.prim_count(n.first_index as usize + 1)
        }
    }

    /// Encodes wide node `node` and returns it with its slots' binary
    /// nodes, writing to `out` its descendants (its inner children first,
    /// then each child's descendants in slot order) and its primitives
    /// (its leaves' first, then each inner child's).
    fn write(&self, node: usize, depth: u32, out: Out) -> (CwBvhNode, [u32; 8]) {
        let aabb = *self.bvh2.nodes[node].aabb();
        let (slots, _) = self.slots(node);
        let p = aabb.min;
        let e = ((aabb.max - aabb.min).max(Vec3A::splat(1e-20)) * (1.0 / 255.0))
            .log2()
            .ceil()
            .exp2();
        let rcp_e = 1.0 / e;
        let e_bits = UVec3::new(e.x.to_bits(), e.y.to_bits(), e.z.to_bits()) >> 23u32;
        let mut wide = CwBvhNode {
            p: p.into(),
            e: [e_bits.x as u8, e_bits.y as u8, e_bits.z as u8],
            imask: 0,
            child_base_idx: out.base,
            primitive_base_idx: out.prim_base,
            ..Default::default()
        };
        let mut own_prims = 0;
        let mut inner = [0usize; 8];
        let mut inner_count = 0;
        for (slot, &c) in slots.iter().enumerate() {
            if c == u32::MAX {
                continue;
            }
            let child = self.bvh2.nodes[c as usize].aabb();
            let lo = ((child.min - p) * rcp_e)
                .floor()
                .clamp(Vec3A::ZERO, Vec3A::splat(255.0));
            let hi = ((child.max - p) * rcp_e)
                .ceil()
                .clamp(Vec3A::ZERO, Vec3A::splat(255.0));
            wide.child_min_x[slot] = lo.x as u8;
            wide.child_min_y[slot] = lo.y as u8;
            wide.child_min_z[slot] = lo.z as u8;
            wide.child_max_x[slot] = hi.x as u8;
            wide.child_max_y[slot] = hi.y as u8;
            wide.child_max_z[slot] = hi.z as u8;
            if self.is_wide(c as usize) {
                wide.imask |= 1 << slot;
                wide.child_meta[slot] = (24 + slot as u8) | 0b0010_0000;
                inner[inner_count] = c as usize;
                inner_count += 1;
            } else {
                let first = own_prims as u8;
                self.leaf_prims(c as usize, out.prims, &mut own_prims);
                let count = own_prims as u8 - first;
                debug_assert!((1..=3).contains(&count));
                // The count in unary in the top three bits.
                wide.child_meta[slot] = first | ((1u8 << count) - 1) << 5;
            }
        }
        let inner = &inner[..inner_count];
        let (block, mut rest) = out.nodes.split_at_mut(inner.len());
        let (slot_block, mut slot_rest) = out.slots.split_at_mut(inner.len());
        let mut rest_prims = &mut out.prims[own_prims..];
        let mut next = out.base + inner.len() as u32;
        let mut next_prim = out.prim_base + own_prims as u32;
        // Each inner child's share of the ranges, from the counting pass.
        let run = |(c, to, node, node_slots): (usize, Out, &mut CwBvhNode, &mut [u32; 8])| {
            (*node, *node_slots) = self.write(c, depth + 1, to);
        };
        let mut jobs = Vec::new();
        for ((&c, node), node_slots) in inner.iter().zip(block).zip(slot_block) {
            let w = self.counts[c].load(Ordering::Relaxed);
            let (n, p) = ((w >> 32) as u32, w as u32);
            let (mine, tail) = rest.split_at_mut(n as usize - 1);
            let (my_slots, slot_tail) = slot_rest.split_at_mut(n as usize - 1);
            let (my_prims, prim_tail) = rest_prims.split_at_mut(p as usize);
            let to = Out {
                base: next,
                nodes: mine,
                slots: my_slots,
                prim_base: next_prim,
                prims: my_prims,
            };
            if depth < PARALLEL_WIDE_LEVELS {
                jobs.push((c, to, node, node_slots));
            } else {
                run((c, to, node, node_slots));
            }
            next += n - 1;
            next_prim += p;
            rest = tail;
            slot_rest = slot_tail;
            rest_prims = prim_tail;
        }
        jobs.into_par_iter().for_each(run);
        (wide, slots)
    }

    /// `children`'s first `count` entries placed in the slots whose
    /// octant direction their centres lie farthest along (greedy, as
    /// obvhs orders them): a ray then meets the slots in order `s ^ oct`.
    fn order(&self, node: usize, children: [u32; 8], count: usize) -> [u32; 8] {
        let centre = self.bvh2.nodes[node].aabb().center();
        let mut cost = [[f32::MAX; 8]; 8];
        for (s, row) in (0..8).map(|s| {
            let d = Vec3A::new(
                if s & 4 != 0 { -1.0 } else { 1.0 },
                if s & 2 != 0 { -1.0 } else { 1.0 },
                if s & 1 != 0 { -1.0 } else { 1.0 },
            );
            (s, d)
        }) {
            for c in 0..count {
                let v = self.bvh2.nodes[children[c] as usize].aabb().center() - centre;
                cost[c][s] = row.dot(v);
            }
        }
        let mut assignment = [usize::MAX; 8];
        let mut filled = [false; 8];
        loop {
            let (mut best, mut slot, mut index) = (f32::MAX, usize::MAX, usize::MAX);
            for c in 0..count {
                if assignment[c] != usize::MAX {
                    continue;
                }
                for s in 0..8 {
                    if !filled[s] && cost[c][s] < best {
                        (best, slot, index) = (cost[c][s], s, c);
                    }
                }
            }
            if slot == usize::MAX {
                break;
            }
            filled[slot] = true;
            assignment[index] = slot;
        }
        let mut out = [u32::MAX; 8];
        for c in 0..count {
            out[assignment[c]] = children[c];
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use obvhs::aabb::Aabb;
    use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};

    /// Boxes of a bumpy sheet of `n` small triangles, deterministic.
    fn boxes(n: usize) -> Vec<Aabb> {
        (0..n)
            .map(|i| {
                let x = (i % 97) as f32 * 0.3 + (i as f32 * 0.618).fract();
                let z = (i / 97) as f32 * 0.3;
                let y = (x * 1.3).sin() * (z * 0.7).cos();
                let lo = Vec3A::new(x, y, z);
                Aabb::new(lo, lo + Vec3A::new(0.4, 0.1 + (i % 5) as f32 * 0.05, 0.35))
            })
            .collect()
    }

    /// The same tree as obvhs' serial collapse, node for node and slot for
    /// slot, at every leaf size.
    #[test]
    fn collapse_matches_obvhs() {
        for n in [1, 2, 3, 5, 40, 3000, 20_000] {
            let boxes = boxes(n);
            let bvh2 = PlocBuilder::with_capacity(n).build(
                PlocSearchDistance::Minimum,
                &boxes,
                (0..n as u32).collect(),
                SortPrecision::U64,
                0,
            );
            for max_prims in 1..=3 {
                let theirs =
                    obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh(&bvh2, max_prims, true, false);
                let ours = collapse(&bvh2, max_prims);
                assert_eq!(
                    ours.nodes.len(),
                    theirs.nodes.len(),
                    "{n} boxes, {max_prims} per leaf"
                );
                assert!(
                    ours.nodes == theirs.nodes,
                    "{n} boxes, {max_prims} per leaf"
                );
                assert_eq!(ours.primitive_indices, theirs.primitive_indices);
            }
        }
    }
}
