//! Skinning and morph targets, applied on the host at the posed instant
//! (glTF 2.0 sections 3.7.3 and 3.7.2.2): a skinned vertex is
//! Σ w_i · J_i · IBM_i · p over its up to 8 joints (JOINTS_0/WEIGHTS_0 and
//! JOINTS_1/WEIGHTS_1), J_i the joint node's world transform and IBM_i its
//! inverse bind matrix; the skinned mesh's own node transform is ignored,
//! as glTF says. Morph targets add Σ w_k · target_k to POSITION and NORMAL
//! before skinning. The skin and targets are read from the JSON and
//! checked here (the crate's accessors for them assume a valid file).

use super::buffer::Buffer;
use super::data::read_accessor;
use super::document::Gltf;
use anyhow::{Context, Result, anyhow, ensure};
use glam::{DMat3, DMat4, DVec3};
use gltf::accessor::Dimensions;

/// What deforms a mesh at the posed instant.
#[derive(Clone, Debug, Default)]
pub(super) struct Deform {
    /// Morph target weights (the node's animated weights, else the node's,
    /// else the mesh's); empty: no morphing.
    pub weights: Vec<f64>,
    /// Per joint of the node's skin: J_i · IBM_i, relative to the world
    /// origin; `None`: not skinned.
    pub joints: Option<Vec<DMat4>>,
}

fn accessor<'a>(gltf: &'a Gltf, index: usize, what: &str) -> Result<gltf::Accessor<'a>> {
    gltf.doc.accessors().nth(index).ok_or_else(|| {
        anyhow!(
            "{what}: accessor #{index} does not exist (the file has {})",
            gltf.doc.accessors().len()
        )
    })
}

/// The joint matrices of skin `skin` for a node: J_i · IBM_i, where
/// `world_of(node)` is a placed node's world transform relative to the
/// world origin.
pub(super) fn joint_matrices(
    gltf: &Gltf,
    buffers: &[Buffer],
    skin: usize,
    world_of: &dyn Fn(usize) -> Option<DMat4>,
) -> Result<Vec<DMat4>> {
    let label = format!("skin #{skin}");
    let json = gltf
        .doc
        .as_json()
        .skins
        .get(skin)
        .ok_or_else(|| anyhow!("{label} does not exist"))?;
    let n = json.joints.len();
    ensure!(n > 0, "{label} has no joints");
    let ibm = match json.inverse_bind_matrices {
        None => vec![DMat4::IDENTITY; n],
        Some(index) => {
            let a = accessor(gltf, index.value(), "inverseBindMatrices").context(label.clone())?;
            let m = read_accessor(&a, buffers, Dimensions::Mat4, |f| f, 0.0)
                .with_context(|| format!("{label}: inverseBindMatrices"))?;
            ensure!(
                m.len() == 16 * n,
                "{label}: inverseBindMatrices holds {} matrices for {n} joints",
                m.len() / 16
            );
            ensure!(
                m.iter().all(|x| x.is_finite()),
                "{label}: inverseBindMatrices is not finite"
            );
            m.chunks_exact(16).map(DMat4::from_cols_slice).collect()
        }
    };
    json.joints
        .iter()
        .zip(ibm)
        .map(|(joint, ibm)| {
            let j = joint.value();
            let world = world_of(j)
                .ok_or_else(|| anyhow!("{label}: joint node #{j} is not in the rendered scene"))?;
            Ok(world * ibm)
        })
        .collect()
}

/// Adds the morph targets of primitive `pi` of mesh `mi`, weighted by
/// `weights`, to `positions` and `normals` (3 floats per vertex).
pub(super) fn morph(
    gltf: &Gltf,
    buffers: &[Buffer],
    (mi, pi): (usize, usize),
    weights: &[f64],
    positions: &mut [f32],
    normals: Option<&mut Vec<f32>>,
) -> Result<()> {
    let targets = gltf.doc.as_json().meshes[mi].primitives[pi]
        .targets
        .as_deref()
        .unwrap_or(&[]);
    if targets.is_empty() || weights.iter().all(|w| *w == 0.0) {
        return Ok(());
    }
    ensure!(
        weights.len() == targets.len(),
        "{} morph weights for {} morph targets",
        weights.len(),
        targets.len()
    );
    let mut normals = normals;
    for (k, (target, &w)) in targets.iter().zip(weights).enumerate() {
        if w == 0.0 {
            continue;
        }
        let attributes = [
            (target.positions, Some(&mut *positions), "POSITION"),
            (
                target.normals,
                normals.as_deref_mut().map(|n| &mut n[..]),
                "NORMAL",
            ),
        ];
        for (index, out, name) in attributes {
            let (Some(index), Some(out)) = (index, out) else {
                continue;
            };
            let what = format!("morph target #{k} {name}");
            let a = accessor(gltf, index.value(), &what)?;
            let delta = read_accessor(&a, buffers, Dimensions::Vec3, |f| f, 0.0)
                .with_context(|| what.clone())?;
            ensure!(
                delta.len() == out.len(),
                "{what} has {} elements for {} vertices",
                delta.len() / 3,
                out.len() / 3
            );
            for (o, d) in out.iter_mut().zip(&delta) {
                *o = (*o as f64 + w * d) as f32;
            }
        }
    }
    Ok(())
}

