//! A binned-SAH top-down BVH builder for large scenes, vkpt's own: the
//! classic scheme (Wald, "On fast construction of SAH-based bounding volume
//! hierarchies", 2007; the one Embree's and pbrt-v4's builders use) of
//! sorting primitives' centroids into `BINS` equal bins per axis, choosing
//! the bin boundary of least SAH cost over the three axes, partitioning
//! the primitives in place and recursing, down to leaves of up to three
//! primitives (the CWBVH's largest). Ranges of a few primitives are split
//! exactly (every position on each axis, sorted by centre), and small
//! ranges bin on one axis only.
//!
//! On every core: nodes of many primitives bin in fixed chunks that are
//! merged by min, max and integer sums (exact, so in any order), and the
//! two halves of a split build as parallel tasks. Each partition runs on
//! one thread and in place, so the tree (every node's box and primitives)
//! is the same on any run and any number of threads.
//!
//! The result is an obvhs `Bvh2` as `collapse::collapse` reads it. A split
//! takes the next free pair of the node array (`NodeArena`), so the array
//! holds the tree's nodes and no gaps: where the binary nodes sit depends
//! on which thread split first, but the collapse walks down from the root
//! and writes the CWBVH in the tree's own order, which does not. (Places
//! fixed by primitive ranges, `2m - 1` and `2m` for a split at `m`, made
//! the array `2n - 1` long with most of its pages touched: 320 MB for
//! 5 M triangles instead of about 130.)

use glam::Vec3A;
use obvhs::Boundable;
use obvhs::aabb::Aabb;
use obvhs::bvh2::{Bvh2, node::Bvh2Node};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Bins per axis.
const BINS: usize = 16;
/// Nodes above this many primitives bin on every core.
const PARALLEL_BINNING: usize = 1 << 15;
/// Primitives per chunk of parallel binning.
const BIN_CHUNK: usize = 1 << 13;
/// Subtrees above this many primitives build their halves as parallel tasks.
const PARALLEL_SUBTREE: usize = 1 << 10;
/// Ranges of at most this many primitives become leaves: the CWBVH's
/// largest leaf. (Leaves of one primitive, the collapse choosing which to
/// merge, gave SAH cost 5.00 instead of 5.07 on bumpy-1.31m but 2.6 M
/// binary nodes instead of about 0.9 M, and half again the build time.)
const MAX_LEAF: usize = 3;

/// What the builder trades for speed (docs/performance.md, "BVH build").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Params {
    /// Ranges of at most this many primitives (0: none) are ordered by
    /// Morton code and split at its bits (`build_morton`): one sort instead
    /// of a binning pass per level.
    pub morton_below: usize,
    /// Whether each side of a split reads its primitives again for its
    /// centres' exact bounds; otherwise they are taken from its box (twice
    /// the box, within the parent's centre bounds): a pass fewer per level,
    /// bins a little coarser.
    pub exact_centres: bool,
}

impl Params {
    /// Binning down to ranges of `SMALL`, exact centre bounds.
    pub const FULL: Params = Params {
        morton_below: 0,
        exact_centres: true,
    };
    /// Morton order below 4,096 primitives, centre bounds from the boxes:
    /// on bumpy-5m 0.8-0.9x the build's CPU time, but 2 % more SAH cost
    /// and about 6 % more render CPU time, so no scene gets it by default.
    pub const FAST: Params = Params {
        morton_below: 4096,
        exact_centres: false,
    };
}

/// A primitive's box and its index in the input.
#[derive(Clone, Copy, Default)]
#[repr(C, align(32))]
struct Prim {
    lo: [f32; 3],
    index: u32,
    hi: [f32; 3],
    _pad: u32,
}

impl Prim {
    fn lo(&self) -> Vec3A {
        Vec3A::from_array(self.lo)
    }
    fn hi(&self) -> Vec3A {
        Vec3A::from_array(self.hi)
    }
    /// Twice the box's centre (no halving: only comparisons use it).
    fn centre2(&self) -> Vec3A {
        self.lo() + self.hi()
    }
}

/// A box as min and max; empty when min > max.
#[derive(Clone, Copy)]
struct Bounds {
    lo: Vec3A,
    hi: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        lo: Vec3A::splat(f32::MAX),
        hi: Vec3A::splat(f32::MIN),
    };
    fn grow(&mut self, lo: Vec3A, hi: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }
    fn union(self, o: Bounds) -> Bounds {
        Bounds {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }
    fn half_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        (d.x + d.y) * d.z + d.x * d.y
    }
    fn aabb(&self) -> Aabb {
        Aabb::new(self.lo, self.hi)
    }
}

