//! Twin of `shaders/common/light_bvh.glsl`: the light BVH's walk by
//! importance, with the receiving normal as the path state carries it, and
//! the pmf MIS recomputes from a light's bit trail. See the GLSL file for
//! the importance; the host builds the tree (`packed::light_bvh`). The
//! walk goes down two levels a step and computes the step's four
//! candidates' importances in the lanes of one SIMD register
//! (`light_tree_importance4`), the GLSL's operations in its order, so the
//! same floats.

use crate::constants::*;
use crate::packed::PackedScene;
use crate::packed::layout::{LightTreeNode, RenderParams};
use glam::{BVec4A, Vec3, Vec4};

pub fn fetch_light_tree_node(scene: &PackedScene, i: u32) -> &LightTreeNode {
    &scene.light_tree.nodes[i as usize]
}

pub fn light_tree_on(scene: &PackedScene) -> bool {
    scene.light_params.tree_nodes > 0
}

/// Importance of node `n` to point `p` with normal `nrm` (zero: no normal).
pub fn light_tree_importance(n: &LightTreeNode, p: Vec3, nrm: Vec3) -> f32 {
    let dp = p - Vec3::from(n.centre);
    let d2 = dp.dot(dp);
    if !(d2 > n.r2) {
        return n.power / n.r2;
    }
    let inv_d = 1.0 / d2.sqrt();
    let mut cos_w = Vec3::from(n.axis).dot(dp) * inv_d;
    if n.flags & LIGHT_TREE_TWO_SIDED != 0 {
        cos_w = cos_w.abs();
    }
    let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
    let (cos_o, sin_o) = (n.cos_theta_o, n.sin_theta_o);
    // cos and sin of max(0, theta_w - theta_o).
    let (mut cos_x, mut sin_x) = (1.0f32, 0.0f32);
    if cos_w < cos_o {
        cos_x = cos_w * cos_o + sin_w * sin_o;
        sin_x = sin_w * cos_o - cos_w * sin_o;
    }
    // Less the half angle theta_b the bounds subtend.
    let sin_b = n.radius * inv_d;
    let cos_b = (1.0 - sin_b * sin_b).max(0.0).sqrt();
    let mut cos_p = 1.0f32;
    if cos_x < cos_b {
        cos_p = cos_x * cos_b + sin_x * sin_b;
    }
    if cos_p <= n.cos_theta_e {
        return 0.0;
    }
    // The receiving side, one-sided: cos of max(0, theta_i - theta_b),
    // at least LIGHT_TREE_MIN_COS_I.
    let mut cos_pi = 1.0f32;
    if nrm != Vec3::ZERO {
        let cos_i = -nrm.dot(dp) * inv_d;
        if cos_i < cos_b {
            let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
            cos_pi = (cos_i * cos_b + sin_i * sin_b).max(LIGHT_TREE_MIN_COS_I);
        }
    }
    n.power * cos_p * cos_pi * (inv_d * inv_d)
}

/// The fields `light_tree_importance` reads, of four nodes, a lane each:
/// the walk's step computes its four candidates' importances in one SIMD
/// register (`light_tree_importance_quad`).
#[derive(Clone, Copy, Debug)]
pub struct LightTreeQuad {
    pub centre: [Vec4; 3],
    pub axis: [Vec4; 3],
    pub r2: Vec4,
    pub radius: Vec4,
    pub cos_theta_o: Vec4,
    pub sin_theta_o: Vec4,
    pub cos_theta_e: Vec4,
    pub power: Vec4,
    pub two_sided: BVec4A,
}

impl LightTreeQuad {
    pub fn of(n: [&LightTreeNode; 4]) -> LightTreeQuad {
        let v = |f: fn(&LightTreeNode) -> f32| Vec4::new(f(n[0]), f(n[1]), f(n[2]), f(n[3]));
        LightTreeQuad {
            centre: [v(|n| n.centre[0]), v(|n| n.centre[1]), v(|n| n.centre[2])],
            axis: [v(|n| n.axis[0]), v(|n| n.axis[1]), v(|n| n.axis[2])],
            r2: v(|n| n.r2),
            radius: v(|n| n.radius),
            cos_theta_o: v(|n| n.cos_theta_o),
            sin_theta_o: v(|n| n.sin_theta_o),
            cos_theta_e: v(|n| n.cos_theta_e),
            power: v(|n| n.power),
            two_sided: BVec4A::from(n.map(|n| n.flags & LIGHT_TREE_TWO_SIDED != 0)),
        }
    }
}

/// `light_tree_importance` of four nodes at once, a lane each (SIMD: the
/// same operations in the same order, so the same floats), for the walk's
/// step.
pub fn light_tree_importance4(n: [&LightTreeNode; 4], p: Vec3, nrm: Vec3) -> Vec4 {
    light_tree_importance_quad(&LightTreeQuad::of(n), p, nrm)
}

