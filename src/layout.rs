//! GPU-visible structs, defined once here and declared again in
//! `shaders/common/types.glsl`. `tests/layout.rs` reads the compiled SPIR-V
//! and checks that every size and member offset agrees: a wrong offset gives
//! a wrong image with no validation error.
//!
//! The CPU reference reads the same packed arrays, so both back ends see
//! identical data. Every struct is packed in 16-byte rows (std430).

use bytemuck::{Pod, Zeroable};

/// BVH2 inner node holding the bounds of both children, 64 bytes, so one
/// fetch tests both. A child is an *item*: the index of another inner node,
/// or a leaf packed as `BVH_LEAF_BIT | count << BVH_LEAF_COUNT_SHIFT | first`
/// (triangles `first .. first + count` of the BVH-ordered arrays).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct BvhNode {
    pub left_min: [f32; 3],
    pub left: u32,
    pub left_max: [f32; 3],
    pub right: u32,
    pub right_min: [f32; 3],
    pub _pad0: u32,
    pub right_max: [f32; 3],
    pub _pad1: u32,
}

/// Triangle vertices for the watertight intersection test, 48 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct TriangleVerts {
    pub v0: [f32; 3],
    pub material: u32,
    pub v1: [f32; 3],
    pub _pad1: u32,
    pub v2: [f32; 3],
    pub _pad2: u32,
}

/// What shading needs of a triangle besides its vertices, 48 bytes.
/// `light_pmf` is the probability that light sampling picks this triangle
/// among the emissive triangles (0 when it does not emit); MIS needs it when
/// a BSDF-sampled ray lands on the triangle.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct TriangleShading {
    pub n0: [f32; 3],
    pub light_pmf: f32,
    pub n1: [f32; 3],
    pub _pad1: f32,
    pub n2: [f32; 3],
    pub _pad2: f32,
}

/// A material as the kernels see it, 32 bytes. Lambertian albedo
/// `base_color.rgb`; `emission` is radiance leaving the front face (both
/// faces when `double_sided != 0`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct MaterialData {
    pub base_color: [f32; 4],
    pub emission: [f32; 3],
    pub double_sided: u32,
}

/// An emissive triangle for light sampling, 16 bytes. Emitters are chosen
/// with probability proportional to power; `cdf` is the inclusive running sum
/// of those probabilities.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct Emitter {
    pub triangle: u32,
    pub cdf: f32,
    pub pmf: f32,
    pub area: f32,
}

/// Everything uniform across a render, 112 bytes (a uniform buffer).
/// The camera looks along `cam_forward`; a pixel's ray direction is
/// `forward + sx * tan_half_fov * aspect * right + sy * tan_half_fov * up`
/// with `sx, sy` in [-1, 1] (y up).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct RenderParams {
    pub cam_position: [f32; 3],
    pub tan_half_fov: f32,
    pub cam_right: [f32; 3],
    pub aspect: f32,
    pub cam_up: [f32; 3],
    pub _pad0: f32,
    pub cam_forward: [f32; 3],
    pub _pad1: f32,
    /// Uniform environment radiance, and the probability that light sampling
    /// picks the environment rather than an emissive triangle.
    pub environment: [f32; 3],
    pub env_select_prob: f32,
    pub width: u32,
    pub height: u32,
    /// Number of segments a path may have (`DEPTH_UNLIMITED` for no limit).
    pub max_depth: u32,
    pub seed: u32,
    pub num_emitters: u32,
    pub num_triangles: u32,
    /// Path slots in the wavefront pool (each ray queue holds this many).
    pub pool_size: u32,
    /// The item traversal starts from (see `BvhNode`).
    pub bvh_root: u32,
}

/// Per-dispatch values, 16 bytes of push constants. A chunk is `count` paths;
/// path `i` renders pixel `(pixel_start + i) % pixels` for sample
/// `sample_start + (pixel_start + i) / pixels`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct PushConstants {
    pub pixel_start: u32,
    pub sample_start: u32,
    pub count: u32,
    /// Bounce index: 0 for camera rays. Also picks the ray queue by parity.
    pub bounce: u32,
}

/// One pixel of the film, 32 bytes: running mean (Welford) with the sample
/// count in `mean.w`, and the sum of squared deviations in `m2.rgb`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct FilmPixel {
    pub mean: [f32; 4],
    pub m2: [f32; 4],
}

const _: () = {
    assert!(std::mem::size_of::<BvhNode>() == 64);
    assert!(std::mem::size_of::<TriangleVerts>() == 48);
    assert!(std::mem::size_of::<TriangleShading>() == 48);
    assert!(std::mem::size_of::<MaterialData>() == 32);
    assert!(std::mem::size_of::<Emitter>() == 16);
    assert!(std::mem::size_of::<RenderParams>() == 112);
    assert!(std::mem::size_of::<PushConstants>() == 16);
    assert!(std::mem::size_of::<FilmPixel>() == 32);
};
