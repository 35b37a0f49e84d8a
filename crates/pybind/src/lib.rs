//! Python bindings of gi (`gi._gi`): thin wrappers over `gi_core`; the Python package `gi`
//! adds scene-file loading, image output and the CLI.

mod errors;
mod guard;
mod options;
mod render;
mod scene;
mod stats;
mod values;

use pyo3::prelude::*;

#[pymodule]
fn _gi(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<scene::PyScene>()?;
    m.add_function(wrap_pyfunction!(scene::builtin_scenes, m)?)?;
    m.add_function(wrap_pyfunction!(scene::builtin_json, m)?)?;
    m.add_class::<render::PyRenderer>()?;
    m.add_function(wrap_pyfunction!(render::gpu_counters, m)?)?;
    m.add_function(wrap_pyfunction!(render::methods, m)?)?;
    m.add_function(wrap_pyfunction!(options::options, m)?)?;
    m.add_class::<stats::PyStats>()?;
    m.add_function(wrap_pyfunction!(render::adapter_report, m)?)?;
    m.add_function(wrap_pyfunction!(render::footprint_radii, m)?)?;
    m.add_function(wrap_pyfunction!(guard::panic_for_tests, m)?)?;
    m.add_function(wrap_pyfunction!(guard::internal_error_for_tests, m)?)?;
    m.add_function(wrap_pyfunction!(guard::wait_gpu_idle, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
