//! The binary side of glTF: reading the file (`.gltf` JSON or `.glb`
//! container), loading its buffers and decoding accessors. Every offset and
//! length that comes from the file is checked here, so the loader never
//! indexes out of bounds on a malformed file.

use anyhow::{Context, Result, anyhow, bail, ensure};
use gltf::json::Value;
use std::path::Path;

/// A parsed glTF document: its JSON and, for `.glb`, the embedded BIN chunk.
pub(super) struct GltfFile {
    pub json: Value,
    pub bin: Option<Vec<u8>>,
}

/// Reads a `.gltf` or `.glb` file (the GLB magic decides, not the extension).
pub(super) fn read_file(path: &Path) -> Result<GltfFile> {
    let bytes = std::fs::read(path).context("cannot read the file")?;
    if bytes.starts_with(b"glTF") {
        let (json, bin) = split_glb(&bytes).context("not a valid binary glTF (.glb) file")?;
        let json = gltf::json::deserialize::from_slice(json)
            .context("the JSON chunk of the .glb is not valid JSON")?;
        Ok(GltfFile { json, bin })
    } else {
        let json = gltf::json::deserialize::from_slice(&bytes).context("not valid glTF JSON")?;
        Ok(GltfFile { json, bin: None })
    }
}

fn le_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB container into its JSON chunk and optional BIN chunk.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<Vec<u8>>)> {
    let version = le_u32(bytes, 4).ok_or_else(|| anyhow!("truncated header"))?;
    ensure!(
        version == 2,
        "GLB version {version} (only version 2 is supported)"
    );
    let length = le_u32(bytes, 8).ok_or_else(|| anyhow!("truncated header"))? as usize;
    ensure!(
        length <= bytes.len(),
        "truncated file: the header says {length} bytes, the file has {}",
        bytes.len()
    );
    let bytes = &bytes[..length];
    let mut at = 12usize;
    let mut json = None;
    let mut bin = None;
    while at < bytes.len() {
        let chunk_len = le_u32(bytes, at).ok_or_else(|| anyhow!("truncated chunk header"))?;
        let chunk_type = le_u32(bytes, at + 4).ok_or_else(|| anyhow!("truncated chunk header"))?;
        let start = at + 8;
        let end = start
            .checked_add(chunk_len as usize)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                anyhow!("truncated file: chunk at byte {at} of {chunk_len} bytes runs past the end")
            })?;
        let data = &bytes[start..end];
        match chunk_type {
            0x4E4F_534A if json.is_none() => json = Some(data),
            0x004E_4942 if bin.is_none() => bin = Some(data.to_vec()),
            _ => {} // unknown chunks are skipped, as the spec says
        }
        at = end;
    }
    let json = json.ok_or_else(|| anyhow!("no JSON chunk"))?;
    Ok((json, bin))
}

pub(super) use super::uri::percent_decode;

/// Loads every buffer of the document: data URIs, files relative to `base`
/// (inside it unless `allow_outside`, see `uri.rs`), or the GLB BIN chunk.
pub(super) fn load_buffers(
    json: &Value,
    base: &Path,
    mut bin: Option<Vec<u8>>,
    allow_outside: bool,
) -> Result<Vec<Vec<u8>>> {
    let mut out = Vec::new();
    for (i, buffer) in array(json, "buffers").iter().enumerate() {
        let label = format!("buffer #{i}{}", name_suffix(buffer));
        let byte_length = buffer
            .get("byteLength")
            .and_then(Value::as_u64)
            .unwrap_or(0);
        let data = match buffer.get("uri").and_then(Value::as_str) {
            None => bin
                .take()
                .ok_or_else(|| anyhow!("{label} has no uri and the file has no GLB BIN chunk"))?,
            Some(uri) if uri.starts_with("data:") => {
                gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
                    .map(|d| d.0)
                    .map_err(|e| anyhow!("{e}"))
                    .with_context(|| format!("{label}: cannot decode its data URI"))?
            }
            Some(uri) if uri.contains("://") => {
                bail!(
                    "{label}: uri {uri:?} is not a local file (only relative paths and data URIs are read)"
                )
            }
            Some(uri) => {
                let file =
                    super::uri::resolve(base, uri, allow_outside).with_context(|| label.clone())?;
                std::fs::read(&file)
                    .with_context(|| format!("{label}: cannot read {}", file.display()))?
            }
        };
        ensure!(
            data.len() as u64 >= byte_length,
            "{label}: byteLength is {byte_length} but only {} bytes were found",
            data.len()
        );
        out.push(data);
    }
    Ok(out)
}

/// `json[key]` as a slice (empty when absent or not an array).
pub(super) fn array<'a>(json: &'a Value, key: &str) -> &'a [Value] {
    json.get(key)
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or(&[])
}

