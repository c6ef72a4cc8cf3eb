//! The `gltf` crate's own checks (indices in range, enum values known,
//! required data present), run with vkpt's policy ([`tolerated`]): vkpt
//! keeps reading what it has always read leniently (cameras and lights are
//! checked when a node uses them, a texture whose image is missing is a
//! warning), leaves skins and morph targets to `skin.rs`, and does not
//! check what it never reads (attributes other than POSITION, NORMAL,
//! TANGENT, TEXCOORD_0/1, JOINTS and WEIGHTS, GPU binding hints, mipmap
//! filters); anything else the crate reports is an
//! error naming the element (`mesh #0 'tri' primitive #1: material:
//! material #3 does not exist (the file has 1)`) before anything is loaded.

use super::document::{NULL, name_of};
use anyhow::{Result, bail};
use gltf::json::validation::{Checked, Error as Problem, Validate};
use gltf::json::{self, Root, Value};

/// Refuses `root` (deserialized from `json`) if the crate's checks find a
/// problem vkpt does not tolerate; the error names the first and counts
/// the others.
pub(super) fn check(root: &Root, json: &Value) -> Result<()> {
    check_position_accessors(root, json)?;
    let mut problems = Vec::new();
    root.validate(root, json::Path::new, &mut |path, problem| {
        problems.push((path().0, problem))
    });
    let fatal: Vec<String> = problems
        .iter()
        .map(|(path, problem)| (segments(path), *problem))
        .filter(|(path, problem)| !tolerated(path, *problem))
        .map(|(path, problem)| describe(&path, problem, json))
        .collect();
    match fatal.as_slice() {
        [] => Ok(()),
        [one] => bail!("{one}"),
        [first, rest @ ..] => bail!("{first} (and {} more problems)", rest.len()),
    }
}

/// The crate's checks index `accessors` by each primitive's POSITION
/// without a bounds check: such an index is refused here first.
fn check_position_accessors(root: &Root, json: &Value) -> Result<()> {
    let position = Checked::Valid(json::mesh::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive.attributes.get(&position)
                && index.value() >= root.accessors.len()
            {
                let path = segments(&format!(
                    "meshes[{m}].primitives[{p}].attributes[\"POSITION\"]"
                ));
                bail!("{}", describe(&path, Problem::IndexOutOfBounds, json));
            }
        }
    }
    Ok(())
}

/// One step of a validation path: `.field`, `[index]` or `["key"]`.
#[derive(Clone, Debug, PartialEq)]
enum Seg {
    Field(String),
    Index(usize),
    Key(String),
}

/// The crate's path (`meshes[0].primitives[1].attributes["POSITION"]`) as
/// steps through the JSON. Fields after `extensions` are renamed from the
/// crate's Rust names to the extensions' names.
fn segments(path: &str) -> Vec<Seg> {
    let path = path.split(" = ").next().unwrap_or(path);
    let mut out = Vec::new();
    let mut rest = path;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('.') {
            rest = r;
        } else if let Some(r) = rest.strip_prefix("[\"") {
            let end = r.find("\"]").unwrap_or(r.len());
            out.push(Seg::Key(r[..end].to_string()));
            rest = r.get(end + 2..).unwrap_or("");
        } else if let Some(r) = rest.strip_prefix('[') {
            let end = r.find(']').unwrap_or(r.len());
            out.push(Seg::Index(r[..end].parse().unwrap_or(usize::MAX)));
            rest = r.get(end + 1..).unwrap_or("");
        } else {
            let end = rest.find(['.', '[']).unwrap_or(rest.len());
            let field = &rest[..end];
            let after_extensions = matches!(out.last(), Some(Seg::Field(f)) if f == "extensions");
            out.push(Seg::Field(if after_extensions {
                extension_name(field).to_string()
            } else {
                field.to_string()
            }));
            rest = &rest[end..];
        }
    }
    out
}

