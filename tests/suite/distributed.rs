//! A render split by sample ranges or regions, rendered apart and merged
//! (`vkpt::film::merge`), is the render made in one piece: sample ranges
//! merge into it within float rounding, regions assemble into it bit for
//! bit, and a stopped render resumed with the rest of its range merges into
//! the uninterrupted one. Checked on both back ends, through real EXR files
//! with their headers. (`tests/suite/merge_cli.rs` checks the command line.)

use crate::common;

use common::*;
use std::ops::Range;
use std::path::Path;
use vkpt::film::Film;
use vkpt::film::merge::merge_files;
use vkpt::image::metrics::closeness;
use vkpt::image::{Image, Region, write_image_with_header};
use vkpt::packed::PackedScene;
use vkpt::render::header::render_header;
use vkpt::render::{PassControl, RenderResult, RenderSettings};
use vkpt::scene::Scene;

/// Float rounding in merging (f64) and in each render's f32 running mean:
/// measured at most 4e-7 here; a wrong sample anywhere moves a pixel by
/// its noise, percents.
const ROUNDING: f64 = 1e-5;

fn settings(spp: u32) -> RenderSettings {
    RenderSettings {
        width: 40,
        height: 30,
        spp,
        seed: 5,
        ..Default::default()
    }
}

/// One back end: the CPU reference or a Vulkan renderer.
enum Back {
    Cpu,
    Gpu(Box<Gpu>),
}

impl Back {
    fn name(&self) -> &'static str {
        match self {
            Back::Cpu => "CPU",
            Back::Gpu(_) => "GPU",
        }
    }

    fn render(
        &mut self,
        scene: &Scene,
        packed: &PackedScene,
        settings: &RenderSettings,
        control: &mut dyn PassControl,
    ) -> RenderResult {
        let result = match self {
            Back::Cpu => {
                vkpt::cpu::render::render_progressive(scene, packed, settings, &|_, _| {}, control)
            }
            Back::Gpu(gpu) => gpu.render_progressive(scene, packed, settings, &|_, _| {}, control),
        }
        .expect("render succeeds");
        assert_eq!(result.nonfinite_samples, 0);
        result
    }
}

/// The CPU back end, and the Vulkan one where there is a device.
fn back_ends(test: &str) -> Vec<Back> {
    let mut v = vec![Back::Cpu];
    v.extend(gpu_renderer(test).map(|g| Back::Gpu(Box::new(g))));
    v
}

/// Renders `settings` and writes it, with its header, to `path`.
fn render_part(
    back: &mut Back,
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    control: &mut dyn PassControl,
    path: &Path,
) -> RenderResult {
    let result = back.render(scene, packed, settings, control);
    let header =
        render_header(scene, packed, settings, result.spp, &result.device_name).expect("header");
    write_image_with_header(
        path,
        &result.film.to_image(),
        &Default::default(),
        Some(&header),
    )
    .expect("part written");
    result
}

/// Merged against whole: same sample counts, means within `ROUNDING`, and
/// the variance of the mean within float rounding too.
fn assert_same_render(what: &str, merged: &Image, whole: &Image) {
    let c = closeness(merged, whole, ROUNDING).expect("same size");
    println!(
        "{what}: {} of {} pixels beyond {ROUNDING:e}; largest |a - b| / (1 + |b|) {:.2e} at {:?}",
        c.differing,
        whole.mean.len(),
        c.largest,
        c.at
    );
    assert_eq!(c.counts_differing, 0, "{what}: sample counts differ");
    assert_eq!(
        c.differing, 0,
        "{what}: the merged image is not the whole render"
    );
    let (mv, wv) = (
        merged.variance.as_ref().unwrap(),
        whole.variance.as_ref().unwrap(),
    );
    let worst = mv
        .iter()
        .zip(wv)
        .flat_map(|(a, b)| (0..3).map(move |k| (a[k] as f64 - b[k] as f64).abs() / b[k] as f64))
        .fold(0.0f64, f64::max);
    println!("{what}: largest relative difference of the variance {worst:.2e}");
    assert!(worst < 1e-4, "{what}: variance differs by {worst:e}");
}

