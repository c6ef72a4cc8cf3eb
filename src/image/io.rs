//! Writing and reading images: linear EXR (with the variance of each pixel's
//! mean, and the denoised image as a layer when there is one) for
//! measurement, tone-mapped sRGB PNG (the denoised image when there is one)
//! for looking.
//!
//! Files are written under a temporary name in the destination folder and
//! renamed into place, so a crash or a full disk never leaves a half-written
//! image that a later comparison would trust.

use super::tonemap::{PngSettings, encode_srgb8};
use super::{Image, RenderHeader};
use anyhow::{Context, Result, anyhow, bail};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Extensions `write_image` understands (matched case-insensitively).
pub const SUPPORTED_EXTENSIONS: &[&str] = &["exr", "png"];

/// Channel names of the variance layer, by the EXR `layer.channel` convention.
const VARIANCE_CHANNELS: [&str; 3] = ["variance.R", "variance.G", "variance.B"];

/// Channel names of the auxiliary outputs (`Image::aovs`): the layer names
/// Open Image Denoise's examples and most compositors read (`albedo`,
/// `normal`, and `depth.Z` as a Z channel), rather than Cycles' `Denoising
/// Albedo`, which only Blender knows.
const ALBEDO_CHANNELS: [&str; 3] = ["albedo.R", "albedo.G", "albedo.B"];
const NORMAL_CHANNELS: [&str; 3] = ["normal.X", "normal.Y", "normal.Z"];
const DEPTH_CHANNEL: &str = "depth.Z";
/// Channel names of the denoised layer (`Image::denoised`). The raw beauty
/// stays in R, G, B, so measuring an EXR always measures the raw render.
const DENOISED_CHANNELS: [&str; 3] = ["denoised.R", "denoised.G", "denoised.B"];

/// The channel with each pixel's sample count (`Image::samples`), which an
/// exact merge of renders needs besides mean and variance.
const SAMPLES_CHANNEL: &str = "samples";

/// Writes `image` as EXR or PNG, chosen by the extension of `path`.
pub fn write_image(path: &Path, image: &Image, png: &PngSettings) -> Result<()> {
    write_image_with_header(path, image, png, None)
}

