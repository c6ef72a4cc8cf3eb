//! The CPU reference: the same estimator as the GPU kernels, in Rust. Each
//! file here mirrors `shaders/common/<name>.glsl` with the same function
//! names and constants; `render.rs` plays the wavefront driver's part.

pub mod anisotropy;
pub mod aov;
pub mod bsdf;
pub mod bvh;
pub mod bvh_avx2;
pub mod bvh_ordered;
pub mod bvh_packet;
#[cfg(target_arch = "x86_64")]
pub mod bvh_window;
pub mod camera;
pub mod clearcoat;
pub mod dispersion;
pub mod gltf_layers;
pub mod integrator;
pub mod intersect;
pub mod lanes;
pub mod lanes_delta;
pub mod lights;
pub mod microfacet;
pub mod motion;
pub mod render;
pub mod rng;
pub mod rng_lanes;
pub mod sampling;
pub mod shading_frame;
pub mod sheen;
pub mod simd;
pub mod textures;
pub mod thin_film;
pub mod trace;
pub(crate) mod wide;
