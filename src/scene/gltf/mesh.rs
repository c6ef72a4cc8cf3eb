//! glTF meshes as world-space triangles: each primitive's vertices, indices
//! and triangle mode, transformed by its node, with bad geometry dropped and
//! counted. Texture coordinates and tangents come from `uv.rs`.

use super::buffer::Buffer;
use super::data::{read_accessor, u32_in_place};
use super::document::Gltf;
use super::notes::{name_suffix, plural};
use super::skin::{self, Deform};
use super::uv::{TextureNeeds, UvLoader};
use super::variants::variant_material;
use crate::scene::texture::Texcoords;
use crate::scene::{Material, Scene, Triangle};
use anyhow::{Context, Result, bail, ensure};
use glam::{DMat3, DMat4, DVec3, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};
use rayon::prelude::*;
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::mem::MaybeUninit;

fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}

/// Coordinates beyond this (in scene units, after the node transforms) are
/// treated like infinities: the watertight ray/triangle test multiplies
/// three coordinate differences, which must stay far below f32::MAX
/// ((4e12)^3 is 6.4e37).
const MAX_COORDINATE: f32 = 1e12;

/// A primitive whose stored f32 positions step by more than this fraction
/// of its size (its bounding box's longest side) is named in a note: it
/// lies so far from its own origin (about 10^4 of its sizes) that the file
/// has already rounded its shape, which no rebasing can undo.
const COARSE_STORAGE: f32 = 1e-4;

/// Where a mesh's stored positions are coarsest: the largest coordinate,
/// the float step there, and that step as a fraction of the primitive.
#[derive(Clone, Copy, Default)]
struct Coarse {
    max_coordinate: f32,
    step: f32,
    fraction: f32,
}

/// How coarsely `positions` (x, y, z, ...) are stored, when more coarsely
/// than [`COARSE_STORAGE`] of their own size.
/// (Bounds on every core: min and max give the same bounds in any order
/// but for the sign of a zero, which changes neither the size nor the
/// largest coordinate.)
fn coarse_storage(positions: &[f32]) -> Option<Coarse> {
    let empty = || (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let (lo, hi) = positions
        .par_chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .filter(|p| p.is_finite())
        .fold(empty, |(lo, hi), p| (lo.min(p), hi.max(p)))
        .reduce(empty, |(lo, hi), (a, b)| (lo.min(a), hi.max(b)));
    let size = (hi - lo).max_element();
    let max_coordinate = lo.abs().max(hi.abs()).max_element();
    if !(size > 0.0 && size.is_finite()) {
        return None;
    }
    let step = f32::from_bits(max_coordinate.to_bits() + 1) - max_coordinate;
    let fraction = step / size;
    (fraction > COARSE_STORAGE).then_some(Coarse {
        max_coordinate,
        step,
        fraction,
    })
}

/// Kinds of bad geometry the loader drops, each reported once per file
/// with a count per mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Dropped {
    /// A vertex position is NaN, infinite or beyond `MAX_COORDINATE`.
    NonFinitePosition,
    /// Zero area (collinear or duplicated vertices), or so small that its
    /// normal cannot be computed in f32.
    ZeroArea,
    /// A vertex normal that is NaN, infinite or zero: replaced by the
    /// triangle's face normal (the triangle is kept).
    BadNormal,
}

impl Dropped {
    const ALL: [Dropped; 3] = [
        Dropped::NonFinitePosition,
        Dropped::ZeroArea,
        Dropped::BadNormal,
    ];

    fn describe(self, n: usize) -> String {
        match self {
            Dropped::NonFinitePosition => format!(
                "dropped {} with NaN, infinite or out-of-range (beyond {MAX_COORDINATE:e}) positions",
                plural(n, "triangle", "triangles")
            ),
            Dropped::ZeroArea => format!(
                "dropped {} (collinear or repeated vertices)",
                plural(n, "zero-area triangle", "zero-area triangles")
            ),
            Dropped::BadNormal => format!(
                "replaced {} (NaN, infinite or zero) by the face normal",
                plural(n, "bad vertex normal", "bad vertex normals")
            ),
        }
    }
}

/// A primitive's vertices in object space, as the file stores them
/// (3 floats each).
struct Vertices {
    positions: Vec<f32>,
    normals: Option<Vec<f32>>,
}

