//! `Scene`: built-in scenes, and JSON descriptions with mesh arrays loaded by Python.

use crate::errors::{to_py, SceneError};
use gi_core::scene::{builtin, EnvImage, MeshData, TriMesh};
use glam::{Vec2, Vec3};
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;

/// A loaded, validated scene.
#[pyclass(module = "gi._gi", name = "Scene", frozen)]
pub struct PyScene {
    pub inner: gi_core::Scene,
    source: String,
    bvh: std::sync::OnceLock<gi_core::trace::SceneBvh>,
}

fn vec3s(a: &PyReadonlyArray2<'_, f32>, what: &str, source: &str) -> PyResult<Vec<Vec3>> {
    let view = a.as_array();
    if view.ncols() != 3 {
        return Err(SceneError::new_err(format!(
            "{source}: {what} must have shape (N, 3), got {:?}",
            view.shape()
        )));
    }
    Ok(view
        .rows()
        .into_iter()
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect())
}

/// Converts one `meshes` entry: (vertices f32 (N,3), faces u32 (M,3), normals f32 (N,3) | None
/// (zero rows: none for that vertex), materials JSON `[[name, material], ...]` | None,
/// face_materials u32 (M,) | None, indices into the materials[, uvs f32 (N,2) | None]).
fn mesh_from_py(key: &str, value: &Bound<'_, PyAny>, source: &str) -> PyResult<MeshData> {
    type Entry<'py> = (
        PyReadonlyArray2<'py, f32>,
        PyReadonlyArray2<'py, u32>,
        Option<PyReadonlyArray2<'py, f32>>,
        Option<String>,
        Option<PyReadonlyArray1<'py, u32>>,
    );
    let expected = |e: PyErr| {
        SceneError::new_err(format!("{source}: mesh `{key}`: expected (vertices, faces, normals, materials, face_materials[, uvs[, tangents]]): {e}"))
    };
    let items: Vec<Bound<'_, PyAny>> = value
        .try_iter()
        .and_then(|it| it.collect::<PyResult<_>>())
        .map_err(expected)?;
    let optional = |i: usize| -> PyResult<Option<PyReadonlyArray2<'_, f32>>> {
        match items.get(i) {
            Some(a) if !a.is_none() => a
                .extract::<PyReadonlyArray2<'_, f32>>()
                .map(Some)
                .map_err(expected),
            _ => Ok(None),
        }
    };
    let (uv, tangents) = (optional(5)?, optional(6)?);
    let head = pyo3::types::PyTuple::new(value.py(), items.iter().take(5))?;
    let (v, f, n, mats, face_mats) = head.extract::<Entry>().map_err(expected)?;
    // The arrays are copied into the mesh, the scene (placed) and its normals.
    let (nv, nf) = (v.as_array().nrows() as u64, f.as_array().nrows() as u64);
    gi_core::memory::check(|| format!("mesh `{key}`"), (nv * 24 + nf * 16) * 3)
        .map_err(|e| to_py(value.py(), e))?;
    let positions = vec3s(&v, "vertices", source)?;
    let faces = f.as_array();
    if faces.ncols() != 3 {
        return Err(SceneError::new_err(format!(
            "{source}: mesh `{key}`: faces must have shape (M, 3)"
        )));
    }
    let indices: Vec<[u32; 3]> = faces
        .rows()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect();
    let normals = match n {
        Some(n) => vec3s(&n, "normals", source)?,
        // No normals: the core shades flat, or as the object's `smooth` asks.
        None => Vec::new(),
    };
    let materials = match mats {
        Some(ref json) => gi_core::scene::parse_materials(json, source)
            .map_err(|e| Python::attach(|py| to_py(py, e)))?,
        None => Vec::new(),
    };
    let material_textures = match &mats {
        Some(json) => gi_core::scene::parse_material_textures(json, source)
            .map_err(|e| Python::attach(|py| to_py(py, e)))?,
        None => Vec::new(),
    };
    let face_materials = face_mats.map(|a| a.as_array().to_vec()).unwrap_or_default();
    let uvs = match uv {
        None => Vec::new(),
        Some(a) => {
            let a = a.as_array();
            if a.ncols() != 2 || a.nrows() != positions.len() {
                return Err(SceneError::new_err(format!(
                    "{source}: mesh `{key}`: uvs must have shape (N, 2), one per vertex"
                )));
            }
            let per_vertex: Vec<Vec2> = a
                .rows()
                .into_iter()
                .map(|r| Vec2::new(r[0], r[1]))
                .collect();
            indices
                .iter()
                .map(|t| t.map(|i| per_vertex.get(i as usize).copied().unwrap_or(Vec2::ZERO)))
                .collect()
        }
    };
    let tangents = match tangents {
        None => Vec::new(),
        Some(a) => corner_tangents(&a, &indices, key, source)?,
    };
    Ok(MeshData {
        mesh: TriMesh {
            positions,
            normals,
            indices,
        },
        materials,
        face_materials,
        material_textures,
        uvs,
        tangents,
    })
}

