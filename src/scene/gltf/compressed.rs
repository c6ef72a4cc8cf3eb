//! Compressed geometry, decoded once when the file is read:
//! `EXT_meshopt_compression` bufferViews (`meshopt.rs`) and
//! `KHR_draco_mesh_compression` primitives (`draco.rs`). The decoded bytes
//! go into one buffer appended after the file's, and the file's JSON is
//! rewritten to read them as plain accessors (a meshopt view points into
//! it; a Draco primitive's attributes and indices become new accessors
//! over it). Everything downstream (`data.rs`, `mesh.rs`, `skin.rs`,
//! `animation.rs`) then reads ordinary glTF. The edits are made on a copy:
//! a file with one bad compressed buffer is refused whole, naming it.

use super::buffer::Buffer;
use super::decoder_panic::catch_quietly;
use super::document::Gltf;
use super::draco;
use super::meshopt;
use super::notes::plural;
use anyhow::{Result, anyhow};
use gltf::json::Value;

/// The decoded data of a file and the bufferViews over it.
pub(super) struct Decoded {
    /// Index of the buffer `data` becomes.
    pub buffer: usize,
    pub data: Vec<u8>,
    /// Index the first of `views` will have.
    pub first_view: usize,
    pub views: Vec<Value>,
}

impl Decoded {
    /// Appends `bytes` (4-byte aligned) with a new view over them; returns
    /// the view's index.
    pub fn push_view(&mut self, bytes: &[u8], stride: Option<usize>) -> usize {
        let at = self.place(bytes);
        let mut view = object(&[
            ("buffer", self.buffer.into()),
            ("byteOffset", at.into()),
            ("byteLength", bytes.len().into()),
        ]);
        if let (Some(stride), Value::Object(v)) = (stride, &mut view) {
            v.insert("byteStride".into(), stride.into());
        }
        self.views.push(view);
        self.first_view + self.views.len() - 1
    }

    /// Appends `bytes` (4-byte aligned); returns their offset.
    pub fn place(&mut self, bytes: &[u8]) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let at = self.data.len();
        self.data.extend_from_slice(bytes);
        at
    }
}

/// A JSON object of `fields`.
pub(super) fn object(fields: &[(&str, Value)]) -> Value {
    let mut value = Value::Object(Default::default());
    if let Value::Object(o) = &mut value {
        for (k, v) in fields {
            o.insert(k.to_string(), v.clone());
        }
    }
    value
}

/// Takes the top-level array `key` out of `json` (empty when absent).
fn take_array(json: &mut Value, key: &str) -> Result<Vec<Value>> {
    let root = json
        .as_object_mut()
        .ok_or_else(|| anyhow!("the top-level JSON value is not an object"))?;
    match root.remove(key) {
        None => Ok(Vec::new()),
        Some(Value::Array(a)) => Ok(a),
        Some(_) => Err(anyhow!("{key} is not an array")),
    }
}

/// The bytes of bufferView `v` as the JSON describes it, checked against
/// its buffer (one of the file's, or the decoded one).
pub(super) fn view_slice<'a>(
    json: &Value,
    buffers: &'a [Buffer],
    decoded: &'a Decoded,
    v: usize,
) -> Result<&'a [u8]> {
    let view = json
        .get("bufferViews")
        .and_then(|a| a.get(v))
        .ok_or_else(|| anyhow!("bufferView #{v} does not exist"))?;
    let field = |k: &str| view.get(k).and_then(Value::as_u64).map(|x| x as usize);
    let b = field("buffer").ok_or_else(|| anyhow!("bufferView #{v} has no buffer"))?;
    let buffer: &[u8] = if b == decoded.buffer {
        &decoded.data
    } else {
        buffers
            .get(b)
            .ok_or_else(|| anyhow!("bufferView #{v}: buffer #{b} does not exist"))?
    };
    range(
        buffer,
        field("byteOffset").unwrap_or(0),
        field("byteLength").unwrap_or(0),
    )
    .map_err(|e| anyhow!("bufferView #{v}: {e} of buffer #{b}"))
}

/// `bytes[offset..offset + length]`, or an error saying it does not fit.
pub(super) fn range(bytes: &[u8], offset: usize, length: usize) -> Result<&[u8]> {
    offset
        .checked_add(length)
        .and_then(|end| bytes.get(offset..end))
        .ok_or_else(|| {
            anyhow!(
                "bytes {offset}..{} are outside the {} bytes",
                offset.saturating_add(length),
                bytes.len()
            )
        })
}

