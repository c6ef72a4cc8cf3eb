//! Constants shared by the Rust host, the CPU reference and the GLSL kernels.
//!
//! `build.rs` turns every `pub const` line of this file into a `#define` in
//! `constants.glsl`, so no number is typed twice. Keep each constant on one
//! line as `pub const NAME: u32|f32 = VALUE;`.

/// Invocations per workgroup of every wavefront kernel.
pub const WORKGROUP_SIZE: u32 = 64;

/// Depth of the per-invocation CWBVH traversal stack (one entry per BVH8
/// level at most; obvhs' own traversal uses 32).
pub const BVH_STACK_SIZE: u32 = 32;
/// Loop iterations a per-path loop invocation may spend before it parks its
/// path for the wavefront kernels: lavapipe ends a SIMD group's loops
/// silently after 65,535 iterations in all (path_loop.comp), and a margin
/// stays for the iterations outside the counted ones.
pub const PATH_LOOP_BUDGET: u32 = 60000;
/// The per-path loop stops taking paths when one more bounce could no
/// longer spend this much traversal work per ray.
pub const PATH_LOOP_MIN_WORK: u32 = 32;
/// Upper bound on node visits plus triangle tests in one traversal. lavapipe
/// silently ends an invocation's loops after 65,535 iterations in total; we
/// stop well before and flag the ray as overflowed instead of returning a
/// wrong hit.
pub const BVH_MAX_ITERATIONS: u32 = 16384;

/// Random-number dimensions: the camera uses the first few, then every bounce
/// owns `DIM_PER_BOUNCE` dimensions starting at `DIM_BOUNCE_BASE`.
pub const DIM_CAMERA_JITTER: u32 = 0;
/// Two dimensions: the point on the aperture (disk, or inside a blade's
/// triangle).
pub const DIM_CAMERA_LENS: u32 = 2;
/// Which blade's triangle of a polygonal aperture the lens sample lands in.
pub const DIM_CAMERA_BLADE: u32 = 4;
/// The path's moment in the shutter interval, as a fraction of it, under
/// the independent sampler (`motion.glsl`; under Sobol it is the jitter
/// point's third coordinate; only scenes that move while the shutter is
/// open read it).
pub const DIM_CAMERA_TIME: u32 = 5;
pub const DIM_BOUNCE_BASE: u32 = 8;
pub const DIM_PER_BOUNCE: u32 = 8;
/// Offsets inside one bounce's dimensions.
pub const DIM_LIGHT_SELECT: u32 = 0;
pub const DIM_LIGHT_SAMPLE: u32 = 1;
pub const DIM_BSDF_SAMPLE: u32 = 3;
pub const DIM_RUSSIAN_ROULETTE: u32 = 5;
/// Picks the BSDF lobe (Phong diffuse or specular, dielectric reflection or
/// refraction).
pub const DIM_BSDF_LOBE: u32 = 6;
/// Picks the colour channel a path carries on from its first dispersive
/// surface (`dispersion.glsl`).
pub const DIM_DISPERSION_CHANNEL: u32 = 7;

/// `RenderParams::sampler`: how random numbers are drawn (`rng.glsl`).
/// Independent: a hash per (path, dimension).
pub const SAMPLER_INDEPENDENT: u32 = 0;
/// Owen-scrambled Sobol, padded by per-dimension index shuffles (Burley 2020).
pub const SAMPLER_SOBOL: u32 = 1;
/// The sampler `rng_path_key` uses and `--sampler` defaults to: the one with
/// the lower relMSE at equal spp on the bundled scenes (docs/design-record.md,
/// "Sobol against independent sampling").
pub const SAMPLER_DEFAULT: u32 = 1;

/// Russian roulette starts at this bounce (0 = the camera ray's hit), as
/// Mitsuba 3's rr_depth 5 does: its path integrator (3.9.1, path.cpp) counts
/// a hit into `depth` before the test `depth >= rr_depth`, so its roulette
/// first plays at the fifth hit, bounce 4. (Before 8ce0c9e this was 5, a
/// bounce later: 10 % more extension rays per sample than Mitsuba's on both
/// Cornell scenes, counted in its `rtcIntersect16` calls.) Starting at 3
/// gave the Cornell box 23% fewer rays per sample but 33% more relMSE at
/// 512 spp than 5: about 10% less efficient.
pub const RR_START_BOUNCE: u32 = 4;
/// Continuation probability is min(max throughput · η², this), η² the
/// product over the path's refractions (`PathState::eta_scale`).
pub const RR_MAX_CONTINUE: f32 = 0.95;
/// Absolute bound on bounces even with `--max-depth` unlimited; with Russian
/// roulette a path reaching it has probability below 0.95^1000.
pub const MAX_BOUNCES_HARD: u32 = 1024;

