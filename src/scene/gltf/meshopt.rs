//! `EXT_meshopt_compression`: a bufferView whose extension names compressed
//! bytes (`buffer`, `byteOffset`, `byteLength`) and how to decode them
//! (`mode` ATTRIBUTES, TRIANGLES or INDICES; `filter` NONE, OCTAHEDRAL,
//! QUATERNION, EXPONENTIAL or COLOR; `count` elements of `byteStride`
//! bytes) is decoded by meshoptimizer into the decoded buffer, and the view
//! is pointed there. The view's own buffer may be the extension's
//! `fallback` buffer, which holds no data (`data.rs` loads it empty).
//!
//! meshoptimizer's decoders check the compressed bytes (a corrupt stream
//! is an error code, never a read out of bounds) but *assert* their size
//! arguments: every stride, count and filter combination is checked here
//! first, as the extension specifies it.

use super::buffer::Buffer;
use super::compressed::{Decoded, range, users_of_view};
use anyhow::{Context, Result, anyhow, bail, ensure};
use gltf::json::Value;
use meshopt::ffi;

/// Decoded sizes above this are refused (a corrupt count, or a file no
/// renderer on this machine could hold).
const MAX_DECODED_BYTES: usize = 1 << 31;

/// Decodes every compressed bufferView of `json` into `decoded` and points
/// the view at it; returns how many were decoded.
pub(super) fn decode_views(
    json: &mut Value,
    buffers: &[Buffer],
    decoded: &mut Decoded,
) -> Result<usize> {
    let n = json
        .get("bufferViews")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let mut done = 0;
    for v in 0..n {
        let Some(ext) = json["bufferViews"][v]
            .get("extensions")
            .and_then(|e| e.get("EXT_meshopt_compression"))
            .cloned()
        else {
            continue;
        };
        // The decoded size is checked before anything is decoded.
        let declared = json["bufferViews"][v]
            .get("byteLength")
            .and_then(Value::as_u64);
        let size = ["count", "byteStride"]
            .iter()
            .map(|k| ext.get(*k).and_then(Value::as_u64))
            .try_fold(1u64, |a, b| a.checked_mul(b?));
        ensure!(
            size.is_some() && size == declared,
            "bufferView #{v}{}: EXT_meshopt_compression: count x byteStride ({}) is not the view's byteLength ({})",
            users_of_view(json, v),
            size.map_or("missing".to_string(), |s| s.to_string()),
            declared.map_or("missing".to_string(), |d| d.to_string())
        );
        let bytes = decode_view(&ext, buffers).with_context(|| {
            format!(
                "bufferView #{v}{}: EXT_meshopt_compression",
                users_of_view(json, v)
            )
        })?;
        let view = &mut json["bufferViews"][v];
        let at = decoded.place(&bytes);
        // The view now reads the decoded bytes (its byteStride, if any,
        // describes them as it did).
        if let Some(obj) = view.as_object_mut() {
            obj.insert("buffer".into(), decoded.buffer.into());
            obj.insert("byteOffset".into(), at.into());
            if let Some(exts) = obj.get_mut("extensions").and_then(Value::as_object_mut) {
                exts.remove("EXT_meshopt_compression");
            }
        }
        done += 1;
    }
    Ok(done)
}

