//! Option values: what callers give, and the checked values of one method's options.

use super::table::{check, spec, OptionSpec, OPTIONS};
use super::{
    BidirStrategy, Estimator, FirstBounce, Kernel, Method, PhotonTrace, SpecularSampling,
    VolumeShape,
};
use crate::error::{Error, Named, Result};
use std::cell::RefCell;

/// An option's value as given by a caller.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// "Automatic" for the options that allow it (`None` in Python).
    None,
    Bool(bool),
    Int(i128),
    Float(f64),
    Str(String),
}

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::None => write!(f, "None"),
            Value::Bool(b) => write!(f, "{}", if *b { "True" } else { "False" }),
            Value::Int(i) => write!(f, "{i}"),
            Value::Float(x) => write!(f, "{x}"),
            Value::Str(s) => write!(f, "{s:?}"),
        }
    }
}

macro_rules! value_from {
    ($($t:ty => $v:ident as $c:ty),* $(,)?) => {$(
        impl From<$t> for Value {
            fn from(v: $t) -> Value {
                Value::$v(v as $c)
            }
        }
    )*};
}
value_from!(
    i32 => Int as i128, u32 => Int as i128, i64 => Int as i128, u64 => Int as i128,
    usize => Int as i128, f32 => Float as f64, f64 => Float as f64,
);

macro_rules! value_from_named {
    ($($t:ty),* $(,)?) => {$(
        impl From<$t> for Value {
            fn from(v: $t) -> Value {
                Value::Str(v.name().to_string())
            }
        }
    )*};
}
value_from_named!(
    BidirStrategy,
    Kernel,
    VolumeShape,
    Estimator,
    FirstBounce,
    PhotonTrace,
    SpecularSampling
);

impl From<bool> for Value {
    fn from(v: bool) -> Value {
        Value::Bool(v)
    }
}

impl From<&str> for Value {
    fn from(v: &str) -> Value {
        Value::Str(v.to_string())
    }
}

impl<T: Into<Value>> From<Option<T>> for Value {
    fn from(v: Option<T>) -> Value {
        v.map_or(Value::None, Into::into)
    }
}

/// The checked values of every option a method sees, the defaults filled in. Reading an
/// option records it, so that a test can tell that each method reads exactly its options.
#[derive(Debug)]
pub struct Values {
    method: Method,
    values: Vec<(&'static str, Value)>,
    read: RefCell<Vec<&'static str>>,
}

impl Values {
    /// The defaults of `method`'s options.
    pub fn defaults(method: Method) -> Values {
        Values {
            method,
            values: OPTIONS
                .iter()
                .filter(|s| s.methods.contains(&method))
                .map(|s| (s.name, s.default.value()))
                .collect(),
            read: RefCell::new(Vec::new()),
        }
    }

    /// `method`'s options with `given` values checked against the table. A name the table
    /// lacks is an error; a name that does not apply to `method` is checked, ignored and
    /// named in the warnings returned.
    pub fn new(method: Method, given: &[(String, Value)]) -> Result<(Values, Vec<String>)> {
        let mut out = Values::defaults(method);
        let mut warnings = Vec::new();
        for (name, value) in given {
            match spec(name, method) {
                Some(spec) => {
                    let v = check(spec, value)?;
                    if let Some(slot) = out.values.iter_mut().find(|(n, _)| *n == spec.name) {
                        slot.1 = v;
                    }
                }
                None => {
                    let rows: Vec<&OptionSpec> =
                        OPTIONS.iter().filter(|s| s.name == name.as_str()).collect();
                    let Some(first) = rows.first() else {
                        return Err(unknown_option(name));
                    };
                    check(first, value)?;
                    let methods: Vec<&str> = rows
                        .iter()
                        .flat_map(|s| s.methods.iter().map(|m| m.name()))
                        .collect();
                    warnings.push(format!(
                        "option `{name}` does not apply to method `{}` (it applies to {}); \
                         ignored",
                        method.name(),
                        methods.join(", ")
                    ));
                }
            }
        }
        Ok((out, warnings))
    }

    fn get(&self, name: &'static str) -> &Value {
        self.read.borrow_mut().push(name);
        match self.values.iter().find(|(n, _)| *n == name) {
            Some((_, v)) => v,
            None => panic!("option `{name}` does not apply to `{}`", self.method.name()),
        }
    }

    fn int(&self, name: &'static str) -> Option<i128> {
        match self.get(name) {
            Value::Int(i) => Some(*i),
            _ => None,
        }
    }

    fn float(&self, name: &'static str) -> Option<f64> {
        match self.get(name) {
            Value::Float(x) => Some(*x),
            Value::Int(i) => Some(*i as f64),
            _ => None,
        }
    }

    // The table checked every value's kind and range: the narrowing casts below cannot
    // truncate, and a missing value is `None` ("automatic") or the default.
    pub(super) fn u32(&self, name: &'static str) -> u32 {
        self.int(name).unwrap_or(0) as u32
    }
    pub(super) fn u64(&self, name: &'static str) -> u64 {
        self.int(name).unwrap_or(0) as u64
    }
    pub(super) fn opt_u32(&self, name: &'static str) -> Option<u32> {
        self.int(name).map(|i| i as u32)
    }
    pub(super) fn opt_u64(&self, name: &'static str) -> Option<u64> {
        self.int(name).map(|i| i as u64)
    }
    pub(super) fn f32(&self, name: &'static str) -> f32 {
        self.float(name).unwrap_or(0.0) as f32
    }
    pub(super) fn opt_f32(&self, name: &'static str) -> Option<f32> {
        self.float(name).map(|x| x as f32)
    }
    pub(super) fn bool(&self, name: &'static str) -> bool {
        matches!(self.get(name), Value::Bool(true))
    }
    pub(super) fn text(&self, name: &'static str) -> Option<String> {
        match self.get(name) {
            Value::Str(s) => Some(s.clone()),
            _ => None,
        }
    }
    pub(super) fn choice<T: Named>(&self, name: &'static str) -> T {
        let s = self.text(name).unwrap_or_default();
        let all = T::all();
        all.iter()
            .copied()
            .find(|v| v.name() == s)
            .unwrap_or(all[0])
    }

    /// The names read so far.
    pub fn read(&self) -> Vec<&'static str> {
        self.read.borrow().clone()
    }
}

fn unknown_option(name: &str) -> Error {
    let mut names: Vec<&str> = OPTIONS.iter().map(|s| s.name).collect();
    names.dedup();
    let close: Vec<&str> = names
        .iter()
        .copied()
        .filter(|n| n.contains(name) || name.contains(n) || edit_distance(n, name) <= 2)
        .collect();
    let hint = if close.is_empty() {
        format!("options: {}", names.join(", "))
    } else {
        format!("did you mean {}?", close.join(" or "))
    };
    Error::setting("settings", format!("unknown option `{name}` ({hint})"))
}

/// Levenshtein distance (for "did you mean").
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}