/// Turns glTF meshes into world-space triangles, counting what it skips.
pub(super) struct MeshLoader<'a> {
    gltf: &'a Gltf,
    buffers: &'a [Buffer],
    n_materials: usize,
    /// By material index.
    texture_needs: Vec<TextureNeeds>,
    /// One per triangle emitted, when any material has a texture.
    texcoords: Vec<Texcoords>,
    uv: UvLoader,
    uses_default_material: bool,
    skipped_modes: BTreeMap<&'static str, usize>,
    no_positions: usize,
    /// Per kind of bad geometry, how many were dropped in each mesh.
    dropped: BTreeMap<Dropped, BTreeMap<String, usize>>,
    trailing_indices: usize,
    morph_targets: usize,
    /// Meshes whose file positions are too coarse for their size.
    coarse: BTreeMap<String, Coarse>,
}

impl<'a> MeshLoader<'a> {
    pub fn new(gltf: &'a Gltf, buffers: &'a [Buffer], materials: &[Material]) -> Self {
        MeshLoader {
            gltf,
            buffers,
            n_materials: materials.len(),
            texture_needs: materials.iter().map(TextureNeeds::of).collect(),
            texcoords: Vec::new(),
            uv: UvLoader::default(),
            uses_default_material: false,
            skipped_modes: BTreeMap::new(),
            no_positions: 0,
            dropped: BTreeMap::new(),
            trailing_indices: 0,
            morph_targets: 0,
            coarse: BTreeMap::new(),
        }
    }

    /// Appends the triangles of `mesh`, placed by `world`, to `out`.
    pub fn load_mesh(
        &mut self,
        mesh: &gltf::Mesh,
        world: &DMat4,
        deform: &Deform,
        out: &mut Vec<Triangle>,
    ) -> Result<()> {
        let mi = mesh.index();
        let mesh_name = match mesh.name() {
            Some(n) => format!("mesh '{n}'"),
            None => format!("mesh #{mi}"),
        };
        for prim in mesh.primitives() {
            self.load_primitive(&prim, mi, world, deform, &mesh_name, out)
                .with_context(|| {
                    format!(
                        "mesh #{mi}{} primitive #{}",
                        name_suffix(mesh.name()),
                        prim.index()
                    )
                })?;
        }
        Ok(())
    }

