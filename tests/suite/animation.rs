//! glTF animation on the host: channels sampled at `--time` and applied
//! through the node hierarchy to meshes, cameras and lights; the choice of
//! animation; notes; and errors (never panics) on malformed animations.
//! Every expected value is worked out by hand in the comments.

use crate::common;

use common::gltf_builder::GltfBuilder;
use glam::{DVec3, Vec3};
use std::path::{Path, PathBuf};
use vkpt::scene::{LoadOptions, Scene};

/// A parent node with three children: a triangle, a camera at (0, 0, 5) and
/// a point light at (0, 2, 0). Animations: "slide" moves the parent from
/// the origin to (4, 0, 0) over 0..2 s (LINEAR); "turn" turns the
/// triangle's node by 90° about Z at t = 1 s (STEP); "look" turns the
/// camera by 90° about Y over 0..1 s (LINEAR, slerp). `animations` lets a
/// test replace the animations' JSON.
fn rig(animations: Option<&str>, parent_extra: &str) -> String {
    let mut b = GltfBuilder::default();
    let tri = b.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let t02 = b.floats(&[0.0, 2.0], "SCALAR");
    let slide = b.floats(&[0., 0., 0., 4., 0., 0.], "VEC3");
    let t01 = b.floats(&[0.0, 1.0], "SCALAR");
    let s = std::f32::consts::FRAC_1_SQRT_2;
    let turn = b.floats(&[0., 0., 0., 1., 0., 0., s, s], "VEC4");
    let look = b.floats(&[0., 0., 0., 1., 0., s, 0., s], "VEC4");
    let default_animations = format!(
        r#"[
    {{"name": "slide", "samplers": [{{"input": {t02}, "output": {slide}}}],
      "channels": [{{"sampler": 0, "target": {{"node": 0, "path": "translation"}}}}]}},
    {{"name": "turn", "samplers": [{{"input": {t01}, "output": {turn}, "interpolation": "STEP"}}],
      "channels": [{{"sampler": 0, "target": {{"node": 1, "path": "rotation"}}}}]}},
    {{"name": "look", "samplers": [{{"input": {t01}, "output": {look}, "interpolation": "LINEAR"}}],
      "channels": [{{"sampler": 0, "target": {{"node": 2, "path": "rotation"}}}}]}}
  ]"#
    );
    let animations = animations.unwrap_or(&default_animations);
    b.finish(&format!(
        r#""extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{{"type": "point", "intensity": 1}}]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0]}}],
  "nodes": [
    {{"name": "parent", "children": [1, 2, 3] {parent_extra}}},
    {{"name": "tri", "mesh": 0}},
    {{"name": "cam", "camera": 0, "translation": [0, 0, 5]}},
    {{"name": "lamp", "translation": [0, 2, 0], "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}}
  ],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.8, "znear": 0.1}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {tri}}}}}]}}],
  "animations": {animations}"#
    ))
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("can write a temp file");
    path
}

fn load_at(path: &Path, time: f64, animation: Option<&str>) -> anyhow::Result<Scene> {
    let options = LoadOptions {
        time,
        animation: animation.map(str::to_string),
        ..Default::default()
    };
    Scene::load_with(path, &options)
}

/// A point in the file's coordinates (the loader measures from the camera).
fn world(scene: &Scene, p: Vec3) -> DVec3 {
    scene.world_position(p)
}

fn assert_near(a: DVec3, b: DVec3, what: &str) {
    assert!((a - b).length() < 1e-5, "{what}: {a} != {b}");
}

fn triangle(scene: &Scene) -> [DVec3; 3] {
    scene.triangles[0].positions.map(|p| world(scene, p))
}

