//! The file's JSON as the `gltf` crate's typed [`Document`]: deserialized
//! (a file that does not fit the schema is an error naming the element and
//! property) and checked by `validation.rs`, so that the crate's accessors
//! cannot panic. The JSON is kept for what the crate does not model.

use super::extensions;
use super::notes::name_suffix;
use super::validation;
use anyhow::{Result, anyhow, bail, ensure};
use gltf::Document;
use gltf::json::{self, Root, Value};

/// A glTF file as the loader reads it.
pub(super) struct Gltf {
    /// The crate's typed document.
    pub doc: Document,
    /// The file's JSON, for what the crate does not model: vkpt's extras,
    /// extensions it does not know, and whether an optional property was
    /// given at all.
    pub json: Value,
    /// The `KHR_materials_variants` variant to render (`variants.rs`).
    pub variant: Option<usize>,
}

pub(super) static NULL: Value = Value::Null;

impl Gltf {
    /// Builds the typed document from the file's JSON.
    pub fn new(json: Value) -> Result<Gltf> {
        ensure!(
            json.is_object(),
            "the top-level JSON value is not an object"
        );
        // Both before the typed model: glTF 1.0 has another schema, and a
        // file needing an extension vkpt lacks is refused for that reason
        // whatever else its JSON holds.
        let version = json
            .get("asset")
            .and_then(|a| a.get("version"))
            .and_then(Value::as_str)
            .unwrap_or("");
        ensure!(
            version.starts_with("2."),
            "asset.version is {version:?}: vkpt reads glTF 2.0"
        );
        extensions::check_required(&json)?;
        let root = typed_root(&json)?;
        validation::check(&root, &json)?;
        Ok(Gltf {
            doc: Document::from_json_without_validation(root),
            json,
            variant: None,
        })
    }

    /// Replaces the file's JSON by `json` (the compressed geometry decoded
    /// into plain accessors, `compressed.rs`), checked as `new` checks it.
    pub fn replace_json(&mut self, json: Value) -> Result<()> {
        let root = typed_root(&json)?;
        validation::check(&root, &json)?;
        self.doc = Document::from_json_without_validation(root);
        self.json = json;
        Ok(())
    }

    /// The JSON of element `index` of the top-level array `kind`
    /// ("materials", "cameras", ...), or null.
    pub fn raw(&self, kind: &str, index: usize) -> &Value {
        self.json
            .get(kind)
            .and_then(|a| a.get(index))
            .unwrap_or(&NULL)
    }

    /// The JSON of `KHR_lights_punctual` light `index`, or null.
    pub fn raw_light(&self, index: usize) -> &Value {
        self.json
            .get("extensions")
            .and_then(|e| e.get("KHR_lights_punctual"))
            .and_then(|e| e.get("lights"))
            .and_then(|a| a.get(index))
            .unwrap_or(&NULL)
    }
}

/// Adapts a copy of the JSON to what the crate's types require where that
/// is more than vkpt needs, so that files vkpt has always read still load:
///
/// - a camera's clipping planes (`znear`, and `zfar` for an orthographic
///   camera), which glTF requires but a path tracer has no use for, get
///   placeholders that are never read;
/// - a scene without `nodes` (optional in glTF, required by the crate)
///   gets an empty list;
/// - animations are left out: `animation.rs` reads them from the JSON,
///   as the crate requires `target.node`, which glTF makes optional
///   (`KHR_animation_pointer` omits it).
fn fit_crate_schema(json: &mut Value) {
    if let Some(root) = json.as_object_mut() {
        root.remove("animations");
    }
    let cameras = json.get_mut("cameras").and_then(Value::as_array_mut);
    for camera in cameras.into_iter().flatten() {
        for (projection, planes) in [
            ("perspective", &["znear"][..]),
            ("orthographic", &["znear", "zfar"][..]),
        ] {
            if let Some(p) = camera.get_mut(projection).and_then(Value::as_object_mut) {
                for plane in planes {
                    p.entry(*plane).or_insert(Value::from(0.0));
                }
            }
        }
    }
    let scenes = json.get_mut("scenes").and_then(Value::as_array_mut);
    for scene in scenes.into_iter().flatten() {
        if let Some(scene) = scene.as_object_mut() {
            scene.entry("nodes").or_insert(Value::Array(Vec::new()));
        }
    }
}

/// Checks one element against the schema: the deserializer's error, if any.
type SchemaCheck = fn(Value) -> Option<String>;

macro_rules! schema_check {
    ($t:ty) => {
        |v| {
            json::deserialize::from_value::<$t>(v)
                .err()
                .map(|e| e.to_string())
        }
    };
}

