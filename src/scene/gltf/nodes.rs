//! The node walk: the scene's roots, the node hierarchy with its transforms,
//! and what each node carries (a mesh, a camera, a light); plus the vkpt
//! scene extras, read from the scene's JSON (the `gltf` crate leaves
//! `extras` unparsed).

use super::animation::NodePose;
use super::buffer::Buffer;
use super::cameras::node_camera;
use super::document::Gltf;
use super::instancing::{gpu_instancing_rows, keep_once, mesh_triangles};
use super::json::{f32_array, finite};
use super::lights::node_light;
use super::mesh::MeshLoader;
use super::notes::name_suffix;
use super::origin::world_origin;
use super::skin::{Deform, joint_matrices};
use crate::scene::{Instance, Instancing, InstancingMode, Scene};
use anyhow::{Context, Result, anyhow, ensure};
use glam::{DMat4, DQuat, DVec3, Vec3};
use gltf::json::Value;
use gltf::scene::Transform;

/// The vkpt scene extras (`scenes[i].extras.vkpt`). Keys that are not
/// understood become notes; a malformed value is an error.
#[derive(Clone, Default)]
pub(super) struct SceneExtras {
    /// `environment`: `[r, g, b]`, the uniform radiance of the environment
    /// (linear, non-negative); when given it is used as is, also in scenes
    /// with emissive surfaces, and no default light is added. With an
    /// `environment_map`, the factor its texels are scaled by.
    pub environment: Option<Vec3>,
    /// `environment_map`: an equirectangular `.exr` or `.hdr` file beside
    /// the scene (row 0 is +Y, the centre faces -Z), importance sampled.
    pub environment_map: Option<String>,
    /// `environment_rotation`: degrees the map turns about +Y.
    pub environment_rotation: f32,
    /// `environment_hidden`: camera rays that leave the scene see black;
    /// the environment still lights the scene.
    pub environment_hidden: bool,
}

/// A node's transform relative to its parent, in f64: its matrix, else
/// T × R × S. The numbers are read from the file's JSON as f64 (the `gltf`
/// crate holds them as f32, which keeps only steps of 0.0078 at 1e5 and of
/// 1 at 1e7); the crate's values are checked first, so a number beyond
/// f32's range is still refused as before. An animated node's `pose`
/// replaces the properties it drives (glTF forbids animating a node given
/// by a matrix).
fn local_transform(gltf: &Gltf, node: &gltf::Node, pose: &NodePose) -> Result<DMat4> {
    let raw = gltf.raw("nodes", node.index());
    let numbers = |key: &str, default: &[f64]| -> Result<Vec<f64>> {
        match raw.get(key).and_then(Value::as_array) {
            None => Ok(default.to_vec()),
            Some(a) => a
                .iter()
                .map(|x| x.as_f64().filter(|f| f.is_finite()))
                .collect::<Option<Vec<f64>>>()
                .filter(|v| v.len() == default.len())
                .ok_or_else(|| {
                    anyhow!("{key} is not an array of {} finite numbers", default.len())
                }),
        }
    };
    Ok(match node.transform() {
        Transform::Matrix { matrix } => {
            ensure!(
                !pose.is_animated(),
                "the node is animated but has a matrix: glTF requires animated nodes to give translation, rotation and scale"
            );
            ensure!(
                matrix.iter().flatten().all(|x| x.is_finite()),
                "matrix is not an array of 16 finite numbers: {matrix:?}"
            );
            let identity = DMat4::IDENTITY.to_cols_array();
            DMat4::from_cols_slice(&numbers("matrix", &identity)?)
        }
        Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            finite(translation, "translation")?;
            finite(rotation, "rotation")?;
            finite(scale, "scale")?;
            let t = numbers("translation", &[0.0; 3])?;
            let r = numbers("rotation", &[0.0, 0.0, 0.0, 1.0])?;
            let s = numbers("scale", &[1.0; 3])?;
            let q = DQuat::from_slice(&r);
            ensure!(q.length() > 0.0, "rotation is the zero quaternion");
            DMat4::from_scale_rotation_translation(
                pose.scale.unwrap_or(DVec3::from_slice(&s)),
                pose.rotation.unwrap_or(q.normalize()),
                pose.translation.unwrap_or(DVec3::from_slice(&t)),
            )
        }
    })
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
pub(super) fn scene_roots(
    gltf: &Gltf,
    notes: &mut Vec<String>,
) -> Result<(Vec<usize>, SceneExtras)> {
    let doc = &gltf.doc;
    let Some(scene) = doc.default_scene().or_else(|| doc.scenes().next()) else {
        // No scene: render every root node (node that is nobody's child).
        let n = doc.nodes().len();
        let mut is_child = vec![false; n];
        for c in doc.nodes().flat_map(|node| node.children()) {
            is_child[c.index()] = true;
        }
        if n > 0 {
            notes.push("the file defines no scene: all root nodes are rendered".to_string());
        }
        let roots = (0..n).filter(|&i| !is_child[i]).collect();
        return Ok((roots, SceneExtras::default()));
    };
    let si = scene.index();
    let label = format!("scene #{si}{}", name_suffix(scene.name()));
    let roots = scene.nodes().map(|node| node.index()).collect();
    let extras = scene_extras(gltf.raw("scenes", si), notes).with_context(|| label.clone())?;
    Ok((roots, extras))
}

