//! The scene's flat world-space view, derived from its meshes and objects on first use:
//! every object's copy of its mesh placed by its transform, for the consumers that still
//! read flat arrays (the GPU upload and passes). The CPU tracers read meshes and transforms
//! through the accessors here ([`Scene::corners`], [`Scene::triangle_material`],
//! [`Scene::corner_uvs`]), which give bitwise the values the flat view holds, and read them
//! from it where it is built (a GPU method built it, or the scene is small enough to be
//! traced baked, `trace::bvh::BAKE_TRIANGLES`).

use super::{Scene, SceneObject};
use glam::{Mat3, Vec2, Vec3};
use std::sync::Arc;

/// Every object's triangles in world space, in object order (object `o` owns
/// `o.vertices` and `o.triangles` of these arrays).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Flat {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Corners (indices into `positions`), with corners 1 and 2 swapped for mirrored objects
    /// so that the winding stays outward.
    pub triangles: Vec<[u32; 3]>,
    /// Material index per triangle.
    pub triangle_materials: Vec<u32>,
    /// Texture coordinates per triangle corner (same order as `triangles`).
    pub uvs: Vec<[Vec2; 3]>,
}

/// The matrix that places an object's normals (inverse transpose of its linear part).
fn normal_matrix(o: &SceneObject) -> Mat3 {
    o.normal_matrix
}

impl Scene {
    /// The flat view, built on first use (shared by clones made after that).
    pub fn flat(&self) -> &Flat {
        self.flat.get_or_init(|| Arc::new(self.build_flat()))
    }

    /// Whether the flat view has been built (for tests: the CPU tracers never build it).
    pub fn flat_is_built(&self) -> bool {
        self.flat.get().is_some()
    }

    fn build_flat(&self) -> Flat {
        let (v, t) = (self.vertex_count(), self.triangle_count());
        let mut f = Flat {
            positions: vec![Vec3::ZERO; v],
            normals: vec![Vec3::ZERO; v],
            triangles: vec![[0; 3]; t],
            triangle_materials: vec![0; t],
            uvs: vec![[Vec2::ZERO; 3]; t],
        };
        for o in 0..self.objects.len() {
            self.write_object(&mut f, o, true);
        }
        f
    }

    /// Writes object `o` into the flat view: its vertices, and with `triangles` its
    /// triangles, materials and texture coordinates.
    pub(crate) fn write_object(&self, f: &mut Flat, o: usize, triangles: bool) {
        let obj = &self.objects[o];
        let mesh = &self.meshes[obj.mesh as usize];
        obj.place(mesh, &mut f.positions, &mut f.normals);
        if !triangles {
            return;
        }
        let first = obj.triangles.start as usize;
        for local in 0..mesh.indices.len() {
            let t = first + local;
            let c = mesh.indices[local].map(|i| i + obj.vertices.start);
            f.triangles[t] = if obj.flipped { [c[0], c[2], c[1]] } else { c };
            f.triangle_materials[t] = self.triangle_material(t);
            f.uvs[t] = self.corner_uvs(t);
        }
    }

    /// Updates the flat view, if built, after object `o` moved (`flipped`: its winding
    /// changed too).
    pub(crate) fn moved_in_flat(&mut self, o: usize, flipped: bool) {
        let Some(mut flat) = self.flat.take() else {
            return;
        };
        self.write_object(Arc::make_mut(&mut flat), o, flipped);
        let _ = self.flat.set(flat);
    }

    /// Vertices of the flat view (every object's copy).
    pub fn vertex_count(&self) -> usize {
        self.objects.last().map_or(0, |o| o.vertices.end as usize)
    }

    /// Triangles of the flat view (every object's copy); flat triangle indices number them.
    pub fn triangle_count(&self) -> usize {
        self.objects.last().map_or(0, |o| o.triangles.end as usize)
    }

