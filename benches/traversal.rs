//! Traversal microbenchmark: obvhs' compressed wide BVH8 as it builds it,
//! traversed by `shaders/bench/trace_cwbvh.comp` (storage buffers) and
//! `trace_cwbvh_texel.comp` (texel buffers), with the renderer's watertight
//! triangle test. (It first compared against the renderer's former BVH2,
//! which CWBVH has since replaced; the renderer's own traversal,
//! `shaders/common/bvh.glsl`, is timed by `benches/render.rs`.)
//!
//!     cargo bench --bench traversal
//!     VKPT_TRAV_RUNS=7 VKPT_TRAV_SIZE=1024 VKPT_TRAV_SCENES=cornell,helmet cargo bench --bench traversal
//!
//! Ray sets: primary rays of the scene's camera (one per pixel, jittered as
//! `camera.glsl` does), and incoherent rays leaving the primary hits in
//! cosine-distributed directions (a diffuse bounce). Each kernel is warmed up
//! once (lavapipe compiles at the first dispatch), then the two kernels are
//! timed alternately, wall clock around submit and wait; medians are
//! reported, and the ratio is the median of the per-run ratios.
//!
//! Validation: both kernels and the CPU reference (`vkpt::cpu::traversal::trace_ray`,
//! the renderer's CWBVH traversal over `PackedScene`) must report the same original triangle and t within 1e-4 relative for
//! more than 99.9% of rays, with no traversal overflow.

mod common;

use ash::vk;
use common::{env_or, median};
use glam::Vec3;
use std::path::Path;
use std::time::{Duration, Instant};
use vkpt::constants::*;
use vkpt::cpu::common::bvh::{Hit, NO_HIT, OVERFLOW_HIT};
use vkpt::cpu::common::camera::generate_camera_ray;
use vkpt::cpu::common::intersect::{offset_ray_origin, triangle_point_error};
use vkpt::cpu::common::rng::{pcg_hash, rng_float2, rng_path_key};
use vkpt::cpu::common::sampling::{FLT_MAX, build_onb, sample_cosine_hemisphere};
use vkpt::cpu::fast::WIDTH as RAYS;
use vkpt::cpu::fast::cache::CpuScene;
use vkpt::cpu::fast::packet::Rays;
use vkpt::cpu::traversal::{order_free, trace_packet, trace_ray};
use vkpt::gpu::buffer::Buffer;
use vkpt::gpu::context::Context;
use vkpt::gpu::context::VulkanDevice;
use vkpt::gpu::pipeline::{compiled::BENCH_KERNELS, create_compute_pipeline, spirv_words};
use vkpt::packed::PackedScene;
use vkpt::packed::layout::{RenderParams, TriangleVerts};
use vkpt::render::RenderSettings;
use vkpt::scene::Scene;

/// CWBVH traversal reading storage buffers, and texel buffers.
const KERNELS: [&str; 2] = ["trace_cwbvh", "trace_cwbvh_texel"];
/// Binding 0 is the uniform buffer, 1..=5 storage buffers, 6 and 7 texel
/// buffers (`shaders/bench/bench_bindings.glsl`).
const LAST_BINDING: u32 = 7;
const FIRST_TEXEL_BINDING: u32 = 6;
/// Words of one CWBVH node (`CwBvhNode`, all read).
const CWBVH_NODE_WORDS: u64 = 20;
/// A triangle test reads v0, v1, v2.
const TRI_WORDS: u64 = 9;

/// A ray as the kernels read it: (origin, t_max), (direction, 0).
type Ray = [[f32; 4]; 2];

fn ray(o: Vec3, d: Vec3) -> Ray {
    [o.extend(FLT_MAX).into(), d.extend(0.0).into()]
}

/// The renderer's `PackedScene` (the CPU reference's) with the scene
/// triangle of each BVH slot.
struct Reference {
    packed: PackedScene,
    order: Vec<u32>,
}