/// Element `i` of a top-level glTF array, or an error naming what is missing.
pub(super) fn element<'a>(items: &'a [Value], what: &str, i: usize) -> Result<&'a Value> {
    items
        .get(i)
        .ok_or_else(|| anyhow!("{what} #{i} does not exist (the file has {})", items.len()))
}

/// `" 'name'"` when the object has a name, else empty.
pub(super) fn name_suffix(obj: &Value) -> String {
    match obj.get("name").and_then(Value::as_str) {
        Some(n) => format!(" '{n}'"),
        None => String::new(),
    }
}

fn index_field(obj: &Value, key: &str) -> Result<Option<usize>> {
    match obj.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(v) => v
            .as_u64()
            .map(|u| Some(u as usize))
            .ok_or_else(|| anyhow!("{key} is not a non-negative integer: {v}")),
    }
}

fn component_size(component_type: u64) -> Option<usize> {
    match component_type {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

fn component_count(type_: &str) -> Option<usize> {
    match type_ {
        "SCALAR" => Some(1),
        "VEC2" => Some(2),
        "VEC3" => Some(3),
        "VEC4" => Some(4),
        _ => None,
    }
}

/// Decodes one component; `b` holds at least `component_size` bytes.
#[inline]
fn decode(component_type: u64, normalized: bool, b: &[u8]) -> f64 {
    match component_type {
        5120 => {
            let v = b[0] as i8 as f64;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        5121 => {
            let v = b[0] as f64;
            if normalized { v / 255.0 } else { v }
        }
        5122 => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f64;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        5123 => {
            let v = u16::from_le_bytes([b[0], b[1]]) as f64;
            if normalized { v / 65535.0 } else { v }
        }
        5125 => {
            let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
            if normalized { v / 4294967295.0 } else { v }
        }
        _ => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
    }
}

/// The bytes of buffer view `view_index`, checked against its buffer, and its stride.
fn view_bytes<'a>(
    json: &Value,
    buffers: &'a [Vec<u8>],
    view_index: usize,
) -> Result<(&'a [u8], Option<usize>)> {
    let view = element(array(json, "bufferViews"), "bufferView", view_index)?;
    let label = format!("bufferView #{view_index}{}", name_suffix(view));
    let buffer_index = index_field(view, "buffer")
        .with_context(|| label.clone())?
        .ok_or_else(|| anyhow!("{label} has no buffer"))?;
    let buffer = buffers
        .get(buffer_index)
        .ok_or_else(|| anyhow!("{label}: buffer #{buffer_index} does not exist"))?;
    let offset = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
    let length = view.get("byteLength").and_then(Value::as_u64).unwrap_or(0) as usize;
    let bytes = offset
        .checked_add(length)
        .and_then(|end| buffer.get(offset..end))
        .ok_or_else(|| {
            anyhow!(
                "{label}: bytes {offset}..{} are outside buffer #{buffer_index} ({} bytes)",
                offset.saturating_add(length),
                buffer.len()
            )
        })?;
    let stride = view
        .get("byteStride")
        .and_then(Value::as_u64)
        .map(|s| s as usize);
    Ok((bytes, stride))
}

/// The bytes of buffer view `view_index` (an embedded image, say), checked
/// against its buffer.
pub(super) fn buffer_view_bytes<'a>(
    json: &Value,
    buffers: &'a [Vec<u8>],
    view_index: usize,
) -> Result<&'a [u8]> {
    Ok(view_bytes(json, buffers, view_index)?.0)
}

/// Reads `count` tightly packed or strided elements of `ncomp` components.
#[allow(clippy::too_many_arguments)]
fn read_elements<T>(
    bytes: &[u8],
    offset: usize,
    stride: Option<usize>,
    count: usize,
    ncomp: usize,
    component_type: u64,
    normalized: bool,
    conv: fn(f64) -> T,
    out: &mut Vec<T>,
) -> Result<()> {
    let csize = component_size(component_type).unwrap_or(4);
    let elem = csize * ncomp;
    let stride = stride.unwrap_or(elem);
    ensure!(
        stride >= elem,
        "byteStride {stride} is smaller than an element ({elem} bytes)"
    );
    if count == 0 {
        return Ok(());
    }
    let needed = (count - 1)
        .checked_mul(stride)
        .and_then(|s| s.checked_add(elem))
        .and_then(|s| s.checked_add(offset));
    ensure!(
        needed.is_some_and(|n| n <= bytes.len()),
        "{count} elements of {elem} bytes (stride {stride}) from byte offset {offset} do not fit in the {} bytes of the buffer view",
        bytes.len()
    );
    out.reserve(count * ncomp);
    for i in 0..count {
        let base = offset + i * stride;
        for c in 0..ncomp {
            let at = base + c * csize;
            out.push(conv(decode(
                component_type,
                normalized,
                &bytes[at..at + csize],
            )));
        }
    }
    Ok(())
}

