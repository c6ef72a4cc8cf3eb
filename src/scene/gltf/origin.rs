//! The world origin of a loaded scene ([`crate::scene::Scene::world_origin`]):
//! the f64 point every f32 position is measured from. It is the position of
//! the camera that will render, so float steps are finest where the image
//! is made; the loader subtracts it from each node's f64 world transform
//! before anything becomes f32 (`nodes.rs`).

use super::cameras::camera_name;
use super::document::Gltf;
use crate::scene::camera::find_camera;
use glam::{DMat4, DVec3};
use gltf::mesh::Semantic;

/// The position of the camera `wanted` names (the first camera when `None`
/// or when it names none: the command line reports that), else, for a
/// file without cameras, the centre of the scene's bounds (where the
/// automatic camera looks from a few radii away), else the origin.
pub(super) fn world_origin(gltf: &Gltf, placed: &[(usize, DMat4)], wanted: Option<&str>) -> DVec3 {
    let nodes: Vec<gltf::Node> = gltf.doc.nodes().collect();
    let cameras: Vec<(String, DVec3)> = placed
        .iter()
        .filter_map(|(ni, world)| {
            let node = &nodes[*ni];
            let cam = node.camera()?;
            Some((camera_name(&cam, node), world.transform_point3(DVec3::ZERO)))
        })
        .collect();
    if !cameras.is_empty() {
        let i = wanted
            .and_then(|w| find_camera(cameras.iter().map(|(n, _)| n.as_str()), w))
            .unwrap_or(0);
        return cameras[i].1;
    }
    bounds_centre(&nodes, placed).unwrap_or(DVec3::ZERO)
}

/// The centre of the world-space box around every mesh's POSITION bounds
/// (the accessors' `min` and `max`, which glTF requires; a mesh without
/// them counts by its node's position), or `None` without meshes.
fn bounds_centre(nodes: &[gltf::Node], placed: &[(usize, DMat4)]) -> Option<DVec3> {
    let mut lo = DVec3::INFINITY;
    let mut hi = DVec3::NEG_INFINITY;
    for (ni, world) in placed {
        let Some(mesh) = nodes[*ni].mesh() else {
            continue;
        };
        for prim in mesh.primitives() {
            let Some(positions) = prim.get(&Semantic::Positions) else {
                continue;
            };
            let corners = match (vec3(positions.min()), vec3(positions.max())) {
                (Some(a), Some(b)) => (0..8)
                    .map(|k| {
                        DVec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), b, a)
                    })
                    .collect(),
                _ => vec![DVec3::ZERO],
            };
            for c in corners {
                let p = world.transform_point3(c);
                if p.is_finite() {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        }
    }
    (lo.x <= hi.x).then(|| 0.5 * (lo + hi))
}

/// An accessor's `min` or `max` as a point, when it has three finite numbers.
fn vec3(v: Option<gltf::json::Value>) -> Option<DVec3> {
    let a = v?;
    let a = a.as_array()?;
    if a.len() != 3 {
        return None;
    }
    let x: Option<Vec<f64>> = a
        .iter()
        .map(|x| x.as_f64().filter(|f| f.is_finite()))
        .collect();
    x.map(|x| DVec3::from_slice(&x))
}
