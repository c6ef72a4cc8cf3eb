//! The CPU back end's lane schedule (`cpu::lanes`) traces the paths of its
//! one-path schedule: on every static bundled scene (Lambertian surfaces,
//! smooth glTF mirrors and glass shaded in the lanes; other materials,
//! escaped rays and lights other than emissive triangles by the scalar
//! twins lane by lane),
//! with either sampler, limited and unlimited depth, auxiliary outputs and
//! a region, the same seed gives the same film bit for bit and the same ray
//! counts, their rays traced in packets where they pay (`packet`). Moving scenes are rendered by the one-path schedule
//! whichever is asked. The packets' hits are also compared ray by ray with
//! single rays' (`packets_find_the_hits_of_one_ray_at_a_time`), and the
//! single ray's nearest-child-first order with the kernels' octant order
//! (`nearest_child_first_finds_the_hits_of_the_octant_order`).

use crate::common;

use common::*;
use glam::Vec3;
use vkpt::cpu::fast::cache::CpuScene;
use vkpt::cpu::fast::lanes::{LaneOptions, lanes_cover, triangle_lights_only};
use vkpt::cpu::render::{CpuSchedule, render_with};
use vkpt::image::Image;
use vkpt::image::region::Region;
use vkpt::packed::PackedScene;
use vkpt::render::{RenderAll, RenderResult, RenderSettings, Sampler};
use vkpt::scene::Scene;

fn render(
    scene: &Scene,
    packed: &PackedScene,
    s: &RenderSettings,
    schedule: CpuSchedule,
) -> RenderResult {
    render_with(scene, packed, s, &|_, _| {}, &mut RenderAll, schedule).expect("CPU render")
}

/// Every bit of the image: mean, variance and the auxiliary outputs.
fn bits(image: &Image) -> Vec<u32> {
    let variance = image.variance.as_deref().unwrap_or(&[]);
    let aov = &image.aovs;
    let albedo = aov.albedo.as_deref().unwrap_or(&[]);
    let normal = aov.normal.as_deref().unwrap_or(&[]);
    let depth = aov.depth.as_deref().unwrap_or(&[]);
    image
        .mean
        .iter()
        .chain(variance)
        .chain(albedo)
        .chain(normal)
        .flat_map(|p| p.map(f32::to_bits))
        .chain(depth.iter().map(|d| d.to_bits()))
        .collect()
}

/// Settings that reach every branch the lanes implement: bounces past
/// Russian roulette's start (unlimited depth), a depth limit ending paths
/// in the middle of the lanes, both samplers, a region, auxiliary outputs.
fn cases() -> Vec<(&'static str, RenderSettings)> {
    let base = RenderSettings {
        width: 40,
        height: 30,
        spp: 12,
        seed: 3,
        ..Default::default()
    };
    vec![
        ("sobol, unlimited depth", base.clone()),
        (
            "independent, unlimited depth",
            RenderSettings {
                sampler: Sampler::Independent,
                ..base.clone()
            },
        ),
        (
            "sobol, depth 2",
            RenderSettings {
                max_depth: Some(2),
                ..base.clone()
            },
        ),
        (
            "independent, depth 1 (emitters only)",
            RenderSettings {
                max_depth: Some(1),
                sampler: Sampler::Independent,
                ..base.clone()
            },
        ),
        (
            "sobol, auxiliary outputs",
            RenderSettings {
                aov: true,
                ..base.clone()
            },
        ),
        (
            "sobol, a region from sample 5",
            RenderSettings {
                region: Some(Region {
                    x0: 7,
                    y0: 4,
                    x1: 29,
                    y1: 21,
                }),
                first_sample: 5,
                ..base
            },
        ),
    ]
}

