//! vkpt: a physically based path tracer on Vulkan compute, with a CPU
//! reference that implements the same estimator.
//!
//! ```no_run
//! use vkpt::{render::{render, DeviceChoice, RenderSettings}, packed::PackedScene, scene::Scene};
//! let scene = Scene::load("scenes/cornell-box.gltf".as_ref())?;
//! let packed = PackedScene::new(&scene)?;
//! let settings = RenderSettings { width: 128, height: 128, spp: 4, ..Default::default() };
//! let result = render(&scene, &packed, &settings, DeviceChoice::Auto, &|_, _| {})?;
//! let image = result.film.to_image();
//! vkpt::image::write_image("cornell.exr".as_ref(), &image, &Default::default())?;
//! # Ok::<(), anyhow::Error>(())
//! ```

// `!(x > 0.0)` is deliberate throughout: unlike `x <= 0.0` it is true for NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

// Layers, each importing only from those listed before it (checked by
// tests/suite/layering.rs): cache, constants, huge_pages and splitmix are
// leaves every layer may read.
pub mod bench;
pub mod cache;
pub mod constants;
pub mod cpu;
pub mod film;
pub mod gpu;
pub mod huge_pages;
pub mod image;
pub mod packed;
pub mod render;
pub mod scene;
pub mod splitmix;
