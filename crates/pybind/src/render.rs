//! `render()`: runs a method with the GIL released and returns numpy arrays.

use crate::errors::to_py;
use crate::scene::PyScene;
use gi_core::frame::{FrameDesc, Images, Renderer};
use gi_core::scene::update::UpdateTarget;
use gi_core::{Image, Method, Settings};
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

fn image_array<'py>(py: Python<'py>, img: Image) -> PyResult<Bound<'py, PyAny>> {
    let (w, h) = (img.width as usize, img.height as usize);
    let flat: Vec<f32> = bytemuck::cast_slice(&img.pixels).to_vec();
    Ok(flat.into_pyarray(py).reshape([h, w, 3])?.into_any())
}

/// A setting's error, named.
fn setting_error(py: Python<'_>, name: &'static str, message: impl Into<String>) -> PyErr {
    to_py(
        py,
        gi_core::Error::Setting {
            name,
            message: message.into(),
        },
    )
}

/// An integer setting of any Python size, range-checked into `T`.
fn int<T: TryFrom<i128>>(v: &Bound<'_, PyAny>, name: &'static str) -> PyResult<T> {
    let py = v.py();
    if v.is_instance_of::<pyo3::types::PyBool>() {
        return Err(setting_error(py, name, "must be an integer, not a bool"));
    }
    let i: i128 = v
        .extract()
        .map_err(|_| setting_error(py, name, format!("must be an integer, got {v}")))?;
    T::try_from(i).map_err(|_| setting_error(py, name, format!("{i} is out of range")))
}

fn opt_int<T: TryFrom<i128>>(v: &Bound<'_, PyAny>, name: &'static str) -> PyResult<Option<T>> {
    if v.is_none() {
        Ok(None)
    } else {
        int(v, name).map(Some)
    }
}

fn float(v: &Bound<'_, PyAny>, name: &'static str) -> PyResult<f32> {
    let py = v.py();
    let x: f64 = v
        .extract()
        .map_err(|_| setting_error(py, name, format!("must be a number, got {v}")))?;
    if !x.is_finite() || x.abs() > f32::MAX as f64 {
        return Err(setting_error(py, name, format!("must be finite, got {x}")));
    }
    Ok(x as f32)
}

fn flag(v: &Bound<'_, PyAny>, name: &'static str) -> PyResult<bool> {
    v.extract()
        .map_err(|_| setting_error(v.py(), name, format!("must be a bool, got {v}")))
}

fn text(v: &Bound<'_, PyAny>, name: &'static str) -> PyResult<String> {
    v.extract()
        .map_err(|_| setting_error(v.py(), name, format!("must be a string, got {v}")))
}

