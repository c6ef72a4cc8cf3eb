//! The node walk: the scene's roots, the node hierarchy with its transforms,
//! and what each node carries (a mesh, a camera, a light); plus the vkpt
//! scene extras.

use super::cameras::node_camera;
use super::data::{array, element, name_suffix};
use super::json::{f32_array, index};
use super::lights::node_light;
use super::mesh::MeshLoader;
use super::notes::plural;
use crate::scene::Scene;
use anyhow::{Context, Result, anyhow, ensure};
use glam::{Mat4, Quat, Vec3};
use gltf::json::Value;

/// The vkpt scene extras (see the README).
#[derive(Default)]
pub(super) struct SceneExtras {
    pub environment: Option<Vec3>,
    pub environment_map: Option<String>,
    pub environment_rotation: f32,
    pub environment_hidden: bool,
}

/// A node's transform relative to its parent: its matrix, else T × R × S.
fn local_transform(node: &Value) -> Result<Mat4> {
    if let Some(m) = f32_array::<16>(node.get("matrix"), "matrix")? {
        return Ok(Mat4::from_cols_array(&m));
    }
    let t = f32_array::<3>(node.get("translation"), "translation")?.unwrap_or([0.0; 3]);
    let r = f32_array::<4>(node.get("rotation"), "rotation")?.unwrap_or([0.0, 0.0, 0.0, 1.0]);
    let s = f32_array::<3>(node.get("scale"), "scale")?.unwrap_or([1.0; 3]);
    let q = Quat::from_array(r);
    ensure!(q.length() > 0.0, "rotation is the zero quaternion");
    Ok(Mat4::from_scale_rotation_translation(
        Vec3::from(s),
        q.normalize(),
        Vec3::from(t),
    ))
}

fn scene_extras(scene_json: &Value, notes: &mut Vec<String>) -> Result<SceneExtras> {
    let mut out = SceneExtras::default();
    let Some(vkpt) = scene_json.get("extras").and_then(|e| e.get("vkpt")) else {
        return Ok(out);
    };
    let obj = vkpt
        .as_object()
        .ok_or_else(|| anyhow!("scene extras \"vkpt\" must be an object, found {vkpt}"))?;
    for key in obj.keys() {
        if !matches!(
            key.as_str(),
            "environment" | "environment_map" | "environment_rotation" | "environment_hidden"
        ) {
            notes.push(format!(
                "scene extras vkpt.{key} is not understood: ignored"
            ));
        }
    }
    if let Some(env) = obj.get("environment") {
        let rgb = f32_array::<3>(Some(env), "scene extras vkpt.environment")?
            .map(Vec3::from)
            .ok_or_else(|| anyhow!("scene extras vkpt.environment is missing"))?;
        ensure!(
            rgb.min_element() >= 0.0,
            "scene extras vkpt.environment must be non-negative [r, g, b] radiance, found {env}"
        );
        out.environment = Some(rgb);
    }
    if let Some(v) = obj.get("environment_map") {
        out.environment_map = Some(
            v.as_str()
                .filter(|s| !s.is_empty())
                .ok_or_else(|| {
                    anyhow!("scene extras vkpt.environment_map must be a file name (.exr or .hdr), found {v}")
                })?
                .to_string(),
        );
    }
    if let Some(v) = obj.get("environment_rotation") {
        out.environment_rotation = v
            .as_f64()
            .map(|f| f as f32)
            .filter(|f| f.is_finite())
            .ok_or_else(|| {
                anyhow!(
                    "scene extras vkpt.environment_rotation must be a number of degrees, found {v}"
                )
            })?;
    }
    if let Some(v) = obj.get("environment_hidden") {
        out.environment_hidden = v.as_bool().ok_or_else(|| {
            anyhow!("scene extras vkpt.environment_hidden must be true or false, found {v}")
        })?;
    }
    Ok(out)
}

