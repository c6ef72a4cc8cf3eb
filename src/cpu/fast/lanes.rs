//! The CPU back end's lane schedule: a vector register of paths side by
//! side (sixteen with AVX-512, eight with AVX2; `wide::WIDTH`), shaded in
//! vector registers (`simd`; the random numbers in `lanes_rng`), the way
//! Mitsuba's LLVM variants and Cycles' CPU kernels get their speed; rays
//! are traced as many at a time where packets pay (`packet`), one at
//! a time (`bvh::trace_ray`) elsewhere. Lambertian surfaces
//! are shaded by `integrator::shade_path` written for lanes: a lane
//! computes both sides of each branch and keeps the side the scalar code
//! takes, with the same float operations in the same order; so are smooth
//! glTF mirrors and glass (`lanes_delta`). Surfaces of other materials
//! (rough or layered glTF, textures, Phong) are shaded by `shade_path`
//! itself, lane by lane. So each path's radiance is the
//! scalar driver's bit for bit (`tests/suite/cpu_lanes.rs` renders both), and
//! the CPU keeps tracing the kernels' paths.
//!
//! Escaped rays, and next-event estimation where some light is not an
//! untextured emissive triangle (an environment, analytic lights), use the
//! scalar twins lane by lane (`shade_path`, `sample_light`); moving scenes
//! take the one-path driver (`render::trace_path`; [`lanes_cover`]). A
//! lane whose path ends takes the next path of the row at once, so the
//! lanes stay full (98 % busy on the Cornell box); radiance goes to the
//! path's own slot and the film adds the row's samples in the scalar order.
//! The paths' state, the shading's results and the ray packets are all
//! structures of arrays (`PathLanes`, `ShadeLanes`, `packet::Rays`),
//! so a bounce moves them a register at a time; only `shade_path`'s lanes
//! go through per-lane structs.
//! What the lanes need of the scene and camera that does not change during
//! a render is worked out once (`LaneOptions`), by the scalar code's own
//! operations, so the bits stay the same.

// Loops over lane indices are the point here: each iteration is one lane,
// written so that the compiler turns the loop into vector instructions.
#![allow(clippy::needless_range_loop)]

#[cfg(target_arch = "x86_64")]
use super::cache::CpuScene;
use super::lanes_delta::{DeltaLanes, lanes_shade_delta};
use super::lanes_rng::KeyLanes;
use super::packet::Rays;
use super::simd::{Bools, Floats, V3, and, not, or, permute, select, select_mask, select3};
use super::wide::WIDTH;
use crate::constants::*;
use crate::cpu::common::aov::{AovSample, aov_after_bounce};
use crate::cpu::common::bvh::{Hit, NO_HIT, OVERFLOW_HIT};
use crate::cpu::common::camera::{aperture_corner, generate_camera_ray_with};
use crate::cpu::common::dispersion::dispersive;
use crate::cpu::common::integrator::{PathState, ShadeResult, shade_path};
#[cfg(test)]
use crate::cpu::common::intersect::offset_component;
use crate::cpu::common::light_bvh::{
    fetch_light_tree_node, light_tree_normal, light_tree_normal_code, light_tree_on,
    light_tree_triangle_pmf,
};
use crate::cpu::common::lights::{environment_shines, sample_light, select_emitter, suns_shine};
use crate::cpu::common::rng::{RngKey, rng_coverage_seed, rng_float, rng_float2, rng_sampler_key};
#[cfg(test)]
use crate::cpu::common::sampling::sample_concentric_disk;
use crate::cpu::common::sampling::{FLT_MAX, INV_PI, sin_cos_octant};
use crate::cpu::common::textures::{alpha_coverage, material_has_textures};
#[cfg(target_arch = "x86_64")]
use crate::cpu::common::trace::{nearest_with_sphere_lights, sphere_light_blocker};
use crate::cpu::fast::light_tree_walk;
use crate::cpu::traversal::{extension_hit, packets_run, shadow_ray_unblocked, trace_packet};
use crate::packed::PackedScene;
use crate::packed::layout::{MaterialData, RenderParams};
use glam::{Vec2, Vec3};

/// Whether the lane schedule renders this scene: any static one-level
/// scene (the lanes gather triangles as they stand, with no time and no
/// instance placing them).
pub fn lanes_cover(scene: &PackedScene) -> bool {
    scene.motion.is_none() && scene.instances.is_empty()
}

/// Whether every light is an untextured emissive triangle: then the lanes
/// sample lights in vector registers (with the light BVH, the walk lane by
/// lane), else `sample_light` lane by lane.
pub fn triangle_lights_only(scene: &PackedScene, params: &RenderParams) -> bool {
    // (The lanes render one-level scenes only: `lanes_cover`.)
    scene.instances.is_empty()
        && !environment_shines(params)
        && !(params.env_select_prob > 0.0)
        && !suns_shine(scene)
        && scene.light_params.num_spheres == 0
        && scene.light_params.num_lights == 0
        && scene.emitters.iter().all(|e| {
            let tv = &scene.tri_verts[e.triangle as usize];
            !material_has_textures(&scene.materials[tv.material as usize])
        })
}

/// How the lanes shade a material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LaneMaterial {
    /// `shade_path`, one lane at a time.
    Scalar,
    /// In vector registers (`lanes_shade`).
    Lambert,
    /// A smooth mirror or glass in vector registers (`lanes_delta`).
    Delta,
}

/// Whether the lanes shade this material in vector registers: untextured
/// Lambert without a volume (the other branches of `shade_path` are then
/// dead). Other materials take `shade_path`, one lane at a time, except
/// smooth mirrors and glass (`lanes_delta::lanes_shade_delta`).
pub fn lanes_shade(m: &MaterialData) -> bool {
    m.kind == MATERIAL_LAMBERT
        && !material_has_textures(m)
        && m.normal_texture == NO_TEXTURE
        && !(m.thickness > 0.0)
        && !dispersive(m)
        && m.lobes == 0
}

/// The per-material values the Lambertian shading reads, material k's in
/// lane k, where a scene has no more materials than lanes: each lane takes
/// its material's by one permute per field (`simd::permute`) rather than a
/// load and a store per lane and field. (Mirrors and glass keep their
/// per-lane `DeltaLanes::set_lane`: tables for those measured 4 % slower
/// on furnace-glass-1.5 and no faster on cornell-spheres.)
#[derive(Clone, Copy, Debug)]
struct MaterialTables {
    base_color: V3,
    emission: V3,
    /// 1 where double-sided, else 0.
    double_sided: Floats,
}

impl MaterialTables {
    /// None where the scene has more materials than lanes.
    fn new(materials: &[MaterialData]) -> Option<MaterialTables> {
        if materials.len() > WIDTH {
            return None;
        }
        let mut tables = MaterialTables {
            base_color: V3::default(),
            emission: V3::default(),
            double_sided: Floats::splat(0.0),
        };
        for (k, m) in materials.iter().enumerate() {
            tables.base_color.set_lane(k, Vec3::from(m.base_color));
            tables.emission.set_lane(k, Vec3::from(m.emission));
            tables.double_sided.0[k] = if m.double_sided != 0 { 1.0 } else { 0.0 };
        }
        Some(tables)
    }
}

/// An untextured emissive triangle as `sample_light` uses it, with the
/// values it computes per sample computed once, by the same operations.
#[derive(Clone, Debug)]
struct LaneEmitter {
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    /// The unit normal of (v1 - v0) x (v2 - v0).
    normal: Vec3,
    /// The density's factor tri_select_prob * pmf / area.
    pdf_scale: f32,
    /// The emission times the alpha coverage.
    radiance: Vec3,
    double_sided: bool,
}

impl LaneEmitter {
    fn new(scene: &PackedScene, e: &crate::packed::layout::Emitter) -> LaneEmitter {
        let tv = &scene.tri_verts[e.triangle as usize];
        let (v0, v1, v2) = (Vec3::from(tv.v0), Vec3::from(tv.v1), Vec3::from(tv.v2));
        let m = &scene.materials[tv.material as usize];
        LaneEmitter {
            v0,
            v1,
            v2,
            normal: (v1 - v0).cross(v2 - v0).normalize(),
            pdf_scale: scene.light_params.tri_select_prob * e.pmf / e.area,
            radiance: Vec3::from(m.emission) * alpha_coverage(m.alpha, m.alpha_cutoff),
            double_sided: m.double_sided != 0,
        }
    }
}