/// Renders with both schedules and requires the same film bit for bit
/// (auxiliary outputs too, as asked), the same sample counts and the same
/// ray counts. Returns the film.
fn assert_lanes_trace_one_paths(
    what: &str,
    scene: &Scene,
    packed: &PackedScene,
    s: &RenderSettings,
) -> Image {
    let lanes = render(scene, packed, s, CpuSchedule::Lanes);
    let one = render(scene, packed, s, CpuSchedule::OnePath);
    let (a, b) = (lanes.film.to_image(), one.film.to_image());
    assert_eq!(
        a.aovs.albedo.is_some(),
        s.aov,
        "{what}: auxiliary outputs recorded as asked"
    );
    let differing = bits(&a)
        .iter()
        .zip(bits(&b))
        .filter(|(x, y)| *x != y)
        .count();
    assert_eq!(differing, 0, "{what}: channels differ");
    assert_eq!(a.samples, b.samples, "{what}: sample counts");
    assert_eq!(
        (
            lanes.extension_rays,
            lanes.shadow_rays,
            lanes.traversal_overflows
        ),
        (one.extension_rays, one.shadow_rays, one.traversal_overflows),
        "{what}: ray counts"
    );
    assert_eq!(lanes.nonfinite_samples, one.nonfinite_samples, "{what}");
    a
}

#[test]
fn lanes_trace_the_paths_of_the_one_path_schedule() {
    let mut covered = Vec::new();
    let mut scenes: Vec<_> = std::fs::read_dir(repo_path("scenes"))
        .expect("scenes folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "gltf"))
        .collect();
    scenes.sort();
    for path in scenes {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let (scene, packed) = load(&format!("scenes/{name}"));
        for (case, s) in cases() {
            if !lanes_cover(&packed) {
                continue;
            }
            covered.push(format!("{name}: {case}"));
            assert_lanes_trace_one_paths(&format!("{name}, {case}"), &scene, &packed, &s);
        }
    }
    println!("lanes and one path agree on {}:", covered.len());
    for c in &covered {
        println!("  {c}");
    }
    // The box is all Lambert; cornell-spheres and materials-showcase mix
    // it with smooth glass and mirrors (in the lanes, `lanes_delta`; the
    // showcase's absorbing glass has a volume) and rough or layered glTF
    // materials, which the lanes hand to `shade_path`; env-sky and
    // lights-showcase have an environment and
    // analytic lights, sampled by `sample_light` lane by lane.
    for scene in [
        "cornell-box.gltf",
        "cornell-spheres.gltf",
        "materials-showcase.gltf",
        "env-sky.gltf",
        "lights-showcase.gltf",
    ] {
        assert!(
            covered.iter().any(|c| c.starts_with(scene)),
            "{scene} is rendered with lanes"
        );
    }
}

/// Moving scenes take the one-path schedule. Static ones run in lanes,
/// which sample their lights in vector registers when all are untextured
/// emissive triangles (with the light BVH too) and with `sample_light`
/// lane by lane otherwise.
#[test]
fn what_the_lanes_cover() {
    let s = RenderSettings::default();
    // Packets where they pay (`packets_run`): eight rays wide where the
    // BVH is small, the box and the two scenes of a few hundred triangles,
    // not cornell-spheres' 4,428; sixteen wide on all four.
    let wide = vkpt::cpu::fast::WIDTH == 16;
    for (name, triangles_only, packets) in [
        ("scenes/cornell-box.gltf", true, true),
        ("scenes/env-sky.gltf", false, true),
        ("scenes/lights-showcase.gltf", false, true),
        ("scenes/cornell-spheres.gltf", true, wide),
    ] {
        let (scene, packed) = load(name);
        let params = packed.render_params(&scene, &s, 0).expect("params");
        assert!(lanes_cover(&packed), "{name} runs in lanes");
        assert_eq!(
            triangle_lights_only(&packed, &params),
            triangles_only,
            "{name}"
        );
        if vkpt::cpu::traversal::vector_traversals() {
            assert_eq!(
                LaneOptions::for_scene(&CpuScene::new(&packed), &params).packets(),
                packets,
                "{name}: rays in packets"
            );
        }
    }
    // The light BVH (auto, over 64 emitters) keeps the lanes' vector
    // triangle sampling, its walk lane by lane.
    let (scene, packed) = load("scenes/hall-lamps.gltf");
    let params = packed.render_params(&scene, &s, 0).expect("params");
    assert!(vkpt::cpu::common::light_bvh::light_tree_on(&packed));
    assert!(triangle_lights_only(&packed, &params), "hall-lamps");
    let (scene, _) = load("scenes/textured.gltf");
    let moving = in_motion(scene, 0.3, 0.1, glam::Vec3::X);
    let packed = PackedScene::new(&moving).expect("the moving scene packs");
    assert!(
        !lanes_cover(&packed),
        "a moving scene takes one path at a time"
    );
}

/// Rays of every kind for `packets_find_the_hits_of_one_ray_at_a_time`:
/// from random points at random triangles' vertices, edges and insides,
/// and along the axes exactly through vertices (where triangles that share
/// the vertex or an edge meet the ray at equal distance), with and without
/// a t_max short of the target.
fn traversal_rays(packed: &PackedScene, count: u32) -> Vec<(Vec3, Vec3, f32)> {
    use vkpt::cpu::common::rng::pcg_hash;
    let state = std::cell::Cell::new(11u32);
    let next = || {
        state.set(pcg_hash(state.get()));
        state.get()
    };
    let unit = || next() as f32 / u32::MAX as f32;
    let tris = &packed.tri_verts;
    let (lo, hi) = tris.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), t| {
            let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
            (lo.min(a).min(b).min(c), hi.max(a).max(b).max(c))
        },
    );
    let extent = (hi - lo).max(Vec3::splat(1e-3));
    (0..count)
        .map(|k| {
            let t = &tris[(next() as usize) % tris.len()];
            let (a, b, c) = (Vec3::from(t.v0), Vec3::from(t.v1), Vec3::from(t.v2));
            let (o, d, target) = if k % 3 == 2 {
                // Along an axis, exactly through vertex a.
                let axis = (next() % 3) as usize;
                let mut d = Vec3::ZERO;
                d[axis] = if next() % 2 == 0 { 1.0 } else { -1.0 };
                let mut o = a;
                o[axis] -= d[axis] * extent[axis] * (0.1 + unit());
                (o, d, a)
            } else {
                let target = match k % 4 {
                    0 => a,
                    1 => (b + c) * 0.5,
                    _ => {
                        let (u, v) = (unit(), unit());
                        let (u, v) = if u + v > 1.0 {
                            (1.0 - u, 1.0 - v)
                        } else {
                            (u, v)
                        };
                        a + (b - a) * u + (c - a) * v
                    }
                };
                let o = lo - extent * 0.1 + extent * 1.2 * Vec3::new(unit(), unit(), unit());
                (o, (target - o).normalize(), target)
            };
            let t_max = if k % 5 == 0 {
                (target - o).length() * (0.2 + 0.7 * unit())
            } else {
                f32::MAX
            };
            (o, d, t_max)
        })
        .filter(|(_, d, _)| d.is_finite())
        .collect()
}

