//! `KHR_lights_punctual` lights placed by their nodes, with the vkpt light
//! extras (`extras.vkpt`, read from the light's JSON): `radius` makes a
//! point light a sphere of the same radiant intensity, `angular_diameter`
//! (radians) a directional light a sun disk of the same irradiance.
//!
//! A light is read from the crate's typed JSON rather than through
//! `khr_lights_punctual::Light::kind`, which panics on a spot light without
//! its `spot` object: glTF requires it, but vkpt has always taken the
//! default cone angles (0 and pi/4) then.

use super::document::Gltf;
use super::json::finite;
use super::notes::name_suffix;
use crate::scene::{Light, LightKind};
use anyhow::{Result, anyhow, bail, ensure};
use glam::{DMat4, DVec3, Vec3};
use gltf::json::Value;
use gltf::json::extensions::scene::khr_lights_punctual::{Spot, Type};
use gltf::json::validation::Checked;

/// The light on a node, placed by the node's world transform.
pub(super) fn node_light(
    gltf: &Gltf,
    light: &gltf::khr_lights_punctual::Light,
    world: &DMat4,
    notes: &mut Vec<String>,
) -> Result<Light> {
    let li = light.index();
    let label = format!(
        "KHR_lights_punctual light #{li}{}",
        name_suffix(light.name())
    );
    let l = gltf
        .doc
        .as_json()
        .extensions
        .as_ref()
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .and_then(|e| e.lights.get(li))
        .ok_or_else(|| anyhow!("{label} does not exist"))?;
    let name = l.name.clone().unwrap_or_else(|| format!("light #{li}"));
    let color = Vec3::from(finite(l.color, &format!("{label}: color"))?);
    ensure!(
        color.min_element() >= 0.0,
        "{label}: color must be non-negative"
    );
    let number = |key: &str, v: f32| -> Result<f32> {
        ensure!(v.is_finite(), "{label}: {key} must be a number, found {v}");
        Ok(v)
    };
    let intensity = number("intensity", l.intensity)?;
    ensure!(
        intensity >= 0.0,
        "{label}: intensity must be non-negative, found {intensity}"
    );
    let range = l.range.map(|r| number("range", r)).transpose()?;
    if let Some(r) = range {
        ensure!(r > 0.0, "{label}: range must be above 0, found {r}");
    }
    let type_ = match l.type_ {
        Checked::Valid(Type::Point) => "point",
        Checked::Valid(Type::Spot) => "spot",
        Checked::Valid(Type::Directional) => "directional",
        Checked::Invalid => gltf
            .raw_light(li)
            .get("type")
            .and_then(Value::as_str)
            .unwrap_or(""),
    };
    let extras = gltf.raw_light(li).get("extras").and_then(|e| e.get("vkpt"));
    let kind = kind(type_, l.spot.as_ref(), extras, &label, notes)?;
    if matches!(kind, LightKind::Sphere { .. }) && range.is_some() {
        notes.push(format!(
            "{label}: range is not applied to a spherical light"
        ));
    }
    // `world` is relative to the world origin (subtracted in f64).
    let position = world.transform_point3(DVec3::ZERO).as_vec3();
    let direction = world
        .transform_vector3(DVec3::NEG_Z)
        .normalize_or_zero()
        .as_vec3();
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

/// What the light is, from its glTF type, its spot cone and its vkpt
/// extras (extras that do not apply to its type are reported).
fn kind(
    type_: &str,
    spot: Option<&Spot>,
    extras: Option<&Value>,
    label: &str,
    notes: &mut Vec<String>,
) -> Result<LightKind> {
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
            let (inner_cone, outer_cone) = spot.map_or((0.0, std::f32::consts::FRAC_PI_4), |s| {
                (s.inner_cone_angle, s.outer_cone_angle)
            });
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
    Ok(kind)
}