/// The lanes' paths between bounces as a structure of arrays: the vector
/// code reads each bounce's path state and writes the next one a register
/// at a time, not lane by lane through per-lane structs (gathering and
/// scattering them was a sixth of cornell-spheres' time).
#[derive(Clone, Copy)]
struct PathLanes {
    /// Which lanes hold a path.
    live: Bools,
    /// Each path's slot in the row's results.
    item: [usize; WIDTH],
    key: [RngKey; WIDTH],
    bounce: [u32; WIDTH],
    origin: V3,
    direction: V3,
    throughput: V3,
    prev_pdf: Floats,
    eta_scale: Floats,
    dispersion_channel: [u32; WIDTH],
    /// PathState::prev_normal.
    prev_normal: [u32; WIDTH],
    radiance: V3,
    aov: [AovSample; WIDTH],
}

impl PathLanes {
    fn new(params: &RenderParams) -> PathLanes {
        PathLanes {
            live: [false; WIDTH],
            item: [0; WIDTH],
            key: no_keys(params),
            bounce: [0; WIDTH],
            origin: V3::default(),
            direction: V3::default(),
            throughput: V3::default(),
            prev_pdf: Floats::splat(0.0),
            eta_scale: Floats::splat(1.0),
            dispersion_channel: [0; WIDTH],
            prev_normal: [0; WIDTH],
            radiance: V3::default(),
            aov: [AovSample::default(); WIDTH],
        }
    }

    /// The lanes that hold no path take the batch's next paths, at their
    /// camera rays; returns whether any lane holds a path. The values every
    /// camera ray starts with are written a register at a time.
    #[inline(always)]
    fn start_paths<const AVX2: bool>(
        &mut self,
        starting: &mut Starting,
        scene: &PackedScene,
        params: &RenderParams,
        options: &LaneOptions,
        paths: &[(u32, u32)],
    ) -> bool {
        let mut fresh: Bools = [false; WIDTH];
        // The lanes without a path, by their bits: a branch per lane on
        // `live` goes either way.
        let mut idle = !bits(&self.live) & ALL_LANES;
        while idle != 0 {
            let l = idle.trailing_zeros() as usize;
            idle &= idle - 1;
            let Some(i) = starting.take::<AVX2>(scene, params, options, paths) else {
                break;
            };
            fresh[l] = true;
            self.live[l] = true;
            self.item[l] = starting.item[i];
            self.key[l] = starting.key[i];
            self.bounce[l] = 0;
            self.origin.set_lane(l, starting.origin.lane(i));
            self.direction.set_lane(l, starting.direction.lane(i));
            self.dispersion_channel[l] = 0;
            self.prev_normal[l] = 0;
            if params.aov != 0 {
                self.aov[l] = AovSample::default();
            }
        }
        // PathState::camera's throughput, pdf and eta scale, and no
        // radiance yet.
        self.throughput = select3(fresh, V3::splat(Vec3::ONE), self.throughput);
        self.prev_pdf = select(fresh, Floats::splat(0.0), self.prev_pdf);
        self.eta_scale = select(fresh, Floats::splat(1.0), self.eta_scale);
        self.radiance = select3(fresh, V3::default(), self.radiance);
        self.live.iter().any(|&l| l)
    }

    #[inline(always)]
    fn state(&self, l: usize) -> PathState {
        PathState {
            origin: self.origin.lane(l),
            direction: self.direction.lane(l),
            throughput: self.throughput.lane(l),
            prev_pdf: self.prev_pdf.0[l],
            eta_scale: self.eta_scale.0[l],
            dispersion_channel: self.dispersion_channel[l],
            prev_normal: self.prev_normal[l],
        }
    }
}

/// A bit for each lane.
const ALL_LANES: u32 = if WIDTH == 32 {
    u32::MAX
} else {
    (1 << WIDTH) - 1
};

/// Every lane's key before it holds a path.
fn no_keys(params: &RenderParams) -> [RngKey; WIDTH] {
    [RngKey {
        hash: 0,
        sample_index: 0,
        kind: params.rng_sampler,
        reversed_index: 0,
    }; WIDTH]
}

/// Bit l set where `b[l]`.
#[inline(always)]
fn bits(b: &Bools) -> u32 {
    b.iter()
        .enumerate()
        .fold(0, |m, (l, &on)| m | (u32::from(on) << l))
}

/// `ShadeResult` for every lane, as a structure of arrays. A lane whose
/// `shadow` or `next` is false leaves the values they guard unread.
#[derive(Clone, Copy, Default)]
struct ShadeLanes {
    emitted: V3,
    shadow: Bools,
    shadow_origin: V3,
    shadow_direction: V3,
    shadow_t_max: Floats,
    shadow_contribution: V3,
    next: Bools,
    next_origin: V3,
    next_direction: V3,
    next_throughput: V3,
    next_prev_pdf: Floats,
    next_eta_scale: Floats,
    next_dispersion_channel: [u32; WIDTH],
    next_prev_normal: [u32; WIDTH],
    aov_event: Bools,
    aov_albedo: V3,
    aov_normal: V3,
}

impl ShadeLanes {
    /// Every lane as `ShadeResult::ends`: nothing emitted, no shadow ray, no
    /// next segment, no auxiliary event.
    #[inline(always)]
    fn end_all(&mut self) {
        self.emitted = V3::default();
        self.shadow = [false; WIDTH];
        self.next = [false; WIDTH];
        self.aov_event = [false; WIDTH];
    }

    /// What `aov_after_bounce` reads of lane `l`'s result (its auxiliary
    /// event), on `ShadeResult::ends` of the lane's state for the rest.
    fn aov_result(&self, l: usize, lanes: &PathLanes) -> ShadeResult {
        let mut r = ShadeResult::ends(&lanes.state(l));
        if self.aov_event[l] {
            r.aov_event = true;
            r.aov_albedo = self.aov_albedo.lane(l);
            r.aov_normal = self.aov_normal.lane(l);
        }
        r
    }

    /// Lane `l` as `r` says; the values a false `shadow`, `next` or
    /// `aov_event` guards are left as they were (nothing reads them).
    #[inline(always)]
    fn set_lane(&mut self, l: usize, r: &ShadeResult) {
        self.emitted.set_lane(l, r.emitted);
        self.shadow[l] = r.shadow;
        if r.shadow {
            self.shadow_origin.set_lane(l, r.shadow_origin);
            self.shadow_direction.set_lane(l, r.shadow_direction);
            self.shadow_t_max.0[l] = r.shadow_t_max;
            self.shadow_contribution.set_lane(l, r.shadow_contribution);
        }
        self.next[l] = r.next;
        if r.next {
            let s = &r.next_state;
            self.next_origin.set_lane(l, s.origin);
            self.next_direction.set_lane(l, s.direction);
            self.next_throughput.set_lane(l, s.throughput);
            self.next_prev_pdf.0[l] = s.prev_pdf;
            self.next_eta_scale.0[l] = s.eta_scale;
            self.next_dispersion_channel[l] = s.dispersion_channel;
            self.next_prev_normal[l] = s.prev_normal;
        }
        self.aov_event[l] = r.aov_event;
        if r.aov_event {
            self.aov_albedo.set_lane(l, r.aov_albedo);
            self.aov_normal.set_lane(l, r.aov_normal);
        }
    }
}

/// A row's paths and what tracing them gives: each path's (pixel, sample
/// index), its radiance and its auxiliary outputs (`aovs` is empty when
/// `params.aov` asks for none), and the ray counts as `render::trace_path`
/// counts them (extension, shadow, overflows).
pub struct PathBatch<'a> {
    pub paths: &'a [(u32, u32)],
    pub radiance: &'a mut [Vec3],
    pub aovs: &'a mut [AovSample],
    pub counts: &'a mut [u64; 3],
}

