//! The light BVH (`packed::light_bvh`, `light_bvh.glsl`): light selection by
//! importance must leave the estimate unchanged. Each scene is rendered with
//! the light BVH forced on and with power sampling, independent seeds, and
//! the images must agree (`compare`, variance-aware): the Cornell box, every
//! analytic light kind (lights-showcase.gltf: spheres, point and spot lights
//! in the tree, directional light and sun beside it), and rooms lit by many
//! small lamps that this file builds. The pmf a leaf's trail gives must be
//! the probability the walk picks it with, and the pmfs of all leaves must
//! sum to one, with and without the receiving normal, which must change
//! the pmfs; a wrong trail (a wrong pmf for MIS) and MIS without the normal
//! light sampling used must be seen failing; the GPU must trace the CPU's
//! paths.

use crate::common;

use common::*;
use glam::Vec3;
use vkpt::constants::LIGHT_TREE_LEAF;
use vkpt::cpu::common::light_bvh::{
    light_tree_importance, light_tree_importance4, light_tree_normal, light_tree_normal_code,
    light_tree_on, light_tree_pmf, light_tree_sample, light_tree_sample_many,
};
use vkpt::cpu::fast::WIDTH;
use vkpt::cpu::fast::cache::CpuScene;
use vkpt::cpu::fast::light_tree_walk;
use vkpt::image::Image;
use vkpt::image::compare::compare;
use vkpt::packed::PackedScene;
use vkpt::render::RenderSettings;
use vkpt::scene::{Camera, Light, LightKind, LightSampler, Material, Scene, Triangle};

fn quad(c: [Vec3; 4], material: u32) -> [Triangle; 2] {
    let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
    let tri = |a: Vec3, b: Vec3, d: Vec3| Triangle {
        positions: [a, b, d],
        normals: [n; 3],
        material,
    };
    [tri(c[0], c[1], c[2]), tri(c[0], c[2], c[3])]
}