/// The bundled scenes whose rays can never exhaust the traversal's budget
/// (`bvh_traversal::order_free`), where packets and the nearest-first order
/// are exact.
fn scenes_that_fit() -> Vec<(String, PackedScene)> {
    let mut names: Vec<String> = std::fs::read_dir(repo_path("scenes"))
        .expect("scenes folder")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".gltf"))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|name| {
            let (_, packed) = load(&format!("scenes/{name}"));
            (name, packed)
        })
        .filter(|(_, packed)| vkpt::cpu::traversal::order_free(&CpuScene::new(packed)))
        .collect()
}

/// Whether more than one triangle meets the ray at the distance `t`.
fn tied(packed: &PackedScene, o: Vec3, d: Vec3, t: f32) -> bool {
    use vkpt::cpu::common::intersect::{ray_shear, triangle_hit};
    let r = ray_shear(d);
    packed
        .tri_verts
        .iter()
        .filter(|tv| {
            triangle_hit(o, &r, tv.v0.into(), tv.v1.into(), tv.v2.into())
                .is_some_and(|(hit_t, _)| hit_t == t)
        })
        .count()
        > 1
}

/// Packets of rays (`packet`) find exactly the hits that one ray at a
/// time finds in the octant order the kernels follow, on the grid's boxes
/// (`octant::trace_ray_octant`; packets test the tight boxes of
/// `CpuScene::tight_nodes`), closest and any hit, on every bundled scene
/// where they could be used (`order_free`; the renderer uses them on the
/// smaller ones, `packets_run`); rays that meet two triangles at the same
/// distance included (the lower index wins either way).
#[test]
#[cfg(target_arch = "x86_64")]
fn packets_find_the_hits_of_one_ray_at_a_time() {
    use vkpt::cpu::common::bvh::{Hit, NO_HIT};
    use vkpt::cpu::fast::WIDTH;
    use vkpt::cpu::fast::octant::trace_ray_octant;
    use vkpt::cpu::fast::packet::Rays;
    use vkpt::cpu::traversal::trace_packet;
    if !vkpt::cpu::traversal::vector_traversals() {
        println!("no AVX2 on this CPU: packets are not used");
        return;
    }
    let mut scenes_with_packets = Vec::new();
    let mut ties = 0;
    for (name, packed) in scenes_that_fit() {
        let scene = CpuScene::new(&packed);
        scenes_with_packets.push(name.clone());
        let rays = traversal_rays(&packed, 3000);
        for any_hit in [false, true] {
            for (k, chunk) in rays.chunks(WIDTH).enumerate() {
                let mut packet = Rays::default();
                for (l, &(o, d, t_max)) in chunk.iter().enumerate() {
                    // Some lanes left out, to check they stay out.
                    if (k + l) % 7 != 6 {
                        packet.set(l, o, d, t_max, (k * WIDTH + l) as u32);
                    }
                }
                // SAFETY: AVX2 checked above; the scene fits packets.
                let hits = unsafe { trace_packet(&scene, &packet, any_hit) };
                for (l, &(o, d, t_max)) in chunk.iter().enumerate() {
                    if packet.active & (1 << l) == 0 {
                        assert_eq!(hits[l].triangle, NO_HIT, "{name}: an inactive lane hit");
                        continue;
                    }
                    let start = Hit::none(t_max);
                    let seed = (k * WIDTH + l) as u32;
                    // SAFETY: AVX2 checked above.
                    let one = unsafe { trace_ray_octant(&scene, o, d, any_hit, seed, 0.0, start) };
                    let got = hits[l];
                    if any_hit {
                        assert_eq!(
                            got.triangle == NO_HIT,
                            one.triangle == NO_HIT,
                            "{name}: any hit along {o} {d} to {t_max}"
                        );
                        continue;
                    }
                    assert_eq!(
                        (
                            got.triangle,
                            got.t.to_bits(),
                            got.b12.x.to_bits(),
                            got.b12.y.to_bits()
                        ),
                        (
                            one.triangle,
                            one.t.to_bits(),
                            one.b12.x.to_bits(),
                            one.b12.y.to_bits()
                        ),
                        "{name}: closest hit along {o} {d} to {t_max}"
                    );
                    ties += (one.triangle != NO_HIT && tied(&packed, o, d, one.t)) as u32;
                }
            }
        }
    }
    println!("packets agree on {scenes_with_packets:?}, {ties} closest hits tied");
    for scene in [
        "cornell-box.gltf",
        "cornell-spheres.gltf",
        "alpha-holes.gltf",
    ] {
        assert!(
            scenes_with_packets.iter().any(|s| s == scene),
            "{scene} is traced in packets"
        );
    }
    assert!(
        ties > 50,
        "only {ties} tied hits: the test exercises little"
    );
}