/// The glTF name of an extension the crate models, from its Rust name.
fn extension_name(field: &str) -> &str {
    match field {
        "khrLightsPunctual" => "KHR_lights_punctual",
        "transmission" => "KHR_materials_transmission",
        "ior" => "KHR_materials_ior",
        "volume" => "KHR_materials_volume",
        "specular" => "KHR_materials_specular",
        "emissiveStrength" => "KHR_materials_emissive_strength",
        "textureTransform" => "KHR_texture_transform",
        other => other,
    }
}

fn field(path: &[Seg], i: usize) -> Option<&str> {
    match path.get(i) {
        Some(Seg::Field(f)) => Some(f),
        _ => None,
    }
}

/// Attributes vkpt reads; problems with any other are never met.
const READ_ATTRIBUTES: [&str; 5] = ["POSITION", "NORMAL", "TANGENT", "TEXCOORD_0", "TEXCOORD_1"];

/// Problems the crate reports that vkpt does not treat as errors of the
/// whole file, because it handles them itself where it reads that part
/// (with the same errors and notes as before it used the crate) or never
/// reads that part at all.
fn tolerated(path: &[Seg], problem: Problem) -> bool {
    let top = field(path, 0).unwrap_or("");
    match top {
        // vkpt's own list (`extensions.rs`) was checked first.
        "extensionsRequired" => problem == Problem::Unsupported,
        // Checked by skin.rs when a skinned node is posed.
        "skins" => true,
        // Checked when a node uses the camera (`cameras.rs`).
        "cameras" => true,
        // Checked when a node uses the light (`lights.rs`).
        "extensions" => {
            field(path, 1) == Some("KHR_lights_punctual") && field(path, 2) == Some("lights")
        }
        // A texture's missing image and an image that cannot be read are
        // warnings (`textures.rs`, `images.rs`).
        "textures" => field(path, 2) == Some("source"),
        "images" => true,
        // Never read: GPU binding hints, and mipmapping (the samples per
        // pixel do the averaging).
        "bufferViews" => field(path, 2) == Some("target"),
        "samplers" => field(path, 2) == Some("minFilter"),
        // The accessors of a Draco-compressed primitive have no data of
        // their own (`draco.rs` gives the primitive new ones); an accessor
        // without data that is read is an error there (`data.rs`).
        "accessors" => field(path, 2) == Some("bufferView") && problem == Problem::Missing,
        "meshes" if field(path, 2) == Some("primitives") => {
            tolerated_in_primitive(path.get(4..).unwrap_or(&[]), problem)
        }
        _ => false,
    }
}

/// `path` below `meshes[m].primitives[p]`.
fn tolerated_in_primitive(path: &[Seg], problem: Problem) -> bool {
    match (field(path, 0), path.get(1)) {
        // Morph targets are ignored (the base shape is rendered).
        (Some("targets"), _) => true,
        (Some("attributes"), Some(Seg::Key(name))) if name == "POSITION" => {
            // Its min and max are never read; a primitive without one is
            // skipped with a note (`mesh.rs`).
            path.len() > 2 || problem == Problem::Missing
        }
        (Some("attributes"), Some(Seg::Key(name))) => !READ_ATTRIBUTES.contains(&name.as_str()),
        _ => false,
    }
}

/// The element a path starts in (`mesh #0 'tri' primitive #1`) and the
/// number of steps that name it.
fn element(path: &[Seg], json: &Value) -> (String, usize) {
    const NOUNS: [(&str, &str); 14] = [
        ("accessors", "accessor"),
        ("animations", "animation"),
        ("buffers", "buffer"),
        ("bufferViews", "bufferView"),
        ("cameras", "camera"),
        ("images", "image"),
        ("materials", "material"),
        ("meshes", "mesh"),
        ("nodes", "node"),
        ("samplers", "sampler"),
        ("scenes", "scene"),
        ("skins", "skin"),
        ("textures", "texture"),
        ("lights", "KHR_lights_punctual light"),
    ];
    let (start, kind) = match (field(path, 0), field(path, 1), field(path, 2)) {
        (Some("extensions"), Some("KHR_lights_punctual"), Some("lights")) => (2, "lights"),
        (Some(kind), ..) => (0, kind),
        _ => return (String::new(), 0),
    };
    let (Some(noun), Some(Seg::Index(i))) = (
        NOUNS.iter().find(|(k, _)| *k == kind).map(|(_, n)| *n),
        path.get(start + 1),
    ) else {
        return (String::new(), 0);
    };
    let name = name_of(lookup(json, &path[..start + 2]));
    let mut label = format!("{noun} #{i}{name}");
    let mut used = start + 2;
    if kind == "meshes"
        && field(path, used) == Some("primitives")
        && let Some(Seg::Index(p)) = path.get(used + 1)
    {
        label.push_str(&format!(" primitive #{p}"));
        used += 2;
    }
    (label, used)
}

