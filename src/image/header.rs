//! What a rendered EXR holds, written into its header as text attributes
//! (`vkpt.*`), so a part of a render split over machines can be checked
//! and merged (`vkpt merge`) without being told how it was made, and a
//! user can read it with any EXR tool (`exrheader`).

use super::Region;
use anyhow::{Context, bail};
use std::ops::Range;

/// The settings and provenance of a render (or of a merge of renders).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderHeader {
    /// vkpt's version (`CARGO_PKG_VERSION`).
    pub version: String,
    /// The scene file as given on the command line.
    pub scene: String,
    /// Hash (16 hex digits) of what the kernels read about the scene and the
    /// view that no other attribute names: geometry, materials, textures,
    /// lights, environment, camera and lens, after command-line overrides.
    pub scene_hash: String,
    /// The camera's name.
    pub camera: String,
    /// The full image's size; `region` is what this file's pixels cover.
    pub width: u32,
    pub height: u32,
    pub region: Region,
    /// Sample indices `start <= i < end` of every pixel.
    pub samples: Range<u32>,
    pub seed: u32,
    /// `sobol` or `independent`.
    pub sampler: String,
    /// Pixel filter and radius, e.g. `box 0.5`.
    pub filter: String,
    /// Longest path in segments, `None` for no limit.
    pub max_depth: Option<u32>,
    /// The back end(s) that rendered it.
    pub backend: String,
}

/// Attribute names, in the order they are written.
const NAMES: [&str; 13] = [
    "vkpt.version",
    "vkpt.scene",
    "vkpt.scene_hash",
    "vkpt.camera",
    "vkpt.image_size",
    "vkpt.region",
    "vkpt.samples",
    "vkpt.seed",
    "vkpt.sampler",
    "vkpt.filter",
    "vkpt.max_depth",
    "vkpt.backend",
    "vkpt.spp",
];

impl RenderHeader {
    /// `(name, value)` of every attribute. `vkpt.spp` (the sample count) is
    /// for readers; it is implied by `vkpt.samples`.
    pub fn attributes(&self) -> Vec<(&'static str, String)> {
        let values = [
            self.version.clone(),
            self.scene.clone(),
            self.scene_hash.clone(),
            self.camera.clone(),
            format!("{}x{}", self.width, self.height),
            self.region.to_string(),
            format!("{}..{}", self.samples.start, self.samples.end),
            self.seed.to_string(),
            self.sampler.clone(),
            self.filter.clone(),
            match self.max_depth {
                Some(d) => d.to_string(),
                None => "-1".into(),
            },
            self.backend.clone(),
            self.samples.len().to_string(),
        ];
        NAMES.into_iter().zip(values).collect()
    }

    /// Reads the attributes back through `get` (name to value). `Ok(None)`
    /// when there is no `vkpt.version` (not written by vkpt); an error names
    /// a missing or malformed attribute.
    pub fn from_attributes(get: impl Fn(&str) -> Option<String>) -> anyhow::Result<Option<Self>> {
        let Some(version) = get("vkpt.version") else {
            return Ok(None);
        };
        let text = |name: &str| get(name).with_context(|| format!("no header attribute {name}"));
        let parsed = |name: &str, ok: Option<()>, value: &str, form: &str| {
            if ok.is_none() {
                bail!("header attribute {name} is '{value}', expected {form}");
            }
            Ok(())
        };
        let size = text("vkpt.image_size")?;
        let (width, height) = match size.split_once('x') {
            Some((w, h)) => (w.parse().ok(), h.parse().ok()),
            None => (None, None),
        };
        parsed("vkpt.image_size", width.zip(height).map(drop), &size, "WxH")?;
        let region_text = text("vkpt.region")?;
        let region = Region::parse(&region_text);
        parsed("vkpt.region", region.map(drop), &region_text, "X0,Y0,X1,Y1")?;
        let samples_text = text("vkpt.samples")?;
        let samples = parse_range(&samples_text);
        parsed(
            "vkpt.samples",
            samples.clone().map(drop),
            &samples_text,
            "A..B",
        )?;
        let seed_text = text("vkpt.seed")?;
        let seed = seed_text.parse().ok();
        parsed("vkpt.seed", seed.map(drop), &seed_text, "a number")?;
        let depth_text = text("vkpt.max_depth")?;
        let max_depth = match depth_text.as_str() {
            "-1" => Some(None),
            d => d.parse().ok().map(Some),
        };
        parsed(
            "vkpt.max_depth",
            max_depth.map(drop),
            &depth_text,
            "-1 or a depth",
        )?;
        Ok(Some(RenderHeader {
            version,
            scene: text("vkpt.scene")?,
            scene_hash: text("vkpt.scene_hash")?,
            camera: text("vkpt.camera")?,
            width: width.unwrap_or_default(),
            height: height.unwrap_or_default(),
            region: region.unwrap_or(Region::full(0, 0)),
            samples: samples.unwrap_or(0..0),
            seed: seed.unwrap_or_default(),
            sampler: text("vkpt.sampler")?,
            filter: text("vkpt.filter")?,
            max_depth: max_depth.flatten(),
            backend: text("vkpt.backend")?,
        }))
    }

