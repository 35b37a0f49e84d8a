//! `render()`: runs a method with the GIL released and returns numpy arrays.

use crate::errors::to_py;
use crate::scene::PyScene;
use gi_core::frame::readout::{Display, Precision, Readout, Tonemap};
use gi_core::frame::{FrameDesc, Images, Renderer};
use gi_core::scene::update::UpdateTarget;
use gi_core::{Image, Method, MethodOptions, RenderOptions};
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

fn image_array<'py>(py: Python<'py>, img: Image) -> PyResult<Bound<'py, PyAny>> {
    let (w, h) = (img.width as usize, img.height as usize);
    // The pixels' own allocation, reinterpreted (Vec3 is three f32s): no copy.
    let flat: Vec<f32> = bytemuck::allocation::try_cast_vec(img.pixels)
        .unwrap_or_else(|(_, pixels)| bytemuck::cast_slice(&pixels).to_vec());
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

/// `repr(v)`, for messages.
fn repr(v: &Bound<'_, PyAny>) -> String {
    v.repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// An integer argument of any Python size as `T`; else what the message about it says:
/// "must be {allowed}, got 1099511627776" for an integer outside `T`, "must be an integer
/// {allowed}, got '4'" for anything else (as the option table's messages read).
fn integer<T: TryFrom<i128>>(v: &Bound<'_, PyAny>) -> Result<T, impl Fn(&str) -> String> {
    let int = if v.is_instance_of::<pyo3::types::PyBool>() {
        None
    } else {
        v.extract::<i128>().ok()
    };
    let given = repr(v);
    match int.map(T::try_from) {
        Some(Ok(t)) => Ok(t),
        _ => Err(move |allowed: &str| {
            let kind = if int.is_some() { "" } else { "an integer " };
            format!("must be {kind}{allowed}, got {given}")
        }),
    }
}

/// A frame as a dict of float32 arrays (radiance, albedo, normal, position, caustics:
/// H×W×3, empty when not read back; depth: H×W), `radiance_half` (H×W×3 uint16: the bits
/// of half floats) and `display` (H×W×3 uint8) when asked for (else absent), `extra` and
/// `stats`. `size`: the frame's width and height.
fn output_dict<'py>(
    py: Python<'py>,
    out: gi_core::RenderOutput,
    size: (usize, usize),
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let (w, h) = (out.albedo.width as usize, out.albedo.height as usize);
    d.set_item("radiance", image_array(py, out.radiance)?)?;
    let (fw, fh) = size;
    if let Some(half) = out.radiance_half {
        let bits: Vec<u16> = half.into_iter().map(|v| v.to_bits()).collect();
        d.set_item("radiance_half", bits.into_pyarray(py).reshape([fh, fw, 3])?)?;
    }
    if let Some(display) = out.display {
        d.set_item("display", display.into_pyarray(py).reshape([fh, fw, 3])?)?;
    }
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
    let stats = crate::stats::PyStats(out.stats);
    d.set_item("stats", stats)?;
    Ok(d)
}

/// The readout of `Renderer.render`'s `radiance`, `tonemap` and `exposure`.
fn readout(
    py: Python<'_>,
    radiance: Option<&str>,
    tonemap: Option<&str>,
    exposure: f32,
) -> PyResult<Readout> {
    let radiance = match radiance {
        None => None,
        Some("float32") => Some(Precision::Float32),
        Some("float16") => Some(Precision::Float16),
        Some(other) => {
            let message = format!("must be 'float32', 'float16' or None, got {other:?}");
            return Err(setting_error(py, "radiance", message));
        }
    };
    let display = match tonemap {
        None => None,
        Some(name) => {
            let tonemap = Tonemap::parse(name).ok_or_else(|| {
                let message =
                    format!("the core encodes 'clip' and 'agx' (or 'filmic'), got {name:?}");
                setting_error(py, "tonemap", message)
            })?;
            if !exposure.is_finite() {
                return Err(setting_error(py, "exposure", "must be finite"));
            }
            Some(Display { tonemap, exposure })
        }
    };
    Ok(Readout { radiance, display })
}

/// A persistent renderer (`gi_core::Renderer`): made once, then `render()` per frame with
/// `update()`s between frames.
#[pyclass(module = "gi._gi", name = "Renderer")]
pub struct PyRenderer {
    inner: Renderer,
    /// Options given that don't apply to the method (ignored).
    warnings: Vec<String>,
}

