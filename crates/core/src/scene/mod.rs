//! The scene: camera, lights, materials and one flat triangle soup in world space.

pub mod animation;
pub mod bench;
pub mod builtin;
pub mod camera;
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

use crate::bsdf::{Coating, Conductor, Material};
use crate::error::{Error, Result};
use crate::memory;
use crate::texture::Texture;
use desc::{LightDesc, MaterialDesc, Scale, ShapeDesc, SmoothDesc, V3};
use glam::{EulerRot, Mat3, Mat4, Quat, Vec2, Vec3};
use std::collections::HashMap;
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

fn finite3(v: V3) -> bool {
    v.iter().all(|x| x.is_finite())
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

fn within_extent(v: V3) -> bool {
    v.iter().all(|x| x.is_finite() && x.abs() <= MAX_EXTENT)
}

/// An object resolved to its unique mesh: transform, mesh index, texture coordinates per
/// triangle corner, the mesh file's data, and the material it names.
type Resolved<'a> = (
    Mat4,
    u32,
    Arc<Vec<[Vec2; 3]>>,
    Option<&'a MeshData>,
    Option<&'a String>,
);

/// Every object of `desc` resolved to a unique mesh (pushed to `unique_meshes` the first
/// time its key, the resolved shape and smoothing, is seen), with its transform checked and
/// its vertices placed within [`MAX_EXTENT`]; and the objects' names.
fn resolve_objects<'a>(
    desc: &'a SceneDesc,
    meshes: &'a HashMap<String, MeshData>,
    unique_meshes: &mut Vec<Arc<TriMesh>>,
    unique_uvs: &mut Vec<Arc<Vec<[Vec2; 3]>>>,
    source_name: &str,
) -> Result<(Vec<Resolved<'a>>, HashMap<&'a str, usize>)> {
    let err = |field: String, msg: &str| Error::scene(source_name, field, msg);
    // Unique meshes by (resolved shape, smoothing): objects with equal keys share one.
    type Found<'a> = (u32, Arc<Vec<[Vec2; 3]>>, Option<&'a MeshData>);
    let mut unique: HashMap<String, Found> = HashMap::new();
    // Object names (the first of equal ones: a repeated name is an error later).
    let mut names: HashMap<&str, usize> = HashMap::new();
    for (i, o) in desc.objects.iter().enumerate() {
        if let Some(n) = &o.name {
            names.entry(n.as_str()).or_insert(i);
        }
    }
    let mut out = Vec::with_capacity(desc.objects.len());
    let mut bounds: HashMap<u32, (Vec3, Vec3)> = HashMap::new();
    for (i, obj) in desc.objects.iter().enumerate() {
        let at = |f: &str| format!("objects[{i}].{f}");
        let xf = transform_matrix(&obj.transform)
            .map_err(|(f, m)| err(at(&format!("transform.{f}")), m))?;
        let (shape, smooth, material) =
            resolve_instance(&desc.objects, &names, i).map_err(|(f, m)| err(at(&f), &m))?;
        let key = serde_json::to_string(&(shape, smooth)).unwrap_or_default();
        let (mesh_index, uvs, file_materials) = match unique.get(&key) {
            Some(found) => found.clone(),
            None => {
                let (mesh, file_materials, uvs) =
                    object_mesh(shape, meshes).map_err(|(f, m)| err(at(&f), &m))?;
                validate_mesh(&mesh).map_err(|m| err(at("shape"), &m))?;
                let smoothing = smoothing(smooth).map_err(|m| err(at("smooth"), m))?;
                unique_meshes.push(Arc::new(shading::shade(&mesh, smoothing)));
                let uvs = Arc::new(uvs);
                unique_uvs.push(uvs.clone());
                let found = (unique_meshes.len() as u32 - 1, uvs, file_materials);
                unique.insert(key, found.clone());
                found
            }
        };
        let mesh = &unique_meshes[mesh_index as usize];
        // O(1) per instance when its mesh's box lands within range (the usual case).
        let (lo, hi) = *bounds
            .entry(mesh_index)
            .or_insert_with(|| mesh_bounds(mesh));
        if !box_within_extent(lo, hi, xf) {
            validate_placed(mesh, xf).map_err(|(f, m)| err(at(&f), &m))?;
        }
        out.push((xf, mesh_index, uvs, file_materials, material));
    }
    Ok((out, names))
}

/// The tangents each unique mesh's file stores (index: mesh), checked against its
/// triangles; an error names the first object that places a mesh with invalid ones.
fn stored_tangents(
    resolved: &[Resolved],
    meshes: usize,
) -> std::result::Result<Vec<Option<tangents::CornerTangents>>, (usize, String)> {
    let mut out: Vec<Option<tangents::CornerTangents>> = vec![None; meshes];
    for (i, (_, m, uvs, data, _)) in resolved.iter().enumerate() {
        let Some(data) = data.filter(|d| !d.tangents.is_empty()) else {
            continue;
        };
        if out[*m as usize].is_some() {
            continue;
        }
        if !tangents::valid(&data.tangents, uvs.len().max(data.mesh.indices.len())) {
            return Err((
                i,
                "tangents must be finite, one per triangle corner".to_string(),
            ));
        }
        out[*m as usize] = Some(Arc::new(data.tangents.clone()));
    }
    Ok(out)
}