fn reference(scene: &Scene) -> Reference {
    let packed = PackedScene::new(scene).expect("scene packs");
    // `PackedScene` does not keep the slot order; the build is deterministic,
    // so a second build gives it (checked).
    let again = vkpt::packed::bvh::build(&scene.triangles).expect("BVH builds");
    assert!(
        again.nodes == packed.nodes,
        "the BVH build is not deterministic: cannot recover PackedScene's triangle order"
    );
    Reference {
        packed,
        order: again.order,
    }
}

struct Cwbvh {
    /// Nodes as 32-bit words (20 per node).
    words: Vec<u32>,
    tri_verts: Vec<TriangleVerts>,
    order: Vec<u32>,
    build_time: Duration,
}

fn cwbvh(scene: &Scene) -> Cwbvh {
    let start = Instant::now();
    let bvh = vkpt::packed::bvh::build_obvhs_cwbvh(
        &scene.triangles,
        vkpt::packed::bvh::BuildPreset::for_size(scene.triangles.len()),
    );
    let build_time = start.elapsed();
    assert_eq!(bvh.primitive_indices.len(), scene.triangles.len());
    let words = bytemuck::cast_slice::<_, u32>(&bvh.nodes).to_vec();
    assert_eq!(words.len(), bvh.nodes.len() * CWBVH_NODE_WORDS as usize);
    let tri_verts = bvh
        .primitive_indices
        .iter()
        .map(|&i| {
            let t = &scene.triangles[i as usize];
            TriangleVerts {
                v0: t.positions[0].into(),
                material: t.material,
                v1: t.positions[1].into(),
                v2: t.positions[2].into(),
                ..Default::default()
            }
        })
        .collect();
    Cwbvh {
        words,
        tri_verts,
        order: bvh.primitive_indices,
        build_time,
    }
}

/// Runs `f` over `0..n` on every core, in order.
fn par_map<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    let chunk = n.div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..n)
            .step_by(chunk)
            .map(|start| {
                let f = &f;
                s.spawn(move || (start..(start + chunk).min(n)).map(f).collect::<Vec<T>>())
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("worker"))
            .collect()
    })
}

/// Primary rays (one per pixel) and diffuse-bounce rays from their hits.
fn ray_sets(scene: &Scene, b: &Reference, size: u32) -> (RenderParams, Vec<Ray>, Vec<Ray>) {
    let settings = RenderSettings {
        width: size,
        height: size,
        seed: 1,
        ..Default::default()
    };
    let params = b
        .packed
        .render_params(scene, &settings, 0)
        .expect("the scene has a camera");
    let n = (size * size) as usize;
    let primary: Vec<Ray> = (0..n as u32)
        .map(|pixel| {
            let key = rng_path_key(pixel, 0, settings.seed);
            let (o, d) = generate_camera_ray(&b.packed, &params, pixel, key);
            ray(o, d)
        })
        .collect();
    let cpu_scene = CpuScene::new(&b.packed);
    let hits = par_map(n, |i| trace(&cpu_scene, &primary[i]));
    let hit_pixels: Vec<usize> = (0..n)
        .filter(|&i| hits[i].triangle < OVERFLOW_HIT)
        .collect();
    assert!(
        !hit_pixels.is_empty(),
        "no primary ray hits {}",
        scene.source.display()
    );
    let incoherent = (0..n)
        .map(|i| {
            // A pixel whose primary ray escapes borrows another pixel's hit.
            let src = if hits[i].triangle < OVERFLOW_HIT {
                i
            } else {
                hit_pixels[pcg_hash(i as u32) as usize % hit_pixels.len()]
            };
            let h = &hits[src];
            let tv = &b.packed.tri_verts[h.triangle as usize];
            let (v0, v1, v2) = (Vec3::from(tv.v0), Vec3::from(tv.v1), Vec3::from(tv.v2));
            let p = v0 + h.b12.x * (v1 - v0) + h.b12.y * (v2 - v0);
            let mut n = (v1 - v0).cross(v2 - v0).normalize();
            if n.dot(Vec3::from_array([
                primary[src][1][0],
                primary[src][1][1],
                primary[src][1][2],
            ])) > 0.0
            {
                n = -n;
            }
            let key = rng_path_key(i as u32, 0, settings.seed);
            let (t, bt) = build_onb(n);
            let l = sample_cosine_hemisphere(rng_float2(key, DIM_BOUNCE_BASE + DIM_BSDF_SAMPLE));
            ray(
                offset_ray_origin(p, triangle_point_error(h.b12, v0, v1, v2, p), n),
                (t * l.x + bt * l.y + n * l.z).normalize(),
            )
        })
        .collect();
    (params, primary, incoherent)
}

