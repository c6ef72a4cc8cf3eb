//! lavapipe as one Vulkan device per CPU core, each with a single thread.
//!
//! lavapipe runs a dispatch's workgroups on a pool of threads, one per core,
//! that take them in turn, so the state a path's last kernel wrote on one
//! core is read by the next kernel on either: the cache lines of the path
//! state cross between the cores at every bounce. How much that costs
//! depends on where the host puts the virtual CPUs: on the 2-core machines a
//! cache line's round trip between the cores takes 50-70 ns or, from one
//! run to the next, 300-380 ns, and then the Cornell box's `shade` kernel
//! took 1.6x as long (docs/design-record.md, "lavapipe as one device per
//! core", has the figures).
//!
//! So where the Vulkan device is lavapipe, vkpt opens one device per core,
//! each with one thread (`LP_NUM_THREADS=1`, set by `configure_process`
//! when the program starts). Every
//! pass is split into contiguous sample ranges, one per device; the devices
//! render them side by side, each path on one core from start to end, and
//! their films are merged with Chan's parallel update (`Film::merge`, as for
//! split renders). The paths are those a single device traces (a path's
//! random numbers depend on its pixel and sample index only).

use super::{GpuRenderer, Upload};
use crate::film::Film;
use crate::film::passes::{PassControl, Progress, RenderAll, RenderResult, pass_spp};
use crate::packed::PackedScene;
use crate::packed::settings::RenderSettings;
use crate::scene::Scene;
use anyhow::Context as _;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// How many lavapipe devices render; set by `configure_process` (the user
/// may set it: 1 keeps one device with lavapipe's own thread pool).
pub const DEVICES_VAR: &str = "VKPT_LAVAPIPE_DEVICES";

/// lavapipe's own setting for its number of threads, read when a Vulkan
/// instance enumerates the device.
const LAVAPIPE_THREADS_VAR: &str = "LP_NUM_THREADS";

/// Devices beyond this many cost memory (a path pool each) for little.
const MAX_DEVICES: usize = 16;

/// Sets up the environment for one lavapipe device per core: unless the
/// user chose lavapipe's threads (`LP_NUM_THREADS`), `VKPT_LAVAPIPE_DEVICES`
/// (default: the cores this process may use) devices of one thread each.
/// Returns the number of devices, or a message for a bad setting.
///
/// # Safety
/// Sets environment variables: call before any other thread starts (the
/// Vulkan driver reads the environment from C, without Rust's lock).
pub unsafe fn configure_process() -> anyhow::Result<usize> {
    if std::env::var_os(LAVAPIPE_THREADS_VAR).is_some() {
        return devices_from_environment();
    }
    let devices = match std::env::var_os(DEVICES_VAR) {
        Some(_) => devices_from_environment()?,
        None => std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(MAX_DEVICES),
    };
    if devices > 1 {
        // SAFETY: the caller's promise (no other thread yet).
        unsafe {
            std::env::set_var(LAVAPIPE_THREADS_VAR, "1");
            std::env::set_var(DEVICES_VAR, devices.to_string());
        }
    }
    Ok(devices)
}

/// `VKPT_LAVAPIPE_DEVICES`, checked; 1 where it is not set.
fn devices_from_environment() -> anyhow::Result<usize> {
    let Ok(text) = std::env::var(DEVICES_VAR) else {
        return Ok(1);
    };
    match text.trim().parse::<usize>() {
        Ok(n) if (1..=MAX_DEVICES).contains(&n) => Ok(n),
        _ => anyhow::bail!(
            "{DEVICES_VAR}={text:?}: expected a number of lavapipe devices from 1 to {MAX_DEVICES}"
        ),
    }
}

/// How many devices to open where `first` is the device asked for: one
/// unless it is lavapipe and the environment asks for more
/// (`configure_process`).
pub fn lavapipe_devices(first: &GpuRenderer) -> anyhow::Result<usize> {
    if !first.is_cpu_device() {
        return Ok(1);
    }
    devices_from_environment()
}

/// Contiguous shares of `samples` for `n` devices, as even as can be.
fn shares(samples: u32, n: u32) -> Vec<(u32, u32)> {
    let (base, extra) = (samples / n, samples % n);
    let mut offset = 0;
    (0..n)
        .map(|d| {
            let count = base + u32::from(d < extra);
            let share = (offset, count);
            offset += count;
            share
        })
        .collect()
}

/// Sums of what the devices' renders counted.
#[derive(Default)]
struct Totals {
    extension_rays: u64,
    shadow_rays: u64,
    traversal_overflows: u64,
    nonfinite_samples: u64,
    paths_parked: u64,
    kernel_variant: Option<String>,
    kernel_times: Vec<(String, Duration)>,
}

impl Totals {
    fn add(&mut self, r: &RenderResult) {
        self.extension_rays += r.extension_rays;
        self.shadow_rays += r.shadow_rays;
        self.traversal_overflows += r.traversal_overflows;
        self.nonfinite_samples += r.nonfinite_samples;
        self.paths_parked += r.paths_parked;
        if self.kernel_variant.is_none() {
            self.kernel_variant.clone_from(&r.kernel_variant);
        }
        for (name, time) in &r.kernel_times {
            match self.kernel_times.iter_mut().find(|(n, _)| n == name) {
                Some((_, total)) => *total += *time,
                None => self.kernel_times.push((name.clone(), *time)),
            }
        }
    }
}