/// The bins of one node: per axis, each bin's box and primitive count.
#[derive(Clone, Copy)]
struct Bins<const B: usize> {
    bounds: [[Bounds; B]; 3],
    counts: [[u32; B]; 3],
}

impl<const B: usize> Bins<B> {
    const EMPTY: Bins<B> = Bins {
        bounds: [[Bounds::EMPTY; B]; 3],
        counts: [[0; B]; 3],
    };
    fn merge(mut self, o: &Bins<B>) -> Bins<B> {
        for axis in 0..3 {
            for b in 0..B {
                self.bounds[axis][b] = self.bounds[axis][b].union(o.bounds[axis][b]);
                self.counts[axis][b] += o.counts[axis][b];
            }
        }
        self
    }
}

/// Maps doubled centres to `B` bins: `(c - origin) * scale`, clamped.
#[derive(Clone, Copy)]
struct Binner<const B: usize> {
    origin: Vec3A,
    scale: Vec3A,
}

impl<const B: usize> Binner<B> {
    fn new(centres: &Bounds) -> Binner<B> {
        let extent = centres.hi - centres.lo;
        // Slightly under B / extent so the largest centre lands in the
        // last bin, not past it; a flat axis puts everything in bin 0.
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(B as f32 * 0.999_99) / extent,
            Vec3A::ZERO,
        );
        Binner {
            origin: centres.lo,
            scale,
        }
    }
    /// The bins of doubled centre `c` on each axis.
    fn bins(&self, c: Vec3A) -> [usize; 3] {
        let x = (c - self.origin) * self.scale;
        [
            clamp_bin::<B>(x.x),
            clamp_bin::<B>(x.y),
            clamp_bin::<B>(x.z),
        ]
    }
    fn bin(&self, c: Vec3A, axis: usize) -> usize {
        clamp_bin::<B>((c[axis] - self.origin[axis]) * self.scale[axis])
    }
    /// Whether a doubled centre coordinate on `axis` falls in a bin below
    /// `s` (1 ..= B - 1): the same arithmetic as `bin`, without the
    /// conversion; the axis's numbers are read once, not per primitive.
    fn below(&self, axis: usize, s: usize) -> impl Fn(f32) -> bool {
        let (origin, scale, s) = (self.origin[axis], self.scale[axis], s as f32);
        move |c| (c - origin) * scale < s
    }
}

/// `x` clamped to a bin of `B` (NaN to bin 0), truncated.
fn clamp_bin<const B: usize>(x: f32) -> usize {
    // f32::max and min return the number when the other is NaN, so the
    // value is in 0 ..= B - 1 and the conversion is exact.
    let x = x.max(0.0).min((B - 1) as f32);
    // SAFETY: x is finite and within u32's range (above).
    unsafe { x.to_int_unchecked::<u32>() as usize }
}

fn bin_prims<const B: usize>(
    prims: &[Prim],
    binner: &Binner<B>,
    bins: &mut Bins<B>,
    axis: Option<usize>,
) {
    if let Some(axis) = axis {
        for p in prims {
            let (lo, hi) = (p.lo(), p.hi());
            let b = binner.bin(lo + hi, axis);
            bins.bounds[axis][b].grow(lo, hi);
            bins.counts[axis][b] += 1;
        }
        return;
    }
    // Neighbours mostly share bins: two sets of bins, even and odd
    // primitives, halve the chains of updates to one bin.
    let mut odd = Bins::<B>::EMPTY;
    let add = |bins: &mut Bins<B>, p: &Prim| {
        let (lo, hi) = (p.lo(), p.hi());
        let b = binner.bins(lo + hi);
        for (axis, &b) in b.iter().enumerate() {
            bins.bounds[axis][b].grow(lo, hi);
            bins.counts[axis][b] += 1;
        }
    };
    let mut pairs = prims.chunks_exact(2);
    for pair in &mut pairs {
        add(bins, &pair[0]);
        add(&mut odd, &pair[1]);
    }
    for p in pairs.remainder() {
        add(bins, p);
    }
    *bins = bins.merge(&odd);
}