fn trace(packed: &CpuScene, r: &Ray) -> Hit {
    let o = Vec3::new(r[0][0], r[0][1], r[0][2]);
    let d = Vec3::new(r[1][0], r[1][1], r[1][2]);
    trace_ray(packed, o, d, r[0][3], false, 0, 0.0)
}

/// The answers for packet `p`: rays RAYS * p onwards, traced together.
fn packet_answers(reference: &Reference, scene: &CpuScene, rays: &[Ray], p: usize) -> Vec<Answer> {
    let mut packet = Rays::default();
    let first = p * RAYS;
    for (lane, r) in rays[first..(first + RAYS).min(rays.len())]
        .iter()
        .enumerate()
    {
        let o = Vec3::new(r[0][0], r[0][1], r[0][2]);
        let d = Vec3::new(r[1][0], r[1][1], r[1][2]);
        packet.set(lane, o, d, r[0][3], 0);
    }
    // SAFETY: packets only where `order_free` found AVX2 and the bit
    // instructions.
    let hits = unsafe { trace_packet(scene, &packet, false) };
    hits.iter()
        .map(|h| answer(h.t, h.triangle, &reference.order))
        .collect()
}

/// The renderer's triangles in its BVH order: 9 little-endian f32 each.
fn dump_triangles(dir: &Path, label: &str, packed: &PackedScene) -> std::io::Result<()> {
    let floats: Vec<f32> = packed
        .tri_verts
        .iter()
        .flat_map(|t| [t.v0, t.v1, t.v2].into_iter().flatten())
        .collect();
    std::fs::create_dir_all(dir)?;
    std::fs::write(
        dir.join(format!("{label}.tris")),
        bytemuck::cast_slice(&floats),
    )
}

/// The rays (8 f32 each, as the kernels read them) and the CPU reference's
/// distance per ray (negative for a miss).
fn dump_ray_set(dir: &Path, name: &str, rays: &[Ray], cpu: &[Answer]) -> std::io::Result<()> {
    let t: Vec<f32> = cpu
        .iter()
        .map(|a| if a.triangle < OVERFLOW_HIT { a.t } else { -1.0 })
        .collect();
    std::fs::write(dir.join(format!("{name}.rays")), bytemuck::cast_slice(rays))?;
    std::fs::write(dir.join(format!("{name}.hits")), bytemuck::cast_slice(&t))
}

/// Vulkan objects of the two benchmark kernels (descriptor layout of
/// `shaders/bench/bench_bindings.glsl`).
struct Kernels {
    set_layout: vk::DescriptorSetLayout,
    layout: vk::PipelineLayout,
    pipelines: Vec<vk::Pipeline>,
    pool: vk::DescriptorPool,
    command_pool: vk::CommandPool,
    fence: vk::Fence,
}

