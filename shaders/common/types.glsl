// GPU-visible structs: twins of src/layout.rs, same order and names.
// tests/suite/layout.rs checks sizes and offsets against the compiled SPIR-V.
#ifndef TYPES_GLSL
#define TYPES_GLSL

// Compressed wide BVH8 node, 80 bytes: see CwBvhNode in src/layout.rs for
// the encoding (byte arrays packed four to a word, little-endian).
struct CwBvhNode {        // 80 bytes
    vec3 p;
    uint e_imask;
    uint child_base_idx;
    uint primitive_base_idx;
    uvec2 child_meta;
    uvec2 qlo_x;
    uvec2 qhi_x;
    uvec2 qlo_y;
    uvec2 qhi_y;
    uvec2 qlo_z;
    uvec2 qhi_z;
};

struct TriangleVerts {    // 48 bytes
    vec3 v0;
    uint material;
    vec3 v1;
    uint alpha_mask;
    vec3 v2;
    uint shade_queue;       // SHADE_QUEUE_BASIC or _FULL, by material kind
};

struct TriangleShading {  // 48 bytes
    vec3 n0;
    float light_pmf;
    vec3 n1;
    float _pad1;
    vec3 n2;
    float _pad2;
};

struct MaterialData {     // 272 bytes
    vec3 base_color;
    uint kind;
    vec3 emission;
    uint double_sided;
    vec3 specular;
    float shininess;
    float ior;
    float metallic;
    float roughness;
    float transmission;
    vec3 specular_color;
    float specular_factor;
    vec3 attenuation;
    float thickness;
    float alpha;
    float alpha_cutoff;
    float normal_scale;
    uint base_color_texture;
    uint metallic_roughness_texture;
    uint normal_texture;
    uint emissive_texture;
    uint specular_texture;
    uint specular_color_texture;
    uint transmission_texture;
    uint _pad1;
    uint _pad2;
    float clearcoat;
    float clearcoat_roughness;
    float clearcoat_normal_scale;
    uint lobes;
    vec3 sheen_color;
    float sheen_roughness;
    float iridescence;
    float iridescence_ior;
    float iridescence_thickness_min;
    float iridescence_thickness_max;
    vec3 diffuse_transmission_color;
    float diffuse_transmission;
    float anisotropy_strength;
    float anisotropy_rotation;
    float dispersion;
    uint _pad3;
    uint clearcoat_texture;
    uint clearcoat_roughness_texture;
    uint clearcoat_normal_texture;
    uint sheen_color_texture;
    uint sheen_roughness_texture;
    uint iridescence_texture;
    uint iridescence_thickness_texture;
    uint anisotropy_texture;
    uint diffuse_transmission_texture;
    uint diffuse_transmission_color_texture;
    uint thickness_texture;
    uint _pad4;
};

struct TextureInfo {      // 48 bytes
    vec3 transform_s;
    uint offset;
    vec3 transform_t;
    uint flags;
    uint width;
    uint height;
    uint levels;
    uint _pad2;
};

struct TriangleTexcoords { // 96 bytes
    vec4 uv0_01;
    vec4 uv0_2_uv1_0;
    vec4 uv1_12;
    vec4 tangent0;
    vec4 tangent1;
    vec4 tangent2;
};

struct Emitter {          // 16 bytes
    uint triangle;
    float cdf;
    float pmf;
    float area;
};

struct Instance {         // 112 bytes
    vec4 to_world_x;
    vec4 to_world_y;
    vec4 to_world_z;
    vec4 to_object_x;
    vec4 to_object_y;
    vec4 to_object_z;
    uint root;
    uint id_base;
    uint first_triangle;
    uint flags;
};

struct RenderParams {     // 176 bytes
    vec3 cam_position;
    float tan_half_fov;
    vec3 cam_right;
    float aspect;
    vec3 cam_up;
    uint num_instances;
    vec3 cam_forward;
    float texture_spread;
    float lens_radius;
    float focus_distance;
    uint aperture_blades;
    float blade_rotation;
    uint projection;
    uint filter_kind;
    float filter_radius;
    uint motion_camera_base;
    vec3 environment;
    float env_select_prob;
    uint width;
    uint height;
    uint max_depth;
    uint seed;
    uint num_emitters;
    uint num_triangles;
    uint pool_size;
    uint rng_sampler;
    uint region_x;
    uint region_y;
    uint region_width;
    uint region_height;
    uint sample_offset;
    uint aov;
    uint motion_steps;
    uint motion_vertex_base;
};

struct Light {            // 80 bytes
    vec3 position;
    uint kind;
    vec3 direction;
    float range;
    vec3 emission;
    float radius;
    float cos_max;
    float one_minus_cos_max;
    float spot_scale;
    float spot_offset;
    float pmf;
    float cdf;
    float _pad1;
    float _pad2;
};

struct LightParams {      // 48 bytes
    uint num_lights;
    float tri_select_prob;
    uint env_width;
    uint env_height;
    float env_rot_cos;
    float env_rot_sin;
    uint env_hidden;
    uint env_sampling;
    uint num_spheres;
    uint num_suns;
    uint tree_nodes;
    uint _pad2;
};

struct LightTreeNode {    // 64 bytes
    vec3 centre;
    float power;
    vec3 axis;
    float cos_theta_o;
    float radius;
    float r2;
    float sin_theta_o;
    float cos_theta_e;
    uint child_or_light;
    uint flags;
    uint _pad1;
    uint _pad2;
};

struct PushConstants {    // 20 bytes
    uint pixel_start;
    uint sample_start;
    uint count;
    uint bounce;
    uint loop_budget;
};

struct FilmPixel {        // 32 bytes
    vec4 mean;
    vec4 m2;
};

struct AovPixel {         // 48 bytes
    vec4 albedo;          // rgb: mean albedo, w: samples
    vec4 normal;          // xyz: mean shading normal, w: unused
    vec4 depth;           // x: mean depth of the samples that hit, y: those samples, zw: unused
};

#endif