/// How the lanes run a scene, decided once per render (`for_scene`).
#[derive(Clone, Debug)]
pub struct LaneOptions {
    /// Every light is an untextured emissive triangle
    /// (`triangle_lights_only`): lights are sampled in vector registers.
    triangle_lights: bool,
    /// Rays are traced a packet at a time (`packet`), with the hits of
    /// one at a time: where that is exact (`traversal::order_free`) and
    /// faster (`traversal::packets_run`).
    packets: bool,
    /// How each material is shaded (`lanes_shade`, `lanes_shade_delta`),
    /// looked up once per render rather than per lane and bounce (it was
    /// 3 % of the Cornell box).
    vector_materials: Vec<LaneMaterial>,
    /// What light sampling needs of each emitter (`scene.emitters` order)
    /// where `triangle_lights`, worked out once.
    emitters: Vec<LaneEmitter>,
    /// A pinhole camera with a box or tent filter: camera rays are made
    /// in vector registers (`pinhole_rays_lanes`).
    pinhole_camera: bool,
    /// The polygonal aperture's corners (`aperture_corner` of 0 to blades;
    /// empty for a round one): two sines and cosines per camera ray
    /// computed once.
    aperture_corners: Vec<Vec2>,
    /// Each material's values in its own lane, where the scene has no more
    /// materials than lanes (`MaterialTables`).
    material_tables: Option<MaterialTables>,
    /// Some triangle is alpha-tested: rays need their coverage seeds
    /// (three hashes each, skipped where no test reads them).
    alpha_tested: bool,
    /// An escaped ray ends its path and adds nothing (no environment or
    /// sun shines and no auxiliary output is kept): `shade_path` would
    /// return `ShadeResult::ends`, which the lanes start from.
    escapes_end: bool,
}

impl LaneOptions {
    pub fn for_scene(scene: &CpuScene, params: &RenderParams) -> LaneOptions {
        let triangle_lights = triangle_lights_only(scene, params);
        let emitters = if triangle_lights {
            scene.emitters[..params.num_emitters as usize]
                .iter()
                .map(|e| LaneEmitter::new(scene, e))
                .collect()
        } else {
            Vec::new()
        };
        let blades = params.aperture_blades;
        let aperture_corners = if blades >= 3 {
            (0..=blades)
                .map(|k| aperture_corner(blades, params.blade_rotation, k as f32))
                .collect()
        } else {
            Vec::new()
        };
        LaneOptions {
            triangle_lights,
            emitters,
            material_tables: MaterialTables::new(&scene.materials),
            escapes_end: !environment_shines(params) && !suns_shine(scene) && params.aov == 0,
            pinhole_camera: params.projection == PROJECTION_PERSPECTIVE
                && params.lens_radius <= 0.0
                && (params.filter_kind == FILTER_BOX || params.filter_kind == FILTER_TENT),
            aperture_corners,
            // The size first: it is free, the fit walks the BVH.
            packets: packets_run(scene),
            vector_materials: scene
                .materials
                .iter()
                .map(|m| {
                    if lanes_shade(m) {
                        LaneMaterial::Lambert
                    } else if lanes_shade_delta(m) {
                        LaneMaterial::Delta
                    } else {
                        LaneMaterial::Scalar
                    }
                })
                .collect(),
            alpha_tested: scene.tri_verts.iter().any(|t| t.alpha_mask != 0),
        }
    }

    pub fn packets(&self) -> bool {
        self.packets
    }
}

/// Traces the batch's paths in `WIDTH` lanes.
pub fn trace_paths(
    scene: &CpuScene,
    params: &RenderParams,
    options: &LaneOptions,
    batch: &mut PathBatch,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked); packets only where
        // `order_free` found the bit instructions too.
        unsafe {
            if options.triangle_lights {
                trace_paths_avx2::<true>(scene, params, options, batch);
            } else {
                trace_paths_avx2::<false>(scene, params, options, batch);
            }
        }
        return;
    }
    if options.triangle_lights {
        run_lanes::<false, true>(scene, params, options, batch);
    } else {
        run_lanes::<false, false>(scene, params, options, batch);
    }
}

/// `trace_paths` compiled for AVX2.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn trace_paths_avx2<const TRIANGLES: bool>(
    scene: &CpuScene,
    params: &RenderParams,
    options: &LaneOptions,
    batch: &mut PathBatch,
) {
    run_lanes::<true, TRIANGLES>(scene, params, options, batch);
}

/// The lanes' loop. `AVX2`: draw the random numbers with `lanes_rng` (only
/// so from `trace_paths_avx2`); `TRIANGLES`: every light is an untextured
/// emissive triangle, so none is delta or at infinity.
#[inline(always)]
fn run_lanes<const AVX2: bool, const TRIANGLES: bool>(
    scene: &CpuScene,
    params: &RenderParams,
    options: &LaneOptions,
    batch: &mut PathBatch,
) {
    // Packets only with AVX2 (`order_free` checks the bit instructions).
    let packets = AVX2 && options.packets;
    let PathBatch {
        paths,
        radiance,
        aovs,
        counts,
    } = batch;
    let mut lanes = PathLanes::new(params);
    // Each bounce's results, written in place.
    let mut shade = ShadeLanes::default();
    let mut starting = Starting::new(params);
    let mut hits = [Hit::none(0.0); WIDTH];
    loop {
        // Lanes whose paths ended take the next paths, their camera rays
        // made a register at a time.
        if !lanes.start_paths::<AVX2>(&mut starting, scene, params, options, paths) {
            return;
        }
        // Extension rays (no time: the scene is static).
        if packets {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `AVX2` only where the CPU has it, and packets only
            // where `order_free` found the bit instructions too.
            unsafe {
                extension_hits(scene, options, &lanes, &mut hits, counts)
            };
        } else {
            for l in 0..WIDTH {
                if lanes.live[l] {
                    let seed = coverage_seed(options, &lanes, l, 0);
                    let (o, d) = (lanes.origin.lane(l), lanes.direction.lane(l));
                    hits[l] = extension_hit(scene, o, d, seed, 0.0, counts);
                }
            }
        }
        shade_lanes::<AVX2, TRIANGLES>(scene, params, options, &lanes, &hits, &mut shade);
        let mut reaches = [false; WIDTH];
        if packets {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as for the extension rays.
            unsafe {
                reaches = shadow_rays_reach(scene, options, &lanes, &shade, counts)
            };
        } else {
            for l in 0..WIDTH {
                if lanes.live[l] && shade.shadow[l] {
                    let seed = coverage_seed(options, &lanes, l, 1);
                    let ray = (
                        shade.shadow_origin.lane(l),
                        shade.shadow_direction.lane(l),
                        shade.shadow_t_max.0[l],
                    );
                    reaches[l] = shadow_ray_unblocked(scene, ray, seed, 0.0, counts);
                }
            }
        }
        if params.aov != 0 {
            for l in 0..WIDTH {
                if lanes.live[l] {
                    let r = shade.aov_result(l, &lanes);
                    aov_after_bounce(&mut lanes.aov[l], lanes.bounce[l], &hits[l], &r);
                }
            }
        }
        // Lanes without a path add and keep whatever: `start_paths` resets
        // them.
        lanes.radiance = lanes.radiance + shade.emitted;
        // The contribution or +0, not a branch on visibility. Adding
        // +0 leaves the sum's bits as they are: it starts at +0 and
        // adds no -0.
        lanes.radiance =
            lanes.radiance + select3(reaches, shade.shadow_contribution, V3::default());
        let next = shade.next;
        lanes.origin = select3(next, shade.next_origin, lanes.origin);
        lanes.direction = select3(next, shade.next_direction, lanes.direction);
        lanes.throughput = select3(next, shade.next_throughput, lanes.throughput);
        lanes.prev_pdf = select(next, shade.next_prev_pdf, lanes.prev_pdf);
        lanes.eta_scale = select(next, shade.next_eta_scale, lanes.eta_scale);
        for l in 0..WIDTH {
            lanes.bounce[l] += u32::from(next[l]);
            if next[l] {
                lanes.dispersion_channel[l] = shade.next_dispersion_channel[l];
                lanes.prev_normal[l] = shade.next_prev_normal[l];
            }
        }
        // The paths that ended, by their bits (no branch per lane).
        let mut ended = bits(&lanes.live) & !bits(&next);
        while ended != 0 {
            let l = ended.trailing_zeros() as usize;
            ended &= ended - 1;
            radiance[lanes.item[l]] = lanes.radiance.lane(l);
            if let Some(a) = aovs.get_mut(lanes.item[l]) {
                *a = lanes.aov[l];
            }
            lanes.live[l] = false;
        }
    }
}

