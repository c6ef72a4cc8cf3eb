//! The triangles' records as the kernels read them, in the BVH's slot
//! order: `TriangleVerts` (positions, material) and `TriangleShading`
//! (vertex normals), from the scene's `Triangle`s.
//!
//! `gather` reads the scene's triangles and leaves them; `consume` takes
//! them and frees them as it packs, so that a big mesh never holds all of
//! its triangles (76 bytes each) beside all of their records (96 bytes):
//! it puts the triangles in slot order in place, then packs them from the
//! end a chunk at a time, shrinking their array behind it. Both give the
//! same records.

use crate::packed::layout::{TriangleShading, TriangleVerts};
use crate::scene::{AlphaMode, Material, Triangle};

/// Triangles packed between shrinks of their array in `consume`.
const CHUNK: usize = 1 << 16;

/// The records of `triangles[order[slot]]` for every slot.
pub fn gather(
    triangles: &[Triangle],
    order: &[u32],
    materials: &[Material],
) -> (Vec<TriangleVerts>, Vec<TriangleShading>) {
    order
        .iter()
        .map(|&i| record(&triangles[i as usize], materials))
        .unzip()
}

/// `gather`'s records, the triangles freed as they are packed. `order`
/// must be a permutation of the triangles' indices (the BVH's).
pub fn consume(
    mut triangles: Vec<Triangle>,
    order: &[u32],
    materials: &[Material],
) -> (Vec<TriangleVerts>, Vec<TriangleShading>) {
    assert_eq!(triangles.len(), order.len(), "one slot per triangle");
    into_slot_order(&mut triangles, order);
    let n = triangles.len();
    // Zeroed pages become resident only as they are written.
    let mut verts: Vec<TriangleVerts> = bytemuck::zeroed_vec(n);
    let mut shading: Vec<TriangleShading> = bytemuck::zeroed_vec(n);
    while !triangles.is_empty() {
        let start = triangles.len().saturating_sub(CHUNK);
        for (k, t) in triangles[start..].iter().enumerate() {
            (verts[start + k], shading[start + k]) = record(t, materials);
        }
        // A big array sits in its own mapping, so shrinking it returns
        // the pages behind `start` to the system.
        triangles.truncate(start);
        triangles.shrink_to_fit();
    }
    (verts, shading)
}

/// Rearranges `items` so that `items[slot]` is the old `items[order[slot]]`,
/// following the permutation's cycles (one bit per item on the side).
fn into_slot_order<T: Copy>(items: &mut [T], order: &[u32]) {
    let mut placed = vec![0u64; items.len().div_ceil(64)];
    for start in 0..items.len() {
        if placed[start / 64] >> (start % 64) & 1 != 0 {
            continue;
        }
        let first = items[start];
        let mut slot = start;
        loop {
            placed[slot / 64] |= 1 << (slot % 64);
            let from = order[slot] as usize;
            if from == start {
                items[slot] = first;
                break;
            }
            items[slot] = items[from];
            slot = from;
        }
    }
}

/// One triangle's records.
fn record(t: &Triangle, materials: &[Material]) -> (TriangleVerts, TriangleShading) {
    let [p0, p1, p2] = t.positions;
    let [n0, n1, n2] = t.normals;
    let masked = materials[t.material as usize].alpha_mode != AlphaMode::Opaque;
    (
        TriangleVerts {
            v0: p0.into(),
            material: t.material,
            v1: p1.into(),
            alpha_mask: masked as u32,
            v2: p2.into(),
            ..Default::default()
        },
        TriangleShading {
            n0: n0.into(),
            n1: n1.into(),
            n2: n2.into(),
            ..Default::default()
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// `consume` gives `gather`'s records, for a permutation with long and
    /// short cycles over more than one chunk.
    #[test]
    fn consuming_the_triangles_packs_what_gathering_them_does() {
        let n = CHUNK * 2 + 777;
        let triangles: Vec<Triangle> = (0..n)
            .map(|i| {
                let f = i as f32;
                Triangle {
                    positions: [
                        Vec3::splat(f),
                        Vec3::new(f, 1.0, 2.0),
                        Vec3::new(0.0, f, 3.0),
                    ],
                    normals: [Vec3::X, Vec3::new(0.0, f, 1.0), Vec3::Z * f],
                    material: (i % 2) as u32,
                }
            })
            .collect();
        // A shuffle (Fisher-Yates on an LCG) that leaves some in place.
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut state = 12345u64;
        for i in (1..n).rev() {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let j = (state >> 33) as usize % (i + 1);
            if i % 97 != 0 {
                order.swap(i, j);
            }
        }
        let opaque = Material::lambert("opaque", Vec3::ONE);
        let blended = Material {
            alpha_mode: AlphaMode::Blend,
            ..opaque.clone()
        };
        let materials = vec![opaque, blended];
        let (gv, gs) = gather(&triangles, &order, &materials);
        let (cv, cs) = consume(triangles.clone(), &order, &materials);
        assert!(gv == cv, "vertex records differ");
        assert!(gs == cs, "shading records differ");
        assert_eq!(
            cv[5].v0,
            triangles[order[5] as usize].positions[0].to_array()
        );
    }
}
