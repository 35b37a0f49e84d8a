//! `gi.RenderStats`: the core's `RenderStats` of a frame, read-only, as a Python class.

use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// Timings (seconds) and counts of one render; the fields are the core's
/// (`gi_core::RenderStats`).
#[pyclass(module = "gi._gi", name = "RenderStats", frozen)]
#[derive(Clone)]
pub struct PyStats(pub gi_core::RenderStats);

/// The class's methods: a getter per field of `gi_core::RenderStats`, and the rest.
macro_rules! stats_class {
    ($($field:ident: $ty:ty),* $(,)?) => {
        #[pymethods]
        impl PyStats {
            $(
                #[getter]
                fn $field(&self) -> $ty {
                    self.0.$field.clone()
                }
            )*

            /// These statistics with one more stage of `seconds` (added to the total).
            fn with_stage(&self, name: String, seconds: f64) -> PyStats {
                let mut s = self.0.clone();
                s.stages.push((name, seconds));
                s.total_seconds += seconds;
                PyStats(s)
            }

            fn __repr__(&self) -> String {
                let stages: Vec<String> = self
                    .0
                    .stages
                    .iter()
                    .map(|(n, t)| format!("{n} {t:.3}s"))
                    .collect();
                format!(
                    "<RenderStats {} {:.3}s, {} spp, {} passes: {}>",
                    self.0.method,
                    self.0.total_seconds,
                    self.0.samples_per_pixel,
                    self.0.passes,
                    stages.join(", ")
                )
            }

            fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
                other
                    .cast::<PyStats>()
                    .is_ok_and(|o| o.get().0 == self.0)
            }

            /// Pickling (Ray tasks return results): the fields as JSON.
            fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
                let py = slf.py();
                let json = serde_json::to_string(&slf.get().0)
                    .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
                let restore = py.get_type::<PyStats>().getattr("_from_json")?;
                PyTuple::new(py, [restore, PyTuple::new(py, [json])?.into_any()])
            }

            #[staticmethod]
            fn _from_json(json: &str) -> PyResult<PyStats> {
                serde_json::from_str(json)
                    .map(PyStats)
                    .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
            }
        }
    };
}

stats_class!(
    method: String,
    stages: Vec<(String, f64)>,
    total_seconds: f64,
    samples_per_pixel: u32,
    camera_paths: u64,
    light_paths: u64,
    triangles: u64,
    photons_emitted: u64,
    photons_first_bounce: u64,
    photons_stored: u64,
    caustic_photons: u64,
    volume_quads: u64,
    passes: u64,
    estimator: String,
    estimator_reason: String,
    first_bounce: String,
    first_bounce_reason: String,
    photon_trace: String,
    photon_trace_reason: String,
    photon_records: String,
    estimator_memory: Vec<(String, u64)>,
    list_entries: u64,
    trivial_accepts: u64,
    vpls: u64,
    bundles: u64,
    bundle_fragments: u64,
    bundle_overflow: u64,
);