/// Bytes of the flat view per vertex (position, normal) and per triangle (corners, texture
/// coordinates, material).
const FLAT_BYTES_PER_VERTEX: u64 = 24;
const FLAT_BYTES_PER_TRIANGLE: u64 = 12 + 24 + 4;
/// Bytes per object (its record and the description's).
const BYTES_PER_OBJECT: u64 = 256;

impl Scene {
    /// Checks that `resolved` objects fit: at most 2^32 - 1 placed vertices and triangles
    /// (the flat numbering is 32-bit), and memory for the object records; before any
    /// object is pushed. (The flat view's memory is checked where it is built.)
    fn check_flat(&self, resolved: &[Resolved]) -> Result<()> {
        let (mut vertices, mut triangles) = (0u64, 0u64);
        for r in resolved {
            let m = &self.meshes[r.1 as usize];
            vertices += m.positions.len() as u64;
            triangles += m.indices.len() as u64;
        }
        if vertices > MAX_VERTICES as u64 || triangles > MAX_VERTICES as u64 {
            return Err(Error::scene(
                "scene",
                "objects",
                format!(
                    "the scene would hold {vertices} vertices and {triangles} triangles \
                     (at most 2^32 - 1 each)"
                ),
            ));
        }
        let n = resolved.len() as u64;
        memory::check(
            || format!("the scene's {n} objects"),
            n.saturating_mul(BYTES_PER_OBJECT),
        )
    }

    /// Estimated bytes of the flat view (built for the GPU passes on their first frame,
    /// checked there before it is built: [`Scene::flat`]).
    pub fn flat_estimate(&self) -> u64 {
        (self.vertex_count() as u64)
            .saturating_mul(FLAT_BYTES_PER_VERTEX)
            .saturating_add((self.triangle_count() as u64).saturating_mul(FLAT_BYTES_PER_TRIANGLE))
    }
}

/// The shape, smoothing and material of object `i`, following `instance` shapes to the
/// object they name (the instance's own `smooth` and `material` win where given); errors as
/// (field, message) for a missing or self-referencing object and for a cycle of instances.
type InstanceOf<'a> = (&'a ShapeDesc, Option<SmoothDesc>, Option<&'a String>);
fn resolve_instance<'a>(
    objects: &'a [desc::ObjectDesc],
    names: &HashMap<&str, usize>,
    i: usize,
) -> std::result::Result<InstanceOf<'a>, (String, String)> {
    let (mut at, mut smooth, mut material) = (i, objects[i].smooth, objects[i].material.as_ref());
    for step in 0..=objects.len() {
        let ShapeDesc::Instance { object } = &objects[at].shape else {
            return Ok((&objects[at].shape, smooth, material));
        };
        let field = "shape.object".to_string();
        let Some(&j) = names.get(object.as_str()) else {
            return Err((field, format!("no object named `{object}`")));
        };
        if j == i && step == 0 {
            return Err((
                field,
                format!("`{object}` is this object (an instance of itself)"),
            ));
        }
        if j == i {
            return Err((field, "instances refer to each other in a cycle".into()));
        }
        at = j;
        smooth = smooth.or(objects[j].smooth);
        material = material.or(objects[j].material.as_ref());
    }
    Err((
        "shape.object".into(),
        "instances refer to each other in a cycle".into(),
    ))
}

/// An object's mesh before placement, the mesh file's data when it is one, and its texture
/// coordinates per triangle corner; errors as (field, message).
type ObjectMesh<'a> = (TriMesh, Option<&'a MeshData>, Vec<[Vec2; 3]>);
fn object_mesh<'a>(
    shape: &ShapeDesc,
    meshes: &'a HashMap<String, MeshData>,
) -> std::result::Result<ObjectMesh<'a>, (String, String)> {
    match shape {
        ShapeDesc::Mesh { file } => {
            let data = meshes.get(file).ok_or_else(|| {
                (
                    "shape.file".to_string(),
                    format!("mesh `{file}` was not loaded"),
                )
            })?;
            let uvs = if data.uvs.is_empty() {
                vec![[Vec2::ZERO; 3]; data.mesh.indices.len()]
            } else if data.uvs.len() == data.mesh.indices.len()
                && data.uvs.iter().flatten().all(|u| u.is_finite())
            {
                data.uvs.clone()
            } else {
                return Err((
                    "shape.file".into(),
                    "texture coordinates must be finite, one per vertex".into(),
                ));
            };
            Ok((data.mesh.clone(), Some(data), uvs))
        }
        shape => {
            let mesh = primitive(shape).map_err(|(f, m)| (format!("shape.{f}"), m.to_string()))?;
            let uvs = primitives::uvs(shape, &mesh);
            Ok((mesh, None, uvs))
        }
    }
}

