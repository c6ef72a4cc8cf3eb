//! The triangles' vertices again as structure of arrays, for the CPU back
//! end's eight-wide triangle test in a moving scene: eight consecutive
//! triangles' x of v0 are one vector load instead of a gather (gathers cost
//! AMD cores about as much as the whole test), at every time step
//! (`packed::motion`). Still scenes read `triangle_blocks`, where a window
//! of eight is contiguous. Built on first use, so the Vulkan back end never
//! pays for it.

use crate::packed::layout::TriangleVerts;

/// Nine arrays, `coords[3 * vertex + axis][step * triangles + triangle]`,
/// each padded with 8 zeros so a load of eight triangles starting at any
/// triangle stays inside. The fields are private so that the nine arrays
/// stay equally long: the AVX2 test checks one of them for all nine.
pub struct TriangleSoa {
    coords: [Vec<f32>; 9],
    /// Triangles per time step (still scenes have one step).
    triangles: usize,
}

/// Padding after the last triangle.
pub const SOA_PADDING: usize = 8;

impl TriangleSoa {
    /// Triangles per time step.
    pub fn triangles(&self) -> usize {
        self.triangles
    }

    /// The length of every one of the nine arrays.
    pub fn len(&self) -> usize {
        self.coords[0].len()
    }

    /// Never: even no triangles leave the padding.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Array `c` (3 * vertex + axis), `len()` floats.
    pub fn coords(&self, c: usize) -> &[f32] {
        &self.coords[c]
    }

    pub fn new(tris: &[TriangleVerts]) -> TriangleSoa {
        let coords = std::array::from_fn(|c| {
            let (vertex, axis) = (c / 3, c % 3);
            tris.iter()
                .map(|t| [t.v0, t.v1, t.v2][vertex][axis])
                .chain(std::iter::repeat_n(0.0, SOA_PADDING))
                .collect()
        });
        TriangleSoa {
            coords,
            triangles: tris.len(),
        }
    }

    /// The vertices of every time step of a moving scene, from the motion
    /// buffer's positions (`packed::motion`).
    pub fn moving(motion: &crate::packed::motion::PackedMotion, triangles: usize) -> TriangleSoa {
        let records = motion.steps as usize * triangles;
        let base = motion.vertex_base as usize;
        let coords = std::array::from_fn(|c| {
            let (vertex, axis) = (c / 3, c % 3);
            (0..records)
                .map(|r| f32::from_bits(motion.texels[base + 3 * r + vertex][axis]))
                .chain(std::iter::repeat_n(0.0, SOA_PADDING))
                .collect()
        });
        TriangleSoa { coords, triangles }
    }
}