/// The split of least SAH cost: (axis, first bin of the right side, left
/// bounds, right bounds), or None when every centre shares one bin.
fn best_split<const B: usize>(
    bins: &Bins<B>,
    only: Option<usize>,
) -> Option<(usize, usize, Bounds, Bounds)> {
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in only.map_or(0..3, |a| a..a + 1) {
        // The cost of bins s.. on the right, for every s.
        let mut right_cost = [0.0f32; B];
        let mut acc = Bounds::EMPTY;
        let mut count = 0u32;
        for s in (1..B).rev() {
            acc = acc.union(bins.bounds[axis][s]);
            count += bins.counts[axis][s];
            right_cost[s] = if count == 0 {
                f32::INFINITY
            } else {
                acc.half_area() * count as f32
            };
        }
        let mut acc = Bounds::EMPTY;
        let mut count = 0u32;
        for (s, &right) in right_cost.iter().enumerate().skip(1) {
            acc = acc.union(bins.bounds[axis][s - 1]);
            count += bins.counts[axis][s - 1];
            if count == 0 {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right;
            if best.is_none_or(|(b, _, _)| cost < b) {
                best = Some((cost, axis, s));
            }
        }
    }
    let (cost, axis, s) = best?;
    if !cost.is_finite() {
        return None;
    }
    let side = |range: std::ops::Range<usize>| {
        bins.bounds[axis][range]
            .iter()
            .fold(Bounds::EMPTY, |a, &b| a.union(b))
    };
    Some((axis, s, side(0..s), side(s..B)))
}

/// A range of primitives to split: its bounds and its centres' bounds.
struct Task<'a> {
    prims: &'a mut [Prim],
    /// Index of `prims[0]` among all primitives.
    first: usize,
    bounds: Bounds,
    /// Its doubled centres' bounds (empty at or below `SMALL`: unused).
    centres: Bounds,
}

/// The binary node array as the builder fills it from several threads:
/// a split takes the next free pair.
struct NodeArena {
    nodes: *mut Bvh2Node,
    capacity: usize,
    next: AtomicUsize,
}

// SAFETY: threads write only the pairs `take_pair` handed each of them,
// and nothing reads the nodes until the build has joined every task.
unsafe impl Sync for NodeArena {}

impl NodeArena {
    /// The index of a pair of nodes no other caller gets.
    fn take_pair(&self) -> usize {
        let pair = self.next.fetch_add(2, Ordering::Relaxed);
        // n primitives split at most n - 1 times: pairs end at 2n - 2.
        assert!(pair + 2 <= self.capacity, "binary node array overflow");
        pair
    }

    /// Writes the pair `take_pair` returned.
    fn write_pair(&self, pair: usize, nodes: [Bvh2Node; 2]) {
        // SAFETY: `pair` and `pair + 1` are within the array (`take_pair`)
        // and this caller's alone.
        unsafe {
            self.nodes.add(pair).write(nodes[0]);
            self.nodes.add(pair + 1).write(nodes[1]);
        }
    }
}

/// The subtree over `task`'s primitives: returns its root, writes its
/// other nodes to pairs it takes from `arena`.
fn build_node(task: Task, arena: &NodeArena, params: Params) -> Bvh2Node {
    let Task {
        prims,
        first,
        bounds,
        centres,
    } = task;
    let n = prims.len();
    if n <= MAX_LEAF {
        return Bvh2Node::new(bounds.aabb(), n as u32, first as u32);
    }
    if n > SMALL && n <= params.morton_below {
        return build_morton(prims, first, &centres, arena);
    }
    let (mid, left, right) = split(prims, &centres, params.exact_centres);
    let (prims_l, prims_r) = prims.split_at_mut(mid);
    let pair = arena.take_pair();
    let task_l = Task {
        prims: prims_l,
        first,
        bounds: left.0,
        centres: left.1,
    };
    let task_r = Task {
        prims: prims_r,
        first: first + mid,
        bounds: right.0,
        centres: right.1,
    };
    let children = if n > PARALLEL_SUBTREE {
        rayon::join(
            || build_node(task_l, arena, params),
            || build_node(task_r, arena, params),
        )
    } else {
        (
            build_node(task_l, arena, params),
            build_node(task_r, arena, params),
        )
    };
    arena.write_pair(pair, [children.0, children.1]);
    Bvh2Node::new(bounds.aabb(), 0, pair as u32)
}

/// Each side of a split: its bounds and its centres' bounds.
type Side = (Bounds, Bounds);

/// The bounds and centre bounds of `prims`.
fn side_of(prims: &[Prim]) -> Side {
    let (mut b, mut c) = (Bounds::EMPTY, Bounds::EMPTY);
    for p in prims {
        b.grow(p.lo(), p.hi());
        let cc = p.centre2();
        c.grow(cc, cc);
    }
    (b, c)
}

/// Ranges of at most this many primitives split by sorting their centres
/// on each axis (every split position evaluated) instead of binning.
const SMALL: usize = 8;
/// Ranges of at most this many primitives bin into 8 bins, larger ones
/// into `BINS`.
const FEW_BINS_BELOW: usize = 256;
/// Ranges of at most this many primitives bin on the axis their centres
/// spread most along only (on bumpy-1.31m: SAH cost 5.10 instead of 5.07
/// with all three axes everywhere, for about a tenth less build time).
const ONE_AXIS_BELOW: usize = 256;