#[test]
fn channels_move_meshes_cameras_and_lights_through_the_hierarchy() {
    let dir = common::fresh_output_dir("animation", "hierarchy");
    let path = write(&dir, "rig.gltf", &rig(None, ""));
    // t = 0.5: parent at (1, 0, 0) (a quarter of 0..4); STEP still holds
    // the identity; the camera has turned 45° about Y, so its forward,
    // -Z turned by 45°, is (-sin 45°, 0, -cos 45°).
    let s = load_at(&path, 0.5, None).unwrap();
    let tri = triangle(&s);
    assert_near(tri[0], DVec3::new(1., 0., 0.), "vertex 0 at 0.5 s");
    assert_near(tri[1], DVec3::new(2., 0., 0.), "vertex 1 at 0.5 s");
    assert_near(tri[2], DVec3::new(1., 1., 0.), "vertex 2 at 0.5 s");
    let cam = &s.cameras[0];
    assert_near(
        world(&s, cam.position),
        DVec3::new(1., 0., 5.),
        "camera at 0.5 s",
    );
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert_near(
        cam.forward.as_dvec3(),
        DVec3::new(-h, 0., -h),
        "camera forward",
    );
    assert_near(
        world(&s, s.lights[0].position),
        DVec3::new(1., 2., 0.),
        "lamp at 0.5 s",
    );

    // t = 1: parent at (2, 0, 0); the STEP key at 1 s turns the triangle
    // 90° about Z: (1, 0, 0) -> (0, 1, 0) and (0, 1, 0) -> (-1, 0, 0).
    let s = load_at(&path, 1.0, None).unwrap();
    let tri = triangle(&s);
    assert_near(tri[0], DVec3::new(2., 0., 0.), "vertex 0 at 1 s");
    assert_near(tri[1], DVec3::new(2., 1., 0.), "vertex 1 at 1 s");
    assert_near(tri[2], DVec3::new(1., 0., 0.), "vertex 2 at 1 s");
    assert_near(
        s.cameras[0].forward.as_dvec3(),
        DVec3::new(-1., 0., 0.),
        "camera forward at 1 s",
    );
    // The shading normals turn with the triangle (it faces +Z throughout).
    assert!((s.triangles[0].normals[0] - Vec3::Z).length() < 1e-5);

    // Past the end the last pose holds; before the start, the first.
    let s = load_at(&path, 7.0, None).unwrap();
    assert_near(triangle(&s)[0], DVec3::new(4., 0., 0.), "vertex 0 at 7 s");
    assert!(
        s.notes
            .iter()
            .any(|n| n.contains("after the last keyframe")),
        "{:?}",
        s.notes
    );
    let s = load_at(&path, -1.0, None).unwrap();
    assert_near(triangle(&s)[0], DVec3::ZERO, "vertex 0 at -1 s");
}

#[test]
fn one_animation_can_be_picked_by_name_or_index() {
    let dir = common::fresh_output_dir("animation", "pick");
    let path = write(&dir, "rig.gltf", &rig(None, ""));
    // Only "turn": the parent stays at the origin, the camera looks down -Z.
    for wanted in ["turn", "1"] {
        let s = load_at(&path, 1.0, Some(wanted)).unwrap();
        let tri = triangle(&s);
        assert_near(tri[1], DVec3::new(0., 1., 0.), wanted);
        assert_near(s.cameras[0].forward.as_dvec3(), DVec3::NEG_Z, wanted);
        assert!(
            s.notes
                .iter()
                .any(|n| n.contains("animation #1 'turn' (of 3) posed at t = 1 s")),
            "{:?}",
            s.notes
        );
    }
    let err = format!("{:#}", load_at(&path, 0.0, Some("run")).unwrap_err());
    assert!(err.contains("--animation run: no such animation"), "{err}");
    assert!(err.contains("'slide'"), "{err}");
    let s = load_at(&path, 0.0, None).unwrap();
    assert!(
        s.notes
            .iter()
            .any(|n| n.contains("all 3 animations posed at t = 0 s")),
        "{:?}",
        s.notes
    );
    assert!(
        !s.notes.iter().any(|n| n.contains("ignored")),
        "{:?}",
        s.notes
    );
}

