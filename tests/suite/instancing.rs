//! Instancing (a two-level BVH, `packed::instances`): a room whose gems
//! and lamps are meshes placed several times, by nodes and by
//! `EXT_mesh_gpu_instancing`, rotated, scaled unevenly and mirrored. The
//! instanced scene must render what the same scene renders with every
//! placement copied (`--instancing off`, and a file the test flattens by
//! hand, placing each vertex itself), on the CPU back end and the kernels,
//! and the kernels must trace the same paths as the CPU for the same seed.

use crate::common;

use common::gltf_builder::GltfBuilder;
use common::*;
use glam::{DMat3, DMat4, DQuat, DVec3};
use std::path::{Path, PathBuf};
use vkpt::packed::PackedScene;
use vkpt::render::{RenderSettings, Sampler};
use vkpt::scene::{InstancingMode, LoadOptions, Scene};

/// A mesh: positions, normals, triangle corners, material.
struct Mesh {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<[u16; 3]>,
    material: usize,
}

/// The room: floor, ceiling, back wall (white), left (red), right (green).
fn room() -> Mesh {
    let quads: [[[f32; 3]; 4]; 5] = [
        [[-1., 0., -1.], [-1., 0., 1.], [1., 0., 1.], [1., 0., -1.]], // floor, up
        [[-1., 2., -1.], [1., 2., -1.], [1., 2., 1.], [-1., 2., 1.]], // ceiling, down
        [[-1., 0., -1.], [1., 0., -1.], [1., 2., -1.], [-1., 2., -1.]], // back, +z
        [[-1., 0., -1.], [-1., 2., -1.], [-1., 2., 1.], [-1., 0., 1.]], // left, +x
        [[1., 0., -1.], [1., 0., 1.], [1., 2., 1.], [1., 2., -1.]],   // right, -x
    ];
    let mut m = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        indices: Vec::new(),
        material: 0,
    };
    for q in quads {
        let (a, b, c) = (
            DVec3::from(q[0].map(f64::from)),
            DVec3::from(q[1].map(f64::from)),
            DVec3::from(q[2].map(f64::from)),
        );
        let n = (b - a).cross(c - a).normalize().as_vec3().to_array();
        let base = m.positions.len() as u16;
        m.positions.extend(q);
        m.normals.extend([n; 4]);
        m.indices.push([base, base + 1, base + 2]);
        m.indices.push([base, base + 2, base + 3]);
    }
    m
}

/// An octahedron with smooth normals, turned off its axes: an instance's
/// uneven scale then changes their directions, so normals placed by the
/// matrix instead of its inverse transpose show.
fn gem() -> Mesh {
    let turn = glam::Quat::from_euler(glam::EulerRot::XYZ, 0.5, 0.7, 0.3);
    let p: [[f32; 3]; 6] = [
        [1., 0., 0.],
        [-1., 0., 0.],
        [0., 1., 0.],
        [0., -1., 0.],
        [0., 0., 1.],
        [0., 0., -1.],
    ]
    .map(|v| (turn * glam::Vec3::from(v)).to_array());
    let faces = [
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    Mesh {
        positions: p.to_vec(),
        normals: p.to_vec(),
        indices: faces.to_vec(),
        material: 3,
    }
}

/// A lamp: a one-sided quad facing down, 0.3 wide.
fn lamp() -> Mesh {
    Mesh {
        positions: vec![
            [-0.15, 0., -0.15],
            [0.15, 0., -0.15],
            [0.15, 0., 0.15],
            [-0.15, 0., 0.15],
        ],
        normals: vec![[0., -1., 0.]; 4],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        material: 4,
    }
}

/// Where the gems are: turned, scaled unevenly, one mirrored.
fn gem_placements() -> Vec<DMat4> {
    let at = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    vec![
        DMat4::from_scale_rotation_translation(
            DVec3::splat(0.25),
            DQuat::from_rotation_y(0.4),
            at(-0.5, 0.3, -0.3),
        ),
        // Flattened hard: normals placed by the matrix instead of its
        // inverse transpose would tilt its reflections far.
        DMat4::from_scale_rotation_translation(
            DVec3::new(0.5, 0.12, 0.3),
            DQuat::from_euler(glam::EulerRot::XYZ, 0.3, 0.5, 0.2),
            at(0.4, 0.45, -0.2),
        ),
        // Mirrored: a negative scale turns the winding.
        DMat4::from_scale_rotation_translation(
            DVec3::new(-0.3, 0.2, 0.25),
            DQuat::from_rotation_z(0.7),
            at(0.0, 0.9, 0.2),
        ),
        DMat4::from_scale_rotation_translation(
            DVec3::splat(0.12),
            DQuat::IDENTITY,
            at(-0.3, 0.15, 0.5),
        ),
    ]
}

/// The lamps: one as modelled, one stretched to 0.75 of its area (1.5 by
/// 0.5), so an instanced emitter's area must be scaled.
fn lamp_placements() -> Vec<DMat4> {
    vec![
        DMat4::from_translation(DVec3::new(-0.4, 1.99, 0.0)),
        DMat4::from_scale_rotation_translation(
            DVec3::new(1.5, 1.0, 0.5),
            DQuat::IDENTITY,
            DVec3::new(0.45, 1.99, 0.3),
        ),
    ]
}

/// How the test's file places the meshes.
#[derive(Clone, Copy, PartialEq)]
enum Layout {
    /// A node per placement, all referencing one mesh.
    Nodes,
    /// One node per mesh with EXT_mesh_gpu_instancing rows.
    GpuInstancing,
    /// Every placement baked into world-space vertices by the test.
    ByHand,
}

const MATERIALS: &str = r#""materials": [
    {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0, "roughnessFactor": 1}},
    {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.1, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 1}},
    {"pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.8, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 1}},
    {"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.7, 0.3, 1], "metallicFactor": 1, "roughnessFactor": 0.25}},
    {"emissiveFactor": [1, 1, 1], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 20}},
     "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}}
  ]"#;

