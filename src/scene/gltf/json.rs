//! Reading values from the file's JSON, for what the `gltf` crate does not
//! model (vkpt's extras, extensions it does not know), and checking the
//! numbers it does model: a JSON number beyond f32's range reaches the
//! crate's types as an infinity. Each helper names the value (`what`) when
//! it is malformed.

use anyhow::{Result, anyhow, ensure};
use glam::Vec3;
use gltf::json::Value;

pub(super) fn f32_array<const N: usize>(v: Option<&Value>, what: &str) -> Result<Option<[f32; N]>> {
    let Some(v) = v else { return Ok(None) };
    let arr = v
        .as_array()
        .filter(|a| a.len() == N)
        .ok_or_else(|| anyhow!("{what} is not an array of {N} numbers: {v}"))?;
    let mut out = [0.0f32; N];
    for (o, x) in out.iter_mut().zip(arr) {
        *o = x
            .as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite())
            .ok_or_else(|| anyhow!("{what} is not an array of {N} finite numbers: {v}"))?;
    }
    Ok(Some(out))
}

pub(super) fn non_negative(v: Option<&Value>, what: &str) -> Result<Option<f32>> {
    match v {
        None => Ok(None),
        Some(v) => v
            .as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite() && *f >= 0.0)
            .map(Some)
            .ok_or_else(|| anyhow!("{what} is not a finite non-negative number: {v}")),
    }
}

pub(super) fn rgb(v: Option<&Value>, what: &str) -> Result<Option<Vec3>> {
    let Some(c) = f32_array::<3>(v, what)?.map(Vec3::from) else {
        return Ok(None);
    };
    ensure!(
        c.min_element() >= 0.0,
        "{what} has a negative component: {c}"
    );
    Ok(Some(c))
}

/// `json[key]` as a slice (empty when absent or not an array).
pub(super) fn array<'a>(json: &'a Value, key: &str) -> &'a [Value] {
    json.get(key)
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or(&[])
}

/// `v` when every component is finite.
pub(super) fn finite<const N: usize>(v: [f32; N], what: &str) -> Result<[f32; N]> {
    ensure!(
        v.iter().all(|x| x.is_finite()),
        "{what} is not an array of {N} finite numbers: {v:?}"
    );
    Ok(v)
}

/// `x` when it is finite and not negative.
pub(super) fn non_negative_f32(x: f32, what: &str) -> Result<f32> {
    ensure!(
        x.is_finite() && x >= 0.0,
        "{what} is not a finite non-negative number: {x}"
    );
    Ok(x)
}

/// A finite, non-negative `[r, g, b]`.
pub(super) fn color(c: [f32; 3], what: &str) -> Result<Vec3> {
    let c = Vec3::from(finite(c, what)?);
    ensure!(
        c.min_element() >= 0.0,
        "{what} has a negative component: {c}"
    );
    Ok(c)
}
