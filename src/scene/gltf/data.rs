//! The binary side of glTF: reading the file (`.gltf` JSON or `.glb`
//! container), loading its buffers and decoding accessors. Every offset and
//! length that comes from the file is checked here, so the loader never
//! indexes out of bounds on a malformed file.
//!
//! Two jobs the `gltf` crate also does are done here by hand. Its GLB
//! reader (`binary::Glb`) subtracts the header size from the header's
//! length unchecked and refuses chunks of unknown type, which the GLB spec
//! says to skip. Its accessor reader (`accessor::util::Iter`, behind
//! `mesh::Reader`) assumes a well-formed file: it computes
//! `offset + stride * (count - 1)` without overflow checks (a panic with
//! debug assertions on, as the fuzzer builds), reads POSITION as f32
//! whatever its componentType, and reports any problem as a bare `None`.
//! The decoder below reads the crate's typed [`Accessor`] and names the
//! accessor and what does not fit.

use super::buffer::Buffer;
use super::notes::name_suffix;
use super::uri;
use anyhow::{Context, Result, anyhow, bail, ensure};
use gltf::Accessor;
use gltf::Document;
use gltf::accessor::{DataType, Dimensions};
use gltf::buffer::{Source, View};
use gltf::json::Value;
use rayon::prelude::*;
use std::ops::Range;
use std::path::Path;

/// A parsed glTF document: its JSON and, for `.glb`, the embedded BIN chunk.
pub(super) struct GltfFile {
    pub json: Value,
    pub bin: Option<Buffer>,
}

/// Reads a `.gltf` or `.glb` file (the GLB magic decides, not the extension),
/// mapped where it can be (`buffer`): a `.glb`'s BIN chunk stays in the
/// mapped file.
pub(super) fn read_file(path: &Path) -> Result<GltfFile> {
    let bytes = Buffer::from_file(path).context("cannot read the file")?;
    if bytes.starts_with(b"glTF") {
        let (json, bin) = split_glb(&bytes).context("not a valid binary glTF (.glb) file")?;
        let json = gltf::json::deserialize::from_slice(&bytes[json])
            .context("the JSON chunk of the .glb is not valid JSON")?;
        let bin = bin.map(|range| bytes.part(range));
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

/// Where a GLB container's JSON chunk and optional BIN chunk lie in it.
fn split_glb(bytes: &[u8]) -> Result<(Range<usize>, Option<Range<usize>>)> {
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
        match chunk_type {
            0x4E4F_534A if json.is_none() => json = Some(start..end),
            0x004E_4942 if bin.is_none() => bin = Some(start..end),
            _ => {} // unknown chunks are skipped, as the spec says
        }
        at = end;
    }
    let json = json.ok_or_else(|| anyhow!("no JSON chunk"))?;
    Ok((json, bin))
}

/// Loads every buffer of the document: data URIs, files relative to `base`
/// (inside it unless `allow_outside`, see `uri.rs`), or the GLB BIN chunk.
///
/// An `EXT_meshopt_compression` fallback buffer (`fallback: true`) holds
/// no data: it is loaded empty whatever its uri (the compressed views that
/// name it are decoded by `meshopt.rs`).
pub(super) fn load_buffers(
    doc: &Document,
    base: &Path,
    mut bin: Option<Buffer>,
    allow_outside: bool,
) -> Result<Vec<Buffer>> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let label = format!("buffer #{}{}", buffer.index(), name_suffix(buffer.name()));
        let byte_length = buffer.length() as u64;
        let fallback = buffer
            .extension_value("EXT_meshopt_compression")
            .and_then(|e| e.get("fallback"))
            .and_then(Value::as_bool)
            .unwrap_or(false);
        if fallback {
            out.push(Buffer::from(Vec::new()));
            continue;
        }
        // Where the bytes were found, for an error about their length.
        let mut found_in = String::new();
        let data: Buffer = match buffer.source() {
            Source::Bin => bin
                .take()
                .ok_or_else(|| anyhow!("{label} has no uri and the file has no GLB BIN chunk"))?,
            Source::Uri(uri) if uri.starts_with("data:") => {
                gltf::buffer::Data::from_source(Source::Uri(uri), None)
                    .map(|d| d.0)
                    .map_err(|e| anyhow!("{e}"))
                    .with_context(|| format!("{label}: cannot decode its data URI"))?
                    .into()
            }
            Source::Uri(uri) if uri.contains("://") => {
                bail!(
                    "{label}: uri {uri:?} is not a local file (only relative paths and data URIs are read)"
                )
            }
            Source::Uri(uri) => {
                let file = uri::resolve(base, uri, allow_outside).with_context(|| label.clone())?;
                found_in = format!(" in {}", file.display());
                Buffer::from_file(&file)
                    .with_context(|| format!("{label}: cannot read {}", file.display()))?
            }
        };
        ensure!(
            data.len() as u64 >= byte_length,
            "{label}: byteLength is {byte_length} but only {} bytes were found{found_in}",
            data.len()
        );
        out.push(data);
    }
    Ok(out)
}