/// Splits `prims` (two or more) in place: returns the left side's length
/// and each side's bounds and centre bounds.
fn split(prims: &mut [Prim], centres: &Bounds, exact_centres: bool) -> (usize, Side, Side) {
    let n = prims.len();
    if n == 2 {
        return (1, small_side(&prims[..1]), small_side(&prims[1..]));
    }
    if n <= SMALL {
        return split_small(prims);
    }
    if n <= FEW_BINS_BELOW {
        split_binned::<8>(prims, centres, exact_centres)
    } else {
        split_binned::<BINS>(prims, centres, exact_centres)
    }
}

/// The exact SAH split of a few primitives: on each axis, sorted by centre
/// (then by input index, so the order is total), every position. Sorts
/// byte indices, not the 32-byte records, and moves the records once.
fn split_small(prims: &mut [Prim]) -> (usize, Side, Side) {
    let n = prims.len();
    let mut best: Option<(f32, usize)> = None;
    let mut best_order: [u8; SMALL] = std::array::from_fn(|i| i as u8);
    for axis in 0..3 {
        // (centre, index) as one integer of the same order: f32::total_cmp's
        // bits above the index.
        let key = |p: &Prim| {
            let bits = (p.lo[axis] + p.hi[axis]).to_bits() as i32;
            let ordered = (bits ^ (((bits >> 31) as u32) >> 1) as i32) as u32 ^ 0x8000_0000;
            (ordered as u64) << 32 | p.index as u64
        };
        let mut keys: [(u64, u8); SMALL] =
            std::array::from_fn(|i| (prims.get(i).map_or(u64::MAX, key), i as u8));
        // Insertion sort: at most 8 entries.
        for k in 1..n {
            let x = keys[k];
            let mut j = k;
            while j > 0 && x.0 < keys[j - 1].0 {
                keys[j] = keys[j - 1];
                j -= 1;
            }
            keys[j] = x;
        }
        let order: [u8; SMALL] = keys.map(|k| k.1);
        let prim = |k: usize| &prims[order[k] as usize];
        let mut right_cost = [0.0f32; SMALL];
        let mut acc = Bounds::EMPTY;
        for k in (1..n).rev() {
            acc.grow(prim(k).lo(), prim(k).hi());
            right_cost[k] = acc.half_area() * (n - k) as f32;
        }
        let mut acc = Bounds::EMPTY;
        let mut improved = false;
        for (k, &right) in right_cost.iter().enumerate().take(n).skip(1) {
            acc.grow(prim(k - 1).lo(), prim(k - 1).hi());
            let cost = acc.half_area() * k as f32 + right;
            if best.is_none_or(|(b, _)| cost < b) {
                best = Some((cost, k));
                improved = true;
            }
        }
        if improved {
            best_order = order;
        }
    }
    let k = best.map_or(n / 2, |(_, k)| k);
    let copy: [Prim; SMALL] = std::array::from_fn(|i| prims.get(i).copied().unwrap_or_default());
    for (p, &i) in prims.iter_mut().zip(&best_order) {
        *p = copy[i as usize];
    }
    (k, small_side(&prims[..k]), small_side(&prims[k..]))
}

/// A side of fewer than `SMALL` primitives: its bounds; its centres are
/// not needed (it is split exactly or is a leaf), so they are left empty.
fn small_side(prims: &[Prim]) -> Side {
    let mut b = Bounds::EMPTY;
    for p in prims {
        b.grow(p.lo(), p.hi());
    }
    (b, Bounds::EMPTY)
}

fn split_binned<const B: usize>(
    prims: &mut [Prim],
    centres: &Bounds,
    exact_centres: bool,
) -> (usize, Side, Side) {
    let n = prims.len();
    let binner = Binner::<B>::new(centres);
    let mut bins = Bins::<B>::EMPTY;
    let only = (n <= ONE_AXIS_BELOW).then(|| {
        let e = centres.hi - centres.lo;
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    });
    if n > PARALLEL_BINNING {
        let parts: Vec<Bins<B>> = prims
            .par_chunks(BIN_CHUNK)
            .map(|c| {
                let mut bins = Bins::<B>::EMPTY;
                bin_prims(c, &binner, &mut bins, only);
                bins
            })
            .collect();
        for part in &parts {
            bins = bins.merge(part);
        }
    } else {
        bin_prims(prims, &binner, &mut bins, only);
    }
    let Some((axis, s, lb, rb)) = best_split(&bins, only) else {
        // Every centre in one bin: halve the range as it lies.
        let mid = n / 2;
        return (mid, side_of(&prims[..mid]), side_of(&prims[mid..]));
    };
    // In place and without branches (a branch per primitive would be
    // mispredicted about half the time; a scratch buffer for one side held
    // up to 32 bytes a primitive on each thread): `prims[l..k]` are the
    // right side's so far, and the primitive read at `k` swaps with the
    // one at `l` whichever side it is on; only a left one advances `l`.
    // (Growing each side's centre bounds in this loop, the other side's
    // masked off, cost more than reading the range again below.)
    let below = binner.below(axis, s);
    let mut mid = 0;
    for k in 0..n {
        let p = prims[k];
        let left = below(p.lo[axis] + p.hi[axis]);
        prims[k] = prims[mid];
        prims[mid] = p;
        mid += left as usize;
    }
    debug_assert!(mid > 0 && mid < n);
    (
        mid,
        (lb, side_centres(&prims[..mid], &lb, centres, exact_centres)),
        (rb, side_centres(&prims[mid..], &rb, centres, exact_centres)),
    )
}

