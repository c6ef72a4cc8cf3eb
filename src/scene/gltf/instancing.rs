//! Which meshes a scene keeps once and places many times (a two-level
//! scene, `packed::instances`): a glTF mesh that several nodes reference,
//! or that one node places many times with `EXT_mesh_gpu_instancing` (one
//! placement per row of its TRANSLATION / ROTATION / SCALE accessors).

use super::buffer::Buffer;
use super::data::read_accessor;
use super::document::Gltf;
use crate::scene::InstancingMode;
use anyhow::{Context, Result, ensure};
use glam::{DMat4, DQuat, DVec3};
use gltf::accessor::Dimensions;

/// Instancing pays, in `InstancingMode::Auto`, once the copies it saves
/// reach this many triangles: below it the copies cost little memory and
/// one level saves the top-level step of every ray.
pub const AUTO_MIN_SAVED_TRIANGLES: u64 = 100_000;

/// The placements `EXT_mesh_gpu_instancing` gives node `ni` (each row's T ×
/// R × S, applied before the node's own transform), or `None` when the
/// node does not use it. Rows whose transform is not invertible are left
/// out and counted in `dropped`.
pub(super) fn gpu_instancing_rows(
    gltf: &Gltf,
    buffers: &[Buffer],
    ni: usize,
    dropped: &mut usize,
) -> Result<Option<Vec<DMat4>>> {
    let Some(ext) = gltf
        .json
        .get("nodes")
        .and_then(|n| n.get(ni))
        .and_then(|n| n.get("extensions"))
        .and_then(|e| e.get("EXT_mesh_gpu_instancing"))
    else {
        return Ok(None);
    };
    let attributes = ext
        .get("attributes")
        .context("EXT_mesh_gpu_instancing has no attributes")?;
    let read = |name: &str, dims: Dimensions| -> Result<Option<Vec<f64>>> {
        let Some(index) = attributes.get(name) else {
            return Ok(None);
        };
        let index = index
            .as_u64()
            .with_context(|| format!("EXT_mesh_gpu_instancing {name} is not an accessor index"))?
            as usize;
        let accessor = gltf.doc.accessors().nth(index).with_context(|| {
            format!("EXT_mesh_gpu_instancing {name}: accessor #{index} does not exist")
        })?;
        read_accessor(&accessor, buffers, dims, |f| f, 0.0)
            .map(Some)
            .with_context(|| format!("EXT_mesh_gpu_instancing {name}"))
    };
    let translation = read("TRANSLATION", Dimensions::Vec3)?;
    let rotation = read("ROTATION", Dimensions::Vec4)?;
    let scale = read("SCALE", Dimensions::Vec3)?;
    let counts = [
        translation.as_ref().map(|t| t.len() / 3),
        rotation.as_ref().map(|r| r.len() / 4),
        scale.as_ref().map(|s| s.len() / 3),
    ];
    let count = counts.iter().flatten().copied().max().unwrap_or(0);
    ensure!(
        counts.iter().flatten().all(|&c| c == count),
        "EXT_mesh_gpu_instancing: its accessors hold different numbers of rows ({})",
        counts
            .iter()
            .flatten()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let mut rows = Vec::with_capacity(count);
    for i in 0..count {
        let t = translation
            .as_ref()
            .map_or(DVec3::ZERO, |t| DVec3::from_slice(&t[3 * i..3 * i + 3]));
        let r = rotation.as_ref().map_or(DQuat::IDENTITY, |r| {
            DQuat::from_xyzw(r[4 * i], r[4 * i + 1], r[4 * i + 2], r[4 * i + 3])
        });
        let s = scale
            .as_ref()
            .map_or(DVec3::ONE, |s| DVec3::from_slice(&s[3 * i..3 * i + 3]));
        let r = if r.length() > 0.0 { r.normalize() } else { r };
        let m = DMat4::from_scale_rotation_translation(s, r, t);
        if crate::scene::placeable(&m) {
            rows.push(m);
        } else {
            *dropped += 1;
        }
    }
    Ok(Some(rows))
}

/// How many triangles mesh `mesh` holds, from its accessors' counts
/// (before anything is dropped).
pub(super) fn mesh_triangles(mesh: &gltf::Mesh) -> u64 {
    mesh.primitives()
        .map(|p| {
            let n = match p.indices() {
                Some(i) => i.count(),
                None => p.get(&gltf::Semantic::Positions).map_or(0, |a| a.count()),
            };
            match p.mode() {
                gltf::mesh::Mode::Triangles => n / 3,
                gltf::mesh::Mode::TriangleStrip | gltf::mesh::Mode::TriangleFan => {
                    n.saturating_sub(2)
                }
                _ => 0,
            }
        })
        .sum::<usize>() as u64
}

/// Whether a mesh of `triangles` triangles placed `placements` times is
/// kept once.
pub(super) fn keep_once(mode: InstancingMode, placements: usize, triangles: u64) -> bool {
    placements >= 2
        && match mode {
            InstancingMode::Off => false,
            InstancingMode::On => true,
            InstancingMode::Auto => (placements as u64 - 1) * triangles >= AUTO_MIN_SAVED_TRIANGLES,
        }
}
