//! The camera and sensor model: projection, thin lens with a round or
//! polygonal aperture, pixel reconstruction filter, and the shutter and ISO
//! that set exposure. Read from a glTF camera's `extras` (the schema is in
//! `gltf/cameras.rs` and docs/gltf-support.md, "vkpt extras") and
//! overridden from the command line by [`CameraOverrides`].
//!
//! Units are scene units (glTF: metres), the lens included: a 50 mm lens has
//! `focal_length` 0.05. The field of view is always the glTF camera's
//! (`yfov`, or `ymag` for an orthographic camera): focal length and f-number
//! set the aperture diameter, focal length / f-number, not the framing.

use anyhow::{Result, bail, ensure};

/// How rays leave the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Rays from the eye (or the aperture) through the image plane; the
    /// field of view is `Camera::yfov`.
    Perspective,
    /// Parallel rays along the view axis from a rectangle of half height
    /// `half_height` (glTF `ymag`) in scene units.
    Orthographic { half_height: f32 },
}

/// Sensor height assumed when a lens gives neither focal length nor sensor
/// size: the 24 mm of a full-frame ("35 mm") sensor.
pub const DEFAULT_SENSOR_HEIGHT: f32 = 0.024;

/// A thin lens. With `fstop` 0 the camera is a pinhole and the other
/// fields are unused.
#[derive(Clone, Debug, PartialEq)]
pub struct ThinLens {
    /// Focal length in scene units; when `None`, the focal length that gives
    /// `yfov` on a sensor of `sensor_height` (default 24 mm).
    pub focal_length: Option<f32>,
    /// Sensor height in scene units, used only to derive a missing focal
    /// length (`yfov` always sets the field of view).
    pub sensor_height: Option<f32>,
    /// f-number N: aperture diameter = focal length / N. 0 is a pinhole.
    pub fstop: f32,
    /// Distance along the view axis of the plane in sharp focus.
    pub focus_distance: Option<f32>,
    /// Straight aperture blades (a regular polygon); 0 means a circle.
    pub blades: u32,
    /// Angle of the first polygon vertex from the camera's right axis toward
    /// its up axis, radians.
    pub blade_rotation: f32,
}

impl Default for ThinLens {
    fn default() -> Self {
        ThinLens {
            focal_length: None,
            sensor_height: None,
            fstop: 0.0,
            focus_distance: None,
            blades: 0,
            blade_rotation: 0.0,
        }
    }
}

impl ThinLens {
    pub fn is_pinhole(&self) -> bool {
        self.fstop <= 0.0
    }

    /// The focal length, derived from the sensor height and `yfov` when not
    /// given.
    pub fn focal_length(&self, yfov: f32) -> f32 {
        self.focal_length.unwrap_or_else(|| {
            self.sensor_height.unwrap_or(DEFAULT_SENSOR_HEIGHT) / (2.0 * (0.5 * yfov).tan())
        })
    }

    /// Radius of the aperture's circumscribed circle: half of focal length /
    /// f-number (0 for a pinhole).
    pub fn aperture_radius(&self, yfov: f32) -> f32 {
        if self.is_pinhole() {
            0.0
        } else {
            0.5 * self.focal_length(yfov) / self.fstop
        }
    }
}

/// Pixel reconstruction filter profiles (`FILTER_*` on the GPU).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterKind {
    Box,
    Tent,
    Gaussian,
    BlackmanHarris,
}

impl FilterKind {
    pub const NAMES: [&'static str; 4] = ["box", "tent", "gaussian", "blackman-harris"];

    pub fn from_name(name: &str) -> Option<FilterKind> {
        match name {
            "box" => Some(FilterKind::Box),
            "tent" => Some(FilterKind::Tent),
            "gaussian" => Some(FilterKind::Gaussian),
            "blackman-harris" => Some(FilterKind::BlackmanHarris),
            _ => None,
        }
    }

    /// The name `from_name` reads.
    pub fn name(self) -> &'static str {
        match self {
            FilterKind::Box => "box",
            FilterKind::Tent => "tent",
            FilterKind::Gaussian => "gaussian",
            FilterKind::BlackmanHarris => "blackman-harris",
        }
    }

    /// Radius in pixels when none is given: box 0.5 (exactly the pixel),
    /// tent 1, Gaussian 1.5 (standard deviation radius / 3), Blackman-Harris 2.
    pub fn default_radius(self) -> f32 {
        match self {
            FilterKind::Box => 0.5,
            FilterKind::Tent => 1.0,
            FilterKind::Gaussian => 1.5,
            FilterKind::BlackmanHarris => 2.0,
        }
    }

    pub fn gpu_kind(self) -> u32 {
        use crate::constants::*;
        match self {
            FilterKind::Box => FILTER_BOX,
            FilterKind::Tent => FILTER_TENT,
            FilterKind::Gaussian => FILTER_GAUSSIAN,
            FilterKind::BlackmanHarris => FILTER_BLACKMAN_HARRIS,
        }
    }
}

/// A separable pixel filter of `radius` pixels around each pixel centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelFilter {
    pub kind: FilterKind,
    pub radius: f32,
}

impl Default for PixelFilter {
    fn default() -> Self {
        PixelFilter {
            kind: FilterKind::Box,
            radius: FilterKind::Box.default_radius(),
        }
    }
}