    fn load_primitive(
        &mut self,
        prim: &gltf::Primitive,
        mi: usize,
        world: &DMat4,
        deform: &Deform,
        mesh_name: &str,
        out: &mut Vec<Triangle>,
    ) -> Result<()> {
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            *self.skipped_modes.entry(mode_name(mode)).or_default() += 1;
            return Ok(());
        }
        let Some(positions) = prim.get(&Semantic::Positions) else {
            self.no_positions += 1;
            return Ok(());
        };
        let mut vertices = self.read_vertices(prim, &positions)?;
        if let Some(c) = coarse_storage(&vertices.positions) {
            let worst = self.coarse.entry(mesh_name.to_string()).or_default();
            if c.fraction > worst.fraction {
                *worst = c;
            }
        }
        let pi = prim.index();
        if self.has_morph_targets(mi, pi) && deform.weights.is_empty() {
            self.morph_targets += 1;
        }
        let v = &mut vertices;
        skin::morph(
            self.gltf,
            self.buffers,
            (mi, pi),
            &deform.weights,
            &mut v.positions,
            v.normals.as_mut(),
        )?;
        // A skinned mesh is placed by its joints, not by its node.
        let world = match &deform.joints {
            Some(joints) => {
                let n = v.positions.len() / 3;
                let influences =
                    skin::joints_and_weights(self.gltf, self.buffers, (mi, pi), n, joints.len())?;
                skin::skin(joints, &influences, &mut v.positions, v.normals.as_mut());
                &DMat4::IDENTITY
            }
            None => world,
        };
        let indices = self.read_indices(prim, vertices.positions.len() / 3)?;
        let material = self.material_index(prim, mi);
        let tris = self.triangulate(mode, &indices);
        let tris = &tris[..];
        let needs = self
            .texture_needs
            .get(material as usize)
            .copied()
            .unwrap_or_default();
        let texcoords = self
            .uv
            .primitive(self.buffers, needs, prim, &vertices.positions, tris)?;
        self.emit(world, vertices, tris, texcoords, material, mesh_name, out);
        Ok(())
    }

    /// Whether the primitive has morph targets, from the typed JSON: the
    /// crate's `Primitive::morph_targets` looks up their accessors, which
    /// are not checked since vkpt ignores them.
    fn has_morph_targets(&self, mi: usize, pi: usize) -> bool {
        let meshes = &self.gltf.doc.as_json().meshes;
        meshes
            .get(mi)
            .and_then(|m| m.primitives.get(pi))
            .is_some_and(|p| p.targets.is_some())
    }

    /// POSITION and, when present, NORMAL.
    fn read_vertices(
        &self,
        prim: &gltf::Primitive,
        positions: &gltf::Accessor,
    ) -> Result<Vertices> {
        let to_f32 = |f: f64| f as f32;
        let positions = read_accessor(positions, self.buffers, Dimensions::Vec3, to_f32, 0.0)
            .context("attribute POSITION")?;
        let n_vertices = positions.len() / 3;
        let normals = match prim.get(&Semantic::Normals) {
            None => None,
            Some(accessor) => {
                let n = read_accessor(&accessor, self.buffers, Dimensions::Vec3, to_f32, 0.0)
                    .context("attribute NORMAL")?;
                ensure!(
                    n.len() == positions.len(),
                    "attribute NORMAL has {} elements but POSITION has {n_vertices}",
                    n.len() / 3
                );
                Some(n)
            }
        };
        Ok(Vertices { positions, normals })
    }

    /// The primitive's indices (read in place when the file stores them
    /// as u32), each checked against the vertex count, or 0..n_vertices
    /// when it has none.
    fn read_indices(&self, prim: &gltf::Primitive, n_vertices: usize) -> Result<Cow<'a, [u32]>> {
        let Some(accessor) = prim.indices() else {
            ensure!(n_vertices <= u32::MAX as usize, "too many vertices");
            return Ok(Cow::Owned((0..n_vertices as u32).collect()));
        };
        let component_type = accessor.data_type();
        ensure!(
            matches!(component_type, DataType::U8 | DataType::U16 | DataType::U32),
            "indices: accessor #{} has componentType {component_type:?}, not an unsigned integer type",
            accessor.index()
        );
        let idx = match u32_in_place(&accessor, self.buffers) {
            Some(idx) => Cow::Borrowed(idx),
            None => Cow::Owned(
                read_accessor(&accessor, self.buffers, Dimensions::Scalar, |f| f as u32, 0)
                    .context("indices")?,
            ),
        };
        // On every core, a part a task (rayon's `position_first` costs an
        // atomic load per index).
        let first_bad = idx
            .par_chunks(EMIT_PART)
            .enumerate()
            .find_map_first(|(j, part)| {
                let k = part.iter().position(|v| *v as usize >= n_vertices)?;
                Some(j * EMIT_PART + k)
            });
        if let Some(k) = first_bad {
            let bad = idx[k];
            bail!("indices: index #{k} is {bad}, but there are only {n_vertices} vertices");
        }
        Ok(idx)
    }

    /// The primitive's material (the chosen `KHR_materials_variants`
    /// variant's when it maps one), or the glTF default material (appended
    /// after the file's) when it names none. (The crate's checks have made
    /// sure a named material exists.)
    fn material_index(&mut self, prim: &gltf::Primitive, mesh: usize) -> u32 {
        let variant = self
            .gltf
            .variant
            .and_then(|v| variant_material(self.gltf, mesh, prim.index(), v));
        match variant.or(prim.material().index()) {
            Some(m) if m < self.n_materials => m as u32,
            _ => {
                self.uses_default_material = true;
                self.n_materials as u32
            }
        }
    }

    /// Triangles as vertex index triples in the file's winding (a list,
    /// read in place, a strip, or, for any other mode, a fan).
    fn triangulate<'i>(&mut self, mode: Mode, indices: &'i [u32]) -> Cow<'i, [[u32; 3]]> {
        let mut tris: Vec<[u32; 3]> = Vec::new();
        match mode {
            Mode::Triangles => {
                let (tris, rest) = indices.as_chunks::<3>();
                self.trailing_indices += rest.len();
                return Cow::Borrowed(tris);
            }
            Mode::TriangleStrip => {
                // Strip: winding alternates so every triangle keeps the front face.
                for i in 0..indices.len().saturating_sub(2) {
                    tris.push(if i % 2 == 0 {
                        [indices[i], indices[i + 1], indices[i + 2]]
                    } else {
                        [indices[i + 1], indices[i], indices[i + 2]]
                    });
                }
            }
            _ => {
                for i in 1..indices.len().saturating_sub(1) {
                    tris.push([indices[i], indices[i + 1], indices[0]]);
                }
            }
        }
        Cow::Owned(tris)
    }

    fn any_textured(&self) -> bool {
        self.texture_needs.iter().any(|n| n.any)
    }

    /// Places the triangles in the world by `world` (a mirroring transform
    /// swaps two corners so the front face stays in front) and appends
    /// those that are finite and not degenerate to `out`, with their
    /// texture coordinates when any material is textured. On every core,
    /// `EMIT_PART` triangles a task, each written where it ends up: the
    /// same triangles in the file's order.
    #[allow(clippy::too_many_arguments)]
    fn emit(
        &mut self,
        world: &DMat4,
        vertices: Vertices,
        tris: &[[u32; 3]],
        texcoords: Option<Vec<Texcoords>>,
        material: u32,
        mesh_name: &str,
        out: &mut Vec<Triangle>,
    ) {
        // `world` is relative to the world origin and in f64: positions
        // become f32 only once placed near the camera.
        let linear = DMat3::from_mat4(*world);
        let normal_matrix = linear.inverse().transpose();
        // Placed where they were read: no second array to fill.
        let object = |p: &[f32]| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        let Vertices {
            mut positions,
            mut normals,
        } = vertices;
        positions.par_chunks_exact_mut(3).for_each(|p| {
            let w = world.transform_point3(object(p)).as_vec3();
            p.copy_from_slice(&w.to_array());
        });
        if let Some(normals) = &mut normals {
            normals.par_chunks_exact_mut(3).for_each(|n| {
                let w = (normal_matrix * object(n)).normalize_or_zero().as_vec3();
                n.copy_from_slice(&w.to_array());
            });
        }
        let placer = Placer {
            wp: positions.as_chunks::<3>().0,
            wn: normals.as_deref().map(|n| n.as_chunks::<3>().0),
            texcoords: self.any_textured().then_some(texcoords.as_deref()),
            linear: linear.as_mat3(),
            flip: linear.determinant() < 0.0,
            material,
        };
        // Each part writes its triangles straight into the arrays' spare
        // room at its own offset, then the parts are closed up in order
        // over what they dropped: no part buffers to fill and copy again.
        out.reserve(tris.len());
        crate::huge_pages::advise(out);
        let textured = placer.texcoords.is_some();
        if textured {
            self.texcoords.reserve(tris.len());
        }
        let tex_spare = if textured {
            &mut self.texcoords.spare_capacity_mut()[..tris.len()]
        } else {
            &mut [][..]
        };
        let tex_parts: Vec<&mut [MaybeUninit<Texcoords>]> = if textured {
            tex_spare.chunks_mut(EMIT_PART).collect()
        } else {
            tris.chunks(EMIT_PART).map(|_| &mut [][..]).collect()
        };
        let parts: Vec<Placed> = out.spare_capacity_mut()[..tris.len()]
            .par_chunks_mut(EMIT_PART)
            .zip(tex_parts)
            .zip(tris.par_chunks(EMIT_PART))
            .enumerate()
            .map(|(j, ((dst, tex_dst), part))| placer.place(j * EMIT_PART, part, dst, tex_dst))
            .collect();
        let written: Vec<usize> = parts.iter().map(|p| p.written).collect();
        // SAFETY: part j wrote its first `written[j]` slots from offset
        // j * EMIT_PART of each array's spare room (all of them
        // initialized: `place` writes every slot it counts).
        unsafe {
            close_up(out, &written);
            if textured {
                close_up(&mut self.texcoords, &written);
            }
        }
        let mut dropped = [0usize; Dropped::ALL.len()];
        for part in &parts {
            for (sum, n) in dropped.iter_mut().zip(part.dropped) {
                *sum += n;
            }
        }
        for kind in Dropped::ALL {
            if dropped[kind as usize] > 0 {
                *self
                    .dropped
                    .entry(kind)
                    .or_default()
                    .entry(mesh_name.to_string())
                    .or_default() += dropped[kind as usize];
            }
        }
    }

    /// Adds the default material if a primitive used it, hands over the
    /// texture coordinates, and says what was skipped or repaired.
    pub fn finish(self, scene: &mut Scene, notes: &mut Vec<String>) {
        if self.uses_default_material {
            scene.materials.push(Material::gltf_default());
            notes.push(
                "primitives without a material use the glTF default material (white, metallic 1, roughness 1)"
                    .into(),
            );
        }
        scene.texcoords = self.texcoords;
        self.uv.notes(notes);
        for (mode, n) in &self.skipped_modes {
            notes.push(format!(
                "skipped {} with mode {mode} (only triangle modes are rendered yet)",
                plural(*n, "primitive", "primitives")
            ));
        }
        if self.no_positions > 0 {
            notes.push(format!(
                "skipped {} without POSITION",
                plural(self.no_positions, "primitive", "primitives")
            ));
        }
        for (kind, per_mesh) in &self.dropped {
            notes.push(dropped_note(*kind, per_mesh));
        }
        if self.trailing_indices > 0 {
            notes.push(format!(
                "ignored {} left over after the last whole triangle",
                plural(self.trailing_indices, "index", "indices")
            ));
        }
        if !self.coarse.is_empty() {
            notes.push(coarse_note(&self.coarse));
        }
        if self.morph_targets > 0 {
            notes.push(format!(
                "morph targets without weights on {} (neither the node, the mesh nor an animation gives them): the base shape is rendered",
                plural(self.morph_targets, "primitive", "primitives")
            ));
        }
    }
}