/// The settings of `method` from keyword arguments (the names of `gi.render`); defaults and
/// validation are the core's (`Settings::default`, `Settings::validate`).
pub fn settings_from(
    py: Python<'_>,
    method: &str,
    kw: Option<&Bound<'_, PyDict>>,
) -> PyResult<Settings> {
    let mut s = Settings::for_method(method.parse().map_err(|e| to_py(py, e))?);
    for (k, v) in kw.into_iter().flat_map(|d| d.iter()) {
        let key: String = k.extract()?;
        let v = &v;
        match key.as_str() {
            "spp" => {
                if !v.is_none() {
                    s.spp = int(v, "spp")?
                }
            }
            "width" => s.width = opt_int(v, "width")?,
            "height" => s.height = opt_int(v, "height")?,
            "seed" => s.seed = int(v, "seed")?,
            "max_depth" => s.max_depth = int(v, "max_depth")?,
            "light_paths" => s.light_paths = opt_int(v, "light_paths")?,
            "photons" => s.photons = int(v, "photons")?,
            "k" => s.k = int(v, "k")?,
            "max_radius" => {
                s.max_radius = if v.is_none() {
                    None
                } else {
                    Some(float(v, "max_radius")?)
                }
            }
            "kernel" => s.kernel = text(v, "kernel")?.parse().map_err(|e| to_py(py, e))?,
            "smoothing" => s.smoothing = float(v, "smoothing")?,
            "leaf_size" => s.leaf_size = opt_int(v, "leaf_size")?,
            "kernel_scale" => s.kernel_scale = float(v, "kernel_scale")?,
            "subsample" => s.subsample = int(v, "subsample")?,
            "footprint_volumes" => s.footprint_volumes = flag(v, "footprint_volumes")?,
            "boundary_compensation" => s.boundary_compensation = flag(v, "boundary_compensation")?,
            "edge_supersampling" => s.edge_supersampling = flag(v, "edge_supersampling")?,
            "volume_shape" => {
                s.volume_shape = text(v, "volume_shape")?.parse().map_err(|e| to_py(py, e))?
            }
            "estimator" => s.estimator = text(v, "estimator")?.parse().map_err(|e| to_py(py, e))?,
            "first_bounce" => {
                s.first_bounce = text(v, "first_bounce")?.parse().map_err(|e| to_py(py, e))?
            }
            "adapter" => {
                s.adapter = if v.is_none() {
                    None
                } else {
                    Some(text(v, "adapter")?)
                }
            }
            "shadow_map_size" => s.shadow_map_size = int(v, "shadow_map_size")?,
            "temporal_frames" => s.temporal_frames = int(v, "temporal_frames")?,
            "progressive" => s.progressive = flag(v, "progressive")?,
            "photon_focus" => s.photon_focus = float(v, "photon_focus")?,
            "caustic_density_bound" => s.caustic_density_bound = flag(v, "caustic_density_bound")?,
            "progressive_alpha" => s.progressive_alpha = float(v, "progressive_alpha")?,
            "vpls_per_light" => s.vpls_per_light = int(v, "vpls_per_light")?,
            "rsm_size" => s.rsm_size = int(v, "rsm_size")?,
            "vpl_shadow_map_size" => s.vpl_shadow_map_size = int(v, "vpl_shadow_map_size")?,
            "bundles" => s.bundles = int(v, "bundles")?,
            "bundle_resolution" => s.bundle_resolution = int(v, "bundle_resolution")?,
            "bundle_memory_mb" => s.bundle_memory_mb = int(v, "bundle_memory_mb")?,
            "bidir_strategy" => {
                s.bidir_strategy = text(v, "bidir_strategy")?
                    .parse()
                    .map_err(|e| to_py(py, e))?
            }
            "roughness_clamping" => s.roughness_clamping = flag(v, "roughness_clamping")?,
            other => {
                return Err(setting_error(
                    py,
                    "settings",
                    format!("unknown setting `{other}`"),
                ))
            }
        }
    }
    s.validate().map_err(|e| to_py(py, e))?;
    Ok(s)
}

/// A frame as a dict of float32 arrays (radiance, albedo, normal, position, caustics:
/// H×W×3, empty when not read back; depth: H×W), `extra` and `stats`.
fn output_dict<'py>(
    py: Python<'py>,
    out: gi_core::RenderOutput,
    method: Method,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let (w, h) = (out.albedo.width as usize, out.albedo.height as usize);
    d.set_item("radiance", image_array(py, out.radiance)?)?;
    d.set_item("albedo", image_array(py, out.albedo)?)?;
    d.set_item("normal", image_array(py, out.normal)?)?;
    d.set_item("position", image_array(py, out.position)?)?;
    d.set_item("caustics", image_array(py, out.caustics)?)?;
    d.set_item("depth", out.depth.into_pyarray(py).reshape([h, w])?)?;
    let extra = PyDict::new(py);
    for (name, img) in out.aovs {
        extra.set_item(name, image_array(py, img)?)?;
    }
    d.set_item("extra", extra)?;
    let stats = PyDict::new(py);
    let s = &out.stats;
    stats.set_item("method", method.name())?;
    stats.set_item("stages", s.stages.clone())?;
    stats.set_item("total_seconds", s.total_seconds)?;
    stats.set_item("samples_per_pixel", s.samples_per_pixel)?;
    stats.set_item("camera_paths", s.camera_paths)?;
    stats.set_item("light_paths", s.light_paths)?;
    stats.set_item("triangles", s.triangles)?;
    stats.set_item("photons_emitted", s.photons_emitted)?;
    stats.set_item("photons_first_bounce", s.photons_first_bounce)?;
    stats.set_item("photons_stored", s.photons_stored)?;
    stats.set_item("caustic_photons", s.caustic_photons)?;
    stats.set_item("volume_quads", s.volume_quads)?;
    stats.set_item("passes", s.passes)?;
    stats.set_item("estimator", s.estimator.clone())?;
    stats.set_item("estimator_reason", s.estimator_reason.clone())?;
    stats.set_item("estimator_memory", s.estimator_memory.clone())?;
    stats.set_item("first_bounce", s.first_bounce.clone())?;
    stats.set_item("first_bounce_reason", s.first_bounce_reason.clone())?;
    stats.set_item("list_entries", s.list_entries)?;
    stats.set_item("trivial_accepts", s.trivial_accepts)?;
    stats.set_item("vpls", s.vpls)?;
    stats.set_item("bundles", s.bundles)?;
    stats.set_item("bundle_fragments", s.bundle_fragments)?;
    stats.set_item("bundle_overflow", s.bundle_overflow)?;
    d.set_item("stats", stats)?;
    Ok(d)
}