/// Every node of the scene's trees with its world transform (world =
/// parent × local, composed in f64, each node in its `poses` entry),
/// depth first in file order; an error when the hierarchy is not a tree.
fn place_nodes(gltf: &Gltf, roots: &[usize], poses: &[NodePose]) -> Result<Vec<(usize, DMat4)>> {
    let nodes: Vec<gltf::Node> = gltf.doc.nodes().collect();
    let mut visited = vec![false; nodes.len()];
    let mut placed = Vec::new();
    let mut stack: Vec<(usize, DMat4)> =
        roots.iter().rev().map(|&r| (r, DMat4::IDENTITY)).collect();
    while let Some((ni, parent)) = stack.pop() {
        let node = nodes
            .get(ni)
            .ok_or_else(|| anyhow!("node #{ni} does not exist (the file has {})", nodes.len()))?;
        let label = format!("node #{ni}{}", name_suffix(node.name()));
        ensure!(
            !visited[ni],
            "{label} is reached twice: the node hierarchy is not a tree (a cycle or a node with two parents)"
        );
        visited[ni] = true;
        let world =
            parent * local_transform(gltf, node, &poses[ni]).with_context(|| label.clone())?;
        placed.push((ni, world));
        for c in node.children().collect::<Vec<_>>().iter().rev() {
            stack.push((c.index(), world));
        }
    }
    Ok(placed)
}

