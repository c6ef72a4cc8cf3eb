//! Twin of `shaders/common/bvh.glsl`: the same bounded traversal, so an
//! overflow on one back end is an overflow on the other.

use super::intersect::{intersect_aabb, intersect_triangle, ray_shear};
use super::sampling::FLT_MAX;
use crate::constants::{BVH_MAX_ITERATIONS, BVH_STACK_SIZE};
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
    let nodes = &scene.nodes;
    let root = &nodes[0];
    if intersect_aabb(o, inv_d, root.min.into(), root.max.into(), t_max) == FLT_MAX {
        return hit;
    }
    let mut stack_node = [0u32; BVH_STACK_SIZE as usize];
    let mut stack_t = [0f32; BVH_STACK_SIZE as usize];
    let mut sp = 0usize;
    let mut node = 0u32;
    let mut work = 0u32;
    loop {
        let n = &nodes[node as usize];
        work += 1 + n.count;
        if work > BVH_MAX_ITERATIONS {
            hit.triangle = OVERFLOW_HIT;
            return hit;
        }
        let mut descend = false;
        if n.count > 0 {
            for i in n.first..n.first + n.count {
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
            let left = &nodes[n.first as usize];
            let right = &nodes[n.first as usize + 1];
            let tl = intersect_aabb(o, inv_d, left.min.into(), left.max.into(), hit.t);
            let tr = intersect_aabb(o, inv_d, right.min.into(), right.max.into(), hit.t);
            if tl != FLT_MAX || tr != FLT_MAX {
                descend = true;
                if tl != FLT_MAX && tr != FLT_MAX {
                    if sp == BVH_STACK_SIZE as usize {
                        hit.triangle = OVERFLOW_HIT;
                        return hit;
                    }
                    let left_first = tl <= tr;
                    stack_node[sp] = if left_first { n.first + 1 } else { n.first };
                    stack_t[sp] = if left_first { tr } else { tl };
                    sp += 1;
                    node = if left_first { n.first } else { n.first + 1 };
                } else {
                    node = if tl != FLT_MAX { n.first } else { n.first + 1 };
                }
            }
        }
        if !descend {
            let mut found = false;
            while sp > 0 && !found {
                sp -= 1;
                found = stack_t[sp] < hit.t;
                node = stack_node[sp];
            }
            if !found {
                return hit;
            }
        }
    }
}
