//! Constants shared by the Rust host, the CPU reference and the GLSL kernels.
//!
//! `build.rs` turns every `pub const` line of this file into a `#define` in
//! `constants.glsl`, so no number is typed twice. Keep each constant on one
//! line as `pub const NAME: u32|f32 = VALUE;`.

/// Invocations per workgroup of every wavefront kernel.
pub const WORKGROUP_SIZE: u32 = 64;

/// Depth of the per-invocation CWBVH traversal stack (one entry per BVH8
/// level at most; obvhs' own traversal uses 32).
pub const BVH_STACK_SIZE: u32 = 32;
/// Upper bound on node visits plus triangle tests in one traversal. lavapipe
/// silently ends an invocation's loops after 65,535 iterations in total; we
/// stop well before and flag the ray as overflowed instead of returning a
/// wrong hit.
pub const BVH_MAX_ITERATIONS: u32 = 16384;

/// Random-number dimensions: the camera uses the first few, then every bounce
/// owns `DIM_PER_BOUNCE` dimensions starting at `DIM_BOUNCE_BASE`.
pub const DIM_CAMERA_JITTER: u32 = 0;
pub const DIM_BOUNCE_BASE: u32 = 8;
pub const DIM_PER_BOUNCE: u32 = 8;
/// Offsets inside one bounce's dimensions.
pub const DIM_LIGHT_SELECT: u32 = 0;
pub const DIM_LIGHT_SAMPLE: u32 = 1;
pub const DIM_BSDF_SAMPLE: u32 = 3;
pub const DIM_RUSSIAN_ROULETTE: u32 = 5;
/// Picks the BSDF lobe (Phong diffuse or specular, dielectric reflection or
/// refraction).
pub const DIM_BSDF_LOBE: u32 = 6;

/// Russian roulette starts at this bounce (0 = the camera ray's hit).
pub const RR_START_BOUNCE: u32 = 3;
/// Continuation probability is min(max throughput, this).
pub const RR_MAX_CONTINUE: f32 = 0.95;
/// Absolute bound on bounces even with `--max-depth` unlimited; with Russian
/// roulette a path reaching it has probability below 0.95^1000.
pub const MAX_BOUNCES_HARD: u32 = 1024;

/// gamma(7) = 7u / (1 - 7u), u = 2^-24: the relative error bound of a point
/// computed as b0 v0 + b1 v1 + b2 v2 in f32 (pbrt-v4, Triangle::
/// InteractionFromIntersection; Higham's gamma_n).
pub const GAMMA7: f32 = 4.172325e-7;
/// gamma(1) = u / (1 - u): one rounding.
pub const GAMMA1: f32 = 5.960465e-8;
/// A hit point's error bound is at least this fraction of its triangle's
/// largest edge component: it covers the rounding of the watertight test
/// itself, so a ray leaving an axis-aligned plane at 0 (zero interpolation
/// error) does not start on it. Relative, so it holds at every scale.
pub const OFFSET_EDGE_FRACTION: f32 = 9.536743e-7;
/// A shadow ray stops this fraction short of its target so it does not hit
/// the light it aims at (relative, so it holds at every scene scale).
pub const SHADOW_RAY_SHORTEN: f32 = 0.0001;

/// Counters buffer slots (u32 each).
pub const COUNTER_RAYS_0: u32 = 0;
pub const COUNTER_RAYS_1: u32 = 1;
pub const COUNTER_SHADOW: u32 = 2;
pub const COUNTER_BVH_OVERFLOW: u32 = 3;
pub const COUNTER_NONFINITE: u32 = 4;
pub const COUNTER_EXTENSION_RAYS_LO: u32 = 5;
pub const COUNTER_EXTENSION_RAYS_HI: u32 = 6;
pub const COUNTER_SHADOW_RAYS_LO: u32 = 7;
pub const COUNTER_SHADOW_RAYS_HI: u32 = 8;
pub const COUNTER_COUNT: u32 = 16;

/// Value of `max_depth` meaning "no limit" (only Russian roulette ends paths).
pub const DEPTH_UNLIMITED: u32 = 0xFFFFFFFF;

/// `MaterialData::kind`: the scattering model of a material.
pub const MATERIAL_LAMBERT: u32 = 0;
pub const MATERIAL_PHONG: u32 = 1;
pub const MATERIAL_MIRROR: u32 = 2;
pub const MATERIAL_DIELECTRIC: u32 = 3;
