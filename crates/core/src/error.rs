//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in gi's core, each variant a category the Python layer maps
/// to its own exception type.
#[derive(Debug, Error)]
pub enum Error {
    /// A scene description is malformed: `field` is a JSON path such as `objects[2].material`
    /// (`(root)`: the whole description, left out of the message).
    #[error("{source_name}: {}{message}", if field == "(root)" { String::new() } else { format!("{field}: ") })]
    Scene {
        /// The scene file (or built-in name) the error was found in.
        source_name: String,
        /// Path of the offending field inside the description.
        field: String,
        /// What is wrong with it.
        message: String,
    },
    /// A render setting is out of range.
    #[error("invalid setting `{name}`: {message}")]
    Setting {
        /// The setting's name, as in the API.
        name: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// No usable GPU adapter, or a GPU operation failed.
    #[error("GPU: {0}")]
    Gpu(String),
    /// The render was cancelled by its progress callback (Ctrl-C, or a callback that
    /// returned `false`). Nothing else returns it.
    #[error("render cancelled")]
    Cancelled,
    /// An internal invariant of gi does not hold (a bug, not bad input): e.g. the GPU state
    /// or the BVH a frame step needs was not built before it.
    #[error(
        "internal error: {0} (this is a bug in gi; please report it with the scene and settings)"
    )]
    Internal(String),
    /// A stage would need more memory than the process can get (estimated before the
    /// allocation, or an allocation that failed).
    #[error(
        "out of memory: {what} needs about {} but only {} is available",
        human(*.needed),
        human(*.available)
    )]
    OutOfMemory {
        /// What the memory is for, e.g. "photon map (5000000 photons)".
        what: String,
        /// Estimated bytes needed.
        needed: u64,
        /// Bytes available to the process when checked.
        available: u64,
    },
}

/// Result alias for gi.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub(crate) fn scene(
        source_name: &str,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Error::Scene {
            source_name: source_name.to_string(),
            field: field.into(),
            message: message.into(),
        }
    }
    /// An [`Error::Internal`] naming the invariant that broke.
    pub(crate) fn internal(what: impl Into<String>) -> Self {
        Error::Internal(what.into())
    }
    pub(crate) fn setting(name: &'static str, message: impl Into<String>) -> Self {
        Error::Setting {
            name,
            message: message.into(),
        }
    }
}

/// A choice among a few named values: the options that take one of a set of names.
pub trait Named: Copy + PartialEq + 'static {
    /// Every value, in the order the choices are listed.
    fn all() -> &'static [Self];
    fn name(self) -> &'static str;
}

/// Implements [`Named`] for enums with an inherent `ALL` and `name()`.
macro_rules! named {
    ($($t:ty),* $(,)?) => {$(
        impl $crate::error::Named for $t {
            fn all() -> &'static [Self] {
                <$t>::ALL
            }
            fn name(self) -> &'static str {
                <$t>::name(self)
            }
        }
    )*};
}
pub(crate) use named;

/// The member of `all` named `s` (by `name`): the `FromStr` of the settings that are one of
/// a few named choices. Else a setting error for `setting` that names the `what` asked for
/// and the choices available.
pub(crate) fn parse_named<T: Copy>(
    s: &str,
    all: &[T],
    name: fn(T) -> &'static str,
    setting: &'static str,
    what: &str,
) -> Result<T> {
    all.iter().copied().find(|&v| name(v) == s).ok_or_else(|| {
        let names: Vec<_> = all.iter().map(|&v| name(v)).collect();
        Error::setting(
            setting,
            format!("unknown {what} `{s}` (available: {})", names.join(", ")),
        )
    })
}

/// `bytes` in binary units, e.g. "1.5 GiB".
pub fn human(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = bytes as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{v:.1} {}", UNITS[unit])
    }
}
