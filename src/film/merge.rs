//! `vkpt merge`: parts of one render (sample ranges, regions, or both) made
//! apart, combined into the image one render would have made.
//!
//! Every part's header must describe the same image (scene content, size,
//! seed, sampler, filter, depth, camera, version). At every pixel the parts
//! covering it must hold disjoint sample ranges that join into one range,
//! the same for every pixel; regions of different parts may not overlap and
//! must cover the image unless holes are allowed. Headers are checked
//! first, from the files' headers alone; then the parts are read one at a
//! time and combined by Chan's parallel Welford update (exact up to float
//! rounding: a sample-count-weighted mean and the variance of all samples),
//! so memory holds one part and the result, and time is linear in the parts.

use crate::image::{Image, Region, RenderHeader, read_exr_header, read_exr_part};
use anyhow::{Context, bail};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// What a merge made.
pub struct Merged {
    pub image: Image,
    pub header: RenderHeader,
    /// Pixels no part covered (left black, with no samples).
    pub holes: u64,
    /// Distinct regions and the parts merged.
    pub regions: usize,
    pub parts: usize,
}

/// Merges the EXR parts at `paths` (`allow_holes`: pixels no part covers
/// are black instead of an error; `expect`: the sample range the result
/// must hold, so a missing last part is noticed). Nothing is written;
/// errors are one line naming the files.
pub fn merge_files(
    paths: &[PathBuf],
    allow_holes: bool,
    expect: Option<Range<u32>>,
) -> anyhow::Result<Merged> {
    anyhow::ensure!(!paths.is_empty(), "no parts to merge");
    let mut headers = Vec::with_capacity(paths.len());
    for path in paths {
        let header = read_exr_header(path)?.with_context(|| {
            format!(
                "{} has no vkpt render header (written by another tool or an older vkpt): \
                 cannot tell what it holds",
                path.display()
            )
        })?;
        headers.push(header);
    }
    let parts: Vec<(&Path, &RenderHeader)> =
        paths.iter().map(|p| p.as_path()).zip(&headers).collect();
    let plan = plan(&parts, allow_holes)?;
    if let Some(expect) = expect {
        let got = &plan.header.samples;
        anyhow::ensure!(
            *got == expect,
            "the parts hold samples {}..{}, not the {}..{} expected: a part is missing or extra",
            got.start,
            got.end,
            expect.start,
            expect.end
        );
    }

    let mut image = empty_image(plan.header.width, plan.header.height);
    for (path, header) in &parts {
        let (part, _) = read_exr_part(path)
            .map_err(|e| anyhow::anyhow!("{e:#} (a truncated or damaged part?)"))?;
        add_part(&mut image, &part, header).with_context(|| format!("{}", path.display()))?;
    }
    Ok(Merged {
        image,
        header: plan.header,
        holes: plan.holes,
        regions: plan.regions,
        parts: parts.len(),
    })
}

/// The parts that cover one region: their files and sample ranges.
type RangeParts<'a> = Vec<(&'a Path, Range<u32>)>;

/// The header of the merged image and the holes it will have.
pub struct Plan {
    pub header: RenderHeader,
    pub holes: u64,
    pub regions: usize,
}