/// As `write_image`; an EXR also records `header` (PNG has no place for it).
/// When the header's region is not the whole image, the EXR's data window
/// is the region inside a display window of the full image.
pub fn write_image_with_header(
    path: &Path,
    image: &Image,
    png: &PngSettings,
    header: Option<&RenderHeader>,
) -> Result<()> {
    check_size(image).with_context(|| format!("cannot write {}", path.display()))?;
    if let Some(h) = header {
        anyhow::ensure!(
            (h.region.width(), h.region.height()) == (image.width, image.height),
            "cannot write {}: the image is {}x{} but its header's region {} is {}x{}",
            path.display(),
            image.width,
            image.height,
            h.region,
            h.region.width(),
            h.region.height()
        );
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("exr") => write_atomically(path, |tmp| write_exr_to(tmp, image, header)),
        Some("png") => write_atomically(path, |tmp| write_png_to(tmp, image, png)),
        _ => bail!(
            "cannot write {}: unsupported image extension (supported: {})",
            path.display(),
            SUPPORTED_EXTENSIONS
                .iter()
                .map(|e| format!(".{e}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Writes a one-channel mosaic (`sensor::SensorImage::mosaic_adu`, values
/// in ADU from 0 to `max_adu`), chosen by the extension of `path`: an EXR
/// with one f32 channel `Y` holding the ADU counts as they are; a 16-bit
/// greyscale PNG holding round(ADU · 65535 / max_adu), linear (no sRGB
/// curve), so full well is white at any bit depth.
pub fn write_mosaic(path: &Path, width: u32, height: u32, adu: &[f32], max_adu: f32) -> Result<()> {
    anyhow::ensure!(
        width > 0 && height > 0 && adu.len() == width as usize * height as usize,
        "cannot write {}: the mosaic has {} values for {width}x{height}",
        path.display(),
        adu.len()
    );
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("exr") => write_atomically(path, |tmp| {
            use exr::prelude::*;
            let channel = AnyChannel::new("Y", FlatSamples::F32(adu.to_vec()));
            let layer = Layer::new(
                (width as usize, height as usize),
                LayerAttributes::default(),
                Encoding::SMALL_LOSSLESS,
                AnyChannels::sort(SmallVec::from_elem(channel, 1)),
            );
            exr::prelude::Image::from_layer(layer)
                .write()
                .to_file(tmp)
                .map_err(|e| anyhow!("EXR encoding failed: {e}"))?;
            sync(tmp)
        }),
        Some("png") => write_atomically(path, |tmp| {
            let scale = 65535.0 / max_adu.max(1.0);
            let grey: Vec<u16> = adu
                .iter()
                .map(|&a| (a * scale).round().clamp(0.0, 65535.0) as u16)
                .collect();
            let buffer = image::ImageBuffer::<image::Luma<u16>, _>::from_raw(width, height, grey)
                .ok_or_else(|| anyhow!("pixel buffer does not match the image size"))?;
            buffer
                .save_with_format(tmp, image::ImageFormat::Png)
                .context("PNG encoding failed")?;
            sync(tmp)
        }),
        _ => bail!(
            "cannot write {}: unsupported image extension (supported: .exr, .png)",
            path.display()
        ),
    }
}

fn check_size(image: &Image) -> Result<()> {
    let n = image.width as usize * image.height as usize;
    if image.width == 0 || image.height == 0 {
        bail!("image is empty ({}x{})", image.width, image.height);
    }
    if image.mean.len() != n {
        bail!(
            "image has {} pixels, expected {}x{} = {n}",
            image.mean.len(),
            image.width,
            image.height
        );
    }
    if let Some(v) = &image.variance
        && v.len() != n
    {
        bail!("variance has {} pixels, expected {n}", v.len());
    }
    if let Some(s) = &image.samples
        && s.len() != n
    {
        bail!("sample counts have {} pixels, expected {n}", s.len());
    }
    if let Some(d) = &image.denoised
        && d.len() != n
    {
        bail!("the denoised image has {} pixels, expected {n}", d.len());
    }
    let a = &image.aovs;
    for (name, len) in [
        ("albedo", a.albedo.as_ref().map(Vec::len)),
        ("normal", a.normal.as_ref().map(Vec::len)),
        ("depth", a.depth.as_ref().map(Vec::len)),
    ] {
        if let Some(len) = len
            && len != n
        {
            bail!("the {name} layer has {len} pixels, expected {n}");
        }
    }
    Ok(())
}

/// Runs `write` on a temporary path next to `path`, then renames it into
/// place (atomic on one file system). The temporary file is removed on error.
fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let file_name = path
        .file_name()
        .ok_or_else(|| anyhow!("cannot write {}: not a file name", path.display()))?;
    let tmp: PathBuf = path.with_file_name(format!(
        ".{}.{}.tmp",
        file_name.to_string_lossy(),
        std::process::id()
    ));
    let result = write(&tmp).and_then(|()| {
        std::fs::rename(&tmp, path).with_context(|| format!("renaming {}", tmp.display()))
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.with_context(|| format!("cannot write {}", path.display()))
}

fn write_exr_to(path: &Path, image: &Image, header: Option<&RenderHeader>) -> Result<()> {
    use exr::prelude::*;
    let channel = |name: &str, data: Vec<f32>| AnyChannel::new(name, FlatSamples::F32(data));
    let plane = |data: &[[f32; 3]], c: usize| data.iter().map(|p| p[c]).collect::<Vec<f32>>();
    let mut list = SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        list.push(channel(name, plane(&image.mean, c)));
    }
    if let Some(var) = &image.variance {
        for (c, name) in VARIANCE_CHANNELS.iter().enumerate() {
            list.push(channel(name, plane(var, c)));
        }
    }
    if let Some(denoised) = &image.denoised {
        for (c, name) in DENOISED_CHANNELS.iter().enumerate() {
            list.push(channel(name, plane(denoised, c)));
        }
    }
    if let Some(samples) = &image.samples {
        list.push(channel(SAMPLES_CHANNEL, samples.clone()));
    }
    for (names, layer) in [
        (ALBEDO_CHANNELS, &image.aovs.albedo),
        (NORMAL_CHANNELS, &image.aovs.normal),
    ] {
        if let Some(layer) = layer {
            for (c, name) in names.iter().enumerate() {
                list.push(channel(name, plane(layer, c)));
            }
        }
    }
    if let Some(depth) = &image.aovs.depth {
        list.push(channel(DEPTH_CHANNEL, depth.clone()));
    }
    let mut attributes = LayerAttributes::default();
    let mut display = None;
    if let Some(h) = header {
        for (name, value) in h.attributes() {
            // EXR text is bytes; file names may be any UTF-8.
            let text = Text::from_bytes_unchecked(value.as_bytes().into());
            attributes
                .other
                .insert(Text::from(name), AttributeValue::Text(text));
        }
        attributes.layer_position = Vec2(h.region.x0 as i32, h.region.y0 as i32);
        display = Some(IntegerBounds::new(
            (0, 0),
            (h.width as usize, h.height as usize),
        ));
    }
    let layer = Layer::new(
        (image.width as usize, image.height as usize),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let file = match display {
        Some(bounds) => exr::prelude::Image::new(ImageAttributes::new(bounds), layer),
        None => exr::prelude::Image::from_layer(layer),
    };
    file.write()
        .to_file(path)
        .map_err(|e| anyhow!("EXR encoding failed: {e}"))?;
    sync(path)
}

fn write_png_to(path: &Path, image: &Image, settings: &PngSettings) -> Result<()> {
    let shown = image.denoised.as_ref().unwrap_or(&image.mean);
    let mut bytes = Vec::with_capacity(shown.len() * 3);
    for &rgb in shown {
        bytes.extend_from_slice(&encode_srgb8(rgb, settings));
    }
    let buffer = image::RgbImage::from_raw(image.width, image.height, bytes)
        .ok_or_else(|| anyhow!("pixel buffer does not match the image size"))?;
    let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut writer = BufWriter::new(file);
    buffer
        .write_to(&mut writer, image::ImageFormat::Png)
        .context("PNG encoding failed")?;
    writer.flush()?;
    writer
        .into_inner()
        .map_err(|e| e.into_error())?
        .sync_all()?;
    Ok(())
}

/// Flushes file contents to disk before the rename makes them visible.
fn sync(path: &Path) -> Result<()> {
    File::open(path)?.sync_all()?;
    Ok(())
}

/// Reads an EXR written by `write_image`, or an RGB(A) or luminance (Y) EXR
/// from another tool: the first layer with R, G, B (or Y) channels is the
/// mean, and `variance.R/G/B` and `denoised.R/G/B` in that layer, when
/// present, the variance and the denoised image.
/// Any sample type is converted to f32; alpha and other channels are ignored.
pub fn read_exr(path: &Path) -> Result<Image> {
    Ok(read_exr_part(path)?.0)
}

/// As `read_exr`, with the `samples` channel and the render header when the
/// file has them (`None`: not written by vkpt, or by a vkpt before headers).
pub fn read_exr_part(path: &Path) -> Result<(Image, Option<RenderHeader>)> {
    read_exr_inner(path).with_context(|| format!("cannot read EXR {}", path.display()))
}

/// The render header of an EXR, reading only the file's header (not its
/// pixels): `None` when it has none.
pub fn read_exr_header(path: &Path) -> Result<Option<RenderHeader>> {
    let read = || -> Result<Option<RenderHeader>> {
        let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| anyhow!("{e}"))?;
        let first = meta
            .headers
            .first()
            .ok_or_else(|| anyhow!("the file has no header"))?;
        header_of(
            &first.own_attributes,
            &first.shared_attributes,
            first.layer_size,
        )
    };
    read().with_context(|| format!("cannot read EXR {}", path.display()))
}

/// The render header in a layer's attributes, checked against where the
/// layer's pixels are (its data window).
fn header_of(
    own: &exr::meta::header::LayerAttributes,
    shared: &exr::meta::header::ImageAttributes,
    size: exr::math::Vec2<usize>,
) -> Result<Option<RenderHeader>> {
    use exr::meta::attribute::{AttributeValue, Text};
    let attribute = |name: &str| -> Option<String> {
        let key = Text::from(name);
        match own.other.get(&key).or_else(|| shared.other.get(&key))? {
            AttributeValue::Text(t) => Some(String::from_utf8_lossy(t.as_slice()).into_owned()),
            _ => None,
        }
    };
    let Some(header) = RenderHeader::from_attributes(attribute)? else {
        return Ok(None);
    };
    let r = header.region;
    let position = own.layer_position;
    anyhow::ensure!(
        (position.0, position.1, size.0, size.1)
            == (
                r.x0 as i32,
                r.y0 as i32,
                r.width() as usize,
                r.height() as usize
            ),
        "the header's region {r} does not match the pixels ({}x{} at {},{})",
        size.0,
        size.1,
        position.0,
        position.1
    );
    Ok(Some(header))
}

fn read_exr_inner(path: &Path) -> Result<(Image, Option<RenderHeader>)> {
    use exr::prelude::*;
    let file = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| anyhow!("{e}"))?;

    let mut names_seen = Vec::new();
    for layer in &file.layer_data {
        let channels = &layer.channel_data.list;
        let find = |name: &str| channels.iter().find(|c| c.name.eq(name));
        names_seen.extend(channels.iter().map(|c| c.name.to_string()));
        let mean_channels = match (find("R"), find("G"), find("B"), find("Y")) {
            (Some(r), Some(g), Some(b), _) => [r, g, b],
            (_, _, _, Some(y)) => [y, y, y],
            _ => continue,
        };
        let (width, height) = (layer.size.0, layer.size.1);
        let n = width * height;
        let plane = |ch: &AnyChannel<FlatSamples>| -> anyhow::Result<Vec<f32>> {
            let v: Vec<f32> = ch.sample_data.values_as_f32().collect();
            if v.len() != n {
                bail!(
                    "channel {} has {} samples for {width}x{height} pixels (subsampled channels are not supported)",
                    ch.name,
                    v.len()
                );
            }
            Ok(v)
        };
        let interleave = |chs: [&AnyChannel<FlatSamples>; 3]| -> anyhow::Result<Vec<[f32; 3]>> {
            let [r, g, b] = [plane(chs[0])?, plane(chs[1])?, plane(chs[2])?];
            Ok((0..n).map(|i| [r[i], g[i], b[i]]).collect())
        };
        let mean = interleave(mean_channels)?;
        let variance = match VARIANCE_CHANNELS.map(find) {
            [Some(r), Some(g), Some(b)] => Some(interleave([r, g, b])?),
            [None, None, None] => None,
            _ => bail!("incomplete variance layer (need variance.R, variance.G, variance.B)"),
        };
        let denoised = match DENOISED_CHANNELS.map(find) {
            [Some(r), Some(g), Some(b)] => Some(interleave([r, g, b])?),
            [None, None, None] => None,
            _ => bail!("incomplete denoised layer (need denoised.R, denoised.G, denoised.B)"),
        };
        let samples = find(SAMPLES_CHANNEL).map(plane).transpose()?;
        let layer3 = |names: [&str; 3], what: &str| match names.map(find) {
            [Some(x), Some(y), Some(z)] => interleave([x, y, z]).map(Some),
            [None, None, None] => Ok(None),
            _ => bail!("incomplete {what} layer (need {})", names.join(", ")),
        };
        let aovs = crate::image::Aovs {
            albedo: layer3(ALBEDO_CHANNELS, "albedo")?,
            normal: layer3(NORMAL_CHANNELS, "normal")?,
            depth: find(DEPTH_CHANNEL).map(plane).transpose()?,
        };
        let header = header_of(&layer.attributes, &file.attributes, layer.size)?;
        let image = crate::image::Image {
            width: u32::try_from(width)?,
            height: u32::try_from(height)?,
            mean,
            variance,
            samples,
            aovs,
            denoised,
        };
        return Ok((image, header));
    }
    bail!(
        "no layer with R, G, B or Y channels (found: {})",
        names_seen.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::ToneMap;

    fn test_dir(name: &str) -> PathBuf {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("target")
            .join("test-output")
            .join(name);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn gradient(width: u32, height: u32) -> Image {
        let mut image = Image::new(width, height);
        for y in 0..height {
            for x in 0..width {
                let i = image.index(x, y);
                image.mean[i] = [x as f32 * 0.37, y as f32 * 1.1e-3, 1.0 / (1.0 + i as f32)];
            }
        }
        image
    }

    #[test]
    fn output_exr_roundtrip_is_exact() {
        let dir = test_dir("output_exr_roundtrip_is_exact");
        let mut image = gradient(13, 7);
        image.variance = Some(
            (0..13 * 7)
                .map(|i| [i as f32 * 1e-7, std::f32::consts::PI, f32::INFINITY])
                .collect(),
        );
        image.denoised = Some((0..13 * 7).map(|i| [i as f32, 0.5, -0.0]).collect());
        let path = dir.join("with_variance.EXR");
        write_image(&path, &image, &PngSettings::default()).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!(back.width, 13);
        assert_eq!(back.height, 7);
        assert_eq!(back.mean, image.mean);
        assert_eq!(back.variance, image.variance);
        assert_eq!(back.denoised, image.denoised);

        let plain = gradient(5, 3);
        let path = dir.join("plain.exr");
        write_image(&path, &plain, &PngSettings::default()).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!(back.mean, plain.mean);
        assert_eq!(back.variance, None);
        assert_eq!(back.denoised, None);
        // No temporary files left behind.
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(leftovers.is_empty());
    }

    #[test]
    fn output_reads_foreign_rgba_f16_exr() {
        let dir = test_dir("output_reads_foreign_rgba_f16_exr");
        let path = dir.join("rgba_f16.exr");
        exr::prelude::write_rgba_file(&path, 4, 2, |x, y| {
            (
                exr::prelude::f16::from_f32(x as f32 * 0.5),
                exr::prelude::f16::from_f32(y as f32),
                exr::prelude::f16::from_f32(0.25),
                exr::prelude::f16::from_f32(1.0),
            )
        })
        .unwrap();
        let image = read_exr(&path).unwrap();
        assert_eq!((image.width, image.height), (4, 2));
        assert_eq!(image.mean[image.index(3, 1)], [1.5, 1.0, 0.25]);
        assert!(image.variance.is_none());
    }

    #[test]
    fn output_png_clamp_mid_grey_is_188() {
        let dir = test_dir("output_png_clamp_mid_grey_is_188");
        let mut image = Image::new(3, 2);
        image.mean = vec![
            [0.5, 0.5, 0.5],
            [0.0, 1.0, 2.0],
            [f32::NAN, f32::INFINITY, -1.0],
            [0.25, 0.25, 0.25],
            [0.002, 0.0, 0.0],
            [0.5, 0.5, 0.5],
        ];
        let settings = PngSettings {
            exposure_ev: 0.0,
            tonemap: ToneMap::Clamp,
        };
        let path = dir.join("grey.Png");
        write_image(&path, &image, &settings).unwrap();
        let back = image::open(&path).unwrap().to_rgb8();
        assert_eq!(back.dimensions(), (3, 2));
        assert_eq!(back.get_pixel(0, 0).0, [188, 188, 188]);
        assert_eq!(back.get_pixel(1, 0).0, [0, 255, 255]);
        assert_eq!(back.get_pixel(2, 0).0, [0, 255, 0]);
        // 0.002 is on the linear segment: 0.002 * 12.92 * 255 = 6.59.
        assert_eq!(back.get_pixel(1, 1).0, [7, 0, 0]);
        // +1 EV turns 0.25 into 0.5.
        let brighter = PngSettings {
            exposure_ev: 1.0,
            ..settings
        };
        assert_eq!(encode_srgb8([0.25; 3], &brighter), [188, 188, 188]);
        // Every tone map survives non-finite input.
        for tm in [ToneMap::PbrNeutral, ToneMap::AcesFilmic, ToneMap::Clamp] {
            let s = PngSettings {
                exposure_ev: 0.0,
                tonemap: tm,
            };
            let _ = encode_srgb8([f32::NAN, f32::INFINITY, f32::NEG_INFINITY], &s);
            assert_eq!(encode_srgb8([1e30; 3], &s), [255, 255, 255], "{tm:?}");
        }
    }

    #[test]
    fn output_png_shows_the_denoised_image() {
        let dir = test_dir("output_png_shows_the_denoised_image");
        let mut image = Image::new(2, 1);
        image.mean = vec![[0.0; 3], [1.0; 3]];
        image.denoised = Some(vec![[0.5; 3], [0.5; 3]]);
        let settings = PngSettings {
            exposure_ev: 0.0,
            tonemap: ToneMap::Clamp,
        };
        let path = dir.join("denoised.png");
        write_image(&path, &image, &settings).unwrap();
        let back = image::open(&path).unwrap().to_rgb8();
        assert_eq!(back.get_pixel(0, 0).0, [188, 188, 188]);
        assert_eq!(back.get_pixel(1, 0).0, [188, 188, 188]);
        image.denoised = Some(vec![[0.5; 3]]);
        assert!(write_image(&path, &image, &settings).is_err());
    }

    #[test]
    fn output_rejects_unknown_extension() {
        let err = write_image(
            Path::new("/tmp/x.tiff"),
            &Image::new(1, 1),
            &PngSettings::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("/tmp/x.tiff") && err.contains(".exr") && err.contains(".png"));
        let err = read_exr(Path::new("/nonexistent/y.exr")).unwrap_err();
        assert!(format!("{err:#}").contains("/nonexistent/y.exr"));
    }
}