/// Camera settings from the command line; each replaces what the file says.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CameraOverrides {
    pub fstop: Option<f32>,
    pub focus_distance: Option<f32>,
    pub focal_length: Option<f32>,
    pub blades: Option<u32>,
    /// Degrees.
    pub blade_rotation: Option<f32>,
    pub filter: Option<FilterKind>,
    pub filter_radius: Option<f32>,
    pub shutter: Option<f32>,
    pub iso: Option<f32>,
}

/// Checks a lens parameter: finite and positive (or non-negative).
pub fn check_length(what: &str, v: f32, allow_zero: bool) -> Result<f32> {
    let ok = v.is_finite() && (v > 0.0 || (allow_zero && v == 0.0));
    ensure!(
        ok,
        "{what} must be a {} number, got {v}",
        if allow_zero {
            "non-negative"
        } else {
            "positive"
        }
    );
    Ok(v)
}

/// Checks a blade count: 0 (a circle) or 3 to 64.
pub fn check_blades(what: &str, n: u32) -> Result<u32> {
    ensure!(
        n == 0 || (3..=64).contains(&n),
        "{what} must be 0 (a round aperture) or 3 to 64 blades, got {n}"
    );
    Ok(n)
}

impl CameraOverrides {
    /// Checks every value on its own (a usage error before any scene is
    /// loaded); whether the lens as a whole works is checked by `apply`.
    pub fn validate(&self) -> Result<()> {
        let mut camera = super::auto_camera::frame_sphere(glam::Vec3::ZERO, 1.0);
        self.set(&mut camera)
    }

    /// Applies the overrides to `camera`; returns the notes to print.
    pub fn apply(&self, camera: &mut super::Camera) -> Result<Vec<String>> {
        let mut notes = Vec::new();
        self.set(camera)?;
        camera.check_lens(&mut notes)?;
        Ok(notes)
    }

    fn set(&self, camera: &mut super::Camera) -> Result<()> {
        let lens = &mut camera.lens;
        if let Some(v) = self.fstop {
            lens.fstop = check_length("f-number", v, true)?;
        }
        if let Some(v) = self.focus_distance {
            lens.focus_distance = Some(check_length("focus distance", v, false)?);
        }
        if let Some(v) = self.focal_length {
            lens.focal_length = Some(check_length("focal length", v, false)?);
        }
        if let Some(n) = self.blades {
            lens.blades = check_blades("blade count", n)?;
        }
        if let Some(deg) = self.blade_rotation {
            ensure!(
                deg.is_finite(),
                "the blade rotation must be a number of degrees"
            );
            lens.blade_rotation = deg.to_radians();
        }
        if let Some(kind) = self.filter {
            camera.filter = PixelFilter {
                kind,
                radius: kind.default_radius(),
            };
        }
        if let Some(r) = self.filter_radius {
            camera.filter.radius = check_length("filter radius", r, false)?;
        }
        if let Some(t) = self.shutter {
            camera.shutter = Some(check_length("shutter time", t, false)?);
        }
        if let Some(s) = self.iso {
            camera.iso = Some(check_length("ISO", s, false)?);
        }
        Ok(())
    }
}

impl super::Camera {
    /// Checks that the lens can be rendered and says what was decided for
    /// the user (a derived focal length, a lens on an orthographic camera).
    pub fn check_lens(&self, notes: &mut Vec<String>) -> Result<()> {
        let lens = &self.lens;
        if lens.is_pinhole() {
            return Ok(());
        }
        if let Projection::Orthographic { .. } = self.projection {
            notes.push(format!(
                "camera '{}' is orthographic: its lens (f/{}) is ignored, everything is in focus",
                self.name, lens.fstop
            ));
            return Ok(());
        }
        let Some(_) = lens.focus_distance else {
            bail!(
                "camera '{}' has f-number {} but no focus distance: give it a focus distance (extras vkpt.lens.focus_distance, or CameraOverrides::focus_distance)",
                self.name,
                lens.fstop
            );
        };
        if lens.focal_length.is_none() {
            notes.push(format!(
                "camera '{}': no focal length given; {:.1} mm from the {:.1} mm sensor height and yfov {:.2}° (aperture {:.2} mm at f/{})",
                self.name,
                lens.focal_length(self.yfov) * 1e3,
                lens.sensor_height.unwrap_or(DEFAULT_SENSOR_HEIGHT) * 1e3,
                self.yfov.to_degrees(),
                2.0 * lens.aperture_radius(self.yfov) * 1e3,
                lens.fstop
            ));
        }
        Ok(())
    }
}

/// The index of the camera `wanted` names among cameras named `names` (in
/// `Scene::cameras` order): a name first, else an index; `None` when
/// neither matches. The command line's `--camera` and the loader's choice
/// of the world origin ([`super::LoadOptions::camera`]) both use it.
pub fn find_camera<'a>(names: impl IntoIterator<Item = &'a str>, wanted: &str) -> Option<usize> {
    let names: Vec<&str> = names.into_iter().collect();
    if let Some(i) = names.iter().position(|n| *n == wanted) {
        return Some(i);
    }
    wanted.parse::<usize>().ok().filter(|&i| i < names.len())
}