/// Malformed animations are errors naming the file, the animation and what
/// is wrong; none panics.
#[test]
fn malformed_animations_are_errors_with_context() {
    let dir = common::fresh_output_dir("animation", "malformed");
    // Accessors in `rig`: 0 triangle, 1 times 0..2, 2 slide, 3 times 0..1,
    // 4 turn, 5 look.
    let cases = [
        (
            r#"[{"samplers": [{"input": 1, "output": 2}], "channels": [{"sampler": 3, "target": {"node": 0, "path": "translation"}}]}]"#,
            "channel #0: sampler 3 does not exist (the animation has 1)",
        ),
        (
            r#"[{"samplers": [{"input": 1, "output": 4}], "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]}]"#,
            "type is \"VEC4\", expected \"VEC3\"",
        ),
        (
            r#"[{"samplers": [{"input": 1, "output": 2, "interpolation": "CUBICSPLINE"}], "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]}]"#,
            "output has 6 numbers for 2 keyframes",
        ),
        (
            r#"[{"samplers": [{"input": 2, "output": 2}], "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]}]"#,
            "type is \"VEC3\", expected \"SCALAR\"",
        ),
        (
            r#"[{"samplers": [{"input": 0, "output": 2}], "channels": [{"sampler": 0, "target": {"node": 9, "path": "translation"}}]}]"#,
            "target node 9 does not exist",
        ),
        (
            r#"[{"samplers": [{"input": 1, "output": 2, "interpolation": "SMOOTH"}], "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]}]"#,
            "interpolation \"SMOOTH\" is not LINEAR, STEP or CUBICSPLINE",
        ),
        (
            r#"[{"samplers": [{"input": 1, "output": 2}], "channels": [{"sampler": 0, "target": {"node": 1, "path": "weights"}}]}]"#,
            "no mesh with morph targets",
        ),
        (
            r#"[{"samplers": [{"input": 1, "output": 2}], "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}, {"sampler": 0, "target": {"node": 0, "path": "translation"}}]}]"#,
            "channel #1 and channel #0 both drive the translation of node #0",
        ),
        (
            r#"[{"samplers": [{"input": 1, "output": 2}], "channels": [{"sampler": 0, "target": {"node": 0, "path": "size"}}]}]"#,
            "target path Some(\"size\")",
        ),
        (
            r#"[{"samplers": [{"input": 99, "output": 2}], "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]}]"#,
            "input accessor #99 does not exist",
        ),
    ];
    for (k, (animations, expected)) in cases.iter().enumerate() {
        let path = write(&dir, &format!("bad{k}.gltf"), &rig(Some(animations), ""));
        let result = std::panic::catch_unwind(|| load_at(&path, 0.5, None))
            .unwrap_or_else(|_| panic!("case {k}: the loader panicked"));
        let err = format!("{:#}", result.expect_err(&format!("case {k} loads")));
        assert!(err.contains(&format!("bad{k}.gltf")), "case {k}: {err}");
        assert!(err.contains("animation #0"), "case {k}: {err}");
        assert!(
            err.contains(expected),
            "case {k}: expected {expected:?} in: {err}"
        );
    }
}

#[test]
fn keyframe_times_must_increase_and_animated_nodes_must_not_use_a_matrix() {
    let dir = common::fresh_output_dir("animation", "times");
    let mut b = GltfBuilder::default();
    let tri = b.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let times = b.floats(&[0.0, 1.0, 1.0], "SCALAR");
    let values = b.floats(&[0.; 9], "VEC3");
    let text = b.finish(&format!(
        r#""nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {tri}}}}}]}}],
  "animations": [{{"samplers": [{{"input": {times}, "output": {values}}}],
    "channels": [{{"sampler": 0, "target": {{"node": 0, "path": "scale"}}}}]}}]"#
    ));
    let path = write(&dir, "times.gltf", &text);
    let err = format!("{:#}", load_at(&path, 0.0, None).unwrap_err());
    assert!(
        err.contains("animation #0: sampler #0: input times must increase strictly: keyframe 2 is at 1 s, keyframe 1 at 1 s"),
        "{err}"
    );

    let matrix = r#", "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]"#;
    let path = write(&dir, "matrix.gltf", &rig(None, matrix));
    let err = format!("{:#}", load_at(&path, 0.0, None).unwrap_err());
    assert!(err.contains("node #0 'parent'"), "{err}");
    assert!(err.contains("animated but has a matrix"), "{err}");
}

