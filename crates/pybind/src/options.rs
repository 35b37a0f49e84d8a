//! Render options from Python keywords, and the option table for the Python layer: both
//! from `gi_core::frame::options::OPTIONS`, so no option is named here.

use crate::errors::to_py;
use gi_core::frame::options::{describe_kind, spec, Kind, Method, Value, OPTIONS};
use gi_core::RenderOptions;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyList, PyString};

/// A setting error naming `name`.
fn setting_error(py: Python<'_>, name: &str, message: String) -> PyErr {
    let name = OPTIONS
        .iter()
        .find(|s| s.name == name)
        .map_or("settings", |s| s.name);
    to_py(py, gi_core::Error::Setting { name, message })
}

/// A Python value as an option value: None, bool, int (any integer type), float or str.
fn value(method: Method, name: &str, v: &Bound<'_, PyAny>) -> PyResult<Value> {
    if v.is_none() {
        return Ok(Value::None);
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Value::Str(v.extract()?));
    }
    if !v.is_instance_of::<PyFloat>() {
        if let Ok(i) = v.extract::<i128>() {
            return Ok(Value::Int(i));
        }
    }
    if let Ok(b) = v.extract::<bool>() {
        if !v.hasattr("__index__")? {
            return Ok(Value::Bool(b));
        }
    }
    if let Ok(x) = v.extract::<f64>() {
        return Ok(Value::Float(x));
    }
    let kind = spec(name, method)
        .or_else(|| OPTIONS.iter().find(|s| s.name == name))
        .map(|s| describe_kind(&s.kind));
    match kind {
        Some(kind) => Err(setting_error(
            v.py(),
            name,
            format!("must be {kind}, got {}", v.repr()?),
        )),
        // An unknown name: the core's error lists the options.
        None => Ok(Value::None),
    }
}

/// The options of `method` from the keywords in `kw` (the table's names), checked by the
/// core, and the warnings for keywords that don't apply to the method.
pub fn from_keywords(
    py: Python<'_>,
    method: &str,
    kw: Option<&Bound<'_, PyDict>>,
) -> PyResult<(RenderOptions, Vec<String>)> {
    let method: Method = method.parse().map_err(|e| to_py(py, e))?;
    let mut given = Vec::new();
    for (k, v) in kw.into_iter().flat_map(|d| d.iter()) {
        let name: String = k.extract().map_err(|_| {
            setting_error(py, "settings", format!("option names are strings, got {k}"))
        })?;
        let v = value(method, &name, &v)?;
        given.push((name, v));
    }
    RenderOptions::new(method, &given).map_err(|e| to_py(py, e))
}

/// An option value as a Python object.
pub fn to_object<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::None => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Int(i) => i.into_pyobject(py)?.into_any(),
        Value::Float(x) => x.into_pyobject(py)?.into_any(),
        Value::Str(s) => s.into_pyobject(py)?.into_any(),
    })
}

/// The option table: one dict per row with `name`, `kind` ("bool", "int", "float",
/// "choice", "text"), `optional`, `default`, `methods`, `doc`, `range` (a description of
/// the values taken) and, by kind, `min`/`max` or `choices`.
#[pyfunction]
pub fn options(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let rows = PyList::empty(py);
    for s in OPTIONS {
        let d = PyDict::new(py);
        d.set_item("name", s.name)?;
        let kind = match s.kind {
            Kind::Bool => "bool",
            Kind::Int { min, max } => {
                d.set_item("min", min)?;
                d.set_item("max", max)?;
                "int"
            }
            Kind::Float { min, max, .. } => {
                d.set_item("min", min)?;
                d.set_item("max", max)?;
                "float"
            }
            Kind::Choice(choices) => {
                d.set_item("choices", choices())?;
                "choice"
            }
            Kind::Text => "text",
        };
        d.set_item("kind", kind)?;
        d.set_item("range", describe_kind(&s.kind))?;
        d.set_item("optional", s.optional)?;
        d.set_item("default", to_object(py, &s.default.value())?)?;
        let methods: Vec<&str> = s.methods.iter().map(|m| m.name()).collect();
        d.set_item("methods", methods)?;
        d.set_item("doc", s.doc)?;
        rows.append(d)?;
    }
    Ok(rows)
}
