//! The scene's two-level BVH flattened for a GPU traversal (`gpu/shaders/bvh.wgsl`): the
//! binary trees that obvhs's PLOC builds and [`SceneBvh`] keeps for refits, as they are built
//! (no new build but the top level's binary tree, O(instances)), in one node array.
//!
//! Why the binary tree and not the compressed wide BVH the CPU queries: a BVH2 node is two
//! boxes' worth of floats that a shader reads without decoding, its traversal is a short
//! loop over one stack, and the same nodes serve the meshes and the top level. The CWBVH's
//! 80-byte 8-wide nodes with quantised child boxes save memory bandwidth on a real GPU (the
//! follow-up once a GPU measures the traversal), at the cost of the octant-ordered traversal
//! of Ylitie et al. in WGSL.

use super::bvh::{top_bvh2, SceneBvh};
use bytemuck::{Pod, Zeroable};
use obvhs::bvh2::Bvh2;

/// No node, instance or triangle.
pub const NONE: u32 = u32::MAX;

/// `BvhNode` in WGSL (32 bytes): a box, and `count` triangles (instances at the top level)
/// from `first` when `count > 0`, else two children at `first` and `first + 1`. Indices
/// are absolute (into [`FlatBvh::nodes`], [`FlatBvh::tris`], [`FlatBvh::instances`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FlatNode {
    pub min: [f32; 3],
    pub count: u32,
    pub max: [f32; 3],
    pub first: u32,
}

/// `BvhTri` in WGSL (48 bytes): a triangle as the CPU's Möller–Trumbore test holds it
/// (corner 0, then the edges to corners 1 and 2, computed on the CPU so both sides test the
/// same floats); the w of the corner row holds the bits of the triangle's index in its mesh.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FlatTri {
    pub rows: [[f32; 4]; 3],
}

/// `BvhInstance` in WGSL (64 bytes): the world → mesh transform as three rows
/// (`local.i = dot(row_i.xyz, p) + row_i.w`), then the mesh's root node (`NONE`: an empty
/// mesh), the instance's first flat triangle, and 1 when it is mirrored (barycentrics swap,
/// as [`SceneBvh::intersect`] does), and a zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FlatInstance {
    pub rows: [[f32; 4]; 3],
    pub refs: [u32; 4],
}

/// The flattened BVH: the top level's nodes from `top_root` (`NONE`: no instance), then
/// each mesh's; the instances in the top level's leaf order; the triangles in their
/// meshes' leaf order.
pub struct FlatBvh {
    pub nodes: Vec<FlatNode>,
    pub tris: Vec<FlatTri>,
    pub instances: Vec<FlatInstance>,
    pub top_root: u32,
}

/// Appends `bvh`'s nodes to `nodes` with child indices made absolute and leaf indices
/// shifted by `leaf_base`; returns the root's index (`NONE` for an empty tree).
fn append_nodes(nodes: &mut Vec<FlatNode>, bvh: &Bvh2, leaf_base: u32) -> u32 {
    if bvh.nodes.is_empty() {
        return NONE;
    }
    let base = nodes.len() as u32;
    nodes.extend(bvh.nodes.iter().map(|n| FlatNode {
        min: n.aabb().min.into(),
        count: n.prim_count,
        max: n.aabb().max.into(),
        first: n.first_index + if n.is_leaf() { leaf_base } else { base },
    }));
    base
}

impl FlatBvh {
    /// Flattens `bvh`; `None` when it cuts hits out by alpha masks (the GPU has no masks).
    pub fn new(bvh: &SceneBvh) -> Option<FlatBvh> {
        if bvh.has_alpha_masks() {
            return None;
        }
        let top = top_bvh2(&bvh.meshes, &bvh.instances);
        let mut nodes = Vec::new();
        let top_root = append_nodes(&mut nodes, &top, 0);
        let mut tris = Vec::new();
        let mut roots = Vec::with_capacity(bvh.meshes.len());
        for mesh in &bvh.meshes {
            roots.push(append_nodes(&mut nodes, &mesh.bvh2, tris.len() as u32));
            tris.extend(mesh.bvh2.primitive_indices.iter().map(|&id| {
                let t = &mesh.triangles[id as usize];
                FlatTri {
                    rows: [
                        t.v0.extend(f32::from_bits(id)).into(),
                        (t.v1 - t.v0).extend(0.0).into(),
                        (t.v2 - t.v0).extend(0.0).into(),
                    ],
                }
            }));
        }
        let instances = top
            .primitive_indices
            .iter()
            .map(|&i| {
                let i = &bvh.instances[i as usize];
                let m = i.to_local.matrix3;
                let t = i.to_local.translation;
                let row = |r: usize| [m.x_axis[r], m.y_axis[r], m.z_axis[r], t[r]];
                FlatInstance {
                    rows: [row(0), row(1), row(2)],
                    refs: [
                        roots[i.mesh as usize],
                        i.first_triangle,
                        i.flipped as u32,
                        0,
                    ],
                }
            })
            .collect();
        Some(FlatBvh {
            nodes,
            tris,
            instances,
            top_root,
        })
    }
}