/// The batch's next paths at their camera rays, made a register at a time
/// so that `camera_rays` fills its vector registers: paths `next..count`
/// of these are still to start.
struct Starting {
    item: [usize; WIDTH],
    key: [RngKey; WIDTH],
    origin: V3,
    direction: V3,
    count: usize,
    next: usize,
    /// The batch's paths made so far.
    made: usize,
}

impl Starting {
    fn new(params: &RenderParams) -> Starting {
        Starting {
            item: [0; WIDTH],
            key: no_keys(params),
            origin: V3::default(),
            direction: V3::default(),
            count: 0,
            next: 0,
            made: 0,
        }
    }

    /// The index of the next path to start, making the batch's next (up
    /// to) `WIDTH` paths when these are used up; None after the last.
    #[inline(always)]
    fn take<const AVX2: bool>(
        &mut self,
        scene: &PackedScene,
        params: &RenderParams,
        options: &LaneOptions,
        paths: &[(u32, u32)],
    ) -> Option<usize> {
        if self.next == self.count {
            self.refill::<AVX2>(scene, params, options, paths);
            if self.count == 0 {
                return None;
            }
        }
        self.next += 1;
        Some(self.next - 1)
    }

    #[inline(always)]
    fn refill<const AVX2: bool>(
        &mut self,
        scene: &PackedScene,
        params: &RenderParams,
        options: &LaneOptions,
        paths: &[(u32, u32)],
    ) {
        let todo = &paths[self.made.min(paths.len())..];
        self.count = todo.len().min(WIDTH);
        self.next = 0;
        let mut pixels = [0; WIDTH];
        for (l, &(pixel, sample_index)) in todo.iter().take(WIDTH).enumerate() {
            pixels[l] = pixel;
            self.item[l] = self.made + l;
            self.key[l] = rng_sampler_key(params.rng_sampler, pixel, sample_index, params.seed);
        }
        self.made += self.count;
        if self.count > 0 {
            camera_rays::<AVX2>(scene, params, options, self, &pixels);
        }
    }
}

/// `generate_camera_ray` for each path of `lanes`, at its `pixel`: a
/// pinhole camera with a box or tent filter in vector registers (the same
/// operations lane by lane), other cameras lane by lane.
#[inline(always)]
fn camera_rays<const AVX2: bool>(
    scene: &PackedScene,
    params: &RenderParams,
    options: &LaneOptions,
    starting: &mut Starting,
    pixel: &[u32; WIDTH],
) {
    #[cfg(target_arch = "x86_64")]
    if AVX2 && options.pinhole_camera {
        let keys = KeyLanes {
            hash: starting.key.map(|k| k.hash),
            reversed: starting.key.map(|k| k.reversed_index),
        };
        // SAFETY: `AVX2` only where the CPU has it (`trace_paths`).
        starting.direction = unsafe { pinhole_rays_lanes(params, &keys, pixel) };
        starting.origin = V3::splat(Vec3::from(params.cam_position));
        return;
    }
    for (l, &p) in pixel.iter().enumerate().take(starting.count) {
        let (origin, direction) =
            generate_camera_ray_with(scene, params, p, starting.key[l], |k| {
                options.aperture_corners[k as usize]
            });
        starting.origin.set_lane(l, origin);
        starting.direction.set_lane(l, direction);
    }
}

/// `generate_camera_ray`'s directions for a still pinhole camera with a
/// box or tent filter, a register of pixels at once.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2")]
fn pinhole_rays_lanes(params: &RenderParams, keys: &KeyLanes, pixel: &[u32; WIDTH]) -> V3 {
    let (one, two, half) = (Floats::splat(1.0), Floats::splat(2.0), Floats::splat(0.5));
    let dim = [DIM_CAMERA_JITTER; WIDTH];
    let (ux, uy) = if params.rng_sampler == SAMPLER_SOBOL {
        keys.float2(&dim)
    } else {
        (
            keys.independent_float(&dim),
            keys.independent_float(&dim.map(|d| d + 1)),
        )
    };
    // sample_filter_1d, box or tent.
    let r = Floats::splat(params.filter_radius);
    let filter = |u: Floats| {
        if params.filter_kind == FILTER_BOX {
            return (two * u - one) * r;
        }
        let below = r * ((two * u).sqrt() - one);
        let above = r * (one - (two - two * u).sqrt());
        select(u.lt(half), below, above)
    };
    let (offset_x, offset_y) = (filter(Floats(ux)), filter(Floats(uy)));
    let x = Floats(pixel.map(|p| (p % params.width) as f32)) + half + offset_x;
    let y = Floats(pixel.map(|p| (p / params.width) as f32)) + half + offset_y;
    let sx = two * x / Floats::splat(params.width as f32) - one;
    let sy = one - two * y / Floats::splat(params.height as f32);
    let splat3 = |v: [f32; 3]| V3::splat(Vec3::from(v));
    let tan = Floats::splat(params.tan_half_fov);
    let film = splat3(params.cam_right) * (sx * tan * Floats::splat(params.aspect))
        + splat3(params.cam_up) * (sy * tan);
    (splat3(params.cam_forward) + film).normalize()
}

/// `render::extension_hit` for every lane, the rays traced as one packet.
///
/// # Safety
/// The CPU must support AVX2 and the bit instructions, and the scene must
/// fit packets (`traversal::order_free`).
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
unsafe fn extension_hits(
    scene: &CpuScene,
    options: &LaneOptions,
    lanes: &PathLanes,
    hits: &mut [Hit; WIDTH],
    counts: &mut [u64; 3],
) {
    let live = lanes.live;
    let rays = lane_rays(
        live,
        lanes.origin,
        lanes.direction,
        Floats::splat(f32::MAX),
        |l| coverage_seed(options, lanes, l, 0),
        options.alpha_tested,
    );
    counts[0] += u64::from(rays.active.count_ones());
    // SAFETY: the caller's promise.
    let found = unsafe { trace_packet(scene, &rays, false) };
    for l in 0..WIDTH {
        if rays.active & (1 << l) != 0 {
            hits[l] =
                nearest_with_sphere_lights(scene, rays.origin(l), rays.direction(l), found[l]);
        }
    }
}

/// Lane `l`'s ray's seed for alpha tests (`rng_coverage_seed`), or 0 where
/// no triangle is alpha-tested (then no test reads it).
#[inline(always)]
fn coverage_seed(options: &LaneOptions, lanes: &PathLanes, l: usize, purpose: u32) -> u32 {
    if options.alpha_tested {
        rng_coverage_seed(lanes.key[l], lanes.bounce[l], purpose)
    } else {
        0
    }
}

/// A packet of the lanes' rays, those of lanes `active` traced: the other
/// lanes hold `Rays::default`'s harmless ray. Seeds only where `seeded`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn lane_rays(
    active: Bools,
    origin: V3,
    direction: V3,
    t_max: Floats,
    seed: impl Fn(usize) -> u32,
    seeded: bool,
) -> Rays {
    let idle = Rays::default();
    let rows = |v: V3, idle: [[f32; WIDTH]; 3]| {
        let idle = V3 {
            x: Floats(idle[0]),
            y: Floats(idle[1]),
            z: Floats(idle[2]),
        };
        let v = select3(active, v, idle);
        [v.x.0, v.y.0, v.z.0]
    };
    let mut rays = Rays {
        origin: rows(origin, idle.origin),
        direction: rows(direction, idle.direction),
        t_max: select(active, t_max, Floats(idle.t_max)).0,
        coverage_seed: idle.coverage_seed,
        active: bits(&active),
    };
    if seeded {
        for l in 0..WIDTH {
            if active[l] {
                rays.coverage_seed[l] = seed(l);
            }
        }
    }
    rays
}

