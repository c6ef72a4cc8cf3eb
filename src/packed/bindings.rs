//! The descriptor bindings of the kernels: ONE table, the only place a
//! binding number is written. `build.rs` includes this file (it depends on
//! nothing, so the build script can compile it too) and writes the GLSL
//! declarations, `bindings.glsl`, from it; the host makes the set layout,
//! the descriptor pool, the buffers, their texel views and the descriptor
//! writes by iterating it (`src/gpu/descriptors.rs`, `src/gpu/resources.rs`).
//! Adding a binding is one row here, plus the line of `resources.rs` that
//! says what fills its buffer.
//!
//! Why texel views: lavapipe gathers a texel fetch as one vector load, while
//! it runs a storage-buffer load or store one lane and one 32-bit word at a
//! time. So kernels read the scene arrays and the path state through
//! RGBA32UI texel views of the storage buffers, and write the path state as
//! pairs of 64-bit words (half the stores of 32-bit ones; `path_state.glsl`).
//! The storage declarations of the viewed scene arrays stay: they give the
//! structs the SPIR-V layout `tests/suite/layout.rs` checks against Rust.
//!
//! No binding's range bounds the scene: the texel views of the arrays that
//! grow with the scene (`split` rows: BVH nodes, triangles, emitters,
//! texture coordinates, texels) are arrays of `SCENE_VIEWS` descriptors.
//! The host cuts such an array into parts of 2^shift texels, each a buffer
//! and a view of its own, the shift the largest the device's limits allow
//! (`maxTexelBufferElements`, `maxMemoryAllocationSize`); the kernels read
//! texel `i` from view `i >> shift` (`scene_texel` in the generated
//! `bindings.glsl`). Where every array fits one view the shift is 0 and the
//! kernels read view 0 alone, as if it were a single binding. The storage
//! binding of a split array covers at most `maxStorageBufferRange` of its
//! first part: the kernels never index it (`tests/suite/texel_reads.rs`).

/// How a binding is declared and what kind of descriptor it takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A std140 `uniform` block holding one value of the row's type.
    Uniform,
    /// A std430 `readonly buffer`.
    ReadOnly,
    /// A std430 `buffer` the kernels write.
    ReadWrite,
    /// A `usamplerBuffer` over a buffer of its own.
    Texels(TexelFormat),
    /// A `usamplerBuffer` viewing the buffer of the storage row named `of`.
    View {
        of: &'static str,
        format: TexelFormat,
    },
}

/// The format of a uniform texel buffer's view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelFormat {
    /// 16-byte texels: one row of a struct packed in 16-byte rows.
    Rgba32Uint,
    /// 4-byte texels.
    R32Uint,
}

impl TexelFormat {
    pub const fn bytes(self) -> u64 {
        match self {
            TexelFormat::Rgba32Uint => 16,
            TexelFormat::R32Uint => 4,
        }
    }
}

/// Which kernel schedules use a binding. The wavefront uses every row; a
/// schedule without path state in memory (a per-path loop for CPU-class
/// devices) takes only the `Any` rows: the scene, parameters, film and
/// counters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Schedule {
    Any,
    /// Path state, queues and indirect dispatch: the wavefront's alone.
    Wavefront,
}

/// How many texel views a `split` row binds: its array's parts (a part is
/// at most 2^shift texels), then copies of the first. Eight parts of the
/// largest view lavapipe allows (2^27 texels) hold 16 GiB of 16-byte texels
/// and 4 GiB of 4-byte ones, above its 2 GiB of device memory.
pub const SCENE_VIEWS: u32 = 8;

/// One descriptor binding (set 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    pub binding: u32,
    /// The GLSL variable and the host's buffer name.
    pub name: &'static str,
    pub kind: Kind,
    /// The GLSL type: `T[]` for a runtime array of T, `T` for one value; ""
    /// for texel buffers.
    pub ty: &'static str,
    pub schedule: Schedule,
    /// Kernel features (`KernelFeatures::describe`'s names) whose code reads
    /// the binding; none: every variant reads it.
    pub needs: &'static [&'static str],
    /// What the elements hold, emitted beside the GLSL declaration.
    pub comment: &'static str,
    /// A texel buffer read through `SCENE_VIEWS` views of parts of its
    /// buffer (module doc); set by [`Binding::split`].
    pub split: bool,
}

const fn row(
    binding: u32,
    name: &'static str,
    kind: Kind,
    ty: &'static str,
    schedule: Schedule,
    needs: &'static [&'static str],
    comment: &'static str,
) -> Binding {
    Binding {
        binding,
        name,
        kind,
        ty,
        schedule,
        needs,
        comment,
        split: false,
    }
}

