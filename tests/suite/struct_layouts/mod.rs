//! Every GPU-visible struct of `src/packed/layout.rs` as Rust lays it out:
//! field names and `offset_of!`, shared by `tests/suite/layout.rs` (against the
//! SPIR-V) and `tests/suite/texel_reads.rs` (against the kernels' texel reads).

use std::mem::{offset_of, size_of};
use vkpt::packed::layout::{
    AovPixel, CwBvhNode, Emitter, FilmPixel, Instance, Light, LightParams, MaterialData,
    PushConstants, RenderParams, TextureInfo, TriangleShading, TriangleTexcoords, TriangleVerts,
};

/// A struct as Rust lays it out.
pub struct Expected {
    pub name: &'static str,
    pub size: usize,
    /// Field names and `offset_of!`, in declaration order.
    pub fields: &'static [(&'static str, usize)],
}

macro_rules! expected {
    ($ty:ident { $($field:ident),* $(,)? }) => {
        Expected {
            name: stringify!($ty),
            size: size_of::<$ty>(),
            fields: &[$((stringify!($field), offset_of!($ty, $field))),*],
        }
    };
}

pub fn rust_layouts() -> Vec<Expected> {
    vec![
        expected!(CwBvhNode {
            p,
            e_imask,
            child_base_idx,
            primitive_base_idx,
            child_meta,
            qlo_x,
            qhi_x,
            qlo_y,
            qhi_y,
            qlo_z,
            qhi_z,
        }),
        expected!(TriangleVerts {
            v0,
            material,
            v1,
            alpha_mask,
            v2,
            shade_queue
        }),
        expected!(TextureInfo {
            transform_s,
            offset,
            transform_t,
            flags,
            width,
            height,
            levels,
            _pad2
        }),
        expected!(TriangleTexcoords {
            uv0_01,
            uv0_2_uv1_0,
            uv1_12,
            tangent0,
            tangent1,
            tangent2
        }),
        expected!(TriangleShading {
            n0,
            light_pmf,
            n1,
            _pad1,
            n2,
            _pad2
        }),
        expected!(MaterialData {
            base_color,
            kind,
            emission,
            double_sided,
            specular,
            shininess,
            ior,
            metallic,
            roughness,
            transmission,
            specular_color,
            specular_factor,
            attenuation,
            thickness,
            alpha,
            alpha_cutoff,
            normal_scale,
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            emissive_texture,
            specular_texture,
            specular_color_texture,
            transmission_texture,
            _pad1,
            _pad2,
            clearcoat,
            clearcoat_roughness,
            clearcoat_normal_scale,
            lobes,
            sheen_color,
            sheen_roughness,
            iridescence,
            iridescence_ior,
            iridescence_thickness_min,
            iridescence_thickness_max,
            diffuse_transmission_color,
            diffuse_transmission,
            anisotropy_strength,
            anisotropy_rotation,
            dispersion,
            _pad3,
            clearcoat_texture,
            clearcoat_roughness_texture,
            clearcoat_normal_texture,
            sheen_color_texture,
            sheen_roughness_texture,
            iridescence_texture,
            iridescence_thickness_texture,
            anisotropy_texture,
            diffuse_transmission_texture,
            diffuse_transmission_color_texture,
            thickness_texture,
            _pad4
        }),
        expected!(Emitter {
            triangle,
            cdf,
            pmf,
            area
        }),
        expected!(Instance {
            to_world_x,
            to_world_y,
            to_world_z,
            to_object_x,
            to_object_y,
            to_object_z,
            root,
            id_base,
            first_triangle,
            flags
        }),
        expected!(RenderParams {
            cam_position,
            tan_half_fov,
            cam_right,
            aspect,
            cam_up,
            num_instances,
            cam_forward,
            texture_spread,
            lens_radius,
            focus_distance,
            aperture_blades,
            blade_rotation,
            projection,
            filter_kind,
            filter_radius,
            motion_camera_base,
            environment,
            env_select_prob,
            width,
            height,
            max_depth,
            seed,
            num_emitters,
            num_triangles,
            pool_size,
            rng_sampler,
            region_x,
            region_y,
            region_width,
            region_height,
            sample_offset,
            aov,
            motion_steps,
            motion_vertex_base,
        }),
        expected!(Light {
            position,
            kind,
            direction,
            range,
            emission,
            radius,
            cos_max,
            one_minus_cos_max,
            spot_scale,
            spot_offset,
            pmf,
            cdf,
            _pad1,
            _pad2,
        }),
        expected!(LightParams {
            num_lights,
            tri_select_prob,
            env_width,
            env_height,
            env_rot_cos,
            env_rot_sin,
            env_hidden,
            env_sampling,
            num_spheres,
            num_suns,
            _pad1,
            _pad2,
        }),
        expected!(PushConstants {
            pixel_start,
            sample_start,
            count,
            bounce,
            loop_budget
        }),
        expected!(FilmPixel { mean, m2 }),
        expected!(AovPixel {
            albedo,
            normal,
            depth
        }),
    ]
}
