//! `KHR_lights_punctual` lights placed by their nodes, with the vkpt light
//! extras that make a point light a sphere and a directional light a sun
//! disk (see the README).

use super::data::{array, element, name_suffix};
use super::json::f32_array;
use crate::scene::{Light, LightKind};
use anyhow::{Result, anyhow, bail, ensure};
use glam::{Mat4, Vec3};
use gltf::json::Value;

/// The KHR_lights_punctual light `li` placed by `node`'s world transform.
pub(super) fn node_light(
    json: &Value,
    li: usize,
    world: &Mat4,
    notes: &mut Vec<String>,
) -> Result<Light> {
    let lights = json
        .get("extensions")
        .and_then(|e| e.get("KHR_lights_punctual"))
        .map(|e| array(e, "lights"))
        .unwrap_or_default();
    let l = element(lights, "KHR_lights_punctual light", li)?;
    let name = l
        .get("name")
        .and_then(Value::as_str)
        .map(str::to_string)
        .unwrap_or_else(|| format!("light #{li}"));
    let label = format!("KHR_lights_punctual light #{li}{}", name_suffix(l));
    let number = |key: &str| -> Result<Option<f32>> {
        match l
            .get(key)
            .or_else(|| l.get("spot").and_then(|s| s.get(key)))
        {
            None | Some(Value::Null) => Ok(None),
            Some(v) => Ok(Some(
                v.as_f64()
                    .map(|f| f as f32)
                    .filter(|f| f.is_finite())
                    .ok_or_else(|| anyhow!("{label}: {key} must be a number, found {v}"))?,
            )),
        }
    };
    let color =
        Vec3::from(f32_array::<3>(l.get("color"), &format!("{label}: color"))?.unwrap_or([1.0; 3]));
    ensure!(
        color.min_element() >= 0.0,
        "{label}: color must be non-negative"
    );
    let intensity = number("intensity")?.unwrap_or(1.0);
    ensure!(
        intensity >= 0.0,
        "{label}: intensity must be non-negative, found {intensity}"
    );
    let range = number("range")?;
    if let Some(r) = range {
        ensure!(r > 0.0, "{label}: range must be above 0, found {r}");
    }
    let extras = l.get("extras").and_then(|e| e.get("vkpt"));
    let extra = |key: &str| -> Result<Option<f32>> {
        match extras.and_then(|v| v.get(key)) {
            None => Ok(None),
            Some(v) => Ok(Some(
                v.as_f64()
                    .map(|f| f as f32)
                    .filter(|f| f.is_finite() && *f >= 0.0)
                    .ok_or_else(|| {
                        anyhow!(
                            "{label}: extras vkpt.{key} must be a non-negative number, found {v}"
                        )
                    })?,
            )),
        }
    };
    let radius = extra("radius")?.filter(|&r| r > 0.0);
    let diameter = extra("angular_diameter")?.filter(|&d| d > 0.0);
    let type_ = l.get("type").and_then(Value::as_str).unwrap_or("");
    // Extras that do not apply to this type of light are reported.
    if let Some(obj) = extras.and_then(Value::as_object) {
        for key in obj.keys() {
            let applies = matches!(
                (type_, key.as_str()),
                ("point", "radius") | ("directional", "angular_diameter")
            );
            if !applies {
                notes.push(format!(
                    "{label}: extras vkpt.{key} does not apply to a {type_} light: ignored (vkpt reads radius on point lights, angular_diameter on directional ones)"
                ));
            }
        }
    }
    let kind = match type_ {
        "point" => match radius {
            Some(radius) => LightKind::Sphere { radius },
            None => LightKind::Point,
        },
        "spot" => {
            let inner_cone = number("innerConeAngle")?.unwrap_or(0.0);
            let outer_cone = number("outerConeAngle")?.unwrap_or(std::f32::consts::FRAC_PI_4);
            ensure!(
                0.0 <= inner_cone
                    && inner_cone < outer_cone
                    && outer_cone <= std::f32::consts::FRAC_PI_2,
                "{label}: spot cone angles must satisfy 0 <= innerConeAngle < outerConeAngle <= pi/2, found {inner_cone} and {outer_cone}"
            );
            LightKind::Spot {
                inner_cone,
                outer_cone,
            }
        }
        "directional" => match diameter {
            Some(d) => {
                ensure!(
                    d < std::f32::consts::PI,
                    "{label}: extras vkpt.angular_diameter must be below pi radians, found {d}"
                );
                LightKind::Sun {
                    angular_diameter: d,
                }
            }
            None => LightKind::Directional,
        },
        _ => bail!("{label}: unknown light type {type_:?} (point, spot or directional)"),
    };
    if matches!(kind, LightKind::Sphere { .. }) && range.is_some() {
        notes.push(format!(
            "{label}: range is not applied to a spherical light"
        ));
    }
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    ensure!(
        position.is_finite() && direction != Vec3::ZERO,
        "{label}: the node's world transform is degenerate (zero scale?)"
    );
    Ok(Light {
        name,
        kind,
        position,
        direction,
        color: color * intensity,
        range,
    })
}
