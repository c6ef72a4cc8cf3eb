//! Equirectangular environment maps (`.exr`, `.hdr`): loading and checking.
//! The sampling distribution is built in `packed.rs` (`env_distribution`).
//!
//! Convention: row 0 is the +Y pole; column u in [0, 1) is the azimuth
//! phi = 2 pi (u - 0.5) with direction (sin theta sin phi, cos theta,
//! -sin theta cos phi), so the map's centre faces -Z (where a default glTF
//! camera looks) and u grows toward +X.

use anyhow::{Context, Result, anyhow, bail, ensure};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Linear RGB radiance texels, row-major, row 0 at the top (+Y).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    pub source: PathBuf,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
}

impl EnvironmentMap {
    /// Loads an equirectangular map; every texel must be finite and
    /// non-negative, and the map at least 2x1 pixels.
    pub fn load(path: &Path) -> Result<EnvironmentMap> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        let (width, height, texels) = match ext.as_str() {
            "exr" => {
                let image = crate::image::read_exr(path)?;
                let texels = image.mean.iter().map(|&c| Vec3::from(c)).collect();
                (image.width, image.height, texels)
            }
            "hdr" => {
                let image = image::open(path)
                    .map_err(|e| anyhow!("{e}"))
                    .with_context(|| format!("cannot read environment map {}", path.display()))?
                    .to_rgb32f();
                let texels = image.pixels().map(|p| Vec3::from(p.0)).collect();
                (image.width(), image.height(), texels)
            }
            _ => bail!(
                "{}: environment maps must be .exr or .hdr (equirectangular)",
                path.display()
            ),
        };
        let map = EnvironmentMap {
            source: path.to_path_buf(),
            width,
            height,
            texels,
        };
        map.validate()?;
        Ok(map)
    }

    pub fn validate(&self) -> Result<()> {
        let name = self.source.display();
        ensure!(
            self.width >= 2 && self.height >= 1,
            "{name}: environment map is {}x{}, need at least 2x1 pixels",
            self.width,
            self.height
        );
        ensure!(
            self.width <= 16384 && self.height <= 8192,
            "{name}: environment map is {}x{}, above 16384x8192",
            self.width,
            self.height
        );
        ensure!(
            self.texels.len() == (self.width * self.height) as usize,
            "{name}: {} texels for {}x{}",
            self.texels.len(),
            self.width,
            self.height
        );
        if let Some(i) = self
            .texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            bail!(
                "{name}: pixel ({}, {}) is {:?}: environment radiance must be finite and non-negative",
                i as u32 % self.width,
                i as u32 / self.width,
                self.texels[i].to_array()
            );
        }
        Ok(())
    }
}