/// gamma(7) = 7u / (1 - 7u), u = 2^-24: the relative error bound of a point
/// computed as b0 v0 + b1 v1 + b2 v2 in f32 (pbrt-v4, Triangle::
/// InteractionFromIntersection; Higham's gamma_n).
pub const GAMMA7: f32 = 4.172325e-7;
/// gamma(1) = u / (1 - u): one rounding.
pub const GAMMA1: f32 = 5.960465e-8;
/// A hit point's error bound is at least this fraction of its triangle's
/// largest edge component: it covers the rounding of the watertight test
/// itself, so a ray leaving an axis-aligned plane at 0 (zero interpolation
/// error) does not start on it. Relative, so it holds at every scale.
pub const OFFSET_EDGE_FRACTION: f32 = 9.536743e-7;
/// A shadow ray stops this fraction short of its target so it does not hit
/// the light it aims at (relative, so it holds at every scene scale).
pub const SHADOW_RAY_SHORTEN: f32 = 0.0001;

/// Counters buffer slots (u32 each). The two queues the shade kernel pushes
/// to sit on cache lines of their own (16 words apart): lavapipe's two
/// threads take turns on each line, and sharing one doubled the traffic.
pub const COUNTER_RAYS_0: u32 = 0;
pub const COUNTER_RAYS_1: u32 = 16;
pub const COUNTER_SHADOW: u32 = 32;
pub const COUNTER_BVH_OVERFLOW: u32 = 48;
pub const COUNTER_NONFINITE: u32 = 49;
pub const COUNTER_EXTENSION_RAYS_LO: u32 = 50;
pub const COUNTER_EXTENSION_RAYS_HI: u32 = 51;
pub const COUNTER_SHADOW_RAYS_LO: u32 = 52;
pub const COUNTER_SHADOW_RAYS_HI: u32 = 53;
/// The per-path loop's next unstarted path slot of the chunk (path_loop.comp).
pub const COUNTER_NEXT_PATH: u32 = 54;
/// The two shading queues extend pushes to when shading is split by
/// material (`SHADE_QUEUE_*`), each on a cache line of its own.
pub const COUNTER_SHADE_BASIC: u32 = 64;
pub const COUNTER_SHADE_FULL: u32 = 80;
pub const COUNTER_COUNT: u32 = 96;

/// Value of `max_depth` meaning "no limit" (only Russian roulette ends paths).
pub const DEPTH_UNLIMITED: u32 = 0xFFFFFFFF;

/// `RenderParams::projection`.
pub const PROJECTION_PERSPECTIVE: u32 = 0;
pub const PROJECTION_ORTHOGRAPHIC: u32 = 1;

/// `RenderParams::filter_kind`: the pixel reconstruction filter, sampled by
/// filter importance sampling (every sample has weight 1).
pub const FILTER_BOX: u32 = 0;
pub const FILTER_TENT: u32 = 1;
pub const FILTER_GAUSSIAN: u32 = 2;
pub const FILTER_BLACKMAN_HARRIS: u32 = 3;
/// Bisection steps inverting a filter's CDF (Gaussian, Blackman-Harris):
/// the offset is found to within radius * 2^-23.
pub const FILTER_BISECTION_STEPS: u32 = 24;
/// Four-term Blackman-Harris window (Harris, Proc. IEEE 1978, table 1:
/// -92 dB side lobes): a0 - a1 cos(2πt) + a2 cos(4πt) - a3 cos(6πt), t in [0, 1].
pub const BLACKMAN_HARRIS_A0: f32 = 0.35875;
pub const BLACKMAN_HARRIS_A1: f32 = 0.48829;
pub const BLACKMAN_HARRIS_A2: f32 = 0.14128;
pub const BLACKMAN_HARRIS_A3: f32 = 0.01168;