/// `rooms` x `rooms` rooms of 4 m, 3 m high, split by walls with a 1 m
/// door in each, each lit by `per_side`^2 small ceiling lamps (facing down;
/// every fifth double-sided) of four radiances over two decades, and one
/// spherical light; the camera stands in the middle room of a 3 x 3 hall,
/// looking through a door.
fn rooms_scene(rooms: usize, per_side: usize) -> Scene {
    let (room, height) = (4.0f32, 3.0f32);
    let size = rooms as f32 * room;
    let mut materials = vec![
        Material::lambert("walls", Vec3::splat(0.6)),
        Material::lambert("floor", Vec3::new(0.5, 0.4, 0.3)),
    ];
    for (k, level) in [1.0f32, 4.6, 21.5, 100.0].iter().enumerate() {
        let mut m = Material::lambert("lamp", Vec3::ZERO);
        m.emission = Vec3::new(1.0, 0.8 - 0.1 * k as f32, 0.5 + 0.1 * k as f32) * *level;
        materials.push(m);
    }
    let mut two_sided = Material::lambert("lamp, both sides", Vec3::ZERO);
    two_sided.emission = Vec3::new(5.0, 5.0, 4.0);
    two_sided.double_sided = true;
    materials.push(two_sided);
    let v = Vec3::new;
    let mut triangles = Vec::new();
    triangles.extend(quad(
        [
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, size),
            v(size, 0.0, size),
            v(size, 0.0, 0.0),
        ],
        1,
    ));
    triangles.extend(quad(
        [
            v(0.0, height, 0.0),
            v(size, height, 0.0),
            v(size, height, size),
            v(0.0, height, size),
        ],
        0,
    ));
    // Outer and partition walls (Lambert scatters on both sides).
    for i in 0..=rooms {
        let c = i as f32 * room;
        for j in 0..rooms {
            let (a, e) = (j as f32 * room, (j + 1) as f32 * room);
            let m = 0.5 * (a + e);
            let spans: Vec<(f32, f32)> = if i == 0 || i == rooms {
                vec![(a, e)]
            } else {
                vec![(a, m - 0.5), (m + 0.5, e)]
            };
            for (u0, u1) in spans {
                triangles.extend(quad(
                    [
                        v(c, 0.0, u0),
                        v(c, height, u0),
                        v(c, height, u1),
                        v(c, 0.0, u1),
                    ],
                    0,
                ));
                triangles.extend(quad(
                    [
                        v(u0, 0.0, c),
                        v(u1, 0.0, c),
                        v(u1, height, c),
                        v(u0, height, c),
                    ],
                    0,
                ));
            }
        }
    }
    let h = 0.1;
    let y = height - 0.001;
    let mut k = 0usize;
    for rx in 0..rooms {
        for rz in 0..rooms {
            for a in 0..per_side {
                for b in 0..per_side {
                    let x = rx as f32 * room + (a as f32 + 0.5) * room / per_side as f32;
                    let z = rz as f32 * room + (b as f32 + 0.5) * room / per_side as f32;
                    let material = if k % 5 == 4 {
                        6
                    } else {
                        2 + (k * 7 % 4) as u32
                    };
                    k += 1;
                    triangles.extend(quad(
                        [
                            v(x - h, y, z - h),
                            v(x + h, y, z - h),
                            v(x + h, y, z + h),
                            v(x - h, y, z + h),
                        ],
                        material,
                    ));
                }
            }
        }
    }
    let eye = v(5.0, 1.5, 5.0);
    Scene {
        source: "light BVH rooms".into(),
        triangles,
        materials,
        lights: vec![Light {
            name: "sphere".into(),
            kind: LightKind::Sphere { radius: 0.15 },
            position: v(3.0, 0.8, 3.2),
            direction: Vec3::NEG_Y,
            color: Vec3::splat(2.0),
            range: None,
        }],
        cameras: vec![Camera {
            aspect_ratio: Some(1.0),
            ..Camera::pinhole(
                "middle",
                eye,
                (v(6.0, 1.2, 8.0) - eye).normalize(),
                Vec3::Y,
                1.3,
            )
        }],
        ..Default::default()
    }
}

fn packed_with(scene: &Scene, sampler: LightSampler) -> (Scene, PackedScene) {
    let mut scene = scene.clone();
    scene.light_sampler = sampler;
    let packed = PackedScene::new(&scene).expect("packs");
    (scene, packed)
}

fn settings(size: u32, spp: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        spp,
        max_depth: Some(4),
        seed,
        camera: 0,
        ..Default::default()
    }
}

/// The light BVH's render and the power-sampled render of `scene` (CPU,
/// independent seeds).
fn both_samplers(scene: &Scene, size: u32, spp: u32) -> (Image, Image) {
    let (s_tree, p_tree) = packed_with(scene, LightSampler::Bvh);
    assert!(light_tree_on(&p_tree), "the light BVH is on");
    let (s_power, p_power) = packed_with(scene, LightSampler::Power);
    assert!(!light_tree_on(&p_power), "power sampling keeps no tree");
    let a = render_cpu(&s_tree, &p_tree, &settings(size, spp, 1));
    let b = render_cpu(&s_power, &p_power, &settings(size, spp, 2));
    (a, b)
}

#[test]
fn light_bvh_agrees_with_power_sampling_on_the_cornell_box() {
    let (scene, _) = load("scenes/cornell-box.gltf");
    let (a, b) = both_samplers(&scene, 32, 512);
    assert_agree(
        "light_bvh_agrees_with_power_sampling_on_the_cornell_box",
        &a,
        &b,
    );
}

#[test]
fn light_bvh_agrees_with_power_sampling_on_every_light_kind() {
    let (scene, _) = load("scenes/lights-showcase.gltf");
    let (a, b) = both_samplers(&scene, 36, 256);
    assert_agree(
        "light_bvh_agrees_with_power_sampling_on_every_light_kind",
        &a,
        &b,
    );
}

