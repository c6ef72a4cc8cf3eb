//! Every bundled scene renders bit-identically to a recorded hash, on both
//! back ends: a refactor that is meant to change no pixel is checked to
//! change none, to the last bit of every film pixel (mean and M2 sums and
//! the sample count).
//!
//! The hashes were recorded from main at 3e297af (before the restructure of
//! issue 12) on the development machine (AMD EPYC, AVX2, Mesa 22.3.6
//! lavapipe). A change that is *meant* to change pixels (a new estimator, a
//! different float order) updates them: run
//! `VKPT_BLESS_GOLDEN=1 cargo test --release --test golden_pixels -- --nocapture`
//! and paste the printed table, saying why in the commit message.

mod common;

use common::*;
use vkpt::packed::layout::FilmPixel;
use vkpt::render::RenderSettings;

/// FNV-1a over every film pixel's bytes.
fn film_hash(pixels: &[FilmPixel]) -> u64 {
    vkpt::cache::fnv1a(bytemuck::cast_slice(pixels), vkpt::cache::FNV_OFFSET)
}

fn settings() -> RenderSettings {
    RenderSettings {
        width: 32,
        height: 24,
        spp: 4,
        seed: 11,
        ..Default::default()
    }
}

/// (scene, CPU film hash, Vulkan film hash).
const GOLDEN: &[(&str, u64, u64)] = &[
    (
        "scenes/alpha-holes.gltf",
        0xf76ad5218ff0ecfb,
        0xc00ab144f6e078cc,
    ),
    (
        "scenes/alpha-mask.gltf",
        0xf76ad5218ff0ecfb,
        0xc00ab144f6e078cc,
    ),
    (
        "scenes/cornell-box.gltf",
        0x55f4631eafe817b8,
        0x96d66fbed83eec3e,
    ),
    (
        "scenes/depth-of-field.gltf",
        0xdb490a5d603c78ab,
        0xe8c2182fe687933b,
    ),
    (
        "scenes/env-sky.gltf",
        0x08d28d911dd052d8,
        0x348ea73ce3ef2de1,
    ),
    (
        "scenes/furnace-glass-0.67.gltf",
        0x682ba733cfa00344,
        0x8896c326823d78c0,
    ),
    (
        "scenes/furnace-glass-1.5.gltf",
        0x187afb79a8f5d3cb,
        0x6f79a33c7b0dfaa0,
    ),
    (
        "scenes/furnace-mirror-0.8.gltf",
        0x5a3d11e65020454f,
        0x5a3d11e65020454f,
    ),
    (
        "scenes/furnace-rough-metal.gltf",
        0x8f19510beeef1d18,
        0x13a3a807dbfab131,
    ),
    (
        "scenes/hard/cornell-scaled-1e-3.gltf",
        0xe0ac847049aabbdd,
        0xabcfd35799556e14,
    ),
    (
        "scenes/hard/cornell-scaled-1e4.gltf",
        0x2f1f60ab5cbf0584,
        0xbd6cabb93645b121,
    ),
    (
        "scenes/hard/cornell-translated-1e5.gltf",
        0x4d42e3f58c966346,
        0xfd00797f37551366,
    ),
    (
        "scenes/hard/degenerate.gltf",
        0x3f0aa1ac00a656c2,
        0x124c4c6f2b627ce7,
    ),
    (
        "scenes/hard/glass-and-tiny-light.gltf",
        0xa2a0b4b0ee98ec8a,
        0x8e50d635c42b658a,
    ),
    (
        "scenes/hard/grazing-plane.gltf",
        0x169d1f765c60f998,
        0xf796b706daf428f3,
    ),
    (
        "scenes/hard/inside-sphere-scaled-1e-3.gltf",
        0x6a66b31c158c2325,
        0x6a66b31c158c2325,
    ),
    (
        "scenes/hard/inside-sphere-translated-1e5.gltf",
        0x6a66b31c158c2325,
        0x6a66b31c158c2325,
    ),
    (
        "scenes/hard/inside-sphere-with-hole.gltf",
        0x05e4db6af6207f15,
        0xed712e381e7f1cfb,
    ),
    (
        "scenes/hard/inside-sphere.gltf",
        0x6a66b31c158c2325,
        0x6a66b31c158c2325,
    ),
    (
        "scenes/hard/low-poly-smooth-sphere.gltf",
        0x2dcda47cf892ac3f,
        0x541ffafab9fa7d68,
    ),
    (
        "scenes/lights-showcase.gltf",
        0x603fb7016f1f28f0,
        0x1c7cb75506aba382,
    ),
    (
        "scenes/materials-grid.gltf",
        0x583847b2cf7296c0,
        0x766fa90909bd7ec4,
    ),
    (
        "scenes/materials-showcase.gltf",
        0xe6bee52fc5f599d9,
        0xd6ea181d28d249f2,
    ),
    (
        "scenes/textured.gltf",
        0x5eaec39fb93358e1,
        0x2a0d49b2aa0e6b32,
    ),
    (
        "scenes/white-furnace.gltf",
        0x5c4ea5e39a23f1a8,
        0x5469e395633e98c9,
    ),
];