/// A mesh's per-vertex tangents (N, 4) in gi's convention (`gi_core::scene::tangents`) as
/// tangents per triangle corner.
fn corner_tangents(
    a: &PyReadonlyArray2<'_, f32>,
    indices: &[[u32; 3]],
    key: &str,
    source: &str,
) -> PyResult<Vec<[glam::Vec4; 3]>> {
    let a = a.as_array();
    let n = indices
        .iter()
        .flatten()
        .max()
        .map_or(0, |&m| m as usize + 1);
    if a.ncols() != 4 || a.nrows() < n {
        return Err(SceneError::new_err(format!(
            "{source}: mesh `{key}`: tangents must have shape (N, 4), one per vertex"
        )));
    }
    let per_vertex: Vec<glam::Vec4> = a
        .rows()
        .into_iter()
        .map(|r| glam::Vec4::new(r[0], r[1], r[2], r[3]))
        .collect();
    Ok(indices
        .iter()
        .map(|t| t.map(|i| per_vertex[i as usize]))
        .collect())
}

/// Converts the `textures` argument: name -> f32 array (H, W, 4), linear RGBA, top row first.
fn textures_from_py(
    textures: Option<&Bound<'_, PyDict>>,
    source: &str,
) -> PyResult<gi_core::scene::TextureMap> {
    let mut out = gi_core::scene::TextureMap::new();
    let Some(textures) = textures else {
        return Ok(out);
    };
    for (k, v) in textures.iter() {
        let name: String = k.extract()?;
        let a: PyReadonlyArray3<'_, f32> = v.extract().map_err(|e| {
            SceneError::new_err(format!(
                "{source}: texture `{name}`: expected a float32 array (H, W, 4): {e}"
            ))
        })?;
        let a = a.as_array();
        let (h, w, c) = a.dim();
        if c != 4 || w == 0 || h == 0 || w > u32::MAX as usize || h > u32::MAX as usize {
            return Err(SceneError::new_err(format!(
                "{source}: texture `{name}`: expected shape (H, W, 4), got {:?}",
                a.shape()
            )));
        }
        gi_core::memory::check(|| format!("texture `{name}`"), (w * h * 16 * 2) as u64)
            .map_err(|e| to_py(v.py(), e))?;
        let data: Vec<f32> = a.iter().copied().collect();
        let tex = gi_core::texture::Texture::new(w as u32, h as u32, &data)
            .map_err(|m| SceneError::new_err(format!("{source}: texture `{name}`: {m}")))?;
        out.insert(name, std::sync::Arc::new(tex));
    }
    Ok(out)
}

