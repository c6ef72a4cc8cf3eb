//! Twin of `shaders/common/light_bvh.glsl`: the light BVH's walk by
//! importance, with the receiving normal as the path state carries it, and
//! the pmf MIS recomputes from a light's bit trail. See the GLSL file for
//! the importance; the host builds the tree (`packed::light_bvh`). The
//! walk's step computes its two children's importances in the lanes of one
//! SIMD register (`light_tree_importance2`), the GLSL's operations in its
//! order, so the same floats.

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
    let (lo, hi) = (Vec3::from(n.lo), Vec3::from(n.hi));
    let dp = p - 0.5 * (lo + hi);
    let d2 = dp.dot(dp);
    let ext = hi - lo;
    let r2 = 0.25 * ext.dot(ext);
    let mut cos_p = 1.0f32;
    let mut cos_pi = 1.0f32;
    if d2 > r2 {
        let d = d2.sqrt();
        let mut cos_w = Vec3::from(n.axis).dot(dp) / d;
        if n.flags & LIGHT_TREE_TWO_SIDED != 0 {
            cos_w = cos_w.abs();
        }
        let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
        let cos_o = n.cos_theta_o;
        let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
        // cos and sin of max(0, theta_w - theta_o).
        let (mut cos_x, mut sin_x) = (1.0f32, 0.0f32);
        if cos_w < cos_o {
            cos_x = cos_w * cos_o + sin_w * sin_o;
            sin_x = sin_w * cos_o - cos_w * sin_o;
        }
        // Less the half angle theta_b the bounds subtend.
        let sin2_b = r2 / d2;
        let cos_b = (1.0 - sin2_b).max(0.0).sqrt();
        let sin_b = sin2_b.sqrt();
        if cos_x < cos_b {
            cos_p = cos_x * cos_b + sin_x * sin_b;
        }
        if cos_p <= n.cos_theta_e {
            return 0.0;
        }
        // The receiving side, one-sided: cos of max(0, theta_i - theta_b),
        // at least LIGHT_TREE_MIN_COS_I.
        if nrm != Vec3::ZERO {
            let cos_i = -nrm.dot(dp) / d;
            if cos_i < cos_b {
                let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
                cos_pi = (cos_i * cos_b + sin_i * sin_b).max(LIGHT_TREE_MIN_COS_I);
            }
        }
    }
    n.power * cos_p * cos_pi / d2.max(r2)
}