impl Scene {
    /// Parses and validates a JSON scene description. `source_name` names the file (or
    /// built-in) in error messages.
    pub fn from_json(
        text: &str,
        source_name: &str,
        meshes: &HashMap<String, MeshData>,
    ) -> Result<Scene> {
        Scene::from_json_with(
            text,
            source_name,
            meshes,
            &HashMap::new(),
            &TextureMap::new(),
        )
    }

    /// [`Scene::from_json`] with the environment images the description names (`file` of
    /// its `environment` section), loaded by the caller.
    pub fn from_json_with_images(
        text: &str,
        source_name: &str,
        meshes: &HashMap<String, MeshData>,
        images: &HashMap<String, EnvImage>,
    ) -> Result<Scene> {
        Scene::from_json_with(text, source_name, meshes, images, &TextureMap::new())
    }

    /// [`Scene::from_json`] with the textures that materials name.
    pub fn from_json_textured(
        text: &str,
        source_name: &str,
        meshes: &HashMap<String, MeshData>,
        textures: &TextureMap,
    ) -> Result<Scene> {
        Scene::from_json_with(text, source_name, meshes, &HashMap::new(), textures)
    }

    /// [`Scene::from_json`] with environment images and material textures.
    pub fn from_json_with(
        text: &str,
        source_name: &str,
        meshes: &HashMap<String, MeshData>,
        images: &HashMap<String, EnvImage>,
        textures: &TextureMap,
    ) -> Result<Scene> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let desc: SceneDesc = serde_path_to_error::deserialize(de).map_err(|e| {
            let field = e.path().to_string();
            Error::scene(
                source_name,
                if field == "." { "(root)".into() } else { field },
                e.inner().to_string(),
            )
        })?;
        let mut scene = Scene::from_desc_textured(&desc, source_name, meshes, textures)?;
        if let Some(env) = &desc.environment {
            let e = Environment::from_desc(env, images).map_err(|(f, m)| {
                let field = if f == "(section)" {
                    "environment".into()
                } else {
                    format!("environment.{f}")
                };
                Error::scene(source_name, field, m)
            })?;
            scene.environment = Some(std::sync::Arc::new(e));
        }
        Ok(scene)
    }

    /// Builds a scene from a parsed description, validating every field.
    pub fn from_desc(
        desc: &SceneDesc,
        source_name: &str,
        meshes: &HashMap<String, MeshData>,
    ) -> Result<Scene> {
        Scene::from_desc_textured(desc, source_name, meshes, &TextureMap::new())
    }

    /// [`Scene::from_desc`] with the textures that materials name.
    pub fn from_desc_textured(
        desc: &SceneDesc,
        source_name: &str,
        meshes: &HashMap<String, MeshData>,
        textures: &TextureMap,
    ) -> Result<Scene> {
        let err = |field: String, msg: &str| Error::scene(source_name, field, msg);
        let camera =
            camera_from_desc(&desc.camera).map_err(|(f, m)| err(format!("camera.{f}"), m))?;

        let mut lights = Vec::new();
        for (i, l) in desc.lights.iter().enumerate() {
            lights.push(light_from_desc(l).map_err(|(f, m)| err(format!("lights[{i}].{f}"), m))?);
        }

        let mut texture_names: Vec<String> = textures.keys().cloned().collect();
        texture_names.sort();
        let texture_index: HashMap<String, u32> = texture_names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i as u32))
            .collect();
        let mut materials = Vec::new();
        let mut material_names = Vec::new();
        let mut material_maps = Vec::new();
        let mut index_of: HashMap<String, u32> = HashMap::new();
        for (name, m) in &desc.materials {
            let mat = material_from_desc(m)
                .map_err(|(f, msg)| err(format!("materials.{name}.{f}"), msg))?;
            let maps = MaterialMaps::resolve(&m.texture_refs(), &texture_index)
                .map_err(|(f, msg)| err(format!("materials.{name}.{f}"), &msg))?;
            index_of.insert(name.clone(), materials.len() as u32);
            materials.push(mat);
            material_names.push(name.clone());
            material_maps.push(maps);
        }

        let mut scene = Scene {
            camera,
            lights,
            materials,
            material_names,
            material_maps,
            textures: texture_names.iter().map(|n| textures[n].clone()).collect(),
            texture_names,
            objects: Vec::new(),
            meshes: Vec::new(),
            mesh_uvs: Vec::new(),
            mesh_tangents: Vec::new(),
            flat: Default::default(),
            animation: None,
            environment: None,
            camera_source: desc.camera.clone(),
        };
        // Unique meshes by (resolved shape, smoothing): objects with equal keys share one.
        let (resolved, names) = resolve_objects(
            desc,
            meshes,
            &mut scene.meshes,
            &mut scene.mesh_uvs,
            source_name,
        )?;
        scene.check_flat(&resolved)?;
        let stored = stored_tangents(&resolved, scene.meshes.len())
            .map_err(|(i, m)| err(format!("objects[{i}].shape.file"), &m))?;
        scene.objects.reserve_exact(resolved.len());
        // The file's per-face materials, shared by the objects that place one mesh.
        let mut face_of: HashMap<u32, Arc<Vec<u32>>> = HashMap::new();
        // Where each mesh file's materials start (pushed once, shared by its objects).
        let mut file_bases: HashMap<*const MeshData, u32> = HashMap::new();
        for (i, (obj, (xf, mesh_index, _uvs, file_materials, material))) in
            desc.objects.iter().zip(resolved).enumerate()
        {
            let at = |f: &str| format!("objects[{i}].{f}");
            let mesh = scene.meshes[mesh_index as usize].clone();
            // Per-triangle materials: the object's own, else those of the file.
            let (base, faces) = match (material, file_materials) {
                (Some(name), _) => {
                    let id = *index_of.get(name).ok_or_else(|| {
                        err(at("material"), &format!("no material named `{name}`"))
                    })?;
                    (id, None)
                }
                (None, Some(data)) if !data.materials.is_empty() => {
                    let base = scene
                        .file_materials(data, &mut file_bases, &texture_index)
                        .map_err(|(f, msg)| err(at(&f), &msg))?;
                    if data.face_materials.len() != mesh.indices.len()
                        || data
                            .face_materials
                            .iter()
                            .any(|&f| f as usize >= data.materials.len())
                    {
                        return Err(err(
                            at("shape.file"),
                            "per-face materials do not match the mesh",
                        ));
                    }
                    let faces = face_of
                        .entry(mesh_index)
                        .or_insert_with(|| Arc::new(data.face_materials.clone()));
                    (base, Some(faces.clone()))
                }
                (None, _) => {
                    return Err(err(
                        at("material"),
                        "required (the shape carries no materials)",
                    ))
                }
            };
            if let Some(name) = &obj.name {
                if names.get(name.as_str()) != Some(&i) {
                    return Err(err(at("name"), "another object has this name"));
                }
            }
            scene.push_object(obj.name.clone(), mesh_index, xf, base, faces);
            if let Some(o) = scene.objects.last_mut() {
                o.described = Some(obj.transform.clone());
            }
        }
        scene.build_tangents(&stored);
        if let Some(anim) = &desc.animation {
            scene.animation = Some(Animation::from_desc(anim, desc, &scene, source_name)?);
        }
        Ok(scene)
    }

    /// The index in `materials` of a mesh file's first material, its materials pushed the
    /// first time an object takes them (`bases`, by the file's data): the objects that place
    /// one file share its materials (one `FILE:NAME` entry each, whatever the number of
    /// objects). Errors name the field under the object.
    fn file_materials(
        &mut self,
        data: &MeshData,
        bases: &mut HashMap<*const MeshData, u32>,
        texture_index: &HashMap<String, u32>,
    ) -> std::result::Result<u32, (String, String)> {
        let key: *const MeshData = data;
        if let Some(&base) = bases.get(&key) {
            return Ok(base);
        }
        let base = self.materials.len() as u32;
        for (i, (name, m)) in data.materials.iter().enumerate() {
            let refs = data.material_textures.get(i).cloned().unwrap_or_default();
            let maps = MaterialMaps::resolve(&refs, texture_index)
                .map_err(|(f, msg)| (format!("shape.file: materials.{name}.{f}"), msg))?;
            self.materials.push(*m);
            self.material_names.push(name.clone());
            self.material_maps.push(maps);
        }
        bases.insert(key, base);
        Ok(base)
    }

    /// Appends an object placing mesh `mesh_index` by `xf`, with material `material` (plus
    /// the file's per-face indices when given).
    fn push_object(
        &mut self,
        name: Option<String>,
        mesh_index: u32,
        xf: Mat4,
        material: u32,
        face_materials: Option<Arc<Vec<u32>>>,
    ) {
        let mesh = &self.meshes[mesh_index as usize];
        let (v, t) = (self.vertex_count() as u32, self.triangle_count() as u32);
        self.objects.push(SceneObject {
            name,
            vertices: v..v + mesh.positions.len() as u32,
            triangles: t..t + mesh.indices.len() as u32,
            transform: xf,
            normal_matrix: update::normal_matrix_of(xf),
            flipped: Mat3::from_mat4(xf).determinant() < 0.0,
            mesh: mesh_index,
            material,
            face_materials,
            described: None,
        });
    }

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