#[test]
fn light_bvh_agrees_with_power_sampling_on_many_lights() {
    let scene = rooms_scene(3, 4);
    let (a, b) = both_samplers(&scene, 32, 512);
    assert_agree(
        "light_bvh_agrees_with_power_sampling_on_many_lights",
        &a,
        &b,
    );
}

/// The rooms with every lamp an instance of one of five lamp meshes (some
/// scaled, some mirrored): instanced emitters enter the tree one leaf per
/// placement.
fn instanced_rooms_scene() -> Scene {
    let mut scene = rooms_scene(3, 4);
    let lamps_from = scene
        .triangles
        .iter()
        .position(|t| t.material >= 2)
        .expect("lamps");
    let lamps: Vec<Triangle> = scene.triangles.split_off(lamps_from);
    let placed = scene.triangles.len();
    let mut meshes = Vec::new();
    for material in 2..=6u32 {
        let start = scene.triangles.len();
        let h = 0.1;
        let v = Vec3::new;
        scene.triangles.extend(quad(
            [v(-h, 0.0, -h), v(h, 0.0, -h), v(h, 0.0, h), v(-h, 0.0, h)],
            material,
        ));
        meshes.push(start..scene.triangles.len());
    }
    let mut instances = Vec::new();
    for (k, pair) in lamps.chunks(2).enumerate() {
        let [a, _, c] = pair[0].positions;
        let centre = 0.5 * (a + c);
        let scale = match k % 3 {
            0 => glam::DVec3::ONE,
            1 => glam::DVec3::new(1.5, 1.0, 1.5),
            _ => glam::DVec3::new(-1.0, 1.0, 1.0), // mirrored: winding flips, facing kept
        };
        instances.push(vkpt::scene::Instance {
            mesh: (pair[0].material - 2) as usize,
            to_world: glam::DMat4::from_scale_rotation_translation(
                scale,
                glam::DQuat::IDENTITY,
                centre.as_dvec3(),
            ),
        });
    }
    scene.instancing = Some(vkpt::scene::Instancing {
        placed,
        meshes,
        instances,
    });
    scene
}

#[test]
fn light_bvh_agrees_with_power_sampling_on_instanced_lamps() {
    let scene = instanced_rooms_scene();
    let (_, packed) = packed_with(&scene, LightSampler::Bvh);
    assert!(!packed.instances.is_empty(), "a two-level scene");
    assert_eq!(
        packed.emitters.len(),
        288,
        "one emitter per placed lamp triangle"
    );
    let (a, b) = both_samplers(&scene, 32, 512);
    assert_agree(
        "light_bvh_agrees_with_power_sampling_on_instanced_lamps",
        &a,
        &b,
    );
}

/// Scenes below `LIGHT_TREE_MIN_LIGHTS` emitters keep power sampling
/// (the Cornell box's pixels do not change); many lights get the tree.
#[test]
fn auto_takes_the_light_bvh_for_many_lights_only() {
    let (scene, packed) = load("scenes/cornell-box.gltf");
    assert_eq!(scene.light_sampler, LightSampler::Auto);
    assert!(!light_tree_on(&packed));
    let (_, packed) = packed_with(&rooms_scene(3, 4), LightSampler::Auto);
    assert!(light_tree_on(&packed));
}