/// A persistent renderer (`gi_core::Renderer`): made once, then `render()` per frame with
/// `update()`s between frames.
#[pyclass(module = "gi._gi", name = "Renderer")]
pub struct PyRenderer {
    inner: Renderer,
}

#[pymethods]
impl PyRenderer {
    #[new]
    #[pyo3(signature = (scene, method = "ispm", settings = None))]
    fn new(
        py: Python<'_>,
        scene: &PyScene,
        method: &str,
        settings: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let settings = settings_from(py, method, settings)?;
        let inner = crate::guard::catch("Renderer", || {
            Renderer::new(&scene.inner, &settings).map_err(|e| to_py(py, e))
        })?;
        Ok(PyRenderer { inner })
    }

    /// Renders one frame; `aovs` adds albedo/normal/position/depth, `extras` the method's
    /// own images. Returns the dict of `render()`.
    #[pyo3(signature = (aovs = false, extras = false, seed = None, progress = None))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        aovs: bool,
        extras: bool,
        seed: Option<u64>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let desc = FrameDesc {
            seed,
            images: Images { aovs, extras },
            serial: false,
        };
        let inner = &mut self.inner;
        let out = crate::guard::run(py, "Renderer.render", progress.as_ref(), |reporter| {
            inner.render(&desc, reporter)
        })?;
        output_dict(py, out, self.inner.settings().method)
    }

    /// Applies a scene update given as JSON: `target` is "camera", "light" (key: index),
    /// "object" (key: index or name) or "material" (key: name); see
    /// `Scene::update_from_json` for the fields.
    #[pyo3(signature = (target, key, json))]
    fn update(
        &mut self,
        py: Python<'_>,
        target: &str,
        key: Option<&Bound<'_, PyAny>>,
        json: &str,
    ) -> PyResult<()> {
        let scene = self.inner.scene();
        let bad = |msg: String| {
            to_py(
                py,
                gi_core::Error::Scene {
                    source_name: "scene update".into(),
                    field: target.to_string(),
                    message: msg,
                },
            )
        };
        let index = |key: Option<&Bound<'_, PyAny>>| -> PyResult<usize> {
            key.and_then(|k| k.extract::<usize>().ok())
                .ok_or_else(|| bad("needs an index".into()))
        };
        let target = match target {
            "camera" => UpdateTarget::Camera,
            "light" => UpdateTarget::Light(index(key)?),
            "material" => UpdateTarget::Material(
                key.and_then(|k| k.extract::<String>().ok())
                    .ok_or_else(|| bad("needs a material name".into()))?,
            ),
            "object" => {
                let i = match key.and_then(|k| k.extract::<String>().ok()) {
                    Some(name) => scene
                        .object_index(&name)
                        .ok_or_else(|| bad(format!("no object named `{name}`")))?,
                    None => index(key)?,
                };
                UpdateTarget::Object(i)
            }
            other => return Err(bad(format!("unknown update target `{other}`"))),
        };
        let value: serde_json::Value =
            serde_json::from_str(json).map_err(|e| bad(format!("invalid JSON: {e}")))?;
        let update = scene
            .update_from_json(&target, &value)
            .map_err(|e| to_py(py, e))?;
        let inner = &mut self.inner;
        crate::guard::catch("Renderer.update", || {
            inner.update(&update).map_err(|e| to_py(py, e))
        })
    }

    /// Changes the image size (targets are rebuilt at the next frame).
    fn resize(&mut self, py: Python<'_>, width: u32, height: u32) -> PyResult<()> {
        let inner = &mut self.inner;
        crate::guard::catch("Renderer.resize", || {
            inner.resize(width, height).map_err(|e| to_py(py, e))
        })
    }

    /// Whether each frame is a progressive pass (setting `progressive`).
    #[getter]
    fn progressive(&self) -> bool {
        self.inner.settings().progressive
    }

    /// Progressive mode: passes in the current running mean (0 after a change).
    #[getter]
    fn passes(&self) -> u64 {
        self.inner.passes()
    }

    /// Frames rendered so far.
    #[getter]
    fn frame_index(&self) -> u64 {
        self.inner.frame_index()
    }

    #[getter]
    fn method(&self) -> &'static str {
        self.inner.settings().method.name()
    }

    /// (width, height) of the frames.
    #[getter]
    fn size(&self) -> (u32, u32) {
        let c = &self.inner.scene().camera;
        (c.width, c.height)
    }

    /// Object names (None for unnamed objects), in scene order.
    #[getter]
    fn object_names(&self) -> Vec<Option<String>> {
        self.inner
            .scene()
            .objects
            .iter()
            .map(|o| o.name.clone())
            .collect()
    }

    /// The current camera, light `i` or material as scene-format JSON.
    #[pyo3(signature = (target, key = None))]
    fn describe(
        &self,
        py: Python<'_>,
        target: &str,
        key: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<String> {
        let scene = self.inner.scene();
        let value = match target {
            "camera" => serde_json::to_string(&scene.camera_desc()),
            "light" => {
                let i: usize = key.map(|k| k.extract()).transpose()?.unwrap_or(0);
                match scene.light_desc(i) {
                    Some(l) => serde_json::to_string(&l),
                    None => return Err(setting_error(py, "light", format!("no light {i}"))),
                }
            }
            "material" => {
                let name: String = key.map(|k| k.extract()).transpose()?.unwrap_or_default();
                match scene.material_desc(&name) {
                    Some(m) => serde_json::to_string(&m),
                    None => {
                        return Err(setting_error(
                            py,
                            "material",
                            format!("no material `{name}`"),
                        ))
                    }
                }
            }
            other => {
                return Err(setting_error(
                    py,
                    "target",
                    format!("unknown target `{other}`"),
                ))
            }
        };
        value.map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))
    }
}

