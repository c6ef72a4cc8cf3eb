//! `KHR_draco_mesh_compression`: a primitive whose extension names a
//! bufferView of Draco data and, per attribute semantic, the Draco
//! attribute id that holds it. The Draco mesh (decoded by
//! `draco-oxide-decoder`, pure Rust) gives per-point values and triangles;
//! each attribute the extension lists becomes a new accessor over the
//! decoded buffer with the Draco data's component type (f32 for quantized
//! positions, normals and UVs: the decoder dequantizes them; integers for
//! joints and colours, normalized as the file's accessor says), and the
//! triangles a new u32 index accessor. The primitive is pointed at them;
//! the file's own accessors (without bufferView) are left unread.

use super::buffer::Buffer;
use super::compressed::{Decoded, no_panic, object, view_slice};
use super::document::name_of;
use anyhow::{Context, Result, anyhow, bail, ensure};
use draco_oxide_core::attribute::ComponentDataType as C;
use draco_oxide_core::mesh::Mesh;
use gltf::json::Value;

/// Decodes every Draco-compressed primitive of `json` into `decoded` and
/// points it at new accessors; returns how many were decoded.
pub(super) fn decode_primitives(
    json: &mut Value,
    buffers: &[Buffer],
    decoded: &mut Decoded,
) -> Result<usize> {
    let meshes = json
        .get("meshes")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let mut done = 0;
    for m in 0..meshes {
        let prims = json["meshes"][m]
            .get("primitives")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        for p in 0..prims {
            let prim = &json["meshes"][m]["primitives"][p];
            let Some(ext) = prim
                .get("extensions")
                .and_then(|e| e.get("KHR_draco_mesh_compression"))
                .cloned()
            else {
                continue;
            };
            let label = format!(
                "mesh #{m}{} primitive #{p}: KHR_draco_mesh_compression",
                name_of(&json["meshes"][m])
            );
            decode_primitive(json, (m, p), &ext, buffers, decoded).context(label)?;
            done += 1;
        }
    }
    Ok(done)
}

/// The glTF componentType of a Draco component type, if glTF has one.
fn gltf_component_type(c: C) -> Option<u64> {
    Some(match c {
        C::I8 => 5120,
        C::U8 => 5121,
        C::I16 => 5122,
        C::U16 => 5123,
        C::U32 => 5125,
        C::F32 => 5126,
        _ => return None,
    })
}

fn components(kind: &str) -> Option<usize> {
    Some(match kind {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        _ => return None,
    })
}

fn decode_primitive(
    json: &mut Value,
    (m, p): (usize, usize),
    ext: &Value,
    buffers: &[Buffer],
    decoded: &mut Decoded,
) -> Result<()> {
    let v = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .ok_or_else(|| anyhow!("bufferView is missing or not a number"))? as usize;
    let bytes = view_slice(json, buffers, decoded, v)?;
    let mesh: Mesh = no_panic("Draco", || {
        draco_oxide_decoder::decode_mesh(bytes).map_err(|e| anyhow!("{e}"))
    })
    .with_context(|| format!("cannot decode bufferView #{v} ({} bytes)", bytes.len()))?;
    let points = mesh.attributes.iter().map(|a| a.len()).max().unwrap_or(0);
    ensure!(
        points > 0 && points <= u32::MAX as usize,
        "the Draco data has no vertices"
    );
    let mut indices = Vec::with_capacity(mesh.faces.len() * 3);
    for face in &mesh.faces {
        for &corner in face {
            let i = usize::from(corner);
            ensure!(
                i < points,
                "a triangle names vertex {i}, but the Draco data has {points}"
            );
            indices.extend_from_slice(&(i as u32).to_le_bytes());
        }
    }
    let wanted = ext
        .get("attributes")
        .and_then(Value::as_object)
        .ok_or_else(|| anyhow!("attributes is missing or not an object"))?;
    let mut accessors = Vec::new();
    for (semantic, id) in wanted {
        let id = id
            .as_u64()
            .ok_or_else(|| anyhow!("attribute {semantic}: id {id} is not a number"))?
            as usize;
        let attr = mesh
            .attributes
            .iter()
            .find(|a| a.get_id().as_usize() == id)
            .ok_or_else(|| {
                anyhow!("attribute {semantic}: Draco attribute id {id} is not in the data")
            })?;
        let original = json["meshes"][m]["primitives"][p]["attributes"]
            .get(semantic)
            .and_then(Value::as_u64)
            .and_then(|a| json.get("accessors")?.get(a as usize))
            .ok_or_else(|| anyhow!("attribute {semantic}: the primitive has no accessor for it"))?;
        let kind = original.get("type").and_then(Value::as_str).unwrap_or("");
        let n = attr.get_num_components();
        ensure!(
            components(kind) == Some(n),
            "attribute {semantic}: the Draco data has {n} components per vertex, the accessor's type is {kind:?}"
        );
        let ty = attr.get_component_type();
        let component_type = gltf_component_type(ty).ok_or_else(|| {
            anyhow!("attribute {semantic}: Draco component type {ty:?} has no glTF equivalent")
        })?;
        let elem = n * ty.size();
        let values = attr.get_data_as_bytes();
        let mut out = Vec::with_capacity(points * elem);
        let map = attr.point_map_as_slice();
        for point in 0..points {
            let value = match map {
                Some(map) => map.get(point).map(|&i| usize::from(i)),
                None => Some(point),
            };
            let bytes = value
                .and_then(|i| values.get(i * elem..(i + 1) * elem))
                .ok_or_else(|| {
                    anyhow!("attribute {semantic}: vertex {point} has no value in the Draco data")
                })?;
            out.extend_from_slice(bytes);
        }
        let normalized = ty != C::F32
            && original
                .get("normalized")
                .and_then(Value::as_bool)
                .unwrap_or(false);
        let view = decoded.push_view(&out, None);
        let mut accessor = object(&[
            ("bufferView", view.into()),
            ("componentType", component_type.into()),
            ("count", points.into()),
            ("type", kind.into()),
        ]);
        if let Value::Object(a) = &mut accessor {
            if normalized {
                a.insert("normalized".into(), true.into());
            }
            for bound in ["min", "max"] {
                if let Some(b) = original.get(bound) {
                    a.insert(bound.into(), b.clone());
                }
            }
        }
        accessors.push((semantic.clone(), accessor));
    }
    let view = decoded.push_view(&indices, None);
    accessors.push((
        "indices".into(),
        object(&[
            ("bufferView", view.into()),
            ("componentType", 5125.into()),
            ("count", (indices.len() / 4).into()),
            ("type", "SCALAR".into()),
        ]),
    ));

    // Point the primitive at the new accessors.
    let list = json
        .get_mut("accessors")
        .and_then(Value::as_array_mut)
        .ok_or_else(|| anyhow!("the file has no accessors"))?;
    let mut placed = Vec::new();
    for (semantic, accessor) in accessors {
        list.push(accessor);
        placed.push((semantic, list.len() - 1));
    }
    let prim = json["meshes"][m]["primitives"][p]
        .as_object_mut()
        .ok_or_else(|| anyhow!("the primitive is not an object"))?;
    for (semantic, index) in placed {
        if semantic == "indices" {
            prim.insert("indices".into(), index.into());
        } else if let Some(attrs) = prim.get_mut("attributes").and_then(Value::as_object_mut) {
            attrs.insert(semantic, index.into());
        } else {
            bail!("the primitive has no attributes");
        }
    }
    if let Some(exts) = prim.get_mut("extensions").and_then(Value::as_object_mut) {
        exts.remove("KHR_draco_mesh_compression");
    }
    Ok(())
}