/// Animation pointer channels (no target node) are dropped with a note,
/// and a property two playing animations drive is named.
#[test]
fn unusable_channels_and_conflicts_are_notes() {
    let dir = common::fresh_output_dir("animation", "notes");
    let animations = r#"[
    {"name": "a", "samplers": [{"input": 1, "output": 2}],
      "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}},
                   {"sampler": 0, "target": {"path": "pointer"}}]},
    {"name": "b", "samplers": [{"input": 1, "output": 2}],
      "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]}
  ]"#;
    let path = write(&dir, "notes.gltf", &rig(Some(animations), ""));
    let s = load_at(&path, 1.0, None).unwrap();
    let has = |text: &str| s.notes.iter().any(|n| n.contains(text));
    assert!(
        has("1 animation channel without a target node"),
        "{:?}",
        s.notes
    );
    assert!(
        has("the translation of node #0 is driven by animation #0 'a', animation #1 'b'"),
        "{:?}",
        s.notes
    );
}

/// A triangle skinned to two joints: "j0" at the origin and "j1" at
/// (1, 0, 0) in the bind pose (inverse bind matrices: identity and a
/// translation by -1 in x). Vertex 0 follows j0, vertex 1 j1, vertex 2
/// a quarter j0 and three quarters j1, through both weight sets (JOINTS_0
/// and JOINTS_1: 0.25 j0 + 0.25 j1, then 0.5 j1). "lift" moves j1 from
/// (1, 0, 0) to (1, 2, 0) over 0..1 s. The skinned node's own translation
/// (5, 5, 5) must be ignored.
fn skinned() -> String {
    let mut b = GltfBuilder::default();
    let tri = b.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let joints0 = b.u16s(&[0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0], "VEC4");
    let weights0 = b.floats(
        &[1., 0., 0., 0., 1., 0., 0., 0., 0.25, 0.25, 0., 0.],
        "VEC4",
    );
    let joints1 = b.u16s(&[0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0], "VEC4");
    let weights1 = b.floats(&[0., 0., 0., 0., 0., 0., 0., 0., 0.5, 0., 0., 0.], "VEC4");
    let mut ibm = glam::Mat4::IDENTITY.to_cols_array().to_vec();
    ibm.extend(glam::Mat4::from_translation(Vec3::new(-1., 0., 0.)).to_cols_array());
    let ibm = b.floats(&ibm, "MAT4");
    let times = b.floats(&[0.0, 1.0], "SCALAR");
    let lift = b.floats(&[1., 0., 0., 1., 2., 0.], "VEC3");
    b.finish(&format!(
        r#""scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": [
    {{"name": "skinned", "mesh": 0, "skin": 0, "translation": [5, 5, 5]}},
    {{"name": "j0", "children": [2]}},
    {{"name": "j1", "translation": [1, 0, 0]}}
  ],
  "skins": [{{"joints": [1, 2], "inverseBindMatrices": {ibm}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": {tri}, "JOINTS_0": {joints0}, "WEIGHTS_0": {weights0}, "JOINTS_1": {joints1}, "WEIGHTS_1": {weights1}}}}}]}}],
  "animations": [{{"name": "lift", "samplers": [{{"input": {times}, "output": {lift}}}],
    "channels": [{{"sampler": 0, "target": {{"node": 2, "path": "translation"}}}}]}}]"#
    ))
}

#[test]
fn skins_blend_joint_matrices_over_both_weight_sets() {
    let dir = common::fresh_output_dir("animation", "skin");
    let path = write(&dir, "skinned.gltf", &skinned());
    // t = 0.5: j1 at (1, 1, 0), so its matrix J·IBM is a translation by
    // (0, 1, 0). Vertex 0: (0, 0, 0); vertex 1: (1, 1, 0); vertex 2:
    // 0.25 I + 0.75 T(0, 1, 0) = T(0, 0.75, 0): (0, 1.75, 0).
    let s = load_at(&path, 0.5, None).unwrap();
    let tri = triangle(&s);
    assert_near(tri[0], DVec3::new(0., 0., 0.), "vertex 0 at 0.5 s");
    assert_near(tri[1], DVec3::new(1., 1., 0.), "vertex 1 at 0.5 s");
    assert_near(tri[2], DVec3::new(0., 1.75, 0.), "vertex 2 at 0.5 s");
    // In the bind pose (t = 0) the mesh is where the file stores it.
    let s = load_at(&path, 0.0, None).unwrap();
    let tri = triangle(&s);
    assert_near(tri[1], DVec3::new(1., 0., 0.), "vertex 1 at 0 s");
    assert_near(tri[2], DVec3::new(0., 1., 0.), "vertex 2 at 0 s");
    assert!(!s.notes.iter().any(|n| n.contains("skin")), "{:?}", s.notes);
}

/// One morph target moving vertex 1 by (0, 0, 2); the mesh's default
/// weight is 0.25; "morph" animates the weight from 0 to 1 over 0..1 s.
fn morphed(with_animation: bool) -> String {
    let mut b = GltfBuilder::default();
    let tri = b.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let target = b.floats(&[0., 0., 0., 0., 0., 2., 0., 0., 0.], "VEC3");
    let times = b.floats(&[0.0, 1.0], "SCALAR");
    let weights = b.floats(&[0.0, 1.0], "SCALAR");
    let animations = if with_animation {
        format!(
            r#", "animations": [{{"name": "morph", "samplers": [{{"input": {times}, "output": {weights}}}],
    "channels": [{{"sampler": 0, "target": {{"node": 0, "path": "weights"}}}}]}}]"#
        )
    } else {
        String::new()
    };
    b.finish(&format!(
        r#""nodes": [{{"mesh": 0}}],
  "meshes": [{{"weights": [0.25], "primitives": [{{"attributes": {{"POSITION": {tri}}}, "targets": [{{"POSITION": {target}}}]}}]}}]{animations}"#
    ))
}