/// Reads accessor `index` as a flat array of `ncomp`-component elements,
/// applying sparse substitution. The accessor type must be `expected_type`.
pub(super) fn read_accessor<T: Copy>(
    json: &Value,
    buffers: &[Vec<u8>],
    index: usize,
    expected_type: &str,
    conv: fn(f64) -> T,
    zero: T,
) -> Result<Vec<T>> {
    let acc = element(array(json, "accessors"), "accessor", index)?;
    let label = format!("accessor #{index}{}", name_suffix(acc));
    let inner = || -> Result<Vec<T>> {
        let type_ = acc.get("type").and_then(Value::as_str).unwrap_or("");
        ensure!(
            type_ == expected_type,
            "type is {type_:?}, expected {expected_type:?}"
        );
        let ncomp = component_count(type_).unwrap_or(1);
        let component_type = acc
            .get("componentType")
            .and_then(Value::as_u64)
            .unwrap_or(0);
        ensure!(
            component_size(component_type).is_some(),
            "unknown componentType {component_type}"
        );
        let normalized = acc
            .get("normalized")
            .and_then(Value::as_bool)
            .unwrap_or(false);
        let count = acc
            .get("count")
            .and_then(Value::as_u64)
            .ok_or_else(|| anyhow!("count is missing"))? as usize;
        let mut out = Vec::new();
        match index_field(acc, "bufferView")? {
            Some(view) => {
                let (bytes, stride) = view_bytes(json, buffers, view)?;
                let offset = acc.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
                read_elements(
                    bytes,
                    offset,
                    stride,
                    count,
                    ncomp,
                    component_type,
                    normalized,
                    conv,
                    &mut out,
                )?;
            }
            None => {
                ensure!(
                    acc.get("sparse").is_some(),
                    "has neither a bufferView nor sparse values"
                );
                // Guard against absurd counts before allocating zeros.
                ensure!(
                    count <= (1 << 28),
                    "count {count} is too large for an accessor without data"
                );
                out = vec![zero; count * ncomp];
            }
        }
        if let Some(sparse) = acc.get("sparse") {
            apply_sparse(
                json,
                buffers,
                sparse,
                count,
                ncomp,
                component_type,
                normalized,
                conv,
                &mut out,
            )
            .context("sparse")?;
        }
        Ok(out)
    };
    inner().with_context(|| label)
}

#[allow(clippy::too_many_arguments)]
fn apply_sparse<T: Copy>(
    json: &Value,
    buffers: &[Vec<u8>],
    sparse: &Value,
    count: usize,
    ncomp: usize,
    component_type: u64,
    normalized: bool,
    conv: fn(f64) -> T,
    out: &mut [T],
) -> Result<()> {
    let n = sparse
        .get("count")
        .and_then(Value::as_u64)
        .ok_or_else(|| anyhow!("count is missing"))? as usize;
    let indices = sparse
        .get("indices")
        .ok_or_else(|| anyhow!("indices are missing"))?;
    let values = sparse
        .get("values")
        .ok_or_else(|| anyhow!("values are missing"))?;

    let index_view = index_field(indices, "bufferView")?
        .ok_or_else(|| anyhow!("indices.bufferView is missing"))?;
    let (bytes, _) = view_bytes(json, buffers, index_view).context("indices")?;
    let index_type = indices
        .get("componentType")
        .and_then(Value::as_u64)
        .unwrap_or(0);
    ensure!(
        matches!(index_type, 5121 | 5123 | 5125),
        "indices.componentType {index_type} is not an unsigned integer type"
    );
    let offset = indices
        .get("byteOffset")
        .and_then(Value::as_u64)
        .unwrap_or(0) as usize;
    let mut sparse_indices: Vec<usize> = Vec::new();
    read_elements(
        bytes,
        offset,
        None,
        n,
        1,
        index_type,
        false,
        |v| v as usize,
        &mut sparse_indices,
    )
    .context("indices")?;

    let value_view = index_field(values, "bufferView")?
        .ok_or_else(|| anyhow!("values.bufferView is missing"))?;
    let (bytes, _) = view_bytes(json, buffers, value_view).context("values")?;
    let offset = values
        .get("byteOffset")
        .and_then(Value::as_u64)
        .unwrap_or(0) as usize;
    let mut sparse_values = Vec::new();
    read_elements(
        bytes,
        offset,
        None,
        n,
        ncomp,
        component_type,
        normalized,
        conv,
        &mut sparse_values,
    )
    .context("values")?;

    for (k, &i) in sparse_indices.iter().enumerate() {
        ensure!(
            i < count,
            "index {i} is outside the accessor ({count} elements)"
        );
        out[i * ncomp..(i + 1) * ncomp].copy_from_slice(&sparse_values[k * ncomp..(k + 1) * ncomp]);
    }
    Ok(())
}