/// The glTF name of an accessor type.
fn type_name(dimensions: Dimensions) -> &'static str {
    match dimensions {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

/// Decodes one component; `b` holds at least `component_type.size()` bytes.
#[inline(always)]
fn decode(component_type: DataType, normalized: bool, b: &[u8]) -> f64 {
    match component_type {
        DataType::I8 => {
            let v = b[0] as i8 as f64;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        DataType::U8 => {
            let v = b[0] as f64;
            if normalized { v / 255.0 } else { v }
        }
        DataType::I16 => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f64;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U16 => {
            let v = u16::from_le_bytes([b[0], b[1]]) as f64;
            if normalized { v / 65535.0 } else { v }
        }
        DataType::U32 => {
            let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
            if normalized { v / 4294967295.0 } else { v }
        }
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
    }
}

/// The bytes of a buffer view (an accessor's data, an embedded image),
/// checked against its buffer, and its stride.
pub(super) fn view_bytes<'a>(
    view: &View,
    buffers: &'a [Buffer],
) -> Result<(&'a [u8], Option<usize>)> {
    let label = format!("bufferView #{}{}", view.index(), name_suffix(view.name()));
    let buffer_index = view.buffer().index();
    let buffer = buffers
        .get(buffer_index)
        .ok_or_else(|| anyhow!("{label}: buffer #{buffer_index} does not exist"))?;
    let offset = view.offset();
    let length = view.length();
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
    Ok((bytes, view.stride()))
}

/// How to read elements out of bytes.
#[derive(Clone, Copy)]
struct Layout {
    stride: Option<usize>,
    ncomp: usize,
    component_type: DataType,
    normalized: bool,
}

/// Elements per parallel task of [`read_elements`].
const DECODE_PART: usize = 1 << 14;

/// Reads `count` tightly packed or strided elements of `layout.ncomp`
/// components, starting `offset` bytes into `bytes`. On every core,
/// `DECODE_PART` elements a task: a 5 M-triangle mesh has 30 M
/// components to decode (docs/performance.md, "Load time").
fn read_elements<T: Copy + Send + Sync>(
    bytes: &[u8],
    offset: usize,
    count: usize,
    layout: Layout,
    conv: fn(f64) -> T,
    zero: T,
) -> Result<Vec<T>> {
    let Layout {
        stride,
        ncomp,
        component_type,
        normalized,
    } = layout;
    let csize = component_type.size();
    let elem = csize * ncomp;
    let stride = stride.unwrap_or(elem);
    ensure!(
        stride >= elem,
        "byteStride {stride} is smaller than an element ({elem} bytes)"
    );
    if count == 0 {
        return Ok(Vec::new());
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
    let mut out = vec![zero; count * ncomp];
    let fill = Fill {
        bytes,
        offset,
        stride,
        ncomp,
    };
    // One copy of the loop per component type, so that `decode` folds
    // into it.
    let c = |ct: DataType| move |b: &[u8]| conv(decode(ct, normalized, b));
    match component_type {
        DataType::I8 => fill.run::<T, 1>(&mut out, c(DataType::I8)),
        DataType::U8 => fill.run::<T, 1>(&mut out, c(DataType::U8)),
        DataType::I16 => fill.run::<T, 2>(&mut out, c(DataType::I16)),
        DataType::U16 => fill.run::<T, 2>(&mut out, c(DataType::U16)),
        DataType::U32 => fill.run::<T, 4>(&mut out, c(DataType::U32)),
        DataType::F32 => fill.run::<T, 4>(&mut out, c(DataType::F32)),
    }
    Ok(out)
}

/// Where [`read_elements`] reads, its bounds already checked.
struct Fill<'a> {
    bytes: &'a [u8],
    offset: usize,
    stride: usize,
    ncomp: usize,
}

impl Fill<'_> {
    /// Fills `out` (`ncomp` components per element) with `get` of each
    /// component's `SIZE` bytes.
    fn run<T: Send, const SIZE: usize>(&self, out: &mut [T], get: impl Fn(&[u8]) -> T + Sync) {
        let ncomp = self.ncomp;
        out.par_chunks_mut(DECODE_PART * ncomp)
            .enumerate()
            .for_each(|(j, part)| {
                let first = self.offset + j * DECODE_PART * self.stride;
                for (k, dst) in part.chunks_exact_mut(ncomp).enumerate() {
                    let element = &self.bytes[first + k * self.stride..];
                    for (d, b) in dst.iter_mut().zip(element.chunks_exact(SIZE)) {
                        *d = get(b);
                    }
                }
            });
    }
}

