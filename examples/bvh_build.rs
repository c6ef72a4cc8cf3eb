//! BVH build speed and tree quality of each preset vkpt may use
//! (`packed::bvh::BuildPreset`: obvhs' PLOC presets and vkpt's binned
//! SAH builder), on a glTF scene's triangles:
//! wall and CPU seconds per build (the fastest of `--rounds`), million
//! triangles per second, and the SAH cost relative to the `medium` preset's
//! tree (what the renderer used before presets were chosen by size).
//!
//!     cargo run --release --example bvh_build -- SCENE.gltf [--rounds N] [--preset NAME]
//!
//! The numbers in docs/performance.md ("BVH build") come from it.

use std::time::Instant;
use vkpt::packed::bvh::{self, BuildPreset};
use vkpt::scene::{LoadOptions, Scene};

/// User plus system CPU seconds of this process so far.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes only the struct it is given.
    let usage = unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_SELF, &mut usage);
        usage
    };
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(usage.ru_utime) + secs(usage.ru_stime)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut scene_path = None;
    let mut rounds = 3;
    let mut presets: Vec<BuildPreset> = BuildPreset::ALL.to_vec();
    let mut k = 0;
    while k < args.len() {
        match args[k].as_str() {
            "--rounds" => {
                k += 1;
                rounds = args.get(k).and_then(|a| a.parse().ok()).unwrap_or(rounds);
            }
            "--preset" => {
                k += 1;
                let name = args.get(k).map(String::as_str).unwrap_or("");
                presets = BuildPreset::ALL
                    .into_iter()
                    .filter(|p| p.name() == name)
                    .collect();
                anyhow::ensure!(!presets.is_empty(), "no preset named {name:?}");
            }
            path => scene_path = Some(std::path::PathBuf::from(path)),
        }
        k += 1;
    }
    let path = scene_path.ok_or_else(|| {
        anyhow::anyhow!("usage: bvh_build SCENE.gltf [--rounds N] [--preset NAME]")
    })?;
    let start = Instant::now();
    let scene = Scene::open_file(&path, &LoadOptions::default())?.at(0.0)?;
    let n = scene.triangles.len();
    println!(
        "{}: {n} triangles, loaded in {:.2} s; {} threads",
        path.display(),
        start.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    let mut medium_sah = None;
    println!(
        "| preset | wall s | CPU s | M triangles/s (wall) | nodes | SAH cost | SAH / medium |"
    );
    println!("|---|---|---|---|---|---|---|");
    let mut rows = Vec::new();
    for &preset in presets.iter().rev() {
        let (mut wall, mut cpu) = (f64::MAX, f64::MAX);
        let mut sah = 0.0;
        let mut nodes = 0;
        for _ in 0..rounds {
            let (w0, c0) = (Instant::now(), cpu_seconds());
            let tree = bvh::build_preset(&scene.triangles, preset)?;
            wall = wall.min(w0.elapsed().as_secs_f64());
            cpu = cpu.min(cpu_seconds() - c0);
            sah = bvh::sah_cost(&tree.nodes);
            nodes = tree.nodes.len();
        }
        if preset == BuildPreset::Medium {
            medium_sah = Some(sah);
        }
        rows.push((preset, wall, cpu, nodes, sah));
    }
    for (preset, wall, cpu, nodes, sah) in rows.into_iter().rev() {
        let relative = medium_sah.map_or("-".to_string(), |m| format!("{:.3}", sah / m));
        println!(
            "| {} | {wall:.3} | {cpu:.3} | {:.2} | {nodes} | {sah:.2} | {relative} |",
            preset.name(),
            n as f64 / wall / 1e6
        );
    }
    Ok(())
}