/// Converts one `images` entry: an equirectangular environment image, float32 (H, W, 3),
/// rows from the top (up). Values are checked by the core.
fn env_image_from_py(key: &str, value: &Bound<'_, PyAny>, source: &str) -> PyResult<EnvImage> {
    let a: PyReadonlyArray3<'_, f32> = value.extract().map_err(|e| {
        SceneError::new_err(format!(
            "{source}: environment image `{key}`: expected a float32 array (H, W, 3): {e}"
        ))
    })?;
    let view = a.as_array();
    let (h, w, c) = view.dim();
    if c != 3 || h == 0 || w == 0 {
        return Err(SceneError::new_err(format!(
            "{source}: environment image `{key}` must have shape (H, W, 3), got {:?}",
            view.shape()
        )));
    }
    gi_core::memory::check(|| format!("environment image `{key}`"), (h * w) as u64 * 24)
        .map_err(|e| to_py(value.py(), e))?;
    let texels = view
        .outer_iter()
        .flat_map(|row| {
            row.outer_iter()
                .map(|t| Vec3::new(t[0], t[1], t[2]))
                .collect::<Vec<_>>()
        })
        .collect();
    Ok(EnvImage {
        width: w as u32,
        height: h as u32,
        texels,
    })
}

/// Converts the `images` argument: environment file name -> float32 (H, W, 3) image.
fn env_images_from_py(
    images: Option<&Bound<'_, PyDict>>,
    source: &str,
) -> PyResult<HashMap<String, EnvImage>> {
    let mut out = HashMap::new();
    if let Some(images) = images {
        for (k, v) in images.iter() {
            let key: String = k.extract()?;
            let image = env_image_from_py(&key, &v, source)?;
            out.insert(key, image);
        }
    }
    Ok(out)
}

/// New lighting from its JSON sections and images (see `gi_core::scene::Lighting`).
pub fn lighting_from_py(
    py: Python<'_>,
    environment: Option<&str>,
    images: Option<&Bound<'_, PyDict>>,
    lights: Option<&str>,
    add: bool,
    source: &str,
) -> PyResult<gi_core::scene::Lighting> {
    let images = env_images_from_py(images, source)?;
    gi_core::scene::Lighting::from_json(environment, &images, lights, add, source)
        .map_err(|e| to_py(py, e))
}

#[pymethods]
impl PyScene {
    /// The scene with an environment (JSON section, `None`: none; `images` holds its
    /// `file`) and lights (a JSON list) added to its light (`add`) or replacing it; errors
    /// name `source` and the field.
    #[pyo3(signature = (environment = None, images = None, lights = None, add = true, source = "lighting".to_string()))]
    fn with_lighting(
        &self,
        py: Python<'_>,
        environment: Option<&str>,
        images: Option<&Bound<'_, PyDict>>,
        lights: Option<&str>,
        add: bool,
        source: String,
    ) -> PyResult<Self> {
        let lighting = lighting_from_py(py, environment, images, lights, add, &source)?;
        Ok(PyScene {
            inner: self.inner.with_lighting(&lighting),
            source: self.source.clone(),
            bvh: Default::default(),
        })
    }

    /// Parses a JSON scene description. `meshes` maps each `mesh` object's `file` string to
    /// its arrays (see `gi.scene` for the loader that fills it); `images` maps the
    /// `environment` section's `file` to its float32 (H, W, 3) image.
    #[staticmethod]
    #[pyo3(signature = (text, source = "<string>".to_string(), meshes = None, images = None, textures = None))]
    fn from_json(
        py: Python<'_>,
        text: &str,
        source: String,
        meshes: Option<&Bound<'_, PyDict>>,
        images: Option<&Bound<'_, PyDict>>,
        textures: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let env_images = env_images_from_py(images, &source)?;
        let mut map = HashMap::new();
        if let Some(meshes) = meshes {
            for (k, v) in meshes.iter() {
                let key: String = k.extract()?;
                let data = mesh_from_py(&key, &v, &source)?;
                map.insert(key, data);
            }
        }
        let textures = textures_from_py(textures, &source)?;
        let inner = crate::guard::run(py, "Scene.from_json", None, |_| {
            gi_core::Scene::from_json_with(text, &source, &map, &env_images, &textures)
        })?;
        Ok(PyScene {
            inner,
            source,
            bvh: Default::default(),
        })
    }