impl GpuRenderer {
    /// `render_progressive` over this device and its replicas.
    pub(super) fn render_split(
        &mut self,
        scene: &Scene,
        packed: &PackedScene,
        settings: &RenderSettings,
        progress: Progress,
        control: &mut dyn PassControl,
    ) -> anyhow::Result<RenderResult> {
        let mut replicas = std::mem::take(&mut self.replicas);
        for r in &mut replicas {
            r.schedule = self.schedule;
            r.all_features = self.all_features;
            r.specialize_ahead = self.specialize_ahead;
            r.split_shade = self.split_shade;
            r.loop_budget = self.loop_budget;
            r.limits = self.limits.clone();
        }
        let mut devices: Vec<&mut GpuRenderer> =
            std::iter::once(&mut *self).chain(&mut replicas).collect();
        let result = render_on(&mut devices, scene, packed, settings, progress, control);
        drop(devices);
        self.replicas = replicas;
        let (film, spp, render_time, totals) = result?;
        Ok(RenderResult {
            film,
            spp,
            device_name: self.device_name(),
            render_time,
            extension_rays: totals.extension_rays,
            shadow_rays: totals.shadow_rays,
            traversal_overflows: totals.traversal_overflows,
            nonfinite_samples: totals.nonfinite_samples,
            paths_parked: totals.paths_parked,
            kernel_variant: totals.kernel_variant,
            kernel_times: totals.kernel_times,
        })
    }
}

/// Runs `work` on every device at once, a thread each; the results in
/// device order.
fn on_each<T: Send>(
    devices: &mut [&mut GpuRenderer],
    work: impl Fn(usize, &mut GpuRenderer) -> Option<anyhow::Result<T>> + Sync,
) -> anyhow::Result<Vec<T>> {
    let work = &work;
    let results: Vec<Option<anyhow::Result<T>>> = std::thread::scope(|scope| {
        let threads: Vec<_> = devices
            .iter_mut()
            .enumerate()
            .map(|(d, device)| scope.spawn(move || work(d, device)))
            .collect();
        threads
            .into_iter()
            .map(|t| {
                t.join().unwrap_or_else(|_| {
                    Some(Err(anyhow::anyhow!("a lavapipe device's thread panicked")))
                })
            })
            .collect()
    });
    results.into_iter().flatten().collect()
}

type Rendered = (Film, u32, Duration, Totals);

fn render_on(
    devices: &mut [&mut GpuRenderer],
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
    progress: Progress,
    control: &mut dyn PassControl,
) -> anyhow::Result<Rendered> {
    // Every device compiles its own kernels, all at once.
    on_each(devices, |_, device| {
        Some(device.prepare_kernels(scene, packed, settings).map(|_| ()))
    })?;
    let pixels = settings.pixel_count();
    let total = pixels * settings.spp as u64;
    let n = devices.len() as u32;
    // A pass gives each device the samples one path pool holds.
    let share = pass_spp(pixels, devices[0].pool_size(pixels) as u64);
    progress(0, total);
    let start = Instant::now();
    let traced = AtomicU64::new(0);
    let mut film: Option<Film> = None;
    let mut totals = Totals::default();
    let mut spp = 0u32;
    let mut upload = Upload {
        bytes: 0,
        reused: true,
    };
    let mut upload_time = Duration::ZERO;
    while spp < settings.spp {
        let pass = share.saturating_mul(n).min(settings.spp - spp);
        let ranges = shares(pass, n);
        let traced = &traced;
        let results = on_each(devices, |d, device| {
            let (offset, count) = ranges[d];
            if count == 0 {
                return None;
            }
            let part = RenderSettings {
                first_sample: settings.first_sample + spp + offset,
                spp: count,
                ..settings.clone()
            };
            // Each device counts its own samples; the bar shows the sum.
            let reported = AtomicU64::new(0);
            let report = |done: u64, _: u64| {
                let new = done.saturating_sub(reported.swap(done, Ordering::Relaxed));
                if new > 0 {
                    progress(traced.fetch_add(new, Ordering::Relaxed) + new, total);
                }
            };
            let result = device
                .render_on_this_device(scene, packed, &part, &report, &mut RenderAll)
                .with_context(|| format!("lavapipe device {} of {n}", d + 1));
            Some(result.map(|r| (r, device.last_upload, device.last_upload_time)))
        })?;
        // What the render uploaded: every device's arrays at its first pass,
        // the parameters at the others (uploads run side by side).
        let first_pass = spp == 0;
        upload.bytes += results.iter().map(|(_, u, _)| u.bytes).sum::<u64>();
        upload.reused &= !first_pass || results.iter().all(|(_, u, _)| u.reused);
        upload_time += results.iter().map(|&(_, _, t)| t).max().unwrap_or_default();
        for (r, _, _) in results {
            totals.add(&r);
            match &mut film {
                None => film = Some(r.film),
                Some(f) => f.merge(&r.film),
            }
        }
        spp += pass;
        if spp < settings.spp {
            let current = film.as_ref().context("a pass rendered nothing")?;
            if !control.after_pass(spp, &mut || Ok(current.clone()))? {
                break;
            }
        }
    }
    devices[0].last_upload = upload;
    devices[0].last_upload_time = upload_time;
    let film = film.context("the render had no samples")?;
    Ok((film, spp, start.elapsed(), totals))
}

#[cfg(test)]
mod tests {
    use super::shares;

    #[test]
    fn shares_cover_the_pass_in_order() {
        assert_eq!(shares(8, 2), vec![(0, 4), (4, 4)]);
        assert_eq!(shares(5, 2), vec![(0, 3), (3, 2)]);
        assert_eq!(shares(1, 3), vec![(0, 1), (1, 0), (1, 0)]);
    }
}