impl Kernels {
    fn new(ctx: &Context) -> anyhow::Result<Kernels> {
        let d = &ctx.device;
        let bindings: Vec<_> = (0..=LAST_BINDING)
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(descriptor_type(b))
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        // SAFETY (all calls below): valid device and create infos that
        // outlive each call; objects are destroyed in `destroy`.
        let set_layout = unsafe {
            d.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                None,
            )
        }?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(8)];
        let set_layouts = [set_layout];
        let layout = unsafe {
            d.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default()
                    .set_layouts(&set_layouts)
                    .push_constant_ranges(&ranges),
                None,
            )
        }?;
        let mut pipelines = Vec::new();
        for name in KERNELS {
            let (_, spirv) = BENCH_KERNELS
                .iter()
                .find(|(n, _)| *n == name)
                .unwrap_or_else(|| panic!("shaders/bench/{name}.comp is not compiled"));
            pipelines.push(create_compute_pipeline(ctx, layout, &spirv_words(spirv))?);
        }
        let sizes = [
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(64),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::STORAGE_BUFFER)
                .descriptor_count(64 * LAST_BINDING),
            vk::DescriptorPoolSize::default()
                .ty(vk::DescriptorType::UNIFORM_TEXEL_BUFFER)
                .descriptor_count(64 * 2),
        ];
        let pool = unsafe {
            d.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(64)
                    .pool_sizes(&sizes)
                    .flags(vk::DescriptorPoolCreateFlags::FREE_DESCRIPTOR_SET),
                None,
            )
        }?;
        let command_pool = unsafe {
            d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(ctx.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }?;
        let fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }?;
        Ok(Kernels {
            set_layout,
            layout,
            pipelines,
            pool,
            command_pool,
            fence,
        })
    }

    /// A descriptor set over `buffers` (bindings 0..=5) and texel buffer
    /// `views` (bindings 6, 7).
    fn set(
        &self,
        ctx: &Context,
        buffers: [&Buffer; 6],
        views: [vk::BufferView; 2],
    ) -> anyhow::Result<vk::DescriptorSet> {
        let layouts = [self.set_layout];
        // SAFETY: the pool and layout are alive.
        let set = unsafe {
            ctx.device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(self.pool)
                    .set_layouts(&layouts),
            )
        }?[0];
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> =
            buffers.iter().map(|b| b.descriptor_info()).collect();
        let views = views.map(|v| [v]);
        let writes: Vec<_> = infos
            .iter()
            .enumerate()
            .map(|(b, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(b as u32)
                    .descriptor_type(descriptor_type(b as u32))
                    .buffer_info(info)
            })
            .chain(views.iter().enumerate().map(|(i, view)| {
                let b = FIRST_TEXEL_BINDING + i as u32;
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(b)
                    .descriptor_type(descriptor_type(b))
                    .texel_buffer_view(view)
            }))
            .collect();
        // SAFETY: the buffers are alive and the set is not in use.
        unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
        Ok(set)
    }

    /// One dispatch of kernel `k` over `rays` rays; returns the wall-clock
    /// time of submit plus wait.
    fn run(
        &self,
        ctx: &Context,
        k: usize,
        set: vk::DescriptorSet,
        rays: u32,
        stats: bool,
    ) -> anyhow::Result<Duration> {
        let d = &ctx.device;
        // SAFETY: objects are alive; we wait for the fence before returning,
        // so the command buffer is never reset while in use.
        unsafe {
            let cmd = d.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(self.command_pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )?[0];
            d.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )?;
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipelines[k]);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &[set],
                &[],
            );
            let push = [rays, stats as u32];
            d.cmd_push_constants(
                cmd,
                self.layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                bytemuck::cast_slice(&push),
            );
            d.cmd_dispatch(cmd, rays.div_ceil(WORKGROUP_SIZE), 1, 1);
            d.end_command_buffer(cmd)?;
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            let start = Instant::now();
            d.queue_submit(ctx.queue, &submit, self.fence)?;
            d.wait_for_fences(&[self.fence], true, u64::MAX)?;
            let elapsed = start.elapsed();
            d.reset_fences(&[self.fence])?;
            d.free_command_buffers(self.command_pool, &cmds);
            Ok(elapsed)
        }
    }

    fn destroy(&mut self, ctx: &Context) {
        // SAFETY: the device is idle (every run waits for its fence).
        unsafe {
            let d = &ctx.device;
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.command_pool, None);
            d.destroy_descriptor_pool(self.pool, None);
            for p in self.pipelines.drain(..) {
                d.destroy_pipeline(p, None);
            }
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

fn descriptor_type(binding: u32) -> vk::DescriptorType {
    match binding {
        0 => vk::DescriptorType::UNIFORM_BUFFER,
        FIRST_TEXEL_BINDING.. => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
        _ => vk::DescriptorType::STORAGE_BUFFER,
    }
}

fn storage(ctx: &Context, name: &str, data: &[u8]) -> Buffer {
    let mut b = Buffer::gpu_only(
        ctx,
        name,
        data.len() as u64,
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
    )
    .expect("buffer");
    b.upload(ctx, data).expect("upload");
    b
}

/// The buffer as RGBA32UI texels.
fn texel_view(ctx: &Context, b: &Buffer) -> vk::BufferView {
    let info = vk::BufferViewCreateInfo::default()
        .buffer(b.raw)
        .format(vk::Format::R32G32B32A32_UINT)
        .range(vk::WHOLE_SIZE);
    // SAFETY: the buffer is alive and has UNIFORM_TEXEL_BUFFER usage.
    unsafe { ctx.device.create_buffer_view(&info, None) }.expect("buffer view")
}

/// A kernel's answer for one ray, in scene triangle ids.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Answer {
    t: f32,
    /// Scene triangle, or NO_HIT / OVERFLOW_HIT.
    triangle: u32,
}

