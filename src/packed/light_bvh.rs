//! Host side of the light BVH: a binary tree over every light that is not
//! at infinity (emissive triangles, spheres, point and spot lights), each
//! node bounding its lights' positions, total power and the cone of
//! directions they emit into, after Conty Estevez and Kulla, "Importance
//! Sampling of Many Lights with Adaptive Tree Splitting" (2018), as
//! pbrt-v4's `BVHLightSampler` uses it. The kernels walk it from the root,
//! choosing a child in proportion to its importance to the shading point
//! (`light_bvh.glsl`, twin `cpu/common/light_bvh.rs`); the environment,
//! directional lights and suns keep their probability by power
//! (`packed::lights`).
//!
//! The probability of any light at any point is the product of the
//! choices on its path from the root, which each leaf's bit trail
//! (`trails`: bit k is the child taken at depth k) lets MIS recompute where
//! a BSDF-sampled ray finds the light.
//!
//! Each node splits its lights by the surface area orientation heuristic
//! (SAOH, Conty Estevez and Kulla section 4.4, as pbrt-v4 weighs it:
//! power x bounds area x the cone's orientation measure, the cheapest
//! bucket boundary of the centroids along any axis), which keeps lights
//! that face apart, and far apart, in different subtrees. Where a split
//! could leave a leaf deeper than `LIGHT_TREE_MAX_DEPTH` (32: the trails'
//! bits), or no boundary separates the centroids, the node splits at their
//! median along the widest axis instead, so the kernels' walk stays a loop
//! of fixed bound.

use crate::constants::*;
use crate::packed::layout::{Emitter, Instance, Light, LightTreeNode, MaterialData, TriangleVerts};
use glam::{DMat3, DQuat, DVec3, Vec3};
use std::f64::consts::PI;

/// Extra angle allowed beyond each light's emission (`cos_theta_e`): the
/// kernels' f32 arithmetic must never call a light that shines on a
/// point unable to reach it.
const EMISSION_MARGIN: f64 = 1e-3;

/// The light BVH as the kernels read it: one dummy node and trail where
/// there is no tree (a buffer may not be empty).
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    pub nodes: Vec<LightTreeNode>,
    /// Each `emitters` row's trail, then each `lights` entry's (0 for a
    /// light not in the tree).
    pub trails: Vec<u32>,
    /// A bug the tests plant (false otherwise): the CPU's MIS finds a
    /// light's pmf without the receiving normal that light sampling used.
    #[doc(hidden)]
    pub plant_mis_without_normal: bool,
}

impl LightTree {
    pub fn none() -> LightTree {
        LightTree {
            nodes: vec![LightTreeNode::default()],
            trails: vec![0],
            plant_mis_without_normal: false,
        }
    }
}

/// What the tree knows of one light.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    lo: Vec3,
    hi: Vec3,
    power: f64,
    axis: DVec3,
    theta_o: f64,
    theta_e: f64,
    two_sided: bool,
}

impl Bounds {
    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    fn union(&self, b: &Bounds) -> Bounds {
        let (axis, theta_o) = union_cone((self.axis, self.theta_o), (b.axis, b.theta_o));
        Bounds {
            lo: self.lo.min(b.lo),
            hi: self.hi.max(b.hi),
            power: self.power + b.power,
            axis,
            theta_o,
            theta_e: self.theta_e.max(b.theta_e),
            two_sided: self.two_sided || b.two_sided,
        }
    }
}

/// The smallest cone (axis, half angle) holding cones `a` and `b` (the
/// construction of Conty Estevez and Kulla, section 4.1). A half angle of
/// pi is every direction.
fn union_cone(a: (DVec3, f64), b: (DVec3, f64)) -> (DVec3, f64) {
    let ((wa, ta), (wb, tb)) = (a, b);
    if ta >= PI || tb >= PI {
        return (wa, PI);
    }
    let td = wa.dot(wb).clamp(-1.0, 1.0).acos();
    if (td + tb).min(PI) <= ta {
        return a;
    }
    if (td + ta).min(PI) <= tb {
        return b;
    }
    let t = 0.5 * (ta + td + tb);
    if t >= PI {
        return (wa, PI);
    }
    let k = wa.cross(wb);
    if k.length_squared() < 1e-24 {
        return (wa, PI);
    }
    // Turn a's axis toward b's by the angle the union adds on a's side.
    let w = DQuat::from_axis_angle(k.normalize(), t - ta) * wa;
    (w.normalize(), t)
}