/// Writes the scene in `layout` under `dir`; returns its path.
fn write_scene(dir: &Path, layout: Layout) -> PathBuf {
    write_scene_at(dir, layout, DVec3::ZERO)
}

/// [`write_scene`] with everything, camera included, moved by `offset`.
fn write_scene_at(dir: &Path, layout: Layout, offset: DVec3) -> PathBuf {
    let mut b = GltfBuilder::default();
    let mut meshes = Vec::new();
    let o = offset.to_array();
    let mut nodes = vec![
        format!(
            r#"{{"camera": 0, "translation": [{}, {}, {}]}}"#,
            o[0],
            1.0 + o[1],
            3.2 + o[2]
        ),
        format!(r#"{{"mesh": 0, "translation": {o:?}}}"#),
    ];
    let moved = DMat4::from_translation(offset);
    // The room: three materials, one primitive each (floor, ceiling and
    // back white; left red; right green).
    let r = room();
    let mut room_prims = Vec::new();
    for (material, tris) in [(0, 0..6), (1, 6..8), (2, 8..10)] {
        let idx: Vec<u16> = r.indices[tris].iter().flatten().copied().collect();
        let pos = b.floats(&r.positions.concat(), "VEC3");
        let nor = b.floats(&r.normals.concat(), "VEC3");
        let ind = b.u16s(&idx, "SCALAR");
        room_prims.push(format!(
            r#"{{"attributes": {{"POSITION": {pos}, "NORMAL": {nor}}}, "indices": {ind}, "material": {material}}}"#
        ));
    }
    meshes.push(format!(r#"{{"primitives": [{}]}}"#, room_prims.join(", ")));

    let mut uses_gpu_instancing = false;
    for (mesh, placements) in [(gem(), gem_placements()), (lamp(), lamp_placements())] {
        let add_mesh = |b: &mut GltfBuilder,
                        positions: &[[f32; 3]],
                        normals: &[[f32; 3]],
                        indices: &[[u16; 3]]| {
            let pos = b.floats(&positions.concat(), "VEC3");
            let nor = b.floats(&normals.concat(), "VEC3");
            let ind = b.u16s(&indices.concat(), "SCALAR");
            format!(
                r#"{{"primitives": [{{"attributes": {{"POSITION": {pos}, "NORMAL": {nor}}}, "indices": {ind}, "material": {}}}]}}"#,
                mesh.material
            )
        };
        match layout {
            Layout::Nodes => {
                meshes.push(add_mesh(
                    &mut b,
                    &mesh.positions,
                    &mesh.normals,
                    &mesh.indices,
                ));
                let k = meshes.len() - 1;
                for m in &placements {
                    nodes.push(format!(
                        r#"{{"mesh": {k}, "matrix": {:?}}}"#,
                        (moved * *m).to_cols_array()
                    ));
                }
            }
            Layout::GpuInstancing => {
                meshes.push(add_mesh(
                    &mut b,
                    &mesh.positions,
                    &mesh.normals,
                    &mesh.indices,
                ));
                let k = meshes.len() - 1;
                let (mut t, mut r, mut s) = (Vec::new(), Vec::new(), Vec::new());
                for m in &placements {
                    // A mirror comes out as a negative x scale.
                    let (scale, rotation, translation) = m.to_scale_rotation_translation();
                    t.extend(translation.as_vec3().to_array());
                    r.extend(rotation.as_quat().to_array());
                    s.extend(scale.as_vec3().to_array());
                }
                let (t, r, s) = (
                    b.floats(&t, "VEC3"),
                    b.floats(&r, "VEC4"),
                    b.floats(&s, "VEC3"),
                );
                nodes.push(format!(
                    r#"{{"mesh": {k}, "translation": {o:?}, "extensions": {{"EXT_mesh_gpu_instancing": {{"attributes": {{"TRANSLATION": {t}, "ROTATION": {r}, "SCALE": {s}}}}}}}}}"#
                ));
                uses_gpu_instancing = true;
            }
            Layout::ByHand => {
                for m in &placements {
                    let normal_matrix = DMat3::from_mat4(*m).inverse().transpose();
                    let flip = m.determinant() < 0.0;
                    let positions: Vec<[f32; 3]> = mesh
                        .positions
                        .iter()
                        .map(|p| {
                            m.transform_point3(DVec3::from(p.map(f64::from)))
                                .as_vec3()
                                .to_array()
                        })
                        .collect();
                    let normals: Vec<[f32; 3]> = mesh
                        .normals
                        .iter()
                        .map(|n| {
                            (normal_matrix * DVec3::from(n.map(f64::from)))
                                .normalize()
                                .as_vec3()
                                .to_array()
                        })
                        .collect();
                    let indices: Vec<[u16; 3]> = mesh
                        .indices
                        .iter()
                        .map(|&[a, b, c]| if flip { [a, c, b] } else { [a, b, c] })
                        .collect();
                    meshes.push(add_mesh(&mut b, &positions, &normals, &indices));
                    nodes.push(format!(r#"{{"mesh": {}}}"#, meshes.len() - 1));
                }
            }
        }
    }
    let used = if uses_gpu_instancing {
        r#""extensionsUsed": ["KHR_materials_emissive_strength", "EXT_mesh_gpu_instancing"]"#
    } else {
        r#""extensionsUsed": ["KHR_materials_emissive_strength"]"#
    };
    let scene_nodes: Vec<String> = (0..nodes.len()).map(|i| i.to_string()).collect();
    let body = format!(
        r#"{used},
  "scene": 0,
  "scenes": [{{"nodes": [{}]}}],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.75, "znear": 0.01}}}}],
  "nodes": [{}],
  "meshes": [{}],
  {MATERIALS}"#,
        scene_nodes.join(", "),
        nodes.join(",\n    "),
        meshes.join(",\n    ")
    );
    assert!(
        layout != Layout::ByHand || offset == DVec3::ZERO,
        "the hand-flattened scene stays at the origin"
    );
    let name = match layout {
        Layout::Nodes => "instanced-nodes",
        Layout::GpuInstancing => "instanced-gpu-instancing",
        Layout::ByHand => "flattened-by-hand",
    };
    let path = if offset == DVec3::ZERO {
        dir.join(format!("{name}.gltf"))
    } else {
        dir.join(format!("{name}-moved.gltf"))
    };
    std::fs::write(&path, b.finish(&body)).expect("scene written");
    path
}