/// Checks that `parts` belong together and cover one sample range
/// everywhere (see the module's rules), from their headers alone.
pub fn plan(parts: &[(&Path, &RenderHeader)], allow_holes: bool) -> anyhow::Result<Plan> {
    let Some(&(first_path, first)) = parts.first() else {
        bail!("no parts to merge");
    };
    for &(path, h) in &parts[1..] {
        if let Some(difference) = first.differs_from(h) {
            bail!(
                "cannot merge {} with {}: they render different images ({difference})",
                path.display(),
                first_path.display()
            );
        }
    }
    // Parts by region; a region's sample ranges in order.
    let mut by_region: BTreeMap<(u32, u32, u32, u32), RangeParts> = BTreeMap::new();
    for &(path, h) in parts {
        h.region
            .check_inside(h.width, h.height)
            .with_context(|| format!("{}", path.display()))?;
        anyhow::ensure!(
            !h.samples.is_empty(),
            "{} holds no samples ({}..{})",
            path.display(),
            h.samples.start,
            h.samples.end
        );
        let r = h.region;
        by_region
            .entry((r.y0, r.x0, r.y1, r.x1))
            .or_default()
            .push((path, h.samples.clone()));
    }
    let regions: Vec<(Region, RangeParts)> = by_region
        .into_iter()
        .map(|((y0, x0, y1, x1), mut ranges)| {
            ranges.sort_by_key(|(_, r)| (r.start, r.end));
            (Region { x0, y0, x1, y1 }, ranges)
        })
        .collect();
    for (i, (a, parts_a)) in regions.iter().enumerate() {
        for (b, parts_b) in &regions[i + 1..] {
            if a.overlaps(b) {
                bail!(
                    "regions {a} ({}) and {b} ({}) overlap",
                    parts_a[0].0.display(),
                    parts_b[0].0.display()
                );
            }
        }
    }
    let mut union: Option<(Range<u32>, Region, &Path)> = None;
    for (region, ranges) in &regions {
        let joined = join_ranges(region, ranges)?;
        match &union {
            None => union = Some((joined, *region, ranges[0].0)),
            Some((u, other, path)) if *u != joined => bail!(
                "region {region} ({}) holds samples {}..{} but region {other} ({}) holds {}..{}: \
                 a part is missing",
                ranges[0].0.display(),
                joined.start,
                joined.end,
                path.display(),
                u.start,
                u.end
            ),
            Some(_) => {}
        }
    }
    let samples = union.map(|(u, _, _)| u).unwrap_or(0..0);
    anyhow::ensure!(
        samples.end <= crate::packed::settings::MAX_SAMPLES,
        "the merged image would count {} samples a pixel, above the {} a film counts exactly",
        samples.len(),
        crate::packed::settings::MAX_SAMPLES
    );
    let (width, height) = (first.width, first.height);
    let covered: u64 = regions.iter().map(|(r, _)| r.pixel_count()).sum();
    let holes = Region::full(width, height).pixel_count() - covered;
    if holes > 0 && !allow_holes {
        let (x, y) = first_hole(width, height, regions.iter().map(|(r, _)| r));
        bail!(
            "the parts leave {holes} pixels of the {width}x{height} image uncovered, the first \
             at ({x}, {y}): a region is missing (or merge with --allow-holes)"
        );
    }
    let mut backends: Vec<&str> = Vec::new();
    for (_, h) in parts {
        if !backends.contains(&h.backend.as_str()) {
            backends.push(&h.backend);
        }
    }
    Ok(Plan {
        header: RenderHeader {
            region: Region::full(width, height),
            samples,
            backend: backends.join(" + "),
            ..(*first).clone()
        },
        holes,
        regions: regions.len(),
    })
}

/// The one range the sorted `ranges` of `region` join into, or an error
/// naming an overlap or a gap.
fn join_ranges(region: &Region, ranges: &[(&Path, Range<u32>)]) -> anyhow::Result<Range<u32>> {
    let (mut last_path, mut joined) = (ranges[0].0, ranges[0].1.clone());
    for (path, r) in &ranges[1..] {
        if r.start < joined.end {
            bail!(
                "sample ranges {}..{} ({}) and {}..{} ({}) of region {region} overlap",
                joined.start,
                joined.end,
                last_path.display(),
                r.start,
                r.end,
                path.display()
            );
        }
        if r.start > joined.end {
            bail!(
                "samples {}..{} of region {region} are in no part (between {} and {})",
                joined.end,
                r.start,
                last_path.display(),
                path.display()
            );
        }
        joined.end = r.end;
        last_path = path;
    }
    Ok(joined)
}

/// The first pixel (row by row) inside none of `regions`.
fn first_hole<'a>(
    width: u32,
    height: u32,
    regions: impl Iterator<Item = &'a Region>,
) -> (u32, u32) {
    let regions: Vec<&Region> = regions.collect();
    for y in 0..height {
        let mut x = 0;
        // Skip along the row over the regions that cover it.
        'row: while x < width {
            for r in &regions {
                if (r.y0..r.y1).contains(&y) && (r.x0..r.x1).contains(&x) {
                    x = r.x1;
                    continue 'row;
                }
            }
            return (x, y);
        }
    }
    (width, height)
}

/// The full image a merge fills in: black, no samples, unknown variance.
pub fn empty_image(width: u32, height: u32) -> Image {
    let n = width as usize * height as usize;
    Image {
        variance: Some(vec![[f32::INFINITY; 3]; n]),
        samples: Some(vec![0.0; n]),
        ..Image::new(width, height)
    }
}

