//! glTF animations: read from the file's JSON (the typed document leaves
//! them out, `document.rs`), checked, and sampled into node poses.
//!
//! Time: every animation that plays is sampled at the same instant `t`
//! (seconds, `--time`, default 0), as viewers play all of a file's
//! animations from 0 together; before its first keyframe a channel holds
//! its first value, after its last its last value (no looping). Time 0 is
//! therefore the animations' first pose, which may differ from the nodes'
//! rest transforms: that is what a glTF viewer shows at 0. A file without
//! animations is rendered from its rest transforms whatever `t` is.

use super::buffer::Buffer;
use super::data::read_accessor;
use super::document::Gltf;
use super::json::array;
use super::keyframes::{Interpolation, Keyframes};
use super::notes::{list, name_suffix, plural};
use anyhow::{Context, Result, anyhow, bail, ensure};
use glam::{DQuat, DVec3};
use gltf::accessor::Dimensions;
use gltf::json::Value;

/// Which node property a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum TargetPath {
    Translation,
    Rotation,
    Scale,
    /// Morph target weights.
    Weights,
}

impl TargetPath {
    fn name(self) -> &'static str {
        match self {
            TargetPath::Translation => "translation",
            TargetPath::Rotation => "rotation",
            TargetPath::Scale => "scale",
            TargetPath::Weights => "weights",
        }
    }
}

/// One channel: `sampler`'s keyframes drive `path` of node `node`.
#[derive(Clone, Debug)]
pub(crate) struct Channel {
    pub node: usize,
    pub path: TargetPath,
    pub sampler: usize,
}

/// One glTF animation, checked: every channel's sampler exists and has
/// keyframes of the shape its target needs.
#[derive(Clone, Debug)]
pub(crate) struct Animation {
    pub index: usize,
    pub name: Option<String>,
    pub channels: Vec<Channel>,
    pub samplers: Vec<Keyframes>,
}

impl Animation {
    /// `animation #1 'Walk'`.
    pub fn label(&self) -> String {
        format!(
            "animation #{}{}",
            self.index,
            name_suffix(self.name.as_deref())
        )
    }

    /// The first and last keyframe times over its channels.
    pub fn range(&self) -> (f64, f64) {
        self.channels
            .iter()
            .map(|c| self.samplers[c.sampler].range())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (a, b)| {
                (lo.min(a), hi.max(b))
            })
    }
}

/// A node's animated properties at one instant; `None` keeps the node's
/// own value.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct NodePose {
    pub translation: Option<DVec3>,
    pub rotation: Option<DQuat>,
    pub scale: Option<DVec3>,
    pub weights: Option<Vec<f64>>,
}

impl NodePose {
    pub fn is_animated(&self) -> bool {
        *self != NodePose::default()
    }
}

/// Reads and checks every animation in the file. Channels vkpt cannot
/// apply (no target node, as `KHR_animation_pointer` writes them) are
/// dropped with a note; anything malformed is an error naming the
/// animation, channel or sampler.
pub(super) fn load_animations(
    gltf: &Gltf,
    buffers: &[Buffer],
    notes: &mut Vec<String>,
) -> Result<Vec<Animation>> {
    let mut out = Vec::new();
    let mut pointer_channels = 0usize;
    for (index, json) in array(&gltf.json, "animations").iter().enumerate() {
        let name = json.get("name").and_then(Value::as_str).map(str::to_string);
        let label = format!("animation #{index}{}", name_suffix(name.as_deref()));
        let (animation, skipped) =
            load_animation(gltf, buffers, index, name, json).with_context(|| label)?;
        pointer_channels += skipped;
        out.push(animation);
    }
    if pointer_channels > 0 {
        notes.push(format!(
            "{} without a target node (KHR_animation_pointer) ignored",
            plural(pointer_channels, "animation channel", "animation channels")
        ));
    }
    Ok(out)
}