/// Names the meshes whose positions the file itself stores too coarsely.
fn coarse_note(coarse: &BTreeMap<String, Coarse>) -> String {
    let worst = coarse.values().copied().fold(Coarse::default(), |w, c| {
        if c.fraction > w.fraction { c } else { w }
    });
    let names: Vec<String> = coarse.keys().cloned().collect();
    let shown = match names.len() {
        n if n > 5 => format!("{} and {} more meshes", names[..5].join(", "), n - 5),
        _ => names.join(", "),
    };
    format!(
        "{shown} {} positions far from {} own origin in f32 (up to {:.1e}, in steps of {:.2e}, {:.2} % of {}): the file has already rounded {} shape; vkpt composes node transforms in f64 and renders relative to the camera, but cannot recover bits the file does not hold (store positions near the mesh's origin and place it with a node translation)",
        if names.len() == 1 { "stores" } else { "store" },
        if names.len() == 1 { "its" } else { "their" },
        worst.max_coordinate,
        worst.step,
        worst.fraction * 100.0,
        if names.len() == 1 {
            "its size"
        } else {
            "a primitive's size"
        },
        if names.len() == 1 { "its" } else { "their" },
    )
}

/// `warning: dropped 3 zero-area triangles in mesh 'a' (2), mesh 'b' (1)`.
fn dropped_note(kind: Dropped, per_mesh: &BTreeMap<String, usize>) -> String {
    let total: usize = per_mesh.values().sum();
    let meshes: Vec<String> = per_mesh
        .iter()
        .map(|(mesh, n)| {
            if per_mesh.len() == 1 {
                mesh.clone()
            } else {
                format!("{mesh} ({n})")
            }
        })
        .collect();
    let shown = meshes
        .iter()
        .take(5)
        .cloned()
        .collect::<Vec<_>>()
        .join(", ");
    let more = match meshes.len() {
        n if n > 5 => format!(" and {} more meshes", n - 5),
        _ => String::new(),
    };
    format!("warning: {} in {shown}{more}", kind.describe(total))
}

