//! The packed scene as the CPU back end reads it: the arrays the kernels
//! read (`PackedScene`), and copies of some of them decoded or rearranged
//! for the CPU's vector code, each built the first time a traversal asks
//! for it. The Vulkan back end never builds them, and a render that does
//! not take a traversal never pays for its copy.

pub mod light_tree_steps;
pub mod node_planes;
pub mod triangle_blocks;
pub mod triangle_soa;

use crate::packed::PackedScene;
use std::sync::OnceLock;

/// A `PackedScene` with the CPU back end's copies of it. It dereferences to
/// the packed scene, so the kernels' twins (`cpu::common`) take it where
/// they take a `PackedScene`.
pub struct CpuScene<'a> {
    packed: &'a PackedScene,
    /// `tri_verts` as structure of arrays (`triangle_soa`).
    triangle_soa: OnceLock<triangle_soa::TriangleSoa>,
    /// `nodes` with their boxes decoded from the grid (`decoded_nodes`).
    decoded_nodes: OnceLock<Vec<node_planes::DecodedNode>>,
    /// `nodes` with their boxes shrunk to the exact bounds (`tight_nodes`).
    tight_nodes: OnceLock<Vec<node_planes::DecodedNode>>,
    /// Each node's leaf triangles in blocks of eight (`triangle_blocks`).
    triangle_blocks: OnceLock<Vec<triangle_blocks::TriangleBlock>>,
    /// The same a register at a time (`window_blocks`).
    window_blocks: OnceLock<Vec<triangle_blocks::WindowBlock>>,
    /// Whether no single ray can exhaust the traversal's work budget or
    /// stack here (`traversal::order_free`, cached).
    order_free: OnceLock<bool>,
    /// The light BVH's steps as vectors (`light_tree_steps`).
    light_tree_steps: OnceLock<Vec<light_tree_steps::LightTreeStep>>,
}

impl<'a> CpuScene<'a> {
    pub fn new(packed: &'a PackedScene) -> CpuScene<'a> {
        CpuScene {
            packed,
            triangle_soa: OnceLock::new(),
            decoded_nodes: OnceLock::new(),
            tight_nodes: OnceLock::new(),
            triangle_blocks: OnceLock::new(),
            window_blocks: OnceLock::new(),
            order_free: OnceLock::new(),
            light_tree_steps: OnceLock::new(),
        }
    }

    /// The triangles' vertices as structure of arrays.
    pub fn triangle_soa(&self) -> &triangle_soa::TriangleSoa {
        self.triangle_soa.get_or_init(|| match &self.packed.motion {
            Some(m) => triangle_soa::TriangleSoa::moving(m, self.packed.tri_verts.len()),
            None => triangle_soa::TriangleSoa::new(&self.packed.tri_verts),
        })
    }

    /// The nodes with their children's boxes as floats.
    pub fn decoded_nodes(&self) -> &[node_planes::DecodedNode] {
        self.decoded_nodes
            .get_or_init(|| node_planes::decode_nodes(&self.packed.nodes))
    }

    /// The nodes with each child's box at its exact bounds: for traversals
    /// whose order and work do not change their hits, in a still scene
    /// (`node_planes::tight_nodes`); their `triangle_block` is the first of
    /// `window_blocks`.
    pub fn tight_nodes(&self) -> &[node_planes::DecodedNode] {
        self.tight_nodes.get_or_init(|| match &self.packed.motion {
            Some(_) => node_planes::decode_nodes(&self.packed.nodes),
            None => node_planes::tight_nodes(&self.packed.nodes, &self.packed.tri_verts),
        })
    }

    /// The nodes' leaf triangles in blocks of eight (empty for a moving
    /// scene, whose traversal reads `triangle_soa`).
    pub fn triangle_blocks(&self) -> &[triangle_blocks::TriangleBlock] {
        self.triangle_blocks
            .get_or_init(|| match &self.packed.motion {
                Some(_) => Vec::new(),
                None => triangle_blocks::build(&self.packed.nodes, &self.packed.tri_verts),
            })
    }

    /// The nodes' leaf triangles in blocks of a register (`wide::WIDTH`;
    /// empty for a moving scene): the windows `tight_nodes`'
    /// `triangle_block` indexes.
    pub fn window_blocks(&self) -> &[triangle_blocks::WindowBlock] {
        self.window_blocks
            .get_or_init(|| match &self.packed.motion {
                Some(_) => Vec::new(),
                None => triangle_blocks::build_windows(&self.packed.nodes, &self.packed.tri_verts),
            })
    }

    /// The light BVH's interior nodes' steps (`fast::light_tree_walk`).
    pub fn light_tree_steps(&self) -> &[light_tree_steps::LightTreeStep] {
        self.light_tree_steps
            .get_or_init(|| light_tree_steps::build(&self.packed.light_tree.nodes))
    }

    /// `order_free`, decided on first use by `decide`.
    pub fn order_free(&self, decide: impl FnOnce(&PackedScene) -> bool) -> bool {
        *self.order_free.get_or_init(|| decide(self.packed))
    }
}

impl std::ops::Deref for CpuScene<'_> {
    type Target = PackedScene;
    fn deref(&self) -> &PackedScene {
        self.packed
    }
}