/// An RGBA32UI view of the storage row `of`.
const fn view(of: &'static str) -> Kind {
    Kind::View {
        of,
        format: TexelFormat::Rgba32Uint,
    }
}

use Kind::{ReadOnly, ReadWrite, Texels, Uniform};
use Schedule::{Any, Wavefront};
use TexelFormat::{R32Uint, Rgba32Uint};

/// Every binding, by binding number. Path state and shadow rays are
/// structures of arrays indexed by path slot (shadow ray index), 16 bytes per
/// element as commented, written as two 64-bit words.
#[rustfmt::skip]
pub const BINDINGS: &[Binding] = &[
    //  binding, name,                kind,                        GLSL type,             schedule,  needs (kernel features),     comment
    row(0,  "params",                     Uniform,                     "RenderParams",        Any,       &[],                         "everything uniform across a render"),
    // The scene, read through the `*_texels` views below.
    row(1,  "bvh_nodes",                  ReadOnly,                    "CwBvhNode[]",         Any,       &[],                         "root at 0"),
    row(2,  "tri_verts",                  ReadOnly,                    "TriangleVerts[]",     Any,       &[],                         "in BVH order"),
    row(3,  "tri_shading",                ReadOnly,                    "TriangleShading[]",   Any,       &[],                         "in BVH order"),
    row(4,  "materials",                  ReadOnly,                    "MaterialData[]",      Any,       &[],                         ""),
    row(5,  "emitters",                   ReadOnly,                    "Emitter[]",           Any,       &[],                         "emissive triangles, power cdf"),
    // Path state, read through the `*_texels` views after the lights.
    row(6,  "path_origin",                ReadWrite,                   "u64vec2[]",           Wavefront, &[],                         "xyz, w = previous BSDF pdf (0: no MIS)"),
    row(7,  "path_direction",             ReadWrite,                   "u64vec2[]",           Wavefront, &[],                         "xyz"),
    row(8,  "path_hit",                   ReadWrite,                   "u64vec2[]",           Wavefront, &[],                         "t bits, triangle, b1 bits, b2 bits"),
    row(9,  "path_throughput",            ReadWrite,                   "u64vec2[]",           Wavefront, &[],                         "rgb, w = eta_scale (product of eta^2 over refractions)"),
    row(10, "path_radiance",              ReadWrite,                   "u64vec2[]",           Wavefront, &[],                         "rgb"),
    row(11, "ray_queue",                  ReadWrite,                   "uint[]",              Wavefront, &[],                         "two queues of path slots (bounce parity), pool size each"),
    row(12, "shadow_origin",              ReadWrite,                   "u64vec2[]",           Wavefront, &[],                         "xyz, w = t_max"),
    row(13, "shadow_direction",           ReadWrite,                   "u64vec2[]",           Wavefront, &[],                         "xyz, w = path slot bits"),
    row(14, "shadow_contribution",        ReadWrite,                   "u64vec2[]",           Wavefront, &[],                         "rgb"),
    row(15, "counters",                   ReadWrite,                   "uint[]",              Any,       &[],                         "COUNTER_* slots"),
    row(16, "dispatch_args",              ReadWrite,                   "uint[]",              Wavefront, &[],                         "4 x (x, y, z) for vkCmdDispatchIndirect: extend and shade, shadow, shade_basic, shade (split)"),
    row(17, "film",                       ReadWrite,                   "FilmPixel[]",         Any,       &[],                         "one per pixel, row-major"),
    row(18, "bvh_node_texels",            view("bvh_nodes"),           "",                    Any,       &[],                         "5 texels per node").split(),
    row(19, "tri_vert_texels",            view("tri_verts"),           "",                    Any,       &[],                         "3 texels per triangle").split(),
    row(20, "tri_shading_texels",         view("tri_shading"),         "",                    Any,       &[],                         "3 texels per triangle").split(),
    row(21, "material_texels",            view("materials"),           "",                    Any,       &[],                         "MATERIAL_TEXELS per material"),
    row(22, "emitter_texels",             view("emitters"),            "",                    Any,       &[],                         "1 texel per emitter").split(),
    // Textures (textures.glsl); 16-byte dummies in untextured scenes.
    row(23, "textures",                   ReadOnly,                    "TextureInfo[]",       Any,       &["textures", "alpha-mask"], "the texture table"),
    row(24, "texture_texels",             Texels(R32Uint),             "",                    Any,       &["textures", "alpha-mask"], "the sRGB decode table (SRGB_TABLE_WORDS), then each image's texels: RGBA8, one per element, or grey at 1 byte (TEXTURE_GREY) or grey+alpha at 2 (TEXTURE_GREY_ALPHA)").split(),
    row(25, "tri_texcoords",              ReadOnly,                    "TriangleTexcoords[]", Any,       &["textures", "alpha-mask", "anisotropy"], "in BVH order; tangents also for anisotropy"),
    // Light sampling (lights.glsl; host side: packed/lights.rs).
    row(26, "light_params",               ReadOnly,                    "LightParams",         Any,       &[],                         "light selection, environment map shape"),
    row(27, "lights",                     ReadOnly,                    "Light[]",             Any,       &["analytic-lights"],        "spheres, then suns, then the rest"),
    row(28, "env_cdf",                    ReadOnly,                    "float[]",             Any,       &["environment-map"],        "marginal cdf over rows (env_height + 1), then each row's conditional cdf (env_width + 1)"),
    row(29, "env_radiance",               ReadOnly,                    "vec4[]",              Any,       &["environment-map"],        "rgb, row-major, row 0 at +Y"),
    // The path state again, for reading (path_state.glsl).
    row(30, "path_origin_texels",         view("path_origin"),         "",                    Wavefront, &[],                         ""),
    row(31, "path_direction_texels",      view("path_direction"),      "",                    Wavefront, &[],                         ""),
    row(32, "path_hit_texels",            view("path_hit"),            "",                    Wavefront, &[],                         ""),
    row(33, "path_throughput_texels",     view("path_throughput"),     "",                    Wavefront, &[],                         ""),
    row(34, "path_radiance_texels",       view("path_radiance"),       "",                    Wavefront, &[],                         ""),
    row(35, "shadow_origin_texels",       view("shadow_origin"),       "",                    Wavefront, &[],                         ""),
    row(36, "shadow_direction_texels",    view("shadow_direction"),    "",                    Wavefront, &[],                         ""),
    row(37, "shadow_contribution_texels", view("shadow_contribution"), "",                    Wavefront, &[],                         ""),
    // Auxiliary outputs (aov.glsl); 16-byte dummies unless recorded.
    row(38, "path_aov",                   ReadWrite,                   "vec4[]",              Wavefront, &["aov"],                    "2 per path: (albedo rgb, depth), (normal xyz, 1 while still open)"),
    row(39, "film_aov",                   ReadWrite,                   "AovPixel[]",          Any,       &["aov"],                    "one per pixel, row-major"),
    // KHR_materials_sheen (sheen.glsl; host side: packed/sheen_table.rs).
    row(40, "sheen_albedo_table",         ReadOnly,                    "float[]",             Any,       &["sheen"],                  "the sheen lobe's directional albedo, SHEEN_TABLE_SIZE^2"),
    // Motion over the shutter (motion.glsl; host side: packed/motion.rs); a 16-byte dummy in still scenes.
    row(41, "motion_texels",              Texels(Rgba32Uint),          "",                    Any,       &["motion"],                 "camera frames, then vertex positions, normals and tangents per time step"),
    // Shading split by material (SHADE_QUEUE_*): extend's sorted hits.
    row(42, "shade_queue",                ReadWrite,                   "uint[]",              Wavefront, &[],                         "path slots: the basic queue from the start, the full one from the end"),
    row(43, "tri_texcoord_texels",        view("tri_texcoords"),       "",                    Any,       &["textures", "alpha-mask", "anisotropy"], "6 texels per triangle").split(),
    // Two-level scenes (instances.glsl; host side: packed/instances.rs); a 16-byte dummy in one-level ones.
    row(44, "instances",                  ReadOnly,                    "Instance[]",          Any,       &["instances"],              "placements of the meshes' BVHs, in top-level BVH order"),
    row(45, "instance_texels",            view("instances"),           "",                    Any,       &["instances"],              "INSTANCE_TEXELS per instance"),
    // The light BVH (light_bvh.glsl; host side: packed/light_bvh.rs); 16-byte dummies without one.
    row(46, "light_tree",                 ReadOnly,                    "LightTreeNode[]",     Any,       &["light-tree"],             "root at 0; a node's children side by side"),
    row(47, "light_tree_texels",          view("light_tree"),          "",                    Any,       &["light-tree"],             "4 texels per node"),
    row(48, "light_trails",               ReadOnly,                    "uint[]",              Any,       &["light-tree"],             "each emitter's path from the root, then each analytic light's: bit k = the child taken at depth k"),
];