fn answer(t: f32, slot: u32, order: &[u32]) -> Answer {
    Answer {
        t,
        triangle: if slot < OVERFLOW_HIT {
            order[slot as usize]
        } else {
            slot
        },
    }
}

fn agree(a: Answer, b: Answer) -> bool {
    a.triangle == b.triangle
        && (a.triangle == NO_HIT || (a.t - b.t).abs() <= 1e-4 * a.t.abs().max(b.t.abs()))
}

/// Agreement of `got` with `want`; prints the first mismatches. Returns the
/// number of mismatches, of which ties (same t, another triangle: a shared
/// edge or duplicate triangle), and overflows.
fn compare(what: &str, want: &[Answer], got: &[Answer]) -> (usize, usize, usize) {
    let (mut bad, mut ties, mut overflows) = (0, 0, 0);
    for (i, (&w, &g)) in want.iter().zip(got).enumerate() {
        overflows += (g.triangle == OVERFLOW_HIT) as usize;
        if agree(w, g) {
            continue;
        }
        bad += 1;
        let tie = w.triangle < OVERFLOW_HIT
            && g.triangle < OVERFLOW_HIT
            && (w.t - g.t).abs() <= 1e-4 * w.t.abs();
        ties += tie as usize;
        if bad <= 3 {
            println!("    mismatch {what} ray {i}: want {w:?}, got {g:?}");
        }
    }
    (bad, ties, overflows)
}

