//! The CPU back end's own fast code, which has no kernel twin: each piece
//! computes what the twins (`cpu::common`) compute, with the same float
//! operations in the same order, only more of it at once.
//!
//! Words used here, one meaning each:
//! - a *lane* is one slot of a vector register, and `wide::WIDTH` is how
//!   many a register holds (sixteen f32 where the build targets AVX-512,
//!   eight elsewhere): a packet's rays, the lane schedule's paths and a
//!   leaf window's triangles are each `WIDTH` wide;
//! - the *lane schedule* (`lanes`) shades a register of paths side by side;
//! - a *leaf window* (`leaf_window`) is `WIDTH` of a node's leaf triangles
//!   tested against one ray in one register;
//! - an *octet* (`octant::Octet`) is eight leaf triangles tested together by
//!   the octant-order traversal, read from a *triangle block*
//!   (`cache::triangle_blocks`) in a still scene.
//!
//! Which traversal runs when is `cpu::traversal`'s choice, not theirs.

pub mod cache;
pub mod lanes;
pub mod lanes_delta;
pub mod lanes_rng;
#[cfg(target_arch = "x86_64")]
pub mod leaf_window;
pub mod light_tree_walk;
pub mod nearest_first;
pub mod octant;
pub mod packet;
pub mod simd;
pub(crate) mod wide;

/// Lanes of one vector register (`wide::WIDTH`), for code outside the crate.
pub use wide::WIDTH;