/// The JSON value at `path`, or null.
fn lookup<'a>(json: &'a Value, path: &[Seg]) -> &'a Value {
    let mut v = json;
    for seg in path {
        v = match seg {
            Seg::Field(f) | Seg::Key(f) => v.get(f.as_str()),
            Seg::Index(i) => v.get(*i),
        }
        .unwrap_or(&NULL);
    }
    v
}

/// The collection an index property points into, as (top-level key, noun),
/// from the last property name on its path.
fn target(path: &[Seg]) -> Option<(&'static str, &'static str)> {
    let last = path.iter().rev().find_map(|s| match s {
        Seg::Field(f) => Some(f.as_str()),
        _ => None,
    })?;
    Some(match last {
        "mesh" => ("meshes", "mesh"),
        "camera" => ("cameras", "camera"),
        "skin" => ("skins", "skin"),
        "children" | "nodes" | "joints" | "skeleton" | "node" => ("nodes", "node"),
        "scene" => ("scenes", "scene"),
        "material" => ("materials", "material"),
        "attributes" | "indices" | "targets" | "inverseBindMatrices" | "input" | "output" => {
            ("accessors", "accessor")
        }
        "bufferView" => ("bufferViews", "bufferView"),
        "buffer" => ("buffers", "buffer"),
        "sampler" => ("samplers", "sampler"),
        "source" => ("images", "image"),
        "index" => ("textures", "texture"),
        "light" => ("lights", "KHR_lights_punctual light"),
        _ => return None,
    })
}

/// The values glTF allows for an enumerated property, by the names of the
/// property and its parent.
fn allowed(parent: Option<&str>, field: &str) -> Option<&'static str> {
    Some(match field {
        "alphaMode" => "OPAQUE, MASK or BLEND",
        "mode" => "0 (POINTS) to 6 (TRIANGLE_FAN)",
        "componentType" if parent == Some("indices") => "5121, 5123 or 5125",
        "componentType" => "5120, 5121, 5122, 5123, 5125 or 5126",
        "type" => "SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4",
        "wrapS" | "wrapT" => "33071, 33648 or 10497",
        "magFilter" => "9728 or 9729",
        "byteStride" => "4 to 252",
        _ => return None,
    })
}

