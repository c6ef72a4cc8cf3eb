//! vkpt: a physically based path tracer on Vulkan compute, with a CPU
//! reference that implements the same estimator.

pub mod constants;
pub mod film;
pub mod layout;
pub mod output;
pub mod scene;
pub mod stats;