/// The top-level arrays, the element type each holds and what messages
/// call one of them.
const ELEMENTS: [(&str, &str, SchemaCheck); 12] = [
    ("accessors", "accessor", schema_check!(json::Accessor)),
    ("buffers", "buffer", schema_check!(json::Buffer)),
    (
        "bufferViews",
        "bufferView",
        schema_check!(json::buffer::View),
    ),
    ("cameras", "camera", schema_check!(json::Camera)),
    ("images", "image", schema_check!(json::Image)),
    ("materials", "material", schema_check!(json::Material)),
    ("meshes", "mesh", schema_check!(json::Mesh)),
    ("nodes", "node", schema_check!(json::Node)),
    ("samplers", "sampler", schema_check!(json::texture::Sampler)),
    ("scenes", "scene", schema_check!(json::Scene)),
    ("skins", "skin", schema_check!(json::Skin)),
    ("textures", "texture", schema_check!(json::Texture)),
];

const LIGHT: SchemaCheck = schema_check!(json::extensions::scene::khr_lights_punctual::Light);

/// The crate's typed model of the file. When the JSON does not fit the
/// schema (a string where a number belongs, a missing required property),
/// the error names the element and, where it can, its property.
fn typed_root(json: &Value) -> Result<Root> {
    let mut filled = json.clone();
    fit_crate_schema(&mut filled);
    let whole = match json::deserialize::from_value::<Root>(filled.clone()) {
        Ok(root) => return Ok(root),
        Err(e) => e,
    };
    for (key, noun, check) in ELEMENTS {
        let items = filled.get(key).and_then(Value::as_array);
        for (i, item) in items.into_iter().flatten().enumerate() {
            if let Some(why) = check(item.clone()) {
                bail!(
                    "{noun} #{i}{}: {}",
                    name_of(item),
                    culprit(item, &check, why)
                );
            }
        }
    }
    let lights = filled
        .get("extensions")
        .and_then(|e| e.get("KHR_lights_punctual"))
        .and_then(|e| e.get("lights"))
        .and_then(Value::as_array);
    for (i, item) in lights.into_iter().flatten().enumerate() {
        if let Some(why) = LIGHT(item.clone()) {
            bail!(
                "KHR_lights_punctual light #{i}{}: {}",
                name_of(item),
                culprit(item, &LIGHT, why)
            );
        }
    }
    let root = |v: Value| {
        json::deserialize::from_value::<Root>(v)
            .err()
            .map(|e| e.to_string())
    };
    Err(anyhow!(
        "the JSON does not fit glTF 2.0's schema: {}",
        culprit(&filled, &root, whole.to_string())
    ))
}

/// `why`, prefixed by the property of `item` that causes it: the one
/// whose removal makes `item` fit the schema, or makes the schema miss
/// just that (required) property.
fn culprit(item: &Value, check: &dyn Fn(Value) -> Option<String>, why: String) -> String {
    let Some(object) = item.as_object() else {
        return why;
    };
    if why.starts_with("missing field") {
        return why;
    }
    for key in object.keys() {
        let mut without = object.clone();
        without.remove(key);
        match check(Value::Object(without)) {
            None => return format!("{key}: {why}"),
            Some(e) if e == format!("missing field `{key}`") => return format!("{key}: {why}"),
            Some(_) => {}
        }
    }
    why
}

pub(super) fn name_of(item: &Value) -> String {
    name_suffix(item.get("name").and_then(Value::as_str))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gltf(text: &str) -> Result<Gltf> {
        Gltf::new(json::deserialize::from_str(text).unwrap())
    }

    #[test]
    fn a_schema_error_names_the_element_and_its_property() {
        let err = gltf(
            r#"{"asset": {"version": "2.0"},
                "accessors": [{"componentType": 5126, "count": "three", "type": "VEC3"}]}"#,
        )
        .err()
        .unwrap();
        assert!(
            err.to_string()
                .starts_with("accessor #0: count: invalid type: string \"three\""),
            "{err}"
        );
        let err =
            gltf(r#"{"asset": {"version": "2.0"}, "nodes": [{"name": "n", "matrix": [1, 2]}]}"#)
                .err()
                .unwrap();
        assert_eq!(
            err.to_string(),
            "node #0 'n': matrix: invalid length 2, expected an array of length 16"
        );
    }

    #[test]
    fn what_the_crate_requires_beyond_vkpts_needs_may_be_missing() {
        // Cameras without clipping planes, a scene without nodes (optional
        // in glTF), an animation channel without a target node
        // (KHR_animation_pointer).
        gltf(
            r#"{"asset": {"version": "2.0"}, "scenes": [{}],
                "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5}},
                            {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1}}],
                "animations": [{"channels": [{"sampler": 0, "target": {"path": "rotation"}}],
                                "samplers": [{"input": 0, "output": 0}]}]}"#,
        )
        .unwrap();
    }
}