/// `render::shadow_ray_reaches` for every lane (whether each lane's shadow
/// ray, if it has one, is unblocked), the rays traced as one packet.
///
/// # Safety
/// As for [`extension_hits`].
#[cfg(target_arch = "x86_64")]
#[inline]
#[target_feature(enable = "avx2,popcnt,lzcnt,bmi1")]
unsafe fn shadow_rays_reach(
    scene: &CpuScene,
    options: &LaneOptions,
    lanes: &PathLanes,
    shade: &ShadeLanes,
    counts: &mut [u64; 3],
) -> [bool; WIDTH] {
    let shadow = and(lanes.live, shade.shadow);
    let mut rays = lane_rays(
        shadow,
        shade.shadow_origin,
        shade.shadow_direction,
        shade.shadow_t_max,
        |l| coverage_seed(options, lanes, l, 1),
        options.alpha_tested,
    );
    let active = rays.active;
    counts[1] += u64::from(active.count_ones());
    if scene.light_params.num_spheres != 0 {
        let mut lanes_left = active;
        while lanes_left != 0 {
            let l = lanes_left.trailing_zeros() as usize;
            lanes_left &= lanes_left - 1;
            let (o, d) = (rays.origin(l), rays.direction(l));
            if sphere_light_blocker(scene, o, d, rays.t_max[l]).is_some() {
                rays.active &= !(1 << l);
            }
        }
    }
    if rays.active == 0 {
        return [false; WIDTH];
    }
    // SAFETY: the caller's promise.
    let blockers = unsafe { trace_packet(scene, &rays, true) };
    std::array::from_fn(|l| rays.active & (1 << l) != 0 && blockers[l].triangle == NO_HIT)
}