/// Adds one part's pixels into `merged` (the full image, see `empty_image`)
/// at its region, as if its samples had been added there. A pixel's first
/// part is copied as it is, so regions assemble exactly.
pub fn add_part(merged: &mut Image, image: &Image, header: &RenderHeader) -> anyhow::Result<()> {
    let (Some(variance), Some(samples)) = (&image.variance, &image.samples) else {
        bail!("no variance or samples channel: cannot merge it exactly");
    };
    // The depth layer keeps no count of the samples that hit something, so
    // AOVs cannot be merged exactly; refuse rather than drop them unsaid.
    anyhow::ensure!(
        image.aovs.is_empty(),
        "it has auxiliary output layers (--aov), which vkpt merge cannot join yet: render the \
         parts without --aov"
    );
    let r = header.region;
    anyhow::ensure!(
        (image.width, image.height) == (r.width(), r.height())
            && r.x1 <= merged.width
            && r.y1 <= merged.height,
        "{}x{} pixels for region {r}",
        image.width,
        image.height
    );
    let (Some(acc_variance), Some(acc_samples)) = (&mut merged.variance, &mut merged.samples)
    else {
        bail!("the merged image keeps no variance or sample counts");
    };
    let most = header.samples.len() as f32;
    for y in 0..r.height() {
        for x in 0..r.width() {
            let i = image.index(x, y);
            let n = samples[i];
            if !(n >= 0.0 && n <= most && n.fract() == 0.0) {
                bail!(
                    "pixel ({}, {}) counts {n} samples, but the part holds {}..{}",
                    r.x0 + x,
                    r.y0 + y,
                    header.samples.start,
                    header.samples.end
                );
            }
            let at = (r.y0 + y) as usize * merged.width as usize + (r.x0 + x) as usize;
            let mut acc = Moments {
                mean: merged.mean[at],
                variance: acc_variance[at],
                n: acc_samples[at],
            };
            acc.add(&Moments {
                mean: image.mean[i],
                variance: variance[i],
                n,
            });
            (merged.mean[at], acc_variance[at], acc_samples[at]) = (acc.mean, acc.variance, acc.n);
        }
    }
    Ok(())
}

/// A pixel as an EXR stores it: the mean of its samples, the variance of
/// that mean (`Film::to_image`: m2 / (n - 1) / n, infinite below two
/// samples) and the sample count.
struct Moments {
    mean: [f32; 3],
    variance: [f32; 3],
    n: f32,
}

