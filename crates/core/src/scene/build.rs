//! A [`Scene`] from its JSON description: the objects resolved to unique meshes (following
//! instances), placed and checked, the materials of the description and of mesh files, the
//! lights, camera and environment converted ([`super::convert`]).

use super::convert::*;
use super::desc::{self, ShapeDesc, SmoothDesc};
use super::*;
use crate::error::{Error, Result};
use crate::memory;
use glam::{Mat3, Mat4, Vec2, Vec3};
use std::collections::HashMap;
use std::sync::Arc;

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
}
