//! Other forms of a scene with instances, for tests and measurements: every object with its
//! own copy of its mesh ([`Scene::unshared`]) and every object baked into world-space
//! triangles ([`Scene::flattened`]).

use super::{Scene, TriMesh};
use glam::Mat4;
use std::sync::Arc;

impl Scene {
    /// The same scene with every object given its own copy of its mesh (nothing shared):
    /// what loading it without instancing gives.
    pub fn unshared(&self) -> Scene {
        let mut s = self.clone();
        s.meshes = s
            .objects
            .iter()
            .map(|o| Arc::new((*self.meshes[o.mesh as usize]).clone()))
            .collect();
        s.mesh_uvs = s
            .objects
            .iter()
            .map(|o| Arc::new((*self.mesh_uvs[o.mesh as usize]).clone()))
            .collect();
        s.mesh_tangents = s
            .objects
            .iter()
            .map(|o| self.mesh_tangents.get(o.mesh as usize).cloned().flatten())
            .collect();
        for (i, o) in s.objects.iter_mut().enumerate() {
            o.mesh = i as u32;
        }
        s.flat = Default::default();
        s
    }

    /// The same scene with every object's mesh replaced by its world-space triangles (the
    /// flat arrays) under the identity transform: the scene flattened into triangles. The
    /// flat arrays, and so everything drawn from them, are unchanged.
    pub fn flattened(&self) -> Scene {
        let mut s = self.clone();
        let flat = self.flat();
        s.meshes = s
            .objects
            .iter()
            .map(|o| {
                let v = o.vertices.start as usize..o.vertices.end as usize;
                let t = o.triangles.start as usize..o.triangles.end as usize;
                Arc::new(TriMesh {
                    positions: flat.positions[v.clone()].to_vec(),
                    normals: flat.normals[v].to_vec(),
                    indices: flat.triangles[t.clone()]
                        .iter()
                        .map(|c| c.map(|i| i - o.vertices.start))
                        .collect(),
                })
            })
            .collect();
        s.mesh_uvs = s
            .objects
            .iter()
            .map(|o| {
                Arc::new(flat.uvs[o.triangles.start as usize..o.triangles.end as usize].to_vec())
            })
            .collect();
        s.mesh_tangents = s.objects.iter().map(|o| self.placed_tangents(o)).collect();
        for (i, o) in s.objects.iter_mut().enumerate() {
            o.mesh = i as u32;
            o.set_transform(Mat4::IDENTITY);
            o.flipped = false;
            o.described = None;
        }
        s.flat = Default::default();
        s
    }
}

impl Scene {
    /// Object `o`'s mesh tangents placed in world space, in its flat corner order (what
    /// [`Scene::tangent_at`] interpolates), for the flattened scene.
    fn placed_tangents(&self, o: &super::SceneObject) -> Option<super::tangents::CornerTangents> {
        let corners = self.mesh_tangents.get(o.mesh as usize)?.as_ref()?;
        let linear = glam::Mat3::from_mat4(o.transform);
        let flip = if o.flipped { -1.0 } else { 1.0 };
        let place = |k: glam::Vec4| {
            (linear * k.truncate())
                .normalize_or_zero()
                .extend(k.w * flip)
        };
        Some(Arc::new(
            corners
                .iter()
                .map(|c| {
                    let c = if o.flipped { [c[0], c[2], c[1]] } else { *c };
                    c.map(place)
                })
                .collect(),
        ))
    }
}
