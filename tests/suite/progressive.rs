//! A render stopped between passes is a consistent image: every pixel has
//! the same sample count, the one reported, and the film is exactly what a
//! render asked for that many samples makes (same seed, same paths). Checked
//! on both back ends with an image size that does not divide the GPU's path
//! pool, so chunks would straddle pass boundaries if the driver let them.

use crate::common;

use common::*;
use vkpt::film::Film;
use vkpt::render::RenderSettings;
use vkpt::render::{PassControl, RenderResult};

/// Stops after the first pass and remembers its spp.
struct StopAfterFirstPass(Option<u32>);

impl PassControl for StopAfterFirstPass {
    fn after_pass(
        &mut self,
        spp: u32,
        _: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool> {
        self.0 = Some(spp);
        Ok(false)
    }
}

fn check(back_end: &str, stopped: RenderResult, control: StopAfterFirstPass, full: RenderResult) {
    let spp = control.0.expect("the renderer called the control");
    assert_eq!(stopped.spp, spp, "{back_end}: reported spp");
    assert!(spp < 200, "{back_end}: it did stop");
    let counts: Vec<f32> = stopped.film.pixels.iter().map(|p| p.mean[3]).collect();
    assert!(
        counts.iter().all(|&n| n == spp as f32),
        "{back_end}: pixel sample counts differ from {spp}: min {:?} max {:?}",
        counts.iter().copied().reduce(f32::min),
        counts.iter().copied().reduce(f32::max)
    );
    assert_eq!(full.spp, spp);
    let differing = pixels_differing(&stopped.film.to_image(), &full.film.to_image(), 1e-5);
    assert_eq!(
        differing, 0,
        "{back_end}: the stopped render differs from a {spp}-spp render"
    );
}

#[test]
fn a_stopped_render_is_a_whole_render_of_fewer_samples() {
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let settings = RenderSettings {
        width: 60,
        height: 50,
        spp: 200,
        seed: 9,
        ..Default::default()
    };
    let mut control = StopAfterFirstPass(None);
    let stopped =
        vkpt::cpu::render::render_progressive(&scene, &packed, &settings, &|_, _| {}, &mut control)
            .expect("CPU render");
    let asked = RenderSettings {
        spp: stopped.spp,
        ..settings.clone()
    };
    let full = vkpt::cpu::render::render(&scene, &packed, &asked, &|_, _| {}).expect("CPU");
    check("CPU", stopped, control, full);

    let Some(mut gpu) = gpu_renderer("a_stopped_render_is_a_whole_render_of_fewer_samples") else {
        return;
    };
    let mut control = StopAfterFirstPass(None);
    let stopped = gpu
        .render_progressive(&scene, &packed, &settings, &|_, _| {}, &mut control)
        .expect("GPU render");
    let asked = RenderSettings {
        spp: stopped.spp,
        ..settings
    };
    let full = gpu
        .render(&scene, &packed, &asked, &|_, _| {})
        .expect("GPU render");
    check("GPU", stopped, control, full);
}

/// What a back end reports through the progress callback: 0 first, when
/// tracing starts (the CLI's samples/s and time left are timed from it, so
/// they leave out kernel compilation), then samples done, never falling,
/// ending at the total.
fn check_progress(back_end: &str, calls: Vec<(u64, u64)>, total: u64) {
    assert_eq!(calls.first(), Some(&(0, total)), "{back_end}: {calls:?}");
    assert!(
        calls
            .windows(2)
            .all(|w| w[0].0 <= w[1].0 && w[1].1 == total),
        "{back_end}: {calls:?}"
    );
    assert_eq!(calls.last(), Some(&(total, total)), "{back_end}: {calls:?}");
    assert_eq!(
        calls.iter().filter(|c| c.0 == 0).count(),
        1,
        "{back_end}: {calls:?}"
    );
}

#[test]
fn progress_starts_at_zero_when_tracing_starts_and_ends_at_the_total() {
    let (scene, packed) = load("scenes/cornell-box.gltf");
    let settings = RenderSettings {
        width: 40,
        height: 30,
        spp: 3,
        ..Default::default()
    };
    let total = 40 * 30 * 3;
    let calls = std::sync::Mutex::new(Vec::new());
    let record = |done, total| calls.lock().expect("lock").push((done, total));
    vkpt::cpu::render::render(&scene, &packed, &settings, &record).expect("CPU render");
    check_progress(
        "CPU",
        std::mem::take(&mut *calls.lock().expect("lock")),
        total,
    );

    let Some(mut gpu) = gpu_renderer("progress") else {
        return;
    };
    gpu.render(&scene, &packed, &settings, &record)
        .expect("GPU render");
    check_progress(
        "GPU",
        std::mem::take(&mut *calls.lock().expect("lock")),
        total,
    );
}

/// Records each pass's end (spp so far) and says whether passes may grow.
struct RecordPasses {
    ends: Vec<u32>,
    may_grow: bool,
}

impl PassControl for RecordPasses {
    fn after_pass(
        &mut self,
        spp: u32,
        _: &mut dyn FnMut() -> anyhow::Result<Film>,
    ) -> anyhow::Result<bool> {
        self.ends.push(spp);
        Ok(true)
    }

    fn passes_may_grow(&self) -> bool {
        self.may_grow
    }
}

/// The CPU driver lengthens short passes where the control allows it and
/// keeps them one length where it does not (a time limit judges the next
/// pass by the last), with the same film either way.
#[test]
fn cpu_passes_grow_only_where_the_control_allows() {
    let (scene, packed) = load("scenes/cornell-box.gltf");
    // 64x64: a first pass of 4 spp, each a few ms, far under the 50 ms
    // below which passes double.
    let settings = RenderSettings {
        width: 64,
        height: 64,
        spp: 200,
        seed: 3,
        ..Default::default()
    };
    let render = |may_grow| {
        let mut control = RecordPasses {
            ends: Vec::new(),
            may_grow,
        };
        let result = vkpt::cpu::render::render_progressive(
            &scene,
            &packed,
            &settings,
            &|_, _| {},
            &mut control,
        )
        .expect("CPU render");
        (result, control.ends)
    };
    let lengths = |ends: &[u32]| -> Vec<u32> {
        std::iter::once(0)
            .chain(ends.iter().copied())
            .collect::<Vec<_>>()
            .windows(2)
            .map(|w| w[1] - w[0])
            .collect()
    };
    // The last pass may be cut short by the spp asked for.
    let (fixed, fixed_ends) = render(false);
    let fixed_lengths = lengths(&fixed_ends);
    let whole = &fixed_lengths[..fixed_lengths.len() - 1];
    assert!(
        whole.iter().all(|&l| l == fixed_lengths[0]),
        "passes changed length though the control said no: {fixed_lengths:?}"
    );
    let (grown, grown_ends) = render(true);
    let grown_lengths = lengths(&grown_ends);
    let whole = &grown_lengths[..grown_lengths.len() - 1];
    // Each pass as long as the last or twice as long (a pass over 50 ms
    // keeps its length), and at least one doubled.
    assert!(
        whole.windows(2).all(|w| w[1] == w[0] || w[1] == 2 * w[0])
            && whole.windows(2).any(|w| w[1] == 2 * w[0]),
        "short passes did not grow: {grown_lengths:?}"
    );
    assert_eq!(fixed.spp, 200);
    assert_eq!(grown.spp, 200);
    let differing = pixels_differing(&fixed.film.to_image(), &grown.film.to_image(), 0.0);
    assert_eq!(differing, 0, "pass lengths changed the film");
}
