//! Which optional features a render's kernels compile in.
//!
//! Every feature is a specialization constant (`shaders/common/features.glsl`,
//! ids `SPEC_*` in `constants.rs`) guarding the code only that feature needs:
//! a scene without textures gets kernels without texture fetches, and so on.
//! The CPU reference ignores this: leaving out code a scene never reaches
//! cannot change the estimate, which `tests/suite/specialization.rs` checks pixel
//! for pixel against the all-features kernels.

use crate::constants::*;
use crate::packed::PackedScene;
use crate::packed::layout::RenderParams;

/// How many specialization constants there are: the bools, the texture
/// slot mask, the shading queue, the scene arrays' view shift.
pub const SPEC_VALUES: usize = SPEC_COUNT as usize + 3;

/// Each feature's name as users (and `packed::bindings`) write it, by `SPEC_*` id.
pub const FEATURE_NAMES: [&str; SPEC_COUNT as usize] = [
    "textures",
    "alpha-mask",
    "phong",
    "gltf-material",
    "analytic-lights",
    "environment-map",
    "thin-lens",
    "filter-bisection",
    "sobol",
    "aov",
    "clearcoat",
    "sheen",
    "iridescence",
    "anisotropy",
    "diffuse-transmission",
    "dispersion",
    "motion",
    "instances",
    "light-tree",
];

/// One flag per specialization constant, in `SPEC_*` order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct KernelFeatures {
    pub textures: bool,
    /// Alpha MASK or BLEND materials (alpha tests during traversal).
    pub alpha_mask: bool,
    pub phong: bool,
    /// glTF metallic-roughness, its transmission and the microfacet lobes.
    pub gltf_material: bool,
    pub analytic_lights: bool,
    pub environment_map: bool,
    pub thin_lens: bool,
    /// Gaussian and Blackman-Harris pixel filters (sampled by bisection).
    pub filter_bisection: bool,
    pub sobol: bool,
    /// Auxiliary outputs (albedo, normal, depth; `aov.glsl`).
    pub aov: bool,
    /// The glTF PBR extension lobes (`LOBE_*`): each only when a material
    /// of the scene has it.
    pub clearcoat: bool,
    pub sheen: bool,
    pub iridescence: bool,
    pub anisotropy: bool,
    pub diffuse_transmission: bool,
    pub dispersion: bool,
    /// Geometry or cameras that move while the shutter is open: every
    /// path has its own time (`motion.glsl`).
    pub motion: bool,
    /// A two-level scene: rays enter the meshes' BVHs through instances
    /// (`instances.glsl`).
    pub instances: bool,
    /// Light selection by the light BVH (`PackedScene::light_tree`).
    pub light_tree: bool,
    /// The texture slots any material fills (`TEXTURE_SLOT_*`, the u32
    /// constant `SPEC_TEXTURE_SLOTS`): on lavapipe every slot compiled in
    /// costs its texture fetches on every hit, used or not.
    pub texture_slots: u32,
    /// Shading split by material (`SPEC_SHADE_QUEUE`): extend sorts hits
    /// into a basic and a full queue, each shaded by a kernel of its own
    /// (`basic_shade`). Only where the scene has triangles of both kinds.
    pub split_shade: bool,
    /// Not a feature but a fact of the device: log2 of the texels per part
    /// of the split scene arrays (`SPEC_SCENE_VIEW_SHIFT`,
    /// `packed::bindings`), 0 where each array is one part. Set by the
    /// Vulkan back end from the device's limits (`of` leaves it 0).
    pub scene_view_shift: u32,
}

/// The glTF PBR extension lobes `shade_basic` leaves out (dispersion stays:
/// see `basic_shade`).
const BASIC_DROPS_LOBES: u32 =
    LOBE_CLEARCOAT | LOBE_SHEEN | LOBE_IRIDESCENCE | LOBE_ANISOTROPY | LOBE_DIFFUSE_TRANSMISSION;

/// Whether the basic shading queue of a scene with these materials keeps
/// the glTF BSDF. Where a glTF material has a lobe the basic kernel leaves
/// out, it drops those lobes (the costliest code) and takes the plain glTF
/// materials too; elsewhere it drops the glTF BSDF and takes Lambert and
/// mirror materials only.
pub fn basic_keeps_gltf(materials: &[crate::packed::layout::MaterialData]) -> bool {
    materials
        .iter()
        .any(|m| m.kind == MATERIAL_GLTF && m.lobes & BASIC_DROPS_LOBES != 0)
}

/// The shading queue (`SHADE_QUEUE_BASIC` or `_FULL`) of hits on material
/// `m`: basic where `shade_basic` shades it exactly as the full kernel
/// does, never reaching the code it leaves out (Lambert and mirror
/// materials; with `keeps_gltf`, `basic_keeps_gltf`, also glTF materials
/// without the lobes it drops).
pub fn shade_queue_of(m: &crate::packed::layout::MaterialData, keeps_gltf: bool) -> u32 {
    match m.kind {
        MATERIAL_LAMBERT | MATERIAL_MIRROR => SHADE_QUEUE_BASIC,
        MATERIAL_GLTF if keeps_gltf && m.lobes & BASIC_DROPS_LOBES == 0 => SHADE_QUEUE_BASIC,
        _ => SHADE_QUEUE_FULL,
    }
}

