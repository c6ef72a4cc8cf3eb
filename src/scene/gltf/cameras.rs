//! glTF cameras placed by their nodes, with the vkpt camera extras (thin
//! lens, shutter, ISO; see the README).

use super::data::{array, element};
use crate::scene::camera::{check_blades, check_length};
use crate::scene::{Camera, Projection};
use anyhow::{Context, Result, anyhow, bail, ensure};
use glam::{Mat4, Vec3};
use gltf::json::Value;

/// The camera on a node: perspective or orthographic, with its vkpt camera
/// extras.
pub(super) fn node_camera(
    json: &Value,
    ci: usize,
    node: &Value,
    world: &Mat4,
    notes: &mut Vec<String>,
) -> Result<Camera> {
    let cam = element(array(json, "cameras"), "camera", ci)?;
    let name = cam
        .get("name")
        .and_then(Value::as_str)
        .or_else(|| node.get("name").and_then(Value::as_str))
        .map(str::to_string)
        .unwrap_or_else(|| format!("camera #{ci}"));
    let label = format!("camera #{ci} '{name}'");
    let type_ = cam.get("type").and_then(Value::as_str).unwrap_or("");
    let positive = |v: Option<&Value>, what: &str| -> Result<Option<f32>> {
        match v {
            None | Some(Value::Null) => Ok(None),
            Some(v) => Ok(Some(
                v.as_f64()
                    .map(|f| f as f32)
                    .filter(|f| f.is_finite() && *f > 0.0)
                    .ok_or_else(|| {
                        anyhow!("{label}: {what} must be a positive number, found {v}")
                    })?,
            )),
        }
    };
    let (projection, yfov, aspect_ratio) = match type_ {
        "perspective" => {
            let persp = cam
                .get("perspective")
                .ok_or_else(|| anyhow!("{label}: perspective parameters are missing"))?;
            let yfov = persp
                .get("yfov")
                .and_then(Value::as_f64)
                .map(|f| f as f32)
                .filter(|f| f.is_finite() && *f > 0.0 && *f < std::f32::consts::PI)
                .ok_or_else(|| anyhow!("{label}: yfov must be a number of radians in (0, pi)"))?;
            let aspect = positive(persp.get("aspectRatio"), "aspectRatio")?;
            (Projection::Perspective, yfov, aspect)
        }
        "orthographic" => {
            let ortho = cam
                .get("orthographic")
                .ok_or_else(|| anyhow!("{label}: orthographic parameters are missing"))?;
            // glTF: xmag and ymag must not be 0 and should not be negative;
            // a negative one is used as its magnitude.
            let mag = |key: &str| -> Result<f32> {
                ortho
                    .get(key)
                    .and_then(Value::as_f64)
                    .map(|f| (f as f32).abs())
                    .filter(|f| f.is_finite() && *f > 0.0)
                    .ok_or_else(|| anyhow!("{label}: orthographic.{key} must be a non-zero number"))
            };
            let (xmag, ymag) = (mag("xmag")?, mag("ymag")?);
            (
                Projection::Orthographic { half_height: ymag },
                0.0,
                Some(xmag / ymag),
            )
        }
        _ => bail!("{label}: unknown camera type {type_:?}"),
    };
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up_raw = world.transform_vector3(Vec3::Y);
    let up = (up_raw - forward * up_raw.dot(forward)).normalize_or_zero();
    ensure!(
        position.is_finite() && forward != Vec3::ZERO && up != Vec3::ZERO,
        "{label}: the node's world transform is degenerate (zero scale?)"
    );
    if let Projection::Orthographic { half_height } = projection {
        // Scale in the node's transform scales the view rectangle.
        let scale = world.transform_vector3(Vec3::Y).length();
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
    };
    camera_extras(cam, &label, &mut camera, notes)?;
    camera.check_lens(notes).with_context(|| label.clone())?;
    Ok(camera)
}

/// Reads the vkpt camera extras (see "vkpt camera extras" above) into
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