    /// Loads a built-in scene by name.
    #[staticmethod]
    fn builtin(py: Python<'_>, name: &str) -> PyResult<Self> {
        let inner = crate::guard::catch("Scene.builtin", || {
            builtin::load(name).map_err(|e| to_py(py, e))
        })?;
        Ok(PyScene {
            inner,
            source: name.to_string(),
            bvh: Default::default(),
        })
    }

    /// The file or built-in name the scene came from.
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }
    #[getter]
    fn width(&self) -> u32 {
        self.inner.camera.width
    }
    #[getter]
    fn height(&self) -> u32 {
        self.inner.camera.height
    }
    #[getter]
    fn triangle_count(&self) -> usize {
        self.inner.triangle_count()
    }
    /// Triangles of the unique meshes: each mesh counted once however many objects place
    /// it (the same file or built-in shape with the same options, or an `instance` shape).
    #[getter]
    fn unique_triangle_count(&self) -> usize {
        self.inner.unique_triangle_count()
    }
    #[getter]
    fn light_count(&self) -> usize {
        self.inner.lights.len()
    }
    /// Whether the scene has an environment light.
    #[getter]
    fn has_environment(&self) -> bool {
        self.inner.environment.is_some()
    }
    #[getter]
    fn material_names(&self) -> Vec<String> {
        self.inner.material_names.clone()
    }
    /// Names of the textures the scene loaded (what material texture fields name).
    #[getter]
    fn texture_names(&self) -> Vec<String> {
        self.inner.texture_names.clone()
    }
    /// Total emitted power of all lights, W per channel.
    #[getter]
    fn total_power(&self) -> [f32; 3] {
        self.inner.total_power().to_array()
    }

    /// Length of the scene's animation in seconds, or `None` without an `animation` section.
    #[getter]
    fn animation_duration(&self) -> Option<f64> {
        self.inner.animation_duration()
    }

    /// The animated targets at `time` (seconds) as Python values: a list of `{"target": "camera" |
    /// "light" | "object" | "material", "key": null | light index | object name (index when
    /// unnamed) | material name, "value": the target's description at that time}` (an
    /// object's value is its whole transform), what `Renderer.update` takes.
    fn animation_at<'py>(&self, py: Python<'py>, time: f64) -> PyResult<Bound<'py, PyAny>> {
        use gi_core::scene::update::UpdateTarget;
        use serde_json::{json, Value};
        let values = self
            .inner
            .animation_values(time)
            .map_err(|e| to_py(py, e))?;
        let list: Vec<Value> = values
            .into_iter()
            .map(|(target, value)| {
                let (name, key) = match target {
                    UpdateTarget::Camera => ("camera", Value::Null),
                    UpdateTarget::Light(i) => ("light", json!(i)),
                    UpdateTarget::Object(i) => (
                        "object",
                        match &self.inner.objects[i].name {
                            Some(n) => json!(n),
                            None => json!(i),
                        },
                    ),
                    UpdateTarget::Material(n) => ("material", json!(n)),
                };
                json!({"target": name, "key": key, "value": value})
            })
            .collect();
        crate::values::to_py(py, &Value::Array(list))
    }

    /// World-space triangles: (vertices float32 (V, 3), faces uint32 (T, 3)).
    fn mesh_arrays<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        use numpy::{IntoPyArray, PyArrayMethods};
        // The flat view is every object's placed copy: refused by its estimate (with the
        // two arrays copied out of it) before it is built.
        if !self.inner.flat_is_built() {
            let s = &self.inner;
            gi_core::memory::check(
                || {
                    format!(
                        "the scene's world-space triangles ({} objects, {} triangles)",
                        s.objects.len(),
                        s.triangle_count()
                    )
                },
                s.flat_estimate().saturating_mul(2),
            )
            .map_err(|e| to_py(py, e))?;
        }
        let v: Vec<f32> = bytemuck::cast_slice(&self.inner.flat().positions).to_vec();
        let f: Vec<u32> = self
            .inner
            .flat()
            .triangles
            .iter()
            .flatten()
            .copied()
            .collect();
        let (nv, nf) = (
            self.inner.flat().positions.len(),
            self.inner.flat().triangles.len(),
        );
        Ok((
            v.into_pyarray(py).reshape([nv, 3])?.into_any(),
            f.into_pyarray(py).reshape([nf, 3])?.into_any(),
        ))
    }

    /// Closest hits of rays against the scene's BVH (built on first use, then cached):
    /// origins and unit directions float32 (N, 3) → (distance float32 (N,), inf on a miss;
    /// triangle int64 (N,), -1 on a miss). The GIL is released; rays run in parallel.
    fn intersect<'py>(
        &self,
        py: Python<'py>,
        origins: PyReadonlyArray2<'py, f32>,
        directions: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        use numpy::IntoPyArray;
        use rayon::prelude::*;
        let o = vec3s(&origins, "origins", &self.source)?;
        let d = vec3s(&directions, "directions", &self.source)?;
        if o.len() != d.len() {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "origins and directions differ in length",
            ));
        }
        if let Some(i) = o.iter().chain(&d).position(|v| !v.is_finite()) {
            let (what, row) = if i < o.len() {
                ("origins", i)
            } else {
                ("directions", i - o.len())
            };
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "{what}[{row}] is not finite"
            )));
        }
        let (t, tri): (Vec<f32>, Vec<i64>) =
            crate::guard::run(py, "Scene.intersect", None, |_| {
                let bvh = self.bvh()?;
                Ok(o.par_iter()
                    .zip(d.par_iter())
                    .map(|(o, d)| match bvh.intersect(*o, *d, f32::INFINITY) {
                        Some(h) => (h.t, h.triangle as i64),
                        None => (f32::INFINITY, -1),
                    })
                    .unzip())
            })?;
        Ok((
            t.into_pyarray(py).into_any(),
            tri.into_pyarray(py).into_any(),
        ))
    }

    /// Builds the ray-query BVH now (otherwise on the first `intersect`).
    fn build_bvh(&self, py: Python<'_>) -> PyResult<()> {
        crate::guard::run(py, "Scene.build_bvh", None, |_| self.bvh().map(|_| ()))
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(source={:?}, triangles={}, lights={}, size={}x{})",
            self.source,
            self.inner.triangle_count(),
            self.inner.lights.len(),
            self.inner.camera.width,
            self.inner.camera.height
        )
    }
}

impl PyScene {
    /// The ray-query BVH, built (after a memory check) on first use.
    fn bvh(&self) -> gi_core::Result<&gi_core::trace::SceneBvh> {
        if let Some(b) = self.bvh.get() {
            return Ok(b);
        }
        let built = gi_core::trace::SceneBvh::try_build(&self.inner)?;
        Ok(self.bvh.get_or_init(|| built))
    }
}

/// (name, description) of every built-in scene; the first is the default.
#[pyfunction]
pub fn builtin_scenes() -> Vec<(&'static str, &'static str)> {
    builtin::BUILTINS.iter().map(|(n, d, _)| (*n, *d)).collect()
}

/// The JSON description of a built-in scene (a starting point for your own).
#[pyfunction]
pub fn builtin_json(name: &str) -> PyResult<&'static str> {
    builtin::json(name)
        .ok_or_else(|| SceneError::new_err(format!("no built-in scene named `{name}`")))
}