/// One problem the crate found, in words, naming the element.
fn describe(path: &[Seg], problem: Problem, json: &Value) -> String {
    let (element, used) = element(path, json);
    let mut steps = &path[used..];
    // `baseColorTexture.index: texture #4` says it twice.
    if problem == Problem::IndexOutOfBounds
        && matches!(steps.last(), Some(Seg::Field(f)) if f == "index")
    {
        steps = &steps[..steps.len() - 1];
    }
    let what = steps
        .iter()
        .map(|s| match s {
            Seg::Field(f) | Seg::Key(f) => format!(".{f}"),
            Seg::Index(i) => format!("[{i}]"),
        })
        .collect::<String>();
    let what = what.trim_start_matches('.');
    let mut fields = steps.iter().rev().filter_map(|s| match s {
        Seg::Field(f) => Some(f.as_str()),
        _ => None,
    });
    let (last, parent) = (fields.next(), fields.next());
    let value = lookup(json, path);
    // `what: message`, or the message alone when the element itself is meant.
    let of = |message: String| {
        if what.is_empty() {
            message
        } else {
            format!("{what}: {message}")
        }
    };
    let message = match problem {
        Problem::IndexOutOfBounds => match target(path) {
            Some((key, noun)) => {
                let collection = if key == "lights" {
                    lookup(json, &segments("extensions.khrLightsPunctual.lights"))
                } else {
                    lookup(json, &[Seg::Field(key.to_string())])
                };
                let n = collection.as_array().map_or(0, Vec::len);
                let message = format!("{noun} #{value} does not exist (the file has {n})");
                // `mesh: mesh #3` says it twice too.
                if what.replace("extensions.", "").replace('.', " ") == noun {
                    message
                } else {
                    of(message)
                }
            }
            None => of(format!("index {value} is out of range")),
        },
        Problem::Invalid => match (value.is_null(), last.and_then(|f| allowed(parent, f))) {
            (true, _) => of("not valid".to_string()),
            (false, Some(allowed)) => of(format!("{value} is not valid (glTF allows {allowed})")),
            (false, None) => of(format!("{value} is not valid")),
        },
        Problem::Missing if what.is_empty() => "a required property is missing".to_string(),
        Problem::Missing => format!("{what} is missing"),
        Problem::Oversize => of(format!("{value} is too large for this machine")),
        Problem::Unsupported => of("not supported".to_string()),
    };
    if element.is_empty() {
        message
    } else {
        format!("{element}: {message}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One triangle's worth of glTF (no buffer data: only the structure is
    /// checked here), changed by `edit`.
    fn check_edited(edit: impl FnOnce(&mut Value)) -> Result<()> {
        let mut json: Value = json::deserialize::from_str(
            r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
                "nodes": [{"name": "n", "mesh": 0}],
                "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}}]}],
                "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
                "bufferViews": [{"buffer": 0, "byteLength": 36}],
                "buffers": [{"byteLength": 36}]}"#,
        )
        .unwrap();
        edit(&mut json);
        let root: Root = json::deserialize::from_value(json.clone()).unwrap();
        check(&root, &json)
    }

    #[test]
    fn crate_paths_become_steps_with_extension_names() {
        let f = |s: &str| Seg::Field(s.to_string());
        assert_eq!(
            segments("nodes[2].extensions.khrLightsPunctual.light"),
            [
                f("nodes"),
                Seg::Index(2),
                f("extensions"),
                f("KHR_lights_punctual"),
                f("light")
            ]
        );
        assert_eq!(
            segments(r#"meshes[0].primitives[1].attributes["POSITION"].min"#),
            [
                f("meshes"),
                Seg::Index(0),
                f("primitives"),
                Seg::Index(1),
                f("attributes"),
                Seg::Key("POSITION".to_string()),
                f("min")
            ]
        );
    }

    #[test]
    fn an_index_out_of_range_names_the_element_and_the_count() {
        let err = check_edited(|j| j["nodes"][0]["mesh"] = 3.into()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "node #0 'n': mesh #3 does not exist (the file has 1)"
        );
        let err = check_edited(|j| j["accessors"][0]["bufferView"] = 9.into()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "accessor #0: bufferView #9 does not exist (the file has 1)"
        );
    }

    #[test]
    fn an_unknown_enum_value_names_the_allowed_values() {
        let err = check_edited(|j| j["meshes"][0]["primitives"][0]["mode"] = 9.into()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "mesh #0 'tri' primitive #0: mode: 9 is not valid (glTF allows 0 (POINTS) to 6 (TRIANGLE_FAN))"
        );
    }

    #[test]
    fn a_position_accessor_past_the_end_is_an_error_not_a_panic() {
        // The crate's own check would index `accessors` with it.
        let err =
            check_edited(|j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7.into())
                .unwrap_err();
        assert!(
            err.to_string().contains("accessor #7 does not exist"),
            "{err}"
        );
    }

    #[test]
    fn what_vkpt_never_reads_is_not_checked() {
        // No POSITION min/max (above), a COLOR_0 past the accessors, a
        // bufferView target and a sampler minFilter that are not GL enums,
        // a skin with a joint past the nodes.
        check_edited(|j| {
            j["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 5.into();
            j["bufferViews"][0]["target"] = 7.into();
            j["samplers"] = json::deserialize::from_str(r#"[{"minFilter": 1}]"#).unwrap();
            j["skins"] = json::deserialize::from_str(r#"[{"joints": [9]}]"#).unwrap();
        })
        .unwrap();
    }
}