impl Moments {
    /// Combines `other`'s samples into these (Chan et al.'s update in f64,
    /// as `film_merge_pixel`), with m2 recovered as variance * n * (n - 1)
    /// (0 for one sample). Into an empty pixel it copies exactly.
    fn add(&mut self, other: &Moments) {
        if other.n == 0.0 {
            return;
        }
        if self.n == 0.0 {
            *self = Moments { ..*other };
            return;
        }
        let (na, nb) = (self.n as f64, other.n as f64);
        let n = na + nb;
        let m2 = |v: f32, k: f64| {
            if k < 2.0 {
                0.0
            } else {
                v as f64 * k * (k - 1.0)
            }
        };
        for c in 0..3 {
            let (ma, mb) = (self.mean[c] as f64, other.mean[c] as f64);
            let delta = mb - ma;
            let m2_sum = m2(self.variance[c], na)
                + m2(other.variance[c], nb)
                + delta * delta * (na * nb / n);
            self.mean[c] = (ma + delta * (nb / n)) as f32;
            self.variance[c] = (m2_sum.max(0.0) / (n - 1.0) / n) as f32;
        }
        self.n = n as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(region: &str, samples: Range<u32>) -> RenderHeader {
        RenderHeader {
            version: "0.1.0".into(),
            scene: "s.gltf".into(),
            scene_hash: "00".into(),
            camera: "c".into(),
            width: 8,
            height: 4,
            region: Region::parse(region).unwrap(),
            samples,
            seed: 0,
            sampler: "sobol".into(),
            filter: "box 0.5".into(),
            max_depth: None,
            backend: "cpu".into(),
        }
    }

    fn plan_of(parts: &[RenderHeader], holes: bool) -> anyhow::Result<Plan> {
        let names: Vec<PathBuf> = (0..parts.len())
            .map(|i| PathBuf::from(format!("p{i}.exr")))
            .collect();
        let list: Vec<(&Path, &RenderHeader)> =
            names.iter().map(|p| p.as_path()).zip(parts).collect();
        plan(&list, holes)
    }

    #[test]
    fn merge_plan_joins_ranges_and_regions() {
        let full = "0,0,8,4";
        let p = plan_of(&[header(full, 8..16), header(full, 0..8)], false).unwrap();
        assert_eq!(p.header.samples, 0..16);
        assert_eq!((p.holes, p.regions), (0, 1));
        let quads = [
            header("0,0,4,2", 0..4),
            header("4,0,8,2", 0..4),
            header("0,2,4,4", 0..2),
            header("0,2,4,4", 2..4),
            header("4,2,8,4", 0..4),
        ];
        let p = plan_of(&quads, false).unwrap();
        assert_eq!((p.header.samples.clone(), p.regions), (0..4, 4));
        assert_eq!(p.header.region, Region::full(8, 4));
    }

    #[test]
    fn merge_plan_refuses_with_one_line() {
        let full = "0,0,8,4";
        let err = |parts: &[RenderHeader], holes| {
            let e = plan_of(parts, holes).err().expect("refused");
            let text = format!("{e:#}");
            assert!(!text.contains('\n'), "{text}");
            text
        };
        let seeded = RenderHeader {
            seed: 1,
            ..header(full, 8..16)
        };
        assert_eq!(
            err(&[header(full, 0..8), seeded], false),
            "cannot merge p1.exr with p0.exr: they render different images (seed: 0 vs 1)"
        );
        assert_eq!(
            err(&[header(full, 0..8), header(full, 4..12)], false),
            "sample ranges 0..8 (p0.exr) and 4..12 (p1.exr) of region 0,0,8,4 overlap"
        );
        assert_eq!(
            err(&[header(full, 0..8), header(full, 9..12)], false),
            "samples 8..9 of region 0,0,8,4 are in no part (between p0.exr and p1.exr)"
        );
        assert_eq!(
            err(&[header("0,0,5,4", 0..8), header("4,0,8,4", 0..8)], false),
            "regions 0,0,5,4 (p0.exr) and 4,0,8,4 (p1.exr) overlap"
        );
        let missing = [header("0,0,4,4", 0..8), header("4,0,8,2", 0..8)];
        assert_eq!(
            err(&missing, false),
            "the parts leave 8 pixels of the 8x4 image uncovered, the first at (4, 2): a region \
             is missing (or merge with --allow-holes)"
        );
        assert_eq!(plan_of(&missing, true).unwrap().holes, 8);
        assert!(
            err(&[header("0,0,4,4", 0..8), header("4,0,8,4", 0..4)], false)
                .ends_with("holds 0..8: a part is missing")
        );
    }

    use crate::film::Film;

    #[test]
    fn merge_adds_parts_as_one_film() {
        // Samples split over two parts and two regions give the film of all.
        let mut whole = Film::new(2, 1);
        let mut left_a = Film::new(1, 1);
        let mut left_b = Film::new(1, 1);
        let mut right = Film::new(1, 1);
        for s in 0..10 {
            let v = [s as f32 * 0.3, (s * s) as f32, 1.0];
            whole.add_sample(0, v);
            whole.add_sample(1, [v[1], v[0], 2.0]);
            if s < 4 { &mut left_a } else { &mut left_b }.add_sample(0, v);
            right.add_sample(0, [v[1], v[0], 2.0]);
        }
        let header = |region, samples| RenderHeader {
            width: 2,
            height: 1,
            ..header(region, samples)
        };
        let mut merged = empty_image(2, 1);
        add_part(&mut merged, &left_a.to_image(), &header("0,0,1,1", 0..4)).unwrap();
        add_part(&mut merged, &left_b.to_image(), &header("0,0,1,1", 4..10)).unwrap();
        let right = right.to_image();
        add_part(&mut merged, &right, &header("1,0,2,1", 0..10)).unwrap();
        let whole = whole.to_image();
        assert_eq!(merged.samples, whole.samples);
        let (mv, wv) = (merged.variance.as_ref().unwrap(), whole.variance.unwrap());
        for i in 0..2 {
            for c in 0..3 {
                let (m, w) = (merged.mean[i][c], whole.mean[i][c]);
                assert!((m - w).abs() <= 1e-6 * w.abs().max(1.0), "mean {m} vs {w}");
                assert!((mv[i][c] - wv[i][c]).abs() <= 1e-5 * wv[i][c].abs().max(1e-6));
            }
        }
        // A pixel's only part is copied bit for bit.
        assert_eq!(merged.mean[1], right.mean[0]);
        assert_eq!(mv[1], right.variance.as_ref().unwrap()[0]);
        // A part claiming fewer samples than its pixels count is refused.
        let err = add_part(&mut merged, &left_b.to_image(), &header("0,0,1,1", 4..8));
        assert!(format!("{:#}", err.unwrap_err()).contains("counts 6 samples"));
    }
}