/// Triangles per parallel task of `emit`.
const EMIT_PART: usize = 1 << 13;

/// What placing one primitive's triangles needs (`MeshLoader::emit`).
struct Placer<'a> {
    /// Positions and normals in the world.
    wp: &'a [[f32; 3]],
    wn: Option<&'a [[f32; 3]]>,
    /// Some when any material is textured: the primitive's texture
    /// coordinates (None: it has none, and gets zeros).
    texcoords: Option<Option<&'a [Texcoords]>>,
    linear: glam::Mat3,
    flip: bool,
    material: u32,
}

/// How many triangles a part wrote, and the dropped or repaired ones by
/// kind.
struct Placed {
    written: usize,
    dropped: [usize; Dropped::ALL.len()],
}

/// Moves each part's `written[j]` elements, at `v.len() + j * EMIT_PART`
/// in `v`'s spare room, down to follow the part before, and takes them
/// into `v`.
///
/// # Safety
/// Those elements must be initialized.
unsafe fn close_up<T: Copy>(v: &mut Vec<T>, written: &[usize]) {
    let base = v.len();
    let mut len = base;
    let p = v.as_mut_ptr();
    for (j, &n) in written.iter().enumerate() {
        let from = base + j * EMIT_PART;
        if from != len {
            // SAFETY: both ranges lie within the capacity (`from + n` is
            // within the reserved room, `len <= from`); `copy` allows the
            // overlap.
            unsafe { std::ptr::copy(p.add(from), p.add(len), n) };
        }
        len += n;
    }
    // SAFETY: the first `len` elements are initialized (the caller's).
    unsafe { v.set_len(len) };
}