impl Binding {
    /// This row as a `split` one (module doc).
    pub const fn split(self) -> Binding {
        Binding {
            split: true,
            ..self
        }
    }

    /// How many descriptors the binding holds.
    pub const fn descriptor_count(&self) -> u32 {
        if self.split { SCENE_VIEWS } else { 1 }
    }

    /// Whether the buffer of this row is cut into parts, each viewed by a
    /// descriptor of a `split` view (the row itself or a view of it), and
    /// the format of those views.
    pub fn parts_format(&self) -> Option<TexelFormat> {
        match self.kind {
            Kind::Texels(format) if self.split => Some(format),
            Kind::ReadOnly | Kind::ReadWrite => views_of(self.name)
                .find(|v| v.split)
                .and_then(|v| v.texel_format()),
            _ => None,
        }
    }

    /// Whether the binding has a buffer of its own (views share another's).
    pub const fn owns_buffer(&self) -> bool {
        !matches!(self.kind, Kind::View { .. })
    }

    /// The format of the texel buffer view this binding takes, if any.
    pub const fn texel_format(&self) -> Option<TexelFormat> {
        match self.kind {
            Kind::Texels(format) | Kind::View { format, .. } => Some(format),
            _ => None,
        }
    }
}

/// The row named `name`: usable in a `const`, so a misspelt name fails to
/// compile.
pub const fn row_of(name: &str) -> &'static Binding {
    let mut i = 0;
    while i < BINDINGS.len() {
        if str_eq(BINDINGS[i].name, name) {
            return &BINDINGS[i];
        }
        i += 1;
    }
    panic!("no binding of that name in packed::bindings::BINDINGS")
}