/// `MaterialData::kind`: the scattering model of a material.
pub const MATERIAL_LAMBERT: u32 = 0;
pub const MATERIAL_PHONG: u32 = 1;
pub const MATERIAL_MIRROR: u32 = 2;
/// glTF 2.0 metallic-roughness (appendix B) with `KHR_materials_specular`,
/// `_transmission`, `_ior` and `_volume`: Lambert, rough or smooth plastic,
/// metal, thin-walled or refractive glass are cases of its parameters.
pub const MATERIAL_GLTF: u32 = 4;
/// `MaterialData::alpha_cutoff` of an opaque material (a MASK cutoff is at
/// least 0) and of an alpha BLEND material (met with probability alpha).
pub const ALPHA_OPAQUE: f32 = -1.0;
pub const ALPHA_BLEND: f32 = -2.0;
/// Salt of the random number of the stochastic alpha (BLEND) test of one
/// ray, kept apart from the sampler's dimensions (rng.glsl).
pub const RNG_COVERAGE_SALT: u32 = 0x632be5ab;
/// A GGX alpha (perceptual roughness squared) below this is a smooth
/// surface: its specular lobes are deltas, not a very narrow GGX (pbrt-v4's
/// TrowbridgeReitzDistribution::EffectivelySmooth uses the same bound).
pub const GGX_SMOOTH_ALPHA: f32 = 0.001;
/// Shading normals are bent until the mirror direction of the incoming ray
/// lies at least this cosine above the geometric surface (shading_frame.glsl).
pub const SHADING_NORMAL_MIN_COS: f32 = 0.01;
/// `KHR_materials_clearcoat`'s normal-incidence reflectance: the coat is a
/// dielectric of IOR 1.5, F0 = ((1.5 - 1) / (1.5 + 1))^2.
pub const CLEARCOAT_F0: f32 = 0.04;

/// 16-byte texels per `MaterialData` (its size / 16).
pub const MATERIAL_TEXELS: u32 = 17;
/// `MaterialData::lobes`: the glTF PBR extension lobes a material uses (a
/// bit is set only when the extension is present with a non-zero factor),
/// so shading skips the lobes a material lacks and `features.rs` compiles
/// out those no material has.
pub const LOBE_CLEARCOAT: u32 = 1;
pub const LOBE_SHEEN: u32 = 2;
pub const LOBE_IRIDESCENCE: u32 = 4;
pub const LOBE_ANISOTROPY: u32 = 8;
pub const LOBE_DIFFUSE_TRANSMISSION: u32 = 16;
pub const LOBE_DISPERSION: u32 = 32;
/// `KHR_materials_dispersion` is rendered at one wavelength per colour
/// channel (nm): red, green and blue primaries' dominant wavelengths.
pub const DISPERSION_WAVELENGTH_R: f32 = 630.0;
pub const DISPERSION_WAVELENGTH_G: f32 = 532.0;
pub const DISPERSION_WAVELENGTH_B: f32 = 465.0;
/// A `MaterialData` texture slot that holds no texture.
pub const NO_TEXTURE: u32 = 0xFFFFFFFF;
/// `Light::kind`: the analytic lights (twin of `scene::LightKind`).
pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DIRECTIONAL: u32 = 2;
/// A sphere of uniform radiance, sampled by the cone it subtends.
pub const LIGHT_SPHERE: u32 = 3;
/// A directional light with an angular diameter: a disk of uniform radiance at infinity.
pub const LIGHT_SUN: u32 = 4;
/// `Hit::triangle` of a ray that hit spherical light k is `LIGHT_HIT_FLAG | k`.
pub const LIGHT_HIT_FLAG: u32 = 0x80000000;
/// `LightTreeNode::flags`: the node is a leaf; its `child_or_light` is an
/// `emitters` row, or with `LIGHT_TREE_ANALYTIC` a `lights` index.
pub const LIGHT_TREE_LEAF: u32 = 1;
/// The node's lights emit on both sides of their normals' cone.
pub const LIGHT_TREE_TWO_SIDED: u32 = 2;
/// A leaf holding an analytic light (sphere, point or spot).
pub const LIGHT_TREE_ANALYTIC: u32 = 4;
/// The light BVH's deepest leaf: a leaf's path from the root is a bit
/// trail in one u32 (`light_trails`), one bit per level.
pub const LIGHT_TREE_MAX_DEPTH: u32 = 32;
/// The least factor the light BVH's receiving-normal bound gives a node
/// (2^-10): a node the bound puts at the surface's horizon keeps a chance,
/// so the normal only reorders what the tree without it can pick.
pub const LIGHT_TREE_MIN_COS_I: f32 = 0.0009765625;
/// `--light-sampler auto` builds the light BVH from this many emitters
/// (emissive triangles, spheres, point and spot lights) on; below it,
/// light selection stays proportional to power. Measured at equal time
/// (docs/performance.md, "Many lights"): the tree loses on the Cornell
/// box's 2 emitters (0.84x) and wins from 7 lights on (1.2-2.9x); 8 keeps
/// scenes of a light or two at power sampling, with a margin.
pub const LIGHT_TREE_MIN_LIGHTS: u32 = 8;
/// A hit or emitter in a one-level scene: no instance places its triangle.
pub const NO_INSTANCE: u32 = 0xFFFFFFFF;
/// `Instance::flags`: the instance's transform mirrors (negative
/// determinant), so its triangles' front faces turn with it.
pub const INSTANCE_MIRRORED: u32 = 1;
/// Texels (16 bytes) per `Instance` in `instance_texels`.
pub const INSTANCE_TEXELS: u32 = 7;
/// `RenderParams::motion_camera_base` of a render camera that does not move
/// while the shutter is open (the kernels then skip its interpolation).
pub const MOTION_CAMERA_STILL: u32 = 0xFFFFFFFF;
/// Below this sin^2 of a cone's half angle (sin^2 of 1.5 degrees, pbrt-v4's
/// threshold) cone sampling uses the small-angle series instead of cosines.
pub const SMALL_CONE_SIN2: f32 = 0.00068523;
/// `LightParams::env_sampling`: how light sampling picks environment directions.
pub const ENV_SAMPLE_IMPORTANCE: u32 = 0;
pub const ENV_SAMPLE_UNIFORM: u32 = 1;