pub(crate) type FieldError = (String, &'static str);

/// The texture fields of the materials in [`parse_materials`]'s format, in order.
pub fn parse_material_textures(json: &str, source_name: &str) -> Result<Vec<desc::TextureRefs>> {
    let de = &mut serde_json::Deserializer::from_str(json);
    let descs: Vec<(String, MaterialDesc)> = serde_path_to_error::deserialize(de).map_err(|e| {
        Error::scene(
            source_name,
            format!("materials{}", e.path()),
            e.inner().to_string(),
        )
    })?;
    Ok(descs.iter().map(|(_, d)| d.texture_refs()).collect())
}

/// Parses the materials carried by a mesh file (e.g. OBJ + MTL), as turned into descriptions
/// by its loader: a JSON array of `[name, material]` pairs in the `materials` section's
/// format. The order is kept: per-face material indices refer to it.
pub fn parse_materials(json: &str, source_name: &str) -> Result<Vec<(String, Material)>> {
    let de = &mut serde_json::Deserializer::from_str(json);
    let descs: Vec<(String, MaterialDesc)> = serde_path_to_error::deserialize(de).map_err(|e| {
        Error::scene(
            source_name,
            format!("materials{}", e.path()),
            e.inner().to_string(),
        )
    })?;
    descs
        .iter()
        .map(|(name, d)| {
            material_from_desc(d)
                .map(|m| (name.clone(), m))
                .map_err(|(f, msg)| Error::scene(source_name, format!("materials.{name}.{f}"), msg))
        })
        .collect()
}

pub(crate) fn camera_from_desc(
    c: &desc::CameraDesc,
) -> std::result::Result<Camera, (String, &'static str)> {
    for (name, v) in [
        ("position", c.position),
        ("look_at", c.look_at),
        ("up", c.up),
    ] {
        if !finite3(v) {
            return Err((name.into(), "must be finite"));
        }
    }
    for (name, v) in [("position", c.position), ("look_at", c.look_at)] {
        if !within_extent(v) {
            return Err((name.into(), "must lie within ±100000 m"));
        }
    }
    let (pos, at, up) = (
        Vec3::from(c.position),
        Vec3::from(c.look_at),
        Vec3::from(c.up),
    );
    if (at - pos).length() < 1e-6 {
        return Err(("look_at".into(), "must differ from position"));
    }
    if up.length() < 1e-6 || (at - pos).normalize().cross(up.normalize()).length() < 1e-4 {
        return Err((
            "up".into(),
            "must be non-zero and not parallel to the viewing direction",
        ));
    }
    if !(c.fov > 0.0 && c.fov < 179.0) {
        return Err(("fov".into(), "must be in (0, 179) degrees"));
    }
    for (name, v) in [("width", c.width), ("height", c.height)] {
        if v == 0 || v > 16384 {
            return Err((name.into(), "must be in 1..=16384 pixels"));
        }
    }
    Ok(Camera::new(pos, at, up, c.fov, c.width, c.height))
}

fn check_intensity(v: V3) -> std::result::Result<Vec3, FieldError> {
    if !finite3(v) || v.iter().any(|x| *x < 0.0) {
        return Err(("intensity".into(), "must be finite and non-negative"));
    }
    if v.iter().any(|x| *x > MAX_INTENSITY) {
        return Err(("intensity".into(), "must be at most 1e10 W/sr per channel"));
    }
    Ok(Vec3::from(v))
}

fn check_light_position(v: V3) -> std::result::Result<Vec3, FieldError> {
    if !finite3(v) {
        return Err(("position".into(), "must be finite"));
    }
    if !within_extent(v) {
        return Err(("position".into(), "must lie within ±100000 m"));
    }
    Ok(Vec3::from(v))
}

pub(crate) fn light_from_desc(l: &LightDesc) -> std::result::Result<Light, FieldError> {
    match *l {
        LightDesc::Point {
            position,
            intensity,
        } => {
            let position = check_light_position(position)?;
            Ok(Light::Point {
                position,
                intensity: check_intensity(intensity)?,
            })
        }
        LightDesc::Spot {
            position,
            direction,
            intensity,
            inner_angle,
            outer_angle,
        } => {
            let position = check_light_position(position)?;
            let d = Vec3::from(direction);
            if !finite3(direction) || d.length() < 1e-6 {
                return Err(("direction".into(), "must be finite and non-zero"));
            }
            let (inner_angle, outer_angle) = desc::spot_angles(inner_angle, outer_angle);
            if !(outer_angle > 0.0 && outer_angle < 90.0) {
                return Err(("outer_angle".into(), "must be in (0, 90) degrees"));
            }
            if !(inner_angle >= 0.0 && inner_angle <= outer_angle) {
                return Err((
                    "inner_angle".into(),
                    "must be in [0, outer_angle] degrees (the angle of full intensity \
                     lies within the cone's outer angle)",
                ));
            }
            Ok(Light::Spot {
                position,
                direction: d.normalize(),
                intensity: check_intensity(intensity)?,
                cos_inner: inner_angle.to_radians().cos(),
                cos_outer: outer_angle.to_radians().cos(),
            })
        }
        LightDesc::Directional {
            direction,
            irradiance,
            angular_diameter,
        } => {
            let d = Vec3::from(direction);
            if !finite3(direction) || d.length() < 1e-6 {
                return Err(("direction".into(), "must be finite and non-zero"));
            }
            if !finite3(irradiance) || irradiance.iter().any(|x| *x < 0.0) {
                return Err(("irradiance".into(), "must be finite and non-negative"));
            }
            if irradiance.iter().any(|x| *x > MAX_RADIANCE) {
                return Err((
                    "irradiance".into(),
                    "must be at most 1e10 W/m² per channel (MAX_RADIANCE)",
                ));
            }
            if !(0.0..MAX_ANGULAR_DIAMETER).contains(&angular_diameter) {
                return Err((
                    "angular_diameter".into(),
                    "must be in [0, 90) degrees (MAX_ANGULAR_DIAMETER)",
                ));
            }
            Ok(Light::Directional {
                direction: d.normalize(),
                irradiance: Vec3::from(irradiance),
                cos_half_angle: (0.5 * angular_diameter).to_radians().cos(),
            })
        }
    }
}

pub(crate) fn material_from_desc(m: &MaterialDesc) -> std::result::Result<Material, FieldError> {
    for (name, v) in [
        ("diffuse", m.diffuse),
        ("specular", m.specular),
        ("transmission", m.transmission),
    ] {
        if !finite3(v) || v.iter().any(|x| !(0.0..=1.0).contains(x)) {
            return Err((name.into(), "each channel must be in [0, 1]"));
        }
    }
    if (0..3).any(|c| m.diffuse[c] + m.transmission[c] > 1.0 + 1e-6) {
        return Err((
            "transmission".into(),
            "diffuse + transmission must not exceed 1 (energy conservation)",
        ));
    }
    if !(0.0..=1.0).contains(&m.roughness) {
        return Err(("roughness".into(), "must be in [0, 1]"));
    }
    if !(m.ior >= 1.0 && m.ior <= 4.0) {
        return Err(("ior".into(), "must be in [1, 4]"));
    }
    if !finite3(m.emission) || m.emission.iter().any(|x| *x < 0.0) {
        return Err(("emission".into(), "must be finite and non-negative"));
    }
    if m.emission.iter().any(|x| *x > MAX_RADIANCE) {
        return Err((
            "emission".into(),
            "must be at most 1e10 W·sr⁻¹·m⁻² per channel (MAX_RADIANCE)",
        ));
    }
    let distribution = match m.distribution {
        desc::DistributionDesc::Ggx => crate::bsdf::Distribution::Ggx,
        desc::DistributionDesc::Beckmann => crate::bsdf::Distribution::Beckmann,
    };
    let coating = match m.coating_ior {
        None => None,
        Some(eta) if !(eta > 1.0 && eta <= 4.0) => {
            return Err(("coating_ior".into(), "must be in (1, 4]"));
        }
        Some(_) if m.transmission.iter().any(|t| *t > 0.0) => {
            return Err((
                "coating_ior".into(),
                "excludes transmission (a coated base is opaque)",
            ));
        }
        Some(eta) => Some(Coating::new(
            eta,
            m.coating_nonlinear,
            m.roughness * m.roughness,
            distribution,
        )),
    };
    if m.coating_nonlinear && coating.is_none() {
        return Err(("coating_nonlinear".into(), "needs coating_ior"));
    }
    let conductor = match (m.conductor_eta, m.conductor_k) {
        (None, None) => None,
        (Some(eta), Some(k)) => {
            for (name, v) in [("conductor_eta", eta), ("conductor_k", k)] {
                if !finite3(v) || v.iter().any(|x| !(0.0..=100.0).contains(x)) {
                    return Err((name.into(), "each channel must be in [0, 100]"));
                }
            }
            if coating.is_some() {
                return Err(("conductor_eta".into(), "excludes coating_ior"));
            }
            Some(Conductor::new(eta.into(), k.into()))
        }
        (Some(_), None) => return Err(("conductor_k".into(), "needed with conductor_eta")),
        (None, Some(_)) => return Err(("conductor_eta".into(), "needed with conductor_k")),
    };
    if m.rough_glass {
        rough_glass_valid(m, coating.is_some() || conductor.is_some())?;
    }
    Ok(Material {
        diffuse: m.diffuse.into(),
        specular: m.specular.into(),
        roughness: m.roughness,
        fresnel: m.fresnel,
        transmission: m.transmission.into(),
        ior: m.ior,
        emission: m.emission.into(),
        two_sided: m.two_sided,
        distribution,
        coating,
        conductor,
        rough_glass: m.rough_glass,
    })
}

/// Rough glass (Mitsuba's roughdielectric) has no diffuse base, no other Fresnel model and
/// a rough surface (Mitsuba clamps α to 1e-4: roughness ≥ 0.01).
fn rough_glass_valid(m: &MaterialDesc, other_model: bool) -> std::result::Result<(), FieldError> {
    if other_model {
        return Err((
            "rough_glass".into(),
            "excludes coating_ior and conductor_* (one model a material)",
        ));
    }
    if m.diffuse.iter().any(|d| *d > 0.0) {
        return Err((
            "rough_glass".into(),
            "needs diffuse 0 (glass has no diffuse base)",
        ));
    }
    if m.roughness < 0.01 {
        return Err((
            "roughness".into(),
            "must be at least 0.01 (α ≥ 1e-4) with rough_glass; smooth glass is roughness 0 without it",
        ));
    }
    if m.ior <= 1.0 {
        return Err(("ior".into(), "must exceed 1 with rough_glass"));
    }
    Ok(())
}

pub(crate) fn transform_matrix(t: &desc::TransformDesc) -> std::result::Result<Mat4, FieldError> {
    if let Some(rows) = &t.matrix {
        if !t.is_trs_default() {
            return Err((
                "matrix".into(),
                "excludes translate/rotate/scale (give one or the other)",
            ));
        }
        return matrix_from_rows(rows).map_err(|(f, m)| (format!("matrix{f}"), m));
    }
    if !finite3(t.translate) {
        return Err(("translate".into(), "must be finite"));
    }
    if !within_extent(t.translate) {
        return Err(("translate".into(), "must lie within ±100000 m"));
    }
    if !finite3(t.rotate) {
        return Err(("rotate".into(), "must be finite"));
    }
    let scale = match t.scale {
        Scale::Uniform(s) => Vec3::splat(s),
        Scale::PerAxis(s) => Vec3::from(s),
    };
    if !scale.is_finite() || scale.abs().min_element() < 1e-12 {
        return Err(("scale".into(), "must be finite and non-zero"));
    }
    if scale.abs().max_element() > MAX_SCALE || scale.abs().min_element() < 1.0 / MAX_SCALE {
        return Err((
            "scale".into(),
            "each factor's magnitude must be in [1e-6, 1e6]",
        ));
    }
    let [rx, ry, rz] = t.rotate.map(f32::to_radians);
    // Rotate about x first, then y, then z: R = Rz·Ry·Rx.
    let rot = Quat::from_euler(EulerRot::ZYX, rz, ry, rx);
    Ok(Mat4::from_scale_rotation_translation(
        scale,
        rot,
        t.translate.into(),
    ))
}

/// An affine transform from 3 or 4 rows of 4 numbers (row-major; the translation in the last
/// column; a 4th row must be `[0, 0, 0, 1]`): finite, its translation within
/// [`MAX_EXTENT`], each axis's image (column) of length in [1/`MAX_SCALE`, `MAX_SCALE`],
/// and invertible by a margin: |det| at least 1e-6 of the product of the columns' lengths
/// (1 for orthogonal axes; Hadamard's bound), so that no axis collapses onto the others.
/// Errors name the part at fault relative to the matrix (`""`, `"[3]"`).
pub(crate) fn matrix_from_rows(rows: &[Vec<f32>]) -> std::result::Result<Mat4, FieldError> {
    if rows.len() != 3 && rows.len() != 4 {
        return Err((String::new(), "must be 3 or 4 rows of 4 numbers"));
    }
    if let Some(r) = rows.iter().position(|row| row.len() != 4) {
        return Err((format!("[{r}]"), "must hold 4 numbers"));
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err((String::new(), "must be finite"));
    }
    if rows.len() == 4 && rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(("[3]".into(), "must be [0, 0, 0, 1] (transforms are affine)"));
    }
    let mut m = Mat4::IDENTITY;
    for (r, row) in rows.iter().take(3).enumerate() {
        for (c, &v) in row.iter().enumerate() {
            m.col_mut(c)[r] = v;
        }
    }
    if !within_extent([m.w_axis.x, m.w_axis.y, m.w_axis.z]) {
        return Err((String::new(), "its translation must lie within ±100000 m"));
    }
    let lin = Mat3::from_mat4(m);
    let lengths = [
        lin.x_axis.length(),
        lin.y_axis.length(),
        lin.z_axis.length(),
    ];
    if lengths
        .iter()
        .any(|&l| !(l.is_finite() && (1.0 / MAX_SCALE..=MAX_SCALE).contains(&l)))
    {
        return Err((
            String::new(),
            "each column's length (an axis's scale) must be in [1e-6, 1e6]",
        ));
    }
    let det = lin.determinant();
    if !(det.is_finite() && det.abs() >= 1e-6 * lengths.iter().product::<f32>()) {
        return Err((
            String::new(),
            "must be invertible (its columns are parallel or coplanar: singular)",
        ));
    }
    Ok(m)
}