#[test]
fn morph_targets_take_animated_weights_else_the_mesh_defaults() {
    let dir = common::fresh_output_dir("animation", "morph");
    // Animated: weight 0.5 at t = 0.5: vertex 1 at (1, 0, 1).
    let path = write(&dir, "morph.gltf", &morphed(true));
    let s = load_at(&path, 0.5, None).unwrap();
    assert_near(
        triangle(&s)[1],
        DVec3::new(1., 0., 1.),
        "vertex 1, weight 0.5",
    );
    assert!(
        !s.notes.iter().any(|n| n.contains("morph targets")),
        "{:?}",
        s.notes
    );
    // Not animated: the mesh's weight 0.25: (1, 0, 0.5).
    let path = write(&dir, "still.gltf", &morphed(false));
    let s = load_at(&path, 0.5, None).unwrap();
    assert_near(
        triangle(&s)[1],
        DVec3::new(1., 0., 0.5),
        "vertex 1, weight 0.25",
    );
}

#[test]
fn malformed_skins_are_errors_with_context() {
    let dir = common::fresh_output_dir("animation", "bad-skin");
    for (k, (from, to, expected)) in [
        (
            r#""joints": [1, 2]"#,
            r#""joints": [1, 9]"#,
            "skin #0: joint node #9 is not in the rendered scene",
        ),
        (
            r#""joints": [1, 2]"#,
            r#""joints": [1]"#,
            "inverseBindMatrices holds 2 matrices for 1 joints",
        ),
    ]
    .iter()
    .enumerate()
    {
        let text = skinned().replace(from, to);
        let path = write(&dir, &format!("bad{k}.gltf"), &text);
        let result = std::panic::catch_unwind(|| load_at(&path, 0.5, None))
            .unwrap_or_else(|_| panic!("case {k}: the loader panicked"));
        let err = match result {
            Ok(_) => panic!("case {k} loads"),
            Err(e) => format!("{e:#}"),
        };
        assert!(
            err.contains(expected),
            "case {k}: expected {expected:?} in: {err}"
        );
        assert!(err.contains(&format!("bad{k}.gltf")), "case {k}: {err}");
    }
}

