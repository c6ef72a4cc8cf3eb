//! glTF cameras placed by their nodes, with the vkpt camera extras (thin
//! lens, shutter, ISO), read from the camera's JSON: the `gltf` crate
//! leaves `extras` unparsed.
//!
//! The extras, lengths in scene units (metres): `lens.fstop` N >= 0 (0 or
//! absent: a pinhole; the aperture's diameter is focal length / N),
//! `lens.focus_distance` along the view axis (> 0, required when N > 0),
//! `lens.focal_length` (when absent, derived from `yfov` and
//! `lens.sensor_height`, default 0.024, with a note; `yfov` always sets the
//! field of view, and a note says when both disagree by more than 1%),
//! `lens.blades` 0 (round) or 3 to 64 with `lens.blade_rotation` in
//! degrees, `shutter` (seconds) and `iso` (the PNG exposure). Command-line
//! flags override each value; unknown keys are notes, malformed values
//! errors naming the camera.

use super::document::Gltf;
use crate::scene::camera::{check_blades, check_length};
use crate::scene::{Camera, Projection};
use anyhow::{Context, Result, anyhow, bail, ensure};
use glam::{DMat4, DVec3, Vec3};
use gltf::json::Value;
use gltf::json::camera::Type;
use gltf::json::validation::Checked;

/// The camera on a node: perspective or orthographic, with its vkpt camera
/// extras.
pub(super) fn node_camera(
    gltf: &Gltf,
    cam: &gltf::Camera,
    node: &gltf::Node,
    world: &DMat4,
    notes: &mut Vec<String>,
) -> Result<Camera> {
    let ci = cam.index();
    let name = camera_name(cam, node);
    let label = format!("camera #{ci} '{name}'");
    let (projection, yfov, aspect_ratio) = projection(gltf, ci, &label)?;
    // `world` is relative to the world origin: the rendering camera sits at 0.
    let position = world.transform_point3(DVec3::ZERO).as_vec3();
    let forward = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
    let up_raw = world.transform_vector3(DVec3::Y);
    let up = (up_raw - forward * up_raw.dot(forward))
        .normalize_or_zero()
        .as_vec3();
    let forward = forward.as_vec3();
    ensure!(
        position.is_finite() && forward != Vec3::ZERO && up != Vec3::ZERO,
        "{label}: the node's world transform is degenerate (zero scale?)"
    );
    if let Projection::Orthographic { half_height } = projection {
        // Scale in the node's transform scales the view rectangle.
        let scale = world.transform_vector3(DVec3::Y).length() as f32;
        if (scale - 1.0).abs() > 1e-4 {
            notes.push(format!(
                "{label}: the node's scale ({scale}) does not change the orthographic view height ({half_height} half height)"
            ));
        }
    }
    let mut camera = Camera {
        name,
        position,
        forward,
        up,
        yfov,
        aspect_ratio,
        projection,
        lens: Default::default(),
        filter: Default::default(),
        shutter: None,
        iso: None,
        framed_automatically: false,
    };
    camera_extras(gltf.raw("cameras", ci), &label, &mut camera, notes)?;
    camera.check_lens(notes).with_context(|| label.clone())?;
    Ok(camera)
}

/// The camera's name as `--camera` finds it: the camera's, else its
/// node's, else `camera #i`.
pub(super) fn camera_name(cam: &gltf::Camera, node: &gltf::Node) -> String {
    cam.name()
        .or(node.name())
        .map(str::to_string)
        .unwrap_or_else(|| format!("camera #{}", cam.index()))
}