/// `light_tree_importance4` of the nodes `n` holds.
#[inline(always)]
fn light_tree_importance_quad(n: &LightTreeQuad, p: Vec3, nrm: Vec3) -> Vec4 {
    let zero = Vec4::ZERO;
    let one = Vec4::ONE;
    let dpx = Vec4::splat(p.x) - n.centre[0];
    let dpy = Vec4::splat(p.y) - n.centre[1];
    let dpz = Vec4::splat(p.z) - n.centre[2];
    let d2 = dpx * dpx + dpy * dpy + dpz * dpz;
    let inv_d = one / d2.sqrt();
    let [ax, ay, az] = n.axis;
    let mut cos_w = (ax * dpx + ay * dpy + az * dpz) * inv_d;
    cos_w = Vec4::select(n.two_sided, cos_w.abs(), cos_w);
    let sin_w = (one - cos_w * cos_w).max(zero).sqrt();
    let (cos_o, sin_o) = (n.cos_theta_o, n.sin_theta_o);
    let narrower = cos_w.cmplt(cos_o);
    let cos_x = Vec4::select(narrower, cos_w * cos_o + sin_w * sin_o, one);
    let sin_x = Vec4::select(narrower, sin_w * cos_o - cos_w * sin_o, zero);
    let sin_b = n.radius * inv_d;
    let cos_b = (one - sin_b * sin_b).max(zero).sqrt();
    let cos_p = Vec4::select(cos_x.cmplt(cos_b), cos_x * cos_b + sin_x * sin_b, one);
    let dark = cos_p.cmple(n.cos_theta_e);
    let mut cos_pi = one;
    if nrm != Vec3::ZERO {
        let cos_i =
            -(Vec4::splat(nrm.x) * dpx + Vec4::splat(nrm.y) * dpy + Vec4::splat(nrm.z) * dpz)
                * inv_d;
        let sin_i = (one - cos_i * cos_i).max(zero).sqrt();
        let bounded = (cos_i * cos_b + sin_i * sin_b).max(Vec4::splat(LIGHT_TREE_MIN_COS_I));
        cos_pi = Vec4::select(cos_i.cmplt(cos_b), bounded, one);
    }
    let power = n.power;
    let lit = Vec4::select(dark, zero, power * cos_p * cos_pi * (inv_d * inv_d));
    Vec4::select(d2.cmpgt(n.r2), lit, power / n.r2)
}

/// The octahedral map's fold of the lower hemisphere onto the square's
/// corners (its own inverse): both ways of the normal's code.
fn light_tree_octahedral_fold(x: f32, y: f32) -> (f32, f32) {
    let sign = |v: f32| if v >= 0.0 { 1.0 } else { -1.0 };
    ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y))
}

/// The receiving normal as the path state carries it (`prev_normal`):
/// octahedral, 14 bits an axis, bit 0 set; 0: none.
pub fn light_tree_normal_code(n: Vec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    let mut x = n.x / l1;
    let mut y = n.y / l1;
    if n.z < 0.0 {
        (x, y) = light_tree_octahedral_fold(x, y);
    }
    let qx = ((x * 8192.0 + 8192.0).max(0.0) as u32).min(16383);
    let qy = ((y * 8192.0 + 8192.0).max(0.0) as u32).min(16383);
    1 | (qx << 1) | (qy << 15)
}

/// The normal `code` stands for (the centre of its cell), unit length;
/// zero for code 0.
pub fn light_tree_normal(code: u32) -> Vec3 {
    if code == 0 {
        return Vec3::ZERO;
    }
    let mut x = ((code >> 1) & 16383) as f32 * (1.0 / 8192.0) - (1.0 - 1.0 / 16384.0);
    let mut y = ((code >> 15) & 16383) as f32 * (1.0 / 8192.0) - (1.0 - 1.0 / 16384.0);
    let z = 1.0 - x.abs() - y.abs();
    if z < 0.0 {
        (x, y) = light_tree_octahedral_fold(x, y);
    }
    let v = Vec3::new(x, y, z);
    v / v.dot(v).sqrt()
}