/// glTF sampler wrap modes as `TextureInfo::flags` stores them (2 bits per
/// axis: S in bits 0-1, T in bits `TEXTURE_WRAP_T_SHIFT` ..).
pub const WRAP_REPEAT: u32 = 0;
pub const WRAP_CLAMP_TO_EDGE: u32 = 1;
pub const WRAP_MIRRORED_REPEAT: u32 = 2;
pub const TEXTURE_WRAP_T_SHIFT: u32 = 2;
/// `TextureInfo::flags`: nearest filtering (glTF magFilter NEAREST) instead
/// of bilinear.
pub const TEXTURE_NEAREST: u32 = 16;
/// `TextureInfo::flags`: the texture reads TEXCOORD_1 instead of TEXCOORD_0.
pub const TEXTURE_TEXCOORD_1: u32 = 32;
/// `TextureInfo::flags`: the image is grey and opaque (R = G = B, A = 255
/// in every texel) and stored at one byte per texel, four to a word, the
/// first texel in the low byte; it reads as the RGBA8 word (g, g, g, 255).
pub const TEXTURE_GREY: u32 = 64;
/// `TextureInfo::flags`: the image is grey with alpha (R = G = B) and
/// stored at two bytes per texel (grey in the low byte, then alpha), two to
/// a word, the first texel in the low half; it reads as (g, g, g, a).
pub const TEXTURE_GREY_ALPHA: u32 = 128;
/// A texture footprint's x (`texture_footprint` in `textures.glsl`) that
/// means none: the image itself is sampled (emission, normal maps, alpha
/// tests, `--texture-filter bilinear`).
pub const NO_FOOTPRINT: f32 = -1.0e30;
/// The least |cos| between the camera's view direction and a surface that
/// the mip level computation divides by (a grazing view's footprint grows
/// as 1/|cos|; this caps it near 6 levels above the head-on one).
pub const FOOTPRINT_MIN_COS: f32 = 0.015625;
/// The texel buffer starts with the sRGB decode table: 256 words holding
/// the f32 bits of the linear value of each 8-bit sRGB code.
pub const SRGB_TABLE_WORDS: u32 = 256;
/// Most bytes the texel buffer may take (lavapipe's maxStorageBufferRange);
/// the loader halves the largest images until all fit.
pub const TEXEL_BUDGET_BYTES: u32 = 134217728;
/// 1/255 as the nearest f32: 8-bit linear channels decode as `c * INV_255`
/// (a multiplication rounds the same on both back ends; a division by 255
/// may not).
pub const INV_255: f32 = 0.003921569;
/// Texel-space coordinates are clamped to ±this before conversion to int
/// (beyond it an f32 no longer holds every integer; repeat patterns alias).
pub const TEXEL_COORD_LIMIT: f32 = 8388608.0;

