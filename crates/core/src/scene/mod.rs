//! The scene: camera, lights, materials and one flat triangle soup in world space.

pub mod animation;
pub mod bench;
mod build;
pub mod builtin;
pub mod camera;
mod convert;
pub mod desc;
pub mod emitters;
pub mod environment;
pub mod flat;
pub mod instances;
pub mod light;
pub mod light_bvh;
pub mod light_views;
pub mod lighting;
pub mod primitives;
pub mod shading;
pub mod sources;
pub mod surface;
pub mod tangents;
pub mod update;

pub use animation::Animation;
pub use camera::Camera;
pub use desc::SceneDesc;
pub use emitters::{EmitterSampler, Emitters};
pub use environment::{EnvImage, Environment};
pub use flat::Flat;
pub use light::{Bounds, Light};
pub use lighting::Lighting;
pub use primitives::TriMesh;
pub use shading::Smoothing;
pub use sources::{Source, Sources};
pub use surface::{MaterialMaps, TextureMap};
pub use update::{Changes, SceneObject, SceneUpdate};

use convert::mesh_bounds;
pub(crate) use convert::{
    camera_from_desc, light_from_desc, material_from_desc, matrix_from_rows, transform_matrix,
};
pub use convert::{parse_material_textures, parse_materials};

use crate::bsdf::Material;
use crate::texture::Texture;
use glam::{Vec2, Vec3};
use std::sync::Arc;

/// Triangle mesh data supplied by the caller for `mesh` objects (loaded from files by the
/// Python layer), keyed by the `file` string of the scene description.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Normals may be empty (the file has none) or zero on some vertices (parts of the file
    /// have none): those triangles are shaded flat unless the object asks otherwise.
    pub mesh: TriMesh,
    /// Optional per-triangle material from the file (e.g. OBJ + MTL): names and materials,
    /// and an index into them per triangle. Used when the object names no material.
    pub materials: Vec<(String, Material)>,
    pub face_materials: Vec<u32>,
    /// The texture fields of `materials` (same order; empty: none), names of the textures
    /// passed with the description.
    pub material_textures: Vec<desc::TextureRefs>,
    /// Texture coordinates per triangle corner (empty: none, all zero).
    pub uvs: Vec<[Vec2; 3]>,
    /// Tangent frames per triangle corner in gi's convention ([`tangents`]; glTF's
    /// `TANGENT` with `w` negated); empty: none (MikkTSpace's where a normal map needs them).
    pub tangents: Vec<[glam::Vec4; 3]>,
}

/// A renderable scene: unique meshes in their local frames ([`Scene::meshes`]), objects that
/// place them (instances: mesh, transform, material; [`Scene::objects`]), and the derived
/// world-space flat view ([`Scene::flat`]), built on first use for the consumers that still
/// read flat arrays (the GPU passes). The CPU tracers read meshes and transforms.
#[derive(Clone, Debug)]
pub struct Scene {
    pub camera: Camera,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub material_names: Vec<String>,
    /// The textures each material reads (same order as `materials`).
    pub material_maps: Vec<MaterialMaps>,
    /// Textures, referenced by index from `material_maps`, and their names.
    pub textures: Vec<Arc<Texture>>,
    pub texture_names: Vec<String>,
    /// The objects of the description, in order: their mesh, transform, and vertex and
    /// triangle ranges of the flat arrays.
    pub objects: Vec<SceneObject>,
    /// The unique meshes (shaded, in their local frames), each stored once however many
    /// objects place it.
    pub meshes: Vec<Arc<TriMesh>>,
    /// Texture coordinates per triangle corner of each unique mesh (same order as `meshes`).
    pub mesh_uvs: Vec<Arc<Vec<[Vec2; 3]>>>,
    /// Tangent frames per triangle corner of each unique mesh (same order as `meshes`),
    /// stored or MikkTSpace's; `None`: each triangle's own frame ([`tangents`]).
    pub mesh_tangents: Vec<Option<tangents::CornerTangents>>,
    /// The flat world-space view, built on first use ([`Scene::flat`]).
    pub(crate) flat: std::sync::OnceLock<Arc<Flat>>,
    /// The description's keyframed tracks, if any (see [`animation`]).
    pub animation: Option<Animation>,
    /// Light from infinitely far away (see [`environment`]); shared, as images are large.
    pub environment: Option<std::sync::Arc<Environment>>,
    /// The camera as described (position, look-at point, up, fov), so that updates of some
    /// of its fields keep the others exactly (`Scene::camera_desc`).
    pub(crate) camera_source: desc::CameraDesc,
}

