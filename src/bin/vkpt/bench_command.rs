//! `vkpt bench SCENE...`: maps the command line onto `vkpt::bench`, with a
//! progress bar for the converged reference it may render first.

use crate::args::{BenchArgs, depth_limit};
use crate::errors::in_flags;
use crate::progress::RenderProgress;
use vkpt::bench::{BenchConfig, run as run_bench};

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    let mut config = BenchConfig {
        scenes: args.scenes,
        devices: args.device,
        schedules: args.schedule,
        width: args.frame.width.unwrap_or(256),
        height: args.frame.height,
        max_depth: depth_limit(args.frame.max_depth),
        sampler: args.frame.sampler,
        texture_filter: args.frame.texture_filter,
        reference: args.reference,
        reference_spp: args.reference_spp,
        out_dir: args.output,
        repeat: args.repeat,
        seed: args.seed,
        denoise: args.denoise,
        light_sampler: args.light_sampler.mode(),
        ..BenchConfig::default()
    };
    if config.denoise {
        // Before any reference takes minutes.
        vkpt::image::denoise::available().map_err(anyhow::Error::msg)?;
    }
    if !args.spp.is_empty() {
        anyhow::ensure!(
            args.spp.windows(2).all(|w| w[0] < w[1]),
            "--spp must list increasing counts of at least 1, e.g. 1,4,16"
        );
        config.spp_steps = args.spp;
    }
    // The reference's pixel count is only known once its scene is loaded:
    // the bar shows the fraction done and samples/s.
    let progress = RenderProgress::new(0, false, true);
    let reports = run_bench(
        &config,
        &mut |line| println!("{}", in_flags(line)),
        &|done, total| progress.update(done, total),
    );
    progress.finish();
    reports.map(|_| ())
}