    /// The object that owns flat triangle `t`.
    #[inline(always)]
    pub fn object_of(&self, t: usize) -> &SceneObject {
        let i = self
            .objects
            .partition_point(|o| (o.triangles.end as usize) <= t);
        &self.objects[i]
    }

    /// The mesh corner indices of flat triangle `t` in its flat order, and its object.
    #[inline]
    fn mesh_corners(&self, t: usize) -> ([usize; 3], &SceneObject) {
        let o = self.object_of(t);
        let c = self.meshes[o.mesh as usize].indices[t - o.triangles.start as usize];
        let c = if o.flipped { [c[0], c[2], c[1]] } else { c };
        (c.map(|i| i as usize), o)
    }

    /// World-space corners and shading normals of flat triangle `t` (bitwise those of the
    /// flat view).
    #[inline(always)]
    pub fn corners(&self, t: usize) -> ([Vec3; 3], [Vec3; 3]) {
        if let Some(f) = self.flat.get() {
            let c = f.triangles[t].map(|i| i as usize);
            return (c.map(|i| f.positions[i]), c.map(|i| f.normals[i]));
        }
        let (c, o) = self.mesh_corners(t);
        let mesh = &self.meshes[o.mesh as usize];
        let nx = normal_matrix(o);
        (
            c.map(|i| o.transform.transform_point3(mesh.positions[i])),
            c.map(|i| (nx * mesh.normals[i]).normalize_or_zero()),
        )
    }

    /// The material index of flat triangle `t`.
    #[inline(always)]
    pub fn triangle_material(&self, t: usize) -> u32 {
        if let Some(f) = self.flat.get() {
            return f.triangle_materials[t];
        }
        let o = self.object_of(t);
        match &o.face_materials {
            Some(f) => o.material + f[t - o.triangles.start as usize],
            None => o.material,
        }
    }

    /// Texture coordinates of flat triangle `t`'s corners (in its flat order).
    #[inline(always)]
    pub fn corner_uvs(&self, t: usize) -> [Vec2; 3] {
        if let Some(f) = self.flat.get() {
            return f.uvs[t];
        }
        let o = self.object_of(t);
        let c = self.mesh_uvs[o.mesh as usize][t - o.triangles.start as usize];
        if o.flipped {
            [c[0], c[2], c[1]]
        } else {
            c
        }
    }

    /// Object `o`'s placed vertices (bitwise those of the flat view), without building it.
    pub fn object_vertices(&self, o: &SceneObject) -> impl Iterator<Item = Vec3> + '_ {
        let xf = o.transform;
        self.meshes[o.mesh as usize]
            .positions
            .iter()
            .map(move |p| xf.transform_point3(*p))
    }

    /// Every flat triangle's index and world-space corners, object by object (no lookup per
    /// triangle), skipping the objects `skip` rejects; without building the flat view.
    pub fn for_each_triangle(
        &self,
        skip: impl Fn(&SceneObject) -> bool,
        mut f: impl FnMut(usize, [Vec3; 3]),
    ) {
        let mut placed = Vec::new();
        for o in &self.objects {
            if skip(o) {
                continue;
            }
            placed.clear();
            placed.extend(self.object_vertices(o));
            let mesh = &self.meshes[o.mesh as usize];
            for (local, c) in mesh.indices.iter().enumerate() {
                let c = if o.flipped { [c[0], c[2], c[1]] } else { *c };
                f(
                    o.triangles.start as usize + local,
                    c.map(|i| placed[i as usize]),
                );
            }
        }
    }

    /// Total area (m²) of every placed triangle, without the flat view, in O(unique
    /// triangles + objects) where the objects' transforms are similarities (rotation,
    /// translation, mirror, uniform scale `s`: the object's area is `s²` times its mesh's);
    /// objects with other transforms are summed triangle by triangle.
    pub fn surface_area(&self) -> f64 {
        let mut mesh_areas: Vec<Option<f64>> = vec![None; self.meshes.len()];
        let mut area = 0.0f64;
        for o in &self.objects {
            if let Some(s2) = similarity_scale2(Mat3::from_mat4(o.transform)) {
                let mesh = &self.meshes[o.mesh as usize];
                let a = *mesh_areas[o.mesh as usize].get_or_insert_with(|| {
                    let p = &mesh.positions;
                    mesh.indices
                        .iter()
                        .map(|&[a, b, c]| {
                            triangle_area(p[a as usize], p[b as usize], p[c as usize])
                        })
                        .sum()
                });
                area += s2 * a;
            }
        }
        self.for_each_triangle(
            |o| similarity_scale2(Mat3::from_mat4(o.transform)).is_some(),
            |_, [a, b, c]| area += triangle_area(a, b, c),
        );
        area
    }

    /// Every placed vertex of every object, in flat order, without building the flat view.
    pub fn for_each_vertex(&self, mut f: impl FnMut(Vec3)) {
        for o in &self.objects {
            for p in &self.meshes[o.mesh as usize].positions {
                f(o.transform.transform_point3(*p));
            }
        }
    }
}