/// The world vertices of emitter `id` (a one-level slot, or a two-level
/// scene's (instance, triangle) hit id), in f64, and whether the instance
/// mirrors.
fn emitter_vertices(id: u32, tri_verts: &[TriangleVerts], instances: &[Instance]) -> [DVec3; 3] {
    let tv = |slot: u32| {
        let t = &tri_verts[slot as usize];
        [t.v0, t.v1, t.v2].map(|v| Vec3::from(v).as_dvec3())
    };
    if instances.is_empty() {
        return tv(id);
    }
    let k = instances.partition_point(|i| i.id_base <= id) - 1;
    let inst = &instances[k];
    let rows = inst.to_world();
    let m = DMat3::from_cols_array_2d(&[0, 1, 2].map(|c| [0, 1, 2].map(|r| rows[r][c] as f64)));
    let t = DVec3::new(rows[0][3] as f64, rows[1][3] as f64, rows[2][3] as f64);
    let mut v = tv(id - inst.id_base + inst.first_triangle).map(|p| m * p + t);
    if inst.flags & INSTANCE_MIRRORED != 0 {
        // The emitting side is the mirrored one (`instance_facing`).
        v.swap(1, 2);
    }
    v
}

/// Bounds of an emissive triangle of power `power` (luminance, as
/// `packed::lights` measures it).
fn triangle_bounds(v: [DVec3; 3], power: f64, two_sided: bool, padded: bool) -> Bounds {
    let lo = v[0].min(v[1]).min(v[2]);
    let hi = v[0].max(v[1]).max(v[2]);
    // Placed by an instance in f64: pad by what the kernels' f32 placing
    // may round (`instance_error`'s order).
    let pad = if padded {
        DVec3::splat(1e-5 * lo.abs().max(hi.abs()).max_element())
    } else {
        DVec3::ZERO
    };
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let axis = if n.length_squared() > 0.0 {
        n.normalize()
    } else {
        DVec3::Z
    };
    Bounds {
        lo: (lo - pad).as_vec3(),
        hi: (hi + pad).as_vec3(),
        power,
        axis,
        theta_o: if n.length_squared() > 0.0 { 0.0 } else { PI },
        theta_e: 0.5 * PI,
        two_sided,
    }
}

/// Bounds of analytic light `l` of power `power`, or `None` for a light the
/// tree does not hold (directional, sun).
fn analytic_bounds(l: &Light, power: f64) -> Option<Bounds> {
    let p = Vec3::from(l.position);
    let r = match l.kind {
        LIGHT_SPHERE => l.radius,
        LIGHT_POINT | LIGHT_SPOT => 0.0,
        _ => return None,
    };
    let (axis, theta_o) = if l.kind == LIGHT_SPOT {
        // Zero where cos * scale + offset <= 0: beyond the outer cone.
        let cos_outer = (-l.spot_offset / l.spot_scale) as f64;
        (
            Vec3::from(l.direction).as_dvec3().normalize(),
            cos_outer.clamp(-1.0, 1.0).acos(),
        )
    } else {
        (DVec3::Z, PI)
    };
    Some(Bounds {
        lo: p - Vec3::splat(r),
        hi: p + Vec3::splat(r),
        power,
        axis,
        theta_o,
        theta_e: 0.5 * PI,
        two_sided: false,
    })
}

/// A light of the tree: its bounds and what its leaf points at.
#[derive(Clone, Copy, Debug)]
struct Item {
    bounds: Bounds,
    /// `emitters` row, or `lights` index with `LIGHT_TREE_ANALYTIC`.
    light: u32,
    analytic: bool,
}

/// Builds the light BVH over `emitters` (world triangles from `tri_verts`,
/// placed by `instances` in a two-level scene; power `emitter_power` each)
/// and the analytic `lights` with their powers (`light_powers`, same
/// order). Returns `None` when no light has power.
#[allow(clippy::too_many_arguments)]
pub fn build(
    emitters: &[Emitter],
    emitter_power: &[f64],
    tri_verts: &[TriangleVerts],
    materials: &[MaterialData],
    instances: &[Instance],
    lights: &[Light],
    light_powers: &[f64],
) -> Option<LightTree> {
    let mut items = Vec::with_capacity(emitters.len() + lights.len());
    for (k, (e, &power)) in emitters.iter().zip(emitter_power).enumerate() {
        if !(power > 0.0) {
            continue;
        }
        let slot_material = if instances.is_empty() {
            tri_verts[e.triangle as usize].material
        } else {
            let i = instances.partition_point(|i| i.id_base <= e.triangle) - 1;
            let slot = e.triangle - instances[i].id_base + instances[i].first_triangle;
            tri_verts[slot as usize].material
        };
        let two_sided = materials[slot_material as usize].double_sided != 0;
        let v = emitter_vertices(e.triangle, tri_verts, instances);
        items.push(Item {
            bounds: triangle_bounds(v, power, two_sided, !instances.is_empty()),
            light: k as u32,
            analytic: false,
        });
    }
    for (k, (l, &power)) in lights.iter().zip(light_powers).enumerate() {
        if !(power > 0.0) {
            continue;
        }
        if let Some(bounds) = analytic_bounds(l, power) {
            items.push(Item {
                bounds,
                light: k as u32,
                analytic: true,
            });
        }
    }
    if items.is_empty() {
        return None;
    }
    let mut tree = LightTree {
        nodes: vec![LightTreeNode::default()],
        trails: vec![0; emitters.len() + lights.len()],
        plant_mis_without_normal: false,
    };
    let emitter_rows = emitters.len();
    build_node(&mut items, 0, 0, 0, emitter_rows, &mut tree);
    Some(tree)
}