impl Placer<'_> {
    /// Places `part`, whose first triangle is the primitive's `first`,
    /// into the first slots of `dst` (and its texture coordinates into
    /// `tex_dst` when textured); says how many.
    fn place(
        &self,
        first: usize,
        part: &[[u32; 3]],
        dst: &mut [MaybeUninit<Triangle>],
        tex_dst: &mut [MaybeUninit<Texcoords>],
    ) -> Placed {
        let mut placed = Placed {
            written: 0,
            dropped: [0; Dropped::ALL.len()],
        };
        let flip = self.flip;
        for (i, &[a, b, c]) in part.iter().enumerate() {
            let (a, b, c) = (a as usize, b as usize, c as usize);
            let corners = if flip { [0, 2, 1] } else { [0, 1, 2] };
            let (b, c) = if flip { (c, b) } else { (b, c) };
            let p = [a, b, c].map(|v| Vec3::from_array(self.wp[v]));
            let in_range = |v: &Vec3| v.is_finite() && v.abs().max_element() <= MAX_COORDINATE;
            if !p.iter().all(in_range) {
                placed.dropped[Dropped::NonFinitePosition as usize] += 1;
                continue;
            }
            // The kernels normalize this cross product: its squared length
            // must be a normal float (GPUs flush denormals to zero).
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let len2 = cross.length_squared();
            if !(len2 >= f32::MIN_POSITIVE && len2.is_finite()) {
                placed.dropped[Dropped::ZeroArea as usize] += 1;
                continue;
            }
            let face = cross / len2.sqrt();
            let normals = match self.wn {
                Some(wn) => [a, b, c].map(|v| {
                    let n = Vec3::from_array(wn[v]);
                    if n.is_finite() && n != Vec3::ZERO {
                        n
                    } else {
                        placed.dropped[Dropped::BadNormal as usize] += 1;
                        face
                    }
                }),
                None => [face; 3],
            };
            dst[placed.written].write(Triangle {
                positions: p,
                normals,
                material: self.material,
            });
            if let Some(texcoords) = self.texcoords {
                let t = texcoords.map_or(Texcoords::default(), |t| {
                    let src = &t[first + i];
                    let sign = if flip { -1.0 } else { 1.0 };
                    Texcoords {
                        uv: src.uv.map(|set| corners.map(|i| set[i])),
                        tangents: corners.map(|i| {
                            let t = src.tangents[i];
                            (self.linear * t.truncate())
                                .normalize_or_zero()
                                .extend(t.w * sign)
                        }),
                    }
                });
                tex_dst[placed.written].write(t);
            }
            placed.written += 1;
        }
        placed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parts that dropped some of their triangles are closed up in order,
    /// after what the vector already held.
    #[test]
    fn close_up_joins_the_parts_in_order() {
        let mut v: Vec<u32> = vec![7, 8];
        let written = [3, EMIT_PART, 0, 2];
        v.reserve(written.len() * EMIT_PART);
        let spare = v.spare_capacity_mut();
        for (j, &n) in written.iter().enumerate() {
            for k in 0..n {
                spare[j * EMIT_PART + k].write((1000 * j + k) as u32);
            }
        }
        // SAFETY: the slots just written.
        unsafe { close_up(&mut v, &written) };
        let mut expected = vec![7, 8];
        for (j, &n) in written.iter().enumerate() {
            expected.extend((0..n).map(|k| (1000 * j + k) as u32));
        }
        assert_eq!(v, expected);
    }
}