fn load_with(path: &Path, instancing: InstancingMode) -> (Scene, PackedScene) {
    let options = LoadOptions {
        instancing,
        ..Default::default()
    };
    let scene = Scene::load_with(path, &options).expect("scene loads");
    let packed = PackedScene::new(&scene).expect("scene packs");
    (scene, packed)
}

fn settings(seed: u32, spp: u32) -> RenderSettings {
    RenderSettings {
        width: 40,
        height: 40,
        spp,
        max_depth: None,
        seed,
        camera: 0,
        sampler: Sampler::Independent,
        ..Default::default()
    }
}

#[test]
fn the_loader_keeps_repeated_meshes_once() {
    let dir = fresh_output_dir("instancing", "keeps_once");
    for layout in [Layout::Nodes, Layout::GpuInstancing] {
        let path = write_scene(&dir, layout);
        let (scene, packed) = load_with(&path, InstancingMode::On);
        let inst = scene.instancing.as_ref().expect("a two-level scene");
        assert_eq!(inst.placed, 10, "the room stays in place");
        assert_eq!(inst.meshes.len(), 2, "the gem and the lamp, once each");
        assert_eq!(inst.instances.len(), 6);
        assert_eq!(scene.triangles.len(), 10 + 8 + 2);
        assert_eq!(inst.placed_triangles(), 10 + 4 * 8 + 2 * 2);
        let stats = packed.instancing.expect("instancing stats");
        assert_eq!(stats.instances, 7, "the room is placed once too");
        assert_eq!(packed.instances.len(), 7);
        // Both lamps are emitters, without their triangles copied.
        assert_eq!(packed.emitters.len(), 4);
        // One level when asked, and by default for so small a scene.
        for mode in [InstancingMode::Off, InstancingMode::Auto] {
            let (flat, packed) = load_with(&path, mode);
            assert!(flat.instancing.is_none());
            assert!(packed.instances.is_empty());
            assert_eq!(flat.triangles.len(), 10 + 4 * 8 + 2 * 2);
        }
    }
}

