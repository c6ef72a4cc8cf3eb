//! The `vkpt bench` command line.

use super::{BenchConfig, run};
use crate::cli_args::{flag_value, parse_number, split_flag};
use crate::render::DeviceChoice;
use anyhow::{anyhow, bail};
use std::path::PathBuf;

pub const HELP: &str = "\
vkpt bench: speed against error

USAGE:
    vkpt bench SCENE.gltf... [OPTIONS]

Renders each scene on each back end at increasing spp (back ends alternate
step by step) and reports, per step, wall time, kernel time (timestamps),
samples/s, rays/s and the relMSE against a converged reference: the mean over
pixels and channels of (x - ref)^2 / (ref^2 + 0.01). Then prints start-up
costs (device, kernel compile, BVH build, scene upload) and the time each
back end needs to reach relMSE 1e-2 and 1e-3 (log-log interpolation between
steps). Writes DIR/bench.csv and a log-log plot DIR/<scene>.png.

OPTIONS:
        --device LIST       Back ends, comma-separated: auto, gpu, lavapipe, cpu
                            [default: auto,cpu; auto is skipped without Vulkan]
        --spp LIST          spp of each step, comma-separated and increasing
                            [default: 1,2,4,...,512]
        --width N           [default: 256]
        --height N          [default: width / the camera's aspect ratio]
        --max-depth N       As for rendering; -1 = no limit [default: -1]
        --reference FILE    Converged EXR to measure against (one scene only).
                            Default: rendered once at --reference-spp on the
                            first back end and cached under $XDG_CACHE_HOME/vkpt
                            (or ~/.cache/vkpt, or $VKPT_CACHE_DIR)
        --reference-spp N   [default: 4096]
        --repeat N          Render each step N times (back ends taking turns)
                            and keep the fastest: on a shared machine other
                            load only adds time [default: 1]
    -o, --output DIR        [default: vkpt-bench]
    -h, --help              This help
";

/// Parses `vkpt bench` arguments; `None` when help was asked for.
pub fn parse(args: &[String]) -> anyhow::Result<Option<BenchConfig>> {
    let mut c = BenchConfig::default();
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let (flag, inline) = split_flag(arg);
        let mut value = || flag_value(flag, &inline, &mut it, "vkpt bench --help");
        match flag {
            "-h" | "--help" => {
                print!("{HELP}");
                return Ok(None);
            }
            "--device" => {
                c.devices = value()?
                    .split(',')
                    .map(|d| {
                        DeviceChoice::from_name(d.trim()).ok_or_else(|| {
                            anyhow!("--device: '{d}' is not one of auto, gpu, lavapipe, cpu")
                        })
                    })
                    .collect::<anyhow::Result<_>>()?;
            }
            "--spp" => {
                c.spp_steps = value()?
                    .split(',')
                    .map(|s| parse_number::<u32>("--spp", s.trim()))
                    .collect::<anyhow::Result<_>>()?;
                if c.spp_steps.contains(&0) || !c.spp_steps.windows(2).all(|w| w[0] < w[1]) {
                    bail!("--spp must list increasing counts of at least 1, e.g. 1,4,16");
                }
            }
            "--width" => c.width = parse_number(flag, &value()?)?,
            "--height" => c.height = Some(parse_number(flag, &value()?)?),
            "--max-depth" => {
                let d: i64 = parse_number(flag, &value()?)?;
                c.max_depth = match d {
                    -1 => None,
                    d if d >= 1 && d < u32::MAX as i64 => Some(d as u32),
                    _ => bail!("--max-depth must be -1 (no limit) or at least 1, got {d}"),
                };
            }
            "--reference" => c.reference = Some(PathBuf::from(value()?)),
            "--reference-spp" => c.reference_spp = parse_number(flag, &value()?)?,
            "--repeat" => {
                c.repeat = parse_number(flag, &value()?)?;
                if c.repeat == 0 {
                    bail!("--repeat must be at least 1");
                }
            }
            "-o" | "--output" => c.out_dir = PathBuf::from(value()?),
            f if f.starts_with('-') && f.len() > 1 => {
                bail!("unknown option '{f}' for bench (see vkpt bench --help)")
            }
            _ => c.scenes.push(PathBuf::from(arg)),
        }
    }
    if c.scenes.is_empty() {
        bail!("vkpt bench needs at least one scene (see vkpt bench --help)");
    }
    Ok(Some(c))
}

/// Runs `vkpt bench ARGS`; returns the exit status (0 done, 1 failed while
/// benchmarking, 2 bad arguments).
pub fn main(args: &[String]) -> i32 {
    let config = match parse(args) {
        Ok(Some(c)) => c,
        Ok(None) => return 0,
        Err(e) => {
            eprintln!("error: {e:#}");
            return 2;
        }
    };
    match run(&config, &mut |line| println!("{line}")) {
        Ok(_) => 0,
        Err(e) => {
            eprintln!("error: {e:#}");
            1
        }
    }
}
