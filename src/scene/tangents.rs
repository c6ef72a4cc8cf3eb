//! Tangents for normal mapping when a primitive has none (glTF says a
//! renderer should generate them, MikkTSpace-style).
//!
//! Per triangle, the tangent is dP/du from the UV derivatives, and the
//! bitangent sign w says whether glTF's bitangent `w · cross(n, t)` points
//! along -dP/dv (glTF's v runs down the image, the normal map's +Y up).
//! Vertex tangents are the area-weighted sums of the tangents of the
//! triangles around the vertex *with the same sign*, so mirrored UV islands
//! sharing a vertex do not cancel (MikkTSpace splits such vertices too).
//! Unlike MikkTSpace we weight by area rather than corner angle, and do not
//! split vertices at UV seams beyond the sign: tangents are smooth across
//! same-handed seams. Shading orthogonalizes against the normal.

use glam::{Vec2, Vec3, Vec4};
use std::collections::HashMap;

/// Per-corner tangents (xyz unit or zero when the UVs are degenerate
/// everywhere around the vertex; w = ±1) of triangles `tris` over the
/// indexed vertices.
pub fn generate_tangents(positions: &[Vec3], uvs: &[Vec2], tris: &[[u32; 3]]) -> Vec<[Vec4; 3]> {
    let face = |t: &[u32; 3]| -> Option<(Vec3, f32)> {
        let [a, b, c] = t.map(|i| i as usize);
        let (dp1, dp2) = (positions[b] - positions[a], positions[c] - positions[a]);
        let (d1, d2) = (uvs[b] - uvs[a], uvs[c] - uvs[a]);
        let det = d1.x * d2.y - d2.x * d1.y;
        if !(det.abs() > 0.0) {
            return None;
        }
        let dpdu = (dp1 * d2.y - dp2 * d1.y) / det;
        let dpdv = (dp2 * d1.x - dp1 * d2.x) / det;
        let n = dp1.cross(dp2);
        let area = 0.5 * n.length();
        let t = dpdu.normalize_or_zero();
        if t == Vec3::ZERO || !area.is_finite() {
            return None;
        }
        let w = if n.cross(dpdu).dot(-dpdv) < 0.0 {
            -1.0
        } else {
            1.0
        };
        Some((t * area, w))
    };
    let faces: Vec<Option<(Vec3, f32)>> = tris.iter().map(face).collect();
    // (vertex, sign is negative) -> summed tangent.
    let mut sums: HashMap<(u32, bool), Vec3> = HashMap::new();
    for (t, f) in tris.iter().zip(&faces) {
        if let Some((tan, w)) = f {
            for &v in t {
                *sums.entry((v, *w < 0.0)).or_insert(Vec3::ZERO) += *tan;
            }
        }
    }
    tris.iter()
        .zip(&faces)
        .map(|(t, f)| {
            let w = f.map_or(1.0, |f| f.1);
            t.map(|v| {
                let sum = sums.get(&(v, w < 0.0)).copied().unwrap_or(Vec3::ZERO);
                sum.normalize_or_zero().extend(w)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quad in the xy plane facing +z, u along +x and v down the image
    /// (along -y): glTF's standard layout, whose bitangent is +y.
    #[test]
    fn tangent_follows_u_and_sign_gives_bitangent_up_the_image() {
        let p = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let uv = [
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        let t = generate_tangents(&p, &uv, &[[0, 1, 2], [0, 2, 3]]);
        for corner in t.iter().flatten() {
            assert!((corner.truncate() - Vec3::X).length() < 1e-6, "{corner}");
            assert_eq!(corner.w, 1.0);
            let bitangent = corner.w * Vec3::Z.cross(corner.truncate());
            assert!((bitangent - Vec3::Y).length() < 1e-6);
        }
    }

    /// Mirroring the UVs (u running along -x) flips the tangent and the
    /// sign, and a vertex shared by both halves keeps one tangent per sign.
    #[test]
    fn mirrored_uvs_get_the_other_sign_without_cancelling() {
        let p = [
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
        ];
        // Left triangle: u grows to +x; right triangle: u grows to -x.
        let uv = [
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ];
        let t = generate_tangents(&p, &uv, &[[0, 1, 2], [1, 3, 2]]);
        for c in t[0] {
            assert!(
                (c.truncate() - Vec3::X).length() < 1e-6 && c.w == 1.0,
                "{c}"
            );
        }
        for c in t[1] {
            assert!(
                (c.truncate() + Vec3::X).length() < 1e-6 && c.w == -1.0,
                "{c}"
            );
            // Bitangent still up the image (+y).
            let b = c.w * Vec3::Z.cross(c.truncate());
            assert!((b - Vec3::Y).length() < 1e-6);
        }
    }

    #[test]
    fn degenerate_uvs_give_a_zero_tangent() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let uv = [Vec2::ZERO; 3];
        let t = generate_tangents(&p, &uv, &[[0, 1, 2]]);
        assert_eq!(t[0][0], Vec4::new(0.0, 0.0, 0.0, 1.0));
    }
}
