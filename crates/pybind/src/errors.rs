//! Python exception types and the mapping from `gi_core::Error`.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

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
    RenderCancelled,
    GiError,
    "The render was cancelled (progress callback or Ctrl-C)."
);

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
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GiError", py.get_type::<GiError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("SettingError", py.get_type::<SettingError>())?;
    m.add("GpuError", py.get_type::<GpuError>())?;
    m.add("RenderCancelled", py.get_type::<RenderCancelled>())?;
    Ok(())
}