/// The root nodes to render and the scene's vkpt extras: the default scene
/// (else the first), or every root node when the file defines no scene.
fn scene_roots(json: &Value, notes: &mut Vec<String>) -> Result<(Vec<usize>, SceneExtras)> {
    let nodes = array(json, "nodes");
    let scenes = array(json, "scenes");
    Ok(if scenes.is_empty() {
        // No scene: render every root node (node that is nobody's child).
        let mut is_child = vec![false; nodes.len()];
        for n in nodes {
            for c in array(n, "children") {
                if let Some(c) = c.as_u64().filter(|&c| (c as usize) < nodes.len()) {
                    is_child[c as usize] = true;
                }
            }
        }
        if !nodes.is_empty() {
            notes.push("the file defines no scene: all root nodes are rendered".to_string());
        }
        (
            (0..nodes.len()).filter(|&i| !is_child[i]).collect(),
            SceneExtras::default(),
        )
    } else {
        let si = index(json.get("scene"), "scene")?.unwrap_or(0);
        let sj = element(scenes, "scene", si)?;
        let label = format!("scene #{si}{}", name_suffix(sj));
        let mut roots = Vec::new();
        for (k, n) in array(sj, "nodes").iter().enumerate() {
            roots.push(
                index(Some(n), &format!("nodes[{k}]"))
                    .with_context(|| label.clone())?
                    .unwrap_or(usize::MAX),
            );
        }
        let extras = scene_extras(sj, notes).with_context(|| label.clone())?;
        (roots, extras)
    })
}

/// Walks the scene's node trees depth first, in file order, adding each
/// node's triangles, camera and light to `scene` (world = parent × local);
/// returns the scene's vkpt extras.
pub(super) fn walk_scene(
    json: &Value,
    buffers: &[Vec<u8>],
    scene: &mut Scene,
    notes: &mut Vec<String>,
) -> Result<SceneExtras> {
    let (roots, extras) = scene_roots(json, notes)?;
    let nodes = array(json, "nodes");
    let mut mesh_loader = MeshLoader::new(json, buffers, &scene.materials);
    let mut visited = vec![false; nodes.len()];
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&r| (r, Mat4::IDENTITY)).collect();
    let mut skinned = 0usize;
    while let Some((ni, parent)) = stack.pop() {
        let node = element(nodes, "node", ni)?;
        let label = format!("node #{ni}{}", name_suffix(node));
        ensure!(
            !visited[ni],
            "{label} is reached twice: the node hierarchy is not a tree (a cycle or a node with two parents)"
        );
        visited[ni] = true;
        let world = parent * local_transform(node).with_context(|| label.clone())?;
        if let Some(mi) = index(node.get("mesh"), "mesh").with_context(|| label.clone())? {
            if node.get("skin").is_some() {
                skinned += 1;
            }
            mesh_loader
                .load_mesh(mi, &world, &mut scene.triangles)
                .with_context(|| label.clone())?;
        }
        if let Some(ci) = index(node.get("camera"), "camera").with_context(|| label.clone())? {
            let cam = node_camera(json, ci, node, &world, notes).with_context(|| label.clone())?;
            scene.cameras.push(cam);
        }
        if let Some(ext) = node
            .get("extensions")
            .and_then(|e| e.get("KHR_lights_punctual"))
        {
            let li = index(ext.get("light"), "KHR_lights_punctual.light")
                .with_context(|| label.clone())?
                .ok_or_else(|| anyhow!("{label}: KHR_lights_punctual names no light"))?;
            let light = node_light(json, li, &world, notes).with_context(|| label.clone())?;
            scene.lights.push(light);
        }
        for c in array(node, "children").iter().rev() {
            let c = index(Some(c), "children").with_context(|| label.clone())?;
            stack.push((c.unwrap_or(usize::MAX), world));
        }
    }
    if skinned > 0 {
        notes.push(format!(
            "skinning ignored on {}: meshes are rendered in their bind pose",
            plural(skinned, "node", "nodes")
        ));
    }
    mesh_loader.finish(scene, notes);
    Ok(extras)
}