    /// The first setting in which `other` would render a different image
    /// from `self` (sample range, region, scene path and back end aside),
    /// as `what: this vs other`; `None` when they render the same image.
    pub fn differs_from(&self, other: &RenderHeader) -> Option<String> {
        let depth = |d: Option<u32>| d.map_or("no limit".to_string(), |d| d.to_string());
        let checks = [
            ("vkpt version", self.version.clone(), other.version.clone()),
            (
                "image size",
                format!("{}x{}", self.width, self.height),
                format!("{}x{}", other.width, other.height),
            ),
            ("seed", self.seed.to_string(), other.seed.to_string()),
            ("sampler", self.sampler.clone(), other.sampler.clone()),
            ("filter", self.filter.clone(), other.filter.clone()),
            ("max depth", depth(self.max_depth), depth(other.max_depth)),
            ("camera", self.camera.clone(), other.camera.clone()),
            (
                "scene content hash (geometry, materials, lights, environment or lens differ)",
                self.scene_hash.clone(),
                other.scene_hash.clone(),
            ),
        ];
        checks
            .into_iter()
            .find(|(_, a, b)| a != b)
            .map(|(what, a, b)| format!("{what}: {a} vs {b}"))
    }
}

/// `A..B` with A <= B.
pub fn parse_range(text: &str) -> Option<Range<u32>> {
    let (a, b) = text.split_once("..")?;
    let (a, b): (u32, u32) = (a.trim().parse().ok()?, b.trim().parse().ok()?);
    (a <= b).then_some(a..b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn header() -> RenderHeader {
        RenderHeader {
            version: "0.1.0".into(),
            scene: "scenes/cornell-box.gltf".into(),
            scene_hash: "0123456789abcdef".into(),
            camera: "main".into(),
            width: 64,
            height: 48,
            region: Region::parse("0,0,32,48").unwrap(),
            samples: 16..48,
            seed: 3,
            sampler: "sobol".into(),
            filter: "box 0.5".into(),
            max_depth: None,
            backend: "CPU reference (2 threads)".into(),
        }
    }

    #[test]
    fn header_attributes_round_trip() {
        let h = header();
        let map: HashMap<&str, String> = h.attributes().into_iter().collect();
        assert_eq!(map["vkpt.spp"], "32");
        let back = RenderHeader::from_attributes(|n| map.get(n).cloned()).unwrap();
        assert_eq!(back, Some(h.clone()));
        let limited = RenderHeader {
            max_depth: Some(4),
            ..h.clone()
        };
        let map: HashMap<&str, String> = limited.attributes().into_iter().collect();
        let back = RenderHeader::from_attributes(|n| map.get(n).cloned()).unwrap();
        assert_eq!(back.unwrap().max_depth, Some(4));
        assert_eq!(RenderHeader::from_attributes(|_| None).unwrap(), None);
    }

    #[test]
    fn header_names_a_malformed_attribute() {
        let mut map: HashMap<&str, String> = header().attributes().into_iter().collect();
        map.insert("vkpt.samples", "48..16".into());
        let err = RenderHeader::from_attributes(|n| map.get(n).cloned()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "header attribute vkpt.samples is '48..16', expected A..B"
        );
        map.remove("vkpt.seed");
        map.insert("vkpt.samples", "0..1".into());
        let err = RenderHeader::from_attributes(|n| map.get(n).cloned()).unwrap_err();
        assert_eq!(err.to_string(), "no header attribute vkpt.seed");
    }

    #[test]
    fn header_differences_name_the_setting() {
        let a = header();
        let other_part = RenderHeader {
            samples: 48..64,
            region: Region::full(64, 48),
            backend: "lavapipe".into(),
            scene: "/elsewhere/cornell-box.gltf".into(),
            ..a.clone()
        };
        assert_eq!(a.differs_from(&other_part), None);
        let b = RenderHeader {
            seed: 4,
            ..a.clone()
        };
        assert_eq!(a.differs_from(&b).as_deref(), Some("seed: 3 vs 4"));
        let c = RenderHeader {
            scene_hash: "fedcba9876543210".into(),
            ..a.clone()
        };
        assert!(
            a.differs_from(&c)
                .unwrap()
                .starts_with("scene content hash")
        );
    }
}