/// At many points, with no normal and with random normals as the path
/// state carries them: the pmf of the leaf the walk picks, recomputed from
/// its trail, is the walk's own (to the bit), and the pmfs of every light
/// sum to one. The normal is in force: it changes most lights' pmfs.
#[test]
fn trail_pmfs_match_the_walk_and_sum_to_one() {
    let (_, packed) = packed_with(&rooms_scene(3, 3), LightSampler::Bvh);
    let tree = &packed.light_tree;
    let emitters = packed.emitters.len();
    let cpu = CpuScene::new(&packed);
    #[cfg(target_arch = "x86_64")]
    let avx2 = std::arch::is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    let avx2 = false;
    println!("the lanes' walk with AVX2 checked: {avx2}");
    let mut rng = 12345u32;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 17;
        rng ^= rng << 5;
        (rng >> 8) as f32 / (1u32 << 24) as f32
    };
    let (mut changed, mut compared) = (0usize, 0usize);
    for k in 0..400 {
        let p = Vec3::new(12.0 * next(), 3.0 * next(), 12.0 * next());
        let nrm = if k % 2 == 0 {
            Vec3::ZERO
        } else {
            let d = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
            let nrm = light_tree_normal(light_tree_normal_code(d));
            assert!((nrm - d).length() < 1e-3, "{d} travels as {nrm}");
            assert!((nrm.length() - 1.0).abs() < 1e-6);
            nrm
        };
        let pmfs: Vec<f32> = tree
            .trails
            .iter()
            .enumerate()
            .filter(|(k, _)| *k <= emitters)
            .map(|(_, &t)| light_tree_pmf(&packed, t, p, nrm))
            .collect();
        let sum: f64 = pmfs.iter().map(|&q| q as f64).sum();
        assert!((sum - 1.0).abs() < 1e-4, "pmfs at {p}, {nrm} sum to {sum}");
        if nrm != Vec3::ZERO {
            for (row, &q) in pmfs.iter().enumerate() {
                let without = light_tree_pmf(&packed, tree.trails[row], p, Vec3::ZERO);
                assert!(q > 0.0 || without == 0.0, "the normal lost a light at {p}");
                changed += usize::from((q - without).abs() > 1e-3 * without);
                compared += 1;
            }
        }
        // The walk's four-lane step is the one-node importance (the GLSL's)
        // to the bit, every node in every lane.
        for (k, n) in tree.nodes.iter().enumerate() {
            let m = tree.nodes.len();
            let four = [k, (k + 1) % m, (k + 7) % m, (k + 31) % m].map(|i| &tree.nodes[i]);
            let imp = light_tree_importance4(four, p, nrm).to_array();
            for (lane, node) in four.iter().enumerate() {
                let one = light_tree_importance(node, p, nrm);
                assert_eq!(
                    imp[lane].to_bits(),
                    one.to_bits(),
                    "node {k}, lane {lane}: {n:?}"
                );
            }
        }
        // The walks taken side by side (the CPU lanes') are the walk's:
        // the twin's, and the lanes' with AVX2 on the CPU's copy of the
        // steps where the CPU has it, at points and normals that differ
        // from lane to lane.
        let u: [f32; WIDTH] = std::array::from_fn(|_| next());
        let active: [bool; WIDTH] = std::array::from_fn(|k| k != 3);
        let at: [Vec3; WIDTH] = std::array::from_fn(|k| {
            if k % 3 == 0 {
                p
            } else {
                p + Vec3::splat(0.3 * k as f32)
            }
        });
        let nrms: [Vec3; WIDTH] =
            std::array::from_fn(|k| if k % 2 == 0 { nrm } else { Vec3::ZERO });
        let walks = [
            light_tree_sample_many(&packed, &at, &nrms, &u, &active),
            if avx2 {
                // SAFETY: AVX2 only where the CPU has it.
                unsafe { light_tree_walk::sample_lanes::<true>(&cpu, &at, &nrms, &u, &active) }
            } else {
                light_tree_sample_many(&packed, &at, &nrms, &u, &active)
            },
        ];
        for (w, (nodes, pmfs)) in walks.iter().enumerate() {
            for k in 0..WIDTH {
                let (leaf, pmf) = light_tree_sample(&packed, at[k], nrms[k], u[k]);
                if active[k] {
                    assert_eq!(&tree.nodes[nodes[k] as usize], leaf, "walk {w}, lane {k}");
                    assert_eq!(pmfs[k].to_bits(), pmf.to_bits(), "walk {w}, lane {k}");
                } else {
                    assert_eq!(pmfs[k], 0.0);
                }
            }
        }
        for _ in 0..20 {
            let (leaf, pmf) = light_tree_sample(&packed, p, nrm, next());
            assert!(leaf.flags & LIGHT_TREE_LEAF != 0 && pmf > 0.0);
            let row = if leaf.flags & vkpt::constants::LIGHT_TREE_ANALYTIC != 0 {
                emitters + leaf.child_or_light as usize
            } else {
                leaf.child_or_light as usize
            };
            assert_eq!(light_tree_pmf(&packed, tree.trails[row], p, nrm), pmf);
        }
    }
    println!("the normal changed {changed} of {compared} pmfs");
    assert!(
        changed * 2 > compared,
        "the normal bound changed {changed} of {compared} pmfs"
    );
}