/// The decoded bytes of one view's extension object.
fn decode_view(ext: &Value, buffers: &[Buffer]) -> Result<Vec<u8>> {
    let field = |k: &str| ext.get(k).and_then(Value::as_u64).map(|x| x as usize);
    let need = |k: &str| field(k).ok_or_else(|| anyhow!("{k} is missing or not a number"));
    let b = need("buffer")?;
    let buffer = buffers
        .get(b)
        .ok_or_else(|| anyhow!("buffer #{b} does not exist"))?;
    let source = range(
        buffer,
        field("byteOffset").unwrap_or(0),
        need("byteLength")?,
    )
    .with_context(|| format!("buffer #{b}"))?;
    let count = need("count")?;
    let stride = need("byteStride")?;
    let text = |k: &str, default: &'static str| -> Result<String> {
        match ext.get(k) {
            None => Ok(default.to_string()),
            Some(Value::String(s)) => Ok(s.clone()),
            Some(other) => bail!("{k} is {other}, not a string"),
        }
    };
    let mode = text("mode", "")?;
    let filter = text("filter", "NONE")?;
    let size = count
        .checked_mul(stride)
        .filter(|&s| s <= MAX_DECODED_BYTES)
        .ok_or_else(|| anyhow!("{count} elements of {stride} bytes are too many"))?;
    let mut out = vec![0u8; size];
    match mode.as_str() {
        "ATTRIBUTES" => {
            ensure!(
                stride > 0 && stride <= 256 && stride.is_multiple_of(4),
                "byteStride {stride} is not a multiple of 4 from 4 to 256 (mode ATTRIBUTES)"
            );
            // SAFETY: `out` holds `count` elements of `stride` bytes, the
            // sizes the decoder asserts were checked above, and `source`
            // is read within its length.
            let rc = unsafe {
                ffi::meshopt_decodeVertexBuffer(
                    out.as_mut_ptr().cast(),
                    count,
                    stride,
                    source.as_ptr(),
                    source.len(),
                )
            };
            ensure!(
                rc == 0,
                "the compressed vertex data is corrupt (meshoptimizer error {rc})"
            );
            apply_filter(&filter, &mut out, count, stride)?;
        }
        "TRIANGLES" | "INDICES" => {
            ensure!(
                stride == 2 || stride == 4,
                "byteStride {stride} is not 2 or 4 (mode {mode})"
            );
            ensure!(
                filter == "NONE",
                "filter {filter} is not allowed with mode {mode}"
            );
            let rc = if mode == "TRIANGLES" {
                ensure!(
                    count.is_multiple_of(3),
                    "count {count} is not a multiple of 3 (mode TRIANGLES)"
                );
                // SAFETY: as above; the index count is a multiple of 3
                // and the index size 2 or 4, as the decoder asserts.
                unsafe {
                    ffi::meshopt_decodeIndexBuffer(
                        out.as_mut_ptr().cast(),
                        count,
                        stride,
                        source.as_ptr(),
                        source.len(),
                    )
                }
            } else {
                // SAFETY: as above (index size 2 or 4).
                unsafe {
                    ffi::meshopt_decodeIndexSequence(
                        out.as_mut_ptr().cast(),
                        count,
                        stride,
                        source.as_ptr(),
                        source.len(),
                    )
                }
            };
            ensure!(
                rc == 0,
                "the compressed index data is corrupt (meshoptimizer error {rc})"
            );
        }
        other => bail!("mode {other:?} is not ATTRIBUTES, TRIANGLES or INDICES"),
    }
    Ok(out)
}

/// Undoes the filter the encoder applied (in place).
fn apply_filter(filter: &str, out: &mut [u8], count: usize, stride: usize) -> Result<()> {
    let ptr = out.as_mut_ptr().cast();
    match filter {
        "NONE" => {}
        "OCTAHEDRAL" | "COLOR" => {
            ensure!(
                stride == 4 || stride == 8,
                "byteStride {stride} is not 4 or 8 (filter {filter})"
            );
            // SAFETY: `out` holds `count` elements of `stride` bytes and
            // the stride is one the filter accepts.
            unsafe {
                if filter == "COLOR" {
                    ffi::meshopt_decodeFilterColor(ptr, count, stride)
                } else {
                    ffi::meshopt_decodeFilterOct(ptr, count, stride)
                }
            }
        }
        "QUATERNION" => {
            ensure!(
                stride == 8,
                "byteStride {stride} is not 8 (filter QUATERNION)"
            );
            // SAFETY: as above.
            unsafe { ffi::meshopt_decodeFilterQuat(ptr, count, stride) }
        }
        "EXPONENTIAL" => {
            // (ATTRIBUTES already requires a multiple of 4.)
            // SAFETY: as above.
            unsafe { ffi::meshopt_decodeFilterExp(ptr, count, stride) }
        }
        other => {
            bail!("filter {other:?} is not NONE, OCTAHEDRAL, QUATERNION, EXPONENTIAL or COLOR")
        }
    }
    Ok(())
}
