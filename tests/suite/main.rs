//! vkpt's integration tests, one binary of modules (one link of the
//! library instead of one per suite). Each module is a suite; run one with
//! `cargo test --release --test suite <module>::`.

mod common;
mod struct_layouts;

mod animation;
mod aov;
mod bad_input;
mod camera_gpu_vs_cpu;
mod camera_loading;
mod cli;
mod compare_without_variance;
mod cpu_lanes;
mod denoise;
mod distributed;
mod docs;
mod furnace;
mod gltf_compressed;
mod gltf_samples;
mod golden_pixels;
mod gpu_vs_cpu;
mod hard_cases;
mod instancing;
mod layering;
mod layout;
mod light_bvh;
mod lights;
mod loop_count;
mod merge_cli;
mod motion_blur;
mod photometric_stereo;
mod progressive;
mod sampler;
mod scene_loading;
mod schedules;
mod sensor;
mod sequence;
mod specialization;
mod texel_reads;
mod textures;
mod thin_lens;