/// A side's doubled centre bounds: exact (`centres_of`), or twice its box
/// `b` within its parent's, `parent`.
fn side_centres(prims: &[Prim], b: &Bounds, parent: &Bounds, exact: bool) -> Bounds {
    if exact || prims.len() <= SMALL {
        return centres_of(prims);
    }
    Bounds {
        lo: (b.lo * 2.0).max(parent.lo),
        hi: (b.hi * 2.0).min(parent.hi),
    }
}

/// The bounds of `prims`' doubled centres, where a split needs them: a
/// side of at most `SMALL` is split exactly or is a leaf, and gets none.
fn centres_of(prims: &[Prim]) -> Bounds {
    if prims.len() <= SMALL {
        return Bounds::EMPTY;
    }
    prims.iter().fold(Bounds::EMPTY, |mut c, p| {
        let cc = p.centre2();
        c.grow(cc, cc);
        c
    })
}

/// Bits per axis of a Morton code.
const MORTON_BITS: u32 = 10;

/// Spreads the low 10 bits of `x` to every third bit.
fn spread_bits(x: u32) -> u32 {
    let x = (x | x << 16) & 0x0300_00FF;
    let x = (x | x << 8) & 0x0300_F00F;
    let x = (x | x << 4) & 0x030C_30C3;
    (x | x << 2) & 0x0924_9249
}

/// The subtree over `prims` (more than `SMALL`) as a linear BVH: sorted by
/// the Morton code of their centres on a cubic grid over `centres` (cubic,
/// so a flat range splits along its long axes first), then split at the
/// highest bit in which a range's first and last codes differ, down to
/// ranges of at most `SMALL`, which split exactly as in the binned build.
/// One sort instead of a binning pass per level; the order is total (code,
/// then place in the range), so the tree is the same on every run.
fn build_morton(prims: &mut [Prim], first: usize, centres: &Bounds, arena: &NodeArena) -> Bvh2Node {
    thread_local! {
        /// Sort keys and a copy of the range, reused: fresh allocations of
        /// this size come from the kernel as zeroed pages each time.
        static SCRATCH: std::cell::RefCell<(Vec<u64>, Vec<Prim>)> = Default::default();
    }
    let extent = (centres.hi - centres.lo).max_element();
    let cells = (1u32 << MORTON_BITS) as f32;
    let scale = if extent > 0.0 {
        cells * 0.999_99 / extent
    } else {
        0.0
    };
    let codes = SCRATCH.with_borrow_mut(|(keys, copy)| {
        keys.clear();
        keys.extend(prims.iter().enumerate().map(|(k, p)| {
            let q = ((p.centre2() - centres.lo) * scale)
                .max(Vec3A::ZERO)
                .min(Vec3A::splat(cells - 1.0));
            let code = spread_bits(q.x as u32) << 2
                | spread_bits(q.y as u32) << 1
                | spread_bits(q.z as u32);
            (code as u64) << 32 | k as u64
        }));
        keys.sort_unstable();
        copy.clear();
        copy.extend_from_slice(prims);
        for (p, &key) in prims.iter_mut().zip(keys.iter()) {
            *p = copy[key as u32 as usize];
        }
        keys.iter()
            .map(|&key| (key >> 32) as u32)
            .collect::<Vec<u32>>()
    });
    morton_node(prims, &codes, first, arena).0
}