/// The single ray's traversal nearest child first (`nearest_first`, which
/// `trace_ray` takes where it is exact) through the tight boxes finds
/// exactly the hits of the octant order that the kernels follow through
/// the grid's boxes (`octant::trace_ray_octant`), closest and any hit, on every
/// bundled scene where it is used (`order_free`), tied hits and rays
/// along box faces included.
#[test]
#[cfg(target_arch = "x86_64")]
fn nearest_child_first_finds_the_hits_of_the_octant_order() {
    use vkpt::cpu::common::bvh::{Hit, NO_HIT};
    use vkpt::cpu::fast::nearest_first::trace_ray_nearest_first;
    use vkpt::cpu::fast::octant::trace_ray_octant;
    if !vkpt::cpu::traversal::vector_traversals() {
        println!("no AVX2 on this CPU: the ordered traversal is not used");
        return;
    }
    let mut scenes = Vec::new();
    let (mut hits, mut blocked, mut ties) = (0, 0, 0);
    for (name, packed) in scenes_that_fit() {
        let scene = CpuScene::new(&packed);
        scenes.push(name.clone());
        for (k, (o, d, t_max)) in traversal_rays(&packed, 3000).into_iter().enumerate() {
            let start = Hit::none(t_max);
            let seed = k as u32;
            for any_hit in [false, true] {
                // SAFETY: AVX2 checked above; a still scene that fits.
                let (octant, ordered) = unsafe {
                    (
                        trace_ray_octant(&scene, o, d, any_hit, seed, 0.0, start),
                        trace_ray_nearest_first(&scene, o, d, any_hit, seed, 0, start),
                    )
                };
                if any_hit {
                    assert_eq!(
                        ordered.triangle == NO_HIT,
                        octant.triangle == NO_HIT,
                        "{name}: any hit along {o} {d} to {t_max}"
                    );
                    blocked += (octant.triangle != NO_HIT) as u32;
                    continue;
                }
                let key = |h: Hit| {
                    (
                        h.triangle,
                        h.t.to_bits(),
                        h.b12.x.to_bits(),
                        h.b12.y.to_bits(),
                    )
                };
                assert_eq!(
                    key(ordered),
                    key(octant),
                    "{name}: closest hit along {o} {d} to {t_max}"
                );
                hits += (octant.triangle != NO_HIT) as u32;
                ties += (octant.triangle != NO_HIT && tied(&packed, o, d, octant.t)) as u32;
            }
        }
    }
    println!(
        "nearest child first agrees on {scenes:?}: {hits} closest hits ({ties} tied), {blocked} blocked"
    );
    for scene in [
        "cornell-spheres.gltf",
        "materials-grid.gltf",
        "coat-grid.gltf",
    ] {
        assert!(
            scenes.iter().any(|s| s == scene),
            "{scene} is traced nearest child first"
        );
    }
    assert!(hits > 10_000, "only {hits} hits: the test exercises little");
    assert!(
        ties > 50,
        "only {ties} tied hits: the test exercises little"
    );
}

