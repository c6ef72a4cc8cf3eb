//! The Vulkan kernels and the CPU reference implement the same estimator:
//! independent renders of the Cornell box must agree under a variance-aware
//! test (per pixel, per block and over the whole image, with Šidák and
//! Bonferroni corrections; see `vkpt::image::compare::compare`).
//!
//! The second test checks the comparison has the power to see a real bug:
//! a 3% albedo error on one side must be rejected.

use crate::common;

use common::*;
use vkpt::image::compare::{compare, write_failure_evidence};
use vkpt::render::{RenderSettings, Sampler};

const ALPHA: f64 = 0.01;

fn settings(seed: u32) -> RenderSettings {
    RenderSettings {
        width: 48,
        height: 48,
        spp: 512,
        max_depth: None,
        seed,
        camera: 0,
        // The variance-aware comparison estimates each pixel's variance from
        // its samples, which assumes they are independent; Sobol samples of a
        // pixel are not (tests/suite/sampler.rs compares Sobol across seeds).
        sampler: Sampler::Independent,
        ..Default::default()
    }
}

#[test]
fn cornell_box_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("cornell_box_gpu_matches_cpu") else {
        return;
    };
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let a = render_gpu(&mut gpu, &scene, &packed, &settings(1));
    let b = render_cpu(&scene, &packed, &settings(2));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("{cmp}");
    if !cmp.passed() {
        let dir = failure_dir("cornell_box_gpu_matches_cpu");
        write_failure_evidence(&dir, &a, &b, &cmp).expect("evidence written");
        panic!("GPU and CPU disagree; evidence in {}", dir.display());
    }
}

/// The same comparison on the Cornell box with a mirror box, a glass sphere
/// and a Phong sphere: every material model on both back ends.
#[test]
fn materials_showcase_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("materials_showcase_gpu_matches_cpu") else {
        return;
    };
    let (scene, packed) = load("scenes/materials-showcase.gltf");
    let s = |seed| RenderSettings {
        width: 40,
        height: 40,
        spp: 256,
        ..settings(seed)
    };
    let a = render_gpu(&mut gpu, &scene, &packed, &s(5));
    let b = render_cpu(&scene, &packed, &s(6));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("{cmp}");
    if !cmp.passed() {
        let dir = failure_dir("materials_showcase_gpu_matches_cpu");
        write_failure_evidence(&dir, &a, &b, &cmp).expect("evidence written");
        panic!("GPU and CPU disagree; evidence in {}", dir.display());
    }
}

/// Every material path, one sphere each filling a 64 x 48 frame
/// (scenes/materials-grid.gltf): diffuse, Phong, tinted mirror, rough
/// metals, rough and smooth plastic, smooth glass with an air bubble (IOR
/// below 1), rough glass, absorbing glass, thin-walled rough transmission
/// and a tinted KHR_materials_specular layer. A GGX visible-normal sampler
/// planted on the GPU side with the wrong stretch (α² for α) fails here
/// while the showcase, whose spheres cover few pixels, passes it.
#[test]
fn materials_grid_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("materials_grid_gpu_matches_cpu") else {
        return;
    };
    let (scene, packed) = load("scenes/materials-grid.gltf");
    let s = |seed| RenderSettings {
        width: 64,
        height: 48,
        spp: 256,
        ..settings(seed)
    };
    let a = render_gpu(&mut gpu, &scene, &packed, &s(8));
    let b = render_cpu(&scene, &packed, &s(9));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("{cmp}");
    if !cmp.passed() {
        let dir = failure_dir("materials_grid_gpu_matches_cpu");
        write_failure_evidence(&dir, &a, &b, &cmp).expect("evidence written");
        panic!("GPU and CPU disagree; evidence in {}", dir.display());
    }
}

/// The clearcoat and anisotropy lobes (scenes/coat-grid.gltf: coats rough
/// and smooth over plastic, metal and an anisotropic base; anisotropic
/// metals, rotated, of roughness 0, and anisotropic rough glass, with file
/// TANGENTs) on both back ends.
#[test]
fn coat_grid_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("coat_grid_gpu_matches_cpu") else {
        return;
    };
    let (scene, packed) = load("scenes/coat-grid.gltf");
    let s = |seed| RenderSettings {
        width: 64,
        height: 32,
        spp: 256,
        ..settings(seed)
    };
    let a = render_gpu(&mut gpu, &scene, &packed, &s(10));
    let b = render_cpu(&scene, &packed, &s(11));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("{cmp}");
    if !cmp.passed() {
        let dir = failure_dir("coat_grid_gpu_matches_cpu");
        write_failure_evidence(&dir, &a, &b, &cmp).expect("evidence written");
        panic!("GPU and CPU disagree; evidence in {}", dir.display());
    }
}