/// Reads the vkpt camera extras (`cam` is the camera's JSON) into
/// `camera`.
fn camera_extras(
    cam: &Value,
    label: &str,
    camera: &mut Camera,
    notes: &mut Vec<String>,
) -> Result<()> {
    let Some(vkpt) = cam.get("extras").and_then(|e| e.get("vkpt")) else {
        return Ok(());
    };
    let obj = vkpt
        .as_object()
        .ok_or_else(|| anyhow!("{label}: extras \"vkpt\" must be an object, found {vkpt}"))?;
    let number = |v: &Value, what: &str| -> Result<f32> {
        v.as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite())
            .ok_or_else(|| anyhow!("{label}: extras vkpt.{what} must be a number, found {v}"))
    };
    for (key, v) in obj {
        match key.as_str() {
            "shutter" => {
                camera.shutter = Some(check_length(
                    &format!("{label}: extras vkpt.shutter (seconds)"),
                    number(v, "shutter")?,
                    false,
                )?)
            }
            "iso" => {
                camera.iso = Some(check_length(
                    &format!("{label}: extras vkpt.iso"),
                    number(v, "iso")?,
                    false,
                )?)
            }
            "lens" => {
                let lens_obj = v.as_object().ok_or_else(|| {
                    anyhow!("{label}: extras vkpt.lens must be an object, found {v}")
                })?;
                let lens = &mut camera.lens;
                for (k, x) in lens_obj {
                    let what = format!("{label}: extras vkpt.lens.{k}");
                    let n = number(x, &format!("lens.{k}"))?;
                    match k.as_str() {
                        "focal_length" => lens.focal_length = Some(check_length(&what, n, false)?),
                        "sensor_height" => {
                            lens.sensor_height = Some(check_length(&what, n, false)?)
                        }
                        "fstop" => lens.fstop = check_length(&what, n, true)?,
                        "focus_distance" => {
                            lens.focus_distance = Some(check_length(&what, n, false)?)
                        }
                        "blades" => {
                            ensure!(
                                n.fract() == 0.0 && n >= 0.0,
                                "{what} must be an integer, found {x}"
                            );
                            lens.blades = check_blades(&what, n as u32)?;
                        }
                        "blade_rotation" => lens.blade_rotation = n.to_radians(),
                        _ => notes.push(format!(
                            "{label}: extras vkpt.lens.{k} is not understood: ignored"
                        )),
                    }
                }
                if let (Some(f), Some(h), Projection::Perspective) =
                    (lens.focal_length, lens.sensor_height, camera.projection)
                {
                    let h_fov = 2.0 * f * (0.5 * camera.yfov).tan();
                    if (h_fov / h - 1.0).abs() > 0.01 {
                        notes.push(format!(
                            "{label}: a {:.1} mm lens on a {:.1} mm sensor would see {:.2}° but yfov is {:.2}°: yfov sets the field of view, the focal length only the aperture",
                            f * 1e3,
                            h * 1e3,
                            (2.0 * (0.5 * h / f).atan()).to_degrees(),
                            camera.yfov.to_degrees()
                        ));
                    }
                }
            }
            _ => notes.push(format!(
                "{label}: extras vkpt.{key} is not understood: ignored"
            )),
        }
    }
    Ok(())
}

/// Camera `ci`'s projection, vertical field of view (0 for orthographic)
/// and aspect ratio. Read from the crate's typed JSON: `Camera::projection`
/// panics when the projection the type names is absent, which vkpt reports
/// as an error naming the camera.
fn projection(gltf: &Gltf, ci: usize, label: &str) -> Result<(Projection, f32, Option<f32>)> {
    let cam = gltf
        .doc
        .as_json()
        .cameras
        .get(ci)
        .ok_or_else(|| anyhow!("{label} does not exist"))?;
    Ok(match cam.type_ {
        Checked::Valid(Type::Perspective) => {
            let persp = cam
                .perspective
                .as_ref()
                .ok_or_else(|| anyhow!("{label}: perspective parameters are missing"))?;
            let yfov = persp.yfov;
            ensure!(
                yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI,
                "{label}: yfov must be a number of radians in (0, pi)"
            );
            let aspect = match persp.aspect_ratio {
                Some(a) if !(a.is_finite() && a > 0.0) => {
                    bail!("{label}: aspectRatio must be a positive number, found {a}")
                }
                a => a,
            };
            (Projection::Perspective, yfov, aspect)
        }
        Checked::Valid(Type::Orthographic) => {
            let ortho = cam
                .orthographic
                .as_ref()
                .ok_or_else(|| anyhow!("{label}: orthographic parameters are missing"))?;
            // glTF: xmag and ymag must not be 0 and should not be negative;
            // a negative one is used as its magnitude.
            let mag = |key: &str, v: f32| -> Result<f32> {
                let v = v.abs();
                ensure!(
                    v.is_finite() && v > 0.0,
                    "{label}: orthographic.{key} must be a non-zero number"
                );
                Ok(v)
            };
            let (xmag, ymag) = (mag("xmag", ortho.xmag)?, mag("ymag", ortho.ymag)?);
            (
                Projection::Orthographic { half_height: ymag },
                0.0,
                Some(xmag / ymag),
            )
        }
        Checked::Invalid => {
            let type_ = gltf.raw("cameras", ci).get("type");
            bail!(
                "{label}: unknown camera type {:?}",
                type_.and_then(Value::as_str).unwrap_or("")
            )
        }
    })
}