/// GPU objects created and uploads made on this thread so far (the device layer's
/// counters): {"buffers", "textures", "bind_groups", "pipelines", "uploads": [(label, bytes)]}.
#[pyfunction]
pub fn gpu_counters(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let c = gi_core::gpu::alloc::counters();
    let d = PyDict::new(py);
    d.set_item("buffers", c.buffers)?;
    d.set_item("textures", c.textures)?;
    d.set_item("bind_groups", c.bind_groups)?;
    d.set_item("pipelines", c.pipelines)?;
    d.set_item("uploads", c.uploads)?;
    Ok(d)
}

/// Names of the available methods.
#[pyfunction]
pub fn methods() -> Vec<&'static str> {
    Method::ALL.iter().map(|m| m.name()).collect()
}

/// A description of the GPU adapter gi would use (name, backend, driver, limits).
/// `adapter` is "cpu", "gpu" or part of an adapter name; `None` follows `GI_ADAPTER`.
#[pyfunction]
#[pyo3(signature = (adapter = None))]
pub fn adapter_report(py: Python<'_>, adapter: Option<String>) -> PyResult<String> {
    crate::guard::run(py, "adapter_report", None, |_| {
        gi_core::gpu::adapter_report(adapter.as_deref())
    })
}

/// Footprint radii of photons traced with photon differentials, per path kind ("direct",
/// "caustic", "diffuse"): {kind: (count, [radius at each percentile])}, radii in metres.
#[pyfunction]
#[pyo3(signature = (scene, photons = 200_000, seed = 0, smoothing = 1.0, percentiles = vec![1.0, 5.0, 25.0, 50.0, 75.0, 95.0, 99.0]))]
pub fn footprint_radii(
    py: Python<'_>,
    scene: &PyScene,
    photons: u64,
    seed: u64,
    smoothing: f32,
    percentiles: Vec<f64>,
) -> PyResult<std::collections::BTreeMap<&'static str, (usize, Vec<f32>)>> {
    use gi_core::photon::{gather::radius_percentiles, PathKind};
    let settings = Settings {
        method: Method::Gather,
        photons,
        seed,
        smoothing,
        ..Default::default()
    };
    settings.validate().map_err(|e| to_py(py, e))?;
    if percentiles.iter().any(|q| !(0.0..=100.0).contains(q)) {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "percentiles must be in [0, 100]",
        ));
    }
    let rows = crate::guard::run(py, "footprint_radii", None, |progress| {
        let bvh = gi_core::trace::SceneBvh::try_build(&scene.inner)?;
        let mut ts = gi_core::frame::gather::trace_settings(&scene.inner, &settings);
        ts.store_direct = true;
        let control = gi_core::photon::trace::Checked::new(progress, "photon trace");
        let set = gi_core::photon::emit_and_trace_checked(
            &scene.inner,
            &bvh,
            photons,
            &ts,
            seed,
            &control,
        )?;
        Ok(radius_percentiles(&set, &percentiles))
    })?;
    Ok(rows
        .into_iter()
        .map(|(kind, n, r)| {
            let name = match kind {
                PathKind::Direct => "direct",
                PathKind::Caustic => "caustic",
                PathKind::Diffuse => "diffuse",
            };
            (name, (n, r))
        })
        .collect())
}