/// Walks the scene's node trees depth first, in file order, adding each
/// node's triangles, camera and light to `scene`, placed relative to the
/// world origin (`origin.rs`: the position of the camera `camera` names)
/// by subtracting it from the f64 world transform before anything becomes
/// f32, or relative to `origin` when given (the poses of one shutter share
/// the first one's). Each node is placed in its `poses` entry (indexed by
/// node).
#[allow(clippy::too_many_arguments)]
pub(super) fn walk_scene(
    gltf: &Gltf,
    buffers: &[Buffer],
    roots: &[usize],
    poses: &[NodePose],
    camera: Option<&str>,
    origin: Option<DVec3>,
    instancing: InstancingMode,
    scene: &mut Scene,
    notes: &mut Vec<String>,
) -> Result<()> {
    let placed = place_nodes(gltf, roots, poses)?;
    let origin = origin.unwrap_or_else(|| world_origin(gltf, &placed, camera));
    scene.world_origin = origin;
    let nodes: Vec<gltf::Node> = gltf.doc.nodes().collect();
    let mut mesh_loader = MeshLoader::new(gltf, buffers, &scene.materials);
    // World transforms relative to the origin, by node (joints need them).
    let mut relative: Vec<Option<DMat4>> = vec![None; nodes.len()];
    for &(ni, world) in &placed {
        let mut world = world;
        world.w_axis -= origin.extend(0.0);
        relative[ni] = Some(world);
    }
    // Each node's placements of its mesh (EXT_mesh_gpu_instancing: one per
    // row), and how often each mesh is placed where it does not deform.
    let mut dropped_rows = 0usize;
    let mut placements: Vec<Option<(Deform, Vec<DMat4>)>> = vec![None; nodes.len()];
    let mut rigid_placements = vec![0usize; gltf.doc.meshes().len()];
    for &(ni, _) in &placed {
        let node = &nodes[ni];
        let Some(mesh) = node.mesh() else { continue };
        let label = format!("node #{ni}{}", name_suffix(node.name()));
        let world = relative[ni].expect("placed");
        let deform = deform_of(gltf, buffers, node, &mesh, &poses[ni], &relative)
            .with_context(|| label.clone())?;
        let worlds = match gpu_instancing_rows(gltf, buffers, ni, &mut dropped_rows)
            .with_context(|| label.clone())?
        {
            Some(rows) => rows.iter().map(|r| world * *r).collect(),
            None => vec![world],
        };
        if deform.joints.is_none() && deform.weights.is_empty() {
            rigid_placements[mesh.index()] += worlds.len();
        }
        placements[ni] = Some((deform, worlds));
    }
    if dropped_rows > 0 {
        notes.push(format!(
            "skipped {dropped_rows} EXT_mesh_gpu_instancing rows whose transform is not invertible"
        ));
    }
    let kept_once: Vec<bool> = gltf
        .doc
        .meshes()
        .map(|m| keep_once(instancing, rigid_placements[m.index()], mesh_triangles(&m)))
        .collect();
    let mut instances: Vec<(usize, DMat4)> = Vec::new();
    for &(ni, _) in &placed {
        let node = &nodes[ni];
        let label = format!("node #{ni}{}", name_suffix(node.name()));
        let world = relative[ni].expect("placed");
        if let (Some(mesh), Some((deform, worlds))) = (node.mesh(), &placements[ni]) {
            let rigid = deform.joints.is_none() && deform.weights.is_empty();
            if rigid && kept_once[mesh.index()] {
                instances.extend(worlds.iter().map(|w| (mesh.index(), *w)));
            } else {
                for w in worlds {
                    mesh_loader
                        .load_mesh(&mesh, w, deform, &mut scene.triangles)
                        .with_context(|| label.clone())?;
                }
            }
        }
        if let Some(camera) = node.camera() {
            let cam =
                node_camera(gltf, &camera, node, &world, notes).with_context(|| label.clone())?;
            scene.cameras.push(cam);
        }
        if let Some(light) = node.light() {
            let light = node_light(gltf, &light, &world, notes).with_context(|| label.clone())?;
            scene.lights.push(light);
        }
    }
    // The meshes kept once, each in its own space after the triangles in
    // place, and their instances.
    if !instances.is_empty() {
        let placed_triangles = scene.triangles.len();
        let mut ranges: Vec<Option<usize>> = vec![None; kept_once.len()];
        let mut meshes = Vec::new();
        let rigid = Deform {
            weights: Vec::new(),
            joints: None,
        };
        for mesh in gltf.doc.meshes().filter(|m| kept_once[m.index()]) {
            let start = scene.triangles.len();
            mesh_loader
                .load_mesh(&mesh, &DMat4::IDENTITY, &rigid, &mut scene.triangles)
                .with_context(|| format!("mesh #{}{}", mesh.index(), name_suffix(mesh.name())))?;
            if scene.triangles.len() > start {
                ranges[mesh.index()] = Some(meshes.len());
                meshes.push(start..scene.triangles.len());
            }
        }
        let instances: Vec<Instance> = instances
            .into_iter()
            .filter_map(|(mesh, to_world)| ranges[mesh].map(|mesh| Instance { mesh, to_world }))
            .collect();
        if !instances.is_empty() {
            scene.instancing = Some(Instancing {
                placed: placed_triangles,
                meshes,
                instances,
            });
        }
    }
    mesh_loader.finish(scene, notes);
    Ok(())
}

/// How node `node`'s mesh deforms: its morph weights (animated, else the
/// node's, else the mesh's) and, with a skin, its joint matrices.
fn deform_of(
    gltf: &Gltf,
    buffers: &[Buffer],
    node: &gltf::Node,
    mesh: &gltf::Mesh,
    pose: &NodePose,
    relative: &[Option<DMat4>],
) -> Result<Deform> {
    let weights = match &pose.weights {
        Some(w) => w.clone(),
        None => node
            .weights()
            .or(mesh.weights())
            .map(|w| w.iter().map(|&x| x as f64).collect())
            .unwrap_or_default(),
    };
    let skin = gltf.doc.as_json().nodes[node.index()].skin;
    let joints = match skin {
        None => None,
        Some(skin) => Some(joint_matrices(gltf, buffers, skin.value(), &|j| {
            relative.get(j).copied().flatten()
        })?),
    };
    Ok(Deform { weights, joints })
}