fn primitive(shape: &ShapeDesc) -> std::result::Result<TriMesh, FieldError> {
    let positive = |name: &str, v: f32| {
        if !(v.is_finite() && v > 0.0) {
            Err((name.to_string(), "must be positive and finite"))
        } else if v > MAX_EXTENT {
            Err((name.to_string(), "must be at most 100000 m"))
        } else {
            Ok(v)
        }
    };
    let segs = |s: u32| {
        if (3..=4096).contains(&s) {
            Ok(s)
        } else {
            Err(("segments".to_string(), "must be in 3..=4096"))
        }
    };
    Ok(match *shape {
        ShapeDesc::Mesh { .. } | ShapeDesc::Instance { .. } => {
            unreachable!("mesh files and instances are resolved by the caller")
        }
        ShapeDesc::Quad { size } => {
            primitives::quad([positive("size", size[0])?, positive("size", size[1])?])
        }
        ShapeDesc::Box { size } => primitives::cuboid(Vec3::new(
            positive("size", size[0])?,
            positive("size", size[1])?,
            positive("size", size[2])?,
        )),
        ShapeDesc::Sphere {
            radius,
            subdivisions,
        } => {
            if subdivisions > 7 {
                return Err((
                    "subdivisions".into(),
                    "must be at most 7 (327,680 triangles)",
                ));
            }
            primitives::sphere(positive("radius", radius)?, subdivisions)
        }
        ShapeDesc::Cylinder {
            radius,
            height,
            segments,
            caps,
        } => primitives::cylinder(
            positive("radius", radius)?,
            positive("height", height)?,
            segs(segments)?,
            caps,
        ),
        ShapeDesc::Ring {
            inner_radius,
            outer_radius,
            height,
            segments,
        } => {
            let inner = positive("inner_radius", inner_radius)?;
            if !(outer_radius.is_finite() && outer_radius > inner && outer_radius <= MAX_EXTENT) {
                return Err((
                    "outer_radius".into(),
                    "must be finite, larger than inner_radius and at most 100000 m",
                ));
            }
            primitives::ring(
                inner,
                outer_radius,
                positive("height", height)?,
                segs(segments)?,
            )
        }
    })
}