fn main() {
    let runs = env_or("VKPT_TRAV_RUNS", 5) as usize;
    let size = env_or("VKPT_TRAV_SIZE", 512);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let all_scenes = [
        ("cornell", root.join("scenes/cornell-box.gltf")),
        (
            "cornell-spheres",
            root.join("scenes/cornell-spheres.gltf"),
        ),
        (
            "helmet",
            root.join("../shared/gltf-samples/DamagedHelmet/DamagedHelmet.glb"),
        ),
        (
            "spheres",
            root.join(
                "../shared/gltf-samples/MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.gltf",
            ),
        ),
    ];
    let wanted =
        std::env::var("VKPT_TRAV_SCENES").unwrap_or_else(|_| "cornell,helmet,spheres".into());

    // Where to write the triangles, rays and CPU hits for
    // benches/embree_traversal.sh (which times Embree on the same rays).
    let dump = std::env::var_os("VKPT_TRAV_DUMP").map(std::path::PathBuf::from);
    let ctx = Context::new(VulkanDevice::Best, None).expect("a Vulkan device");
    let mut kernels = Kernels::new(&ctx).expect("benchmark pipelines");
    println!(
        "{} | {size}x{size} rays per set | median of {runs} dispatches",
        ctx.device_name()
    );
    let mut table = Vec::new();
    let mut all_ok = true;
    for (label, path) in all_scenes {
        if !wanted.split(',').any(|w| w == label) {
            continue;
        }
        if !path.exists() {
            println!("{label}: {} not found, skipped", path.display());
            continue;
        }
        let scene = Scene::load(&path).expect("scene loads");
        let start = Instant::now();
        let reference = reference(&scene);
        let reference_time = start.elapsed();
        let cw = cwbvh(&scene);
        println!(
            "\n{label}: {} triangles | renderer's CWBVH {} nodes (built twice in {:.2?}) | obvhs CWBVH {} nodes x 80 B ({:.2?})",
            scene.triangles.len(),
            reference.packed.nodes.len(),
            reference_time,
            cw.words.len() / CWBVH_NODE_WORDS as usize,
            cw.build_time,
        );
        let (params, primary, incoherent) = ray_sets(&scene, &reference, size);
        if let Some(dir) = &dump {
            dump_triangles(dir, label, &reference.packed).expect("triangles written");
        }

        let ubo = {
            let bytes = bytemuck::bytes_of(&params);
            let mut b = Buffer::gpu_only(
                &ctx,
                "params",
                bytes.len() as u64,
                vk::BufferUsageFlags::UNIFORM_BUFFER,
            )
            .expect("buffer");
            b.upload(&ctx, bytes).expect("upload");
            b
        };
        let nodes8 = storage(&ctx, "cwbvh nodes", bytemuck::cast_slice(&cw.words));
        let tris8 = storage(&ctx, "cwbvh tris", bytemuck::cast_slice(&cw.tri_verts));
        let views = [texel_view(&ctx, &nodes8), texel_view(&ctx, &tris8)];

        for (set_name, rays) in [("primary", &primary), ("incoherent", &incoherent)] {
            let n = rays.len();
            let ray_buf = storage(&ctx, "rays", bytemuck::cast_slice(rays.as_slice()));
            let mut results = Buffer::gpu_only(
                &ctx,
                "results",
                8 * n as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )
            .expect("buffer");
            let mut stats = Buffer::gpu_only(
                &ctx,
                "stats",
                16 * n as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            )
            .expect("buffer");
            let sets = KERNELS.map(|_| {
                kernels
                    .set(
                        &ctx,
                        [&ubo, &nodes8, &tris8, &ray_buf, &results, &stats],
                        views,
                    )
                    .expect("set")
            });

            // Reference on the CPU, timed as often as the kernels.
            let mut cpu_rates = Vec::new();
            let mut cpu = Vec::new();
            let cpu_scene = CpuScene::new(&reference.packed);
            for _ in 0..runs {
                let cpu_start = Instant::now();
                cpu = par_map(n, |i| {
                    let h = trace(&cpu_scene, &rays[i]);
                    answer(h.t, h.triangle, &reference.order)
                });
                cpu_rates.push(n as f64 / cpu_start.elapsed().as_secs_f64() / 1e6);
            }
            // The lane schedule's packets (`traversal::trace_packet`): runs of
            // RAYS consecutive rays, where the packets fit the scene.
            let packet_rates = order_free(&cpu_scene).then(|| {
                let mut rates = Vec::new();
                for _ in 0..runs {
                    let start = Instant::now();
                    let found = par_map(n.div_ceil(RAYS), |p| {
                        packet_answers(&reference, &cpu_scene, rays, p)
                    });
                    rates.push(n as f64 / start.elapsed().as_secs_f64() / 1e6);
                    let found: Vec<Answer> = found.into_iter().flatten().take(n).collect();
                    assert!(
                        found.iter().zip(&cpu).all(
                            |(a, b)| a.triangle == b.triangle && a.t.to_bits() == b.t.to_bits()
                        ),
                        "{label} {set_name}: packets and single rays disagree"
                    );
                }
                median(rates)
            });
            if let Some(dir) = &dump {
                dump_ray_set(dir, &format!("{label}-{set_name}"), rays, &cpu)
                    .expect("ray set written");
            }

            // Warm-up (compiles the kernel) doubles as the validation run.
            let mut gpu = Vec::new();
            let mut sum8 = [0u64; 4];
            for (k, &set) in sets.iter().enumerate() {
                let order = &cw.order;
                kernels
                    .run(&ctx, k, set, n as u32, k == 0)
                    .expect("dispatch");
                let bytes = results.read(&ctx, 8 * n).expect("read results");
                let words: &[u32] = bytemuck::cast_slice(&bytes);
                gpu.push(
                    words
                        .chunks_exact(2)
                        .map(|w| answer(f32::from_bits(w[0]), w[1], order))
                        .collect::<Vec<_>>(),
                );
                if k == 0 {
                    let bytes = stats.read(&ctx, 16 * n).expect("read stats");
                    for s in bytemuck::cast_slice::<u8, [u32; 4]>(&bytes) {
                        (0..4).for_each(|j| sum8[j] += s[j] as u64);
                    }
                }
            }
            let mut times = KERNELS.map(|_| Vec::new());
            for run in 0..runs {
                // Rotate which kernel goes first.
                for j in 0..KERNELS.len() {
                    let k = (j + run) % KERNELS.len();
                    let t = kernels
                        .run(&ctx, k, sets[k], n as u32, false)
                        .expect("dispatch");
                    times[k].push(t.as_secs_f64());
                }
            }
            // SAFETY: every run waited for its fence.
            unsafe { ctx.device.free_descriptor_sets(kernels.pool, &sets) }.expect("free sets");

            let hits = cpu.iter().filter(|a| a.triangle < OVERFLOW_HIT).count();
            println!(
                "  {set_name}: {n} rays, {:.1}% hit; CPU reference {:.2} Mrays/s (median of {runs}){}",
                100.0 * hits as f64 / n as f64,
                median(cpu_rates),
                packet_rates.map_or(String::new(), |r| format!(", packets of {RAYS} {r:.2}"))
            );
            let mut ok = true;
            for (what, want, got) in [
                ("cwbvh vs cpu", &cpu, &gpu[0]),
                ("cwbvh_texel vs cpu", &cpu, &gpu[1]),
            ] {
                let (bad, ties, overflows) = compare(what, want, got);
                let agree = 1.0 - bad as f64 / n as f64;
                println!(
                    "    {what}: {:.4}% agree ({bad} mismatches, {ties} of them ties at equal t), {overflows} overflows",
                    100.0 * agree
                );
                ok &= agree > 0.999 && overflows == 0;
            }
            all_ok &= ok;
            let per_ray = |x: u64| x as f64 / n as f64;
            // Rays: 6 words read, 2 written.
            let words8 = per_ray(sum8[0] * CWBVH_NODE_WORDS + sum8[1] * TRI_WORDS) + 8.0;
            println!(
                "    per ray: CWBVH {:.1} nodes, {:.1} tris, {:.1} pushes, {:.0} buffer words",
                per_ray(sum8[0]),
                per_ray(sum8[1]),
                per_ray(sum8[2]),
                words8,
            );
            let mrays = |k: usize| median(times[k].iter().map(|t| n as f64 / t / 1e6).collect());
            // Speed of kernel k relative to kernel j: median (min-max) of per-run ratios.
            let ratio = |k: usize, j: usize| {
                let r: Vec<f64> = times[j].iter().zip(&times[k]).map(|(a, b)| a / b).collect();
                format!(
                    "{:.2}x ({:.2}-{:.2})",
                    median(r.clone()),
                    r.iter().copied().fold(f64::INFINITY, f64::min),
                    r.iter().copied().fold(0.0, f64::max)
                )
            };
            table.push(format!(
                "{label:<8} {set_name:<11} {:>8.2} {:>8.2} {:>19} {words8:>6.0} {:>5}",
                mrays(0),
                mrays(1),
                ratio(1, 0),
                if ok { "ok" } else { "FAIL" }
            ));
            for mut b in [ray_buf, results, stats] {
                b.destroy(&ctx);
            }
        }
        for view in views {
            // SAFETY: no dispatch using the view is in flight.
            unsafe { ctx.device.destroy_buffer_view(view, None) };
        }
        for mut b in [ubo, nodes8, tris8] {
            b.destroy(&ctx);
        }
    }
    kernels.destroy(&ctx);

    println!(
        "\nMrays/s (median); speed ratios (median and range of per-run ratios); storage-buffer words read per ray"
    );
    println!(
        "{:<8} {:<11} {:>8} {:>8} {:>19} {:>6} {:>5}",
        "scene", "rays", "CWBVH", "CW tx", "CW tx/CWBVH", "CW w", "valid"
    );
    for row in table {
        println!("{row}");
    }
    if !all_ok {
        eprintln!("validation failed");
        std::process::exit(1);
    }
}