/// Each vertex's joints and weights (up to 8: sets 0 and 1), weights
/// normalized to sum 1.
pub(super) fn joints_and_weights(
    gltf: &Gltf,
    buffers: &[Buffer],
    (mi, pi): (usize, usize),
    n_vertices: usize,
    n_joints: usize,
) -> Result<Vec<Vec<(usize, f64)>>> {
    let attributes = &gltf.doc.as_json().meshes[mi].primitives[pi].attributes;
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;
    let find = |semantic: Semantic| {
        attributes
            .iter()
            .find(|(k, _)| matches!(k, Checked::Valid(s) if *s == semantic))
            .map(|(_, v)| v.value())
    };
    let mut out = vec![Vec::new(); n_vertices];
    let mut any = false;
    for set in 0..2 {
        let (Some(j), Some(w)) = (find(Semantic::Joints(set)), find(Semantic::Weights(set))) else {
            continue;
        };
        any = true;
        let joints = read_accessor(
            &accessor(gltf, j, "JOINTS")?,
            buffers,
            Dimensions::Vec4,
            |f| f,
            0.0,
        )
        .with_context(|| format!("attribute JOINTS_{set}"))?;
        let weights = read_accessor(
            &accessor(gltf, w, "WEIGHTS")?,
            buffers,
            Dimensions::Vec4,
            |f| f,
            0.0,
        )
        .with_context(|| format!("attribute WEIGHTS_{set}"))?;
        ensure!(
            joints.len() == 4 * n_vertices && weights.len() == 4 * n_vertices,
            "JOINTS_{set} / WEIGHTS_{set} do not have one element per vertex ({n_vertices})"
        );
        for (v, list) in out.iter_mut().enumerate() {
            for c in 0..4 {
                let (j, w) = (joints[4 * v + c], weights[4 * v + c]);
                ensure!(
                    w.is_finite() && w >= 0.0,
                    "WEIGHTS_{set} of vertex {v} is {w}"
                );
                if w > 0.0 {
                    ensure!(
                        (j as usize) < n_joints,
                        "JOINTS_{set} of vertex {v} names joint {j}, but the skin has {n_joints}"
                    );
                    list.push((j as usize, w));
                }
            }
        }
    }
    ensure!(
        any,
        "the node has a skin but the primitive has no JOINTS_0 and WEIGHTS_0"
    );
    for list in &mut out {
        let sum: f64 = list.iter().map(|(_, w)| w).sum();
        if sum > 0.0 {
            list.iter_mut().for_each(|(_, w)| *w /= sum);
        }
    }
    Ok(out)
}

/// Skins `positions` and `normals` in place into world space (relative to
/// the world origin): each vertex by its blend of `joints` matrices.
pub(super) fn skin(
    joints: &[DMat4],
    influences: &[Vec<(usize, f64)>],
    positions: &mut [f32],
    normals: Option<&mut Vec<f32>>,
) {
    let mut normals = normals;
    for (v, list) in influences.iter().enumerate() {
        let m = if list.is_empty() {
            DMat4::IDENTITY
        } else {
            list.iter()
                .fold(DMat4::ZERO, |acc, &(j, w)| acc + joints[j] * w)
        };
        let p = DVec3::new(
            positions[3 * v] as f64,
            positions[3 * v + 1] as f64,
            positions[3 * v + 2] as f64,
        );
        let q = m.transform_point3(p);
        positions[3 * v..3 * v + 3].copy_from_slice(&q.as_vec3().to_array());
        if let Some(n) = normals.as_deref_mut() {
            let nm = DMat3::from_mat4(m).inverse().transpose();
            let d = DVec3::new(n[3 * v] as f64, n[3 * v + 1] as f64, n[3 * v + 2] as f64);
            let r = (nm * d).normalize_or_zero();
            n[3 * v..3 * v + 3].copy_from_slice(&r.as_vec3().to_array());
        }
    }
}