/// Largest coordinate (m, absolute value per axis) of any point of a scene after its
/// transform: f32 keeps steps of at most 8 mm there (2⁻⁷ m at 10⁵), and the BVH builders
/// see bounded boxes whose sizes neither overflow nor lose all resolution.
pub const MAX_EXTENT: f32 = 1.0e5;
/// Largest scale factor (absolute value, per axis) of an object transform, and the inverse
/// of the smallest: transforms stay invertible with well-conditioned normals.
pub const MAX_SCALE: f32 = 1.0e6;
/// Largest light intensity per channel (W/sr): emitted powers, photon powers and radiance
/// estimates stay far from f32 overflow (3.4·10³⁸) even at millimetre distances.
pub const MAX_INTENSITY: f32 = 1.0e10;
/// Largest emitted radiance of a surface (W·sr⁻¹·m⁻² per channel) and irradiance of a
/// directional light (W·m⁻² per channel).
pub const MAX_RADIANCE: f32 = 1.0e10;
/// Widest directional light (degrees of angular diameter).
pub const MAX_ANGULAR_DIAMETER: f32 = 90.0;
/// Most vertices (and triangles) a scene may hold: indices are 32-bit.
pub const MAX_VERTICES: usize = u32::MAX as usize;

impl Scene {
    /// The box of every placed vertex (empty: lo > hi), without the flat view.
    ///
    /// An object whose transform only scales and translates (no rotation) contributes its
    /// mesh's box placed by two corners: each placed coordinate is then a monotone function
    /// of one local coordinate (`s·x + 0·y + 0·z + t`, rounded), so the result is the
    /// per-vertex box exactly, in O(unique vertices + objects).
    pub fn vertex_box(&self) -> (Vec3, Vec3) {
        let mut boxes: Vec<Option<(Vec3, Vec3)>> = vec![None; self.meshes.len()];
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for o in &self.objects {
            let m = o.transform;
            let diagonal = [
                m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.z, m.z_axis.x, m.z_axis.y,
            ]
            .iter()
            .all(|&v| v == 0.0)
                && m.x_axis.w == 0.0
                && m.y_axis.w == 0.0
                && m.z_axis.w == 0.0
                && m.w_axis.w == 1.0;
            let mesh = &self.meshes[o.mesh as usize];
            let (mlo, mhi) = *boxes[o.mesh as usize].get_or_insert_with(|| mesh_bounds(mesh));
            if diagonal && mlo.is_finite() && mhi.is_finite() {
                let (a, b) = (m.transform_point3(mlo), m.transform_point3(mhi));
                lo = lo.min(a.min(b));
                hi = hi.max(a.max(b));
            } else {
                for p in self.object_vertices(o) {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        }
        (lo, hi)
    }

    /// Triangles of the unique meshes (each counted once however many objects place it).
    pub fn unique_triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.indices.len()).sum()
    }

    /// The three corners of triangle `t`.
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        self.corners(t).0
    }

    pub fn material_of(&self, t: usize) -> &Material {
        &self.materials[self.triangle_material(t) as usize]
    }

    /// Total power of all light sources (W per channel): lights, emitting surfaces and the
    /// environment (distant lights and the environment through the bounding sphere).
    pub fn total_power(&self) -> Vec3 {
        Sources::of(self).power()
    }

    /// The bounding sphere of the scene's vertices (a unit sphere at the origin without
    /// any).
    pub fn bounds(&self) -> Bounds {
        let (lo, hi) = self.vertex_box();
        if lo.x > hi.x {
            return Bounds {
                centre: Vec3::ZERO,
                radius: 1.0,
            };
        }
        Bounds {
            centre: 0.5 * (lo + hi),
            radius: (0.5 * (hi - lo).length()).max(1e-6),
        }
    }
}