/// The subtree over Morton-sorted `prims` (`codes` theirs) and its bounds.
fn morton_node(
    prims: &mut [Prim],
    codes: &[u32],
    first: usize,
    arena: &NodeArena,
) -> (Bvh2Node, Bounds) {
    let n = prims.len();
    if n <= SMALL {
        let (bounds, centres) = small_side(prims);
        let task = Task {
            prims,
            first,
            bounds,
            centres,
        };
        return (build_node(task, arena, Params::FULL), bounds);
    }
    let (a, z) = (codes[0], codes[n - 1]);
    let mid = if a == z {
        n / 2
    } else {
        // The first code with the highest differing bit set. (Choosing by
        // SAH cost among the cell boundaries of the three bit levels from
        // there down gave 5.47 instead of 5.48 on bumpy-5m.)
        let mask = u32::MAX << (31 - (a ^ z).leading_zeros());
        codes.partition_point(|&c| c & mask < z & mask)
    };
    let pair = arena.take_pair();
    let (prims_l, prims_r) = prims.split_at_mut(mid);
    let (l, lb) = morton_node(prims_l, &codes[..mid], first, arena);
    let (r, rb) = morton_node(prims_r, &codes[mid..], first + mid, arena);
    arena.write_pair(pair, [l, r]);
    let b = lb.union(rb);
    (Bvh2Node::new(b.aabb(), 0, pair as u32), b)
}

