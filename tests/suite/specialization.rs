//! Kernels specialized to a scene (src/features.rs) trace exactly the paths
//! the all-features kernels trace: leaving out code a scene never reaches
//! must not change a single pixel. And the features detected are the ones
//! each bundled scene uses.

use crate::common;

use common::*;
use vkpt::cpu::common::lights::{environment_shines, suns_shine};
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
const SCENES: [(&str, &[&str]); 8] = [
    ("scenes/cornell-box.gltf", &["sobol"]),
    // Glass among Lambert walls and a mirror: shading split by material.
    (
        "scenes/cornell-spheres.gltf",
        &["gltf-material", "sobol", "split-shade"],
    ),
    (
        "scenes/materials-showcase.gltf",
        &["phong", "gltf-material", "sobol", "split-shade"],
    ),
    (
        "scenes/textured.gltf",
        &["textures", "alpha-mask", "gltf-material", "sobol"],
    ),
    (
        "scenes/lights-showcase.gltf",
        &["gltf-material", "analytic-lights", "sobol", "split-shade"],
    ),
    ("scenes/env-sky.gltf", &["environment-map", "sobol"]),
    // Tangents read by anisotropy in a scene without textures.
    (
        "scenes/coat-grid.gltf",
        &[
            "gltf-material",
            "sobol",
            "clearcoat",
            "anisotropy",
            "split-shade",
        ],
    ),
    (
        "scenes/depth-of-field.gltf",
        &[
            "gltf-material",
            "analytic-lights",
            "environment-map",
            "thin-lens",
            "sobol",
            "light-tree",
            "split-shade",
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

/// Shading split by material (`KernelFeatures::split_shade`): extend sorts
/// the hits into a basic queue (misses, unless nothing at infinity shines;
/// lights, Lambert and mirror materials), shaded by `shade_basic` compiled without the Phong and glTF
/// code (or, where a glTF material has a lobe, without the lobes: plain
/// glTF hits too), and a full one. Every path must come out bit for bit as
/// one `shade` kernel for all hits renders it, on every scene above that
/// splits, on materials-grid with dispersive glass, whose paths carry a
/// colour channel from the glass on to the walls, and on materials-grid
/// with one sheen material, whose plain glTF materials the basic queue
/// takes.
#[test]
fn shading_split_by_material_traces_the_same_paths() {
    let Some(mut split) = gpu_renderer("split shading") else {
        return;
    };
    let Some(mut whole) = gpu_renderer("one shade kernel") else {
        return;
    };
    split.split_shade = true;
    whole.split_shade = false;
    let mut cases: Vec<(String, _, _)> = SCENES
        .iter()
        .filter(|(_, expected)| expected.contains(&"split-shade"))
        .map(|(path, _)| {
            let (scene, packed) = load(path);
            (path.to_string(), scene, packed)
        })
        .collect();
    // materials-grid with one material made a glTF material and edited.
    let grid = |material: &str, edit: &dyn Fn(&mut vkpt::scene::Material)| {
        let (mut scene, _) = load("scenes/materials-grid.gltf");
        let m = scene
            .materials
            .iter_mut()
            .find(|m| m.name == material)
            .unwrap_or_else(|| panic!("materials-grid has a material {material}"));
        m.kind = vkpt::scene::MaterialKind::Gltf;
        edit(m);
        let packed = vkpt::packed::PackedScene::new(&scene).expect("packs");
        (scene, packed)
    };
    let (scene, packed) = grid("glass", &|m| m.lobes.dispersion = 2.0);
    cases.push(("materials-grid, dispersive glass".into(), scene, packed));
    let (scene, packed) = grid("smooth blue plastic", &|m| {
        m.lobes.sheen_color = glam::Vec3::splat(0.6);
        m.lobes.sheen_roughness = 0.15;
    });
    cases.push(("materials-grid, one sheen material".into(), scene, packed));
    // lights-showcase without its environment, its suns widened so that
    // escaped rays meet them: misses shaded for suns alone.
    let (mut scene, _) = load("scenes/lights-showcase.gltf");
    scene.environment = None;
    scene.environment_map = None;
    let mut suns = 0;
    for l in &mut scene.lights {
        if let vkpt::scene::LightKind::Sun { angular_diameter } = &mut l.kind {
            *angular_diameter = 1.2;
            suns += 1;
        }
    }
    assert!(suns > 0, "lights-showcase has sun disks");
    let packed = vkpt::packed::PackedScene::new(&scene).expect("packs");
    cases.push(("lights-showcase, suns only".into(), scene, packed));
    assert!(cases.len() >= 4, "too few scenes split shading");
    // Both kinds of basic queue: without the glTF BSDF (Lambert and mirror
    // hits), and, where some glTF material has a lobe, with it but without
    // the lobes (plain glTF hits too: materials-grid with one sheen
    // material; coat-grid, where every glTF material has a lobe).
    let mut keeps_gltf = [false, false];
    // Escaped rays that end in extend (nothing at infinity shines) and ones
    // shaded for the environment or a sun they see.
    let mut escapes_dark = [false, false];
    for (name, scene, packed) in &cases {
        let s = settings(7);
        let params = packed.render_params(scene, &s, 1 << 12).expect("params");
        let basic = KernelFeatures::of(packed, &params).basic_shade();
        let gltf = basic[vkpt::constants::SPEC_GLTF_MATERIAL as usize] != 0;
        keeps_gltf[gltf as usize] = true;
        println!("{name}: the basic queue's kernel has the glTF BSDF: {gltf}");
        let dark = !environment_shines(&params) && !suns_shine(packed);
        escapes_dark[dark as usize] = true;
        let a = render_gpu(&mut split, scene, packed, &s);
        assert!(
            split.kernel_module("shade_basic").is_some(),
            "{name}: shade_basic was not compiled, so shading was not split"
        );
        let b = render_gpu(&mut whole, scene, packed, &s);
        assert!(
            whole.kernel_module("shade_basic").is_none(),
            "{name}: the unsplit renderer split shading"
        );
        let differ = pixels_differing(&a, &b, 0.0);
        println!("{name}: split shading: {differ} of 384 pixels differ");
        assert_eq!(differ, 0, "{name}: splitting shading changes the image");
    }
    assert_eq!(
        keeps_gltf,
        [true, true],
        "both kinds of basic queue are tested"
    );
    assert_eq!(
        escapes_dark,
        [true, true],
        "scenes where escaped rays end in extend and where they are shaded are both tested"
    );
}