/// The box of a mesh's vertices (non-finite when a vertex is).
fn mesh_bounds(m: &TriMesh) -> (Vec3, Vec3) {
    m.positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            if p.is_finite() {
                (lo.min(*p), hi.max(*p))
            } else {
                (Vec3::NAN, Vec3::NAN)
            }
        })
}

/// Whether every corner of the box (lo, hi), placed by `xf`, is finite and within
/// [`MAX_EXTENT`]: then so is every vertex inside it (an affine map keeps points inside
/// the corners' hull).
fn box_within_extent(lo: Vec3, hi: Vec3, xf: Mat4) -> bool {
    if !(lo.is_finite() && hi.is_finite()) {
        return false;
    }
    (0..8).all(|i| {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let p = xf.transform_point3(c);
        p.is_finite() && p.abs().max_element() <= MAX_EXTENT
    })
}

/// Checks that every vertex of `m` lies within [`MAX_EXTENT`] once placed by `xf`; blames
/// the shape when its own coordinates are out of range, else the transform.
fn validate_placed(m: &TriMesh, xf: Mat4) -> std::result::Result<(), (String, String)> {
    let outside = |p: Vec3| !(p.is_finite() && p.abs().max_element() <= MAX_EXTENT);
    if let Some(i) = m.positions.iter().position(|p| outside(*p)) {
        return Err(("shape".into(), format!("vertex {i} lies outside ±100000 m")));
    }
    if let Some(i) = m
        .positions
        .iter()
        .position(|p| outside(xf.transform_point3(*p)))
    {
        return Err((
            "transform".into(),
            format!("places vertex {i} outside ±100000 m"),
        ));
    }
    Ok(())
}