#[pymethods]
impl PyRenderer {
    #[new]
    #[pyo3(signature = (scene, method = "ispm", options = None))]
    fn new(
        py: Python<'_>,
        scene: &PyScene,
        method: &str,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let (options, warnings) = crate::options::from_keywords(py, method, options)?;
        let inner = crate::guard::catch("Renderer", || {
            Renderer::new(&scene.inner, &options).map_err(|e| to_py(py, e))
        })?;
        let mut warnings = warnings;
        warnings.extend(inner.warnings().iter().cloned());
        Ok(PyRenderer { inner, warnings })
    }

    /// The options given that don't apply to the method (ignored) and what the method leaves
    /// out of the scene's light, one message each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Every option of the renderer's method with its value (given or the table's default).
    #[getter]
    fn options<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, value) in self.inner.options().values() {
            d.set_item(name, crate::options::to_object(py, &value)?)?;
        }
        Ok(d)
    }

    /// Renders one frame; `aovs` adds albedo/normal/position/depth, `extras` the method's
    /// own images; `radiance` is "float32", "float16" or None (not handed back), `tonemap`
    /// ("clip", "agx"/"filmic") asks for the 8-bit display image at `exposure`. Returns the
    /// dict of `render()`.
    #[pyo3(signature = (aovs = false, extras = false, seed = None, progress = None,
        radiance = Some("float32"), tonemap = None, exposure = 0.0))]
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        aovs: bool,
        extras: bool,
        seed: Option<&Bound<'py, PyAny>>,
        progress: Option<Py<PyAny>>,
        radiance: Option<&str>,
        tonemap: Option<&str>,
        exposure: f32,
    ) -> PyResult<Bound<'py, PyDict>> {
        let readout = readout(py, radiance, tonemap, exposure)?;
        let seed = match seed {
            Some(v) if !v.is_none() => Some(integer::<u64>(v).map_err(|message| {
                setting_error(py, "seed", message(&format!("in 0..={}", u64::MAX)))
            })?),
            _ => None,
        };
        let desc = FrameDesc {
            seed,
            images: Images { aovs, extras },
            serial: false,
            readout,
        };
        let camera = &self.inner.scene().camera;
        let size = (camera.width as usize, camera.height as usize);
        let inner = &mut self.inner;
        let out = crate::guard::run(py, "Renderer.render", progress.as_ref(), |reporter| {
            inner.render(&desc, reporter)
        })?;
        output_dict(py, out, size)
    }

    /// Applies a scene update given as Python values (a dict of the fields that change, in
    /// the scene format): `target` is "camera", "light" (key: index), "object" (key: index
    /// or name) or "material" (key: name); see `Scene::update_from_json` for the fields.
    #[pyo3(signature = (target, key, fields))]
    fn update(
        &mut self,
        py: Python<'_>,
        target: &str,
        key: Option<&Bound<'_, PyAny>>,
        fields: &Bound<'_, PyAny>,
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
        let value = crate::values::to_value(fields).map_err(bad)?;
        let update = scene
            .update_from_json(&target, &value)
            .map_err(|e| to_py(py, e))?;
        let inner = &mut self.inner;
        crate::guard::catch("Renderer.update", || {
            inner.update(&update).map_err(|e| to_py(py, e))
        })
    }

    /// Gives the scene an environment (JSON section, `None`: none; `images` holds its
    /// `file`) and lights (a JSON list), added to its light (`add`) or replacing it, before
    /// the next frame.
    #[pyo3(signature = (environment = None, images = None, lights = None, add = true))]
    fn set_lighting(
        &mut self,
        py: Python<'_>,
        environment: Option<&str>,
        images: Option<&Bound<'_, PyDict>>,
        lights: Option<&str>,
        add: bool,
    ) -> PyResult<()> {
        let lighting =
            crate::scene::lighting_from_py(py, environment, images, lights, add, "scene update")?;
        let inner = &mut self.inner;
        crate::guard::catch("Renderer.set_lighting", || {
            inner.set_lighting(&lighting).map_err(|e| to_py(py, e))
        })
    }

    /// Changes the image size (targets are rebuilt at the next frame).
    fn resize(
        &mut self,
        py: Python<'_>,
        width: &Bound<'_, PyAny>,
        height: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        // A side that is not an integer of u32 is passed as 0, which the core refuses with
        // the range it allows; the message then says what was given.
        let (w, bad_w) = match integer::<u32>(width) {
            Ok(w) => (w, None),
            Err(m) => (0, Some(m)),
        };
        let (h, bad_h) = match integer::<u32>(height) {
            Ok(h) => (h, None),
            Err(m) => (0, Some(m)),
        };
        let inner = &mut self.inner;
        let resized = crate::guard::catch("Renderer.resize", || Ok(inner.resize(w, h)))?;
        match resized {
            Ok(()) => Ok(()),
            Err(gi_core::Error::Setting { name, message }) => {
                let allowed = message.strip_prefix("must be ").unwrap_or(&message);
                let message = match if name == "width" { &bad_w } else { &bad_h } {
                    Some(given) => given(allowed),
                    None => message.clone(),
                };
                Err(setting_error(py, name, message))
            }
            Err(e) => Err(to_py(py, e)),
        }
    }

    /// Whether each frame is a progressive pass (option `progressive`).
    #[getter]
    fn progressive(&self) -> bool {
        self.inner.options().common.progressive
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
        self.inner.method().name()
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

    /// The current camera, light `i` or material as a scene-format dict; object `i` (index
    /// or name) as `{"name", "matrix": 4×4 rows, "triangles": [start, end]}`.
    #[pyo3(signature = (target, key = None))]
    fn describe<'py>(
        &self,
        py: Python<'py>,
        target: &str,
        key: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
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
            "object" => {
                let i = match key.map(|k| k.extract::<String>()) {
                    Some(Ok(name)) => scene.object_index(&name),
                    _ => key.map(|k| k.extract::<usize>()).transpose()?,
                };
                let (Some(object), Some(described)) = (
                    i.and_then(|i| scene.objects.get(i)),
                    i.and_then(|i| scene.object_desc(i)),
                ) else {
                    let n = scene.objects.len();
                    return Err(setting_error(
                        py,
                        "object",
                        format!("no such object: give its name or index (0..{n})"),
                    ));
                };
                // The transform in the scene format (none for a sheared matrix) and as the
                // rows that `update("object", ..)` takes as `matrix`, and the object's range
                // of the scene's triangles (`Scene.mesh_arrays`).
                let rows = object.transform.transpose().to_cols_array_2d();
                // Through text, so that its f32 values read as written (0.35, not
                // 0.3499999940395355 as a JSON value made from the f32 would).
                let transform: Option<serde_json::Value> = match described {
                    Ok(desc) => serde_json::to_string(&desc)
                        .and_then(|text| serde_json::from_str(&text))
                        .ok(),
                    Err(_) => None,
                };
                serde_json::to_string(&serde_json::json!({
                    "name": object.name,
                    "transform": transform,
                    "matrix": rows,
                    "triangles": [object.triangles.start, object.triangles.end],
                }))
            }
            other => {
                return Err(setting_error(
                    py,
                    "target",
                    format!("unknown target `{other}`"),
                ))
            }
        };
        // Through text, so that the f32 values read as written (0.35, not
        // 0.3499999940395355 as a JSON value made from the f32 would).
        let text = value.map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        crate::values::to_py(py, &value)
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
    use gi_core::photon::{footprint_map::radius_percentiles, PathKind};
    let mut options = gi_core::frame::options::GatherOptions {
        photons,
        ..Default::default()
    };
    options.refine.smoothing = smoothing;
    let options = RenderOptions::of(MethodOptions::Gather(options)).with_seed(seed);
    options.validate().map_err(|e| to_py(py, e))?;
    let MethodOptions::Gather(gather) = &options.method else {
        return Err(setting_error(py, "method", "not gather"));
    };
    if percentiles.iter().any(|q| !(0.0..=100.0).contains(q)) {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "percentiles must be in [0, 100]",
        ));
    }
    let rows = crate::guard::run(py, "footprint_radii", None, |progress| {
        let bvh = gi_core::trace::SceneBvh::try_build(&scene.inner)?;
        let mut ts = gi_core::frame::gather::trace_settings(
            &scene.inner,
            gather.photons,
            gather.max_depth,
            gather.refine.smoothing,
            &gather.kernel,
            1.0,
        );
        ts.store_direct = true;
        let control = gi_core::photon::trace::Checked::new(progress, "photon trace");
        let mut set = gi_core::photon::emit_and_trace_checked(
            &scene.inner,
            &bvh,
            photons,
            &ts,
            seed,
            &control,
        )?;
        // The diffuse footprints sized as method `gather` sizes them.
        if let Some(ds) = &ts.differentials {
            use gi_core::photon::footprint_scale::{photons_per_estimate, scale_to_overlap};
            let target = photons_per_estimate(gather.final_gather, smoothing);
            scale_to_overlap(&mut set, target, ds.r_max);
        }
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
