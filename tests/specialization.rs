//! Kernels specialized to a scene (src/features.rs) trace exactly the paths
//! the all-features kernels trace: leaving out code a scene never reaches
//! must not change a single pixel. And the features detected are the ones
//! each bundled scene uses.

mod common;

use common::*;
use vkpt::packed::features::KernelFeatures;
use vkpt::render::RenderSettings;

fn settings(seed: u32) -> RenderSettings {
    RenderSettings {
        width: 24,
        height: 16,
        spp: 4,
        seed,
        ..Default::default()
    }
}

/// Scene, and the features its kernels must have (the rest must be off).
const SCENES: [(&str, &[&str]); 7] = [
    ("scenes/cornell-box.gltf", &["sobol"]),
    (
        "scenes/materials-showcase.gltf",
        &["phong", "gltf-material", "sobol"],
    ),
    (
        "scenes/textured.gltf",
        &["textures", "alpha-mask", "gltf-material", "sobol"],
    ),
    (
        "scenes/lights-showcase.gltf",
        &["gltf-material", "analytic-lights", "sobol"],
    ),
    ("scenes/env-sky.gltf", &["environment-map", "sobol"]),
    // Tangents read by anisotropy in a scene without textures.
    (
        "scenes/coat-grid.gltf",
        &["gltf-material", "sobol", "clearcoat", "anisotropy"],
    ),
    (
        "scenes/depth-of-field.gltf",
        &[
            "gltf-material",
            "analytic-lights",
            "environment-map",
            "thin-lens",
            "sobol",
        ],
    ),
];

#[test]
fn specialized_kernels_trace_the_same_paths_as_all_features() {
    let Some(mut gpu) = gpu_renderer("specialization") else {
        return;
    };
    for (path, expected) in SCENES {
        let (scene, packed) = load(path);
        let s = settings(3);
        let params = packed
            .render_params(&scene, &s, 1 << 12)
            .expect("render params");
        let features = KernelFeatures::of(&packed, &params);
        let described = features.describe();
        let on: Vec<&str> = described.split(", ").collect();
        assert_eq!(on, expected, "{path}: kernels specialized to '{described}'");

        gpu.all_features = false;
        let specialized = render_gpu(&mut gpu, &scene, &packed, &s);
        gpu.all_features = true;
        let all = render_gpu(&mut gpu, &scene, &packed, &s);
        gpu.all_features = false;
        let differ = pixels_differing(&specialized, &all, 1e-5);
        println!("{path}: kernels '{described}': {differ} of 384 pixels differ from all-features");
        assert_eq!(
            differ, 0,
            "{path}: specialized kernels ('{described}') change the image"
        );
    }
}

/// On lavapipe the large kernels reach the driver specialized ahead by
/// `spirv-opt` (src/gpu/specialize.rs), constants frozen and dead code
/// removed: on every scene above they must render the driver's own
/// specialization's image bit for bit, and they must really be the ones
/// in use.
#[test]
fn kernels_specialized_ahead_trace_the_same_paths() {
    use vkpt::gpu::specialize::Specialized;
    let Some(mut ahead) = gpu_renderer("specialized ahead") else {
        return;
    };
    if !ahead.is_cpu_device() {
        println!("not lavapipe: kernels are not specialized ahead here");
        return;
    }
    let Some(mut driver) = gpu_renderer("specialized by the driver") else {
        return;
    };
    driver.specialize_ahead = false;
    for (path, _) in SCENES {
        let (scene, packed) = load(path);
        let s = settings(5);
        let a = render_gpu(&mut ahead, &scene, &packed, &s);
        let module = ahead.kernel_module("shade").expect("shade is compiled");
        assert!(
            matches!(module, Specialized::Cached(_) | Specialized::Made(_)),
            "{path}: {} (spirv-opt comes with glslang-tools)",
            module.describe()
        );
        let b = render_gpu(&mut driver, &scene, &packed, &s);
        assert!(
            matches!(driver.kernel_module("shade"), Some(Specialized::No(_))),
            "{path}: the driver's specialization was not the one compared"
        );
        // The same arithmetic reaches Mesa, so the same bits come out.
        let differ = pixels_differing(&a, &b, 0.0);
        println!(
            "{path}: {}: {differ} of 384 pixels differ",
            module.describe()
        );
        assert_eq!(
            differ, 0,
            "{path}: shade specialized ahead changes the image"
        );
    }
}