#[test]
fn comparison_rejects_a_three_percent_albedo_error() {
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let mut brighter = vkpt::packed::PackedScene::new(&scene).expect("packs");
    for m in &mut brighter.materials {
        for c in &mut m.base_color[..3] {
            *c *= 1.03;
        }
    }
    let a = render_cpu(&scene, &packed, &settings(3));
    let b = render_cpu(&scene, &brighter, &settings(4));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("{cmp}");
    assert!(!cmp.passed(), "a 3% albedo error went unnoticed");
}

/// With the same seed both back ends draw the same random numbers for the
/// same path, so they trace the same paths: images agree pixel by pixel up to
/// float rounding (a rounding difference can flip a Russian-roulette or
/// light-selection decision, so a few pixels may differ more). This catches
/// a divergence between a GLSL file and its Rust twin long before statistics
/// would.
#[test]
fn same_seed_traces_the_same_paths() {
    same_seed("same_seed_traces_the_same_paths", "scenes/cornell-box.gltf");
}

/// The same on the materials grid: the twins' glTF lobes draw the same
/// lobe and direction from the same random numbers.
#[test]
fn same_seed_traces_the_same_paths_through_every_gltf_lobe() {
    same_seed(
        "same_seed_traces_the_same_paths_through_every_gltf_lobe",
        "scenes/materials-grid.gltf",
    );
}

/// The same on the materials showcase (mirror, glass, Phong): the twins'
/// BSDFs draw the same lobe and direction from the same random numbers.
#[test]
fn same_seed_traces_the_same_paths_through_every_material() {
    same_seed(
        "same_seed_traces_the_same_paths_through_every_material",
        "scenes/materials-showcase.gltf",
    );
}

/// The same through the clearcoat and anisotropic lobes and their frames.
#[test]
fn same_seed_traces_the_same_paths_through_coats_and_anisotropy() {
    same_seed(
        "same_seed_traces_the_same_paths_through_coats_and_anisotropy",
        "scenes/coat-grid.gltf",
    );
}

/// Both samplers: the GLSL and Rust twins of `rng` draw the same numbers.
fn same_seed(test: &str, path: &str) {
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, packed) = load(path);
    for sampler in [Sampler::Independent, Sampler::Sobol] {
        let s = RenderSettings {
            width: 64,
            height: 64,
            spp: 8,
            sampler,
            ..settings(7)
        };
        let a = render_gpu(&mut gpu, &scene, &packed, &s);
        let b = render_cpu(&scene, &packed, &s);
        let differing = pixels_differing(&a, &b, 1e-4);
        let fraction = differing as f64 / a.mean.len() as f64;
        println!(
            "{test} ({}): {differing} of {} pixels differ by more than 1e-4",
            sampler.name(),
            a.mean.len()
        );
        assert!(
            fraction < 0.01,
            "{}: {:.1}% of pixels differ",
            sampler.name(),
            fraction * 100.0
        );
    }
}

