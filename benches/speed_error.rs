//! Speed against error on the bundled scenes: `vkpt bench` (src/bench/) with
//! modest spp steps, every back end side by side.
//!
//!     cargo bench --bench speed_error
//!     VKPT_BENCH_WIDTH=256 VKPT_BENCH_MAX_SPP=512 VKPT_BENCH_REPEAT=3 cargo bench --bench speed_error
//!
//! Writes target/bench-speed-error/bench.csv and one log-log plot per scene;
//! references are rendered once (1024 spp) and cached (see `vkpt bench --help`).

mod common;

use common::env_or;
use std::path::Path;
use vkpt::bench::{BenchConfig, run};

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let max_spp = env_or("VKPT_BENCH_MAX_SPP", 64).max(1);
    let config = BenchConfig {
        scenes: ["cornell-box", "materials-showcase", "white-furnace"]
            .iter()
            .map(|s| root.join("scenes").join(format!("{s}.gltf")))
            .collect(),
        width: env_or("VKPT_BENCH_WIDTH", 128),
        spp_steps: (0..=max_spp.ilog2()).map(|i| 1 << i).collect(),
        reference_spp: env_or("VKPT_BENCH_REFERENCE_SPP", 1024),
        repeat: env_or("VKPT_BENCH_REPEAT", 1),
        out_dir: root.join("target/bench-speed-error"),
        ..Default::default()
    };
    if let Err(e) = run(&config, &mut |line| println!("{line}"), &|_, _| {}) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