/// `shade_path` for all the lanes. On a Lambertian surface every
/// quantity is computed for all lanes at once (`simd`): a lane takes both
/// sides of each of `shade_path`'s branches and keeps the one the scalar
/// code takes; lanes that are not on one compute on zeros and keep nothing
/// of it. Lanes on other materials get `shade_path`'s own result.
#[inline(always)]
fn shade_lanes<const AVX2: bool, const TRIANGLES: bool>(
    scene: &CpuScene,
    params: &RenderParams,
    options: &LaneOptions,
    lanes: &PathLanes,
    hits: &[Hit; WIDTH],
    out: &mut ShadeLanes,
) {
    let zero = Floats::splat(0.0);
    let one = Floats::splat(1.0);

    // Gather: the hit triangle, its material and the lane's path, for the
    // lanes on a Lambertian surface; overflows end the path, and so do
    // escaped rays where nothing shines from beyond (`escapes_end`).
    let mut shading = [false; WIDTH];
    // The path state straight from the lanes' registers; lanes not
    // shaded here compute on it and keep nothing of it.
    let (key, bounce) = (lanes.key, lanes.bounce);
    let dir = lanes.direction;
    let mut throughput = lanes.throughput;
    let (prev_pdf, eta_scale) = (lanes.prev_pdf, lanes.eta_scale);
    let (mut t, mut b1, mut b2) = (zero, zero, zero);
    let (mut v0, mut v1, mut v2) = (V3::default(), V3::default(), V3::default());
    // The vertex normals interpolated (interpolate_normal, before its
    // normalization), lane by lane: three values to store rather than nine.
    let mut nv = V3::default();
    let mut light_pmf = zero;
    let (mut albedo, mut emission) = (V3::default(), V3::default());
    let mut double_sided = [false; WIDTH];
    // Lanes on smooth mirrors and glass, their materials.
    let mut delta = [false; WIDTH];
    let mut delta_lanes = DeltaLanes::default();
    // Each lane's material, where the tables give its values.
    let mut material = [0u32; WIDTH];
    let aov_on = params.aov != 0;
    out.end_all();
    for l in 0..WIDTH {
        if !lanes.live[l] {
            continue;
        }
        let hit = &hits[l];
        let tri = hit.triangle;
        if tri == OVERFLOW_HIT || (tri == NO_HIT && options.escapes_end) {
            continue;
        }
        // Escaped rays, spherical lights and other materials: `shade_path`
        // itself, for this lane.
        let kind = if tri == NO_HIT || tri & LIGHT_HIT_FLAG != 0 {
            LaneMaterial::Scalar
        } else {
            options.vector_materials[scene.tri_verts[tri as usize].material as usize]
        };
        if kind == LaneMaterial::Scalar {
            let r = shade_path(scene, params, &lanes.state(l), hit, key[l], bounce[l]);
            out.set_lane(l, &r);
            continue;
        }
        let tv = &scene.tri_verts[tri as usize];
        shading[l] = true;
        delta[l] = kind == LaneMaterial::Delta;
        material[l] = tv.material;
        if delta[l] {
            delta_lanes.set_lane(l, &scene.materials[tv.material as usize]);
        }
        if options.material_tables.is_none() {
            let m = &scene.materials[tv.material as usize];
            albedo.set_lane(l, Vec3::from(m.base_color));
            emission.set_lane(l, Vec3::from(m.emission));
            double_sided[l] = m.double_sided != 0;
        }
        t.0[l] = hit.t;
        (b1.0[l], b2.0[l]) = (hit.b12.x, hit.b12.y);
        v0.set_lane(l, tv.v0.into());
        v1.set_lane(l, tv.v1.into());
        v2.set_lane(l, tv.v2.into());
        let sh = &scene.tri_shading[tri as usize];
        let (u1, u2) = (hit.b12.x, hit.b12.y);
        let n =
            Vec3::from(sh.n0) * (1.0 - u1 - u2) + Vec3::from(sh.n1) * u1 + Vec3::from(sh.n2) * u2;
        nv.set_lane(l, n);
        light_pmf.0[l] = sh.light_pmf;
    }
    let any_delta = delta.iter().any(|&d| d);
    if let Some(tables) = &options.material_tables {
        // Lanes not shaded here take material 0's values, never read.
        albedo = tables.base_color.permute(&material);
        emission = tables.emission.permute(&material);
        double_sided = permute(tables.double_sided, &material).gt(zero);
    }

    // The surface: the point and its error (triangle_point, _error).
    let (e1, e2) = (v1 - v0, v2 - v0);
    let p = v0 + (e1 * b1 + e2 * b2);
    let e = e1.abs().max_glam(e2.abs());
    let floor_e = Floats::splat(OFFSET_EDGE_FRACTION) * e.x.max(e.y.max(e.z));
    let bound = p.abs() * Floats::splat(GAMMA1)
        + ((e1 * b1).abs() + (e2 * b2).abs()) * Floats::splat(GAMMA7);
    let p_error = bound.max_glam(V3 {
        x: floor_e,
        y: floor_e,
        z: floor_e,
    });
    let ng_raw = e1.cross(e2);
    let area = Floats::splat(0.5) * ng_raw.length();
    let ng = ng_raw / (Floats::splat(2.0) * area);
    let cos_o = dir.dot(ng);
    let front = cos_o.lt(zero);
    if any_delta {
        delta_lanes.absorb(&delta, front, t, &mut throughput);
    }

    // Emission, weighted against light sampling (triangle_light_pdf).
    let tri_select_prob = Floats::splat(scene.light_params.tri_select_prob);
    let mut light_pdf = tri_select_prob * light_pmf / area * t * t / cos_o.abs();
    if light_tree_on(scene) {
        // The light BVH's choice at the point the ray left from, lane by
        // lane where it counts.
        for l in 0..WIDTH {
            if shading[l] && prev_pdf.0[l] > 0.0 && emission.lane(l).max_element() > 0.0 {
                let pmf = light_tree_triangle_pmf(
                    scene,
                    params,
                    hits[l].triangle,
                    lanes.origin.lane(l),
                    light_tree_normal(lanes.prev_normal[l]),
                );
                light_pdf.0[l] = pmf / area.0[l] * t.0[l] * t.0[l] / cos_o.0[l].abs();
            }
        }
    }
    let w = select(
        prev_pdf.gt(zero),
        power_heuristic_lanes(prev_pdf, light_pdf),
        one,
    );
    let emits = and(emission.max_element().gt(zero), or(front, double_sided));
    let emitted = select3(emits, throughput * emission * w, V3::default());

    // The shading normal (interpolate_normal, reconcile_shading_normal)
    // and its frame (build_onb).
    let n = select3(front, ng, -ng);
    let wo = -dir;
    let nv_len = nv.length();
    let n_vertex = select3(nv_len.gt(Floats::splat(1e-12)), nv / nv_len, ng);
    let ns = reconcile_lanes(n, select3(front, n_vertex, -n_vertex), wo);
    let (frame_t, frame_b) = build_onb_lanes(ns);

    // A path may add a segment only while it stays within max_depth.
    // (`&`, not `&&`, and masks, not `if`s: branches per lane on these
    // went either way.)
    let mut grows: Bools = [false; WIDTH];
    for l in 0..WIDTH {
        grows[l] =
            shading[l] & (bounce[l] + 1 < params.max_depth) & (bounce[l] + 1 < MAX_BOUNCES_HARD);
    }
    out.emitted = select3(shading, emitted, out.emitted);
    if aov_on {
        for l in 0..WIDTH {
            // A Lambertian surface ends the delta chain.
            if shading[l] && prev_pdf.0[l] == 0.0 && !delta[l] {
                out.aov_event[l] = true;
                out.aov_albedo.set_lane(l, albedo.lane(l));
                out.aov_normal.set_lane(l, ns.lane(l));
            }
        }
    }
    if !grows.iter().any(|&g| g) {
        return;
    }

    // The bounce's random numbers (the BSDF lobe's is not drawn: Lambert
    // has one lobe, and a draw changes nothing else).
    let (mut u_select, mut u_rr) = ([0f32; WIDTH], [0f32; WIDTH]);
    let (mut u_light_x, mut u_light_y) = ([0f32; WIDTH], [0f32; WIDTH]);
    let (mut u_bsdf_x, mut u_bsdf_y) = ([0f32; WIDTH], [0f32; WIDTH]);
    // The lobe's number, which only mirrors and glass draw.
    let mut u_lobe = [0f32; WIDTH];
    let mut dim = [0u32; WIDTH];
    for l in 0..WIDTH {
        dim[l] = DIM_BOUNCE_BASE + DIM_PER_BOUNCE * bounce[l];
    }
    let keys = KeyLanes {
        hash: key.map(|k| k.hash),
        reversed: key.map(|k| k.reversed_index),
    };
    let at = |offset: u32| dim.map(|d| d + offset);
    if AVX2 && params.rng_sampler == SAMPLER_SOBOL {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `AVX2` only where the CPU has it (`trace_paths`).
        unsafe {
            u_select = keys.float(&at(DIM_LIGHT_SELECT));
            (u_light_x, u_light_y) = keys.float2(&at(DIM_LIGHT_SAMPLE));
            (u_bsdf_x, u_bsdf_y) = keys.float2(&at(DIM_BSDF_SAMPLE));
            u_rr = keys.float(&at(DIM_RUSSIAN_ROULETTE));
            if any_delta {
                u_lobe = keys.float(&at(DIM_BSDF_LOBE));
            }
        }
    } else if AVX2 {
        // Independent numbers (`rng_float2` draws dim and dim + 1).
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as above.
        unsafe {
            u_select = keys.independent_float(&at(DIM_LIGHT_SELECT));
            u_light_x = keys.independent_float(&at(DIM_LIGHT_SAMPLE));
            u_light_y = keys.independent_float(&at(DIM_LIGHT_SAMPLE + 1));
            u_bsdf_x = keys.independent_float(&at(DIM_BSDF_SAMPLE));
            u_bsdf_y = keys.independent_float(&at(DIM_BSDF_SAMPLE + 1));
            u_rr = keys.independent_float(&at(DIM_RUSSIAN_ROULETTE));
            if any_delta {
                u_lobe = keys.independent_float(&at(DIM_BSDF_LOBE));
            }
        }
    } else {
        for l in 0..WIDTH {
            u_select[l] = rng_float(key[l], dim[l] + DIM_LIGHT_SELECT);
            let u = rng_float2(key[l], dim[l] + DIM_LIGHT_SAMPLE);
            (u_light_x[l], u_light_y[l]) = (u.x, u.y);
            let u = rng_float2(key[l], dim[l] + DIM_BSDF_SAMPLE);
            (u_bsdf_x[l], u_bsdf_y[l]) = (u.x, u.y);
            u_rr[l] = rng_float(key[l], dim[l] + DIM_RUSSIAN_ROULETTE);
            if delta[l] {
                u_lobe[l] = rng_float(key[l], dim[l] + DIM_BSDF_LOBE);
            }
        }
    }

    // The light BVH's receiving normal as the path state carries it
    // (shade_path's n_code: Lambert only reflects; mirrors and glass,
    // all delta, give none).
    let mut n_code = [0u32; WIDTH];
    if light_tree_on(scene) {
        for l in 0..WIDTH {
            if grows[l] && !delta[l] {
                n_code[l] = light_tree_normal_code(n.lane(l));
            }
        }
    }

    // Rays leave from the side they go to (offset_ray_origin).
    let origin_front = offset_ray_origin_lanes(p, p_error, n);
    let origin_back = offset_ray_origin_lanes(p, p_error, -n);

    // Next-event estimation on Lambertian surfaces only: a delta BSDF has
    // nothing to evaluate.
    let nee = and(grows, not(delta));
    // The light sample: point, direction, distance (FLT_MAX at infinity),
    // radiance, density (0: none) and whether it is a delta light.
    let (mut ls_point, mut ls_wi, mut ls_radiance) = (V3::default(), V3::default(), V3::default());
    let (mut ls_distance, mut ls_pdf) = (zero, zero);
    let mut ls_delta = [false; WIDTH];
    if TRIANGLES {
        (ls_point, ls_wi, ls_distance, ls_radiance, ls_pdf) = sample_triangle_lights_lanes::<AVX2>(
            scene,
            params,
            &options.emitters,
            &nee,
            p,
            (&origin_front, &n_code),
            &u_select,
            (Floats(u_light_x), Floats(u_light_y)),
        );
    } else {
        // Any light: `sample_light` lane by lane.
        for l in 0..WIDTH {
            if !nee[l] {
                continue;
            }
            let u = Vec2::new(u_light_x[l], u_light_y[l]);
            let ls = sample_light(
                scene,
                params,
                p.lane(l),
                origin_front.lane(l),
                light_tree_normal(n_code[l]),
                u_select[l],
                u,
                0.0,
            );
            ls_point.set_lane(l, ls.point);
            ls_wi.set_lane(l, ls.wi);
            ls_radiance.set_lane(l, ls.radiance);
            ls_distance.0[l] = ls.distance;
            ls_pdf.0[l] = ls.pdf;
            ls_delta[l] = ls.delta;
        }
    }

    // Next-event estimation (Lambert: f and pdf about the shading normal).
    let (point, wi, pdf) = (ls_point, ls_wi, ls_pdf);
    let cos_s = ns.dot(wi);
    let f = albedo * (Floats::splat(INV_PI) * cos_s.max(zero));
    let mis = power_heuristic_lanes(pdf, cos_s.max(zero) * Floats::splat(INV_PI));
    let w = if TRIANGLES {
        mis
    } else {
        select(ls_delta, one, mis)
    };
    let c = throughput * f * ls_radiance * (w / pdf);
    let lights = and(and(nee, pdf.gt(zero)), same_side_lanes(n, ns, wi));
    // aim_shadow_ray from the side the light is on: to the sampled point,
    // or along wi, unbounded, for a light at infinity.
    let shadow_origin = select3(wi.dot(n).gt(zero), origin_front, origin_back);
    let d = point - shadow_origin;
    let len = d.length();
    let to_point = d / len;
    let short_by = to_point.abs().dot(point.abs() * Floats::splat(GAMMA7));
    let t_point = len * Floats::splat(1.0 - SHADOW_RAY_SHORTEN) - short_by;
    let (shadow_dir, t_max) = if TRIANGLES {
        (to_point, t_point)
    } else {
        let infinite = ls_distance.test(zero, |a, _| a == FLT_MAX);
        (
            select3(infinite, wi, to_point),
            select(infinite, Floats::splat(FLT_MAX), t_point),
        )
    };
    let shadow = and(lights, c.max_element().gt(zero));

    // The BSDF sample (lambert_sample), Russian roulette and the next
    // segment.
    let (dx, dy) = concentric_disk_lanes(Floats(u_bsdf_x), Floats(u_bsdf_y));
    let lz = (one - (dx * dx + dy * dy)).max(zero).sqrt();
    let bsdf_pdf = lz.max(zero) * Floats::splat(INV_PI);
    let mut bsdf_wi = (frame_t * dx + frame_b * dy + ns * lz).normalize();
    let mut weight = select3(bsdf_pdf.gt(zero), albedo, V3::default());
    let mut drawn = bsdf_pdf.gt(zero);
    let mut next_eta_scale = eta_scale;
    if any_delta {
        // Mirrors and glass (gltf_sample's delta branches); a refraction
        // into a volume scales by eta^2, which Russian roulette undoes.
        let d = delta_lanes.sample(front, wo, (frame_t, frame_b, ns), Floats(u_lobe));
        bsdf_wi = select3(delta, d.wi, bsdf_wi);
        weight = select3(delta, d.weight, weight);
        drawn = select_mask(delta, d.sampled, drawn);
        let bends = and(and(delta, bsdf_wi.dot(n).lt(zero)), delta_lanes.bends());
        next_eta_scale = select(bends, eta_scale * (d.eta * d.eta), eta_scale);
    }
    let sampled = and(and(grows, drawn), same_side_lanes(n, ns, bsdf_wi));
    let next_throughput = throughput * weight;
    // A refracted ray leaves from the other side.
    let next_origin = select3(bsdf_wi.dot(n).lt(zero), origin_back, origin_front);
    let q = (next_throughput.max_element() * next_eta_scale).min(Floats::splat(RR_MAX_CONTINUE));
    let mut roulette: Bools = [false; WIDTH];
    for l in 0..WIDTH {
        roulette[l] = bounce[l] >= RR_START_BOUNCE;
    }
    let survives = not(and(roulette, Floats(u_rr).ge(q)));
    let next_throughput = select3(roulette, next_throughput / q, next_throughput);
    let next = and(
        and(sampled, survives),
        next_throughput.max_element().gt(zero),
    );

    // Written whether or not the lane has a shadow ray or a next segment
    // (`shadow` and `next` say; nothing reads the rest otherwise): a
    // branch per lane on either goes as the light's side and Russian
    // roulette go.
    out.shadow_contribution = select3(grows, c, out.shadow_contribution);
    out.shadow_origin = select3(grows, shadow_origin, out.shadow_origin);
    out.shadow_direction = select3(grows, shadow_dir, out.shadow_direction);
    out.shadow_t_max = select(grows, t_max, out.shadow_t_max);
    out.shadow = select_mask(grows, shadow, out.shadow);
    out.next = select_mask(grows, next, out.next);
    out.next_origin = select3(grows, next_origin, out.next_origin);
    out.next_direction = select3(grows, bsdf_wi, out.next_direction);
    out.next_throughput = select3(grows, next_throughput, out.next_throughput);
    // A delta bounce: no MIS, like the camera ray.
    let next_prev_pdf = select(delta, zero, bsdf_pdf);
    out.next_prev_pdf = select(grows, next_prev_pdf, out.next_prev_pdf);
    out.next_eta_scale = select(grows, next_eta_scale, out.next_eta_scale);
    for l in 0..WIDTH {
        if grows[l] {
            out.next_dispersion_channel[l] = lanes.dispersion_channel[l];
            out.next_prev_normal[l] = n_code[l];
        }
    }
}