fn bundled_scenes() -> Vec<String> {
    let mut scenes = Vec::new();
    for dir in ["scenes", "scenes/hard"] {
        let entries = std::fs::read_dir(repo_path(dir)).expect("scenes folder is readable");
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().to_string();
            if name.ends_with(".gltf") {
                scenes.push(format!("{dir}/{name}"));
            }
        }
    }
    scenes.sort();
    scenes
}

#[test]
fn every_bundled_scene_renders_bit_identically_to_its_recorded_hash() {
    let bless = std::env::var("VKPT_BLESS_GOLDEN").is_ok_and(|v| v == "1");
    let mut gpu = gpu_renderer("golden_pixels");
    let s = settings();
    let mut table = String::new();
    let mut mismatches = Vec::new();
    let scenes = bundled_scenes();
    for path in &scenes {
        let (scene, packed) = load(path);
        let cpu = vkpt::cpu::render::render(&scene, &packed, &s, &|_, _| {})
            .expect("CPU render succeeds");
        let cpu_hash = film_hash(&cpu.film.pixels);
        let gpu_hash = gpu.as_mut().map(|g| {
            let r = g
                .render(&scene, &packed, &s, &|_, _| {})
                .expect("GPU render succeeds");
            film_hash(&r.film.pixels)
        });
        table.push_str(&format!(
            "    ({path:?}, 0x{cpu_hash:016x}, 0x{:016x}),\n",
            gpu_hash.unwrap_or(0)
        ));
        if bless {
            continue;
        }
        let Some(&(_, want_cpu, want_gpu)) = GOLDEN.iter().find(|(p, _, _)| p == path) else {
            mismatches.push(format!("{path}: no recorded hash (bless the table)"));
            continue;
        };
        if cpu_hash != want_cpu {
            mismatches.push(format!(
                "{path}: CPU film hash 0x{cpu_hash:016x}, recorded 0x{want_cpu:016x}"
            ));
        }
        if let Some(h) = gpu_hash
            && h != want_gpu
        {
            mismatches.push(format!(
                "{path}: Vulkan film hash 0x{h:016x}, recorded 0x{want_gpu:016x}"
            ));
        }
    }
    if bless {
        println!("const GOLDEN: &[(&str, u64, u64)] = &[\n{table}];");
        return;
    }
    for (p, _, _) in GOLDEN {
        assert!(
            scenes.iter().any(|s| s == p),
            "{p} has a recorded hash but is no longer bundled"
        );
    }
    assert!(
        mismatches.is_empty(),
        "{} film(s) changed:\n{}\nIf the change is intended, re-record with \
         VKPT_BLESS_GOLDEN=1 (see the file's doc).",
        mismatches.len(),
        mismatches.join("\n")
    );
}