fn smoothing(s: Option<SmoothDesc>) -> std::result::Result<Smoothing, &'static str> {
    Ok(match s {
        None => Smoothing::Auto,
        Some(SmoothDesc::On(false)) => Smoothing::Flat,
        Some(SmoothDesc::On(true)) => Smoothing::Smooth,
        Some(SmoothDesc::CreaseAngle(deg)) if (0.0..=180.0).contains(&deg) => {
            Smoothing::from_angle_degrees(deg)
        }
        Some(SmoothDesc::CreaseAngle(_)) => {
            return Err("must be false, true or a crease angle in [0, 180] degrees")
        }
    })
}

fn validate_mesh(m: &TriMesh) -> std::result::Result<(), String> {
    if m.indices.is_empty() {
        return Err("mesh has no triangles".into());
    }
    if let Some(i) = m.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} is not finite (NaN or infinity)"));
    }
    let count_ok = m.normals.is_empty() || m.normals.len() == m.positions.len();
    if !count_ok || m.normals.iter().any(|n| !n.is_finite()) {
        return Err("normals must be finite, one per vertex (or none)".into());
    }
    let n = m.positions.len() as u32;
    if let Some(t) = m.indices.iter().position(|t| t.iter().any(|&i| i >= n)) {
        return Err(format!("triangle {t} indexes a vertex out of range"));
    }
    Ok(())
}
