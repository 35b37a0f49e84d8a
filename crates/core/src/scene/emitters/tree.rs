//! The emitters that the GPU direct pass samples per shading point: those of no polygon
//! group (tessellated spheres, meshes: too many triangles for the closed form), untextured,
//! as a light BVH ([`LightBvh`]: each node's power, box and cone of normals) flattened into
//! texels. Each pixel descends it for its own light samples, choosing by importance at its
//! point (power, distance, orientation of both surfaces) instead of sharing the frame's
//! few points (`raster/shaders/common/emitter_tree.wgsl`).

use super::{Emitters, PolygonGroups};
use crate::scene::light_bvh::{LightBounds, LightBvh};
use crate::scene::Scene;
use std::f32::consts::PI;

/// Texels per entry (a node or an emitting triangle) of [`PixelTree::texels`].
pub const TREE_ENTRY_TEXELS: u32 = 4;

/// Most entries: their indices travel as `f32` texel values (exact below 2²⁴).
const MAX_ENTRIES: usize = 1 << 24;

/// A light BVH over emitting triangles as GPU texels: the nodes depth-first, then the
/// triangles, [`TREE_ENTRY_TEXELS`] texels each.
///
/// A node: (box min, power), (box max, cos θo), (cone axis, cos θe), (1 for a leaf,
/// 1 when two-sided, the leaf's triangle or an interior node's second child, 0); the first
/// child of an interior node follows it. A triangle: (corner a, area/π: the radius² of the
/// near-field disc), (corner b, 1 when two-sided), (corner c, area), (radiance, 0).
#[derive(Clone, Debug)]
pub struct PixelTree {
    pub nodes: u32,
    pub triangles: u32,
    pub texels: Vec<[f32; 4]>,
}

impl PixelTree {
    /// Entries (nodes and triangles).
    pub fn entries(&self) -> u32 {
        self.nodes + self.triangles
    }
}

impl Emitters {
    /// The tree over the emitters outside `groups`' polygon groups; `None` when there are
    /// none, or when one has an emission texture (their light stays with the frame's
    /// points).
    pub fn pixel_tree(&self, scene: &Scene, groups: &PolygonGroups) -> Option<PixelTree> {
        let slots = groups.rest()?;
        let textured = |s: &u32| {
            let t = self.triangles[*s as usize] as usize;
            scene.maps_of(t).emission.is_some()
        };
        if slots.iter().any(textured) || 3 * slots.len() > MAX_ENTRIES {
            return None;
        }
        let bounds: Vec<LightBounds> = slots
            .iter()
            .map(|&s| {
                let s = s as usize;
                let (corners, n) = self.corners[s];
                LightBounds::triangle(corners, n, self.weights[s], self.two_sided[s])
            })
            .collect();
        let bvh = LightBvh::build(&bounds)?;
        let flag = |b: bool| b as u32 as f32;
        let mut texels = Vec::with_capacity(4 * 3 * slots.len());
        let mut nodes = 0;
        for (b, leaf, index) in bvh.nodes() {
            texels.extend([
                b.lo.extend(b.phi).to_array(),
                b.hi.extend(b.cos_o).to_array(),
                b.axis.extend(b.cos_e).to_array(),
                [flag(leaf), flag(b.two_sided), index as f32, 0.0],
            ]);
            nodes += 1;
        }
        for &s in slots {
            let s = s as usize;
            let ([a, b, c], _) = self.corners[s];
            let area = self.areas[s];
            let radiance = scene.material_of(self.triangles[s] as usize).emission;
            texels.extend([
                a.extend(area / PI).to_array(),
                b.extend(flag(self.two_sided[s])).to_array(),
                c.extend(area).to_array(),
                radiance.extend(0.0).to_array(),
            ]);
        }
        Some(PixelTree {
            nodes,
            triangles: slots.len() as u32,
            texels,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// A quad panel (a group) and a 320-triangle sphere (not: one group at most; it would
    /// be a round group, `round::sphere`, with room for two): the tree holds the sphere's
    /// triangles alone, 2n − 1 nodes over them, every leaf naming one triangle once, every
    /// interior node's second child after its first; the triangles' radiance and area.
    #[test]
    fn tree_holds_the_emitters_outside_the_groups() {
        let json = r#"{"camera": {"position": [0, 1, 4], "look_at": [0, 1, 0]},
          "materials": {"panel": {"diffuse": [0, 0, 0], "emission": [8, 8, 8]},
                        "globe": {"diffuse": [0, 0, 0], "emission": [1, 2, 4]}},
          "objects": [
            {"shape": {"type": "quad", "size": [1, 1]}, "material": "panel",
             "transform": {"rotate": [180, 0, 0], "translate": [0, 2.5, 0]}},
            {"shape": {"type": "sphere", "radius": 0.2, "subdivisions": 2}, "material": "globe"}]}"#;
        let scene = Scene::from_json(json, "t", &HashMap::new()).unwrap();
        let e = Emitters::of(&scene);
        let groups = e.polygon_groups(&scene, (64, 1), 16);
        assert_eq!(groups.groups, 1);
        let tree = e.pixel_tree(&scene, &groups).expect("a tree");
        assert_eq!(tree.triangles, 320);
        assert_eq!(tree.nodes, 2 * 320 - 1);
        assert_eq!(tree.texels.len(), 4 * tree.entries() as usize);
        let mut seen = vec![false; 320];
        for k in 0..tree.nodes as usize {
            let t3 = tree.texels[4 * k + 3];
            let index = t3[2] as usize;
            if t3[0] > 0.5 {
                assert!(!seen[index], "triangle {index} in two leaves");
                seen[index] = true;
            } else {
                assert!(index > k + 1 && index < tree.nodes as usize, "node {k}");
            }
        }
        assert!(seen.iter().all(|&s| s));
        let mut area = 0.0;
        for k in 0..320 {
            let row = &tree.texels[4 * (tree.nodes as usize + k)..][..4];
            assert_eq!(row[3][..3], [1.0, 2.0, 4.0]);
            area += row[2][3];
        }
        // A geodesic sphere of radius 0.2 has a little less area than the sphere.
        let sphere = 4.0 * PI * 0.04;
        assert!(area < sphere && area > 0.95 * sphere, "{area}");
        // Both groups (the sphere round): no tree.
        let both = e.polygon_groups(&scene, (64, 8), 16);
        assert_eq!(both.groups, 2);
        assert!(e.pixel_tree(&scene, &both).is_none());
    }
}