/// The candidates of one step of the walk from interior node `n`, two
/// levels at once: its children a and b (nodes `c` and `c + 1`, `c` =
/// `n.child_or_light`), each one's two children in lanes 0, 1 (a's) and
/// 2, 3 (b's), or, for a child that is a leaf, the leaf itself and a
/// second lane of no importance. Returns the lanes' nodes, their
/// importances to `p` (`light_tree_importance4`: four nodes in one SIMD
/// register, where the binary walk's step filled two) and which of a and
/// b are leaves. The GLSL computes the same lanes a side at a time:
/// `light_tree_lanes(c)` and `light_tree_lanes(c + 1)`.
fn light_tree_grandchildren(
    scene: &PackedScene,
    n: &LightTreeNode,
    p: Vec3,
    nrm: Vec3,
) -> ([u32; 4], [f32; 4], [bool; 2]) {
    let c = n.child_or_light;
    let (a, b) = (
        fetch_light_tree_node(scene, c),
        fetch_light_tree_node(scene, c + 1),
    );
    let lanes = |x: &LightTreeNode, i: u32| {
        if x.flags & LIGHT_TREE_LEAF != 0 {
            [i, i]
        } else {
            [x.child_or_light, x.child_or_light + 1]
        }
    };
    let ([a0, a1], [b0, b1]) = (lanes(a, c), lanes(b, c + 1));
    let idx = [a0, a1, b0, b1];
    let imp = light_tree_importance4(idx.map(|i| fetch_light_tree_node(scene, i)), p, nrm);
    let mut q = imp.to_array();
    let leaf = [a, b].map(|x| x.flags & LIGHT_TREE_LEAF != 0);
    if leaf[0] {
        q[1] = 0.0;
    }
    if leaf[1] {
        q[3] = 0.0;
    }
    (idx, q, leaf)
}

/// Takes one step of the walk at interior node `n` (see the GLSL's
/// `light_tree_step`) over its lanes (`light_tree_grandchildren`):
/// `light_tree_choose_lane`. Returns the node reached, the step's
/// probability and the levels it went down (1 or 2: the trail bits it
/// used); `None` where no light reaches `p`.
#[inline(always)]
fn light_tree_step(
    scene: &PackedScene,
    n: &LightTreeNode,
    p: Vec3,
    nrm: Vec3,
    choose: impl FnMut(f32) -> bool,
) -> Option<(u32, f32, u32)> {
    let (idx, q, leaf) = light_tree_grandchildren(scene, n, p, nrm);
    let (lane, pmf, levels) = light_tree_choose_lane(q, leaf, choose)?;
    Some((idx[lane], pmf, levels))
}

/// A step's choice among its four lanes' importances `q` (a's children in
/// lanes 0 and 1, b's in 2 and 3; `leaf`: which of a and b are leaves): a
/// child in proportion to the sum of its lanes, then, unless that child
/// is a leaf, one of its lanes in proportion to its own; `choose(q)` says
/// whether the first of two choices of probability q is taken. Returns the
/// lane (a leaf child's first), the step's probability and the levels it
/// went down; `None` where every importance is zero.
#[inline(always)]
fn light_tree_choose_lane(
    q: [f32; 4],
    leaf: [bool; 2],
    mut choose: impl FnMut(f32) -> bool,
) -> Option<(usize, f32, u32)> {
    let ia = q[0] + q[1];
    let ib = q[2] + q[3];
    let total = ia + ib;
    if !(total > 0.0) {
        return None;
    }
    let (pa, pb) = (ia / total, ib / total);
    let side = usize::from(!choose(pa));
    let mut pmf = if side == 0 { pa } else { pb };
    if leaf[side] {
        return Some((2 * side, pmf, 1));
    }
    let (i0, i1) = (q[2 * side], q[2 * side + 1]);
    let t = i0 + i1;
    if !(t > 0.0) {
        return None;
    }
    let (p0, p1) = (i0 / t, i1 / t);
    let bit = usize::from(!choose(p0));
    pmf *= if bit == 0 { p0 } else { p1 };
    Some((2 * side + bit, pmf, 2))
}

/// Whether `u` falls in the first of two choices of probability `q`, and
/// `u` rescaled to [0, 1) within the one it falls in.
#[inline(always)]
fn light_tree_choose(u: &mut f32, q: f32) -> bool {
    if *u < q {
        *u = (*u / q).min(0.999_999_94);
        true
    } else {
        *u = ((*u - q) / (1.0 - q)).min(0.999_999_94);
        false
    }
}

/// The leaf chosen for `p` with normal `nrm` (zero: none) and `u` in
/// [0, 1), and its probability (0: no light reaches `p`).
pub fn light_tree_sample(
    scene: &PackedScene,
    p: Vec3,
    nrm: Vec3,
    mut u: f32,
) -> (&LightTreeNode, f32) {
    let mut n = fetch_light_tree_node(scene, 0);
    let mut pmf = 1.0f32;
    for _ in 0..LIGHT_TREE_MAX_DEPTH {
        if n.flags & LIGHT_TREE_LEAF != 0 {
            return (n, pmf);
        }
        let Some((next, q, _)) =
            light_tree_step(scene, n, p, nrm, |q| light_tree_choose(&mut u, q))
        else {
            break;
        };
        pmf *= q;
        n = fetch_light_tree_node(scene, next);
    }
    if n.flags & LIGHT_TREE_LEAF == 0 {
        pmf = 0.0;
    }
    (n, pmf)
}

