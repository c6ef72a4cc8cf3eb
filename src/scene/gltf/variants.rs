//! `KHR_materials_variants`: one file, several material sets (a shoe in
//! three colourways). The root lists the variants by name; each primitive
//! maps variants to materials, and a primitive without a mapping for the
//! chosen variant keeps its own material, as the specification says.

use super::document::Gltf;
use super::json::array;
use super::notes::list;
use anyhow::{Result, bail, ensure};
use gltf::json::Value;

const EXT: &str = "KHR_materials_variants";

/// The variants' names, in file order.
fn variant_names(gltf: &Gltf) -> Vec<String> {
    let root = gltf.json.get("extensions").and_then(|e| e.get(EXT));
    root.map(|r| array(r, "variants"))
        .unwrap_or(&[])
        .iter()
        .enumerate()
        .map(|(i, v)| {
            v.get("name")
                .and_then(Value::as_str)
                .map_or_else(|| format!("#{i}"), str::to_string)
        })
        .collect()
}

/// The index of the variant the user asked for (`--variant NAME`; a name or
/// an index), after checking every primitive's mappings. Without a request
/// a file with variants renders its default materials, with a note.
pub(super) fn choose_variant(
    gltf: &Gltf,
    wanted: Option<&str>,
    notes: &mut Vec<String>,
) -> Result<Option<usize>> {
    let names = variant_names(gltf);
    check_mappings(gltf, names.len())?;
    let Some(wanted) = wanted else {
        if !names.is_empty() {
            notes.push(format!(
                "the file has material variants {}: rendering its default materials (pick one with --variant NAME)",
                list(&names)
            ));
        }
        return Ok(None);
    };
    ensure!(
        !names.is_empty(),
        "--variant {wanted}: the file has no material variants ({EXT})"
    );
    if let Some(i) = names.iter().position(|n| n == wanted) {
        return Ok(Some(i));
    }
    match wanted.parse::<usize>() {
        Ok(i) if i < names.len() => Ok(Some(i)),
        _ => bail!(
            "--variant {wanted}: no such variant; the file has {}",
            list(&names)
        ),
    }
}

/// Every primitive's mappings must name existing materials and variants.
fn check_mappings(gltf: &Gltf, n_variants: usize) -> Result<()> {
    let n_materials = array(&gltf.json, "materials").len();
    for (mi, mesh) in array(&gltf.json, "meshes").iter().enumerate() {
        for (pi, prim) in array(mesh, "primitives").iter().enumerate() {
            let Some(ext) = prim.get("extensions").and_then(|e| e.get(EXT)) else {
                continue;
            };
            let at = format!("mesh #{mi} primitive #{pi}: {EXT}");
            for (k, mapping) in array(ext, "mappings").iter().enumerate() {
                let material = mapping.get("material").and_then(Value::as_u64);
                ensure!(
                    material.is_some_and(|m| (m as usize) < n_materials),
                    "{at} mapping #{k}: material {} does not exist ({n_materials} materials)",
                    mapping.get("material").unwrap_or(&Value::Null)
                );
                for v in array(mapping, "variants") {
                    ensure!(
                        v.as_u64().is_some_and(|v| (v as usize) < n_variants),
                        "{at} mapping #{k}: variant {v} does not exist ({n_variants} variants)"
                    );
                }
            }
        }
    }
    Ok(())
}

/// The material primitive `prim` of mesh `mesh` uses under `variant`, if its
/// mappings name one (checked by [`choose_variant`]).
pub(super) fn variant_material(
    gltf: &Gltf,
    mesh: usize,
    prim: usize,
    variant: usize,
) -> Option<usize> {
    let prim = gltf.raw("meshes", mesh).get("primitives")?.get(prim)?;
    let ext = prim.get("extensions")?.get(EXT)?;
    array(ext, "mappings")
        .iter()
        .find(|m| {
            array(m, "variants")
                .iter()
                .any(|v| v.as_u64() == Some(variant as u64))
        })
        .and_then(|m| m.get("material")?.as_u64())
        .map(|m| m as usize)
}
