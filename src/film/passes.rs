//! How a back end renders in passes and what it hands back: the protocol
//! both the CPU reference and the Vulkan renderer follow, so the layer
//! above (`render/`) drives either the same way.

use super::Film;
use std::time::Duration;

/// What a render produced and measured.
pub struct RenderResult {
    pub film: Film,
    /// Samples every pixel of `film` has: the spp asked for, or fewer when a
    /// `PassControl` stopped the render early.
    pub spp: u32,
    /// "CPU back end (N threads)" or the Vulkan device's name.
    pub device_name: String,
    pub render_time: Duration,
    pub extension_rays: u64,
    pub shadow_rays: u64,
    /// Rays whose BVH traversal exceeded the stack or iteration bound.
    pub traversal_overflows: u64,
    /// Samples dropped because they were NaN or infinite.
    pub nonfinite_samples: u64,
    /// Paths the per-path loop schedule parked for the wavefront kernels to
    /// finish (lavapipe's loop limit: `path_loop.comp`); 0 otherwise.
    pub paths_parked: u64,
    /// The features the kernels were specialized to (Vulkan only).
    pub kernel_variant: Option<String>,
    /// Total time per kernel, from timestamp queries (GPU only).
    pub kernel_times: Vec<(String, Duration)>,
}

/// Progress callback: samples finished so far, out of the total. Every
/// back end first reports 0 when tracing starts (after kernels are compiled
/// and the scene is uploaded), so that rates exclude start-up.
pub type Progress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// Both back ends render in passes, each adding the same number of samples to
/// every pixel, so between passes the film is a consistent image (every pixel
/// has the same sample count). After each pass the renderer asks its
/// `PassControl` whether to go on.
pub trait PassControl {
    /// Called after each pass with the samples per pixel finished so far;
    /// `film()` returns the film as it is now (on the GPU, a read-back: call
    /// it only when needed). Returns `false` to stop here.
    fn after_pass(
        &mut self,
        spp: u32,
        film: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool>;

    /// Whether the renderer may lengthen its passes as it goes (fewer
    /// pauses between them): not where the control predicts the next pass
    /// from the last one (a time limit).
    fn passes_may_grow(&self) -> bool {
        true
    }
}

/// Renders every sample asked for.
pub struct RenderAll;

impl PassControl for RenderAll {
    fn after_pass(
        &mut self,
        _: u32,
        _: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool> {
        Ok(true)
    }
}

/// Paths per pass the back ends aim for: passes are whole samples of every
/// pixel, as many as fit (at least one).
pub fn pass_spp(pixels: u64, paths: u64) -> u32 {
    (paths / pixels.max(1)).clamp(1, u32::MAX as u64) as u32
}