/// The lanes pick an emitter by comparing each lane's number with the
/// whole CDF where there are at most as many emitters as lanes, and by
/// `select_emitter` lane by lane above that: depth-of-field without its
/// sphere light and sky (26 emissive triangles), with two of its three
/// spots dark (10), and with the light BVH (26), all render as the
/// one-path schedule does, bit for bit.
#[test]
fn lanes_pick_among_many_emitters_as_the_one_path_schedule() {
    let (base, _) = load("scenes/depth-of-field.gltf");
    let s = cases().swap_remove(0).1;
    let dark = |scene: &mut Scene, name: &str| {
        let m = scene
            .materials
            .iter_mut()
            .find(|m| m.name == name)
            .unwrap_or_else(|| panic!("material {name}"));
        m.emission = Vec3::ZERO;
    };
    // Its sphere light and sky off: emissive triangles are its only lights.
    let mut all = base.clone();
    all.lights.clear();
    all.environment = None;
    all.environment_map = None;
    let mut some = all.clone();
    dark(&mut some, "spot 0");
    dark(&mut some, "spot 1");
    // With the light BVH: the walk lane by lane, the rest in vectors.
    let mut tree = all.clone();
    tree.light_sampler = vkpt::scene::LightSampler::Bvh;
    for (scene, emitters) in [(all, 26), (some, 10), (tree, 26)] {
        let packed = PackedScene::new(&scene).expect("packs");
        let params = packed.render_params(&scene, &s, 0).expect("params");
        assert_eq!(packed.emitters.len(), emitters);
        assert!(
            triangle_lights_only(&packed, &params),
            "{emitters} emitters: lights sampled in the lanes"
        );
        let film =
            assert_lanes_trace_one_paths(&format!("{emitters} emitters"), &scene, &packed, &s);
        let lit = film
            .mean
            .iter()
            .filter(|p| p.iter().any(|&c| c > 0.0))
            .count();
        assert!(
            lit > film.mean.len() / 4,
            "{emitters} emitters: {lit} pixels lit"
        );
    }
}
