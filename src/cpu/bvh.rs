//! Twin of `shaders/common/bvh.glsl`: the same bounded traversal, so an
//! overflow on one back end is an overflow on the other.

use super::intersect::{intersect_aabb, intersect_triangle, ray_shear};
use super::sampling::FLT_MAX;
use crate::constants::*;
use crate::packed::PackedScene;
use glam::{Vec2, Vec3};

pub const NO_HIT: u32 = 0xFFFF_FFFF;
pub const OVERFLOW_HIT: u32 = 0xFFFF_FFFE;

#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub b12: Vec2,
}

pub fn trace_ray(scene: &PackedScene, o: Vec3, d: Vec3, t_max: f32, any_hit: bool) -> Hit {
    let mut hit = Hit {
        t: t_max,
        triangle: NO_HIT,
        b12: Vec2::ZERO,
    };
    let shear = ray_shear(d);
    let inv_d = Vec3::ONE / d;
    let mut stack_item = [0u32; BVH_STACK_SIZE as usize];
    let mut stack_t = [0f32; BVH_STACK_SIZE as usize];
    let mut sp = 0usize;
    let mut item = scene.bvh_root;
    let mut work = 0u32;
    loop {
        if item & BVH_LEAF_BIT != 0 {
            let first = item & BVH_LEAF_FIRST_MASK;
            let count = (item >> BVH_LEAF_COUNT_SHIFT) & BVH_LEAF_COUNT_MASK;
            work += count;
            if work > BVH_MAX_ITERATIONS {
                hit.triangle = OVERFLOW_HIT;
                return hit;
            }
            for i in first..first + count {
                let tv = &scene.tri_verts[i as usize];
                if let Some((t, b12)) =
                    intersect_triangle(o, &shear, tv.v0.into(), tv.v1.into(), tv.v2.into(), hit.t)
                {
                    hit = Hit {
                        t,
                        triangle: i,
                        b12,
                    };
                    if any_hit {
                        return hit;
                    }
                }
            }
        } else {
            work += 1;
            if work > BVH_MAX_ITERATIONS {
                hit.triangle = OVERFLOW_HIT;
                return hit;
            }
            let n = &scene.nodes[item as usize];
            let tl = intersect_aabb(o, inv_d, n.left_min.into(), n.left_max.into(), hit.t);
            let tr = intersect_aabb(o, inv_d, n.right_min.into(), n.right_max.into(), hit.t);
            if tl != FLT_MAX && tr != FLT_MAX {
                if sp == BVH_STACK_SIZE as usize {
                    hit.triangle = OVERFLOW_HIT;
                    return hit;
                }
                let left_first = tl <= tr;
                stack_item[sp] = if left_first { n.right } else { n.left };
                stack_t[sp] = if left_first { tr } else { tl };
                sp += 1;
                item = if left_first { n.left } else { n.right };
                continue;
            }
            if tl != FLT_MAX {
                item = n.left;
                continue;
            }
            if tr != FLT_MAX {
                item = n.right;
                continue;
            }
        }
        let mut found = false;
        while sp > 0 && !found {
            sp -= 1;
            found = stack_t[sp] < hit.t;
            item = stack_item[sp];
        }
        if !found {
            return hit;
        }
    }
}
