//! Reading values from raw glTF JSON, for what the `gltf` crate does not
//! model (vkpt's extras, extensions it does not know). Each helper checks
//! the value and names it (`what`) when it is malformed.

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

pub(super) fn index(v: Option<&Value>, what: &str) -> Result<Option<usize>> {
    match v {
        None | Some(Value::Null) => Ok(None),
        Some(v) => v
            .as_u64()
            .map(|u| Some(u as usize))
            .ok_or_else(|| anyhow!("{what} is not a non-negative integer: {v}")),
    }
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