/// Decodes the file's compressed geometry and rewrites `gltf` to read the
/// decoded data (a new last buffer); says what it decoded in one note.
pub(super) fn decode_geometry(
    gltf: &mut Gltf,
    buffers: &mut Vec<Buffer>,
    notes: &mut Vec<String>,
) -> Result<()> {
    let uses = |name: &str| gltf.doc.extensions_used().any(|e| e == name);
    if !uses("EXT_meshopt_compression") && !uses("KHR_draco_mesh_compression") {
        return Ok(());
    }
    let mut json = gltf.json.clone();
    let count = |key: &str| json.get(key).and_then(Value::as_array).map_or(0, Vec::len);
    let mut decoded = Decoded {
        buffer: count("buffers"),
        data: Vec::new(),
        first_view: count("bufferViews"),
        views: Vec::new(),
    };
    let views = meshopt::decode_views(&mut json, buffers, &mut decoded)?;
    let primitives = draco::decode_primitives(&mut json, buffers, &mut decoded)?;
    if views == 0 && primitives == 0 {
        return Ok(());
    }
    let mut all_views = take_array(&mut json, "bufferViews")?;
    all_views.append(&mut decoded.views);
    let mut all_buffers = take_array(&mut json, "buffers")?;
    all_buffers.push(object(&[
        ("byteLength", decoded.data.len().into()),
        ("name", "vkpt: decoded geometry".into()),
    ]));
    if let Value::Object(root) = &mut json {
        root.insert("bufferViews".into(), Value::Array(all_views));
        root.insert("buffers".into(), Value::Array(all_buffers));
    }
    gltf.replace_json(json)?;
    buffers.push(decoded.data.into());
    let mut what = Vec::new();
    if views > 0 {
        what.push(format!(
            "{} (EXT_meshopt_compression)",
            plural(views, "bufferView", "bufferViews")
        ));
    }
    if primitives > 0 {
        what.push(format!(
            "{} (KHR_draco_mesh_compression)",
            plural(primitives, "primitive", "primitives")
        ));
    }
    notes.push(format!(
        "decoded compressed geometry: {}",
        what.join(" and ")
    ));
    Ok(())
}

/// `mesh #0 'name' primitive #1` for the primitives whose accessors read
/// bufferView `v` (the first few), for errors about that view.
pub(super) fn users_of_view(json: &Value, v: usize) -> String {
    let accessors: Vec<usize> = json
        .get("accessors")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .enumerate()
        .filter(|(_, a)| a.get("bufferView").and_then(Value::as_u64) == Some(v as u64))
        .map(|(i, _)| i)
        .collect();
    let mut users = Vec::new();
    let meshes = json.get("meshes").and_then(Value::as_array);
    for (m, mesh) in meshes.into_iter().flatten().enumerate() {
        let prims = mesh.get("primitives").and_then(Value::as_array);
        for (p, prim) in prims.into_iter().flatten().enumerate() {
            let attrs = prim.get("attributes").and_then(Value::as_object);
            let mut what: Vec<String> = attrs
                .into_iter()
                .flatten()
                .filter(|(_, a)| {
                    a.as_u64()
                        .is_some_and(|a| accessors.contains(&(a as usize)))
                })
                .map(|(k, _)| k.clone())
                .collect();
            if prim
                .get("indices")
                .and_then(Value::as_u64)
                .is_some_and(|a| accessors.contains(&(a as usize)))
            {
                what.push("indices".into());
            }
            if !what.is_empty() {
                users.push(format!(
                    "mesh #{m}{} primitive #{p} ({})",
                    super::document::name_of(mesh),
                    what.join(", ")
                ));
            }
        }
    }
    match users.len() {
        0 if accessors.is_empty() => String::new(),
        0 => format!(
            " (read by accessor {})",
            accessors
                .iter()
                .take(3)
                .map(|a| format!("#{a}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        n if n > 3 => format!(" (read by {} and {} more)", users[..3].join(", "), n - 3),
        _ => format!(" (read by {})", users.join(", ")),
    }
}

/// Turns a panic inside a decoder (a crate's bug on hostile input) into
/// an error, so that no file can take the loader down.
pub(super) fn no_panic<T>(what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
    catch_quietly(f).unwrap_or_else(|message| {
        Err(anyhow!(
            "the {what} decoder failed on malformed data ({message})"
        ))
    })
}