/// The `TEXTURE_SLOT_*` bit of each `MaterialData` texture slot.
fn texture_slots_of(m: &crate::packed::layout::MaterialData) -> u32 {
    [
        (m.base_color_texture, TEXTURE_SLOT_BASE_COLOR),
        (
            m.metallic_roughness_texture,
            TEXTURE_SLOT_METALLIC_ROUGHNESS,
        ),
        (m.emissive_texture, TEXTURE_SLOT_EMISSIVE),
        (m.specular_texture, TEXTURE_SLOT_SPECULAR),
        (m.specular_color_texture, TEXTURE_SLOT_SPECULAR_COLOR),
        (m.transmission_texture, TEXTURE_SLOT_TRANSMISSION),
        (m.clearcoat_texture, TEXTURE_SLOT_CLEARCOAT),
        (
            m.clearcoat_roughness_texture,
            TEXTURE_SLOT_CLEARCOAT_ROUGHNESS,
        ),
        (m.anisotropy_texture, TEXTURE_SLOT_ANISOTROPY),
        (m.sheen_color_texture, TEXTURE_SLOT_SHEEN_COLOR),
        (m.sheen_roughness_texture, TEXTURE_SLOT_SHEEN_ROUGHNESS),
        (m.iridescence_texture, TEXTURE_SLOT_IRIDESCENCE),
        (
            m.iridescence_thickness_texture,
            TEXTURE_SLOT_IRIDESCENCE_THICKNESS,
        ),
        (
            m.diffuse_transmission_texture,
            TEXTURE_SLOT_DIFFUSE_TRANSMISSION,
        ),
        (
            m.diffuse_transmission_color_texture,
            TEXTURE_SLOT_DIFFUSE_TRANSMISSION_COLOR,
        ),
        (m.thickness_texture, TEXTURE_SLOT_THICKNESS),
        (m.normal_texture, TEXTURE_SLOT_NORMAL),
        (m.clearcoat_normal_texture, TEXTURE_SLOT_CLEARCOAT_NORMAL),
    ]
    .iter()
    .filter(|(t, _)| *t != NO_TEXTURE)
    .fold(0, |mask, (_, bit)| mask | bit)
}

impl KernelFeatures {
    /// Every feature compiled in: the kernels that can render any scene.
    pub const ALL: KernelFeatures = KernelFeatures {
        textures: true,
        alpha_mask: true,
        phong: true,
        gltf_material: true,
        analytic_lights: true,
        environment_map: true,
        thin_lens: true,
        filter_bisection: true,
        sobol: true,
        aov: true,
        clearcoat: true,
        sheen: true,
        iridescence: true,
        anisotropy: true,
        diffuse_transmission: true,
        dispersion: true,
        motion: true,
        instances: true,
        light_tree: true,
        texture_slots: TEXTURE_SLOTS_ALL,
        split_shade: false,
        scene_view_shift: 0,
    };

    /// What this scene and these render parameters use.
    pub fn of(packed: &PackedScene, params: &RenderParams) -> KernelFeatures {
        let kinds = |k: u32| packed.materials.iter().any(|m| m.kind == k);
        let lobe = |bit: u32| {
            packed
                .materials
                .iter()
                .any(|m| m.kind == MATERIAL_GLTF && m.lobes & bit != 0)
        };
        KernelFeatures {
            textures: !packed.textures.textures.is_empty(),
            alpha_mask: packed
                .materials
                .iter()
                .any(|m| m.alpha_cutoff != ALPHA_OPAQUE),
            phong: kinds(MATERIAL_PHONG),
            gltf_material: kinds(MATERIAL_GLTF),
            analytic_lights: packed.light_params.num_lights > 0,
            environment_map: packed.light_params.env_width > 0,
            thin_lens: params.lens_radius > 0.0,
            filter_bisection: params.filter_kind == FILTER_GAUSSIAN
                || params.filter_kind == FILTER_BLACKMAN_HARRIS,
            sobol: params.rng_sampler == SAMPLER_SOBOL,
            aov: params.aov != 0,
            clearcoat: lobe(LOBE_CLEARCOAT),
            sheen: lobe(LOBE_SHEEN),
            iridescence: lobe(LOBE_IRIDESCENCE),
            anisotropy: lobe(LOBE_ANISOTROPY),
            diffuse_transmission: lobe(LOBE_DIFFUSE_TRANSMISSION),
            dispersion: lobe(LOBE_DISPERSION),
            motion: packed.motion.is_some(),
            instances: !packed.instances.is_empty(),
            light_tree: packed.light_params.tree_nodes > 0,
            texture_slots: packed
                .materials
                .iter()
                .map(texture_slots_of)
                .fold(0, |a, b| a | b),
            split_shade: [SHADE_QUEUE_BASIC, SHADE_QUEUE_FULL]
                .iter()
                .all(|&q| packed.tri_verts.iter().any(|t| t.shade_queue == q)),
            scene_view_shift: 0,
        }
    }