/// `light_tree_sample` for `N` points at once (those where `active`),
/// their walks taken a step each in turn: they are independent, so one
/// walk's long sqrt and division chains overlap the others'. Each result is
/// `light_tree_sample`'s for its point to the bit (the same steps): the
/// leaf's node index and its probability (0: none, or not active).
pub fn light_tree_sample_many<const N: usize>(
    scene: &PackedScene,
    p: &[Vec3; N],
    nrm: &[Vec3; N],
    u: &[f32; N],
    active: &[bool; N],
) -> ([u32; N], [f32; N]) {
    let mut node = [0u32; N];
    let mut pmf = [0.0f32; N];
    let mut u = *u;
    let mut walking = *active;
    for l in 0..N {
        if active[l] {
            pmf[l] = 1.0;
        }
    }
    for _ in 0..LIGHT_TREE_MAX_DEPTH {
        let mut any = false;
        for l in 0..N {
            if !walking[l] {
                continue;
            }
            let n = fetch_light_tree_node(scene, node[l]);
            if n.flags & LIGHT_TREE_LEAF != 0 {
                walking[l] = false;
                continue;
            }
            any = true;
            let ul = &mut u[l];
            match light_tree_step(scene, n, p[l], nrm[l], |q| light_tree_choose(ul, q)) {
                Some((next, q, _)) => {
                    pmf[l] *= q;
                    node[l] = next;
                }
                None => {
                    walking[l] = false;
                    pmf[l] = 0.0;
                }
            }
        }
        if !any {
            break;
        }
    }
    for l in 0..N {
        if fetch_light_tree_node(scene, node[l]).flags & LIGHT_TREE_LEAF == 0 {
            pmf[l] = 0.0;
        }
    }
    (node, pmf)
}

/// The probability that `light_tree_sample` at `p` with `nrm` picks the
/// leaf `trail` leads to (bit k: the child taken at depth k).
pub fn light_tree_pmf(scene: &PackedScene, mut trail: u32, p: Vec3, nrm: Vec3) -> f32 {
    let mut n = fetch_light_tree_node(scene, 0);
    let mut pmf = 1.0f32;
    for _ in 0..LIGHT_TREE_MAX_DEPTH {
        if n.flags & LIGHT_TREE_LEAF != 0 {
            return pmf;
        }
        let mut t = trail;
        let Some((next, q, levels)) = light_tree_step(scene, n, p, nrm, |_| {
            let first = t & 1 == 0;
            t >>= 1;
            first
        }) else {
            return 0.0;
        };
        trail >>= levels;
        pmf *= q;
        n = fetch_light_tree_node(scene, next);
    }
    if n.flags & LIGHT_TREE_LEAF != 0 {
        pmf
    } else {
        0.0
    }
}

/// The normal MIS bounds with: `nrm`, or none where the tests plant that
/// bug (`LightTree::plant_mis_without_normal`).
fn mis_normal(scene: &PackedScene, nrm: Vec3) -> Vec3 {
    if scene.light_tree.plant_mis_without_normal {
        Vec3::ZERO
    } else {
        nrm
    }
}

/// The `emitters` row of emissive triangle `id` (rows are sorted by id).
pub fn light_tree_emitter_row(scene: &PackedScene, params: &RenderParams, id: u32) -> u32 {
    let (mut lo, mut hi) = (0u32, params.num_emitters - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if scene.emitters[mid as usize].triangle < id {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The probability that light sampling picks emissive triangle `id` from `p`
/// with normal `nrm`.
pub fn light_tree_triangle_pmf(
    scene: &PackedScene,
    params: &RenderParams,
    id: u32,
    p: Vec3,
    nrm: Vec3,
) -> f32 {
    if params.num_emitters == 0 {
        return 0.0;
    }
    let row = light_tree_emitter_row(scene, params, id);
    if scene.emitters[row as usize].triangle != id {
        return 0.0;
    }
    scene.light_params.tri_select_prob
        * light_tree_pmf(
            scene,
            scene.light_tree.trails[row as usize],
            p,
            mis_normal(scene, nrm),
        )
}

/// The probability that light sampling picks analytic light `k` from `p`
/// with normal `nrm`.
pub fn light_tree_light_pmf(
    scene: &PackedScene,
    params: &RenderParams,
    k: u32,
    p: Vec3,
    nrm: Vec3,
) -> f32 {
    scene.light_params.tri_select_prob
        * light_tree_pmf(
            scene,
            scene.light_tree.trails[(params.num_emitters + k) as usize],
            p,
            mis_normal(scene, nrm),
        )
}
