//! Extension policy: which extensions a file may require and still be
//! rendered, and which used extensions are reported as not rendered. The
//! extensions are looked up by name in the file's JSON, so those the
//! `gltf` crate does not model are found too.

use super::document::Gltf;
use super::json::array;
use super::notes::{Grouped, list};
use anyhow::{Result, ensure};
use gltf::json::Value;

/// Extensions a file may *require* and still be rendered meaningfully.
fn required_extension_supported(name: &str) -> bool {
    matches!(
        name,
        "KHR_materials_emissive_strength" | "KHR_lights_punctual" | "KHR_texture_transform"
    ) || name.starts_with("KHR_materials_")
        || READ_EXTENSIONS.contains(&name)
}

/// Extensions of the file's data (geometry and images) that vkpt reads:
/// `KHR_mesh_quantization`'s integer attributes are decoded by
/// `data.rs` like any accessor (normalized or not, as the extension
/// allows); Draco and meshopt data by `compressed.rs`; KTX2 (Basis
/// Universal) and WebP images by `images.rs`, chosen by `textures.rs`;
/// `EXT_mesh_gpu_instancing`'s placements by `instancing.rs`.
pub(super) const READ_EXTENSIONS: &[&str] = &[
    "EXT_mesh_gpu_instancing",
    "KHR_mesh_quantization",
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_texture_basisu",
    "EXT_texture_webp",
];

/// Refuses a file that requires an extension vkpt cannot render (read from
/// the JSON: it runs before the typed model is built).
pub(super) fn check_required(json: &Value) -> Result<()> {
    for ext in array(json, "extensionsRequired") {
        let name = ext.as_str().unwrap_or("?");
        ensure!(
            required_extension_supported(name),
            "the file requires extension {name}, which vkpt does not support"
        );
    }
    Ok(())
}

/// Notes extensions the file uses that nothing else reports.
pub(super) fn note_unused_extensions(gltf: &Gltf, notes: &mut Vec<String>) {
    for name in gltf.doc.extensions_used() {
        // By name, whether or not the crate models the extension.
        let on_a_material = array(&gltf.json, "materials")
            .iter()
            .any(|m| m.get("extensions").and_then(|e| e.get(name)).is_some());
        let reported_elsewhere = on_a_material
            || name == "KHR_materials_emissive_strength"
            || name == "KHR_lights_punctual"
            || name == "KHR_texture_transform"
            || name.starts_with("KHR_materials_")
            || READ_EXTENSIONS.contains(&name);
        if !reported_elsewhere {
            notes.push(format!("extension {name} is not supported: ignored"));
        }
    }
}

/// Material extensions a file uses that were not rendered, by extension.
#[derive(Default)]
pub(super) struct UnrenderedMaterialExtensions(Grouped);

impl UnrenderedMaterialExtensions {
    /// Records the extensions of material `m` (named `name`) other than
    /// `rendered` and the always-rendered emissive strength.
    pub fn add(&mut self, m: &Value, name: &str, rendered: &[&str]) {
        if let Some(Value::Object(exts)) = m.get("extensions") {
            for ext in exts.keys() {
                if ext != "KHR_materials_emissive_strength" && !rendered.contains(&ext.as_str()) {
                    self.0.add(ext.clone(), name.to_string());
                }
            }
        }
    }

    /// One note per extension, naming its materials.
    pub fn notes(self, notes: &mut Vec<String>) {
        for (ext, mats) in self.0.0 {
            notes.push(format!(
                "{ext} on {} {} is not rendered yet",
                if mats.len() == 1 {
                    "material"
                } else {
                    "materials"
                },
                list(&mats)
            ));
        }
    }
}