/// The comparison sees a wrong pmf: MIS given, for every light, the
/// probability of the other child at depth 1 of its path (its trail's bit
/// 1 flipped) must fail against power sampling.
#[test]
fn a_wrong_light_pmf_is_seen_failing() {
    let scene = rooms_scene(3, 4);
    let (s_tree, mut p_tree) = packed_with(&scene, LightSampler::Bvh);
    let (s_power, p_power) = packed_with(&scene, LightSampler::Power);
    for t in &mut p_tree.light_tree.trails {
        *t ^= 2;
    }
    let a = render_cpu(&s_tree, &p_tree, &settings(32, 512, 1));
    let b = render_cpu(&s_power, &p_power, &settings(32, 512, 2));
    let cmp = compare(&a, &b, 0.01).expect("comparable");
    println!("{cmp}");
    assert!(!cmp.passed(), "a wrong pmf went unseen");
}

/// A floor in a box whose walls and ceiling are lamps, 4 x 4 tiles a face:
/// seen from the floor, the light BVH with the receiving normal picks
/// tiles nearly as cosine-weighted BSDF sampling finds them, without it
/// nearly by solid angle, so MIS weights differ a lot between the two.
fn glowing_box_scene() -> Scene {
    let v = Vec3::new;
    let mut lamp = Material::lambert("tile", Vec3::ZERO);
    lamp.emission = Vec3::new(1.0, 0.9, 0.7);
    let materials = vec![Material::lambert("floor", Vec3::new(0.5, 0.4, 0.3)), lamp];
    let mut triangles = Vec::new();
    let floor = [
        v(-2.0, 0.0, -2.0),
        v(-2.0, 0.0, 2.0),
        v(2.0, 0.0, 2.0),
        v(2.0, 0.0, -2.0),
    ];
    triangles.extend(quad(floor, 0));
    // Corner and edges of each face, e1 x e2 pointing inside.
    let faces = [
        (v(-2.0, 2.0, -2.0), v(4.0, 0.0, 0.0), v(0.0, 0.0, 4.0)),
        (v(-2.0, 0.0, -2.0), v(0.0, 2.0, 0.0), v(0.0, 0.0, 4.0)),
        (v(2.0, 0.0, -2.0), v(0.0, 0.0, 4.0), v(0.0, 2.0, 0.0)),
        (v(-2.0, 0.0, -2.0), v(4.0, 0.0, 0.0), v(0.0, 2.0, 0.0)),
        (v(-2.0, 0.0, 2.0), v(0.0, 2.0, 0.0), v(4.0, 0.0, 0.0)),
    ];
    let n = 4;
    for (c, e1, e2) in faces {
        let (d1, d2) = (e1 / n as f32, e2 / n as f32);
        for i in 0..n {
            for j in 0..n {
                let a = c + i as f32 * d1 + j as f32 * d2;
                triangles.extend(quad([a, a + d1, a + d1 + d2, a + d2], 1));
            }
        }
    }
    let eye = v(0.0, 1.2, -1.5);
    Scene {
        source: "light BVH glowing box".into(),
        triangles,
        materials,
        cameras: vec![Camera {
            aspect_ratio: Some(1.0),
            ..Camera::pinhole(
                "inside",
                eye,
                (v(0.0, 0.0, 0.8) - eye).normalize(),
                Vec3::Y,
                1.3,
            )
        }],
        ..Default::default()
    }
}