/// The binary BVH over `items`' boxes, leaves of up to `MAX_LEAF`
/// primitives.
pub fn build<T: Boundable + Sync>(items: &[T], params: Params) -> Bvh2 {
    let n = items.len();
    if n == 0 {
        return Bvh2::default();
    }
    let mut prims: Vec<Prim> = crate::huge_pages::with_capacity(n);
    prims.par_extend(items.par_iter().enumerate().map(|(i, item)| {
        let b = item.aabb();
        Prim {
            lo: b.min.to_array(),
            index: i as u32,
            hi: b.max.to_array(),
            _pad: 0,
        }
    }));
    let (bounds, centres) = prims
        .par_chunks(BIN_CHUNK)
        .map(|ps| {
            let (mut b, mut c) = (Bounds::EMPTY, Bounds::EMPTY);
            for p in ps {
                b.grow(p.lo(), p.hi());
                let cc = p.centre2();
                c.grow(cc, cc);
            }
            (b, c)
        })
        .reduce(
            || (Bounds::EMPTY, Bounds::EMPTY),
            |a, b| (a.0.union(b.0), a.1.union(b.1)),
        );
    // Zeroed pages: only the nodes the tree has become resident.
    let mut nodes: Vec<Bvh2Node> = crate::huge_pages::zeroed_vec(2 * n - 1);
    let arena = NodeArena {
        nodes: nodes.as_mut_ptr(),
        capacity: nodes.len(),
        next: AtomicUsize::new(1),
    };
    let root = build_node(
        Task {
            prims: &mut prims,
            first: 0,
            bounds,
            centres,
        },
        &arena,
        params,
    );
    let used = arena.next.into_inner();
    nodes[0] = root;
    nodes.truncate(used);
    nodes.shrink_to_fit();
    let mut bvh = Bvh2::zeroed(0);
    bvh.nodes = nodes;
    bvh.primitive_indices = prims.par_iter().map(|p| p.index).collect();
    bvh
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packed::bvh::{self, BuildPreset, byte, grid_plane, grid_step};
    use crate::packed::collapse;
    use crate::packed::layout::CwBvhNode;
    use crate::scene::Triangle;
    use glam::Vec3;

    /// A deterministic stream of floats in [0, 1).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }
        fn vec(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next())
        }
    }

    /// `n` random triangles in the unit cube, each within `size` of its
    /// first vertex.
    fn triangles(n: usize, size: f32, seed: u64) -> Vec<Triangle> {
        let mut r = Lcg(seed);
        (0..n)
            .map(|_| {
                let a = r.vec();
                let b = a + (r.vec() - 0.5) * size;
                let c = a + (r.vec() - 0.5) * size;
                Triangle {
                    positions: [a, b, c],
                    normals: [Vec3::Z; 3],
                    material: 0,
                }
            })
            .collect()
    }

    fn contains(outer: &Aabb, inner: &Aabb) -> bool {
        outer.min.cmple(inner.min).all() && outer.max.cmpge(inner.max).all()
    }

    /// Checks the binary tree under `node`: its box is the union of its
    /// children's (of its primitives' at a leaf); counts each primitive.
    fn check_bvh2(bvh: &Bvh2, items: &[Triangle], node: usize, seen: &mut [u32]) {
        let n = &bvh.nodes[node];
        if n.prim_count != 0 {
            for k in 0..n.prim_count {
                let i = bvh.primitive_indices[(n.first_index + k) as usize] as usize;
                seen[i] += 1;
                assert!(contains(n.aabb(), &items[i].aabb()), "leaf {node}");
            }
            return;
        }
        for child in [n.first_index as usize, n.first_index as usize + 1] {
            assert!(
                contains(n.aabb(), bvh.nodes[child].aabb()),
                "node {node}'s box does not hold child {child}'s"
            );
            check_bvh2(bvh, items, child, seen);
        }
    }

    /// The decoded box of slot `slot` of `n`, as traversal computes it.
    fn slot_box(n: &CwBvhNode, slot: usize) -> (Vec3, Vec3) {
        let p = Vec3::from(n.p);
        let step = grid_step(n.e_imask);
        let plane = |w: [u32; 2], axis: usize| grid_plane(p[axis], step[axis], byte(w, slot));
        (
            Vec3::new(plane(n.qlo_x, 0), plane(n.qlo_y, 1), plane(n.qlo_z, 2)),
            Vec3::new(plane(n.qhi_x, 0), plane(n.qhi_y, 1), plane(n.qhi_z, 2)),
        )
    }

    /// Each occupied slot of `node`: Ok(inner node index) or Err(slots of
    /// its triangles).
    fn slots(n: &CwBvhNode) -> Vec<(usize, Result<usize, std::ops::Range<usize>>)> {
        let imask = n.e_imask >> 24;
        (0..8)
            .filter(|&slot| byte(n.child_meta, slot) != 0)
            .map(|slot| {
                let meta = byte(n.child_meta, slot);
                if imask & (1 << slot) != 0 {
                    let before = (imask & ((1 << slot) - 1)).count_ones();
                    (slot, Ok((n.child_base_idx + before) as usize))
                } else {
                    let first = (n.primitive_base_idx + (meta & 31)) as usize;
                    (slot, Err(first..first + (meta >> 5).count_ones() as usize))
                }
            })
            .collect()
    }

    /// The triangles under `node`, checking every slot's decoded box holds
    /// its subtree's triangles.
    fn check_cwbvh(
        tree: &bvh::Bvh,
        tris: &[Triangle],
        node: usize,
        seen: &mut [u32],
    ) -> Vec<usize> {
        let n = &tree.nodes[node];
        let mut all = Vec::new();
        for (slot, child) in slots(n) {
            let under: Vec<usize> = match &child {
                Ok(inner) => check_cwbvh(tree, tris, *inner, seen),
                Err(range) => range.clone().map(|s| tree.order[s] as usize).collect(),
            };
            let (lo, hi) = slot_box(n, slot);
            for &i in &under {
                for v in tris[i].positions {
                    assert!(
                        lo.cmple(v).all() && v.cmple(hi).all(),
                        "node {node} slot {slot}: triangle {i} outside its box"
                    );
                }
            }
            if child.is_err() {
                under.iter().for_each(|&i| seen[i] += 1);
            }
            all.extend(under);
        }
        all
    }

    fn hit_triangle(t: &Triangle, o: Vec3, d: Vec3) -> Option<f32> {
        let [a, b, c] = t.positions;
        let (e1, e2) = (b - a, c - a);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let tv = o - a;
        let u = tv.dot(pv) * inv;
        let qv = tv.cross(e1);
        let v = d.dot(qv) * inv;
        let t = e2.dot(qv) * inv;
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
    }

    fn hit_box((lo, hi): (Vec3, Vec3), o: Vec3, inv_d: Vec3, t_max: f32) -> bool {
        let (t0, t1) = ((lo - o) * inv_d, (hi - o) * inv_d);
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element().min(t_max);
        near <= far
    }

    /// The nearest hit (distance, triangle; the lower index on a tie) by
    /// a stack walk of the CWBVH.
    fn nearest(tree: &bvh::Bvh, tris: &[Triangle], o: Vec3, d: Vec3) -> Option<(f32, usize)> {
        let inv_d = d.recip();
        let mut best: Option<(f32, usize)> = None;
        let mut stack = vec![0usize];
        while let Some(node) = stack.pop() {
            let n = &tree.nodes[node];
            for (slot, child) in slots(n) {
                let t_max = best.map_or(f32::INFINITY, |b| b.0);
                if !hit_box(slot_box(n, slot), o, inv_d, t_max) {
                    continue;
                }
                match child {
                    Ok(inner) => stack.push(inner),
                    Err(range) => {
                        for s in range {
                            let i = tree.order[s] as usize;
                            if let Some(t) = hit_triangle(&tris[i], o, d)
                                && best.is_none_or(|b| (t, i) < b)
                            {
                                best = Some((t, i));
                            }
                        }
                    }
                }
            }
        }
        best
    }

    /// The binned builder's tree holds every triangle once, each box holds
    /// its children, and its CWBVH finds the same nearest hits as the
    /// `medium` preset's tree on random rays: with binning only, and with
    /// a Morton-ordered bottom (`Params::FAST`, and below 64 primitives, so
    /// that both parts meet in one tree).
    #[test]
    fn binned_tree_is_valid_and_finds_the_nearest_hits() {
        let params = [
            Params::FULL,
            Params::FAST,
            Params {
                morton_below: 64,
                exact_centres: false,
            },
        ];
        for (n, size, seed) in [
            (1, 0.1, 1),
            (2, 0.1, 2),
            (3, 0.1, 3),
            (9, 0.1, 6),
            (4000, 0.05, 4),
            (3000, 0.4, 5),
        ] {
            let tris = triangles(n, size, seed);
            for p in params {
                let bvh2 = build(&tris, p);
                let mut seen = vec![0u32; n];
                check_bvh2(&bvh2, &tris, 0, &mut seen);
                assert!(
                    seen.iter().all(|&c| c == 1),
                    "{n} triangles, {p:?}: binary tree"
                );
                assert_eq!(count_reachable(&bvh2, 0), bvh2.nodes.len(), "{p:?}");
            }

            let theirs = bvh::build_preset(&tris, BuildPreset::Medium).unwrap();
            for preset in [BuildPreset::BinnedSah, BuildPreset::BinnedMorton] {
                let ours = bvh::build_preset(&tris, preset).unwrap();
                let mut seen = vec![0u32; n];
                let under = check_cwbvh(&ours, &tris, 0, &mut seen);
                assert_eq!(under.len(), n);
                assert!(seen.iter().all(|&c| c == 1), "{n} triangles: CWBVH");

                let mut r = Lcg(seed * 77);
                let mut hits = 0;
                for _ in 0..2000 {
                    let o = r.vec() * 1.4 - 0.2;
                    let d = (r.vec() - 0.5).normalize_or(Vec3::X);
                    let a = nearest(&ours, &tris, o, d);
                    assert_eq!(
                        a,
                        nearest(&theirs, &tris, o, d),
                        "{n} triangles, {preset:?}, ray {o} {d}"
                    );
                    hits += a.is_some() as usize;
                }
                assert!(n < 100 || hits > 100, "{n} triangles: only {hits} hits");
            }
        }
    }

    /// Many copies of one triangle and a few others: Morton codes and bins
    /// that cannot separate them still give a valid tree.
    #[test]
    fn coincident_triangles_build_a_valid_tree() {
        let mut tris = triangles(5, 0.1, 7);
        tris.extend(std::iter::repeat_n(tris[0], 3000));
        for p in [
            Params::FULL,
            Params::FAST,
            Params {
                morton_below: 64,
                exact_centres: false,
            },
        ] {
            let bvh2 = build(&tris, p);
            let mut seen = vec![0u32; tris.len()];
            check_bvh2(&bvh2, &tris, 0, &mut seen);
            assert!(seen.iter().all(|&c| c == 1), "{p:?}");
            assert_eq!(count_reachable(&bvh2, 0), bvh2.nodes.len(), "{p:?}");
        }
    }

    /// The same tree on one thread as on several (the parallel binning and
    /// subtrees included), and on every run: the same primitive order and
    /// the same CWBVH, node for node (the binary nodes' places in their
    /// array may differ), and no unused binary node.
    #[test]
    fn binned_tree_is_deterministic() {
        let tris = triangles(100_000, 0.02, 9);
        for params in [Params::FULL, Params::FAST] {
            deterministic_with(&tris, params);
        }
    }

    fn deterministic_with(tris: &[Triangle], params: Params) {
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let bvh2 = build(tris, params);
                let reachable = count_reachable(&bvh2, 0);
                assert_eq!(reachable, bvh2.nodes.len(), "{threads} threads");
                (bvh2.primitive_indices.clone(), collapse::collapse(&bvh2, 3))
            })
        };
        let (one_order, one) = on(1);
        for threads in [2, 3, 8] {
            let (order, other) = on(threads);
            assert_eq!(one_order, order, "{threads} threads, {params:?}");
            assert_eq!(
                one.primitive_indices, other.primitive_indices,
                "{threads} threads, {params:?}"
            );
            assert!(
                bytemuck::cast_slice::<_, u8>(&one.nodes)
                    == bytemuck::cast_slice::<_, u8>(&other.nodes),
                "{threads} threads, {params:?}"
            );
        }
    }

    /// Nodes reachable from `node`, itself included.
    fn count_reachable(bvh2: &Bvh2, node: usize) -> usize {
        let n = &bvh2.nodes[node];
        if n.prim_count != 0 {
            return 1;
        }
        let first = n.first_index as usize;
        1 + count_reachable(bvh2, first) + count_reachable(bvh2, first + 1)
    }
}
