//! `render()`: runs a method with the GIL released and returns numpy arrays.

use crate::errors::to_py;
use crate::scene::PyScene;
use gi_core::{Image, Method, Settings};
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

fn image_array<'py>(py: Python<'py>, img: Image) -> PyResult<Bound<'py, PyAny>> {
    let (w, h) = (img.width as usize, img.height as usize);
    let flat: Vec<f32> = bytemuck::cast_slice(&img.pixels).to_vec();
    Ok(flat.into_pyarray(py).reshape([h, w, 3])?.into_any())
}

/// Renders `scene`; returns a dict of float32 arrays (radiance, albedo, normal, position,
/// caustics: H×W×3; depth: H×W) and `stats`.
#[pyfunction]
#[pyo3(signature = (scene, method = "path", spp = 64, width = None, height = None, seed = 0, max_depth = 64, light_paths = None, photons = 200_000, k = 100, max_radius = None, kernel = "cone", smoothing = 1.0, leaf_size = None, kernel_scale = 1.0, subsample = 2, footprint_volumes = false, boundary_compensation = true, volume_shape = "auto", adapter = None, shadow_map_size = 1024, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    scene: &PyScene,
    method: &str,
    spp: u32,
    width: Option<u32>,
    height: Option<u32>,
    seed: u64,
    max_depth: u32,
    light_paths: Option<u64>,
    photons: u64,
    k: u32,
    max_radius: Option<f32>,
    kernel: &str,
    smoothing: f32,
    leaf_size: Option<u32>,
    kernel_scale: f32,
    subsample: u32,
    footprint_volumes: bool,
    boundary_compensation: bool,
    volume_shape: &str,
    adapter: Option<String>,
    shadow_map_size: u32,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let method: Method = method.parse().map_err(|e| to_py(py, e))?;
    let kernel: gi_core::render::Kernel = kernel.parse().map_err(|e| to_py(py, e))?;
    let volume_shape: gi_core::render::VolumeShape =
        volume_shape.parse().map_err(|e| to_py(py, e))?;
    let settings = Settings {
        method,
        spp,
        width,
        height,
        seed,
        max_depth,
        light_paths,
        photons,
        k,
        max_radius,
        kernel,
        smoothing,
        leaf_size,
        kernel_scale,
        subsample,
        footprint_volumes,
        boundary_compensation,
        volume_shape,
        adapter,
        shadow_map_size,
    };
    let out = crate::guard::run(py, "render", progress.as_ref(), |reporter| {
        gi_core::render(&scene.inner, &settings, reporter)
    })?;
    let d = PyDict::new(py);
    let (w, h) = (out.radiance.width as usize, out.radiance.height as usize);
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
    stats.set_item("volume_quads", s.volume_quads)?;
    d.set_item("stats", stats)?;
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
        let mut ts = gi_core::render::gather_trace_settings(&scene.inner, &settings);
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