fn node_of(b: &Bounds, child_or_light: u32, flags: u32) -> LightTreeNode {
    let cos = |t: f64| t.min(PI).cos() as f32;
    // A sphere holding the box: its centre in f32, its radius the farthest
    // corner's distance from that centre, rounded up.
    let centre = 0.5 * (b.lo + b.hi);
    let far = (b.hi.as_dvec3() - centre.as_dvec3())
        .abs()
        .max((centre.as_dvec3() - b.lo.as_dvec3()).abs());
    let radius = (far.length() as f32).next_up();
    let radius = if far == DVec3::ZERO { 0.0 } else { radius };
    let cos_theta_o = cos(b.theta_o);
    LightTreeNode {
        centre: centre.into(),
        power: b.power as f32,
        axis: b.axis.as_vec3().into(),
        cos_theta_o,
        radius,
        r2: radius * radius,
        sin_theta_o: (1.0 - cos_theta_o * cos_theta_o).max(0.0).sqrt(),
        cos_theta_e: cos(b.theta_e + EMISSION_MARGIN),
        child_or_light,
        flags: flags | if b.two_sided { LIGHT_TREE_TWO_SIDED } else { 0 },
        ..Default::default()
    }
}

/// Buckets along each axis that the split heuristic tries.
const SPLIT_BUCKETS: usize = 12;

/// The orientation measure M_Omega of a node's cone (Conty Estevez and
/// Kulla, section 4.4; pbrt-v4's `EvaluateCost`): the solid angle its
/// lights may emit into, weighted by cosine beyond theta_o up to theta_e.
fn orientation_measure(b: &Bounds) -> f64 {
    let theta_o = b.theta_o.min(PI);
    let theta_w = (theta_o + b.theta_e).min(PI);
    let (sin_o, cos_o) = theta_o.sin_cos();
    2.0 * PI * (1.0 - cos_o)
        + 0.5
            * PI
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + cos_o)
}

/// The surface area orientation heuristic's cost of a child with bounds
/// `b` split off along `axis` of its parent's `extent`: power x bounds area
/// x M_Omega, times the parent's longest side over its side along `axis`
/// (thin slabs split across).
fn split_cost(b: &Bounds, extent: DVec3, axis: usize) -> f64 {
    let d = (b.hi - b.lo).as_dvec3();
    let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    let kr = extent.max_element() / extent[axis];
    b.power * area * orientation_measure(b) * kr
}

/// Orders `items` and returns where node `bounds` at `depth` splits them:
/// by the surface area orientation heuristic (SAOH: the least sum of the
/// children's `split_cost` over `SPLIT_BUCKETS` buckets of the centroids
/// along each axis), or at the median centroid along the widest axis where
/// no bucket boundary separates them or the heuristic's split could leave
/// a leaf deeper than `LIGHT_TREE_MAX_DEPTH` (a median split from depth d
/// with n lights has its leaves within d + ceil(log2 n)).
fn split(items: &mut [Item], bounds: &Bounds, depth: u32) -> usize {
    let n = items.len();
    let (clo, chi) = items.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), i| (lo.min(i.bounds.centroid()), hi.max(i.bounds.centroid())),
    );
    let ext = chi - clo;
    let extent = (bounds.hi - bounds.lo).as_dvec3();
    let bucket_of = |c: Vec3, axis: usize| {
        let t = (c[axis] - clo[axis]) / ext[axis];
        ((t * SPLIT_BUCKETS as f32) as usize).min(SPLIT_BUCKETS - 1)
    };
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        if !(ext[axis] > 0.0) || !(extent[axis] > 0.0) {
            continue;
        }
        let mut buckets: [Option<Bounds>; SPLIT_BUCKETS] = [None; SPLIT_BUCKETS];
        for it in items.iter() {
            let k = bucket_of(it.bounds.centroid(), axis);
            buckets[k] = Some(match buckets[k] {
                Some(b) => b.union(&it.bounds),
                None => it.bounds,
            });
        }
        let union = |a: Option<Bounds>, b: Option<Bounds>| match (a, b) {
            (Some(a), Some(b)) => Some(a.union(&b)),
            (a, None) => a,
            (None, b) => b,
        };
        // Prefix unions from the left, suffix from the right.
        let mut right = [None; SPLIT_BUCKETS];
        let mut acc = None;
        for k in (1..SPLIT_BUCKETS).rev() {
            acc = union(acc, buckets[k]);
            right[k] = acc;
        }
        let mut left = None;
        for k in 1..SPLIT_BUCKETS {
            left = union(left, buckets[k - 1]);
            if let (Some(l), Some(r)) = (left, right[k]) {
                let cost = split_cost(&l, extent, axis) + split_cost(&r, extent, axis);
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, k));
                }
            }
        }
    }
    let ceil_log2 = |m: usize| usize::BITS - (m - 1).leading_zeros();
    if let Some((_, axis, k)) = best {
        let mut mid = 0;
        for i in 0..n {
            if bucket_of(items[i].bounds.centroid(), axis) < k {
                items.swap(i, mid);
                mid += 1;
            }
        }
        let fits = |m: usize| depth + 1 + ceil_log2(m) <= LIGHT_TREE_MAX_DEPTH;
        if mid > 0 && mid < n && fits(mid) && fits(n - mid) {
            return mid;
        }
    }
    // The widest axis of the centroids, split at their median.
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = n / 2;
    items.select_nth_unstable_by(mid, |a, b| {
        a.bounds.centroid()[axis].total_cmp(&b.bounds.centroid()[axis])
    });
    mid
}