/// The instanced scene, by nodes and by EXT_mesh_gpu_instancing, renders
/// what the same scene flattened by hand renders (CPU back end,
/// independent seeds, variance-aware).
#[test]
fn instanced_scene_equals_the_scene_flattened_by_hand() {
    let dir = fresh_output_dir("instancing", "equals_flattened");
    let (flat_scene, flat) = load_with(&write_scene(&dir, Layout::ByHand), InstancingMode::Off);
    let reference = render_cpu(&flat_scene, &flat, &settings(1, 256));
    for layout in [Layout::Nodes, Layout::GpuInstancing] {
        let (scene, packed) = load_with(&write_scene(&dir, layout), InstancingMode::On);
        assert!(!packed.instances.is_empty());
        let image = render_cpu(&scene, &packed, &settings(2, 256));
        assert_agree(
            "instanced_scene_equals_the_scene_flattened_by_hand",
            &image,
            &reference,
        );
    }
}

/// The kernels trace the same paths through the two levels as the CPU
/// back end (same seed), and agree with the one-level render.
#[test]
fn instanced_scene_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("instanced_scene_gpu_matches_cpu") else {
        return;
    };
    let dir = fresh_output_dir("instancing", "gpu_matches_cpu");
    let (scene, packed) = load_with(
        &write_scene(&dir, Layout::GpuInstancing),
        InstancingMode::On,
    );
    let s = settings(3, 16);
    let a = render_gpu(&mut gpu, &scene, &packed, &s);
    let b = render_cpu(&scene, &packed, &s);
    let differing = pixels_differing(&a, &b, 1e-4);
    println!(
        "{differing} of {} pixels differ by more than 1e-4",
        a.mean.len()
    );
    assert!(
        (differing as f64) < 0.01 * a.mean.len() as f64,
        "{differing} pixels differ"
    );
    let (flat_scene, flat) = load_with(&write_scene(&dir, Layout::ByHand), InstancingMode::Off);
    let reference = render_cpu(&flat_scene, &flat, &settings(4, 256));
    let image = render_gpu(&mut gpu, &scene, &packed, &settings(5, 256));
    assert_agree("instanced_scene_gpu_matches_cpu", &image, &reference);
}

/// Precision stays with instances: the scene 1e6 m from the file's origin
/// (node transforms composed in f64 and rebased on the camera) renders
/// what it renders at the origin.
#[test]
fn instanced_scene_far_from_the_origin_renders_the_same() {
    let dir = fresh_output_dir("instancing", "far_from_origin");
    for layout in [Layout::Nodes, Layout::GpuInstancing] {
        let (near_scene, near) = load_with(&write_scene(&dir, layout), InstancingMode::On);
        let far_at = DVec3::new(1e6, -3e5, 2e6);
        let (far_scene, far) = load_with(&write_scene_at(&dir, layout, far_at), InstancingMode::On);
        assert!(!far.instances.is_empty());
        let a = render_cpu(&near_scene, &near, &settings(6, 256));
        let b = render_cpu(&far_scene, &far, &settings(7, 256));
        assert_agree(
            "instanced_scene_far_from_the_origin_renders_the_same",
            &b,
            &a,
        );
    }
}
