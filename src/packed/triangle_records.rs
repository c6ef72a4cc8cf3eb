//! The triangles' records as the kernels read them, in the BVH's slot
//! order: `TriangleVerts` (positions, material) and `TriangleShading`
//! (vertex normals), from the scene's `Triangle`s.
//!
//! `gather` reads the scene's triangles and leaves them; `consume` takes
//! them and frees them as it packs, so that a big mesh never holds all of
//! its triangles (76 bytes each) beside all of their records (96 bytes).
//! Both give the same records.

use crate::packed::layout::{TriangleShading, TriangleVerts};
use crate::scene::{AlphaMode, Material, Triangle};
use rayon::prelude::*;

/// Triangles packed between shrinks of their array in `consume`.
const CHUNK: usize = 1 << 16;

/// The records of `triangles[order[slot]]` for every slot.
pub fn gather(
    triangles: &[Triangle],
    order: &[u32],
    materials: &[Material],
) -> (Vec<TriangleVerts>, Vec<TriangleShading>) {
    let mut verts = crate::huge_pages::zeroed_vec(order.len());
    let mut shading = crate::huge_pages::zeroed_vec(order.len());
    verts
        .par_iter_mut()
        .zip(&mut shading)
        .zip(order)
        .for_each(|((v, s), &i)| (*v, *s) = record(&triangles[i as usize], materials));
    (verts, shading)
}

/// `gather`'s records, the triangles freed as they are packed. `order`
/// must be a permutation of the triangles' indices (the BVH's).
///
/// The records are written in the triangles' own order first, from the
/// end a chunk at a time, the triangles' array shrinking behind (at most
/// 96 bytes a triangle held), then each array is gathered into slot order
/// (at most three record arrays of 48 bytes held). Putting the triangles
/// in slot order in place instead holds less, but follows the
/// permutation's cycles one cache miss at a time: 1.2 s on 5 M triangles
/// against about 0.3 s for this.
pub fn consume(
    mut triangles: Vec<Triangle>,
    order: &[u32],
    materials: &[Material],
) -> (Vec<TriangleVerts>, Vec<TriangleShading>) {
    assert_eq!(triangles.len(), order.len(), "one slot per triangle");
    let n = triangles.len();
    // Zeroed pages become resident only as they are written.
    let mut verts: Vec<TriangleVerts> = crate::huge_pages::zeroed_vec(n);
    let mut shading: Vec<TriangleShading> = crate::huge_pages::zeroed_vec(n);
    while !triangles.is_empty() {
        let start = triangles.len().saturating_sub(CHUNK);
        verts[start..]
            .par_iter_mut()
            .zip(&mut shading[start..])
            .zip(&triangles[start..])
            .for_each(|((v, s), t)| (*v, *s) = record(t, materials));
        // A big array sits in its own mapping, so shrinking it returns
        // the pages behind `start` to the system.
        triangles.truncate(start);
        triangles.shrink_to_fit();
    }
    let verts = in_slot_order(verts, order);
    let shading = in_slot_order(shading, order);
    (verts, shading)
}

/// `items[order[slot]]` for every slot; `items` is freed on return.
fn in_slot_order<T: bytemuck::Pod + Send + Sync>(items: Vec<T>, order: &[u32]) -> Vec<T> {
    let mut slots = crate::huge_pages::zeroed_vec(order.len());
    slots
        .par_iter_mut()
        .zip(order)
        .for_each(|(slot, &i)| *slot = items[i as usize]);
    slots
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