/// Specialization constant ids of the optional kernel features
/// (`shaders/common/features.glsl`, `src/features.rs`).
pub const SPEC_TEXTURES: u32 = 0;
pub const SPEC_ALPHA_MASK: u32 = 1;
pub const SPEC_PHONG: u32 = 2;
pub const SPEC_GLTF_MATERIAL: u32 = 3;
pub const SPEC_ANALYTIC_LIGHTS: u32 = 4;
pub const SPEC_ENVIRONMENT_MAP: u32 = 5;
pub const SPEC_THIN_LENS: u32 = 6;
pub const SPEC_FILTER_BISECTION: u32 = 7;
pub const SPEC_SOBOL: u32 = 8;
pub const SPEC_AOV: u32 = 9;
/// The glTF PBR extension lobes (`LOBE_*`), one constant each.
pub const SPEC_CLEARCOAT: u32 = 10;
pub const SPEC_SHEEN: u32 = 11;
pub const SPEC_IRIDESCENCE: u32 = 12;
pub const SPEC_ANISOTROPY: u32 = 13;
pub const SPEC_DIFFUSE_TRANSMISSION: u32 = 14;
pub const SPEC_DISPERSION: u32 = 15;
/// Geometry or cameras that move while the shutter is open (`motion.glsl`).
pub const SPEC_MOTION: u32 = 16;
/// A two-level scene: meshes kept once and placed by instances
/// (`instances.glsl`).
pub const SPEC_INSTANCES: u32 = 17;
/// Light selection by the light BVH (`light_bvh.glsl`): scenes with many
/// emitters (`LIGHT_TREE_MIN_LIGHTS`) or `--light-sampler bvh`.
pub const SPEC_LIGHT_TREE: u32 = 18;
pub const SPEC_COUNT: u32 = 19;
/// The one u32 specialization constant, after the bools: which
/// `MaterialData` texture slots any material of the scene fills
/// (`TEXTURE_SLOT_*`). The kernels compile in the sampling of those slots
/// only: lavapipe runs every branch of a kernel, taken or not.
pub const SPEC_TEXTURE_SLOTS: u32 = 19;
/// Which hits a `shade` kernel takes (`SHADE_QUEUE_*`), and whether extend
/// sorts hits into the two shading queues. lavapipe runs every branch of a
/// kernel for every hit, so a wall hit in a scene with glass paid for the
/// glTF BSDF it never evaluates; split, the basic queue's kernel has none.
pub const SPEC_SHADE_QUEUE: u32 = 20;
/// log2 of the texels in each part of a split scene array
/// (`packed::bindings`), or 0 where every such array is one part.
pub const SPEC_SCENE_VIEW_SHIFT: u32 = 21;
/// One `shade` kernel takes every hit, from the ray queue.
pub const SHADE_QUEUE_NONE: u32 = 0;
/// Misses, light hits and Lambert and mirror materials: the kernel compiled
/// without the Phong, glTF and extension-lobe code
/// (`KernelFeatures::basic_shade`).
pub const SHADE_QUEUE_BASIC: u32 = 1;
/// Phong and glTF materials: the scene's full kernel.
pub const SHADE_QUEUE_FULL: u32 = 2;
pub const TEXTURE_SLOT_BASE_COLOR: u32 = 0x1;
pub const TEXTURE_SLOT_METALLIC_ROUGHNESS: u32 = 0x2;
pub const TEXTURE_SLOT_EMISSIVE: u32 = 0x4;
pub const TEXTURE_SLOT_SPECULAR: u32 = 0x8;
pub const TEXTURE_SLOT_SPECULAR_COLOR: u32 = 0x10;
pub const TEXTURE_SLOT_TRANSMISSION: u32 = 0x20;
pub const TEXTURE_SLOT_CLEARCOAT: u32 = 0x40;
pub const TEXTURE_SLOT_CLEARCOAT_ROUGHNESS: u32 = 0x80;
pub const TEXTURE_SLOT_ANISOTROPY: u32 = 0x100;
pub const TEXTURE_SLOT_SHEEN_COLOR: u32 = 0x200;
pub const TEXTURE_SLOT_SHEEN_ROUGHNESS: u32 = 0x400;
pub const TEXTURE_SLOT_IRIDESCENCE: u32 = 0x800;
pub const TEXTURE_SLOT_IRIDESCENCE_THICKNESS: u32 = 0x1000;
pub const TEXTURE_SLOT_DIFFUSE_TRANSMISSION: u32 = 0x2000;
pub const TEXTURE_SLOT_DIFFUSE_TRANSMISSION_COLOR: u32 = 0x4000;
pub const TEXTURE_SLOT_THICKNESS: u32 = 0x8000;
pub const TEXTURE_SLOT_NORMAL: u32 = 0x10000;
pub const TEXTURE_SLOT_CLEARCOAT_NORMAL: u32 = 0x20000;
pub const TEXTURE_SLOTS_ALL: u32 = 0x3ffff;
/// `KHR_materials_sheen`: the sheen roughness is clamped to at least this
/// (below it the Charlie lobe is a sliver at grazing angles that neither
/// the albedo table nor sampling resolves); alpha is its square.
pub const SHEEN_MIN_ROUGHNESS: f32 = 0.07;
/// Nodes per axis of the sheen directional-albedo table
/// (`src/packed/sheen_table.rs`): cos θo and sheen roughness, each 0..1.
pub const SHEEN_TABLE_SIZE: u32 = 32;