fn load_animation(
    gltf: &Gltf,
    buffers: &[Buffer],
    index: usize,
    name: Option<String>,
    json: &Value,
) -> Result<(Animation, usize)> {
    let sampler_json = array(json, "samplers");
    let mut channels = Vec::new();
    let mut skipped = 0;
    // The width (numbers per element) each sampler must have, from the
    // channels that use it.
    let mut widths: Vec<Option<(usize, TargetPath)>> = vec![None; sampler_json.len()];
    let node_count = gltf.doc.nodes().len();
    for (ci, c) in array(json, "channels").iter().enumerate() {
        let clabel = format!("channel #{ci}");
        let sampler =
            c.get("sampler")
                .and_then(Value::as_u64)
                .ok_or_else(|| anyhow!("{clabel} has no sampler index"))? as usize;
        ensure!(
            sampler < sampler_json.len(),
            "{clabel}: sampler {sampler} does not exist (the animation has {})",
            sampler_json.len()
        );
        let target = c
            .get("target")
            .ok_or_else(|| anyhow!("{clabel} has no target"))?;
        let path = match target.get("path").and_then(Value::as_str) {
            Some("translation") => TargetPath::Translation,
            Some("rotation") => TargetPath::Rotation,
            Some("scale") => TargetPath::Scale,
            Some("weights") => TargetPath::Weights,
            Some("pointer") => {
                skipped += 1;
                continue;
            }
            other => bail!(
                "{clabel}: target path {other:?} is not translation, rotation, scale or weights"
            ),
        };
        let Some(node) = target.get("node") else {
            skipped += 1;
            continue;
        };
        let node = node
            .as_u64()
            .map(|n| n as usize)
            .filter(|&n| n < node_count)
            .ok_or_else(|| {
                anyhow!("{clabel}: target node {node} does not exist (the file has {node_count})")
            })?;
        if let Some(prev) = channels
            .iter()
            .position(|p: &Channel| p.node == node && p.path == path)
        {
            bail!(
                "{clabel} and channel #{prev} both drive the {} of node #{node}",
                path.name()
            );
        }
        let width = match path {
            TargetPath::Translation | TargetPath::Scale => 3,
            TargetPath::Rotation => 4,
            TargetPath::Weights => morph_target_count(gltf, node)
                .ok_or_else(|| anyhow!("{clabel} drives the weights of node #{node}, which has no mesh with morph targets"))?,
        };
        if let Some((w, p)) = widths[sampler] {
            ensure!(
                w == width,
                "{clabel}: sampler {sampler} also drives a {} ({w} numbers per keyframe), not a {} ({width})",
                p.name(),
                path.name()
            );
        }
        widths[sampler] = Some((width, path));
        channels.push(Channel {
            node,
            path,
            sampler,
        });
    }
    let mut samplers = Vec::with_capacity(sampler_json.len());
    for (si, s) in sampler_json.iter().enumerate() {
        // A sampler no channel uses is not read.
        let keys = match widths[si] {
            Some((width, path)) => load_sampler(gltf, buffers, s, width, path)
                .with_context(|| format!("sampler #{si}"))?,
            None => Keyframes {
                times: vec![0.0],
                values: Vec::new(),
                width: 0,
                interpolation: Interpolation::Step,
            },
        };
        samplers.push(keys);
    }
    let animation = Animation {
        index,
        name,
        channels,
        samplers,
    };
    Ok((animation, skipped))
}

/// The number of morph targets of node `node`'s mesh (that of its first
/// primitive; glTF requires all primitives to have the same count), or
/// `None` without a mesh or targets.
fn morph_target_count(gltf: &Gltf, node: usize) -> Option<usize> {
    let mesh = gltf.doc.nodes().nth(node)?.mesh()?;
    let prim = mesh.primitives().next()?;
    let n = prim.morph_targets().len();
    (n > 0).then_some(n)
}

fn load_sampler(
    gltf: &Gltf,
    buffers: &[Buffer],
    json: &Value,
    width: usize,
    path: TargetPath,
) -> Result<Keyframes> {
    let interpolation = match json.get("interpolation").map(|v| v.as_str()) {
        None | Some(Some("LINEAR")) => Interpolation::Linear,
        Some(Some("STEP")) => Interpolation::Step,
        Some(Some("CUBICSPLINE")) => Interpolation::CubicSpline,
        Some(_) => bail!(
            "interpolation {} is not LINEAR, STEP or CUBICSPLINE",
            json["interpolation"]
        ),
    };
    let accessor = |key: &str| -> Result<gltf::Accessor> {
        let i = json
            .get(key)
            .and_then(Value::as_u64)
            .ok_or_else(|| anyhow!("no {key} accessor"))? as usize;
        gltf.doc.accessors().nth(i).ok_or_else(|| {
            anyhow!(
                "{key} accessor #{i} does not exist (the file has {})",
                gltf.doc.accessors().len()
            )
        })
    };
    let times = read_accessor(&accessor("input")?, buffers, Dimensions::Scalar, |f| f, 0.0)
        .context("input (keyframe times)")?;
    ensure!(!times.is_empty(), "input has no keyframes");
    if let Some(bad) = times.iter().position(|t| !t.is_finite()) {
        bail!("input keyframe {bad} is not a finite time: {}", times[bad]);
    }
    if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
        bail!(
            "input times must increase strictly: keyframe {} is at {} s, keyframe {k} at {} s",
            k + 1,
            times[k + 1],
            times[k]
        );
    }
    let dims = match path {
        TargetPath::Translation | TargetPath::Scale => Dimensions::Vec3,
        TargetPath::Rotation => Dimensions::Vec4,
        TargetPath::Weights => Dimensions::Scalar,
    };
    let values = read_accessor(&accessor("output")?, buffers, dims, |f| f, 0.0)
        .context("output (keyframe values)")?;
    let per_key = interpolation.elements_per_key() * width;
    ensure!(
        values.len() == times.len() * per_key,
        "output has {} numbers for {} keyframes: a {} channel with {interpolation:?} needs {per_key} per keyframe ({})",
        values.len(),
        times.len(),
        path.name(),
        times.len() * per_key
    );
    if let Some(bad) = values.iter().position(|v| !v.is_finite()) {
        bail!("output value {bad} is not finite: {}", values[bad]);
    }
    Ok(Keyframes {
        times,
        values,
        width,
        interpolation,
    })
}