/// Area of the triangle `a b c` (m²).
fn triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    0.5 * (b - a).cross(c - a).length() as f64
}

/// `s²` where the linear map `m` is a similarity of scale `s` (orthogonal columns of equal
/// length, to 1e-6 relative: areas within about that of the exact placed sum), else `None`.
fn similarity_scale2(m: Mat3) -> Option<f64> {
    let c = [m.x_axis, m.y_axis, m.z_axis].map(|v| v.as_dvec3());
    let l = c.map(|v| v.length_squared());
    let s2 = (l[0] + l[1] + l[2]) / 3.0;
    let tol = 1e-6 * s2;
    let similar = s2.is_finite()
        && s2 > 0.0
        && l.iter().all(|&x| (x - s2).abs() <= tol)
        && [(0, 1), (0, 2), (1, 2)]
            .iter()
            .all(|&(i, j)| c[i].dot(c[j]).abs() <= tol);
    similar.then_some(s2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Quat};

    /// The sum over every placed triangle, the definition `surface_area` shortcuts.
    fn placed_area(scene: &Scene) -> f64 {
        let mut area = 0.0;
        scene.for_each_triangle(|_| false, |_, [a, b, c]| area += triangle_area(a, b, c));
        area
    }

    #[test]
    fn surface_area_is_the_sum_over_the_placed_triangles() {
        let rotation = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 0.7);
        let transforms = [
            // Similarities: the mesh's area times s².
            Mat4::from_scale_rotation_translation(Vec3::splat(2.5), rotation, Vec3::X),
            Mat4::from_scale(Vec3::new(-0.5, 0.5, 0.5)),
            // Not similarities: triangle by triangle.
            Mat4::from_scale(Vec3::new(1.0, 3.0, 0.25)),
            Mat4::from_cols_array(&[
                1.0, 0.4, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.2, 0.0, 1.5, 0.0, 0.0, 0.0, 0.0, 1.0,
            ]),
        ];
        let kinds = transforms.map(|m| similarity_scale2(Mat3::from_mat4(m)).is_some());
        assert_eq!(kinds, [true, true, false, false]);
        for name in ["cornell", "cornell-glass", "ring-room"] {
            let mut scene = crate::scene::builtin::load(name).unwrap();
            let before = placed_area(&scene);
            assert!((scene.surface_area() / before - 1.0).abs() < 1e-6, "{name}");
            // Objects sharing a mesh get different transforms (the mesh's area is reused).
            for (o, m) in scene.objects.iter_mut().zip(transforms.iter().cycle()) {
                o.set_transform(*m * o.transform);
            }
            let (fast, exact) = (scene.surface_area(), placed_area(&scene));
            // f32 placement against f64 products of the local areas: ~1e-7 relative.
            assert!(
                (fast / exact - 1.0).abs() < 1e-5,
                "{name}: {fast} against {exact}"
            );
            assert!(
                (exact / before - 1.0).abs() > 0.1,
                "{name}: the transforms change it"
            );
        }
    }
}