/// `sample_light`'s triangle branch per lane, for scenes whose lights are
/// all untextured emissive triangles: the emitter chosen lane by lane (by
/// power, or by the light BVH's walk from `p_tree` with the normal
/// `n_code` stands for), the point on it and the density in vector
/// registers. Returns the point, the
/// direction, the distance, the radiance and the density (0 where the
/// scalar code returns no sample).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn sample_triangle_lights_lanes<const AVX2: bool>(
    scene: &CpuScene,
    params: &RenderParams,
    emitters: &[LaneEmitter],
    grows: &Bools,
    p: V3,
    (p_tree, n_code): (&V3, &[u32; WIDTH]),
    u_select: &[f32; WIDTH],
    (ux, uy): (Floats, Floats),
) -> (V3, V3, Floats, V3, Floats) {
    let (zero, one) = (Floats::splat(0.0), Floats::splat(1.0));
    let p_env = params.env_select_prob;
    let p_tri = scene.light_params.tri_select_prob;
    let mut picked = [false; WIDTH];
    let (mut ev0, mut ev1, mut ev2) = (V3::default(), V3::default(), V3::default());
    let (mut en, mut e_radiance) = (V3::default(), V3::default());
    let mut pdf_scale = zero;
    let mut e_double_sided = [false; WIDTH];
    let n = params.num_emitters as usize;
    let tree = light_tree_on(scene);
    let few = !tree && n > 0 && n <= WIDTH && n == emitters.len();
    if few {
        // Few emitters: `select_emitter`'s binary search as comparisons
        // with the whole CDF. With the CDF non-decreasing, it returns e
        // where cdf[e - 1] <= u (or e = 0) and not cdf[e] <= u (or
        // e = n - 1); each emitter's values are blended into its lanes.
        let u = Floats(*u_select);
        let picked_lanes = and(*grows, u.lt(Floats::splat(p_env + p_tri)));
        let u_tri =
            ((u - Floats::splat(p_env)) / Floats::splat(p_tri)).min(Floats::splat(0.999_999_94));
        let mut above_previous = [true; WIDTH];
        for (k, e) in emitters.iter().enumerate() {
            let above_this = if k + 1 < n {
                u_tri.ge(Floats::splat(scene.emitters[k].cdf))
            } else {
                [false; WIDTH]
            };
            let here = and(and(above_previous, not(above_this)), picked_lanes);
            ev0 = select3(here, V3::splat(e.v0), ev0);
            ev1 = select3(here, V3::splat(e.v1), ev1);
            ev2 = select3(here, V3::splat(e.v2), ev2);
            en = select3(here, V3::splat(e.normal), en);
            pdf_scale = select(here, Floats::splat(e.pdf_scale), pdf_scale);
            e_radiance = select3(here, V3::splat(e.radiance), e_radiance);
            e_double_sided = select_mask(here, [e.double_sided; WIDTH], e_double_sided);
            above_previous = above_this;
        }
        picked = picked_lanes;
    }
    let walks = |l: usize| !few && grows[l] && u_select[l] < p_env + p_tri && !emitters.is_empty();
    // sample_light's walks, every lane's at once (light_tree_walk::sample_lanes).
    let (mut leaf, mut leaf_pmf) = ([0u32; WIDTH], [0f32; WIDTH]);
    if tree {
        let (mut at, mut nrm, mut u_tri, mut active) = (
            [Vec3::ZERO; WIDTH],
            [Vec3::ZERO; WIDTH],
            [0f32; WIDTH],
            [false; WIDTH],
        );
        for l in 0..WIDTH {
            if walks(l) {
                active[l] = true;
                at[l] = p_tree.lane(l);
                nrm[l] = light_tree_normal(n_code[l]);
                u_tri[l] = ((u_select[l] - p_env) / p_tri).min(0.999_999_94);
            }
        }
        // SAFETY: `AVX2` only where the CPU has it (`trace_paths`).
        (leaf, leaf_pmf) =
            unsafe { light_tree_walk::sample_lanes::<AVX2>(scene, &at, &nrm, &u_tri, &active) };
    }
    for l in 0..WIDTH {
        if !walks(l) {
            continue;
        }
        let e = if tree {
            // sample_emitter's density factor with the area it computes
            // (`triangle_lights_only`: every leaf is an emissive triangle).
            let pmf = leaf_pmf[l];
            if !(pmf > 0.0) {
                continue;
            }
            let row = fetch_light_tree_node(scene, leaf[l]).child_or_light;
            let e = &emitters[row as usize];
            let area = 0.5 * (e.v1 - e.v0).cross(e.v2 - e.v0).length();
            if !(area > 0.0) {
                continue;
            }
            pdf_scale.0[l] = p_tri * pmf / area;
            e
        } else {
            let u_tri = ((u_select[l] - p_env) / p_tri).min(0.999_999_94);
            let e = &emitters[select_emitter(scene, params, u_tri) as usize];
            pdf_scale.0[l] = e.pdf_scale;
            e
        };
        picked[l] = true;
        ev0.set_lane(l, e.v0);
        ev1.set_lane(l, e.v1);
        ev2.set_lane(l, e.v2);
        en.set_lane(l, e.normal);
        e_radiance.set_lane(l, e.radiance);
        e_double_sided[l] = e.double_sided;
    }
    // sample_uniform_triangle, then the point as sample_light takes it.
    let su = ux.sqrt();
    let (lb1, lb2) = (one - su, uy * su);
    let point = ev0 * (one - lb1 - lb2) + ev1 * lb1 + ev2 * lb2;
    let to_light = point - p;
    let dist2 = to_light.dot(to_light);
    let distance = dist2.sqrt();
    let wi = to_light / distance;
    let cos_light = -en.dot(wi);
    // sample_light's test as written there (NaNs included).
    let unlit = or(
        or(not(picked), not(dist2.gt(zero))),
        or(
            cos_light.abs().lt(Floats::splat(1e-7)),
            and(cos_light.lt(zero), not(e_double_sided)),
        ),
    );
    let pdf = pdf_scale * dist2 / cos_light.abs();
    (point, wi, distance, e_radiance, select(unlit, zero, pdf))
}