/// The materials grid with glTF PBR extension lobes put on some of its
/// materials (in code: no bundled scene uses them): sheen over diffuse,
/// over smooth plastic and over rough glass, diffuse transmission, and
/// sheen with diffuse transmission over a half metal, and thin films on a
/// rough metal, a white metal and a thin-walled transmitter.
fn lobes_grid() -> (vkpt::scene::Scene, vkpt::packed::PackedScene) {
    use glam::Vec3;
    let (mut scene, _) = load("scenes/materials-grid.gltf");
    let by_name = |scene: &mut vkpt::scene::Scene, name: &str| {
        let i = scene.materials.iter().position(|m| m.name == name);
        i.unwrap_or_else(|| panic!("materials-grid has a material {name}"))
    };
    let edit =
        |scene: &mut vkpt::scene::Scene, name: &str, f: &dyn Fn(&mut vkpt::scene::Material)| {
            let i = by_name(scene, name);
            let m = &mut scene.materials[i];
            m.kind = vkpt::scene::MaterialKind::Gltf;
            f(m);
        };
    edit(&mut scene, "diffuse", &|m| {
        m.lobes.sheen_color = Vec3::new(0.9, 0.7, 0.9);
        m.lobes.sheen_roughness = 0.4;
    });
    edit(&mut scene, "smooth blue plastic", &|m| {
        m.lobes.sheen_color = Vec3::splat(0.6);
        m.lobes.sheen_roughness = 0.15;
    });
    edit(&mut scene, "rough glass", &|m| {
        m.lobes.sheen_color = Vec3::new(0.3, 0.6, 0.9);
        m.lobes.sheen_roughness = 0.8;
    });
    edit(&mut scene, "rough red plastic", &|m| {
        m.lobes.diffuse_transmission = 0.7;
        m.lobes.diffuse_transmission_color = Vec3::new(0.9, 0.8, 0.2);
    });
    edit(&mut scene, "half-metal, tinted specular", &|m| {
        m.lobes.sheen_color = Vec3::splat(0.5);
        m.lobes.sheen_roughness = 0.6;
        m.lobes.diffuse_transmission = 0.5;
    });
    edit(&mut scene, "rough gold", &|m| {
        m.lobes.iridescence = 1.0;
        m.lobes.iridescence_ior = 1.8;
        m.lobes.iridescence_thickness_max = 550.0;
    });
    edit(&mut scene, "white rough metal", &|m| {
        m.roughness = 0.4;
        m.lobes.iridescence = 0.8;
        m.lobes.iridescence_ior = 1.3;
        m.lobes.iridescence_thickness_max = 300.0;
    });
    // KHR_materials_dispersion on the solid glasses (dispersion.rs).
    edit(&mut scene, "glass", &|m| m.lobes.dispersion = 2.0);
    edit(&mut scene, "absorbing green glass", &|m| {
        m.lobes.dispersion = 0.6
    });
    edit(&mut scene, "frosted thin-walled", &|m| {
        m.lobes.iridescence = 1.0;
        m.lobes.iridescence_ior = 1.4;
        m.lobes.iridescence_thickness_max = 250.0;
    });
    let packed = vkpt::packed::PackedScene::new(&scene).expect("packs");
    (scene, packed)
}

/// The dispersion estimator (`dispersion.rs`) keeps one channel × 3 behind
/// the first dispersive surface: with a vanishing dispersion (indices
/// differing by 1e-5) it must have the expectation of plain glass.
#[test]
fn channel_picking_for_dispersion_has_no_bias() {
    let (plain, plain_packed) = load("scenes/materials-grid.gltf");
    let mut scene = plain.clone();
    for m in scene.materials.iter_mut() {
        if m.transmission > 0.0 && m.thickness > 0.0 {
            m.lobes.dispersion = 1e-4;
        }
    }
    let packed = vkpt::packed::PackedScene::new(&scene).expect("packs");
    assert!(
        packed
            .materials
            .iter()
            .any(|m| m.lobes & vkpt::constants::LOBE_DISPERSION != 0),
        "the grid has solid glass"
    );
    let s = |seed| RenderSettings {
        width: 40,
        height: 40,
        spp: 256,
        ..settings(seed)
    };
    let a = render_cpu(&scene, &packed, &s(31));
    let b = render_cpu(&plain, &plain_packed, &s(32));
    common::assert_agree("channel_picking_for_dispersion_has_no_bias", &a, &b);
}

/// GPU = CPU, statistically, through every lobe of `lobes_grid`.
#[test]
fn pbr_lobes_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("pbr_lobes_gpu_matches_cpu") else {
        return;
    };
    let (scene, packed) = lobes_grid();
    let s = |seed| RenderSettings {
        width: 40,
        height: 40,
        spp: 256,
        ..settings(seed)
    };
    let a = render_gpu(&mut gpu, &scene, &packed, &s(21));
    let b = render_cpu(&scene, &packed, &s(22));
    let cmp = compare(&a, &b, ALPHA).expect("comparable images");
    println!("{cmp}");
    if !cmp.passed() {
        let dir = failure_dir("pbr_lobes_gpu_matches_cpu");
        write_failure_evidence(&dir, &a, &b, &cmp).expect("evidence written");
        panic!("GPU and CPU disagree; evidence in {}", dir.display());
    }
}