/// `light_tree_importance` of nodes `a` and `b` at once, a lane each (SIMD:
/// the same operations in the same order, so the same floats), for the
/// walk's step.
pub fn light_tree_importance2(
    a: &LightTreeNode,
    b: &LightTreeNode,
    p: Vec3,
    nrm: Vec3,
) -> (f32, f32) {
    let v = |x: f32, y: f32| Vec4::new(x, y, y, y);
    let zero = Vec4::ZERO;
    let one = Vec4::ONE;
    let (lox, loy, loz) = (
        v(a.lo[0], b.lo[0]),
        v(a.lo[1], b.lo[1]),
        v(a.lo[2], b.lo[2]),
    );
    let (hix, hiy, hiz) = (
        v(a.hi[0], b.hi[0]),
        v(a.hi[1], b.hi[1]),
        v(a.hi[2], b.hi[2]),
    );
    let dpx = Vec4::splat(p.x) - 0.5 * (lox + hix);
    let dpy = Vec4::splat(p.y) - 0.5 * (loy + hiy);
    let dpz = Vec4::splat(p.z) - 0.5 * (loz + hiz);
    let d2 = dpx * dpx + dpy * dpy + dpz * dpz;
    let (ex, ey, ez) = (hix - lox, hiy - loy, hiz - loz);
    let r2 = 0.25 * (ex * ex + ey * ey + ez * ez);
    let d = d2.sqrt();
    let (ax, ay, az) = (
        v(a.axis[0], b.axis[0]),
        v(a.axis[1], b.axis[1]),
        v(a.axis[2], b.axis[2]),
    );
    let mut cos_w = (ax * dpx + ay * dpy + az * dpz) / d;
    let two_sided = BVec4A::new(
        a.flags & LIGHT_TREE_TWO_SIDED != 0,
        b.flags & LIGHT_TREE_TWO_SIDED != 0,
        b.flags & LIGHT_TREE_TWO_SIDED != 0,
        b.flags & LIGHT_TREE_TWO_SIDED != 0,
    );
    cos_w = Vec4::select(two_sided, cos_w.abs(), cos_w);
    let sin_w = (one - cos_w * cos_w).max(zero).sqrt();
    let cos_o = v(a.cos_theta_o, b.cos_theta_o);
    let sin_o = (one - cos_o * cos_o).max(zero).sqrt();
    let narrower = cos_w.cmplt(cos_o);
    let cos_x = Vec4::select(narrower, cos_w * cos_o + sin_w * sin_o, one);
    let sin_x = Vec4::select(narrower, sin_w * cos_o - cos_w * sin_o, zero);
    let sin2_b = r2 / d2;
    let cos_b = (one - sin2_b).max(zero).sqrt();
    let sin_b = sin2_b.sqrt();
    let cos_p = Vec4::select(cos_x.cmplt(cos_b), cos_x * cos_b + sin_x * sin_b, one);
    let dark = cos_p.cmple(v(a.cos_theta_e, b.cos_theta_e));
    let mut cos_pi = one;
    if nrm != Vec3::ZERO {
        let cos_i =
            -(Vec4::splat(nrm.x) * dpx + Vec4::splat(nrm.y) * dpy + Vec4::splat(nrm.z) * dpz) / d;
        let sin_i = (one - cos_i * cos_i).max(zero).sqrt();
        let bounded = (cos_i * cos_b + sin_i * sin_b).max(Vec4::splat(LIGHT_TREE_MIN_COS_I));
        cos_pi = Vec4::select(cos_i.cmplt(cos_b), bounded, one);
    }
    let outside = d2.cmpgt(r2);
    let cos_p = Vec4::select(outside, cos_p, one);
    let cos_pi = Vec4::select(outside, cos_pi, one);
    let power = v(a.power, b.power);
    let imp = Vec4::select(outside & dark, zero, power * cos_p * cos_pi / d2.max(r2));
    (imp.x, imp.y)
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

/// One step of the walk: `n`'s children and the probabilities of taking
/// each at `p`, in proportion to importance; `[0, 0]` where neither reaches
/// `p`.
fn light_tree_children<'a>(
    scene: &'a PackedScene,
    n: &LightTreeNode,
    p: Vec3,
    nrm: Vec3,
) -> (&'a LightTreeNode, &'a LightTreeNode, [f32; 2]) {
    let a = fetch_light_tree_node(scene, n.child_or_light);
    let b = fetch_light_tree_node(scene, n.child_or_light + 1);
    let (ia, ib) = light_tree_importance2(a, b, p, nrm);
    let total = ia + ib;
    if !(total > 0.0) {
        return (a, b, [0.0, 0.0]);
    }
    (a, b, [ia / total, ib / total])
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
        let (a, b, [pa, pb]) = light_tree_children(scene, n, p, nrm);
        if !(pa + pb > 0.0) {
            break;
        }
        if u < pa {
            u = (u / pa).min(0.999_999_94);
            pmf *= pa;
            n = a;
        } else {
            u = ((u - pa) / (1.0 - pa)).min(0.999_999_94);
            pmf *= pb;
            n = b;
        }
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
            let (_, _, [pa, pb]) = light_tree_children(scene, n, p[l], nrm[l]);
            if !(pa + pb > 0.0) {
                walking[l] = false;
                pmf[l] = 0.0;
                continue;
            }
            if u[l] < pa {
                u[l] = (u[l] / pa).min(0.999_999_94);
                pmf[l] *= pa;
                node[l] = n.child_or_light;
            } else {
                u[l] = ((u[l] - pa) / (1.0 - pa)).min(0.999_999_94);
                pmf[l] *= pb;
                node[l] = n.child_or_light + 1;
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
        let (a, b, [pa, pb]) = light_tree_children(scene, n, p, nrm);
        if !(pa + pb > 0.0) {
            return 0.0;
        }
        if trail & 1 == 0 {
            pmf *= pa;
            n = a;
        } else {
            pmf *= pb;
            n = b;
        }
        trail >>= 1;
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