/// The values of a SCALAR accessor of plain u32 (not normalized, tightly
/// packed, no sparse values) as they lie in its buffer, when the buffer
/// holds them aligned and the machine is little-endian: 5 M triangles'
/// indices are 60 MB not to copy. None otherwise, or when they do not fit
/// ([`read_accessor`] says why).
pub(super) fn u32_in_place<'a>(accessor: &Accessor, buffers: &'a [Buffer]) -> Option<&'a [u32]> {
    let plain = cfg!(target_endian = "little")
        && accessor.data_type() == DataType::U32
        && accessor.dimensions() == Dimensions::Scalar
        && !accessor.normalized()
        && accessor.sparse().is_none();
    if !plain {
        return None;
    }
    let (bytes, stride) = view_bytes(&accessor.view()?, buffers).ok()?;
    if stride.is_some_and(|s| s != 4) {
        return None;
    }
    let start = accessor.offset();
    let end = accessor.count().checked_mul(4)?.checked_add(start)?;
    bytemuck::try_cast_slice(bytes.get(start..end)?).ok()
}

/// Reads `accessor` as a flat array of elements of type `expected`,
/// applying sparse substitution; `conv` turns each decoded component (with
/// normalization) into a `T`.
pub(super) fn read_accessor<T: Copy + Send + Sync>(
    accessor: &Accessor,
    buffers: &[Buffer],
    expected: Dimensions,
    conv: fn(f64) -> T,
    zero: T,
) -> Result<Vec<T>> {
    let label = format!(
        "accessor #{}{}",
        accessor.index(),
        name_suffix(accessor.name())
    );
    let inner = || -> Result<Vec<T>> {
        let dimensions = accessor.dimensions();
        ensure!(
            dimensions == expected,
            "type is {:?}, expected {:?}",
            type_name(dimensions),
            type_name(expected)
        );
        let ncomp = dimensions.multiplicity();
        let component_type = accessor.data_type();
        let normalized = accessor.normalized();
        let count = accessor.count();
        let mut out;
        match accessor.view() {
            Some(view) => {
                let (bytes, stride) = view_bytes(&view, buffers)?;
                let layout = Layout {
                    stride,
                    ncomp,
                    component_type,
                    normalized,
                };
                out = read_elements(bytes, accessor.offset(), count, layout, conv, zero)?;
            }
            None => {
                ensure!(
                    accessor.sparse().is_some(),
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
        if let Some(sparse) = accessor.sparse() {
            let layout = Layout {
                stride: None,
                ncomp,
                component_type,
                normalized,
            };
            apply_sparse(&sparse, buffers, count, layout, (conv, zero), &mut out)
                .context("sparse")?;
        }
        Ok(out)
    };
    inner().with_context(|| label)
}

/// Replaces the elements a sparse accessor lists by its values.
fn apply_sparse<T: Copy + Send + Sync>(
    sparse: &gltf::accessor::sparse::Sparse,
    buffers: &[Buffer],
    count: usize,
    layout: Layout,
    (conv, zero): (fn(f64) -> T, T),
    out: &mut [T],
) -> Result<()> {
    use gltf::accessor::sparse::IndexType;
    let n = sparse.count();
    let indices = sparse.indices();
    let (bytes, _) = view_bytes(&indices.view(), buffers).context("indices")?;
    let index_type = match indices.index_type() {
        IndexType::U8 => DataType::U8,
        IndexType::U16 => DataType::U16,
        IndexType::U32 => DataType::U32,
    };
    let index_layout = Layout {
        stride: None,
        ncomp: 1,
        component_type: index_type,
        normalized: false,
    };
    let sparse_indices: Vec<usize> =
        read_elements(bytes, indices.offset(), n, index_layout, |v| v as usize, 0)
            .context("indices")?;

    let values = sparse.values();
    let (bytes, _) = view_bytes(&values.view(), buffers).context("values")?;
    let sparse_values =
        read_elements(bytes, values.offset(), n, layout, conv, zero).context("values")?;

    let ncomp = layout.ncomp;
    for (k, &i) in sparse_indices.iter().enumerate() {
        ensure!(
            i < count,
            "index {i} is outside the accessor ({count} elements)"
        );
        out[i * ncomp..(i + 1) * ncomp].copy_from_slice(&sparse_values[k * ncomp..(k + 1) * ncomp]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pseudo_random_bytes(n: usize) -> Vec<u8> {
        (0..n as u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 23) as u8)
            .collect()
    }

    /// A `.glb`'s BIN chunk, read where it lies in the mapped file (after
    /// an unknown chunk, which is skipped), holds exactly the chunk's
    /// bytes, and its JSON chunk is the document.
    #[test]
    fn a_glb_bin_chunk_is_read_in_place() {
        let json = br#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":5003}]}  "#;
        let bin = pseudo_random_bytes(5003);
        let chunk = |kind: u32, data: &[u8]| {
            let mut c = (data.len() as u32).to_le_bytes().to_vec();
            c.extend(kind.to_le_bytes());
            c.extend(data);
            c
        };
        let body = [
            chunk(0x4E4F_534A, json),
            chunk(0x1234_5678, &[7; 12]),
            chunk(0x004E_4942, &bin),
        ]
        .concat();
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend((12 + body.len() as u32).to_le_bytes());
        glb.extend(body);
        let dir = std::env::temp_dir().join(format!("vkpt-glb-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("in-place.glb");
        std::fs::write(&path, &glb).unwrap();
        let file = read_file(&path).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        let read = file.bin.expect("a BIN chunk");
        assert!(
            *read == bin[..],
            "the BIN chunk read differs from the one written"
        );
        assert_eq!(file.json["buffers"][0]["byteLength"], 5003);
    }

    /// The parallel decode gives what decoding one element after another
    /// gives, over several parts, for every component type, normalized or
    /// not, with strides that leave gaps of odd sizes.
    #[test]
    fn parallel_decode_matches_one_element_at_a_time() {
        let count = 2 * DECODE_PART + 7;
        let types = [
            DataType::I8,
            DataType::U8,
            DataType::I16,
            DataType::U16,
            DataType::U32,
            DataType::F32,
        ];
        for component_type in types {
            for normalized in [false, true] {
                for ncomp in [1, 3, 4] {
                    for gap in [0, 1, 3] {
                        let csize = component_type.size();
                        let stride = csize * ncomp + gap;
                        let offset = 5;
                        let bytes = pseudo_random_bytes(offset + count * stride);
                        let layout = Layout {
                            stride: Some(stride),
                            ncomp,
                            component_type,
                            normalized,
                        };
                        let got = read_elements(&bytes, offset, count, layout, |f| f, 0.0).unwrap();
                        let mut expected = Vec::new();
                        for i in 0..count {
                            for c in 0..ncomp {
                                let at = offset + i * stride + c * csize;
                                expected.push(decode(component_type, normalized, &bytes[at..]));
                            }
                        }
                        let bits = |v: &[f64]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                        assert!(
                            bits(&got) == bits(&expected),
                            "{component_type:?} normalized {normalized}, {ncomp} components, stride {stride}"
                        );
                    }
                }
            }
        }
    }

    /// u32 indices are read in place only when they lie aligned and
    /// tightly packed, and then equal the decoded ones; anything else is
    /// left to `read_accessor`.
    #[test]
    fn u32_indices_in_place_match_the_decoded_ones() {
        let doc = gltf::Gltf::from_slice_without_validation(
            br#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 64}],
                "bufferViews": [{"buffer": 0, "byteLength": 64},
                                {"buffer": 0, "byteLength": 64, "byteStride": 8}],
                "accessors": [
                    {"bufferView": 0, "byteOffset": 4, "componentType": 5125, "count": 5, "type": "SCALAR"},
                    {"bufferView": 0, "byteOffset": 2, "componentType": 5125, "count": 5, "type": "SCALAR"},
                    {"bufferView": 0, "componentType": 5123, "count": 6, "type": "SCALAR"},
                    {"bufferView": 1, "componentType": 5125, "count": 4, "type": "SCALAR"},
                    {"bufferView": 0, "componentType": 5125, "count": 4, "type": "SCALAR", "normalized": true},
                    {"bufferView": 0, "byteOffset": 4, "componentType": 5125, "count": 20, "type": "SCALAR"}]}"#,
        )
        .unwrap()
        .document;
        let buffers = vec![Buffer::from(pseudo_random_bytes(64))];
        let aligned = |offset: usize| (buffers[0].as_ptr() as usize + offset).is_multiple_of(4);
        let accessors: Vec<Accessor> = doc.accessors().collect();
        let decoded =
            |a: &Accessor| read_accessor(a, &buffers, Dimensions::Scalar, |f| f as u32, 0);
        let in_place = u32_in_place(&accessors[0], &buffers);
        assert_eq!(in_place.is_some(), aligned(4));
        if let Some(values) = in_place {
            assert_eq!(values, &decoded(&accessors[0]).unwrap()[..]);
        }
        assert_eq!(u32_in_place(&accessors[1], &buffers).is_some(), aligned(2));
        for a in &accessors[2..] {
            assert!(
                u32_in_place(a, &buffers).is_none(),
                "accessor #{}",
                a.index()
            );
        }
        let err = format!("{:#}", decoded(&accessors[5]).unwrap_err());
        assert!(
            err.contains("accessor #5") && err.contains("do not fit"),
            "{err}"
        );
    }
}