/// The same seed traces the same paths through the lobes of `lobes_grid`.
#[test]
fn same_seed_traces_the_same_paths_through_the_pbr_lobes() {
    let test = "same_seed_traces_the_same_paths_through_the_pbr_lobes";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let (scene, packed) = lobes_grid();
    let s = RenderSettings {
        width: 64,
        height: 64,
        spp: 8,
        ..settings(7)
    };
    let a = render_gpu(&mut gpu, &scene, &packed, &s);
    let b = render_cpu(&scene, &packed, &s);
    let differing = pixels_differing(&a, &b, 1e-4);
    println!(
        "{test}: {differing} of {} pixels differ by more than 1e-4",
        a.mean.len()
    );
    assert!(
        (differing as f64) < 0.01 * a.mean.len() as f64,
        "{differing} pixels differ"
    );
}

/// No texel view's size bounds the scene (`vkpt::packed::bindings`): with
/// the device's texel-view limit lowered until a scene's largest arrays are
/// each cut into several parts, each read through a view of its own, the
/// kernels still trace the CPU's paths: the same seed gives the same
/// pixels. Between them the three scenes split BVH nodes, triangles,
/// texture coordinates and texels. A part picked
/// wrongly (an off-by-one in the view index) moves whole triangles and
/// texels, far beyond the tolerance.
#[test]
fn split_scene_arrays_trace_the_same_paths() {
    use vkpt::packed::bindings::SCENE_VIEWS;
    let test = "split_scene_arrays_trace_the_same_paths";
    let Some(mut gpu) = gpu_renderer(test) else {
        return;
    };
    let mut split_somewhere = std::collections::BTreeSet::new();
    for path in [
        "scenes/textured.gltf",
        "scenes/textured-terrain.gltf",
        "scenes/cornell-spheres.gltf",
    ] {
        let (scene, packed) = load(path);
        // Each split array's length in texels (16 bytes; texels 4).
        let t = &packed.textures;
        let arrays = [
            ("BVH nodes", 5 * packed.nodes.len()),
            ("triangle vertices", 3 * packed.tri_verts.len()),
            ("triangle shading", 3 * packed.tri_shading.len()),
            ("emitters", packed.emitters.len()),
            ("texture coordinates", 6 * t.tri_texcoords.len()),
            ("texels", t.texels.len()),
        ];
        let largest = arrays.iter().map(|a| a.1).max().unwrap_or(0) as u64;
        // The smallest power of two that leaves every array within
        // SCENE_VIEWS parts and the unsplit views (materials, path state)
        // within one.
        let materials = vkpt::constants::MATERIAL_TEXELS as u64 * packed.materials.len() as u64;
        let part = largest
            .div_ceil(SCENE_VIEWS as u64)
            .max(materials)
            .max(64)
            .next_power_of_two();
        let split: Vec<String> = arrays
            .iter()
            .filter(|a| a.1 as u64 > part)
            .map(|a| {
                split_somewhere.insert(a.0);
                format!("{} in {} parts", a.0, (a.1 as u64).div_ceil(part))
            })
            .collect();
        println!(
            "{test}: {path}: parts of {part} texels: {}",
            split.join(", ")
        );

        let original = gpu.limits_mut().clone();
        gpu.limits_mut().max_texel_buffer_elements = part;
        let s = RenderSettings {
            width: 32,
            height: 32,
            spp: 4,
            ..settings(7)
        };
        let a = render_gpu(&mut gpu, &scene, &packed, &s);
        *gpu.limits_mut() = original;
        let b = render_cpu(&scene, &packed, &s);
        let differing = pixels_differing(&a, &b, 1e-4);
        println!(
            "{test}: {path}: {differing} of {} pixels differ by more than 1e-4",
            a.mean.len()
        );
        assert!(
            differing as f64 / (a.mean.len() as f64) < 0.01,
            "{path}: {differing} pixels differ"
        );
    }
    // Emitters too read through scene_texel, but these scenes have too few
    // to cut (the materials' unsplit view sets the smallest part).
    for array in [
        "BVH nodes",
        "triangle vertices",
        "triangle shading",
        "texture coordinates",
        "texels",
    ] {
        assert!(
            split_somewhere.contains(array),
            "{array} never split: {split_somewhere:?}"
        );
    }
}
