//! The twins of `shaders/common/`: each file mirrors `<name>.glsl` with the
//! same function names and constants, and computes what the kernels compute
//! in the same order, so the CPU back end and the GPU trace the same paths.
//! Nothing here names the fast code above it (`cpu::fast`).

pub mod anisotropy;
pub mod aov;
pub mod bsdf;
pub mod bvh;
pub mod camera;
pub mod clearcoat;
pub mod dispersion;
pub mod instances;
pub mod integrator;
pub mod intersect;
pub mod light_bvh;
pub mod lights;
pub mod microfacet;
pub mod motion;
pub mod rng;
pub mod sampling;
pub mod shading_frame;
pub mod sheen;
pub mod textures;
pub mod thin_film;
pub mod trace;