/// The texel views of the buffer of storage row `name`.
pub fn views_of(name: &str) -> impl Iterator<Item = &'static Binding> + '_ {
    BINDINGS
        .iter()
        .filter(move |b| matches!(b.kind, Kind::View { of, .. } if of == name))
}

const fn str_eq(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packed::features::FEATURE_NAMES;

    #[test]
    fn binding_numbers_are_unique_and_ascending() {
        for pair in BINDINGS.windows(2) {
            assert!(
                pair[0].binding < pair[1].binding,
                "{} (binding {}) comes before {} (binding {})",
                pair[0].name,
                pair[0].binding,
                pair[1].name,
                pair[1].binding
            );
        }
    }

    #[test]
    fn names_are_unique() {
        for (i, b) in BINDINGS.iter().enumerate() {
            assert!(
                BINDINGS[..i].iter().all(|a| a.name != b.name),
                "two bindings named {}",
                b.name
            );
        }
    }

    #[test]
    fn views_view_storage_rows() {
        for b in BINDINGS {
            if let Kind::View { of, .. } = b.kind {
                let viewed = row_of(of);
                assert!(
                    matches!(viewed.kind, Kind::ReadOnly | Kind::ReadWrite),
                    "{} views {of}, which is not a storage buffer",
                    b.name
                );
                assert!(
                    viewed.ty.ends_with("[]"),
                    "{} views {of}, which is not an array",
                    b.name
                );
                assert_eq!(b.ty, "", "{}: a texel buffer has no GLSL type", b.name);
            } else if b.owns_buffer() && !matches!(b.kind, Kind::Texels(_)) {
                assert_ne!(b.ty, "", "{}: no GLSL type", b.name);
            }
        }
    }

    #[test]
    fn needs_name_kernel_features() {
        for b in BINDINGS {
            for need in b.needs {
                assert!(
                    FEATURE_NAMES.contains(need),
                    "{}: unknown feature '{need}'",
                    b.name
                );
            }
        }
    }

    #[test]
    fn a_view_is_used_by_the_schedules_of_its_buffer() {
        for b in BINDINGS {
            if let Kind::View { of, .. } = b.kind {
                assert!(
                    b.schedule == Schedule::Wavefront || row_of(of).schedule == Schedule::Any,
                    "{} serves more schedules than {of}",
                    b.name
                );
            }
        }
    }

    #[test]
    fn rows_are_found_by_name() {
        const FILM: &Binding = row_of("film");
        assert_eq!(FILM.kind, Kind::ReadWrite);
        let views: Vec<&str> = views_of("materials").map(|b| b.name).collect();
        assert_eq!(views, ["material_texels"]);
    }

    #[test]
    fn split_rows_are_texel_buffers_of_scene_arrays() {
        for b in BINDINGS.iter().filter(|b| b.split) {
            assert!(
                b.texel_format().is_some(),
                "{}: split but not texels",
                b.name
            );
            assert_eq!(b.descriptor_count(), SCENE_VIEWS, "{}", b.name);
        }
        assert_eq!(row_of("tri_verts").parts_format(), Some(Rgba32Uint));
        assert_eq!(row_of("texture_texels").parts_format(), Some(R32Uint));
        assert_eq!(row_of("materials").parts_format(), None);
        assert_eq!(row_of("path_origin").parts_format(), None);
        assert_eq!(row_of("material_texels").descriptor_count(), 1);
    }
}