/// Fills node `index` with `items`; `trail` and `depth` say how it is
/// reached from the root.
fn build_node(
    items: &mut [Item],
    index: usize,
    trail: u32,
    depth: u32,
    emitter_rows: usize,
    tree: &mut LightTree,
) {
    let bounds = items[1..]
        .iter()
        .fold(items[0].bounds, |b, i| b.union(&i.bounds));
    if items.len() == 1 {
        let it = items[0];
        let flags = LIGHT_TREE_LEAF | if it.analytic { LIGHT_TREE_ANALYTIC } else { 0 };
        tree.nodes[index] = node_of(&bounds, it.light, flags);
        let row = if it.analytic {
            emitter_rows + it.light as usize
        } else {
            it.light as usize
        };
        tree.trails[row] = trail;
        return;
    }
    assert!(
        depth < LIGHT_TREE_MAX_DEPTH,
        "the split keeps the light BVH within 32 levels"
    );
    let mid = split(items, &bounds, depth);
    let child = tree.nodes.len();
    tree.nodes.push(LightTreeNode::default());
    tree.nodes.push(LightTreeNode::default());
    tree.nodes[index] = node_of(&bounds, child as u32, 0);
    let (left, right) = items.split_at_mut(mid);
    build_node(left, child, trail, depth + 1, emitter_rows, tree);
    build_node(
        right,
        child + 1,
        trail | 1 << depth,
        depth + 1,
        emitter_rows,
        tree,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn emitter(triangle: u32) -> Emitter {
        Emitter {
            triangle,
            ..Default::default()
        }
    }

    fn tri(x: f32) -> TriangleVerts {
        TriangleVerts {
            v0: [x, 0.0, 0.0],
            v1: [x + 1.0, 0.0, 0.0],
            v2: [x, 1.0, 0.0],
            ..Default::default()
        }
    }

    #[test]
    fn every_trail_leads_to_its_own_leaf() {
        let n = 37;
        let verts: Vec<TriangleVerts> = (0..n).map(|k| tri(k as f32 * 3.0)).collect();
        let emitters: Vec<Emitter> = (0..n).map(emitter).collect();
        let powers = vec![1.0; n as usize];
        let materials = vec![MaterialData::default()];
        let tree = build(&emitters, &powers, &verts, &materials, &[], &[], &[]).expect("a tree");
        for (row, &trail) in tree.trails.iter().enumerate() {
            let (mut node, mut t) = (0usize, trail);
            while tree.nodes[node].flags & LIGHT_TREE_LEAF == 0 {
                node = (tree.nodes[node].child_or_light + (t & 1)) as usize;
                t >>= 1;
            }
            assert_eq!(tree.nodes[node].child_or_light, row as u32);
        }
        assert_eq!(tree.nodes.len(), 2 * n as usize - 1);
        assert!((tree.nodes[0].power - n as f32).abs() < 1e-4);
    }

    #[test]
    fn cone_union_holds_both_cones() {
        let a = (DVec3::Z, 0.1);
        let b = (DVec3::X, 0.2);
        let (w, t) = union_cone(a, b);
        for (axis, half) in [a, b] {
            let angle = w.dot(axis).clamp(-1.0, 1.0).acos();
            assert!(angle + half <= t + 1e-9, "{angle} + {half} > {t}");
        }
        assert!(union_cone((DVec3::Z, 0.0), (-DVec3::Z, 0.0)).1 >= 0.5 * PI);
    }
}
