//! The camera vkpt adds when a file has none: it looks at the scene from the
//! glTF "front" (+Z side, looking toward -Z, +Y up) and fits the bounding
//! sphere of the scene in its field of view.

use super::{Camera, Triangle};
use glam::Vec3;

/// Vertical field of view of the automatic camera.
pub const AUTO_CAMERA_YFOV_DEGREES: f32 = 40.0;
/// How much room is left around the bounding sphere (1.0 = touching the frame).
const MARGIN: f32 = 1.1;

/// A camera named "auto" that frames the bounding sphere of `triangles`, or
/// `None` when there are no triangles.
pub fn frame_triangles(triangles: &[Triangle]) -> Option<Camera> {
    frame_points(&|| Box::new(triangles.iter().flat_map(|t| t.positions.iter().copied())))
}

/// [`frame_triangles`] of every triangle the scene places: with
/// instancing, each instance's where it places them, as a copy would be.
pub fn frame_scene(scene: &crate::scene::Scene) -> Option<Camera> {
    let Some(inst) = &scene.instancing else {
        return frame_triangles(&scene.triangles);
    };
    let points = || -> Box<dyn Iterator<Item = Vec3> + '_> {
        let placed = scene.triangles[..inst.placed]
            .iter()
            .flat_map(|t| t.positions.iter().copied());
        let instanced = inst.instances.iter().flat_map(|i| {
            scene.triangles[inst.meshes[i.mesh].clone()]
                .iter()
                .flat_map(move |t| {
                    t.positions
                        .iter()
                        .map(move |p| i.to_world.transform_point3(p.as_dvec3()).as_vec3())
                })
        });
        Box::new(placed.chain(instanced))
    };
    frame_points(&points)
}

/// The camera framing the points `points()` yields (walked twice).
fn frame_points<'a>(points: &dyn Fn() -> Box<dyn Iterator<Item = Vec3> + 'a>) -> Option<Camera> {
    let mut it = points();
    let first = it.next()?;
    let (lo, hi) = it.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
    let center = (lo + hi) * 0.5;
    // The bounding sphere about the box centre, tight to the actual points.
    let radius = points().map(|p| p.distance(center)).fold(0.0f32, f32::max);
    Some(frame_sphere(center, radius))
}

/// A camera named "auto" looking toward -Z at `center` from the distance at
/// which a sphere of `radius` fits in a 40° vertical field of view.
pub fn frame_sphere(center: Vec3, radius: f32) -> Camera {
    let yfov = AUTO_CAMERA_YFOV_DEGREES.to_radians();
    // A point-like scene still needs a positive distance.
    let radius = if radius > 0.0 && radius.is_finite() {
        radius
    } else {
        1.0
    };
    let distance = MARGIN * radius / (0.5 * yfov).sin();
    Camera {
        framed_automatically: true,
        ..Camera::pinhole(
            "auto",
            center + Vec3::Z * distance,
            Vec3::NEG_Z,
            Vec3::Y,
            yfov,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_fits_in_the_field_of_view() {
        let c = frame_sphere(Vec3::new(1.0, 2.0, 3.0), 2.0);
        let d = c.position.distance(Vec3::new(1.0, 2.0, 3.0));
        let half_angle = (2.0 / d).asin();
        assert!(half_angle < 0.5 * c.yfov);
        assert!(half_angle > 0.4 * c.yfov);
        assert_eq!(c.forward, Vec3::NEG_Z);
    }
}