#[test]
fn four_sample_ranges_merge_into_the_full_render() {
    let test = "four_sample_ranges_merge_into_the_full_render";
    let (scene, packed) = load("scenes/cornell-box.gltf");
    // Uneven ranges: a one-sample part, and ends that are not powers of two
    // (Sobol's stratification is by powers of two).
    let ranges: [Range<u32>; 4] = [0..5, 5..16, 16..17, 17..32];
    for mut back in back_ends(test) {
        let dir = common::output_dir(&format!("distributed/{test}")).join(back.name());
        std::fs::create_dir_all(&dir).unwrap();
        let mut paths = Vec::new();
        for (i, r) in ranges.iter().enumerate() {
            let s = RenderSettings {
                first_sample: r.start,
                spp: r.len() as u32,
                ..settings(0)
            };
            let path = dir.join(format!("part-{i}.exr"));
            render_part(
                &mut back,
                &scene,
                &packed,
                &s,
                &mut vkpt::render::RenderAll,
                &path,
            );
            paths.push(path);
        }
        let merged = merge_files(&paths, false, Some(0..32)).expect("the parts merge");
        assert_eq!(merged.header.samples, 0..32);
        let whole = back.render(&scene, &packed, &settings(32), &mut vkpt::render::RenderAll);
        assert_same_render(back.name(), &merged.image, &whole.film.to_image());
    }
}

#[test]
fn four_regions_assemble_into_the_full_image_exactly() {
    let test = "four_regions_assemble_into_the_full_image_exactly";
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let regions =
        ["0,0,13,30", "13,0,40,7", "13,7,27,30", "27,7,40,30"].map(|r| Region::parse(r).unwrap());
    for mut back in back_ends(test) {
        let dir = common::output_dir(&format!("distributed/{test}")).join(back.name());
        std::fs::create_dir_all(&dir).unwrap();
        let mut paths = Vec::new();
        for (i, r) in regions.iter().enumerate() {
            let s = RenderSettings {
                region: Some(*r),
                ..settings(8)
            };
            let path = dir.join(format!("region-{i}.exr"));
            let part = render_part(
                &mut back,
                &scene,
                &packed,
                &s,
                &mut vkpt::render::RenderAll,
                &path,
            );
            assert_eq!((part.film.width, part.film.height), (r.width(), r.height()));
            paths.push(path);
        }
        let merged = merge_files(&paths, false, None).expect("the regions assemble");
        let whole = back
            .render(&scene, &packed, &settings(8), &mut vkpt::render::RenderAll)
            .film
            .to_image();
        let differing = merged
            .image
            .mean
            .iter()
            .zip(&whole.mean)
            .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
            .count();
        println!(
            "{}: {differing} of {} pixels differ",
            back.name(),
            whole.mean.len()
        );
        assert_eq!(
            differing,
            0,
            "{}: regions do not assemble exactly",
            back.name()
        );
        assert_eq!(merged.image.variance, whole.variance, "{}", back.name());
        assert_eq!(merged.image.samples, whole.samples, "{}", back.name());
    }
}

/// Stops after the first pass, as a time limit or Ctrl-C would.
struct StopAfterFirstPass;

impl PassControl for StopAfterFirstPass {
    fn after_pass(
        &mut self,
        _: u32,
        _: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool> {
        Ok(false)
    }
}

#[test]
fn a_resumed_render_equals_the_uninterrupted_one() {
    let test = "a_resumed_render_equals_the_uninterrupted_one";
    let (scene, packed) = load("scenes/cornell-box.gltf");
    for mut back in back_ends(test) {
        let dir = common::output_dir(&format!("distributed/{test}")).join(back.name());
        std::fs::create_dir_all(&dir).unwrap();
        // 64x64 pixels: a GPU pass (its path pool) is 64 spp on lavapipe,
        // a CPU pass 4 spp; 96 spp stops either before the end.
        let asked = RenderSettings {
            width: 64,
            height: 64,
            ..settings(96)
        };
        let first = dir.join("stopped.exr");
        let stopped = render_part(
            &mut back,
            &scene,
            &packed,
            &asked,
            &mut StopAfterFirstPass,
            &first,
        );
        let k = stopped.spp;
        assert!(k < 96, "{}: the render stopped at {k}", back.name());
        let rest = RenderSettings {
            first_sample: k,
            spp: 96 - k,
            ..asked.clone()
        };
        let second = dir.join("rest.exr");
        render_part(
            &mut back,
            &scene,
            &packed,
            &rest,
            &mut vkpt::render::RenderAll,
            &second,
        );
        let merged = merge_files(&[first, second], false, Some(0..96)).expect("merges");
        let whole = back.render(&scene, &packed, &asked, &mut vkpt::render::RenderAll);
        let what = format!("{} stopped at {k} spp, resumed to 96", back.name());
        assert_same_render(&what, &merged.image, &whole.film.to_image());
    }
}