/// `sample_concentric_disk` per lane: both wedges computed, each lane's
/// kept.
#[inline(always)]
fn concentric_disk_lanes(ux: Floats, uy: Floats) -> (Floats, Floats) {
    let (zero, one, two) = (Floats::splat(0.0), Floats::splat(1.0), Floats::splat(2.0));
    let (ox, oy) = (two * ux - one, two * uy - one);
    let about_x = ox.abs().gt(oy.abs());
    let (r, across) = (select(about_x, ox, oy), select(about_x, oy, ox));
    let a = Floats::splat(std::f32::consts::PI / 4.0) * (across / r);
    let (mut sin, mut cos) = (zero, zero);
    for l in 0..WIDTH {
        (sin.0[l], cos.0[l]) = sin_cos_octant(a.0[l]);
    }
    let centre = and(ox.test(zero, |a, b| a == b), oy.test(zero, |a, b| a == b));
    (
        select(centre, zero, r * select(about_x, cos, sin)),
        select(centre, zero, r * select(about_x, sin, cos)),
    )
}

/// `power_heuristic` per lane.
#[inline(always)]
fn power_heuristic_lanes(f_pdf: Floats, g_pdf: Floats) -> Floats {
    let (f2, g2) = (f_pdf * f_pdf, g_pdf * g_pdf);
    let sum = f2 + g2;
    select(sum.gt(Floats::splat(0.0)), f2 / sum, Floats::splat(0.0))
}

/// `same_side` per lane.
#[inline(always)]
fn same_side_lanes(ng: V3, ns: V3, w: V3) -> Bools {
    (w.dot(ng) * w.dot(ns)).gt(Floats::splat(0.0))
}

/// `reconcile_shading_normal` per lane: every return computed, the first
/// that the scalar code reaches kept.
#[inline(always)]
fn reconcile_lanes(ng: V3, ns: V3, wo: V3) -> V3 {
    let zero = Floats::splat(0.0);
    let tiny = Floats::splat(1e-12);
    let c = SHADING_NORMAL_MIN_COS;
    // reflect_about(wo, ns)
    let r = ns * (Floats::splat(2.0) * ns.dot(wo)) - wo;
    let height = r.dot(ng);
    let tangent = r - ng * height;
    let len = tangent.length();
    let lifted = tangent * (Floats::splat((1.0 - c * c).sqrt()) / len) + ng * Floats::splat(c);
    let h = wo + lifted;
    let hl = h.length();
    let bent = select3(hl.le(tiny), ng, h / hl);
    let bent = select3(len.le(tiny), ng, bent);
    let kept = select3(height.ge(Floats::splat(c)), ns, bent);
    select3(ns.dot(ng).le(zero), ng, kept)
}

/// `build_onb` per lane: the tangent and bitangent of n.
#[inline(always)]
fn build_onb_lanes(n: V3) -> (V3, V3) {
    let s = select(
        n.z.ge(Floats::splat(0.0)),
        Floats::splat(1.0),
        Floats::splat(-1.0),
    );
    let a = Floats::splat(-1.0) / (s + n.z);
    let c = n.x * n.y * a;
    (
        V3 {
            x: Floats::splat(1.0) + s * n.x * n.x * a,
            y: s * c,
            z: -s * n.x,
        },
        V3 {
            x: c,
            y: s + n.y * n.y * a,
            z: -n.y,
        },
    )
}

/// `offset_ray_origin` per lane.
#[inline(always)]
fn offset_ray_origin_lanes(p: V3, p_error: V3, n: V3) -> V3 {
    let d = n.abs().dot(p_error);
    let o = n * d;
    V3 {
        x: p.x.zip(o.x, offset_component_selected),
        y: p.y.zip(o.y, offset_component_selected),
        z: p.z.zip(o.z, offset_component_selected),
    }
}

/// `intersect::offset_component` (with its `next_float_toward`) with every
/// branch taken and the scalar code's result selected, so that a register
/// of it is vector code. Tested equal to it, bit for bit, below.
#[inline(always)]
fn offset_component_selected(p: f32, o: f32) -> f32 {
    // An all-ones mask where `c` holds.
    let mask = |c: bool| 0u32.wrapping_sub(c as u32);
    let pick = |c: bool, a: u32, b: u32| (a & mask(c)) | (b & !mask(c));
    let po = p + o;
    let bits = po.to_bits();
    // One float away from zero in o's direction: bits + 1, else bits - 1.
    let up = ((po > 0.0) == (o > 0.0)) as u32;
    let stepped = bits.wrapping_add(up.wrapping_mul(2)).wrapping_sub(1);
    let tiny = 1 | ((!(o > 0.0)) as u32) << 31;
    let toward = pick(o == 0.0, bits, pick(po == 0.0, tiny, stepped));
    f32::from_bits(pick((po - p).abs() < o.abs(), toward, bits))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offsets of every kind: zero, tiny, huge, of either sign, where the
    /// sum rounds short of the offset and where it does not.
    #[test]
    fn selected_offset_equals_the_scalar_one_bit_for_bit() {
        let values = [
            0.0,
            -0.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            1e-30,
            -3e-8,
            1e-7,
            0.5,
            -1.0,
            1.0 + f32::EPSILON,
            3.0,
            -1234.5,
            1e7,
            -3.4e38,
            f32::MAX,
        ];
        let mut checked = 0;
        for &p in &values {
            for &o in &values {
                for (p, o) in [(p, o), (p, o * 0.37), (p * 1.0001, o * 1e-9)] {
                    assert_eq!(
                        offset_component_selected(p, o).to_bits(),
                        offset_component(p, o).to_bits(),
                        "p {p:e}, o {o:e}"
                    );
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 3 * values.len() * values.len());
    }

    /// The disk of the lanes is the scalar disk, bit for bit: on a grid
    /// with both wedges, their diagonals, the centre and the edges.
    #[test]
    fn disk_of_the_lanes_equals_the_scalar_disk() {
        let n = 257;
        let mut u: Vec<Vec2> = (0..n * n)
            .map(|i| {
                Vec2::new(
                    (i % n) as f32 / (n - 1) as f32,
                    (i / n) as f32 / (n - 1) as f32,
                )
            })
            .collect();
        u.extend([Vec2::splat(0.5), Vec2::new(0.5, 0.0), Vec2::new(1.0, 0.5)]);
        u.resize(u.len().next_multiple_of(WIDTH), Vec2::splat(0.5));
        for chunk in u.chunks(WIDTH) {
            let (dx, dy) = concentric_disk_lanes(
                Floats(std::array::from_fn(|l| chunk[l].x)),
                Floats(std::array::from_fn(|l| chunk[l].y)),
            );
            for l in 0..WIDTH {
                let d = sample_concentric_disk(chunk[l]);
                assert_eq!(
                    (dx.0[l].to_bits(), dy.0[l].to_bits()),
                    (d.x.to_bits(), d.y.to_bits()),
                    "u {:?}",
                    chunk[l]
                );
            }
        }
    }
}
