//! The CPU back end: the same estimator as the GPU kernels, in Rust, and
//! the fast schedule that runs it on a CPU.
//!
//! - [`common`]: the twins of `shaders/common/<name>.glsl`, one file each
//!   with the same name, the same functions and the same arithmetic, so the
//!   same seed traces the same paths on both back ends.
//! - [`fast`]: the CPU's own code, which has no kernel twin: the lane
//!   schedule (a vector register of paths shaded together), the vector
//!   registers it runs on, and the vectorized BVH traversals.
//! - [`traversal`]: the one place that chooses which traversal a ray takes.
//! - [`render`]: the driver, playing the wavefront driver's part.
//!
//! Imports point down that list's reverse: `common` names nothing above it,
//! `fast` only `common`, and `traversal` and `render` both
//! (`tests/suite/layering.rs` checks it).

pub mod common;
pub mod fast;
pub mod render;
pub mod traversal;