/// The centre of the triangles of material `name` (a cube: its centre).
fn centre_of(scene: &Scene, name: &str) -> DVec3 {
    let points: Vec<DVec3> = scene
        .triangles
        .iter()
        .filter(|t| scene.materials[t.material as usize].name == name)
        .flat_map(|t| t.positions.map(|p| world(scene, p)))
        .collect();
    assert!(!points.is_empty(), "no triangles of {name}");
    points.iter().sum::<DVec3>() / points.len() as f64
}

/// scenes/animated/interpolation-test.gltf: cubes rising from y = 0.25 to
/// 1.75 over 0..1 s and falling back over 1..2 s. STEP holds the earlier
/// key; LINEAR is halfway (1.0) at 0.5 and 1.5 s; CUBICSPLINE with
/// tangents +3 at 0 s and -3 at 1 s (interval 1 s): at u = 0.5,
/// 0.5·0.25 + 0.125·3 + 0.5·1.75 = 1.375 at 0.5 s and 0.5·1.75 +
/// 0.125·(-3) + 0.5·0.25 = 0.625 at 1.5 s. The turning cube is at 45° at
/// 0.5 s: its +Z face's normal is (sin 45°, 0, cos 45°).
#[test]
fn the_interpolation_scene_poses_each_cube_as_computed_by_hand() {
    let path = common::repo_path("scenes/animated/interpolation-test.gltf");
    for (t, step, linear, cubic) in [
        (0.5, 0.25, 1.0, 1.375),
        (1.5, 1.75, 1.0, 0.625),
        (1.0, 1.75, 1.75, 1.75),
        (3.0, 0.25, 0.25, 0.25),
    ] {
        let s = load_at(&path, t, None).unwrap();
        let y = |name| centre_of(&s, name).y;
        assert!(
            (y("step") - step).abs() < 1e-5,
            "STEP at {t} s: {}",
            y("step")
        );
        assert!(
            (y("linear") - linear).abs() < 1e-5,
            "LINEAR at {t} s: {}",
            y("linear")
        );
        assert!(
            (y("cubicspline") - cubic).abs() < 1e-5,
            "CUBICSPLINE at {t} s: {}",
            y("cubicspline")
        );
    }
    let s = load_at(&path, 0.5, None).unwrap();
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let turned = Vec3::new(h, 0.0, h);
    assert!(
        s.triangles
            .iter()
            .filter(|t| s.materials[t.material as usize].name == "turn")
            .any(|t| (t.normals[0] - turned).length() < 1e-5),
        "no face of the turning cube faces (sin 45°, 0, cos 45°) at 0.5 s"
    );
}

/// Khronos' own animated samples (`tests/data/khronos`, CC0), posed at
/// times whose answers are worked out by hand.
fn khronos(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos")
        .join(name)
}

/// Whether the triangle has a vertex within `tol` of `p`.
fn has_vertex(scene: &Scene, p: DVec3, tol: f64) -> bool {
    triangle(scene).iter().any(|v| (*v - p).length() < tol)
}