/// Where the receiving normal reorders the lights most, the light BVH
/// (with it) and power sampling agree.
#[test]
fn light_bvh_agrees_with_power_sampling_where_the_normal_counts() {
    let (a, b) = both_samplers(&glowing_box_scene(), 32, 512);
    assert_agree(
        "light_bvh_agrees_with_power_sampling_where_the_normal_counts",
        &a,
        &b,
    );
}

/// The comparison sees MIS without the receiving normal that light
/// sampling bounded with (`plant_mis_without_normal`, CPU): the weights of
/// a path found both ways no longer sum to one.
#[test]
fn mis_without_the_normal_is_seen_failing() {
    let scene = glowing_box_scene();
    let (s_tree, mut p_tree) = packed_with(&scene, LightSampler::Bvh);
    let (s_power, p_power) = packed_with(&scene, LightSampler::Power);
    p_tree.light_tree.plant_mis_without_normal = true;
    let a = render_cpu(&s_tree, &p_tree, &settings(32, 512, 1));
    let b = render_cpu(&s_power, &p_power, &settings(32, 512, 2));
    let cmp = compare(&a, &b, 0.01).expect("comparable");
    println!("{cmp}");
    assert!(!cmp.passed(), "MIS without the normal went unseen");
}

/// With the same seed both back ends trace the same paths through the
/// light BVH, and independent renders agree.
#[test]
fn light_bvh_gpu_matches_cpu() {
    let Some(mut gpu) = gpu_renderer("light_bvh_gpu_matches_cpu") else {
        return;
    };
    let scene = rooms_scene(3, 4);
    let (scene, packed) = packed_with(&scene, LightSampler::Bvh);
    let a = render_gpu(&mut gpu, &scene, &packed, &settings(24, 8, 7));
    let b = render_cpu(&scene, &packed, &settings(24, 8, 7));
    let differing = pixels_differing(&a, &b, 1e-4);
    println!("same seed: {differing} of {} pixels differ", a.mean.len());
    assert!(differing * 100 < a.mean.len(), "{differing} pixels differ");
    let a = render_gpu(&mut gpu, &scene, &packed, &settings(24, 256, 1));
    let b = render_cpu(&scene, &packed, &settings(24, 256, 2));
    assert_agree("light_bvh_gpu_matches_cpu", &a, &b);
}

/// The light BVH bounds with the surface's normal (one-sided) only where
/// the surface reflects alone: Lambert and rough glTF plastic do; rough
/// glass, diffuse transmission and a mirror do not (the first two reach
/// through, the mirror has no lobe light sampling can meet).
#[test]
fn only_surfaces_that_reflect_alone_bound_with_their_normal() {
    use vkpt::constants::{
        LOBE_DIFFUSE_TRANSMISSION, MATERIAL_GLTF, MATERIAL_LAMBERT, MATERIAL_MIRROR,
    };
    use vkpt::cpu::common::integrator::light_tree_receiving_normal;
    use vkpt::packed::layout::MaterialData;
    let m = |kind: u32, transmission: f32, lobes: u32| MaterialData {
        kind,
        roughness: 0.5,
        transmission,
        lobes,
        alpha: 1.0,
        ..Default::default()
    };
    assert!(light_tree_receiving_normal(&m(MATERIAL_LAMBERT, 0.0, 0)));
    assert!(light_tree_receiving_normal(&m(MATERIAL_GLTF, 0.0, 0)));
    assert!(!light_tree_receiving_normal(&m(MATERIAL_GLTF, 1.0, 0)));
    assert!(!light_tree_receiving_normal(&m(
        MATERIAL_GLTF,
        0.0,
        LOBE_DIFFUSE_TRANSMISSION
    )));
    assert!(!light_tree_receiving_normal(&m(MATERIAL_MIRROR, 0.0, 0)));
}
