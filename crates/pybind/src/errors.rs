//! Python exception types and the mapping from `gi_core::Error`.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyMemoryError, PyUserWarning};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyType};

create_exception!(
    _gi,
    GiError,
    PyException,
    "Base class of every error raised by gi."
);
create_exception!(
    _gi,
    SceneError,
    GiError,
    "A scene description is malformed; `.file` and `.field` say where."
);
create_exception!(
    _gi,
    SettingError,
    GiError,
    "A render setting is out of range; `.setting` names it."
);
create_exception!(
    _gi,
    GpuError,
    GiError,
    "No usable GPU adapter (install Mesa lavapipe), or a GPU operation failed."
);
create_exception!(
    _gi,
    InternalError,
    GiError,
    "A bug in gi: its core failed an internal check (a broken invariant or a Rust panic). \
     Please report it with the message and the scene and settings that caused it."
);
create_exception!(
    _gi,
    RenderCancelled,
    GiError,
    "The render was cancelled (a progress callback that returned False, or Ctrl-C)."
);

create_exception!(
    _gi,
    RenderWarning,
    PyUserWarning,
    "A render does not compute what it was asked for: an option the method ignores, or light \
     transport it leaves out."
);

/// `OutOfMemoryError(GiError, MemoryError)`, made when the module is registered (a class
/// with two bases, which `create_exception!` cannot make).
static OUT_OF_MEMORY: PyOnceLock<Py<PyType>> = PyOnceLock::new();

fn out_of_memory_type(py: Python<'_>) -> PyResult<&Bound<'_, PyType>> {
    OUT_OF_MEMORY
        .get_or_try_init(py, || {
            let ns = PyDict::new(py);
            ns.set_item("__module__", "gi._gi")?;
            ns.set_item(
                "__doc__",
                "A render or scene needs more memory than the process can get (estimated \
                 before allocating). Also a `MemoryError`.",
            )?;
            let bases = (py.get_type::<GiError>(), py.get_type::<PyMemoryError>());
            let ty = py
                .get_type::<PyType>()
                .call1(("OutOfMemoryError", bases, ns))?;
            Ok::<_, PyErr>(ty.cast_into::<PyType>()?.unbind())
        })
        .map(|t| t.bind(py))
}

/// An `InternalError` for a panic caught at the binding layer, `what` naming the call.
pub fn internal(what: &str, payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    InternalError::new_err(format!(
        "internal error in {what}: {msg} (this is a bug in gi; please report it with the \
         scene and settings)"
    ))
}

/// Converts a core error into the matching Python exception, with structured attributes.
pub fn to_py(py: Python<'_>, e: gi_core::Error) -> PyErr {
    let msg = e.to_string();
    match e {
        gi_core::Error::Scene {
            source_name,
            field,
            message,
        } => {
            let err = SceneError::new_err(msg);
            let v = err.value(py);
            let _ = v.setattr("file", source_name);
            let _ = v.setattr("field", field);
            let _ = v.setattr("reason", message);
            err
        }
        gi_core::Error::Setting { name, .. } => {
            let err = SettingError::new_err(msg);
            let _ = err.value(py).setattr("setting", name);
            err
        }
        gi_core::Error::Gpu(_) => GpuError::new_err(msg),
        gi_core::Error::Cancelled => RenderCancelled::new_err(msg),
        gi_core::Error::Internal(_) => InternalError::new_err(msg),
        gi_core::Error::OutOfMemory { needed, .. } => match out_of_memory_type(py) {
            Ok(ty) => {
                let err = PyErr::from_type(ty.clone(), msg);
                let _ = err.value(py).setattr("needed", needed);
                err
            }
            Err(e) => e,
        },
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GiError", py.get_type::<GiError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("SettingError", py.get_type::<SettingError>())?;
    m.add("GpuError", py.get_type::<GpuError>())?;
    m.add("RenderCancelled", py.get_type::<RenderCancelled>())?;
    m.add("InternalError", py.get_type::<InternalError>())?;
    m.add("RenderWarning", py.get_type::<RenderWarning>())?;
    m.add("OutOfMemoryError", out_of_memory_type(py)?)?;
    Ok(())
}