/// AnimatedTriangle turns the triangle (0,0,0), (1,0,0), (0,1,0) about +Z
/// through keys 0°, 90°, 180°, 270°, 360° at t = 0, 0.25, 0.5, 0.75, 1 s
/// (quaternions stored with 0.707 for 1/√2, hence the tolerance). At
/// 0.125 s vertex (1,0,0) is at 45°; at 0.875 s slerp must take the short
/// arc from 270° to 360° (the stored keys have a negative dot product), so
/// the vertex is at 315°, where the long arc would put it at 135°; after
/// the last key the last pose holds.
#[test]
fn khronos_animated_triangle_turns_along_the_short_arc() {
    let path = khronos("AnimatedTriangle.gltf");
    let s = std::f64::consts::FRAC_1_SQRT_2;
    for (time, expected) in [
        (0.0, DVec3::new(1.0, 0.0, 0.0)),
        (0.125, DVec3::new(s, s, 0.0)),
        (0.5, DVec3::new(-1.0, 0.0, 0.0)),
        (0.875, DVec3::new(s, -s, 0.0)),
        (3.0, DVec3::new(1.0, 0.0, 0.0)),
    ] {
        let scene = load_at(&path, time, None).expect("AnimatedTriangle loads");
        assert!(
            has_vertex(&scene, expected, 2e-3),
            "t = {time} s: no vertex at {expected}: {:?}",
            triangle(&scene)
        );
        assert!(has_vertex(&scene, DVec3::ZERO, 1e-6), "the pivot stays put");
    }
}

/// SimpleMorph: vertex 2 at (0.5, 0.5, 0) moves by (-1, 1, 0) under target
/// 0 and by (1, 1, 0) under target 1; the weights are keyed (0,0), (0,1),
/// (1,1), (1,0), (0,0) at t = 0..4 s. At 1.5 s the weights are (0.5, 1):
/// (0.5, 0.5) + 0.5 (-1, 1) + (1, 1) = (1, 2). At 3.25 s, (0.75, 0):
/// (-0.25, 1.25). The mesh's default weights (0.5, 0.5) are overridden.
#[test]
fn khronos_simple_morph_follows_its_weight_keys() {
    let path = khronos("SimpleMorph.gltf");
    for (time, expected) in [
        (0.0, DVec3::new(0.5, 0.5, 0.0)),
        (1.5, DVec3::new(1.0, 2.0, 0.0)),
        (3.25, DVec3::new(-0.25, 1.25, 0.0)),
    ] {
        let scene = load_at(&path, time, None).expect("SimpleMorph loads");
        assert!(
            has_vertex(&scene, expected, 1e-5),
            "t = {time} s: no vertex at {expected}: {:?}",
            triangle(&scene)
        );
        assert!(
            !scene.notes.iter().any(|n| n.contains("ignored")),
            "{:?}",
            scene.notes
        );
    }
}

/// Over a shutter the poses share the first one's world origin: a camera
/// sliding past a still triangle and a still lamp leaves both where they
/// are (each pose measured from its own camera would move them, and the
/// lamp's move would send the render to host time steps), and the kernels
/// follow the camera.
#[test]
fn a_moving_camera_leaves_still_objects_and_lights_in_place() {
    // rig()'s accessors 1 (times 0 and 2 s) and 2 (0,0,0 to 4,0,0) move the
    // camera's node (2) instead of the parent.
    let animations = r#"[{"name": "dolly", "samplers": [{"input": 1, "output": 2}],
      "channels": [{"sampler": 0, "target": {"node": 2, "path": "translation"}}]}]"#;
    let text = rig(Some(animations), "");
    let dir = common::fresh_output_dir("animation", "moving-camera");
    let path = write(&dir, "dolly.gltf", &text);
    let file = Scene::open_file(&path, &LoadOptions::default()).expect("opens");
    let mut pose = |t: f64, origin| file.at_from(t, origin);
    let scene = vkpt::scene::motion::pose_over_shutter(&mut pose, 0.25, 0.5)
        .expect("poses")
        .expect("a moving camera with still lights is followed per path");
    let m = scene.motion.as_ref().expect("moves");
    let (first, last) = (&m.steps[0], &m.steps[m.steps.len() - 1]);
    assert_eq!(first.triangles, last.triangles, "the still triangle moved");
    let moved = last.cameras[0].position - first.cameras[0].position;
    assert!(
        (moved - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-5,
        "camera moved {moved}"
    );
}
