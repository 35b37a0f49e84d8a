//! Python values ⇄ `serde_json::Value`: scene updates, descriptions and animation poses
//! cross the binding as Python objects (dicts, lists, numbers, strings, `None`), not as JSON
//! text that each side writes and parses again.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};

/// `obj` as a JSON value: dicts with string keys, lists and tuples, strings, booleans,
/// integers, finite floats and `None`; else a message naming what is not one of those.
pub fn to_value(obj: &Bound<'_, PyAny>) -> Result<Value, String> {
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if let Ok(i) = obj.cast::<PyInt>() {
        if let Ok(v) = i.extract::<u64>() {
            return Ok(Value::Number(v.into()));
        }
        if let Ok(v) = i.extract::<i64>() {
            return Ok(Value::Number(v.into()));
        }
        // Beyond 64 bits: the float JSON text would have parsed to.
        let v: f64 = i.extract().map_err(|e: PyErr| e.to_string())?;
        return Number::from_f64(v)
            .map(Value::Number)
            .ok_or_else(|| format!("integer out of range: {obj}"));
    }
    if let Ok(f) = obj.cast::<PyFloat>() {
        let v = f.value();
        return Number::from_f64(v)
            .map(Value::Number)
            .ok_or_else(|| format!("must be a finite number, got {v}"));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(
            s.to_str().map_err(|e| e.to_string())?.to_owned(),
        ));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = Map::new();
        for (k, v) in d.iter() {
            let key = k
                .cast::<PyString>()
                .map_err(|_| format!("field names are strings, got {k}"))?;
            map.insert(
                key.to_str().map_err(|e| e.to_string())?.to_owned(),
                to_value(&v)?,
            );
        }
        return Ok(Value::Object(map));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let items = obj.try_iter().map_err(|e| e.to_string())?;
        return items
            .map(|v| to_value(&v.map_err(|e| e.to_string())?))
            .collect::<Result<_, _>>()
            .map(Value::Array);
    }
    Err(format!(
        "expected a number, string, list or dict, got {}",
        obj.repr().map(|r| r.to_string()).unwrap_or_default()
    ))
}

/// `value` as Python objects: objects as dicts, arrays as lists, numbers as `int` or
/// `float` (the `float` a JSON parser gives the number's text).
pub fn to_py<'py>(py: Python<'py>, value: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => {
            if let Some(v) = n.as_u64() {
                v.into_pyobject(py)?.into_any()
            } else if let Some(v) = n.as_i64() {
                v.into_pyobject(py)?.into_any()
            } else if let Some(v) = n.as_f64() {
                PyFloat::new(py, v).into_any()
            } else {
                return Err(PyTypeError::new_err(format!("unrepresentable number {n}")));
            }
        }
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(to_py(py, item)?)?;
            }
            list.into_any()
        }
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, v) in map {
                dict.set_item(k, to_py(py, v)?)?;
            }
            dict.into_any()
        }
    })
}
