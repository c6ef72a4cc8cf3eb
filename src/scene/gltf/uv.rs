//! Texture coordinates and tangents of textured primitives: the
//! `TEXCOORD_0`/`_1` sets their textures read and, for normal maps (the
//! base's and `KHR_materials_clearcoat`'s) and `KHR_materials_anisotropy`
//! (whose direction is relative to the tangent, textured or not), the
//! file's `TANGENT`s or tangents generated from the UVs.

use super::buffer::Buffer;
use super::data::read_accessor;
use super::notes::plural;
use crate::scene::Material;
use crate::scene::tangents::generate_tangents;
use crate::scene::texture::Texcoords;
use anyhow::{Context, Result, ensure};
use glam::{Vec2, Vec3, Vec4};
use gltf::accessor::Dimensions;
use gltf::mesh::Semantic;
use std::collections::BTreeMap;

/// What a material's textures need from the vertices.
#[derive(Clone, Copy, Default)]
pub(super) struct TextureNeeds {
    pub any: bool,
    /// Which texture coordinate sets its textures read.
    sets: [bool; 2],
    /// The texture coordinate set its tangents follow, if it needs
    /// tangents: its normal texture's, else its clearcoat normal texture's,
    /// else (anisotropic) its anisotropy texture's or set 0.
    tangent_texcoord: Option<u32>,
}

impl TextureNeeds {
    pub fn of(m: &Material) -> TextureNeeds {
        let t = &m.textures;
        let anisotropic = m.lobes.anisotropy_strength > 0.0;
        let tangent_texcoord = t
            .normal
            .or(t.clearcoat_normal)
            .map(|r| r.texcoord)
            .or(anisotropic.then(|| t.anisotropy.map_or(0, |r| r.texcoord)));
        TextureNeeds {
            any: m.textures.any() || anisotropic,
            sets: [0, 1].map(|set| {
                m.textures
                    .slots()
                    .iter()
                    .flatten()
                    .any(|t| t.texcoord == set)
            }),
            tangent_texcoord,
        }
    }
}

/// Reads texture coordinates and tangents, counting what was missing or
/// repaired for the notes.
#[derive(Default)]
pub(super) struct UvLoader {
    /// Textured primitives lacking the TEXCOORD_n their textures read.
    missing_texcoords: BTreeMap<u32, usize>,
    generated_tangents: usize,
    nonfinite_texcoords: usize,
}

impl UvLoader {
    /// Object-space texture coordinates and tangents of each triangle of
    /// `prim` (`None` when its material, needing `needs`, has no texture).
    /// `positions` are the primitive's (3 floats each), `tris` its
    /// triangles as vertex indices.
    pub fn primitive(
        &mut self,
        buffers: &[Buffer],
        needs: TextureNeeds,
        prim: &gltf::Primitive,
        positions: &[f32],
        tris: &[[u32; 3]],
    ) -> Result<Option<Vec<Texcoords>>> {
        if !needs.any {
            return Ok(None);
        }
        let n_vertices = positions.len() / 3;
        let to_f32 = |f: f64| f as f32;
        let mut sets: [Option<Vec<Vec2>>; 2] = [None, None];
        for (set, out) in sets.iter_mut().enumerate() {
            let key = format!("TEXCOORD_{set}");
            let Some(accessor) = prim.get(&Semantic::TexCoords(set as u32)) else {
                continue;
            };
            let raw = read_accessor(&accessor, buffers, Dimensions::Vec2, to_f32, 0.0)
                .with_context(|| format!("attribute {key}"))?;
            ensure!(
                raw.len() == 2 * n_vertices,
                "attribute {key} has {} elements but POSITION has {n_vertices}",
                raw.len() / 2
            );
            *out = Some(
                raw.chunks_exact(2)
                    .map(|c| {
                        let uv = Vec2::new(c[0], c[1]);
                        if uv.is_finite() {
                            uv
                        } else {
                            self.nonfinite_texcoords += 1;
                            Vec2::ZERO
                        }
                    })
                    .collect(),
            );
        }
        for (set, uv) in sets.iter().enumerate() {
            if uv.is_none() && needs.sets[set] {
                *self.missing_texcoords.entry(set as u32).or_default() += 1;
            }
        }
        let uv_or_zero = |set: usize| sets[set].clone().unwrap_or(vec![Vec2::ZERO; n_vertices]);
        let uv = [uv_or_zero(0), uv_or_zero(1)];
        let corner_tangents: Vec<[Vec4; 3]> = match needs.tangent_texcoord {
            None => vec![[Vec4::new(0.0, 0.0, 0.0, 1.0); 3]; tris.len()],
            Some(set) => match prim.get(&Semantic::Tangents) {
                Some(accessor) => {
                    let raw = read_accessor(&accessor, buffers, Dimensions::Vec4, to_f32, 0.0)
                        .context("attribute TANGENT")?;
                    file_tangents(&raw, n_vertices, tris)?
                }
                None => {
                    self.generated_tangents += 1;
                    let p: Vec<Vec3> = positions
                        .chunks_exact(3)
                        .map(|p| Vec3::new(p[0], p[1], p[2]))
                        .collect();
                    generate_tangents(&p, &uv[set as usize], tris)
                }
            },
        };
        Ok(Some(
            tris.iter()
                .zip(corner_tangents)
                .map(|(tri, tangents)| Texcoords {
                    uv: [0, 1].map(|set| tri.map(|v| uv[set][v as usize])),
                    tangents,
                })
                .collect(),
        ))
    }

    /// Notes for missing texture coordinates, generated tangents and
    /// repaired UVs.
    pub fn notes(&self, notes: &mut Vec<String>) {
        for (set, n) in &self.missing_texcoords {
            notes.push(format!(
                "{} with a texture reading TEXCOORD_{set} {} no TEXCOORD_{set}: the texture is read at (0, 0) there",
                plural(*n, "primitive", "primitives"),
                if *n == 1 { "has" } else { "have" }
            ));
        }
        if self.generated_tangents > 0 {
            notes.push(format!(
                "generated tangents for normal mapping or anisotropy on {} without TANGENT (from the UVs, per vertex and handedness)",
                plural(self.generated_tangents, "primitive", "primitives")
            ));
        }
        if self.nonfinite_texcoords > 0 {
            notes.push(format!(
                "replaced {} non-finite texture coordinates by (0, 0)",
                self.nonfinite_texcoords
            ));
        }
    }
}

/// The file's TANGENT attribute (`raw`, 4 floats per vertex) at each
/// triangle corner; w is the bitangent sign (±1), a non-finite tangent
/// becomes (0, 0, 0, 1).
fn file_tangents(raw: &[f32], n_vertices: usize, tris: &[[u32; 3]]) -> Result<Vec<[Vec4; 3]>> {
    ensure!(
        raw.len() == 4 * n_vertices,
        "attribute TANGENT has {} elements but POSITION has {n_vertices}",
        raw.len() / 4
    );
    let t: Vec<Vec4> = raw
        .chunks_exact(4)
        .map(|c| {
            let t = Vec4::new(c[0], c[1], c[2], if c[3] < 0.0 { -1.0 } else { 1.0 });
            if t.is_finite() {
                t
            } else {
                Vec4::new(0.0, 0.0, 0.0, 1.0)
            }
        })
        .collect();
    Ok(tris.iter().map(|tri| tri.map(|v| t[v as usize])).collect())
}