/// The animations that play: the one `wanted` names (a name, else an
/// index), or all of them.
pub(super) fn select(animations: Vec<Animation>, wanted: Option<&str>) -> Result<Vec<Animation>> {
    let Some(wanted) = wanted else {
        return Ok(animations);
    };
    let found = animations
        .iter()
        .position(|a| a.name.as_deref() == Some(wanted))
        .or_else(|| {
            wanted
                .parse::<usize>()
                .ok()
                .filter(|&i| i < animations.len())
        });
    match found {
        Some(i) => Ok(vec![animations[i].clone()]),
        None if animations.is_empty() => {
            bail!("--animation {wanted}: the file has no animations")
        }
        None => {
            let names: Vec<String> = animations.iter().map(Animation::label).collect();
            bail!(
                "--animation {wanted}: no such animation; the file has {}",
                list(&names)
            )
        }
    }
}

/// The pose of every node (indexed by node) at time `t` under the
/// animations that play; where two animations drive the same property the
/// later one in the file wins (see [`conflicts`]).
pub(super) fn pose_at(animations: &[Animation], node_count: usize, t: f64) -> Vec<NodePose> {
    let mut poses = vec![NodePose::default(); node_count];
    for a in animations {
        for c in &a.channels {
            let keys = &a.samplers[c.sampler];
            let pose = &mut poses[c.node];
            match c.path {
                TargetPath::Translation => pose.translation = Some(vec3(&keys.sample(t))),
                TargetPath::Scale => pose.scale = Some(vec3(&keys.sample(t))),
                TargetPath::Rotation => pose.rotation = Some(keys.sample_rotation(t)),
                TargetPath::Weights => pose.weights = Some(keys.sample(t)),
            }
        }
    }
    poses
}

fn vec3(v: &[f64]) -> DVec3 {
    DVec3::new(v[0], v[1], v[2])
}

/// Notes on what plays at `t`: which animations, their time span, and
/// properties two of them drive at once.
pub(super) fn describe(playing: &[Animation], total: usize, t: f64, notes: &mut Vec<String>) {
    if total == 0 {
        return;
    }
    let (lo, hi) = playing
        .iter()
        .map(Animation::range)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (a, b)| {
            (lo.min(a), hi.max(b))
        });
    let what = if playing.len() == total {
        if total == 1 {
            playing[0].label()
        } else {
            format!("all {total} animations")
        }
    } else {
        format!("{} (of {total})", playing[0].label())
    };
    let mut note = format!("{what} posed at t = {t} s (keyframes {lo}..{hi} s)");
    if t < lo {
        note.push_str(": before the first keyframe, the first pose holds");
    } else if t > hi {
        note.push_str(": after the last keyframe, the last pose holds");
    }
    notes.push(note);
    notes.extend(conflicts(playing));
}

/// Node properties driven by more than one of the animations that play:
/// one note per set of animations, counting the properties and naming a
/// few (a rigged character's three clips would otherwise give a line per
/// bone).
fn conflicts(playing: &[Animation]) -> Vec<String> {
    let mut seen: std::collections::BTreeMap<(usize, TargetPath), Vec<String>> = Default::default();
    for a in playing {
        for c in &a.channels {
            seen.entry((c.node, c.path)).or_default().push(a.label());
        }
    }
    let mut by_animations: std::collections::BTreeMap<Vec<String>, Vec<String>> =
        Default::default();
    for ((node, path), by) in seen {
        if by.len() > 1 {
            by_animations
                .entry(by)
                .or_default()
                .push(format!("the {} of node #{node}", path.name()));
        }
    }
    by_animations
        .into_iter()
        .map(|(by, properties)| match properties.as_slice() {
            [one] => format!(
                "{one} is driven by {}: the last wins (pick one with --animation)",
                by.join(", ")
            ),
            many => {
                const SHOWN: usize = 3;
                let more = match many.len() - SHOWN.min(many.len()) {
                    0 => String::new(),
                    n => format!(" and {n} more"),
                };
                format!(
                    "{} node properties are driven by {}: the last wins (pick one with --animation); e.g. {}{more}",
                    many.len(),
                    by.join(", "),
                    many[..SHOWN.min(many.len())].join(", ")
                )
            }
        })
        .collect()
}
