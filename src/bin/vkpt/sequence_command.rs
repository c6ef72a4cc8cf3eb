//! `vkpt SCENE --frames A..B --fps F -o out_%04d.png`: the scene posed at
//! `--time + n / F` for each frame n, rendered one after the other on one
//! back end. The file is read once (`GltfFile`); each frame re-walks the
//! node hierarchy, rebuilds the BVH (its cost is printed per frame) and
//! renders with the device, pipelines and kernels of the first frame,
//! re-uploading only the arrays that changed (`gpu::resources`).

use crate::args::RenderArgs;
use crate::render_command::{
    apply_light_options, frame_settings, image_to_write, load_options, motion_shutter,
    note_what_png_loses, output_path, render_blurred, scene_in_motion,
};
use anyhow::{Context as _, bail, ensure};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vkpt::image::write_image_with_header;
use vkpt::packed::PackedScene;
use vkpt::render::header::render_header;
use vkpt::render::{Backend, RenderAll, RenderSettings};
use vkpt::scene::Scene;

/// The file name of frame `frame` from a pattern holding one `%d` or
/// `%0Nd` (N digits, zero-padded); `None` when it holds none. A literal
/// percent sign is written `%%`.
pub fn frame_path(pattern: &Path, frame: u32) -> anyhow::Result<Option<PathBuf>> {
    let text = pattern.to_string_lossy();
    let mut out = String::new();
    let mut found = false;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c != '%' {
            out.push(c);
            continue;
        }
        if chars.peek() == Some(&'%') {
            chars.next();
            out.push('%');
            continue;
        }
        let mut width = String::new();
        while let Some(d) = chars.peek().filter(|d| d.is_ascii_digit()) {
            width.push(*d);
            chars.next();
        }
        ensure!(
            chars.next() == Some('d') && !found,
            "{}: a frame pattern holds one %d or %0Nd (e.g. out_%04d.png)",
            pattern.display()
        );
        found = true;
        let width: usize = width.parse().unwrap_or(0);
        out.push_str(&format!("{frame:0width$}"));
    }
    Ok(found.then(|| PathBuf::from(out)))
}

/// Renders and writes every frame; the exit status.
pub fn run(args: &RenderArgs, scene_path: &Path, frames: Range<u32>) -> anyhow::Result<i32> {
    let p = &args.progressive;
    // Frames are written when done: no checkpoints.
    if args.split.samples.is_some() || args.sensor.raw_mosaic.is_some() {
        bail!("--frames renders whole frames: it does not take --samples or --raw-mosaic");
    }
    if p.time_limit.is_some() || p.target_error.is_some() {
        bail!(
            "--frames renders every frame at --spp: it does not take --time-limit or --target-error"
        );
    }
    let pattern = output_path(args, scene_path)?;
    if frame_path(&pattern, 0)?.is_none() && frames.len() > 1 {
        bail!(
            "-o {}: {} frames need a file name pattern with %04d (or %d), e.g. -o out_%04d.png",
            pattern.display(),
            frames.len()
        );
    }
    note_what_png_loses(args, &pattern);
    let load = load_options(args);
    let file = Scene::open_file(scene_path, &load)?;
    if !file.is_animated() {
        eprintln!(
            "note: nothing in {} is animated: every frame is the same image",
            scene_path.display()
        );
    }
    let mut backend: Option<(Backend, String)> = None;
    for frame in frames.clone() {
        let time = args.animation.time + frame as f64 / args.animation.fps;
        let load_start = Instant::now();
        let mut scene = file.at(time)?;
        apply_light_options(&mut scene, &args.light)?;
        if frame == frames.start {
            for note in &scene.notes {
                eprintln!("{}", vkpt::scene::note_line(note));
            }
        }
        let (settings, png, sensor) = frame_settings(
            args,
            &mut scene,
            (&file, time),
            false,
            frame == frames.start,
        )?;
        let mut blur_on_host = None;
        if let Some(shutter) = motion_shutter(&file, &scene, &settings, time) {
            match scene_in_motion(args, &file, shutter)? {
                Ok(moving) => scene = moving,
                Err(_) => blur_on_host = Some(shutter),
            }
        }
        scene.light_sampler = args.light_sampler.mode();
        let packed = PackedScene::new(&scene)?;
        let load_time = load_start.elapsed();
        let (backend, why) = match &mut backend {
            Some(b) => b,
            None => backend.insert(Backend::open(
                args.device,
                args.schedule,
                &scene,
                &packed,
                &settings,
            )?),
        };
        let result = match blur_on_host {
            Some(shutter) => render_blurred(args, &file, backend, &settings, shutter),
            None => render_frame(backend, &scene, &packed, &settings),
        }
        .with_context(|| format!("frame {frame} (t = {time} s)"))?;
        let output = frame_path(&pattern, frame)?.unwrap_or_else(|| pattern.clone());
        let written = image_to_write(&result.film, args, sensor.as_ref())?;
        let mut header = render_header(&scene, &packed, &settings, 0, "")?;
        header.samples = settings.first_sample..settings.first_sample + result.spp;
        header.backend = result.device_name.clone();
        write_image_with_header(&output, &written.image, &png, Some(&header))
            .with_context(|| format!("writing {}", output.display()))?;
        let upload = match backend {
            Backend::Vulkan(gpu) => format!(
                ", upload {} B{}",
                gpu.last_upload.bytes,
                if gpu.last_upload.reused {
                    " (buffers kept)"
                } else {
                    ""
                }
            ),
            Backend::Cpu => String::new(),
        };
        println!(
            "frame {frame} (t = {time:.4} s): pose {:.1} ms, BVH {:.1} ms ({} triangles){upload}, rendered {} spp in {:.2} s on {} ({why}): wrote {}",
            (load_time - packed.bvh_build_time).as_secs_f64() * 1e3,
            packed.bvh_build_time.as_secs_f64() * 1e3,
            packed.tri_verts.len(),
            result.spp,
            result.render_time.as_secs_f64(),
            result.device_name,
            output.display()
        );
    }
    Ok(0)
}

fn render_frame(
    backend: &mut Backend,
    scene: &Scene,
    packed: &PackedScene,
    settings: &RenderSettings,
) -> anyhow::Result<vkpt::render::RenderResult> {
    backend.render_progressive(scene, packed, settings, &|_, _| {}, &mut RenderAll)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_patterns_expand_and_are_checked() {
        let p =
            |s: &str, f| frame_path(Path::new(s), f).map(|o| o.map(|p| p.display().to_string()));
        assert_eq!(
            p("out_%04d.png", 7).unwrap().as_deref(),
            Some("out_0007.png")
        );
        assert_eq!(p("f%d.exr", 12).unwrap().as_deref(), Some("f12.exr"));
        assert_eq!(
            p("a%%b_%02d.png", 3).unwrap().as_deref(),
            Some("a%b_03.png")
        );
        assert_eq!(p("out.png", 3).unwrap(), None);
        assert!(p("out_%04x.png", 3).is_err());
        assert!(p("out_%d_%d.png", 3).is_err());
    }
}