    /// The specialization constant values, indexed by `SPEC_*` id: the
    /// bools, then the texture-slot mask and the shading queue (every
    /// kernel but `shade_basic`'s).
    pub fn values(&self) -> [u32; SPEC_VALUES] {
        let mut v = [0u32; SPEC_VALUES];
        for (id, on) in self.flags() {
            v[id as usize] = on as u32;
        }
        v[SPEC_TEXTURE_SLOTS as usize] = self.texture_slots;
        v[SPEC_SHADE_QUEUE as usize] = if self.split_shade {
            SHADE_QUEUE_FULL
        } else {
            SHADE_QUEUE_NONE
        };
        v[SPEC_SCENE_VIEW_SHIFT as usize] = self.scene_view_shift;
        v
    }

    /// The constants of `shade_basic`, the kernel of the basic shading
    /// queue: these features without Phong and the lobes of
    /// `BASIC_DROPS_LOBES`, and without glTF materials unless one of those
    /// lobes is on (`basic_keeps_gltf`, read from the flags). Texture slots
    /// stay: a light sample reads its emitter's emissive texture whatever
    /// the material it leaves from. Dispersion stays too: a path that left
    /// dispersive glass carries its colour channel on to the walls it
    /// lights.
    pub fn basic_shade(&self) -> [u32; SPEC_VALUES] {
        let without_lobes = KernelFeatures {
            clearcoat: false,
            sheen: false,
            iridescence: false,
            anisotropy: false,
            diffuse_transmission: false,
            ..*self
        };
        let keeps_gltf = without_lobes != *self;
        let basic = KernelFeatures {
            phong: false,
            gltf_material: self.gltf_material && keeps_gltf,
            ..without_lobes
        };
        let mut v = basic.values();
        v[SPEC_SHADE_QUEUE as usize] = SHADE_QUEUE_BASIC;
        v
    }

    fn flags(&self) -> [(u32, bool); SPEC_COUNT as usize] {
        [
            (SPEC_TEXTURES, self.textures),
            (SPEC_ALPHA_MASK, self.alpha_mask),
            (SPEC_PHONG, self.phong),
            (SPEC_GLTF_MATERIAL, self.gltf_material),
            (SPEC_ANALYTIC_LIGHTS, self.analytic_lights),
            (SPEC_ENVIRONMENT_MAP, self.environment_map),
            (SPEC_THIN_LENS, self.thin_lens),
            (SPEC_FILTER_BISECTION, self.filter_bisection),
            (SPEC_SOBOL, self.sobol),
            (SPEC_AOV, self.aov),
            (SPEC_CLEARCOAT, self.clearcoat),
            (SPEC_SHEEN, self.sheen),
            (SPEC_IRIDESCENCE, self.iridescence),
            (SPEC_ANISOTROPY, self.anisotropy),
            (SPEC_DIFFUSE_TRANSMISSION, self.diffuse_transmission),
            (SPEC_DISPERSION, self.dispersion),
            (SPEC_MOTION, self.motion),
            (SPEC_INSTANCES, self.instances),
            (SPEC_LIGHT_TREE, self.light_tree),
        ]
    }

    /// "textures, gltf-material, sobol" or "minimal" for the summary line.
    pub fn describe(&self) -> String {
        let split = match self.scene_view_shift {
            0 => String::new(),
            shift => format!("; scene arrays split into parts of 2^{shift} texels"),
        };
        if self.scene_view_shift != 0 {
            let unsplit = KernelFeatures {
                scene_view_shift: 0,
                ..*self
            };
            return unsplit.describe() + &split;
        }
        if *self == KernelFeatures::ALL {
            return "all features".to_string();
        }
        let mut on: Vec<&str> = self
            .flags()
            .iter()
            .filter(|(_, on)| *on)
            .map(|(id, _)| FEATURE_NAMES[*id as usize])
            .collect();
        if self.split_shade {
            on.push("split-shade");
        }
        if on.is_empty() {
            "minimal (Lambert, mirror, emissive triangles, uniform environment)".to_string()
        } else {
            on.join(", ")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_spec_id_is_listed_once() {
        let mut seen = [false; SPEC_COUNT as usize];
        for (id, _) in KernelFeatures::ALL.flags() {
            assert!(!seen[id as usize], "SPEC id {id} listed twice");
            seen[id as usize] = true;
        }
        assert!(seen.iter().all(|s| *s));
        let values = KernelFeatures::ALL.values();
        assert!(values[..SPEC_COUNT as usize].iter().all(|v| *v == 1));
        assert_eq!(values[SPEC_TEXTURE_SLOTS as usize], TEXTURE_SLOTS_ALL);
        assert_eq!(values[SPEC_SHADE_QUEUE as usize], SHADE_QUEUE_NONE);
        assert_eq!(values[SPEC_SCENE_VIEW_SHIFT as usize], 0);
    }
}
